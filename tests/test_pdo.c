/* SPDX-License-Identifier: Apache-2.0 */
/* test_pdo.c -- RPDOs and TPDOs: transmission types, timing, length errors, deadline
 * monitoring, the re-mapping procedure and bit-level mapping. */
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define NODE 5

static char dump[4096];

/* What on_rpdo saw, for the test running now. */
static struct {
    uint16_t rpdo[16];
    uint32_t count;
} rpdos;

static void rec_rpdo(void *user, uint16_t rpdo)
{
    (void)user;
    if (rpdos.count < 16) {
        rpdos.rpdo[rpdos.count++] = rpdo;
    }
}

static const char *bus(test_node_t *t) { return fake_dump(&t->bus, dump, sizeof dump); }

/* A started node (no heartbeat), recording RPDOs, boot-up cleared; operational if asked. */
static void setup(test_node_t *t, bool operational)
{
    memset(&rpdos, 0, sizeof rpdos);
    test_node_init(t, NODE, 0);
    t->node.cfg.on_rpdo = rec_rpdo;
    co_node_start(&t->node, 0);
    if (operational) {
        ingest(t, 0, 0x000, "01 05");
    }
    fake_clear(&t->bus);
}

/* ---- TPDO, event-driven */

static void test_tpdo_sent_on_change(void)
{
    test_node_t t;
    setup(&t, true);
    co_node_poll(&t.node, 10 * MS);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 0x11223344), CO_ABORT_NONE);
    CHECK_STR(bus(&t), "185#44332211");
    uint8_t v[4] = {0x78, 0x56, 0x34, 0x12};
    CHECK_EQ(co_node_write_net(&t.node, 0x2000, 0, v, 4), CO_ABORT_NONE);
    CHECK_STR(bus(&t), "185#44332211 185#78563412");
    CHECK_EQ(co_pdo_event(&t.node, 0x2000, 0), 1);
    CHECK_EQ(co_pdo_event(&t.node, 0x2001, 0), 0); /* mapped nowhere */
    CHECK_EQ(co_tpdo_request(&t.node, 0), CO_OK);
    CHECK_STR(bus(&t), "185#44332211 185#78563412 185#78563412 185#78563412");
    CHECK_EQ(co_tpdo_request(&t.node, 1), CO_ERR_STATE); /* TPDO2 maps nothing */
    CHECK_EQ(co_tpdo_request(&t.node, 9), CO_ERR_ARG);
    CHECK_EQ(co_node_poll(&t.node, 20 * MS), CO_TIME_NEVER); /* no event timer */
}

static void test_pdos_only_in_operational(void)
{
    test_node_t t;
    setup(&t, false);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 0x11223344), CO_ABORT_NONE);
    CHECK_EQ(co_tpdo_request(&t.node, 0), CO_ERR_STATE);
    ingest(&t, 1 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(t.od.outputs[0], 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_gated, 1);
    CHECK_EQ(rpdos.count, 0);
    CHECK_STR(bus(&t), "");
    /* Operational: both run; stopped: nothing again. */
    ingest(&t, 2 * MS, 0x000, "01 05");
    ingest(&t, 3 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(t.od.outputs[3], 4);
    co_node_set_uint(&t.node, 0x2000, 0, 1);
    ingest(&t, 4 * MS, 0x000, "02 05");
    co_node_set_uint(&t.node, 0x2000, 0, 2);
    ingest(&t, 5 * MS, 0x205, "05 06 07 08");
    CHECK_EQ(t.od.outputs[3], 4);
    CHECK_STR(bus(&t), "185#01000000");
}

static void test_tpdo_inhibit_time(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u16(&t, 0x1800, 3, 100), CO_ABORT_NONE); /* 10 ms */
    co_node_poll(&t.node, 100 * MS);
    co_node_set_uint(&t.node, 0x2000, 0, 1);
    CHECK_STR(bus(&t), "185#01000000");
    CHECK_EQ(co_node_poll(&t.node, 103 * MS), CO_TIME_NEVER);
    co_node_set_uint(&t.node, 0x2000, 0, 2); /* inside the inhibit time: waits */
    co_node_set_uint(&t.node, 0x2000, 0, 3);
    CHECK_STR(bus(&t), "185#01000000");
    CHECK_EQ(co_node_poll(&t.node, 104 * MS), 110 * MS);
    CHECK_EQ(co_node_poll(&t.node, 110 * MS - 1), 110 * MS);
    CHECK_STR(bus(&t), "185#01000000");
    CHECK_EQ(co_node_poll(&t.node, 110 * MS), CO_TIME_NEVER);
    CHECK_STR(bus(&t), "185#01000000 185#03000000"); /* the latest value, once */
    /* After the inhibit time an event goes at once. */
    co_node_poll(&t.node, 125 * MS);
    co_node_set_uint(&t.node, 0x2000, 0, 4);
    CHECK_STR(bus(&t), "185#01000000 185#03000000 185#04000000");
}

