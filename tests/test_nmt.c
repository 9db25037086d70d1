/* SPDX-License-Identifier: Apache-2.0 */
/* test_nmt.c -- NMT state machine: boot-up, commands, resets, per-state services. */
#include "check.h"
#include "harness.h"

#define MS 1000ull

static char dump[4096];

static void test_boot_sends_one_bootup_then_pre_operational(void)
{
    test_node_t t;
    CHECK_EQ(test_node_init(&t, 5, 0), CO_OK);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_INITIALISING);
    CHECK_EQ(t.bus.count, 0); /* init sends nothing */
    CHECK_EQ(co_node_start(&t.node, 0), CO_OK);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(t.reset_count, 2);
    CHECK_EQ(t.resets[0], CO_RESET_APPLICATION);
    CHECK_EQ(t.resets[1], CO_RESET_COMMUNICATION);
    CHECK_EQ(t.state_count, 1);
    CHECK_EQ(t.states[0], CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_node_start(&t.node, 0), CO_ERR_STATE);
    /* Nothing more over time without a heartbeat configured. */
    CHECK_EQ(co_node_poll(&t.node, 10000000), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 1);
}

static void test_self_start_enters_operational(void)
{
    test_node_t t;
    test_node_init(&t, 9, 0);
    t.node.cfg.self_start = true;
    co_node_start(&t.node, 0);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "709#00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
}

static void test_commands_to_own_id_and_to_all(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 1, 0x000, "01 05");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    ingest(&t, 2, 0x000, "02 00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
    ingest(&t, 3, 0x000, "80 05");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
    ingest(&t, 4, 0x000, "01 00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    /* Addressed to another node: no change, not malformed. */
    ingest(&t, 5, 0x000, "02 06");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
    CHECK_EQ(t.bus.count, 1); /* state changes send nothing by themselves */
}

static void test_wrong_length_and_unknown_command_are_ignored(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 1, 0x000, "01");
    ingest(&t, 1, 0x000, "01 05 00");
    ingest(&t, 1, 0x000, "");
    ingest(&t, 1, 0x000, "03 05");
    ingest(&t, 1, 0x000, "R2");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 5);
}

static void test_reset_node_restores_application_objects(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&t.node, 0x1017, 0, 500), CO_ABORT_NONE);
    CHECK_EQ(t.od.app_u32, 0xCAFE);
    ingest(&t, 10, 0x000, "01 05");
    fake_clear(&t.bus);
    ingest(&t, 20, 0x000, "81 05");
    CHECK_EQ(t.od.app_u32, 0x12345678);
    CHECK_EQ(t.od.hb_period_ms, 0);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
}

static void test_reset_communication_keeps_application_objects(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    co_node_set_uint(&t.node, 0x1017, 0, 500);
    fake_clear(&t.bus);
    t.reset_count = 0;
    ingest(&t, 20, 0x000, "82 00");
    CHECK_EQ(t.od.app_u32, 0xCAFE);
    CHECK_EQ(t.od.hb_period_ms, 0);
    CHECK_EQ(t.reset_count, 1);
    CHECK_EQ(t.resets[0], CO_RESET_COMMUNICATION);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00");
}

