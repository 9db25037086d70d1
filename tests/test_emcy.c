/* SPDX-License-Identifier: Apache-2.0 */
/* test_emcy.c -- EMCY producer (0x1001, 0x1003, 0x1014, 0x1015) and consumer (0x1028). */
#include "check.h"
#include "harness.h"

#define MS 1000ull

static char dump[4096];

/* What on_emcy received. */
static co_emcy_msg_t got[16];
static unsigned got_count;

static void rec_emcy(void *user, const co_emcy_msg_t *msg)
{
    (void)user;
    if (got_count < 16) {
        got[got_count++] = *msg;
    }
}

/* A started node (pre-operational) with the boot-up frame cleared away. */
static void start(test_node_t *t, uint8_t id)
{
    test_node_init(t, id, 0);
    t->cfg.on_emcy = rec_emcy;
    co_node_init(&t->node, &t->cfg);
    got_count = 0;
    co_node_start(&t->node, 0);
    fake_clear(&t->bus);
}

static const char *bus(test_node_t *t) { return fake_dump(&t->bus, dump, sizeof dump); }

static void test_register_bit_of_each_group(void)
{
    CHECK_EQ(co_emcy_register_bit(0x1000), 0x00);
    CHECK_EQ(co_emcy_register_bit(0x2310), 0x02);
    CHECK_EQ(co_emcy_register_bit(0x3210), 0x04);
    CHECK_EQ(co_emcy_register_bit(0x4210), 0x08);
    CHECK_EQ(co_emcy_register_bit(0x5000), 0x00);
    CHECK_EQ(co_emcy_register_bit(0x8000), 0x00);
    CHECK_EQ(co_emcy_register_bit(0x8100), 0x10);
    CHECK_EQ(co_emcy_register_bit(0x8130), 0x10);
    CHECK_EQ(co_emcy_register_bit(0x8FFF), 0x10);
    CHECK_EQ(co_emcy_register_bit(0x9000), 0x00);
    CHECK_EQ(co_emcy_register_bit(0xF000), 0x00);
    CHECK_EQ(co_emcy_register_bit(0xFF00), 0x80);
    CHECK_EQ(co_emcy_register_bit(0xFFFF), 0x80);
}

static void test_raise_and_clear_frames_and_register(void)
{
    test_node_t t;
    start(&t, 5);
    static const uint8_t mfr[5] = {0x11, 0x22, 0x33, 0x44, 0x55};
    CHECK_EQ(co_emcy_raise(&t.node, 0x2310, mfr), CO_OK);
    CHECK_EQ(t.od.error_register, 0x03);
    CHECK(co_emcy_active(&t.node, 0x2310));
    CHECK_EQ(co_emcy_raise(&t.node, 0x4210, NULL), CO_OK);
    CHECK_EQ(t.od.error_register, 0x0B);
    CHECK_STR(bus(&t), "085#1023031122334455 085#10420B0000000000");
    fake_clear(&t.bus);
    /* Not the last: the register changes, no frame. */
    CHECK_EQ(co_emcy_clear(&t.node, 0x2310), CO_OK);
    CHECK_EQ(t.od.error_register, 0x09);
    CHECK(!co_emcy_active(&t.node, 0x2310));
    CHECK_EQ(t.bus.count, 0);
    /* The last: error reset, register 0. */
    CHECK_EQ(co_emcy_clear(&t.node, 0x4210), CO_OK);
    CHECK_EQ(t.od.error_register, 0x00);
    CHECK_STR(bus(&t), "085#0000000000000000");
    CHECK_EQ(co_emcy_clear(&t.node, 0x4210), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_emcy_raise(&t.node, 0x0000, NULL), CO_ERR_ARG);
    CHECK_EQ(t.bus.count, 1);
    CHECK_EQ(co_node_poll(&t.node, 1 * MS), CO_TIME_NEVER);
}

static void test_raising_an_active_code_sends_again(void)
{
    test_node_t t;
    start(&t, 5);
    co_emcy_raise(&t.node, 0xFF01, NULL);
    co_emcy_raise(&t.node, 0xFF01, NULL);
    CHECK_STR(bus(&t), "085#01FF810000000000 085#01FF810000000000");
    CHECK_EQ(t.od.error_count, 2);
    /* One clear ends it. */
    fake_clear(&t.bus);
    co_emcy_clear(&t.node, 0xFF01);
    CHECK_STR(bus(&t), "085#0000000000000000");
}

