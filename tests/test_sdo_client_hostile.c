/* SPDX-License-Identifier: Apache-2.0 */
/* tests/test_sdo_client_hostile.c -- the SDO client against a server that keeps talking
 * but makes no progress (silence after the start, sequence numbers that never advance, a
 * sub-block repeated without its first segment, a toggle that never alternates, more data
 * than announced, a block download acknowledged with nothing again and again). Each transfer ends
 * with the CiA code for it within the channel's time-out of its last progress, tells the server,
 * and leaves the channel usable. Virtual time: the test feeds frames and polls at chosen
 * microseconds. Client: node 1, channel time-out 100 ms; server: node 5. */
#include "check.h"
#include "harness.h"

#define TIMEOUT_MS 100u
#define STEP_US 10000u    /* the hostile server talks every 10 ms */
#define LIMIT_US 5000000u /* and would go on for 5 s */

static test_node_t g_t; /* large: static */
static sdo_result_t g_r;
static uint8_t g_buf[64];
static uint64_t g_now;

static co_node_t *client(void)
{
    CHECK_EQ(test_node_init(&g_t, 1, 0), CO_OK);
    CHECK_EQ(co_node_start(&g_t.node, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&g_t.node, 0, 5), CO_OK);
    CHECK_EQ(co_sdo_client_set_timeout(&g_t.node, 0, TIMEOUT_MS), CO_OK);
    CHECK_EQ(co_sdo_client_block_options(&g_t.node, 0, 4, false, 0), CO_OK);
    fake_clear(&g_t.bus);
    memset(&g_r, 0, sizeof g_r);
    g_now = 0;
    return &g_t.node;
}

static void reply(const char *hex) { ingest(&g_t, g_now, 0x585, hex); }

static const char *last_sent(void)
{
    static char buf[40];
    return g_t.bus.count ? frame_str(&g_t.bus.frames[g_t.bus.count - 1], buf, sizeof buf) : "";
}

static void start_upload(co_sdo_mode_t mode, uint32_t cap)
{
    CHECK_EQ(co_sdo_upload(&g_t.node, 0, 0x2000, 0, mode, g_buf, cap, sdo_result_done, &g_r),
             CO_OK);
}

/* Let the server say `frames` (NULL-terminated) every STEP_US, polling the client in
 * between, until the transfer ends or LIMIT_US passes. Returns the time it ended. */
static uint64_t keep_saying(const char *const *frames)
{
    while (g_r.calls == 0 && g_now < LIMIT_US) {
        g_now += STEP_US;
        for (const char *const *f = frames; *f != NULL && g_r.calls == 0; f++) {
            reply(*f);
        }
        co_node_poll(&g_t.node, g_now);
    }
    return g_now;
}

/* The transfer ended once with `code`, the abort went out, and the channel serves the
 * next transfer. */
static void check_aborted_and_usable(co_abort_t code, const char *abort_frame)
{
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, code);
    CHECK_STR(last_sent(), abort_frame);
    CHECK(!co_sdo_client_busy(&g_t.node, 0));
    memset(&g_r, 0, sizeof g_r);
    start_upload(CO_SDO_AUTO, 4);
    reply("43 00 20 00 0A 0B 0C 0D");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_buf[3], 0x0D);
}

/* Block upload answered, then silence after the client's start: the time-out. */
static void test_block_upload_silent_after_initiate(void)
{
    client();
    start_upload(CO_SDO_BLOCK, 32);
    reply("C2 00 20 00 0E 00 00 00");
    CHECK_STR(last_sent(), "605#A300000000000000");
    static const char *const nothing[] = {NULL};
    uint64_t end = keep_saying(nothing);
    CHECK(end <= TIMEOUT_MS * 1000u + STEP_US);
    check_aborted_and_usable(CO_ABORT_TIMEOUT, "605#8000200000000405");
}

/* Segment 1 over and over: the next one never comes. Frames that bring nothing new do
 * not restart the time-out, which runs from the last accepted segment. */
static void test_block_upload_sequence_never_advances(void)
{
    client();
    start_upload(CO_SDO_BLOCK, 32);
    reply("C2 00 20 00 0E 00 00 00");
    static const char *const seg1[] = {"01 01 02 03 04 05 06 07", NULL};
    uint64_t end = keep_saying(seg1);
    CHECK(end <= STEP_US + TIMEOUT_MS * 1000u + STEP_US);
    check_aborted_and_usable(CO_ABORT_TIMEOUT, "605#8000200000000405");
}

/* The sub-block repeated without its first segment: each round the client acknowledges
 * nothing (ackseq 0) and the server sends the same again. Acknowledging nothing is no
 * progress either. */
