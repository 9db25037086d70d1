/* SPDX-License-Identifier: Apache-2.0 */
/* test_sync.c -- SYNC producer and consumer (0x1005, 0x1006, 0x1007, 0x1019). */
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define NODE 5

static char dump[4096];

/* What on_sync saw, for the test running now. */
static struct {
    uint8_t counters[64];
    uint64_t at_us[64];
    uint32_t count;
} syncs;

static void rec_sync(void *user, uint8_t counter)
{
    test_node_t *t = user;
    if (syncs.count < 64) {
        syncs.counters[syncs.count] = counter;
        syncs.at_us[syncs.count] = t->node.now_us;
        syncs.count++;
    }
}

/* A started node (no heartbeat), recording SYNCs, with the boot-up frame cleared. */
static void setup(test_node_t *t)
{
    memset(&syncs, 0, sizeof syncs);
    test_node_init(t, NODE, 0);
    t->node.cfg.on_sync = rec_sync;
    co_node_start(&t->node, 0);
    fake_clear(&t->bus);
}

/* Make the node a SYNC producer on 0x080 at `now` with `period_us` (and 0x1019 first). */
static void make_producer(test_node_t *t, uint64_t now, uint32_t period_us, uint8_t overflow)
{
    t->node.now_us = now;
    CHECK_EQ(write_u8(t, 0x1019, 0, overflow), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1006, 0, period_us), CO_ABORT_NONE);
}

/* ---- producer */

static void test_producer_exact_timing(void)
{
    test_node_t t;
    setup(&t);
    CHECK_EQ(co_node_poll(&t.node, 0), CO_TIME_NEVER); /* 0x1005 = 0x80: consumer only */
    make_producer(&t, 0, 10000, 0);
    CHECK_EQ(co_node_poll(&t.node, 0), 10 * MS);
    CHECK_EQ(co_node_poll(&t.node, 10 * MS - 1), 10 * MS);
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(co_node_poll(&t.node, 10 * MS), 20 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "080#");
    CHECK_EQ(co_node_poll(&t.node, 20 * MS - 1), 20 * MS);
    CHECK_EQ(co_node_poll(&t.node, 20 * MS), 30 * MS);
    CHECK_EQ(co_node_poll(&t.node, 30 * MS), 40 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "080# 080# 080#");
}

static void test_producer_late_poll_keeps_cadence(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 0);
    CHECK_EQ(co_node_poll(&t.node, 13 * MS), 20 * MS); /* 3 ms late: cadence kept */
    CHECK_EQ(co_node_poll(&t.node, 45 * MS), 55 * MS); /* far behind: missed SYNCs dropped */
    CHECK_EQ(fake_count_id(&t.bus, 0x080), 2);
}

static void test_producer_handles_its_own_sync(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 4);
    co_node_poll(&t.node, 10 * MS);
    co_node_poll(&t.node, 21 * MS);
    CHECK_EQ(syncs.count, 2);
    CHECK_EQ(syncs.counters[0], 1);
    CHECK_EQ(syncs.at_us[0], 10 * MS);
    CHECK_EQ(syncs.counters[1], 2);
    CHECK_EQ(syncs.at_us[1], 21 * MS); /* the time it really went out */
    CHECK_EQ(co_sync_counter(&t.node), 2);
    CHECK(co_sync_in_window(&t.node, 21 * MS));
}

static void test_counter_wraps_after_overflow(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 3);
    for (uint64_t ms = 10; ms <= 50; ms += 10) {
        co_node_poll(&t.node, ms * MS);
    }
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "080#01 080#02 080#03 080#01 080#02");
    CHECK_EQ(syncs.count, 5);
    CHECK_EQ(syncs.counters[2], 3);
    CHECK_EQ(syncs.counters[3], 1);
    CHECK_EQ(co_sync_counter(&t.node), 2);
}