static void test_tpdo_event_timer(void)
{
    test_node_t t;
    setup(&t, true);
    co_node_poll(&t.node, 10 * MS);
    CHECK_EQ(write_u16(&t, 0x1800, 5, 50), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 10 * MS), 60 * MS);
    CHECK_EQ(co_node_poll(&t.node, 60 * MS - 1), 60 * MS);
    CHECK_STR(bus(&t), "");
    CHECK_EQ(co_node_poll(&t.node, 60 * MS), 110 * MS);
    CHECK_STR(bus(&t), "185#78563412");
    /* A transmission on change restarts the period. */
    co_node_poll(&t.node, 80 * MS);
    co_node_set_uint(&t.node, 0x2000, 0, 7);
    CHECK_EQ(co_node_poll(&t.node, 110 * MS), 130 * MS); /* the old deadline: nothing */
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 2);
    CHECK_EQ(co_node_poll(&t.node, 130 * MS), 180 * MS);
    CHECK_STR(bus(&t), "185#78563412 185#07000000 185#07000000");
    /* Leaving operational stops it; entering again starts it afresh. */
    ingest(&t, 140 * MS, 0x000, "80 05");
    CHECK_EQ(co_node_poll(&t.node, 180 * MS), CO_TIME_NEVER);
    ingest(&t, 200 * MS, 0x000, "01 05");
    CHECK_EQ(co_node_poll(&t.node, 200 * MS), 250 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 3);
}

static void test_event_timer_waits_for_inhibit(void)
{
    test_node_t t;
    setup(&t, true);
    co_node_poll(&t.node, 0);
    CHECK_EQ(write_u16(&t, 0x1800, 3, 300), CO_ABORT_NONE); /* 30 ms */
    CHECK_EQ(write_u16(&t, 0x1800, 5, 20), CO_ABORT_NONE);  /* 20 ms */
    co_node_poll(&t.node, 5 * MS);
    co_node_set_uint(&t.node, 0x2000, 0, 1); /* sent at 5: timer to 25, inhibit to 35 */
    CHECK_EQ(co_node_poll(&t.node, 20 * MS), 25 * MS);
    CHECK_EQ(co_node_poll(&t.node, 25 * MS), 35 * MS); /* the timer waits for the inhibit end */
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 1);
    CHECK_EQ(co_node_poll(&t.node, 35 * MS), 55 * MS);
    CHECK_STR(bus(&t), "185#01000000 185#01000000");
}

/* ---- TPDO, synchronous */

static void test_tpdo_every_second_sync(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 2), CO_ABORT_NONE);
    co_node_set_uint(&t.node, 0x2000, 0, 9); /* no event for a cyclic type */
    CHECK_STR(bus(&t), "");
    for (int i = 1; i <= 5; i++) {
        ingest(&t, (uint64_t)i * 10 * MS, 0x080, "");
        co_node_set_uint(&t.node, 0x2000, 0, (uint64_t)(i + 10));
    }
    CHECK_STR(bus(&t), "185#0B000000 185#0D000000");
}

/* A cyclic TPDO on a 29-bit COB-ID goes out with it (the short path sends 11-bit ones). */
static void test_tpdo_29bit_cob_on_sync(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x20012345u), CO_ABORT_NONE);
    co_node_set_uint(&t.node, 0x2000, 0, 7);
    ingest(&t, 10 * MS, 0x080, "");
    CHECK_STR(bus(&t), "00012345#07000000");
}

static void test_tpdo_sync_start_value(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 5), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 2), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1800, 6, 3), CO_ABORT_NONE);
    const char *counters[] = {"01", "02", "03", "04", "05", "01", "02"};
    for (int i = 0; i < 7; i++) {
        co_node_set_uint(&t.node, 0x2000, 0, (uint64_t)(i + 1));
        ingest(&t, (uint64_t)(i + 1) * 10 * MS, 0x080, counters[i]);
    }
    /* First at counter 3, then every second SYNC: 5, 2. */
    CHECK_STR(bus(&t), "185#03000000 185#05000000 185#07000000");
}

static void test_tpdo_acyclic_goes_at_next_sync(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 0), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x080, "");
    co_node_set_uint(&t.node, 0x2000, 0, 1);
    co_node_set_uint(&t.node, 0x2000, 0, 2);
    CHECK_STR(bus(&t), "");
    ingest(&t, 11 * MS, 0x080, "");
    ingest(&t, 21 * MS, 0x080, "");
    CHECK_STR(bus(&t), "185#02000000");
    CHECK_EQ(co_tpdo_request(&t.node, 0), CO_OK);
    ingest(&t, 31 * MS, 0x080, "");
    CHECK_STR(bus(&t), "185#02000000 185#02000000");
}

static void test_tpdo_own_sync_producer(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 1), CO_ABORT_NONE);
    t.node.now_us = 0;
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1006, 0, 10000), CO_ABORT_NONE);
    co_node_poll(&t.node, 10 * MS);
    co_node_poll(&t.node, 20 * MS);
    CHECK_STR(bus(&t), "080# 185#78563412 080# 185#78563412");
}