static void test_full_active_table_still_sends_and_records(void)
{
    test_node_t t;
    start(&t, 5);
    for (uint16_t i = 0; i < CO_EMCY_ACTIVE_MAX; i++) {
        CHECK_EQ(co_emcy_raise(&t.node, (uint16_t)(0x1000 + i), NULL), CO_OK);
    }
    fake_clear(&t.bus);
    CHECK_EQ(co_emcy_raise(&t.node, 0x3100, NULL), CO_ERR_FULL);
    CHECK_STR(bus(&t), "085#0031050000000000");
    CHECK_EQ(t.od.error_history[0], 0x3100);
    CHECK(!co_emcy_active(&t.node, 0x3100));
    /* An active code raised again needs no room. */
    CHECK_EQ(co_emcy_raise(&t.node, 0x1000, NULL), CO_OK);
}

static void test_history_newest_first_and_cleared_by_writing_zero(void)
{
    test_node_t t;
    start(&t, 5);
    static const uint8_t mfr[5] = {0xAA, 0xBB, 0xCC, 0xDD, 0xEE};
    co_emcy_raise(&t.node, 0x2310, mfr);
    co_emcy_raise(&t.node, 0x3210, NULL);
    co_emcy_clear(&t.node, 0x3210); /* clears are not recorded */
    co_emcy_raise(&t.node, 0x4210, NULL);
    CHECK_EQ(t.od.error_count, 3);
    CHECK_EQ(t.od.error_history[0], 0x4210);
    CHECK_EQ(t.od.error_history[1], 0x3210);
    CHECK_EQ(t.od.error_history[2], 0xBBAA2310u); /* additional info in the high 16 bits */
    CHECK_EQ(t.od.error_history[3], 0);
    /* Over 8: the oldest fall off, the count stays at what the OD holds. */
    for (uint16_t i = 1; i <= 7; i++) {
        co_emcy_raise(&t.node, (uint16_t)(0x5000 + i), NULL);
    }
    CHECK_EQ(t.od.error_count, EXAMPLE_EMCY_HISTORY);
    CHECK_EQ(t.od.error_history[0], 0x5007);
    CHECK_EQ(t.od.error_history[6], 0x5001);
    CHECK_EQ(t.od.error_history[7], 0x4210);
    /* Through the network as a master would read it. */
    uint8_t buf[4];
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&t.node, 0x1003, 1, buf, sizeof buf, &len), CO_ABORT_NONE);
    CHECK_EQ(co_get_u32(buf), 0x5007);
    /* Only 0 may be written to sub0; the entries are read-only. */
    CHECK_EQ(write_u8(&t, 0x1003, 0, 1), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1003, 0, 0xFF), 0x06090030u);
    CHECK_EQ(t.od.error_count, EXAMPLE_EMCY_HISTORY);
    CHECK_EQ(write_u32(&t, 0x1003, 1, 0), CO_ABORT_READ_ONLY);
    CHECK_EQ(write_u8(&t, 0x1003, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(t.od.error_count, 0);
    for (unsigned i = 0; i < EXAMPLE_EMCY_HISTORY; i++) {
        CHECK_EQ(t.od.error_history[i], 0);
    }
    /* An empty history has no data above sub0 (CiA 301 7.5.2.4): an abort, not 0. */
    CHECK_EQ(co_node_read_net(&t.node, 0x1003, 1, buf, sizeof buf, &len), CO_ABORT_NO_DATA);
    CHECK_EQ(co_node_read_net(&t.node, 0x1003, 0, buf, sizeof buf, &len), CO_ABORT_NONE);
    CHECK_EQ(buf[0], 0);
    /* Clearing the history does not clear the errors. */
    CHECK_EQ(t.od.error_register, 0x0B);
    co_emcy_raise(&t.node, 0x6100, NULL);
    CHECK_EQ(t.od.error_count, 1);
    CHECK_EQ(t.od.error_history[0], 0x6100);
    /* By SDO: sub1 answers, sub2 (above the count) is aborted with 0x08000024. */
    fake_clear(&t.bus);
    ingest(&t, 0, 0x605, "40 03 10 01 00 00 00 00");
    ingest(&t, 0, 0x605, "40 03 10 02 00 00 00 00");
    CHECK_STR(bus(&t), "585#4303100100610000 585#8003100224000008");
}

static void test_inhibit_time_spaces_frames_exactly(void)
{
    test_node_t t;
    start(&t, 5);
    CHECK_EQ(write_u16(&t, 0x1015, 0, 10), CO_ABORT_NONE); /* 1 ms */
    co_emcy_raise(&t.node, 0x5001, NULL);
    co_emcy_raise(&t.node, 0x5002, NULL);
    CHECK_STR(bus(&t), "085#0150010000000000");
    CHECK_EQ(co_node_poll(&t.node, 0), 1 * MS);
    CHECK_EQ(co_node_poll(&t.node, 1 * MS - 1), 1 * MS);
    CHECK_EQ(t.bus.count, 1);
    CHECK_EQ(co_node_poll(&t.node, 1 * MS), CO_TIME_NEVER);
    CHECK_STR(bus(&t), "085#0150010000000000 085#0250010000000000");
    /* 0.5 ms after the last frame: waits the other half. */
    CHECK_EQ(co_node_poll(&t.node, 1500), CO_TIME_NEVER);
    co_emcy_raise(&t.node, 0x5003, NULL);
    CHECK_EQ(t.bus.count, 2);
    CHECK_EQ(co_node_poll(&t.node, 1500), 2 * MS);
    CHECK_EQ(co_node_poll(&t.node, 2 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 3);
    /* Long after: straight out. */
    co_node_poll(&t.node, 10 * MS);
    co_emcy_raise(&t.node, 0x5004, NULL);
    CHECK_EQ(t.bus.count, 4);
    /* A late poll: the spacing counts from when the frame really left. */
    co_emcy_raise(&t.node, 0x5005, NULL);
    co_emcy_raise(&t.node, 0x5006, NULL);
    CHECK_EQ(co_node_poll(&t.node, 11 * MS + 300), 12 * MS + 300);
    CHECK_EQ(t.bus.count, 5);
    CHECK_EQ(co_node_poll(&t.node, 12 * MS + 300), CO_TIME_NEVER);
    CHECK_STR(bus(&t), "085#0150010000000000 085#0250010000000000 085#0350010000000000 "
                       "085#0450010000000000 085#0550010000000000 085#0650010000000000");
}

static void test_new_inhibit_time_takes_effect_at_once(void)
{
    test_node_t t;
    start(&t, 5);
    write_u16(&t, 0x1015, 0, 100); /* 10 ms */
    co_emcy_raise(&t.node, 0x5001, NULL);
    co_emcy_raise(&t.node, 0x5002, NULL);
    CHECK_EQ(co_node_poll(&t.node, 1 * MS), 10 * MS);
    /* Shorter: the waiting frame may leave 2 ms after the last one. */
    CHECK_EQ(write_u16(&t, 0x1015, 0, 20), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 1 * MS), 2 * MS);
    CHECK_EQ(co_node_poll(&t.node, 2 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 2);
    /* Longer: it waits the longer time. */
    co_emcy_raise(&t.node, 0x5003, NULL);
    CHECK_EQ(co_node_poll(&t.node, 2 * MS), 4 * MS);
    CHECK_EQ(write_u16(&t, 0x1015, 0, 50), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 4 * MS), 7 * MS);
    CHECK_EQ(t.bus.count, 2);
    CHECK_EQ(co_node_poll(&t.node, 7 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 3);
}

static void test_full_queue_drops_the_newest(void)
{
    test_node_t t;
    start(&t, 5);
    write_u16(&t, 0x1015, 0, 100); /* 10 ms */
    for (uint16_t i = 1; i <= CO_EMCY_QUEUE_LEN + 2; i++) {
        co_emcy_raise(&t.node, (uint16_t)(0x5000 + i), NULL);
    }
    CHECK_EQ(t.node.emcy.dropped, 1);
    CHECK_EQ(t.bus.count, 1);
    CHECK_EQ(t.od.error_count, CO_EMCY_QUEUE_LEN + 2); /* every raise is recorded */
    uint64_t next = co_node_poll(&t.node, 0);
    for (int guard = 0; next != CO_TIME_NEVER && guard < 10; guard++) {
        next = co_node_poll(&t.node, next);
    }
    CHECK_STR(bus(&t), "085#0150010000000000 085#0250010000000000 085#0350010000000000 "
                       "085#0450010000000000 085#0550010000000000");
    CHECK_EQ(t.node.now_us, 40 * MS);
}

static void test_not_sent_while_stopped_sent_on_pre_operational(void)
{
    test_node_t t;
    start(&t, 5);
    write_u16(&t, 0x1015, 0, 10); /* 1 ms */
    ingest(&t, 1 * MS, 0x000, "02 05");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
    co_emcy_raise(&t.node, 0x4210, NULL);
    co_emcy_clear(&t.node, 0x4210);
    co_emcy_raise(&t.node, 0x3210, NULL);
    /* Recorded, not sent, nothing scheduled. */
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(t.od.error_register, 0x05);
    CHECK_EQ(t.od.error_count, 2);
    CHECK_EQ(co_node_poll(&t.node, 50 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 0);
    /* Pre-operational: out in order, one inhibit time apart. */
    ingest(&t, 60 * MS, 0x000, "80 05");
    CHECK_STR(bus(&t), "085#1042090000000000");
    CHECK_EQ(co_node_poll(&t.node, 60 * MS), 61 * MS);
    co_node_poll(&t.node, 61 * MS);
    co_node_poll(&t.node, 62 * MS);
    CHECK_STR(bus(&t), "085#1042090000000000 085#0000000000000000 085#1032050000000000");
    /* Operational sends too. */
    ingest(&t, 70 * MS, 0x000, "01 05");
    co_emcy_raise(&t.node, 0x3211, NULL);
    CHECK_EQ(t.bus.count, 4);
}

static void test_cob_id_off_29_bit_and_changed(void)
{
    test_node_t t;
    start(&t, 5);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x80000085u), CO_ABORT_NONE);
    CHECK_EQ(co_emcy_raise(&t.node, 0x4210, NULL), CO_OK);
    CHECK_EQ(co_emcy_clear(&t.node, 0x4210), CO_OK);
    co_emcy_raise(&t.node, 0x3210, NULL);
    /* Off: nothing sent or queued, errors and history kept. */
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(t.node.emcy.queue_count, 0);
    CHECK_EQ(t.od.error_register, 0x05);
    CHECK_EQ(t.od.error_count, 2);
    CHECK(co_emcy_active(&t.node, 0x3210));
    /* On again: nothing stale comes out; new raises go on the new COB-ID. */
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x0000009Au), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 1 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 0);
    co_emcy_raise(&t.node, 0x3211, NULL);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x8000009Au), CO_ABORT_NONE); /* valid -> valid: via off */
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x20012345u), CO_ABORT_NONE);
    co_emcy_clear(&t.node, 0x3210);
    co_emcy_clear(&t.node, 0x3211);
    CHECK_STR(bus(&t), "09A#1132050000000000 00012345#0000000000000000");
    CHECK(t.bus.frames[1].flags & CO_FRAME_EXT);
    /* Turning it off drops what waits for the inhibit time. */
    write_u32(&t, 0x1014, 0, 0x80000085u);
    write_u32(&t, 0x1014, 0, 0x85);
    write_u16(&t, 0x1015, 0, 10);
    co_node_poll(&t.node, 10 * MS);
    fake_clear(&t.bus);
    co_emcy_raise(&t.node, 0x5001, NULL);
    co_emcy_raise(&t.node, 0x5002, NULL);
    CHECK_EQ(t.node.emcy.queue_count, 1);
    write_u32(&t, 0x1014, 0, 0x80000085u);
    CHECK_EQ(t.node.emcy.queue_count, 0);
    CHECK_EQ(co_node_poll(&t.node, 15 * MS), CO_TIME_NEVER);
    CHECK_STR(bus(&t), "085#0150010000000000");
}

