/* SPDX-License-Identifier: Apache-2.0 */
/* test_heartbeat.c -- heartbeat producer (0x1017) and consumer (0x1016). */
#include "check.h"
#include "harness.h"

#define MS 1000ull

static char dump[4096];

static void test_producer_period_and_state_byte(void)
{
    test_node_t t;
    test_node_init(&t, 5, 100);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_node_poll(&t.node, 0), 100 * MS);
    CHECK_EQ(co_node_poll(&t.node, 99 * MS), 100 * MS);
    CHECK_EQ(t.bus.count, 1);
    CHECK_EQ(co_node_poll(&t.node, 100 * MS), 200 * MS);
    ingest(&t, 150 * MS, 0x000, "01 05");
    CHECK_EQ(co_node_poll(&t.node, 200 * MS), 300 * MS);
    ingest(&t, 250 * MS, 0x000, "02 05");
    co_node_poll(&t.node, 300 * MS);
    ingest(&t, 350 * MS, 0x000, "80 05");
    co_node_poll(&t.node, 400 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00 705#7F 705#05 705#04 705#7F");
}

static void test_producer_new_period_takes_effect_at_once(void)
{
    test_node_t t;
    test_node_init(&t, 5, 100);
    co_node_start(&t.node, 0);
    co_node_poll(&t.node, 100 * MS);
    t.node.now_us = 130 * MS;
    CHECK_EQ(write_u16(&t, 0x1017, 0, 50), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 130 * MS), 180 * MS);
    CHECK_EQ(co_node_poll(&t.node, 180 * MS), 230 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x705), 3);
    CHECK_EQ(write_u16(&t, 0x1017, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 10000 * MS), CO_TIME_NEVER);
    CHECK_EQ(fake_count_id(&t.bus, 0x705), 3);
    /* And starts again from zero. */
    t.node.now_us = 10000 * MS;
    write_u16(&t, 0x1017, 0, 20);
    CHECK_EQ(co_node_poll(&t.node, 10000 * MS), 10020 * MS);
}

static void test_producer_late_poll_keeps_cadence(void)
{
    test_node_t t;
    test_node_init(&t, 5, 100);
    co_node_start(&t.node, 0);
    /* Polled 30 ms late: one heartbeat, the next one period after now. */
    CHECK_EQ(co_node_poll(&t.node, 130 * MS), 200 * MS);
    CHECK_EQ(co_node_poll(&t.node, 450 * MS), 550 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x705), 3);
}

static void test_consumer_starts_at_first_heartbeat_and_times_out_exactly(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(3, 250)), CO_ABORT_NONE);
    /* No heartbeat yet: no timeout however long. */
    CHECK_EQ(co_node_poll(&t.node, 5000 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.event_count, 0);
    ingest(&t, 6000 * MS, 0x703, "7F");
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_STARTED);
    CHECK_EQ(t.events[0].node_id, 3);
    CHECK_EQ(t.events[0].state, 0x7F);
    CHECK_EQ(co_hb_remote_state(&t.node, 3), 0x7F);
    CHECK_EQ(co_node_poll(&t.node, 6000 * MS), 6250 * MS);
    CHECK_EQ(co_node_poll(&t.node, 6250 * MS - 1), 6250 * MS);
    CHECK_EQ(t.event_count, 1);
    co_node_poll(&t.node, 6250 * MS);
    CHECK_EQ(t.event_count, 2);
    CHECK_EQ(t.events[1].kind, CO_EC_HB_TIMEOUT);
    CHECK_EQ(t.events[1].node_id, 3);
    /* Reported once. */
    co_node_poll(&t.node, 9000 * MS);
    CHECK_EQ(t.event_count, 2);
    /* Heartbeats again: resumed. */
    ingest(&t, 9100 * MS, 0x703, "05");
    CHECK_EQ(t.events[2].kind, CO_EC_HB_RESUMED);
    CHECK_EQ(t.events[2].state, 0x05);
}

static void test_consumer_each_heartbeat_moves_deadline(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    write_u32(&t, 0x1016, 2, hb_consumer_value(7, 100));
    for (uint64_t ms = 10; ms <= 1000; ms += 90) {
        ingest(&t, ms * MS, 0x707, "05");
        co_node_poll(&t.node, ms * MS + 99 * MS);
    }
    CHECK_EQ(test_find_event(&t, CO_EC_HB_TIMEOUT, 7), -1);
}