static void test_tpdo_252_sampled_at_sync(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 252), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x185, "R4"); /* nothing sampled yet */
    co_node_set_uint(&t.node, 0x2000, 0, 0xA1);
    ingest(&t, 2 * MS, 0x080, "");
    co_node_set_uint(&t.node, 0x2000, 0, 0xB2);
    CHECK_STR(bus(&t), "");
    ingest(&t, 3 * MS, 0x185, "R4");
    ingest(&t, 4 * MS, 0x185, "R4");
    CHECK_STR(bus(&t), "185#A1000000 185#A1000000");
    ingest(&t, 5 * MS, 0x080, "");
    ingest(&t, 6 * MS, 0x185, "R4");
    CHECK_STR(bus(&t), "185#A1000000 185#A1000000 185#B2000000");
}

static void test_tpdo_253_on_rtr(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 253), CO_ABORT_NONE);
    co_node_set_uint(&t.node, 0x2000, 0, 0xA1);
    ingest(&t, 1 * MS, 0x080, "");
    CHECK_STR(bus(&t), "");
    ingest(&t, 2 * MS, 0x185, "R4");
    co_node_set_uint(&t.node, 0x2000, 0, 0xB2);
    ingest(&t, 3 * MS, 0x185, "R4");
    CHECK_STR(bus(&t), "185#A1000000 185#B2000000");
    ingest(&t, 4 * MS, 0x185, "00"); /* a data frame on our own COB-ID */
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 1);
}

static void test_rtr_refused_with_bit_30(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 253), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x40000185u), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x185, "R4");
    CHECK_STR(bus(&t), "");
    CHECK_EQ(co_node_stats(&t.node)->rx_unrouted, 1);
}

/* ---- RPDO */

static void test_rpdo_applied(void)
{
    test_node_t t;
    setup(&t, true);
    ingest(&t, 1 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(t.od.outputs[0], 1);
    CHECK_EQ(t.od.outputs[1], 2);
    CHECK_EQ(t.od.outputs[2], 3);
    CHECK_EQ(t.od.outputs[3], 4);
    CHECK_EQ(rpdos.count, 1);
    CHECK_EQ(rpdos.rpdo[0], 0);
    CHECK_STR(bus(&t), "");
    ingest(&t, 2 * MS, 0x205, "R4"); /* RPDOs are not requested */
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 1);
    CHECK_EQ(rpdos.count, 1);
}

static void test_rpdo_too_short(void)
{
    test_node_t t;
    setup(&t, true);
    ingest(&t, 1 * MS, 0x205, "01 02 03");
    CHECK_EQ(t.od.outputs[0], 0);
    CHECK_EQ(rpdos.count, 0);
    CHECK_STR(bus(&t), "085#1082110000000000");
    CHECK(co_emcy_active(&t.node, 0x8210));
    /* The right length again: applied, the error is over. */
    ingest(&t, 2 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(t.od.outputs[0], 1);
    CHECK_STR(bus(&t), "085#1082110000000000 085#0000000000000000");
}

static void test_rpdo_too_long(void)
{
    test_node_t t;
    setup(&t, true);
    ingest(&t, 1 * MS, 0x205, "01 02 03 04 05");
    CHECK_EQ(t.od.outputs[3], 4);
    CHECK_EQ(rpdos.count, 1);
    CHECK_STR(bus(&t), "085#2082110000000000");
    ingest(&t, 2 * MS, 0x205, "01 02 03 04");
    CHECK_STR(bus(&t), "085#2082110000000000 085#0000000000000000");
    CHECK_EQ(rpdos.count, 2);
}

static void test_rpdo_synchronous(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 0), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(t.od.outputs[0], 0);
    CHECK_EQ(rpdos.count, 0);
    ingest(&t, 2 * MS, 0x080, "");
    CHECK_EQ(t.od.outputs[0], 1);
    CHECK_EQ(rpdos.count, 1);
    ingest(&t, 3 * MS, 0x080, ""); /* applied once */
    CHECK_EQ(rpdos.count, 1);
    /* Outside the synchronous window: dropped. */
    CHECK_EQ(write_u32(&t, 0x1007, 0, 5000), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x205, "05 06 07 08");
    ingest(&t, 12 * MS, 0x080, "");
    CHECK_EQ(t.od.outputs[0], 1);
    ingest(&t, 13 * MS, 0x205, "09 0A 0B 0C"); /* inside: applied at the next SYNC */
    CHECK_EQ(t.od.outputs[0], 1);
    ingest(&t, 22 * MS, 0x080, "");
    CHECK_EQ(t.od.outputs[0], 9);
    CHECK_EQ(rpdos.count, 2);
}

/* An empty frame for an RPDO off the short path (here synchronous) is too short, and
 * never taken as a frame of the short path's length (co_pdo_t.fast is 0 there). */
static void test_rpdo_empty_frame_off_short_path(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 0), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x205, "");
    CHECK_EQ(rpdos.count, 0);
    CHECK(co_emcy_active(&t.node, 0x8210));
    ingest(&t, 2 * MS, 0x080, "");
    CHECK_EQ(t.od.outputs[0], 0);
    CHECK_EQ(rpdos.count, 0);
}