/* CiA 301 7.5.2.17: the identifier of a valid EMCY COB-ID does not change; a new one goes
 * through "not valid" (bit 31). Writing the value it has is no change. */
static void test_valid_cob_id_changes_only_through_not_valid(void)
{
    test_node_t t;
    start(&t, 5);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x86), CO_ABORT_VALUE);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x20000085u), CO_ABORT_VALUE);
    CHECK_EQ(t.od.emcy_cob_id, 0x85u);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x85), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x80000085u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x80000086u), CO_ABORT_NONE); /* not valid: free */
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x86), CO_ABORT_NONE);
    co_emcy_raise(&t.node, 0x1000, NULL);
    CHECK_STR(bus(&t), "086#0010010000000000");
}

static void test_heartbeat_loss_raises_0x8130_and_resume_clears_it(void)
{
    test_node_t t;
    start(&t, 1);
    co_nmt_apply(&t.node, CO_NMT_CMD_START);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100)), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x703, "05");
    CHECK_EQ(co_node_poll(&t.node, 10 * MS), 110 * MS);
    CHECK_EQ(co_node_poll(&t.node, 110 * MS - 1), 110 * MS);
    CHECK_EQ(t.bus.count, 0);
    co_node_poll(&t.node, 110 * MS);
    CHECK_STR(bus(&t), "081#3081110000000000");
    CHECK_EQ(t.od.error_register, 0x11);
    CHECK_EQ(t.od.error_history[0], 0x8130);
    CHECK(co_emcy_active(&t.node, 0x8130));
    /* 0x1029 sub1 = 0: operational -> pre-operational (where EMCY still runs). */
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
    ingest(&t, 300 * MS, 0x703, "05");
    CHECK_STR(bus(&t), "081#3081110000000000 081#0000000000000000");
    CHECK_EQ(t.od.error_register, 0);
    CHECK(!co_emcy_active(&t.node, 0x8130));
}

