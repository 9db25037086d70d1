/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_cm_can.c -- port/cortex-m's CAN side (cm_can.c) against a fake controller: three
 * mailboxes the test empties one at a time (the highest priority first, as the bus would),
 * with the transmit-complete interrupt behind each; a node with the example dictionary on
 * top. The queue's arbitration order, the receive ring and its overflow, bus states to the
 * node's EMCY and error behaviour, filters from the routes, the LSS bit rates.
 */
#include <stdlib.h>

#include "canola/cm_can.h"
#include "check.h"
#include "cm_host.h"
#include "example_od.h"
#include "harness.h"

#define MAILBOXES 3
#define WIRE_MAX 256

typedef struct fake_ctrl {
    co_frame_t mailbox[MAILBOXES];
    bool busy[MAILBOXES];
    bool one_per_id; /* refuse a frame whose identifier a mailbox holds (as the drivers do) */
    co_frame_t wire[WIRE_MAX];
    uint32_t wire_count;
    uint32_t unmasked_puts; /* mailbox_put outside the critical section */
    uint32_t tx_done_pending;
    uint32_t filter_calls;
    uint32_t filter_ids[CO_CM_FILTER_IDS_MAX + 8];
    size_t filter_n;
    bool filter_all;
    uint32_t bit_rate;
    co_cm_port_t *port;
} fake_ctrl_t;

static bool fake_put(void *hw, const co_frame_t *frame)
{
    fake_ctrl_t *c = hw;
    c->unmasked_puts += !cm_host_masked();
    for (int i = 0; c->one_per_id && i < MAILBOXES; i++) {
        if (c->busy[i] && c->mailbox[i].id == frame->id) {
            return false;
        }
    }
    for (int i = 0; i < MAILBOXES; i++) {
        if (!c->busy[i]) {
            c->mailbox[i] = *frame;
            c->busy[i] = true;
            return true;
        }
    }
    return false;
}

static bool fake_filters(void *hw, const uint32_t *ids, size_t n)
{
    fake_ctrl_t *c = hw;
    c->filter_calls++;
    c->filter_all = ids == NULL;
    c->filter_n = n;
    for (size_t i = 0; ids && i < n && i < CO_CM_FILTER_IDS_MAX + 8; i++) {
        c->filter_ids[i] = ids[i];
    }
    return true;
}

static co_err_t fake_bit_rate(void *hw, uint32_t bit_rate)
{
    ((fake_ctrl_t *)hw)->bit_rate = bit_rate;
    return CO_OK;
}

static void fake_counters(void *hw, uint8_t *tec, uint8_t *rec)
{
    (void)hw;
    *tec = 0;
    *rec = 0;
}

static const co_cm_can_ops_t k_fake_ops = {fake_put, fake_filters, fake_bit_rate, fake_counters};

/* The transmit-complete interrupt: one per emptied mailbox. */
static bool fake_irq(void *ctx)
{
    fake_ctrl_t *c = ctx;
    if (c->tx_done_pending == 0) {
        return false;
    }
    c->tx_done_pending--;
    co_cm_isr_tx_done(c->port);
    return true;
}

/* The bus takes the mailbox with the lowest identifier (the lowest mailbox among equals). */
static bool fake_complete(fake_ctrl_t *c)
{
    int best = -1;
    for (int i = 0; i < MAILBOXES; i++) {
        if (c->busy[i] && (best < 0 || c->mailbox[i].id < c->mailbox[best].id)) {
            best = i;
        }
    }
    if (best < 0) {
        return false;
    }
    c->busy[best] = false;
    if (c->wire_count < WIRE_MAX) {
        c->wire[c->wire_count++] = c->mailbox[best];
    }
    c->tx_done_pending++;
    cm_host_raise();
    return true;
}

typedef struct rig {
    fake_ctrl_t ctrl;
    co_cm_port_t port;
    example_od_t od;
    co_node_t node;
    co_emcy_msg_t emcy[8];
} rig_t;

