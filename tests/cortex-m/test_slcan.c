/* SPDX-License-Identifier: Apache-2.0 */
/* test_slcan.c -- the QEMU examples' SLCAN line protocol (examples/firmware/slcan.c): every
 * frame form both ways, the commands python-can's slcan interface sends, and bad lines
 * refused without losing the next one. */
#include "check.h"
#include "harness.h"
#include "slcan.h"

static slcan_cmd_t feed_line(slcan_parser_t *p, const char *line, co_frame_t *frame, uint32_t *arg)
{
    slcan_cmd_t cmd = SLCAN_NONE;
    for (const char *c = line; *c; c++) {
        slcan_cmd_t got = slcan_feed(p, (uint8_t)*c, frame, arg);
        if (got != SLCAN_NONE) {
            CHECK_EQ(c[1], '\0'); /* a command only at the line's end */
            cmd = got;
        }
    }
    return cmd;
}

static void test_frames_both_ways(void)
{
    static const char *lines[] = {
        "t7000\r",
        "t705105\r",
        "t60181122334455667788\r",
        "T1FFFFFFF3ABCDEF\r",
        "T000000000\r",
        "r1232\r",
        "R0000012A8\r",
        "t7FF0\r",
    };
    for (size_t i = 0; i < sizeof lines / sizeof lines[0]; i++) {
        slcan_parser_t p = {0};
        co_frame_t f;
        uint32_t arg;
        CHECK_EQ(feed_line(&p, lines[i], &f, &arg), SLCAN_FRAME);
        char out[SLCAN_LINE_MAX];
        uint8_t n = slcan_format(&f, out);
        CHECK_EQ(n, strlen(lines[i]));
        CHECK(memcmp(out, lines[i], n) == 0);
    }
    slcan_parser_t p = {0};
    co_frame_t f;
    uint32_t arg;
    CHECK_EQ(feed_line(&p, "t60181122334455667788\r", &f, &arg), SLCAN_FRAME);
    CHECK_EQ(f.id, 0x601);
    CHECK_EQ(f.flags, 0);
    CHECK_EQ(f.len, 8);
    CHECK_EQ(f.data[7], 0x88);
    CHECK_EQ(feed_line(&p, "R0000012A8\r", &f, &arg), SLCAN_FRAME);
    CHECK_EQ(f.id, 0x12A);
    CHECK_EQ(f.flags, CO_FRAME_EXT | CO_FRAME_RTR);
    CHECK_EQ(f.len, 8);
    CHECK_EQ(feed_line(&p, "t123101\r", &f, &arg), SLCAN_FRAME); /* lower-case hex taken */
    CHECK_EQ(f.data[0], 0x01);
    CHECK_EQ(feed_line(&p, "t1231ab\r", &f, &arg), SLCAN_FRAME);
    CHECK_EQ(f.data[0], 0xAB);
}

static void test_commands(void)
{
    slcan_parser_t p = {0};
    co_frame_t f;
    uint32_t arg = 0;
    CHECK_EQ(feed_line(&p, "\r\r\r", &f, &arg), SLCAN_NONE); /* a host's flush */
    CHECK_EQ(feed_line(&p, "C\r", &f, &arg), SLCAN_CLOSE);
    CHECK_EQ(feed_line(&p, "S6\r", &f, &arg), SLCAN_BIT_RATE);
    CHECK_EQ(arg, 500000);
    CHECK_EQ(feed_line(&p, "S8\r", &f, &arg), SLCAN_BIT_RATE);
    CHECK_EQ(arg, 1000000);
    CHECK_EQ(feed_line(&p, "O\r", &f, &arg), SLCAN_OPEN);
    CHECK_EQ(feed_line(&p, "L\r", &f, &arg), SLCAN_OPEN);
    CHECK_EQ(feed_line(&p, "V\r", &f, &arg), SLCAN_VERSION);
    CHECK_EQ(feed_line(&p, "v\r", &f, &arg), SLCAN_VERSION_FW);
    CHECK_EQ(feed_line(&p, "N\r", &f, &arg), SLCAN_SERIAL);
    CHECK_EQ(feed_line(&p, "F\r", &f, &arg), SLCAN_STATUS);
    CHECK_EQ(feed_line(&p, "s031C\r", &f, &arg), SLCAN_OTHER);
    CHECK_EQ(feed_line(&p, "Z0\r", &f, &arg), SLCAN_OTHER);
    CHECK_EQ(feed_line(&p, "\nO\r", &f, &arg), SLCAN_OPEN); /* CR LF line ends */
}

static void test_bad_lines_refused(void)
{
    static const char *bad[] = {
        "t8000\r",                               /* 11-bit identifier above 0x7FF */
        "T200000000\r",                          /* 29-bit identifier above 0x1FFFFFFF */
        "t1239\r",                               /* length 9 */
        "t12310\r",                              /* one data digit */
        "t1231123\r",                            /* three */
        "t12G0\r",                               /* not hex */
        "t1231G0\r",                             /* nor this byte */
        "r123\r",                                /* no length */
        "S9\r",                                  /* no such rate */
        "O1\r",                                  /* trailing bytes */
        "Q\r",                                   /* unknown */
        "t12\r",                                 /* short */
        "t6018112233445566778899AABBCCDDEEFF\r", /* longer than any line */
    };
    slcan_parser_t p = {0};
    co_frame_t f;
    uint32_t arg;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (feed_line(&p, bad[i], &f, &arg) != SLCAN_REFUSED) {
            printf("  taken: %s\n", bad[i]);
            CHECK(0);
        }
        /* the next line is read as it should be */
        CHECK_EQ(feed_line(&p, "t7000\r", &f, &arg), SLCAN_FRAME);
        CHECK_EQ(f.id, 0x700);
    }
}

int main(void)
{
    RUN(test_frames_both_ways);
    RUN(test_commands);
    RUN(test_bad_lines_refused);
    return check_summary();
}