/* A boot-up ends 0x8130 when nothing is lost any more, even from a node no longer counted
 * as lost (its consumer entry written anew while it was: monitoring waits afresh). */
static void test_heartbeat_loss_ends_when_the_node_boots(void)
{
    test_node_t t;
    start(&t, 1);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100)), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x703, "05");
    co_node_poll(&t.node, 110 * MS);
    CHECK(co_emcy_active(&t.node, 0x8130));
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(3, 200)), CO_ABORT_NONE);
    CHECK(co_emcy_active(&t.node, 0x8130)); /* not heard yet */
    fake_clear(&t.bus);
    ingest(&t, 300 * MS, 0x703, "00");
    CHECK_STR(bus(&t), "081#0000000000000000");
    CHECK(!co_emcy_active(&t.node, 0x8130));
}

static void test_heartbeat_loss_of_two_nodes_clears_when_both_are_back(void)
{
    test_node_t t;
    start(&t, 1);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    write_u32(&t, 0x1016, 2, hb_consumer_value(4, 100));
    ingest(&t, 0, 0x703, "05");
    ingest(&t, 0, 0x704, "05");
    co_node_poll(&t.node, 100 * MS);
    /* Each loss reports. */
    CHECK_STR(bus(&t), "081#3081110000000000 081#3081110000000000");
    fake_clear(&t.bus);
    ingest(&t, 200 * MS, 0x703, "05");
    CHECK_EQ(t.bus.count, 0);
    ingest(&t, 210 * MS, 0x704, "05");
    CHECK_STR(bus(&t), "081#0000000000000000");
}