static void test_producer_idle_in_stopped_and_resumed_on_start(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 5);
    co_node_poll(&t.node, 10 * MS);
    co_node_poll(&t.node, 20 * MS);
    ingest(&t, 25 * MS, 0x000, "02 05");
    CHECK_EQ(co_node_poll(&t.node, 30 * MS), CO_TIME_NEVER); /* the old deadline: nothing */
    CHECK_EQ(co_node_poll(&t.node, 100 * MS), CO_TIME_NEVER);
    CHECK_EQ(fake_count_id(&t.bus, 0x080), 2);
    /* Started again: one period from now, counting from 1. */
    ingest(&t, 103 * MS, 0x000, "01 05");
    CHECK_EQ(co_node_poll(&t.node, 103 * MS), 113 * MS);
    co_node_poll(&t.node, 113 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "080#01 080#02 080#01");
}

static void test_producer_keeps_cadence_between_preop_and_operational(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 0);
    co_node_poll(&t.node, 10 * MS);
    ingest(&t, 14 * MS, 0x000, "01 05"); /* both states run SYNC: no new start */
    CHECK_EQ(co_node_poll(&t.node, 14 * MS), 20 * MS);
    ingest(&t, 26 * MS, 0x000, "80 05");
    CHECK_EQ(co_node_poll(&t.node, 26 * MS), 30 * MS);
    CHECK_EQ(co_node_poll(&t.node, 30 * MS), 40 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x080), 3);
}

static void test_period_change_takes_effect_at_once(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 5);
    co_node_poll(&t.node, 10 * MS);
    co_node_poll(&t.node, 20 * MS);
    /* New period: the next SYNC one new period from now; the counter goes on. */
    t.node.now_us = 23 * MS;
    CHECK_EQ(write_u32(&t, 0x1006, 0, 5000), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 23 * MS), 28 * MS);
    CHECK_EQ(co_node_poll(&t.node, 28 * MS), 33 * MS);
    /* Period 0: idle. */
    t.node.now_us = 30 * MS;
    CHECK_EQ(write_u32(&t, 0x1006, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 33 * MS), CO_TIME_NEVER);
    CHECK_EQ(co_node_poll(&t.node, 1000 * MS), CO_TIME_NEVER);
    /* Enabled again: from scratch, counter at 1. */
    t.node.now_us = 1000 * MS;
    CHECK_EQ(write_u32(&t, 0x1006, 0, 20000), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 1000 * MS), 1020 * MS);
    co_node_poll(&t.node, 1020 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "080#01 080#02 080#03 080#01");
}

static void test_producer_bit_of_0x1005(void)
{
    test_node_t t;
    setup(&t);
    make_producer(&t, 0, 10000, 0);
    co_node_poll(&t.node, 10 * MS);
    /* Bit 30 cleared: idle, though the period stays. */
    t.node.now_us = 12 * MS;
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x80), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 20 * MS), CO_TIME_NEVER);
    /* Set again: one period from now. */
    t.node.now_us = 57 * MS;
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 57 * MS), 67 * MS);
    co_node_poll(&t.node, 67 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x080), 2);
}

static void test_producer_29_bit_cob_id(void)
{
    test_node_t t;
    setup(&t);
    t.node.now_us = 0;
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x60000000u | 0x12345u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1006, 0, 1000), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 1000), 2000);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "00012345#");
    CHECK_EQ(t.bus.frames[0].flags, CO_FRAME_EXT);
}

/* Let reset communication leave an entry's value alone (no power-on default). */
static void keep_over_reset(test_node_t *t, uint16_t index)
{
    for (uint32_t i = 0; i < EXAMPLE_OD_MAX_ENTRIES; i++) {
        if (t->od.entries[i].index == index) {
            t->od.entries[i].dflt = NULL;
        }
    }
}

static void test_producer_from_power_on_and_after_reset(void)
{
    test_node_t t;
    memset(&syncs, 0, sizeof syncs);
    test_node_init(&t, NODE, 0);
    t.node.cfg.on_sync = rec_sync;
    keep_over_reset(&t, 0x1005);
    keep_over_reset(&t, 0x1006);
    keep_over_reset(&t, 0x1019);
    t.od.sync_cob_id = 0x40000080u;
    t.od.sync_period_us = 10000;
    t.od.sync_overflow = 2;
    /* First SYNC one period after entering pre-operational. */
    co_node_start(&t.node, 7 * MS);
    fake_clear(&t.bus);
    CHECK_EQ(co_node_poll(&t.node, 7 * MS), 17 * MS);
    co_node_poll(&t.node, 17 * MS);
    co_node_poll(&t.node, 27 * MS);
    CHECK_EQ(co_sync_counter(&t.node), 2);
    /* Reset communication: the latest SYNC forgotten, a new start counting from 1. */
    ingest(&t, 30 * MS, 0x000, "82 05");
    CHECK_EQ(co_sync_counter(&t.node), 0);
    CHECK(!co_sync_in_window(&t.node, 30 * MS));
    CHECK_EQ(co_node_poll(&t.node, 37 * MS), 40 * MS); /* 37 ms: the old deadline */
    co_node_poll(&t.node, 40 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "080#01 080#02 705#00 080#01");
    CHECK_EQ(co_sync_counter(&t.node), 1);
}