static void test_rpdo_deadline(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u16(&t, 0x1400, 5, 100), CO_ABORT_NONE);
    CHECK_EQ(co_node_poll(&t.node, 5 * MS), CO_TIME_NEVER); /* starts with the first RPDO */
    ingest(&t, 10 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(co_node_poll(&t.node, 10 * MS), 110 * MS);
    ingest(&t, 60 * MS, 0x205, "01 02 03 04");
    CHECK_EQ(co_node_poll(&t.node, 110 * MS), 160 * MS); /* the old deadline: nothing */
    CHECK_EQ(co_node_poll(&t.node, 160 * MS - 1), 160 * MS);
    CHECK_STR(bus(&t), "");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_node_poll(&t.node, 160 * MS), CO_TIME_NEVER);
    CHECK_STR(bus(&t), "085#5082110000000000");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL); /* 0x1029 sub1 = 0 */
    /* Operational again: monitoring waits for the next RPDO, which ends the error. */
    ingest(&t, 200 * MS, 0x000, "01 05");
    CHECK_EQ(co_node_poll(&t.node, 400 * MS), CO_TIME_NEVER);
    ingest(&t, 410 * MS, 0x205, "01 02 03 04");
    CHECK_STR(bus(&t), "085#5082110000000000 085#0000000000000000");
    CHECK_EQ(co_node_poll(&t.node, 410 * MS), 510 * MS);
}

static void test_rpdo_deadline_error_behaviour_none(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1029, 1, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u16(&t, 0x1400, 5, 20), CO_ABORT_NONE);
    ingest(&t, 0, 0x205, "01 02 03 04");
    CHECK_EQ(co_node_poll(&t.node, 20 * MS), CO_TIME_NEVER); /* reported once */
    CHECK_EQ(co_node_poll(&t.node, 100 * MS), CO_TIME_NEVER);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    CHECK_STR(bus(&t), "085#5082110000000000");
}

/* ---- re-mapping */

static void test_remapping_procedure(void)
{
    test_node_t t;
    setup(&t, false);
    /* While valid: neither entries nor sub0. */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x10010008), CO_ABORT_UNSUPPORTED);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 0), CO_ABORT_UNSUPPORTED);
    /* A valid COB-ID may only become not valid. */
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x186), CO_ABORT_VALUE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x185), CO_ABORT_NONE);        /* the same value */
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000800u), CO_ABORT_VALUE); /* not an 11-bit ID */
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    /* Not valid, but sub0 still 1. */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x10010008), CO_ABORT_UNSUPPORTED);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 0), CO_ABORT_NONE);
    /* Entries are checked when sub0 is written. */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x30000020), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 1), CO_ABORT_NO_MAP); /* no such object */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x62000108), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 1), CO_ABORT_NO_MAP); /* RPDO-mappable only */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x20010010), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 1), CO_ABORT_NO_MAP); /* not mappable at all */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x00070020), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 1), CO_ABORT_NO_MAP); /* dummies: RPDOs only */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x20000021), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 1), CO_ABORT_NO_MAP); /* 33 bits of a 32-bit object */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x20000020), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A00, 2, 0x20000020), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A00, 3, 0x10010008), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 3), CO_ABORT_MAP_LEN); /* 72 bits */
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 9), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(t.od.tpdo[0].map_count, 0);
    /* The new mapping: error register, then 0x2000. */
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x10010008), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 2), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x185), CO_ABORT_NONE);
    /* Reserved transmission types. */
    CHECK_EQ(write_u8(&t, 0x1800, 2, 245), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 252), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 252), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 255), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x000, "01 05");
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 0xAABBCCDD), CO_ABORT_NONE);
    CHECK_STR(bus(&t), "185#00DDCCBBAA");
}

static void test_rpdo_remapping_with_dummy(void)
{
    test_node_t t;
    setup(&t, false);
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x80000205u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1600, 1, 0x00000008), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 1), CO_ABORT_NO_MAP);         /* index 0 is no dummy */
    CHECK_EQ(write_u32(&t, 0x1600, 1, 0x00050008), CO_ABORT_NONE); /* skip a byte */
    CHECK_EQ(write_u32(&t, 0x1600, 2, 0x62000208), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1600, 3, 0x20000020), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 3), CO_ABORT_NONE);
    /* Not valid: the frame is not routed. */
    ingest(&t, 1 * MS, 0x000, "01 05");
    ingest(&t, 2 * MS, 0x205, "11 22 33 44 55 66");
    CHECK_EQ(t.od.outputs[1], 0);
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x205), CO_ABORT_NONE);
    fake_clear(&t.bus);
    ingest(&t, 3 * MS, 0x205, "11 22 33 44 55 66");
    CHECK_EQ(t.od.outputs[0], 0);
    CHECK_EQ(t.od.outputs[1], 0x22);
    CHECK_EQ(t.od.app_u32, 0x66554433);
    /* 0x2000 is mapped into TPDO1 too: a received value is a change. */
    CHECK_STR(bus(&t), "185#33445566");
}

/* ---- bit-level mapping between two nodes */

/* A small dictionary: an RPDO and a TPDO (COB-ID 0x181), a BOOLEAN, an UNSIGNED8 and an
 * UNSIGNED16, mapped with 1, 4 and 12 bits (or the UNSIGNED8 skipped by a dummy). */