static void test_node_id_relative_default_applied_at_reset(void)
{
    test_node_t t;
    test_node_init(&t, 42, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(t.od.emcy_cob_id, 0x80 + 42);
    co_node_set_uint(&t.node, 0x1014, 0, 0x80000000u);
    co_nmt_apply(&t.node, CO_NMT_CMD_RESET_COMMUNICATION);
    CHECK_EQ(t.od.emcy_cob_id, 0x80 + 42);
    /* The guarding COB-ID follows the node-ID too. */
    co_frame_t rtr = frm(0x72A, "R1");
    CHECK(co_node_accepts(&t.node, &rtr));
    co_frame_t other = frm(0x705, "R1");
    CHECK(!co_node_accepts(&t.node, &other));
}

static void test_unconfigured_node_stays_initialising(void)
{
    test_node_t t;
    CHECK_EQ(test_node_init(&t, CO_NODE_ID_UNCONFIGURED, 100), CO_OK);
    co_node_start(&t.node, 0);
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_INITIALISING);
    ingest(&t, 1, 0x000, "01 00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_INITIALISING);
    CHECK_EQ(co_node_stats(&t.node)->rx_gated, 1);
    co_node_poll(&t.node, 1000000);
    CHECK_EQ(t.bus.count, 0); /* no heartbeat either */
    /* Not even when the application sets a heartbeat time while it waits. */
    CHECK_EQ(co_node_set_uint(&t.node, 0x1017, 0, 50), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 1000000), CO_TIME_NEVER);
    CHECK_EQ(co_node_poll(&t.node, 2000000), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(co_nmt_apply(&t.node, CO_NMT_CMD_START), CO_ERR_STATE);
}

static void test_service_table(void)
{
    CHECK(co_nmt_allows(CO_NMT_INITIALISING, CO_SVC_BOOTUP));
    CHECK(!co_nmt_allows(CO_NMT_INITIALISING, CO_SVC_NMT));
    CHECK(!co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_BOOTUP));
    CHECK(co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_SDO));
    CHECK(co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_SYNC));
    CHECK(co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_TIME));
    CHECK(co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_EMCY));
    CHECK(co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_ERROR_CONTROL));
    CHECK(!co_nmt_allows(CO_NMT_PRE_OPERATIONAL, CO_SVC_PDO));
    CHECK(co_nmt_allows(CO_NMT_OPERATIONAL, CO_SVC_PDO));
    CHECK(co_nmt_allows(CO_NMT_OPERATIONAL, CO_SVC_SDO));
    CHECK(co_nmt_allows(CO_NMT_OPERATIONAL, CO_SVC_NMT));
    CHECK(!co_nmt_allows(CO_NMT_OPERATIONAL, CO_SVC_BOOTUP));
    CHECK(co_nmt_allows(CO_NMT_STOPPED, CO_SVC_NMT));
    CHECK(co_nmt_allows(CO_NMT_STOPPED, CO_SVC_ERROR_CONTROL));
    CHECK(!co_nmt_allows(CO_NMT_STOPPED, CO_SVC_SDO));
    CHECK(!co_nmt_allows(CO_NMT_STOPPED, CO_SVC_PDO));
    CHECK(!co_nmt_allows(CO_NMT_STOPPED, CO_SVC_EMCY));
    CHECK(!co_nmt_allows(CO_NMT_STOPPED, CO_SVC_SYNC));
    CHECK(!co_nmt_allows(CO_NMT_STOPPED, CO_SVC_TIME));
    CHECK_STR(co_nmt_state_name(0x7F), "pre-operational");
    CHECK_STR(co_nmt_state_name(0x05), "operational");
    CHECK_STR(co_nmt_state_name(0x04), "stopped");
    CHECK_STR(co_nmt_state_name(0x00), "initialising");
    CHECK_STR(co_nmt_state_name(0x33), "unknown");
}

static void test_master_sends_commands_byte_exact(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    CHECK_EQ(co_nmt_send(&t.node, CO_NMT_CMD_START, 5), CO_OK);
    CHECK_EQ(co_nmt_send(&t.node, CO_NMT_CMD_STOP, 127), CO_OK);
    CHECK_EQ(co_nmt_send(&t.node, CO_NMT_CMD_ENTER_PRE_OPERATIONAL, 5), CO_OK);
    CHECK_EQ(co_nmt_send(&t.node, CO_NMT_CMD_RESET_COMMUNICATION, 5), CO_OK);
    CHECK_EQ(co_nmt_send(&t.node, CO_NMT_CMD_RESET_NODE, 5), CO_OK);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "000#0105 000#027F 000#8005 000#8205 000#8105");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL); /* none was for node 1 */
    CHECK_EQ(co_nmt_send(&t.node, CO_NMT_CMD_START, 128), CO_ERR_ARG);
    CHECK_EQ(co_nmt_send(&t.node, (co_nmt_cmd_t)0x03, 5), CO_ERR_ARG);
    /* To all: the master applies it to itself as well. */
    fake_clear(&t.bus);
    co_nmt_send(&t.node, CO_NMT_CMD_START, 0);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "000#0100");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    /* Reset of itself: the command leaves first, then its own boot-up. */
    fake_clear(&t.bus);
    co_nmt_send(&t.node, CO_NMT_CMD_RESET_COMMUNICATION, 1);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "000#8201 701#00");
}