/* ---- 0x1019 writes */

static void test_overflow_write_rules(void)
{
    test_node_t t;
    setup(&t);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 1), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 241), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 255), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 2), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 240), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(t.od.sync_overflow, 0);
    /* Not while a period is set, producer or not. */
    CHECK_EQ(write_u32(&t, 0x1006, 0, 10000), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 5), CO_ABORT_DATA_STATE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 0), CO_ABORT_DATA_STATE);
    CHECK_EQ(t.od.sync_overflow, 0);
    CHECK_EQ(write_u32(&t, 0x1006, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 5), CO_ABORT_NONE);
    CHECK_EQ(t.od.sync_overflow, 5);
}

/* ---- consumer */

static void test_consumer_reports_sync_with_counter(void)
{
    test_node_t t;
    setup(&t);
    CHECK_EQ(co_node_poll(&t.node, 0), CO_TIME_NEVER);
    ingest(&t, 1 * MS, 0x080, "");
    CHECK_EQ(syncs.count, 1);
    CHECK_EQ(syncs.counters[0], 0);
    CHECK_EQ(co_sync_counter(&t.node), 0);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 4), CO_ABORT_NONE);
    ingest(&t, 2 * MS, 0x080, "03");
    CHECK_EQ(syncs.count, 2);
    CHECK_EQ(syncs.counters[1], 3);
    CHECK_EQ(syncs.at_us[1], 2 * MS);
    CHECK_EQ(co_sync_counter(&t.node), 3);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
    CHECK_EQ(t.bus.count, 0); /* a consumer sends nothing */
}

static void test_consumer_wrong_length_is_not_reported(void)
{
    test_node_t t;
    setup(&t);
    /* No counter expected: a data byte is wrong. (EMCY 0x8240 goes out, not checked here.) */
    ingest(&t, 1 * MS, 0x080, "01");
    CHECK_EQ(syncs.count, 0);
    CHECK(!co_sync_in_window(&t.node, 1 * MS));
    /* A counter expected: none or two bytes are wrong. */
    CHECK_EQ(write_u8(&t, 0x1019, 0, 10), CO_ABORT_NONE);
    ingest(&t, 2 * MS, 0x080, "");
    ingest(&t, 3 * MS, 0x080, "01 02");
    CHECK_EQ(syncs.count, 0);
    CHECK_EQ(co_sync_counter(&t.node), 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 3);
    /* RTR frames are no SYNC. */
    ingest(&t, 4 * MS, 0x080, "R1");
    CHECK_EQ(syncs.count, 0);
    ingest(&t, 5 * MS, 0x080, "07");
    CHECK_EQ(syncs.count, 1);
    CHECK_EQ(co_sync_counter(&t.node), 7);
}

static void test_window_edges(void)
{
    test_node_t t;
    setup(&t);
    CHECK(!co_sync_in_window(&t.node, 0)); /* before any SYNC, even without a window */
    CHECK_EQ(write_u32(&t, 0x1007, 0, 1000), CO_ABORT_NONE);
    CHECK(!co_sync_in_window(&t.node, 0));
    ingest(&t, 50 * MS, 0x080, "");
    CHECK(co_sync_in_window(&t.node, 50 * MS));
    CHECK(co_sync_in_window(&t.node, 50 * MS + 999));
    CHECK(!co_sync_in_window(&t.node, 50 * MS + 1000));
    CHECK(!co_sync_in_window(&t.node, 50 * MS - 1)); /* before the SYNC itself */
    /* The next SYNC opens it again. */
    ingest(&t, 60 * MS, 0x080, "");
    CHECK(co_sync_in_window(&t.node, 60 * MS + 999));
    CHECK(!co_sync_in_window(&t.node, 60 * MS + 1000));
    /* A new window length counts at once; 0 means no window. */
    CHECK_EQ(write_u32(&t, 0x1007, 0, 2000), CO_ABORT_NONE);
    CHECK(co_sync_in_window(&t.node, 60 * MS + 1999));
    CHECK(!co_sync_in_window(&t.node, 60 * MS + 2000));
    CHECK_EQ(write_u32(&t, 0x1007, 0, 0), CO_ABORT_NONE);
    CHECK(co_sync_in_window(&t.node, 10000 * MS));
}