static void test_block_upload_sub_block_repeated_without_progress(void)
{
    client();
    start_upload(CO_SDO_BLOCK, 32);
    reply("C2 00 20 00 0E 00 00 00");
    static const char *const round[] = {"02 01 02 03 04 05 06 07", "03 01 02 03 04 05 06 07",
                                        "04 01 02 03 04 05 06 07", NULL};
    reply(round[0]);
    reply(round[1]);
    reply(round[2]);
    CHECK_STR(last_sent(), "605#A200040000000000"); /* ackseq 0: repeat from 1 */
    uint64_t end = keep_saying(round);
    CHECK(end <= TIMEOUT_MS * 1000u + STEP_US);
    check_aborted_and_usable(CO_ABORT_TIMEOUT, "605#8000200000000405");
}

/* A sub-block going on past its lost first segment, slower than the time-out in all:
 * each segment beyond the ones seen restarts it, and the repetition completes. */
static void test_block_upload_slow_sub_block_with_a_lost_segment_completes(void)
{
    client();
    start_upload(CO_SDO_BLOCK, 32);
    reply("C2 00 20 00 1C 00 00 00"); /* 28 bytes: one sub-block of 4 */
    static const char *const segs[] = {"02 01 02 03 04 05 06 07", "03 01 02 03 04 05 06 07",
                                       "04 01 02 03 04 05 06 07", "01 01 02 03 04 05 06 07",
                                       "02 01 02 03 04 05 06 07", "03 01 02 03 04 05 06 07",
                                       "84 01 02 03 04 05 06 07"};
    for (int i = 0; i < 7; i++) { /* 60 ms apart: 420 ms in all */
        g_now += 60000;
        co_node_poll(&g_t.node, g_now);
        reply(segs[i]);
        if (i == 2) {
            CHECK_STR(last_sent(), "605#A200040000000000"); /* nothing kept: repeat */
        }
    }
    CHECK_STR(last_sent(), "605#A204040000000000");
    reply("C1 00 00 00 00 00 00 00");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, 28);
}

/* The same in a later sub-block: after one that made progress, the segments seen so far
 * start again from none, so a lost segment there still lets the later ones count. */
static void test_block_upload_lost_segment_in_a_later_sub_block_completes(void)
{
    client();
    start_upload(CO_SDO_BLOCK, 64);
    reply("C2 00 20 00 38 00 00 00"); /* 56 bytes: two sub-blocks of 4 */
    reply("01 01 02 03 04 05 06 07");
    reply("02 01 02 03 04 05 06 07");
    reply("03 01 02 03 04 05 06 07");
    reply("04 01 02 03 04 05 06 07");
    CHECK_STR(last_sent(), "605#A204040000000000");
    /* segment 1 of the second sub-block lost; the rest and the repetition 60 ms apart (the
     * time-out is 100 ms) */
    static const char *const segs[] = {"02 01 02 03 04 05 06 07", "03 01 02 03 04 05 06 07",
                                       "04 01 02 03 04 05 06 07", "01 01 02 03 04 05 06 07",
                                       "02 01 02 03 04 05 06 07", "03 01 02 03 04 05 06 07",
                                       "84 01 02 03 04 05 06 07"};
    for (int i = 0; i < 7; i++) {
        g_now += 60000;
        co_node_poll(&g_t.node, g_now);
        reply(segs[i]);
    }
    CHECK_STR(last_sent(), "605#A204040000000000");
    reply("C1 00 00 00 00 00 00 00");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, 56);
}

/* Sequence numbers outside 1..blksize belong to no sub-block the client asked for. */
static void test_block_upload_invalid_sequence_number(void)
{
    static const char *const bad[] = {"00 01 02 03 04 05 06 07", "05 01 02 03 04 05 06 07",
                                      "FF 01 02 03 04 05 06 07"};
    for (int i = 0; i < 3; i++) {
        client();
        start_upload(CO_SDO_BLOCK, 32);
        reply("C2 00 20 00 0E 00 00 00");
        reply(bad[i]);
        check_aborted_and_usable(CO_ABORT_SEQUENCE, "605#8000200003000405");
    }
}

/* Whole sub-blocks with no end, size indicated or not: refused once past the size, or
 * once past the caller's buffer. */