static rig_t *rig_new(void)
{
    rig_t *r = calloc(1, sizeof *r);
    cm_host_reset();
    r->ctrl.port = &r->port;
    co_cm_can_init(&r->port.can, &k_fake_ops, &r->ctrl);
    cm_host_add_source(fake_irq, &r->ctrl);
    co_node_config_t cfg = {.node_id = 5, .od = example_od_init(&r->od, 0)};
    cfg.driver = co_cm_can_driver(&r->port.can);
    CHECK_EQ(co_node_init(&r->node, &cfg), CO_OK);
    co_cm_can_bind(&r->port.can, &r->node);
    return r;
}

static co_frame_t frame_of(uint32_t id, uint8_t flags, uint8_t tag)
{
    co_frame_t f = {.id = id, .flags = flags, .len = 1, .data = {tag}};
    return f;
}

static co_err_t send(rig_t *r, uint32_t id, uint8_t flags, uint8_t tag)
{
    co_frame_t f = frame_of(id, flags, tag);
    co_driver_t d = co_cm_can_driver(&r->port.can);
    return d.tx(d.ctx, &f);
}

/* ---- transmit */

static void test_free_mailboxes_take_frames_at_once(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(send(r, 0x300, 0, 1), CO_OK);
    CHECK_EQ(send(r, 0x200, 0, 2), CO_OK);
    CHECK_EQ(send(r, 0x100, 0, 3), CO_OK);
    CHECK(r->ctrl.busy[0] && r->ctrl.busy[1] && r->ctrl.busy[2]);
    CHECK_EQ(r->port.can.tx_count, 0);
    CHECK_EQ(r->ctrl.unmasked_puts, 0);
    free(r);
}

/* Behind full mailboxes: lowest identifier first, an 11-bit frame before the 29-bit ones of
 * its base identifier, data before remote, first in first out among equals. */
static void test_queue_in_arbitration_order(void)
{
    rig_t *r = rig_new();
    for (uint8_t i = 0; i < 3; i++) {
        CHECK_EQ(send(r, 0x7FF, 0, i), CO_OK); /* the mailboxes: lowest priority */
    }
    CHECK_EQ(send(r, 0x100u << 18, CO_FRAME_EXT, 10), CO_OK); /* 29-bit, base 0x100 */
    CHECK_EQ(send(r, 0x100, CO_FRAME_RTR, 11), CO_OK);
    CHECK_EQ(send(r, 0x100, 0, 12), CO_OK);
    CHECK_EQ(send(r, 0x100, 0, 13), CO_OK);
    CHECK_EQ(r->port.can.tx_count, 4);
    CHECK_EQ(send(r, 0x050, 0, 14), CO_ERR_BUSY); /* the queue is full: the node keeps it */
    uint8_t want[] = {12, 13, 11, 10};
    for (int i = 0; i < 4; i++) {
        CHECK_EQ(r->port.can.tx_queue[i].data[0], want[i]);
    }
    while (fake_complete(&r->ctrl)) {
    }
    CHECK_EQ(r->ctrl.wire_count, 7);
    /* after the three in the mailboxes, the queue's order (the bus takes the lowest id
     * among the mailboxes: 12 goes before the 0x7FF frames still waiting) */
    uint32_t pos[16] = {0};
    for (uint32_t i = 0; i < r->ctrl.wire_count; i++) {
        pos[r->ctrl.wire[i].data[0]] = i;
    }
    CHECK(pos[12] < pos[13] && pos[13] < pos[11] && pos[11] < pos[10]);
    CHECK_EQ(r->port.can.tx_count, 0);
    CHECK_EQ(r->ctrl.unmasked_puts, 0);
    free(r);
}

/* The interrupt refills the freed mailbox from the queue's head, and tells the main loop
 * when the node may hand over what tx refused. */