static void test_bus_events(void)
{
    test_node_t t;
    start(&t, 5);
    co_nmt_apply(&t.node, CO_NMT_CMD_START);
    co_node_bus_event(&t.node, CO_BUS_RX_OVERRUN);
    co_node_bus_event(&t.node, CO_BUS_ERROR_PASSIVE);
    co_node_bus_event(&t.node, CO_BUS_ERROR_PASSIVE); /* still passive: once */
    CHECK_STR(bus(&t), "085#1081110000000000 085#2081110000000000");
    CHECK(co_emcy_active(&t.node, 0x8110)); /* the application clears the overrun */
    fake_clear(&t.bus);
    co_node_bus_event(&t.node, CO_BUS_ERROR_ACTIVE);
    CHECK(!co_emcy_active(&t.node, 0x8120));
    CHECK_EQ(t.bus.count, 0); /* 0x8110 still active */
    /* Bus-off: the error behaviour (0x1029 sub1 = 0), no frame. */
    co_node_bus_event(&t.node, CO_BUS_ERROR_PASSIVE);
    fake_clear(&t.bus);
    co_node_bus_event(&t.node, CO_BUS_OFF);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(t.bus.count, 0);
    /* Recovered: 0x8140, and the controller is error active again. */
    co_node_bus_event(&t.node, CO_BUS_OFF_RECOVERED);
    CHECK_STR(bus(&t), "085#4081110000000000");
    CHECK(co_emcy_active(&t.node, 0x8140));
    CHECK(!co_emcy_active(&t.node, 0x8120));
    co_emcy_clear(&t.node, 0x8110);
    co_emcy_clear(&t.node, 0x8140);
    CHECK_STR(bus(&t), "085#4081110000000000 085#0000000000000000");
    /* Error behaviour 2: bus-off stops the node. */
    write_u8(&t, 0x1029, 1, 2);
    co_node_bus_event(&t.node, CO_BUS_OFF);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
}