static void test_stopped_node_still_obeys_nmt(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 1, 0x000, "02 05");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
    fake_clear(&t.bus);
    ingest(&t, 2, 0x000, "81 05");
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
}

/* ---- edges: the documented answers to inputs seldom seen */

static void test_nmt_before_start(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    CHECK_EQ(co_nmt_apply(&t.node, CO_NMT_CMD_START), CO_ERR_STATE);
    CHECK_EQ(t.bus.count, 0);
}

/* ---- NMT states and the frames that wait in the transmit queue */

/* An SDO response that waits in the queue (driver busy) while the NMT command `cmd` arrives
 * and takes the node to `state`; then the driver is free again. */
static void queued_response_then(test_node_t *t, const char *cmd, co_nmt_state_t state)
{
    test_node_init(t, 5, 0);
    co_node_start(&t->node, 0);
    fake_clear(&t->bus);
    t->bus.busy = true;
    ingest(t, 1 * MS, 0x605, "40 00 10 00 00 00 00 00");
    ingest(t, 2 * MS, 0x000, cmd);
    CHECK_EQ(co_nmt_state(&t->node), state);
    t->bus.busy = false;
    (void)co_node_poll(&t->node, 3 * MS);
}

/* nmt.h: SDO runs in pre-operational and operational only, and "every producer" consults
 * the service table. An SDO response that waited in the queue when an NMT stop arrived must
 * not leave once the node is stopped. */
static void test_sdo_response_queued_before_stop_is_not_sent_when_stopped(void)
{
    test_node_t t;
    queued_response_then(&t, "02 05", CO_NMT_STOPPED);
    CHECK_EQ(fake_count_id(&t.bus, 0x585), 0);
}

/* The other way round: an SDO response that waited when an NMT start arrived may still
 * leave, as operational allows SDO. */
static void test_sdo_response_queued_before_start_is_sent_when_operational(void)
{
    test_node_t t;
    queued_response_then(&t, "01 05", CO_NMT_OPERATIONAL);
    CHECK_EQ(fake_count_id(&t.bus, 0x585), 1);
    CHECK_EQ(co_node_stats(&t.node)->tx_gated, 0);
}

/* A heartbeat left waiting by a busy driver must not leave after the boot-up that a reset
 * sends: the reset makes it stale (same COB-ID, so it would otherwise go first). */
static void test_reset_drops_a_heartbeat_left_waiting(void)
{
    test_node_t t;
    test_node_init(&t, 5, 100);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    t.bus.busy = true;
    co_node_poll(&t.node, 100 * MS); /* the heartbeat 705#7F waits */
    co_frame_t reset = frm(0x000, "81 05");
    co_node_ingest(&t.node, 110 * MS, &reset);
    t.bus.busy = false;
    co_node_poll(&t.node, 111 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00");
    CHECK_EQ(co_node_stats(&t.node)->tx_gated, 1);
}

/* An unconfigured node (0xFF) keeps $NODEID defaults at their base: 0x1014 is 0x80, not
 * 0x80 + 0xFF. */
static void test_unconfigured_node_keeps_node_id_defaults_at_base(void)
{
    test_node_t t;
    test_node_init(&t, CO_NODE_ID_UNCONFIGURED, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(t.od.emcy_cob_id, 0x80);
}

int main(void)
{
    RUN(test_boot_sends_one_bootup_then_pre_operational);
    RUN(test_self_start_enters_operational);
    RUN(test_commands_to_own_id_and_to_all);
    RUN(test_wrong_length_and_unknown_command_are_ignored);
    RUN(test_reset_node_restores_application_objects);
    RUN(test_reset_communication_keeps_application_objects);
    RUN(test_node_id_relative_default_applied_at_reset);
    RUN(test_unconfigured_node_stays_initialising);
    RUN(test_service_table);
    RUN(test_master_sends_commands_byte_exact);
    RUN(test_stopped_node_still_obeys_nmt);
    RUN(test_nmt_before_start);
    RUN(test_sdo_response_queued_before_stop_is_not_sent_when_stopped);
    RUN(test_sdo_response_queued_before_start_is_sent_when_operational);
    RUN(test_reset_drops_a_heartbeat_left_waiting);
    RUN(test_unconfigured_node_keeps_node_id_defaults_at_base);
    return check_summary();
}