static void test_tx_done_refills_and_wakes_the_node(void)
{
    rig_t *r = rig_new();
    for (uint8_t i = 0; i < 3 + CO_CM_TX_QUEUE_LEN; i++) {
        CHECK_EQ(send(r, 0x200 + i, 0, i), CO_OK);
    }
    CHECK_EQ(send(r, 0x280, 0, 99), CO_ERR_BUSY);
    CHECK(!r->port.can.tx_room);
    CHECK(fake_complete(&r->ctrl)); /* 0x200 leaves; the interrupt puts 0x203 in */
    CHECK_EQ(r->port.can.tx_count, CO_CM_TX_QUEUE_LEN - 1);
    CHECK(r->ctrl.busy[0] && r->ctrl.busy[1] && r->ctrl.busy[2]);
    CHECK(r->port.can.tx_room);
    CHECK(!co_cm_can_idle(&r->port.can));
    CHECK(co_cm_can_process(&r->port.can, 0));
    CHECK(!r->port.can.tx_room);
    free(r);
}

/* One frame per identifier in the mailboxes: the next of the same identifier waits in the
 * queue although a mailbox is free, and the interrupt moves it when its predecessor left. */
static void test_same_identifier_keeps_its_order(void)
{
    rig_t *r = rig_new();
    r->ctrl.one_per_id = true;
    for (uint8_t i = 0; i < 4; i++) {
        CHECK_EQ(send(r, 0x585, 0, i), CO_OK);
    }
    CHECK_EQ(r->port.can.tx_count, 3);
    CHECK_EQ(send(r, 0x185, 0, 9), CO_OK); /* another identifier: the new head, a mailbox */
    CHECK_EQ(r->port.can.tx_count, 3);
    while (fake_complete(&r->ctrl)) {
    }
    CHECK_EQ(r->ctrl.wire_count, 5);
    uint8_t tag = 0;
    for (uint32_t i = 0; i < r->ctrl.wire_count; i++) {
        if (r->ctrl.wire[i].id == 0x585) {
            CHECK_EQ(r->ctrl.wire[i].data[0], tag);
            tag++;
        }
    }
    CHECK_EQ(tag, 4);
    free(r);
}

/* ---- receive */

static void test_ring_hands_frames_to_the_node_in_order(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    while (fake_complete(&r->ctrl)) { /* the boot-up */
    }
    co_frame_t start = frm(0x000, "01 05");
    co_cm_isr_rx(&r->port, &start);
    CHECK(!co_cm_can_idle(&r->port.can));
    CHECK(co_cm_can_process(&r->port.can, 1000));
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_OPERATIONAL);
    CHECK(co_cm_can_idle(&r->port.can));
    CHECK(!co_cm_can_process(&r->port.can, 2000));
    /* a stop and a start: the last one wins (order kept) */
    co_frame_t stop = frm(0x000, "02 05");
    co_cm_isr_rx(&r->port, &stop);
    co_cm_isr_rx(&r->port, &start);
    co_cm_can_process(&r->port.can, 3000);
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_node_stats(&r->node)->rx_frames, 3);
    free(r);
}

/* A full ring loses the newest frames: counted, and the node hears of it once (EMCY 0x8110
 * on the bus); the frames before are kept. A flood is drained a ring's worth per call. */
