/* SPDX-License-Identifier: Apache-2.0 */
/* test_time.c -- TIME_OF_DAY coding, TIME producer and consumer (0x1012). */
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define NODE 5
#define US_PER_DAY 86400000000ull
#define LAST_MS 86399999u

static char dump[4096];

/* What on_time saw, for the test running now. */
static struct {
    co_time_of_day_t times[16];
    uint32_t count;
} seen;

static void rec_time(void *user, const co_time_of_day_t *time)
{
    (void)user;
    if (seen.count < 16) {
        seen.times[seen.count++] = *time;
    }
}

/* A started node (no heartbeat), recording TIME, with the boot-up frame cleared. */
static void setup(test_node_t *t)
{
    memset(&seen, 0, sizeof seen);
    test_node_init(t, NODE, 0);
    t->node.cfg.on_time = rec_time;
    co_node_start(&t->node, 0);
    fake_clear(&t->bus);
}

/* Days from 1984-01-01 to a Gregorian date, counted the slow, obvious way. */
static bool leap(unsigned y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

static uint32_t days_since_1984(unsigned year, unsigned month, unsigned day)
{
    static const unsigned mdays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    uint32_t n = 0;
    for (unsigned y = 1984; y < year; y++) {
        n += leap(y) ? 366 : 365;
    }
    for (unsigned m = 1; m < month; m++) {
        n += mdays[m - 1] + (m == 2 && leap(year));
    }
    return n + day - 1;
}

static bool same(co_time_of_day_t a, co_time_of_day_t b)
{
    return a.ms == b.ms && a.days == b.days;
}

/* ---- coding */

static void test_encode_decode_edges(void)
{
    uint8_t b[6];
    co_time_of_day_t zero = {0, 0};
    co_time_encode(&zero, b);
    CHECK(memcmp(b, "\x00\x00\x00\x00\x00\x00", 6) == 0);
    CHECK(same(co_time_decode(b), zero));

    co_time_of_day_t last = {LAST_MS, 65535}; /* 86399999 = 0x05265BFF */
    co_time_encode(&last, b);
    CHECK(memcmp(b, "\xFF\x5B\x26\x05\xFF\xFF", 6) == 0);
    CHECK(same(co_time_decode(b), last));

    co_time_of_day_t mixed = {1, 0x1234};
    co_time_encode(&mixed, b);
    CHECK(memcmp(b, "\x01\x00\x00\x00\x34\x12", 6) == 0);
    CHECK(same(co_time_decode(b), mixed));
}

static void test_reserved_bits_dropped(void)
{
    /* Received: bits 28..31 set, ignored. */
    const uint8_t in[6] = {0xFF, 0x5B, 0x26, 0xF5, 0x34, 0x12};
    co_time_of_day_t t = co_time_decode(in);
    CHECK_EQ(t.ms, LAST_MS);
    CHECK_EQ(t.days, 0x1234);
    const uint8_t all[6] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    CHECK_EQ(co_time_decode(all).ms, 0x0FFFFFFF);
    /* Sent: always 0. */
    co_time_of_day_t high = {0xF0000001u, 7};
    uint8_t b[6];
    co_time_encode(&high, b);
    CHECK(memcmp(b, "\x01\x00\x00\x00\x07\x00", 6) == 0);
}

static void test_microsecond_conversions(void)
{
    co_time_of_day_t zero = {0, 0};
    CHECK_EQ(co_time_to_us(&zero), 0);
    CHECK(same(co_time_from_us(0), zero));

    co_time_of_day_t one = {1, 1};
    CHECK_EQ(co_time_to_us(&one), US_PER_DAY + 1000);
    CHECK(same(co_time_from_us(US_PER_DAY + 1000), one));
    CHECK(same(co_time_from_us(US_PER_DAY + 1999), one)); /* sub-millisecond part dropped */

    co_time_of_day_t last = {LAST_MS, 65535};
    uint64_t last_us = 65536ull * US_PER_DAY - 1000;
    CHECK_EQ(co_time_to_us(&last), last_us);
    CHECK(same(co_time_from_us(last_us), last));
    /* Midnight rolls into the next day. */
    co_time_of_day_t before = {LAST_MS, 9};
    co_time_of_day_t after = {0, 10};
    CHECK(same(co_time_from_us(co_time_to_us(&before) + 1000), after));
}

static void test_known_dates(void)
{
    CHECK_EQ(days_since_1984(1984, 1, 1), 0);
    CHECK_EQ(days_since_1984(1985, 1, 1), 366); /* 1984 is a leap year */
    CHECK_EQ(days_since_1984(2000, 1, 1), 5844);
    CHECK_EQ(days_since_1984(2024, 2, 29), 14669);
    /* 2000-01-01 12:00:00.000 */
    co_time_of_day_t noon = {12u * 3600u * 1000u, (uint16_t)days_since_1984(2000, 1, 1)};
    CHECK_EQ(co_time_to_us(&noon), 5844ull * US_PER_DAY + 43200000000ull);
    uint8_t b[6];
    co_time_encode(&noon, b);
    CHECK(memcmp(b, "\x00\x2E\x93\x02\xD4\x16", 6) == 0); /* 43200000 = 0x02932E00 */
}

/* ---- producer */

static void test_send_byte_exact(void)
{
    test_node_t t;
    setup(&t);
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x40000100u), CO_ABORT_NONE);
    co_time_of_day_t noon = {43200000u, 5844};
    CHECK_EQ(co_time_send(&t.node, &noon), CO_OK);
    co_time_of_day_t last = {LAST_MS, 65535};
    CHECK_EQ(co_time_send(&t.node, &last), CO_OK);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "100#002E9302D416 100#FF5B2605FFFF");
    /* In operational too, and on a 29-bit identifier. */
    ingest(&t, 1 * MS, 0x000, "01 05");
    fake_clear(&t.bus);
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x60000000u | 0x1ABCDEu), CO_ABORT_NONE);
    co_time_of_day_t small = {1, 2};
    CHECK_EQ(co_time_send(&t.node, &small), CO_OK);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "001ABCDE#010000000200");
    CHECK_EQ(t.bus.frames[0].flags, CO_FRAME_EXT);
    CHECK_EQ(seen.count, 0); /* own TIME is not consumed */
}