static void test_block_upload_endless(void)
{
    static const char *const sub_block[] = {"01 01 02 03 04 05 06 07", "02 01 02 03 04 05 06 07",
                                            "03 01 02 03 04 05 06 07", "04 01 02 03 04 05 06 07",
                                            NULL};
    client();
    start_upload(CO_SDO_BLOCK, 32);
    reply("C2 00 20 00 0E 00 00 00"); /* 14 bytes */
    keep_saying(sub_block);
    check_aborted_and_usable(CO_ABORT_LEN_HIGH, "605#8000200012000706");
    client();
    start_upload(CO_SDO_BLOCK, 32);
    reply("C0 00 20 00 00 00 00 00"); /* size not indicated */
    keep_saying(sub_block);
    check_aborted_and_usable(CO_ABORT_OUT_OF_MEMORY, "605#8000200005000405");
}

/* Segmented upload whose toggle bit stays 0. */
static void test_segmented_upload_toggle_never_alternates(void)
{
    client();
    start_upload(CO_SDO_SEGMENTED, 32);
    reply("41 00 20 00 0E 00 00 00");
    reply("00 01 02 03 04 05 06 07");
    CHECK_STR(last_sent(), "605#7000000000000000");
    static const char *const toggle0[] = {"00 01 02 03 04 05 06 07", NULL};
    keep_saying(toggle0);
    check_aborted_and_usable(CO_ABORT_TOGGLE, "605#8000200000000305");
}

/* Segmented upload that goes on past its size, indicated or not. */
static void test_segmented_upload_endless(void)
{
    client();
    start_upload(CO_SDO_SEGMENTED, 32);
    reply("41 00 20 00 0E 00 00 00"); /* 14 bytes */
    static const char *const segs[] = {"00 01 02 03 04 05 06 07", "10 01 02 03 04 05 06 07", NULL};
    keep_saying(segs);
    check_aborted_and_usable(CO_ABORT_LEN_HIGH, "605#8000200012000706");
    client();
    start_upload(CO_SDO_SEGMENTED, 32);
    reply("40 00 20 00 00 00 00 00"); /* size not indicated */
    keep_saying(segs);
    check_aborted_and_usable(CO_ABORT_OUT_OF_MEMORY, "605#8000200005000405");
}

static const uint8_t g_data[40] = {1, 2, 3};

/* A block download whose server acknowledges no segment of any sub-block: the first
 * repetition is sent on a fresh time-out, the ones after it are not. */
static void test_block_download_acknowledged_with_nothing(void)
{
    client();
    CHECK_EQ(co_sdo_download(&g_t.node, 0, 0x2000, 0, CO_SDO_BLOCK, g_data, sizeof g_data,
                             sdo_result_done, &g_r),
             CO_OK);
    reply("A4 00 20 00 04 00 00 00");
    static const char *const ack0[] = {"A2 00 04 00 00 00 00 00", NULL};
    uint64_t end = keep_saying(ack0);
    CHECK(end <= STEP_US + TIMEOUT_MS * 1000u + STEP_US);
    check_aborted_and_usable(CO_ABORT_TIMEOUT, "605#8000200000000405");
}

/* One repetition, then progress again: the transfer completes, however long it takes. */
static void test_block_download_one_repetition_at_a_time_completes(void)
{
    client();
    CHECK_EQ(co_sdo_download(&g_t.node, 0, 0x2000, 0, CO_SDO_BLOCK, g_data, sizeof g_data,
                             sdo_result_done, &g_r),
             CO_OK);
    reply("A4 00 20 00 04 00 00 00");
    /* 40 bytes = 6 segments: each sub-block is first refused once, 80 ms apart */
    static const char *const acks[] = {"A2 00 04 00 00 00 00 00", "A2 04 04 00 00 00 00 00",
                                       "A2 00 04 00 00 00 00 00", "A2 02 04 00 00 00 00 00"};
    for (int i = 0; i < 4; i++) {
        g_now += 80000;
        co_node_poll(&g_t.node, g_now);
        CHECK_EQ(g_r.calls, 0);
        reply(acks[i]);
    }
    CHECK_EQ(g_t.bus.frames[g_t.bus.count - 1].data[0] & 0xE3, 0xC1); /* the end */
    reply("A1 00 00 00 00 00 00 00");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, 40);
}

int main(void)
{
    RUN(test_block_upload_silent_after_initiate);
    RUN(test_block_upload_sequence_never_advances);
    RUN(test_block_upload_sub_block_repeated_without_progress);
    RUN(test_block_upload_slow_sub_block_with_a_lost_segment_completes);
    RUN(test_block_upload_lost_segment_in_a_later_sub_block_completes);
    RUN(test_block_upload_invalid_sequence_number);
    RUN(test_block_upload_endless);
    RUN(test_segmented_upload_toggle_never_alternates);
    RUN(test_segmented_upload_endless);
    RUN(test_block_download_acknowledged_with_nothing);
    RUN(test_block_download_one_repetition_at_a_time_completes);
    return check_summary();
}