typedef struct bit_od {
    co_od_entry_t e[24];
    uint32_t rcob, tcob, map[3];
    uint8_t rtype, ttype, rcount, tcount;
    bool flag;
    uint8_t u8;
    uint16_t u16;
} bit_od_t;

#define BIT_VAR(i, s, t, sz, a, v)                                                                 \
    (co_od_entry_t)                                                                                \
    {                                                                                              \
        .index = (i), .sub = (s), .type = (t), .attr = (a), .size = (sz), .value = (v)             \
    }

static co_od_t bit_od_init(bit_od_t *x, bool dummy)
{
    memset(x, 0, sizeof *x);
    x->rcob = 0x181;
    x->tcob = 0x181;
    x->rtype = 255;
    x->ttype = 255;
    x->rcount = 3;
    x->tcount = 3;
    x->map[0] = 0x21000001;
    x->map[1] = dummy ? 0x00050004 : 0x21010004;
    x->map[2] = 0x2102000C;
    uint32_t n = 0;
    uint8_t pdo = CO_OD_RW | CO_OD_TPDO | CO_OD_RPDO;
    x->e[n++] = BIT_VAR(0x1400, 1, CO_TYPE_UNSIGNED32, 4, CO_OD_RW, &x->rcob);
    x->e[n++] = BIT_VAR(0x1400, 2, CO_TYPE_UNSIGNED8, 1, CO_OD_RW, &x->rtype);
    x->e[n++] = BIT_VAR(0x1600, 0, CO_TYPE_UNSIGNED8, 1, CO_OD_RW, &x->rcount);
    for (uint8_t i = 0; i < 3; i++) {
        x->e[n++] = BIT_VAR(0x1600, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, 4, CO_OD_RW, &x->map[i]);
    }
    x->e[n++] = BIT_VAR(0x1800, 1, CO_TYPE_UNSIGNED32, 4, CO_OD_RW, &x->tcob);
    x->e[n++] = BIT_VAR(0x1800, 2, CO_TYPE_UNSIGNED8, 1, CO_OD_RW, &x->ttype);
    x->e[n++] = BIT_VAR(0x1A00, 0, CO_TYPE_UNSIGNED8, 1, CO_OD_RW, &x->tcount);
    for (uint8_t i = 0; i < 3; i++) {
        x->e[n++] = BIT_VAR(0x1A00, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, 4, CO_OD_RW, &x->map[i]);
    }
    x->e[n++] = BIT_VAR(0x2100, 0, CO_TYPE_BOOLEAN, 1, pdo, &x->flag);
    x->e[n++] = BIT_VAR(0x2101, 0, CO_TYPE_UNSIGNED8, 1, pdo, &x->u8);
    x->e[n++] = BIT_VAR(0x2102, 0, CO_TYPE_UNSIGNED16, 2, pdo, &x->u16);
    return (co_od_t){.entries = x->e, .count = n};
}

typedef struct bit_node {
    bit_od_t od;
    fake_bus_t bus;
    co_node_t node;
} bit_node_t;

static void bit_node_start(bit_node_t *b, uint8_t id, bool dummy)
{
    memset(b, 0, sizeof *b);
    co_node_config_t cfg = {.node_id = id, .self_start = true};
    cfg.od = bit_od_init(&b->od, dummy);
    cfg.driver = fake_driver(&b->bus);
    CHECK_EQ(co_node_init(&b->node, &cfg), CO_OK);
    co_node_start(&b->node, 0);
    CHECK_EQ(co_nmt_state(&b->node), CO_NMT_OPERATIONAL);
    fake_clear(&b->bus);
}

/* Set the sender's values (the last change sends the TPDO) and hand it to the receiver. */
static void bit_transfer(bit_node_t *tx, bit_node_t *rx, uint16_t u16)
{
    co_node_set_uint(&tx->node, 0x2100, 0, 1);
    co_node_set_uint(&tx->node, 0x2101, 0, 0x0D);
    co_node_set_uint(&tx->node, 0x2102, 0, u16);
    CHECK(tx->bus.count >= 1);
    co_node_ingest(&rx->node, 1 * MS, &tx->bus.frames[tx->bus.count - 1]);
}

static void test_bit_level_round_trip(void)
{
    static bit_node_t tx;
    static bit_node_t rx;
    bit_node_start(&tx, 1, false);
    bit_node_start(&rx, 2, false);
    rx.od.u16 = 0xF000; /* bits above the 12 mapped keep their value */
    bit_transfer(&tx, &rx, 0xABC5);
    /* 1 | 0xD << 1 | 0xBC5 << 5 = 0x178BB */
    CHECK_STR(frame_str(&tx.bus.frames[tx.bus.count - 1], dump, sizeof dump), "181#BB7801");
    CHECK_EQ(rx.od.flag, 1);
    CHECK_EQ(rx.od.u8, 0x0D);
    CHECK_EQ(rx.od.u16, 0xFBC5);
    /* A cleared bit arrives cleared too. */
    co_node_set_uint(&tx.node, 0x2100, 0, 0);
    co_node_ingest(&rx.node, 2 * MS, &tx.bus.frames[tx.bus.count - 1]);
    CHECK_EQ(rx.od.flag, 0);
    CHECK_EQ(rx.od.u16, 0xFBC5);
}