static void test_send_refused(void)
{
    test_node_t t;
    memset(&seen, 0, sizeof seen);
    test_node_init(&t, NODE, 0);
    co_time_of_day_t noon = {43200000u, 5844};
    /* Not started: initialising. */
    t.node.time.cob_id = 0x40000100u;
    CHECK_EQ(co_time_send(&t.node, &noon), CO_ERR_STATE);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    /* 0x1012 = 0x80000100: a consumer, no producer. */
    CHECK_EQ(co_time_send(&t.node, &noon), CO_ERR_STATE);
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0xC0000100u), CO_ABORT_NONE);
    co_time_of_day_t bad = {86400000u, 0};
    CHECK_EQ(co_time_send(&t.node, &bad), CO_ERR_ARG);
    CHECK_EQ(co_time_send(&t.node, NULL), CO_ERR_ARG);
    /* Stopped. */
    ingest(&t, 1 * MS, 0x000, "02 05");
    CHECK_EQ(co_time_send(&t.node, &noon), CO_ERR_STATE);
    CHECK_EQ(t.bus.count, 0);
    ingest(&t, 2 * MS, 0x000, "80 05");
    CHECK_EQ(co_time_send(&t.node, &noon), CO_OK);
    CHECK_EQ(fake_count_id(&t.bus, 0x100), 1);
}

/* ---- consumer */

static void test_consumer_reports_time(void)
{
    test_node_t t;
    setup(&t); /* 0x1012 = 0x80000100: consumer */
    ingest(&t, 1 * MS, 0x100, "00 2E 93 02 D4 16");
    CHECK_EQ(seen.count, 1);
    CHECK_EQ(seen.times[0].ms, 43200000u);
    CHECK_EQ(seen.times[0].days, 5844);
    ingest(&t, 2 * MS, 0x100, "FF 5B 26 F5 FF FF"); /* reserved bits set */
    CHECK_EQ(seen.count, 2);
    CHECK_EQ(seen.times[1].ms, LAST_MS);
    CHECK_EQ(seen.times[1].days, 65535);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
}