static void test_consumer_events_boot_state_remote_reset(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    write_u32(&t, 0x1016, 1, hb_consumer_value(4, 500));
    ingest(&t, 1 * MS, 0x704, "00");
    CHECK_EQ(t.events[0].kind, CO_EC_BOOT);
    ingest(&t, 2 * MS, 0x704, "7F");
    CHECK_EQ(t.events[1].kind, CO_EC_STARTED);
    ingest(&t, 3 * MS, 0x704, "05");
    CHECK_EQ(t.events[2].kind, CO_EC_STATE_CHANGED);
    CHECK_EQ(t.events[2].previous, 0x7F);
    CHECK_EQ(t.events[2].state, 0x05);
    ingest(&t, 4 * MS, 0x704, "05");
    CHECK_EQ(t.event_count, 3); /* same state: no event */
    ingest(&t, 5 * MS, 0x704, "00");
    CHECK_EQ(t.events[3].kind, CO_EC_REMOTE_RESET);
    CHECK_EQ(t.events[3].previous, 0x05);
    /* After a boot-up, monitoring waits for the next heartbeat: no timeout. */
    co_node_poll(&t.node, 5000 * MS);
    CHECK_EQ(test_find_event(&t, CO_EC_HB_TIMEOUT, 4), -1);
}

static void test_consumer_timeout_applies_error_behaviour(void)
{
    static const struct {
        uint8_t behaviour;
        co_nmt_state_t expected;
    } cases[] = {{0, CO_NMT_PRE_OPERATIONAL}, {1, CO_NMT_OPERATIONAL}, {2, CO_NMT_STOPPED}};
    for (unsigned i = 0; i < 3; i++) {
        test_node_t t;
        test_node_init(&t, 1, 0);
        co_node_start(&t.node, 0);
        co_nmt_apply(&t.node, CO_NMT_CMD_START);
        write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
        uint8_t b = cases[i].behaviour;
        CHECK_EQ(co_node_write_net(&t.node, 0x1029, 1, &b, 1), CO_ABORT_NONE);
        ingest(&t, 10 * MS, 0x703, "05");
        co_node_poll(&t.node, 110 * MS);
        CHECK_EQ(co_nmt_state(&t.node), cases[i].expected);
    }
    /* Behaviour 0 leaves a pre-operational node where it is. */
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    co_nmt_apply(&t.node, CO_NMT_CMD_STOP);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    ingest(&t, 10 * MS, 0x703, "05");
    co_node_poll(&t.node, 110 * MS);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
}

static void test_consumer_duplicate_node_refused(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100)), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1016, 2, hb_consumer_value(3, 200)), CO_ABORT_PARAM_INCOMPAT);
    CHECK_EQ(t.od.hb_consumer[1], 0);
    /* Same entry may change its own time; a zero time never conflicts. */
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(3, 300)), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1016, 2, hb_consumer_value(3, 0)), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1016, 3, hb_consumer_value(4, 100)), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1016, 9, hb_consumer_value(5, 100)), CO_ABORT_NO_SUB);
    /* Disabling entry 1 frees node 3 for entry 4. */
    CHECK_EQ(write_u32(&t, 0x1016, 1, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1016, 4, hb_consumer_value(3, 100)), CO_ABORT_NONE);
}

static void test_consumer_routes_follow_0x1016(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    co_frame_t hb = frm(0x70A, "05");
    CHECK(!co_node_accepts(&t.node, &hb));
    uint32_t changes = t.bus.routes_changed;
    write_u32(&t, 0x1016, 1, hb_consumer_value(10, 100));
    CHECK(co_node_accepts(&t.node, &hb));
    CHECK(t.bus.routes_changed > changes);
    write_u32(&t, 0x1016, 1, 0);
    CHECK(!co_node_accepts(&t.node, &hb));
}

static void test_consumer_malformed_heartbeats_ignored(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    ingest(&t, 1 * MS, 0x703, "05 00");
    ingest(&t, 1 * MS, 0x703, "");
    ingest(&t, 1 * MS, 0x703, "06");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 3);
    CHECK_EQ(t.event_count, 0);
    ingest(&t, 1 * MS, 0x703, "R1"); /* a master guarding node 3: not a heartbeat */
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 3);
    CHECK_EQ(t.event_count, 0);
}