static void test_bit_level_dummy_skips(void)
{
    static bit_node_t tx;
    static bit_node_t rx;
    bit_node_start(&tx, 1, false);
    bit_node_start(&rx, 2, true);
    rx.od.u8 = 0x77;
    bit_transfer(&tx, &rx, 0x0123);
    CHECK_EQ(rx.od.flag, 1);
    CHECK_EQ(rx.od.u8, 0x77); /* the dummy took its 4 bits */
    CHECK_EQ(rx.od.u16, 0x0123);
}

/* ---- TPDO: whole values at odd bit positions, an event-driven TPDO at SYNC */

static void test_tpdo_whole_value_at_odd_bit_position(void)
{
    test_node_t t;
    setup(&t, true);
    /* TPDO1: 0x1001 low 4 bits, 0x2000 whole (32 bits) from bit 4, 0x1001 low 4 bits. */
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x10010004u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A00, 2, 0x20000020u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A00, 3, 0x10010004u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 3), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x185u), CO_ABORT_NONE);
    t.od.error_register = 0x0B;
    fake_clear(&t.bus);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 0x11223344), CO_ABORT_NONE);
    /* 0xB | 0x11223344 << 4 | 0xB << 36 = 0xB11223344B, 5 bytes little-endian. */
    CHECK_STR(bus(&t), "185#4B342312B1");
}

/* The other way: a whole value received from bit 4 on, after a 4-bit dummy. */
static void test_rpdo_whole_value_at_odd_bit_position(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x80000205u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1600, 1, 0x00050004u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1600, 2, 0x20000020u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 2), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x205u), CO_ABORT_NONE);
    /* 0x5 | 0x12345678 << 4 = 0x123456785, 5 bytes little-endian. */
    ingest(&t, 1 * MS, 0x205, "85 67 45 23 01");
    CHECK_EQ(t.od.app_u32, 0x12345678u);
    CHECK_EQ(rpdos.count, 1);
}

/* An application that stops the node from on_rpdo, as a SYNC applies an RPDO: the rest of
 * that SYNC's PDOs is neither applied nor sent. */
static void stop_on_rpdo(void *user, uint16_t rpdo)
{
    test_node_t *t = user;
    rec_rpdo(user, rpdo);
    (void)co_nmt_apply(&t->node, CO_NMT_CMD_STOP);
}

static void test_node_stopped_by_on_rpdo_at_a_sync(void)
{
    test_node_t t;
    setup(&t, true);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 0), CO_ABORT_NONE); /* RPDO1: at the next SYNC */
    /* RPDO2 (0x305): 0x2007, at the next SYNC too. */
    CHECK_EQ(write_u32(&t, 0x1401, 1, 0x80000305u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1601, 1, 0x20070020u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1601, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1401, 1, 0x305u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1401, 2, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 1), CO_ABORT_NONE); /* TPDO1: every SYNC */
    ingest(&t, 1 * MS, 0x205, "01 02 03 04");
    ingest(&t, 1 * MS, 0x305, "05 06 07 08");
    t.node.cfg.on_rpdo = stop_on_rpdo;
    ingest(&t, 2 * MS, 0x080, "");
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
    CHECK_EQ(t.od.outputs[0], 1); /* RPDO1, whose callback stopped the node */
    CHECK_EQ(t.od.app_u32b, 0);   /* RPDO2 not applied */
    CHECK_EQ(rpdos.count, 1);
    CHECK_STR(bus(&t), ""); /* TPDO1 not sent */
}

static void test_event_driven_tpdo_not_sent_at_sync(void)
{
    test_node_t t;
    setup(&t, true);
    /* TPDO2: 0x2007, every SYNC; TPDO1 stays event-driven. */
    CHECK_EQ(write_u32(&t, 0x1801, 1, 0x80000285u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A01, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A01, 1, 0x20070020u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A01, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1801, 2, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1801, 1, 0x285u), CO_ABORT_NONE);
    co_node_poll(&t.node, 1 * MS);
    fake_clear(&t.bus);
    t.od.app_u32b = 0xA5;
    ingest(&t, 10 * MS, 0x080, "");
    ingest(&t, 20 * MS, 0x080, "");
    CHECK_STR(bus(&t), "285#A5000000 285#A5000000");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 0);
}

/* ---- an RPDO that writes an object a TPDO maps */