static void test_sync_ignored_in_stopped(void)
{
    test_node_t t;
    setup(&t);
    ingest(&t, 1 * MS, 0x000, "02 05");
    uint32_t gated = co_node_stats(&t.node)->rx_gated;
    ingest(&t, 2 * MS, 0x080, "");
    CHECK_EQ(syncs.count, 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_gated, gated + 1);
    CHECK(!co_sync_in_window(&t.node, 2 * MS));
    ingest(&t, 3 * MS, 0x000, "01 05");
    ingest(&t, 4 * MS, 0x080, "");
    CHECK_EQ(syncs.count, 1);
}

static void test_cob_id_change_moves_the_route(void)
{
    test_node_t t;
    setup(&t);
    co_frame_t old_id = frm(0x080, "");
    co_frame_t new_id = frm(0x081, "");
    CHECK(co_node_accepts(&t.node, &old_id));
    uint32_t changes = t.bus.routes_changed;
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x81), CO_ABORT_NONE);
    CHECK(t.bus.routes_changed > changes);
    CHECK(!co_node_accepts(&t.node, &old_id));
    CHECK(co_node_accepts(&t.node, &new_id));
    ingest(&t, 1 * MS, 0x081, "");
    CHECK_EQ(syncs.count, 1);
    /* Only the producer bit changes: same route, no rebuild. */
    changes = t.bus.routes_changed;
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x40000081u), CO_ABORT_NONE);
    CHECK_EQ(t.bus.routes_changed, changes);
    /* A 29-bit identifier. */
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x20000000u | 0x1ABCDu), CO_ABORT_NONE);
    co_frame_t ext = frm(0x1ABCD, "");
    CHECK(co_node_accepts(&t.node, &ext));
    ingest(&t, 2 * MS, 0x1ABCD, "");
    CHECK_EQ(syncs.count, 2);
}

/* ---- edges: the documented answers to inputs seldom seen */

static void test_sync_producer_follows_values_changed_directly(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 5), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1006, 0, 10000), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    fake_clear(&t.bus);
    for (uint64_t ms = 10; ms <= 40; ms += 10) {
        co_node_poll(&t.node, ms * MS);
    }
    CHECK_EQ(t.bus.count, 4);
    CHECK_EQ(t.bus.frames[3].data[0], 4);
    t.od.sync_overflow = 2; /* the counter (now 5) is past it: starts over at 1 */
    co_node_poll(&t.node, 50 * MS);
    CHECK_EQ(t.bus.frames[4].data[0], 1);
    t.od.sync_period_us = 0; /* period gone: no more SYNC */
    CHECK_EQ(co_node_poll(&t.node, 60 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 5);
}

int main(void)
{
    RUN(test_producer_exact_timing);
    RUN(test_producer_late_poll_keeps_cadence);
    RUN(test_producer_handles_its_own_sync);
    RUN(test_counter_wraps_after_overflow);
    RUN(test_producer_idle_in_stopped_and_resumed_on_start);
    RUN(test_producer_keeps_cadence_between_preop_and_operational);
    RUN(test_period_change_takes_effect_at_once);
    RUN(test_producer_bit_of_0x1005);
    RUN(test_producer_29_bit_cob_id);
    RUN(test_producer_from_power_on_and_after_reset);
    RUN(test_overflow_write_rules);
    RUN(test_consumer_reports_sync_with_counter);
    RUN(test_consumer_wrong_length_is_not_reported);
    RUN(test_window_edges);
    RUN(test_sync_ignored_in_stopped);
    RUN(test_cob_id_change_moves_the_route);
    RUN(test_sync_producer_follows_values_changed_directly);
    return check_summary();
}
