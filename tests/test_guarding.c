/* SPDX-License-Identifier: Apache-2.0 */
/* test_guarding.c -- node guarding: the node's replies and life guarding, the master's watch. */
#include "check.h"
#include "harness.h"

#define MS 1000ull

static char dump[4096];

static void set_u16(test_node_t *t, uint16_t idx, uint16_t v)
{
    uint8_t b[2];
    co_put_u16(b, v);
    CHECK_EQ(co_node_write_net(&t->node, idx, 0, b, 2), CO_ABORT_NONE);
}

static void test_replies_toggle_and_state(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    ingest(&t, 1 * MS, 0x705, "R1");
    ingest(&t, 2 * MS, 0x705, "R1");
    ingest(&t, 3 * MS, 0x000, "01 05");
    ingest(&t, 4 * MS, 0x705, "R1");
    ingest(&t, 5 * MS, 0x000, "02 05");
    ingest(&t, 6 * MS, 0x705, "R1");
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#7F 705#FF 705#05 705#84");
    /* Reset communication: the toggle starts at 0 again (after the boot-up). */
    ingest(&t, 7 * MS, 0x000, "82 05");
    fake_clear(&t.bus);
    ingest(&t, 8 * MS, 0x705, "R1");
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#7F");
}

static void test_no_reply_while_heartbeat_runs(void)
{
    test_node_t t;
    test_node_init(&t, 5, 100);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    ingest(&t, 1 * MS, 0x705, "R1");
    CHECK_EQ(t.bus.count, 0);
    /* A data frame on our own ID is someone else's: counted, not answered. */
    ingest(&t, 1 * MS, 0x705, "05");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 1);
    /* ... another node with our node-ID: reported (event + EMCY 0x8150), once. */
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_ID_COLLISION);
    CHECK_EQ(t.events[0].state, 5);
    CHECK_EQ(fake_count_id(&t.bus, 0x085), 1);
    CHECK_EQ(t.bus.frames[0].data[0], 0x50);
    CHECK_EQ(t.bus.frames[0].data[1], 0x81);
    ingest(&t, 2 * MS, 0x705, "");
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(fake_count_id(&t.bus, 0x085), 1);
}

static void test_life_guarding_event_and_error_behaviour(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    set_u16(&t, 0x100C, 100);
    uint8_t factor = 3;
    CHECK_EQ(co_node_write_net(&t.node, 0x100D, 0, &factor, 1), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x000, "01 05");
    /* Not monitored before the first RTR. */
    co_node_poll(&t.node, 5000 * MS);
    CHECK_EQ(t.event_count, 0);
    ingest(&t, 5000 * MS, 0x705, "R1");
    CHECK_EQ(co_node_poll(&t.node, 5000 * MS), 5300 * MS);
    ingest(&t, 5200 * MS, 0x705, "R1");
    CHECK_EQ(co_node_poll(&t.node, 5499 * MS), 5500 * MS);
    CHECK_EQ(t.event_count, 0);
    co_node_poll(&t.node, 5500 * MS);
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_LIFE_GUARD);
    CHECK_EQ(t.events[0].node_id, 5);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL); /* 0x1029 sub1 = 0 */
    /* Reported once: polled on (a SYNC producer keeps the node busy) with still no
     * guarding RTR, there is no new event. */
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1006, 0, 100000), CO_ABORT_NONE);
    for (uint64_t at = 5500 * MS; at <= 5900 * MS; at += 100 * MS) {
        co_node_poll(&t.node, at);
    }
    CHECK(fake_count_id(&t.bus, 0x080) >= 4);
    CHECK_EQ(t.event_count, 1);
    ingest(&t, 6000 * MS, 0x705, "R1");
    CHECK_EQ(t.events[1].kind, CO_EC_LIFE_GUARD_RESUMED);
}