static void map_rpdo2_to_0x2000(test_node_t *t)
{
    CHECK_EQ(write_u32(t, 0x1401, 1, 0x80000305u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(t, 0x1601, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1601, 1, 0x20000020u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(t, 0x1601, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u8(t, 0x1401, 2, 254), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1401, 1, 0x305u), CO_ABORT_NONE);
}

static void test_rpdo_into_a_tpdo_mapped_object(void)
{
    test_node_t t;
    setup(&t, true);
    map_rpdo2_to_0x2000(&t);
    co_node_poll(&t.node, 1 * MS);
    fake_clear(&t.bus);
    /* Received into 0x2000, which event-driven TPDO1 maps: the change sends TPDO1. */
    ingest(&t, 10 * MS, 0x305, "44 33 22 11");
    CHECK_EQ(t.od.app_u32, 0x11223344);
    CHECK_EQ(rpdos.count, 1);
    CHECK_EQ(rpdos.rpdo[0], 1);
    CHECK_STR(bus(&t), "185#44332211");
    /* Without on_rpdo the same. */
    t.node.cfg.on_rpdo = NULL;
    ingest(&t, 20 * MS, 0x305, "88 77 66 55");
    CHECK_EQ(t.od.app_u32, 0x55667788);
    CHECK_EQ(rpdos.count, 1);
    CHECK_STR(bus(&t), "185#44332211 185#88776655");
}

static void test_rpdo_without_listeners(void)
{
    test_node_t t;
    setup(&t, true);
    void (*on_rpdo)(void *, uint16_t) = t.node.cfg.on_rpdo;
    t.node.cfg.on_rpdo = NULL;
    /* TPDO1 maps 0x2007 instead: nothing listens to RPDO1's outputs or to 0x2000. */
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1A00, 1, 0x20070020u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1A00, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x185u), CO_ABORT_NONE);
    map_rpdo2_to_0x2000(&t);
    co_node_poll(&t.node, 1 * MS);
    fake_clear(&t.bus);
    ingest(&t, 10 * MS, 0x205, "01 02 03 04");
    ingest(&t, 11 * MS, 0x305, "04 03 02 01");
    CHECK_EQ(t.od.outputs[0], 1);
    CHECK_EQ(t.od.outputs[3], 4);
    CHECK_EQ(t.od.app_u32, 0x01020304);
    CHECK_EQ(rpdos.count, 0);
    CHECK_STR(bus(&t), ""); /* no TPDO maps what changed */
    /* The application listening, no TPDO: it hears of the frame, nothing is sent. */
    t.node.cfg.on_rpdo = on_rpdo;
    ingest(&t, 12 * MS, 0x305, "05 06 07 08");
    CHECK_EQ(t.od.app_u32, 0x08070605);
    CHECK_EQ(rpdos.count, 1);
    CHECK_EQ(rpdos.rpdo[0], 1);
    CHECK_STR(bus(&t), "");
    /* No event-driven TPDO at all (TPDO1 off): values still applied, the application told. */
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    ingest(&t, 13 * MS, 0x305, "0A 0B 0C 0D");
    CHECK_EQ(t.od.app_u32, 0x0D0C0B0A);
    CHECK_EQ(rpdos.count, 2);
    t.node.cfg.on_rpdo = NULL;
    ingest(&t, 14 * MS, 0x305, "01 00 00 00");
    CHECK_EQ(t.od.app_u32, 1);
    CHECK_EQ(rpdos.count, 2);
    CHECK_STR(bus(&t), "");
}

/* ---- edges: the documented answers to inputs seldom seen */

/* Two RPDOs: an error they share (deadline, length) ends only when both are fine again. */
static void two_rpdos(test_node_t *t)
{
    test_node_init(t, 5, 0);
    co_node_start(&t->node, 0);
    CHECK_EQ(write_u8(t, 0x1029, 1, 1), CO_ABORT_NONE); /* stay operational */
    CHECK_EQ(write_u32(t, 0x1401, 1, 0x80000305u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1601, 1, 0x62000208), CO_ABORT_NONE);
    CHECK_EQ(write_u8(t, 0x1601, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1401, 1, 0x305), CO_ABORT_NONE);
    ingest(t, 0, 0x000, "01 05");
}

static void test_pdo_event_and_rtr_of_what_the_node_lacks(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x000, "01 05");
    fake_clear(&t.bus);
    CHECK_EQ(co_pdo_event(&t.node, 0x2FFF, 0), 0); /* no such entry: no TPDO */
    CHECK_EQ(co_tpdo_request(&t.node, EXAMPLE_PDOS), CO_ERR_ARG);
    CHECK_EQ(co_tpdo_request(&t.node, 1), CO_ERR_STATE); /* maps nothing: not valid */
    /* TPDO2 maps nothing: not valid, so an RTR for it is not answered. */
    ingest(&t, 0, 0x285, "R0");
    CHECK_EQ(t.bus.count, 0);
}

static void test_pdo_parameter_writes_that_change_nothing(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint32_t changes = t.bus.routes_changed;
    CHECK_EQ(write_u16(&t, 0x1800, 3, 10), CO_ABORT_NONE); /* inhibit: filters unchanged */
    CHECK_EQ(t.bus.routes_changed, changes);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 254), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 253), CO_ABORT_VALUE); /* RTR types are TPDO-only */
    /* Mapping entries that can never be valid. */
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x80000205u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 0), CO_ABORT_NONE);
    const uint32_t bad[] = {0x62000100, 0x00050010, 0x00080020};
    for (int i = 0; i < 3; i++) {
        CHECK_EQ(write_u32(&t, 0x1600, 1, bad[i]), CO_ABORT_NONE);
        CHECK_EQ(write_u8(&t, 0x1600, 0, 1), CO_ABORT_NO_MAP); /* 0 bits, too wide, no object */
    }
    /* TPDO request in pre-operational: not running. */
    CHECK_EQ(co_tpdo_request(&t.node, 0), CO_ERR_STATE);
}