static void test_consumer_decodes_frames_of_0x1028_cob_ids(void)
{
    test_node_t t;
    start(&t, 1);
    co_frame_t f = frm(0x08A, "30 81 11 01 02 03 04 05");
    CHECK(!co_node_accepts(&t.node, &f));
    uint32_t changes = t.bus.routes_changed;
    CHECK_EQ(write_u32(&t, 0x1028, 1, 0x8A), CO_ABORT_NONE);
    CHECK(co_node_accepts(&t.node, &f));
    CHECK(t.bus.routes_changed > changes);
    co_node_ingest(&t.node, 1 * MS, &f);
    CHECK_EQ(got_count, 1);
    CHECK_EQ(got[0].cob_id, 0x8A);
    CHECK_EQ(got[0].code, 0x8130);
    CHECK_EQ(got[0].reg, 0x11);
    CHECK_EQ(got[0].manufacturer[0], 0x01);
    CHECK_EQ(got[0].manufacturer[4], 0x05);
    /* A 29-bit COB-ID. */
    CHECK_EQ(write_u32(&t, 0x1028, 2, 0x30000ABCu), CO_ABORT_NONE);
    ingest(&t, 2 * MS, 0x10000ABC, "00 00 00 00 00 00 00 00");
    CHECK_EQ(got_count, 2);
    CHECK_EQ(got[1].cob_id, 0x30000ABCu);
    CHECK_EQ(got[1].code, 0);
    /* Other EMCY COB-IDs are not ours. */
    ingest(&t, 3 * MS, 0x08B, "30 81 11 01 02 03 04 05");
    CHECK_EQ(got_count, 2);
    /* Stopped: EMCY is not consumed either. */
    co_nmt_apply(&t.node, CO_NMT_CMD_STOP);
    uint32_t gated = co_node_stats(&t.node)->rx_gated;
    co_node_ingest(&t.node, 4 * MS, &f);
    CHECK_EQ(got_count, 2);
    CHECK_EQ(co_node_stats(&t.node)->rx_gated, gated + 1);
    co_nmt_apply(&t.node, CO_NMT_CMD_START);
    co_node_ingest(&t.node, 5 * MS, &f);
    CHECK_EQ(got_count, 3);
    /* Bit 31: the entry is unused again. */
    CHECK_EQ(write_u32(&t, 0x1028, 1, 0x8000008Au), CO_ABORT_NONE);
    CHECK(!co_node_accepts(&t.node, &f));
    co_node_ingest(&t.node, 6 * MS, &f);
    CHECK_EQ(got_count, 3);
    /* Entries come back from 0x1028's power-on values at reset communication. */
    write_u32(&t, 0x1028, 1, 0x8A);
    ingest(&t, 7 * MS, 0x000, "82 01");
    CHECK(!co_node_accepts(&t.node, &f));
}

static void test_consumer_ignores_malformed_frames(void)
{
    test_node_t t;
    start(&t, 1);
    write_u32(&t, 0x1028, 1, 0x8A);
    uint32_t bad = co_node_stats(&t.node)->rx_malformed;
    ingest(&t, 1 * MS, 0x08A, "30 81 11 01 02 03 04");
    ingest(&t, 1 * MS, 0x08A, "");
    ingest(&t, 1 * MS, 0x08A, "R8");
    CHECK_EQ(got_count, 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, bad + 3);
    ingest(&t, 1 * MS, 0x08A, "30 81 11 01 02 03 04 05");
    CHECK_EQ(got_count, 1);
}

static void test_reset_communication_keeps_errors_and_ends_0x8130(void)
{
    test_node_t t;
    start(&t, 1);
    co_emcy_raise(&t.node, 0x4210, NULL);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    ingest(&t, 0, 0x703, "05");
    co_node_poll(&t.node, 100 * MS);
    CHECK_EQ(t.od.error_register, 0x19);
    fake_clear(&t.bus);
    ingest(&t, 200 * MS, 0x000, "82 01");
    /* Monitoring restarts, so the heartbeat error is over; the temperature is not. */
    CHECK(!co_emcy_active(&t.node, 0x8130));
    CHECK(co_emcy_active(&t.node, 0x4210));
    CHECK_EQ(t.od.error_register, 0x09);
    CHECK_EQ(t.od.error_count, 0); /* 0x1003 back to its power-on value */
    CHECK_STR(bus(&t), "701#00");
    /* The last error cleared after the reset: the error reset follows the boot-up. */
    co_emcy_clear(&t.node, 0x4210);
    CHECK_STR(bus(&t), "701#00 081#0000000000000000");
}