static void test_master_watch_sends_rtr_and_checks_replies(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    CHECK_EQ(co_guard_watch(&t.node, 5, 100, 3), CO_OK);
    CHECK_EQ(co_node_poll(&t.node, 0), 100 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#R1");
    ingest(&t, 1 * MS, 0x705, "7F");
    CHECK_EQ(t.events[0].kind, CO_EC_STARTED);
    CHECK_EQ(t.events[0].state, 0x7F);
    co_node_poll(&t.node, 100 * MS);
    ingest(&t, 101 * MS, 0x705, "85"); /* toggle 1, operational */
    CHECK_EQ(t.events[1].kind, CO_EC_STATE_CHANGED);
    CHECK_EQ(t.events[1].state, 0x05);
    co_node_poll(&t.node, 200 * MS);
    ingest(&t, 201 * MS, 0x705, "85"); /* toggle not alternated */
    CHECK_EQ(t.events[2].kind, CO_EC_GUARD_TOGGLE);
    CHECK_EQ(t.event_count, 3);
    /* Silence: the life time (300 ms) counts from the last good reply at 101 ms. */
    CHECK_EQ(co_node_poll(&t.node, 300 * MS), 400 * MS);
    CHECK_EQ(co_node_poll(&t.node, 400 * MS), 401 * MS);
    co_node_poll(&t.node, 401 * MS);
    CHECK_EQ(t.events[3].kind, CO_EC_GUARD_TIMEOUT);
    CHECK_EQ(t.events[3].node_id, 5);
    CHECK_EQ(fake_count_id(&t.bus, 0x705), 5); /* RTRs at 0, 100, 200, 300, 400 ms */
    /* The next good reply (toggle resynchronised to 0) resumes. */
    ingest(&t, 450 * MS, 0x705, "05");
    CHECK_EQ(t.events[4].kind, CO_EC_GUARD_RESUMED);
}

static void test_master_watch_limits(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_guard_watch(&t.node, 0, 100, 3), CO_ERR_ARG);
    CHECK_EQ(co_guard_watch(&t.node, 128, 100, 3), CO_ERR_ARG);
    CHECK_EQ(co_guard_watch(&t.node, 5, 100, 0), CO_ERR_ARG);
    for (uint8_t i = 0; i < CO_GUARD_WATCH_MAX; i++) {
        CHECK_EQ(co_guard_watch(&t.node, (uint8_t)(10 + i), 100, 2), CO_OK);
    }
    CHECK_EQ(co_guard_watch(&t.node, 60, 100, 2), CO_ERR_FULL);
    CHECK_EQ(co_guard_watch(&t.node, 10, 200, 2), CO_OK); /* replaces its own slot */
    CHECK_EQ(co_guard_watch(&t.node, 10, 0, 0), CO_OK);   /* removes it */
    co_frame_t reply = frm(0x70A, "05");
    CHECK(!co_node_accepts(&t.node, &reply));
    CHECK_EQ(co_guard_watch(&t.node, 60, 100, 2), CO_OK);
    /* A node the heartbeat consumer watches cannot be guarded, nor the reverse. */
    uint8_t b[4];
    co_put_u32(b, hb_consumer_value(20, 100));
    CHECK_EQ(co_node_write_net(&t.node, 0x1016, 1, b, 4), CO_ABORT_NONE);
    CHECK_EQ(co_guard_watch(&t.node, 20, 100, 2), CO_ERR_STATE);
    co_put_u32(b, hb_consumer_value(60, 100));
    CHECK_EQ(co_node_write_net(&t.node, 0x1016, 2, b, 4), CO_ABORT_PARAM_INCOMPAT);
}

/* ---- edges: the documented answers to inputs seldom seen */