static void test_tpdo_252_rtr_before_any_sync(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 252), CO_ABORT_NONE);
    ingest(&t, 0, 0x000, "01 05");
    fake_clear(&t.bus);
    ingest(&t, 1 * MS, 0x185, "R4"); /* nothing sampled yet: no answer */
    CHECK_EQ(t.bus.count, 0);
    ingest(&t, 2 * MS, 0x080, "");
    ingest(&t, 3 * MS, 0x185, "R4");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 1);
}

static void test_shared_rpdo_errors_end_with_the_last(void)
{
    test_node_t t;
    two_rpdos(&t);
    CHECK_EQ(write_u16(&t, 0x1400, 5, 50), CO_ABORT_NONE);
    CHECK_EQ(write_u16(&t, 0x1401, 5, 50), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x205, "01 02 03 04");
    ingest(&t, 10 * MS, 0x305, "05");
    co_node_poll(&t.node, 100 * MS);
    CHECK(co_emcy_active(&t.node, 0x8250));
    ingest(&t, 110 * MS, 0x205, "01 02 03 04");
    CHECK(co_emcy_active(&t.node, 0x8250)); /* RPDO2 is still missing */
    ingest(&t, 120 * MS, 0x305, "05");
    CHECK(!co_emcy_active(&t.node, 0x8250));

    two_rpdos(&t);
    ingest(&t, 10 * MS, 0x205, "01 02");
    ingest(&t, 10 * MS, 0x305, "");
    CHECK(co_emcy_active(&t.node, 0x8210));
    ingest(&t, 20 * MS, 0x205, "01 02 03 04");
    CHECK(co_emcy_active(&t.node, 0x8210));
    ingest(&t, 20 * MS, 0x305, "05");
    CHECK(!co_emcy_active(&t.node, 0x8210));
    CHECK_EQ(t.od.outputs[1], 5);
}

/* A change of a mapped value sends an event-driven TPDO only: not in pre-operational, not
 * for a synchronous one. */
static void test_value_changes_and_tpdo_types(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 0); /* pre-operational */
    ingest(&t, 0, 0x000, "01 05");
    CHECK_EQ(write_u8(&t, 0x1800, 2, 1), CO_ABORT_NONE); /* every SYNC */
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 2), CO_ABORT_NONE);
    CHECK_EQ(co_pdo_event(&t.node, 0x2000, 0), 0);
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 0);
    ingest(&t, 1 * MS, 0x080, "");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 1);
    /* A SYNC start value with SYNCs that carry no counter: sent from the first SYNC. */
    CHECK_EQ(write_u8(&t, 0x1800, 6, 3), CO_ABORT_NONE);
    ingest(&t, 2 * MS, 0x080, "");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 2);
    /* A TPDO made not valid sends nothing, whatever changes. */
    CHECK_EQ(write_u8(&t, 0x1800, 2, 255), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(co_pdo_event(&t.node, 0x2000, 0), 0);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 3), CO_ABORT_NONE);
    ingest(&t, 3 * MS, 0x185, "R4");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 2);
}

int main(void)
{
    RUN(test_tpdo_sent_on_change);
    RUN(test_pdos_only_in_operational);
    RUN(test_tpdo_inhibit_time);
    RUN(test_tpdo_event_timer);
    RUN(test_event_timer_waits_for_inhibit);
    RUN(test_tpdo_every_second_sync);
    RUN(test_tpdo_29bit_cob_on_sync);
    RUN(test_tpdo_sync_start_value);
    RUN(test_tpdo_acyclic_goes_at_next_sync);
    RUN(test_tpdo_own_sync_producer);
    RUN(test_tpdo_252_sampled_at_sync);
    RUN(test_tpdo_253_on_rtr);
    RUN(test_rtr_refused_with_bit_30);
    RUN(test_rpdo_applied);
    RUN(test_rpdo_too_short);
    RUN(test_rpdo_too_long);
    RUN(test_rpdo_synchronous);
    RUN(test_rpdo_empty_frame_off_short_path);
    RUN(test_rpdo_deadline);
    RUN(test_rpdo_deadline_error_behaviour_none);
    RUN(test_remapping_procedure);
    RUN(test_rpdo_remapping_with_dummy);
    RUN(test_bit_level_round_trip);
    RUN(test_bit_level_dummy_skips);
    RUN(test_tpdo_whole_value_at_odd_bit_position);
    RUN(test_event_driven_tpdo_not_sent_at_sync);
    RUN(test_rpdo_whole_value_at_odd_bit_position);
    RUN(test_node_stopped_by_on_rpdo_at_a_sync);
    RUN(test_rpdo_into_a_tpdo_mapped_object);
    RUN(test_rpdo_without_listeners);
    RUN(test_pdo_event_and_rtr_of_what_the_node_lacks);
    RUN(test_pdo_parameter_writes_that_change_nothing);
    RUN(test_tpdo_252_rtr_before_any_sync);
    RUN(test_shared_rpdo_errors_end_with_the_last);
    RUN(test_value_changes_and_tpdo_types);
    return check_summary();
}