static void test_error_reset_after_0x8130_follows_boot_up(void)
{
    test_node_t t;
    start(&t, 1);
    write_u32(&t, 0x1016, 1, hb_consumer_value(3, 100));
    ingest(&t, 0, 0x703, "05");
    co_node_poll(&t.node, 100 * MS);
    fake_clear(&t.bus);
    ingest(&t, 200 * MS, 0x000, "82 01");
    CHECK_STR(bus(&t), "701#00 081#0000000000000000");
    CHECK_EQ(t.od.error_register, 0);
}

static void test_raised_before_start_sent_after_boot_up(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_emcy_raise(&t.node, 0x5000, NULL);
    CHECK_EQ(t.bus.count, 0);
    co_node_start(&t.node, 0);
    CHECK_STR(bus(&t), "705#00 085#0050010000000000");
}

static void test_producer_invalidated_behind_the_nodes_back(void)
{
    test_node_t t;
    start(&t, 5);
    CHECK_EQ(write_u16(&t, 0x1015, 0, 100), CO_ABORT_NONE); /* 10 ms */
    co_emcy_raise(&t.node, 0x5001, NULL);
    co_emcy_raise(&t.node, 0x5002, NULL); /* waits for the inhibit time */
    CHECK_STR(bus(&t), "085#0150010000000000");
    /* The application makes 0x1014 not valid in storage, not through the node: the
     * waiting frame is dropped, not sent. */
    t.od.emcy_cob_id |= 0x80000000u;
    co_node_poll(&t.node, 20 * MS);
    CHECK_EQ(t.bus.count, 1);
    /* Valid again: the dropped frame does not come back. */
    t.od.emcy_cob_id &= ~0x80000000u;
    co_node_poll(&t.node, 40 * MS);
    CHECK_EQ(t.bus.count, 1);
    CHECK(co_emcy_active(&t.node, 0x5002)); /* still an active error */
    co_emcy_raise(&t.node, 0x5003, NULL);
    CHECK_STR(bus(&t), "085#0150010000000000 085#0350010000000000");
}

static void test_unknown_bus_event_ignored(void)
{
    test_node_t t;
    start(&t, 5);
    co_node_bus_event(&t.node, (co_bus_event_t)99);
    CHECK_STR(bus(&t), "");
    CHECK_EQ(t.od.error_register, 0);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
}

static void test_history_entry_written_locally_keeps_history(void)
{
    test_node_t t;
    start(&t, 5);
    co_emcy_raise(&t.node, 0x5001, NULL);
    co_emcy_raise(&t.node, 0x5002, NULL);
    uint64_t count = 0;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1003, 0, &count), CO_OK);
    CHECK_EQ(count, 2);
    /* Writing an entry (not sub0) is no clear. */
    CHECK_EQ(co_node_set_uint(&t.node, 0x1003, 2, 0x1234), CO_ABORT_NONE);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1003, 0, &count), CO_OK);
    CHECK_EQ(count, 2);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1003, 1, &v), CO_OK);
    CHECK_EQ(v & 0xFFFF, 0x5002);
    /* Sub0 = 0 clears it. */
    CHECK_EQ(co_node_set_uint(&t.node, 0x1003, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1003, 0, &count), CO_OK);
    CHECK_EQ(count, 0);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1003, 1, &v), CO_OK);
    CHECK_EQ(v, 0);
}

/* A power-on value of 0x1014 with bit 31 set: what waited (held back while stopped) is
 * dropped by reset communication, which makes EMCY not valid again; enabling it
 * afterwards brings back nothing stale. */