static void test_not_booted_within_boot_time(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    t.node.cfg.boot_time_ms = 2000;
    co_node_start(&t.node, 0);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    write_u32(&t, 0x1016, 2, hb_consumer_value(4, 100));
    ingest(&t, 500 * MS, 0x704, "00");
    CHECK_EQ(co_node_poll(&t.node, 1999 * MS), 2000 * MS);
    CHECK_EQ(test_find_event(&t, CO_EC_NOT_BOOTED, 3), -1);
    co_node_poll(&t.node, 2000 * MS);
    CHECK(test_find_event(&t, CO_EC_NOT_BOOTED, 3) >= 0);
    CHECK_EQ(test_find_event(&t, CO_EC_NOT_BOOTED, 4), -1);
    uint32_t n = t.event_count;
    co_node_poll(&t.node, 9000 * MS);
    CHECK_EQ(t.event_count, n); /* once */
}

static void test_consumers_survive_restart_of_consumer(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    ingest(&t, 1 * MS, 0x703, "05");
    /* Reset communication restores 0x1016 to its default (unused). */
    co_nmt_apply(&t.node, CO_NMT_CMD_RESET_COMMUNICATION);
    co_frame_t hb = frm(0x703, "05");
    CHECK(!co_node_accepts(&t.node, &hb));
    co_node_poll(&t.node, 1000 * MS);
    CHECK_EQ(test_find_event(&t, CO_EC_HB_TIMEOUT, 3), -1);
}

/* ---- edges: the documented answers to inputs seldom seen */

static void test_unconfigured_node_sends_no_heartbeat(void)
{
    test_node_t t;
    CHECK_EQ(test_node_init(&t, CO_NODE_ID_UNCONFIGURED, 100), CO_OK);
    co_node_start(&t.node, 0);
    co_node_poll(&t.node, 1000 * MS);
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_INITIALISING);
    CHECK_EQ(co_hb_remote_state(&t.node, 9), 0xFF); /* not consumed */
}

static void test_consumer_entry_of_the_wrong_length(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u16(&t, 0x1016, 1, 500), CO_ABORT_LEN_LOW);
    CHECK_EQ(co_hb_remote_state(&t.node, 0), 0xFF);
}

static void test_heartbeat_consumer_edges(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    /* Node-ID 200 is no node: the entry is unused, nothing is routed for it. */
    uint32_t routes = co_node_route_count(&t.node);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(200, 100)), CO_ABORT_NONE);
    CHECK_EQ(co_node_route_count(&t.node), routes);
    CHECK_EQ(co_node_route_id(&t.node, routes), 0); /* past the end */
    /* Two boot-ups in a row: two boots, not a remote reset (it never ran in between). */
    CHECK_EQ(write_u32(&t, 0x1016, 2, hb_consumer_value(9, 100)), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x709, "00");
    ingest(&t, 2 * MS, 0x709, "00");
    CHECK_EQ(t.event_count, 2);
    CHECK_EQ(t.events[0].kind, CO_EC_BOOT);
    CHECK_EQ(t.events[1].kind, CO_EC_BOOT);
}

/* A node does not consume its own heartbeat (0x700 + its ID is its own error-control
 * COB-ID). */
static void test_own_node_id_refused_for_consuming(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(5, 100)), CO_ABORT_PARAM_INCOMPAT);
}

int main(void)
{
    RUN(test_producer_period_and_state_byte);
    RUN(test_producer_new_period_takes_effect_at_once);
    RUN(test_producer_late_poll_keeps_cadence);
    RUN(test_consumer_starts_at_first_heartbeat_and_times_out_exactly);
    RUN(test_consumer_each_heartbeat_moves_deadline);
    RUN(test_consumer_events_boot_state_remote_reset);
    RUN(test_consumer_timeout_applies_error_behaviour);
    RUN(test_consumer_duplicate_node_refused);
    RUN(test_consumer_routes_follow_0x1016);
    RUN(test_consumer_malformed_heartbeats_ignored);
    RUN(test_not_booted_within_boot_time);
    RUN(test_consumers_survive_restart_of_consumer);
    RUN(test_unconfigured_node_sends_no_heartbeat);
    RUN(test_consumer_entry_of_the_wrong_length);
    RUN(test_heartbeat_consumer_edges);
    RUN(test_own_node_id_refused_for_consuming);
    return check_summary();
}