static void test_consumer_malformed_frames(void)
{
    test_node_t t;
    setup(&t);
    ingest(&t, 1 * MS, 0x100, "00 2E 93 02 D4");
    ingest(&t, 2 * MS, 0x100, "00 2E 93 02 D4 16 00");
    ingest(&t, 3 * MS, 0x100, "");
    ingest(&t, 4 * MS, 0x100, "R6");
    CHECK_EQ(seen.count, 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 4);
}

static void test_consumer_bit_and_state(void)
{
    test_node_t t;
    setup(&t);
    /* Stopped: gated. */
    ingest(&t, 1 * MS, 0x000, "02 05");
    ingest(&t, 2 * MS, 0x100, "01 00 00 00 00 00");
    CHECK_EQ(seen.count, 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_gated, 1);
    ingest(&t, 3 * MS, 0x000, "01 05");
    ingest(&t, 4 * MS, 0x100, "01 00 00 00 00 00");
    CHECK_EQ(seen.count, 1);
    /* Bit 31 cleared: not consumed any more. */
    co_frame_t time = frm(0x100, "");
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x00000100u), CO_ABORT_NONE);
    CHECK(!co_node_accepts(&t.node, &time));
    ingest(&t, 5 * MS, 0x100, "01 00 00 00 00 00");
    CHECK_EQ(seen.count, 1);
    /* Consumed again, on another identifier. */
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x80000101u), CO_ABORT_NONE);
    co_frame_t moved = frm(0x101, "");
    CHECK(co_node_accepts(&t.node, &moved));
    CHECK(!co_node_accepts(&t.node, &time));
    ingest(&t, 6 * MS, 0x101, "02 00 00 00 03 00");
    CHECK_EQ(seen.count, 2);
    CHECK_EQ(seen.times[1].ms, 2);
    CHECK_EQ(seen.times[1].days, 3);
    /* Producer bit only: routes unchanged. */
    uint32_t changes = t.bus.routes_changed;
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0xC0000101u), CO_ABORT_NONE);
    CHECK_EQ(t.bus.routes_changed, changes);
}

/* ---- edges: the documented answers to inputs seldom seen */

static void test_time_producer_arguments_and_consumer_without_callback(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_time_of_day_t tod = {.ms = 1000, .days = 1};
    CHECK_EQ(co_time_send(NULL, &tod), CO_ERR_ARG);
    CHECK_EQ(co_time_send(&t.node, NULL), CO_ERR_ARG);
    CHECK_EQ(co_time_send(&t.node, &tod), CO_ERR_STATE); /* not a producer */
    /* Consumer without on_time: the frame is taken (not malformed) and dropped. */
    ingest(&t, 0, 0x100, "00 00 00 00 00 00");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_unrouted, 0);
    /* Producer on: now it sends; a producer keeps consuming nothing of its own. */
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x40000100u), CO_ABORT_NONE);
    fake_clear(&t.bus);
    CHECK_EQ(co_time_send(&t.node, &tod), CO_OK);
    CHECK_EQ(fake_count_id(&t.bus, 0x100), 1);
    tod.ms = 86400000u;
    CHECK_EQ(co_time_send(&t.node, &tod), CO_ERR_ARG);
}

static void test_time_cob_id_moves_the_route(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_frame_t old_id = frm(0x100, "00 00 00 00 00 00");
    co_frame_t new_id = frm(0x101, "00 00 00 00 00 00");
    CHECK(co_node_accepts(&t.node, &old_id));
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x80000101u), CO_ABORT_NONE);
    CHECK(!co_node_accepts(&t.node, &old_id));
    CHECK(co_node_accepts(&t.node, &new_id));
}

int main(void)
{
    RUN(test_encode_decode_edges);
    RUN(test_reserved_bits_dropped);
    RUN(test_microsecond_conversions);
    RUN(test_known_dates);
    RUN(test_send_byte_exact);
    RUN(test_send_refused);
    RUN(test_consumer_reports_time);
    RUN(test_consumer_malformed_frames);
    RUN(test_consumer_bit_and_state);
    RUN(test_time_producer_arguments_and_consumer_without_callback);
    RUN(test_time_cob_id_moves_the_route);
    return check_summary();
}