static void test_guard_watch_limits_and_replies(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    /* One error control per node: a node consumed by heartbeat is not guarded too. */
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(9, 500)), CO_ABORT_NONE);
    CHECK_EQ(co_guard_watch(&t.node, 9, 100, 3), CO_ERR_STATE);
    CHECK_EQ(co_guard_watch(&t.node, 9, 0, 0), CO_OK); /* removing what is not there */
    for (uint8_t id = 10; id < 10 + CO_GUARD_WATCH_MAX; id++) {
        CHECK_EQ(co_guard_watch(&t.node, id, 100, 3), CO_OK);
    }
    CHECK_EQ(co_guard_watch(&t.node, 100, 100, 3), CO_ERR_FULL);
    CHECK_EQ(co_guard_watch(&t.node, 100, 0, 0), CO_OK);
    t.event_count = 0;
    /* Replies of node 10: a wrong length is malformed, another master's RTR is ignored. */
    uint32_t malformed = co_node_stats(&t.node)->rx_malformed;
    ingest(&t, 1 * MS, 0x70A, "05 00");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, malformed + 1);
    ingest(&t, 1 * MS, 0x70A, "R1");
    CHECK_EQ(t.event_count, 0);
    /* First reply: started; a change of state is reported; a boot-up restarts the toggle. */
    ingest(&t, 2 * MS, 0x70A, "7F");
    ingest(&t, 3 * MS, 0x70A, "85");
    ingest(&t, 4 * MS, 0x70A, "00");
    ingest(&t, 5 * MS, 0x70A, "FF"); /* any toggle is taken after a boot-up */
    CHECK_EQ(t.event_count, 4);
    CHECK_EQ(t.events[0].kind, CO_EC_STARTED);
    CHECK_EQ(t.events[1].kind, CO_EC_STATE_CHANGED);
    CHECK_EQ(t.events[1].state, CO_NMT_OPERATIONAL);
    CHECK_EQ(t.events[2].kind, CO_EC_BOOT);
    CHECK_EQ(t.events[3].kind, CO_EC_STATE_CHANGED);
    CHECK_EQ(t.events[3].previous, CO_NMT_INITIALISING);
}

static void test_life_time_change_while_guarded(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u16(&t, 0x100C, 0, 100), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x100D, 0, 2), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x705, "R1");                    /* monitoring starts: life time 200 ms */
    CHECK_EQ(write_u8(&t, 0x100D, 0, 5), CO_ABORT_NONE); /* from now: 500 ms */
    co_node_poll(&t.node, 250 * MS);
    CHECK_EQ(t.event_count, 0); /* the old 200 ms would have run out at 210 ms */
    co_node_poll(&t.node, 509 * MS);
    CHECK_EQ(t.event_count, 0);
    co_node_poll(&t.node, 510 * MS);
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_LIFE_GUARD);
    CHECK_EQ(co_node_poll(&t.node, 520 * MS), CO_TIME_NEVER); /* lost: nothing to wait for */
    CHECK_EQ(write_u8(&t, 0x100D, 0, 3), CO_ABORT_NONE);      /* changes nothing while lost */
    co_node_poll(&t.node, 590 * MS);
    CHECK_EQ(t.event_count, 1);
    ingest(&t, 600 * MS, 0x705, "R1"); /* resumed */
    CHECK_EQ(t.event_count, 2);
    CHECK_EQ(write_u16(&t, 0x100C, 0, 0), CO_ABORT_NONE); /* guarding off */
    co_node_poll(&t.node, 5000 * MS);
    CHECK_EQ(t.event_count, 2);
}

static void test_collision_report_of_an_empty_frame(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x705, "");
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_ID_COLLISION);
    CHECK_EQ(t.events[0].state, 0xFF); /* nothing heard: no byte was read */
}

static void test_guard_watch_repeats_and_timeouts_once(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_guard_watch(&t.node, 9, 100, 2), CO_OK);
    ingest(&t, 1 * MS, 0x709, "7F");
    ingest(&t, 2 * MS, 0x709, "FF"); /* same state: no event */
    CHECK_EQ(t.event_count, 1);
    co_node_poll(&t.node, 500 * MS);
    co_node_poll(&t.node, 900 * MS);
    CHECK_EQ(t.event_count, 2); /* one timeout, not one per poll */
    CHECK_EQ(t.events[1].kind, CO_EC_GUARD_TIMEOUT);
}

/* A node does not guard itself (0x700 + its ID is its own error-control COB-ID). */
static void test_own_node_id_refused_for_guarding(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_guard_watch(&t.node, 5, 100, 3), CO_ERR_ARG);
}

int main(void)
{
    RUN(test_replies_toggle_and_state);
    RUN(test_no_reply_while_heartbeat_runs);
    RUN(test_life_guarding_event_and_error_behaviour);
    RUN(test_master_watch_sends_rtr_and_checks_replies);
    RUN(test_master_watch_limits);
    RUN(test_guard_watch_limits_and_replies);
    RUN(test_life_time_change_while_guarded);
    RUN(test_collision_report_of_an_empty_frame);
    RUN(test_guard_watch_repeats_and_timeouts_once);
    RUN(test_own_node_id_refused_for_guarding);
    return check_summary();
}