static void test_reset_communication_to_an_invalid_cob_id_drops_the_queue(void)
{
    static const uint32_t off = 0x80000080u; /* + $NODEID */
    test_node_t t;
    test_node_init(&t, 5, 0);
    for (uint32_t e = 0; e < t.cfg.od.count; e++) {
        if (t.od.entries[e].index == 0x1014) {
            t.od.entries[e].dflt = &off;
        }
    }
    t.cfg.on_emcy = rec_emcy;
    co_node_init(&t.node, &t.cfg);
    co_node_start(&t.node, 0);
    CHECK_EQ(t.od.emcy_cob_id, 0x80000085u);
    CHECK_EQ(co_emcy_raise(&t.node, 0x5001, NULL), CO_OK); /* off: recorded, not sent */
    CHECK_STR(bus(&t), "705#00");
    CHECK_EQ(t.node.emcy.queue_count, 0);
    /* Enabled by the application, then stopped: the next one waits. */
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x85), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x000, "02 05");
    CHECK_EQ(co_emcy_raise(&t.node, 0x5002, NULL), CO_OK);
    CHECK_EQ(t.node.emcy.queue_count, 1);
    fake_clear(&t.bus);
    ingest(&t, 2 * MS, 0x000, "82 05");
    CHECK_EQ(t.od.emcy_cob_id, 0x80000085u);
    CHECK_EQ(t.node.emcy.queue_count, 0);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x85), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 10 * MS), CO_TIME_NEVER);
    CHECK_STR(bus(&t), "705#00");
    /* The errors themselves are still active. */
    CHECK(co_emcy_active(&t.node, 0x5001));
    CHECK(co_emcy_active(&t.node, 0x5002));
    co_emcy_raise(&t.node, 0x5003, NULL);
    CHECK_STR(bus(&t), "705#00 085#0350010000000000");
}

/* ---- edges: the documented answers to inputs seldom seen */

static void test_emcy_consumer_without_callback_or_with_bad_frames(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1028, 1, 0x85), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x085, "10 81 11 00 00 00 00 00"); /* no on_emcy: dropped */
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
    ingest(&t, 1 * MS, 0x085, "10 81 11");
    ingest(&t, 1 * MS, 0x085, "R8");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 2);
    /* The history: only 0 may be written to sub0. */
    CHECK_EQ(write_u8(&t, 0x1003, 0, 1), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1003, 0, 0), CO_ABORT_NONE);
}

static void test_emcy_producer_off(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x80000085u), CO_ABORT_NONE);
    fake_clear(&t.bus);
    CHECK_EQ(co_emcy_raise(&t.node, 0x5000, NULL), CO_OK);
    CHECK_EQ(t.bus.count, 0);            /* EMCY off: no frame */
    CHECK_EQ(t.od.error_count, 1);       /* but recorded */
    CHECK_EQ(t.od.error_register, 0x01); /* and the register set */
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x85), CO_ABORT_NONE);
    CHECK_EQ(co_emcy_raise(&t.node, 0x5001, NULL), CO_OK);
    CHECK_EQ(fake_count_id(&t.bus, 0x085), 1); /* on again: the next one goes out */
}

int main(void)
{
    RUN(test_register_bit_of_each_group);
    RUN(test_raise_and_clear_frames_and_register);
    RUN(test_raising_an_active_code_sends_again);
    RUN(test_full_active_table_still_sends_and_records);
    RUN(test_history_newest_first_and_cleared_by_writing_zero);
    RUN(test_inhibit_time_spaces_frames_exactly);
    RUN(test_new_inhibit_time_takes_effect_at_once);
    RUN(test_full_queue_drops_the_newest);
    RUN(test_not_sent_while_stopped_sent_on_pre_operational);
    RUN(test_cob_id_off_29_bit_and_changed);
    RUN(test_valid_cob_id_changes_only_through_not_valid);
    RUN(test_heartbeat_loss_raises_0x8130_and_resume_clears_it);
    RUN(test_heartbeat_loss_ends_when_the_node_boots);
    RUN(test_heartbeat_loss_of_two_nodes_clears_when_both_are_back);
    RUN(test_bus_events);
    RUN(test_consumer_decodes_frames_of_0x1028_cob_ids);
    RUN(test_consumer_ignores_malformed_frames);
    RUN(test_reset_communication_keeps_errors_and_ends_0x8130);
    RUN(test_error_reset_after_0x8130_follows_boot_up);
    RUN(test_raised_before_start_sent_after_boot_up);
    RUN(test_producer_invalidated_behind_the_nodes_back);
    RUN(test_unknown_bus_event_ignored);
    RUN(test_history_entry_written_locally_keeps_history);
    RUN(test_reset_communication_to_an_invalid_cob_id_drops_the_queue);
    RUN(test_emcy_consumer_without_callback_or_with_bad_frames);
    RUN(test_emcy_producer_off);
    return check_summary();
}