static void test_ring_overflow_is_reported_once(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    while (fake_complete(&r->ctrl)) {
    }
    r->ctrl.wire_count = 0;
    co_frame_t sync = frm(0x080, "");
    for (int i = 0; i < CO_CM_RX_RING_LEN + 3; i++) {
        co_cm_isr_rx(&r->port, &sync);
    }
    CHECK_EQ(r->port.can.rx_lost, 3);
    CHECK(co_cm_can_process(&r->port.can, 1000));
    co_node_poll(&r->node, 1000);
    while (fake_complete(&r->ctrl)) {
    }
    CHECK_EQ(co_node_stats(&r->node)->rx_frames, CO_CM_RX_RING_LEN);
    CHECK(co_emcy_active(&r->node, 0x8110));
    CHECK_EQ(r->ctrl.wire_count, 1);
    CHECK_EQ(r->ctrl.wire[0].id, 0x085);
    CHECK_EQ(r->ctrl.wire[0].data[0] | r->ctrl.wire[0].data[1] << 8, 0x8110);
    CHECK(!co_cm_can_process(&r->port.can, 2000)); /* reported once */
    /* a flood: one call takes at most a ring's worth */
    for (int i = 0; i < CO_CM_RX_RING_LEN; i++) {
        co_cm_isr_rx(&r->port, &sync);
    }
    co_cm_can_process(&r->port.can, 3000);
    CHECK_EQ(co_node_stats(&r->node)->rx_frames, 2 * CO_CM_RX_RING_LEN);
    free(r);
}

static void test_fifo_overrun_is_reported(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    co_cm_isr_rx_overrun(&r->port);
    co_cm_can_process(&r->port.can, 1000);
    CHECK(co_emcy_active(&r->node, 0x8110));
    free(r);
}

/* ---- bus states */

static uint32_t emcy_codes(const fake_ctrl_t *c, uint16_t *codes, uint32_t max)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < c->wire_count && n < max; i++) {
        if (c->wire[i].id == 0x085) {
            codes[n++] = (uint16_t)(c->wire[i].data[0] | c->wire[i].data[1] << 8);
        }
    }
    return n;
}

static void settle(rig_t *r, uint64_t now)
{
    co_cm_can_process(&r->port.can, now);
    co_node_poll(&r->node, now);
    while (fake_complete(&r->ctrl)) {
    }
}

static void test_bus_states_reach_the_node(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    co_frame_t start = frm(0x000, "01 05");
    co_cm_isr_rx(&r->port, &start);
    settle(r, 0);
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_OPERATIONAL);
    r->ctrl.wire_count = 0;

    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_WARNING); /* no event of its own */
    CHECK(co_cm_can_idle(&r->port.can));
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_PASSIVE);
    settle(r, 1000);
    CHECK(co_emcy_active(&r->node, 0x8120));
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_WARNING);
    settle(r, 2000);
    CHECK(!co_emcy_active(&r->node, 0x8120));
    /* bus-off: error behaviour (0x1029 sub 1 = 0: pre-operational); then back */
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_BUS_OFF);
    settle(r, 3000);
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_PRE_OPERATIONAL);
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_ACTIVE);
    settle(r, 4000);
    CHECK(co_emcy_active(&r->node, 0x8140));
    uint16_t codes[8];
    uint32_t n = emcy_codes(&r->ctrl, codes, 8);
    CHECK_EQ(n, 3);
    CHECK_EQ(codes[0], 0x8120);
    CHECK_EQ(codes[1], 0x0000); /* error reset: 0x8120 ended */
    CHECK_EQ(codes[2], 0x8140);
    free(r);
}

/* Between two calls of the main loop: passive and back (the latest last), and a bus-off
 * with its recovery (in that order). */
static void test_bus_events_between_two_calls_keep_their_order(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    settle(r, 0);
    r->ctrl.wire_count = 0;
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_PASSIVE);
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_ACTIVE);
    settle(r, 1000);
    CHECK(!co_emcy_active(&r->node, 0x8120));
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_PASSIVE);
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_ACTIVE);
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_PASSIVE);
    settle(r, 2000);
    CHECK(co_emcy_active(&r->node, 0x8120));
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_BUS_OFF);
    co_cm_isr_bus_state(&r->port, CO_CM_CAN_ERROR_ACTIVE);
    settle(r, 3000);
    CHECK(co_emcy_active(&r->node, 0x8140));
    CHECK(!co_emcy_active(&r->node, 0x8120));
    free(r);
}

/* ---- filters, bit rates */

static void test_filters_follow_the_routes(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    CHECK(co_cm_can_process(&r->port.can, 0));
    CHECK_EQ(r->ctrl.filter_calls, 1);
    CHECK(!r->ctrl.filter_all);
    CHECK(r->ctrl.filter_n >= 3);
    bool nmt = false, sdo = false;
    for (size_t i = 0; i < r->ctrl.filter_n; i++) {
        nmt |= r->ctrl.filter_ids[i] == 0x000;
        sdo |= r->ctrl.filter_ids[i] == 0x605;
        CHECK(i == 0 || r->ctrl.filter_ids[i] > r->ctrl.filter_ids[i - 1]); /* each once */
    }
    CHECK(nmt && sdo);
    CHECK_EQ(r->ctrl.filter_n, co_node_route_count(&r->node)); /* none twice here */
    CHECK(!co_cm_can_process(&r->port.can, 1000));             /* nothing changed: not again */
    CHECK_EQ(r->ctrl.filter_calls, 1);
    /* a change of the routes (RPDO 1 invalid): programmed again, at the next call */
    uint8_t invalid[4] = {0x05, 0x02, 0x00, 0x80};
    CHECK_EQ(co_node_write_net(&r->node, 0x1400, 1, invalid, 4), CO_ABORT_NONE);
    CHECK(co_cm_can_process(&r->port.can, 2000));
    CHECK_EQ(r->ctrl.filter_calls, 2);
    for (size_t i = 0; i < r->ctrl.filter_n; i++) {
        CHECK(r->ctrl.filter_ids[i] != 0x205);
    }
    free(r);
}

/* More routes than the port's list holds (a build with CO_CM_FILTER_IDS_MAX 4): accept
 * every frame, and the node still gets them. */
static void test_too_many_routes_accept_all(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    CHECK(co_node_route_count(&r->node) > 4);
    co_cm_can_process(&r->port.can, 0);
    CHECK_EQ(r->ctrl.filter_calls, 1);
    CHECK(r->ctrl.filter_all);
    CHECK_EQ(r->ctrl.filter_n, 0);
    free(r);
}

static void test_lss_bit_rates(void)
{
    rig_t *r = rig_new();
    CHECK_EQ(co_cm_lss_bit_rate(0), 1000000);
    CHECK_EQ(co_cm_lss_bit_rate(1), 800000);
    CHECK_EQ(co_cm_lss_bit_rate(4), 125000);
    CHECK_EQ(co_cm_lss_bit_rate(5), 0);
    CHECK_EQ(co_cm_lss_bit_rate(8), 10000);
    CHECK_EQ(co_cm_lss_bit_rate(9), 0);
    co_cm_can_lss_bit_timing(&r->port.can, 3);
    CHECK_EQ(r->ctrl.bit_rate, 250000);
    co_cm_can_lss_bit_timing(&r->port.can, 5); /* none: nothing changes */
    CHECK_EQ(r->ctrl.bit_rate, 250000);
    free(r);
}

int main(void)
{
    if (CO_CM_FILTER_IDS_MAX < 8) { /* the build with a small filter list */
        RUN(test_too_many_routes_accept_all);
        return check_summary();
    }
    RUN(test_free_mailboxes_take_frames_at_once);
    RUN(test_queue_in_arbitration_order);
    RUN(test_tx_done_refills_and_wakes_the_node);
    RUN(test_same_identifier_keeps_its_order);
    RUN(test_ring_hands_frames_to_the_node_in_order);
    RUN(test_ring_overflow_is_reported_once);
    RUN(test_fifo_overrun_is_reported);
    RUN(test_bus_states_reach_the_node);
    RUN(test_bus_events_between_two_calls_keep_their_order);
    RUN(test_filters_follow_the_routes);
    RUN(test_lss_bit_rates);
    return check_summary();
}
