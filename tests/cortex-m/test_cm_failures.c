/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_cm_failures.c -- the failures users meet in other stacks' microcontroller ports, as
 * tests of canola's (port/cortex-m's CAN side, the STM32 drivers, the models of their
 * controllers on the simulated bus with canola nodes on the other side), each on both
 * controllers:
 *   (a) every mailbox busy at high bus load while the SDO server answers a block upload:
 *       the transfer completes, no frame is lost, the main loop never waits on the
 *       controller;
 *   (b) a receive FIFO overrun during a burst: counted, EMCY 0x8110 on the bus, no
 *       interrupt storm, the device goes on working;
 *   (c) bus-off and recovery: the error behaviour, back on the bus on time, EMCY 0x8140,
 *       frames resume; error passive and back: EMCY 0x8120 and its reset;
 *   (d) the transmit-complete interrupt racing the main loop's send: taken at every point
 *       of the send path where the processor could take it; no frame lost, duplicated,
 *       reordered among equal identifiers, or left waiting while a mailbox is free.
 *
 * Built once as it is and once with each CO_TEST_FAULT_* (tests/cortex-m/CMakeLists.txt),
 * which puts back a bug of the kind: the test must fail on those.
 */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "cm_rig.h"
#include "harness.h"

#define MS 1000ull

static rig_ctrl_t g_ctrl;

/* ---- the network: the device (node 5), a master (node 1), a monitor, a load */

typedef struct net {
    co_sim_bus_t bus;
    rig_dut_t dut;
    rig_peer_t master;
    rig_monitor_t mon;
    co_sim_port_t load_port;
    bool load_on;             /* bursts of 3 ms of frames at 0x010 every 4 ms */
    co_sim_port_t burst_port; /* frames the test sends in bursts */
    sdo_result_t result;
} net_t;

static net_t *net_new(bool request_order, uint16_t hb_ms)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 1000000u);
    rig_options_t o = {.ctrl = g_ctrl, .request_order = request_order, .hb_ms = hb_ms};
    CHECK_EQ(rig_dut_init(&n->dut, &n->bus, &o), CO_OK);
    CHECK_EQ(rig_monitor_attach(&n->mon, &n->bus), CO_OK);
    CHECK_EQ(co_sim_port_attach_raw(&n->bus, &n->load_port, NULL, NULL), CO_OK);
    CHECK_EQ(co_sim_port_attach_raw(&n->bus, &n->burst_port, NULL, NULL), CO_OK);
    CHECK_EQ(rig_peer_start(&n->master, &n->bus, 1, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&n->master.node, 0, 5), CO_OK);
    CHECK_EQ(rig_dut_start(&n->dut, 0), CO_OK);
    return n;
}

static void load_step(void *ctx, uint64_t now_us)
{
    net_t *n = ctx;
    if (n->load_on && now_us % (4 * MS) < 3 * MS) {
        co_frame_t f = {.id = 0x010, .len = 8};
        while (co_sim_send(&n->load_port, &f) == CO_OK) {
        }
    }
}

static void run(net_t *n, uint64_t for_us)
{
    rig_run(&n->bus, &n->dut, n->bus.now_us + for_us, load_step, n);
}

/* The time of the first EMCY of the device with `code` from `since` on (0: none). */
static uint64_t emcy_at(const net_t *n, uint16_t code, uint64_t since_us)
{
    for (uint32_t i = 0; i < n->mon.count; i++) {
        const co_frame_t *f = &n->mon.frames[i];
        if (f->id == 0x085 && n->mon.at_us[i] >= since_us &&
            (f->data[0] | f->data[1] << 8) == code) {
            return n->mon.at_us[i];
        }
    }
    return 0;
}

static void start_device(net_t *n)
{
    CHECK_EQ(co_nmt_send(&n->master.node, CO_NMT_CMD_START, 5), CO_OK);
    run(n, 2 * MS);
    CHECK_EQ(co_nmt_state(&n->dut.node), CO_NMT_OPERATIONAL);
}

/* Frames the node handed over = frames on the wire + frames still in the port. */
static void check_nothing_lost(net_t *n)
{
    const co_cm_can_t *can = &n->dut.port.can;
    uint32_t in_slots = 0;
    for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
        in_slots += n->dut.model->slot_pending[i];
    }
    const co_node_stats_t *st = co_node_stats(&n->dut.node);
    CHECK_EQ(st->tx_frames, n->dut.model->tx_sent + in_slots + can->tx_count);
    CHECK_EQ(st->tx_overflow, 0);
    CHECK_EQ(st->tx_dropped, 0);
}

/* ---- (a) */

/* TPDO 1..4 every 10 ms, all mapping 0x2000 (priority mode: with the SDO server's frames,
 * more identifiers than mailboxes). */
static void tpdos_every_10ms(net_t *n)
{
    for (uint16_t i = 0; i < 4; i++) {
        uint16_t comm = (uint16_t)(0x1800 + i), map = (uint16_t)(0x1A00 + i);
        uint32_t cob = 0x180u + 0x100u * i + 5u;
        CHECK_EQ(co_node_set_uint(&n->dut.node, comm, 1, cob | 0x80000000u), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->dut.node, comm, 2, 0xFE), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->dut.node, comm, 5, 10), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->dut.node, map, 0, 0), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->dut.node, map, 1, 0x20000020), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->dut.node, map, 0, 1), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->dut.node, comm, 1, cob), CO_ABORT_NONE);
    }
}

static void block_upload_with_mailboxes_busy(bool request_order)
{
    net_t *n = net_new(request_order, 0);
    run(n, 5 * MS);
    if (!request_order) {
        tpdos_every_10ms(n);
    }
    start_device(n);
    n->load_on = true;
    static uint8_t buf[8192];
    n->dut.domain = (pattern_domain_t){.length = sizeof buf, .up_seed = 9};
    uint64_t t0 = n->bus.now_us;
    CHECK_EQ(co_sdo_upload(&n->master.node, 0, 0x3000, 0, CO_SDO_BLOCK, buf, sizeof buf,
                           sdo_result_done, &n->result),
             CO_OK);
    while (n->result.calls == 0 && n->bus.now_us < t0 + 5000 * MS) {
        run(n, 10 * MS);
    }
    uint64_t took = n->bus.now_us - t0;
    printf("    block upload of %zu bytes: %llu ms, bus load %.0f %%, longest run of register "
           "reads %u\n",
           sizeof buf, (unsigned long long)(took / MS), 100.0 * co_sim_load(&n->bus),
           n->dut.model->max_reads_in_a_row);
    CHECK_EQ(n->result.calls, 1);
    CHECK_EQ(n->result.abort, CO_ABORT_NONE);
    CHECK_EQ(n->result.len, sizeof buf);
    CHECK(pattern_matches(buf, 9, sizeof buf));
    CHECK(took < 2000 * MS); /* at 75 % load from the bursts: about half a second */
    /* the situation asked for: every mailbox busy, the port's queue full (the node kept
     * frames: tx said busy) */
    CHECK(n->dut.model->full_requests > 0);
    CHECK_EQ(n->dut.model->max_pending, 3);
    CHECK(co_node_stats(&n->dut.node)->tx_queued > 0);
    check_nothing_lost(n);
    /* the main loop never waited on the controller: no run of register reads */
    CHECK(n->dut.model->max_reads_in_a_row < 64);
    CHECK_EQ(n->dut.model->violations, 0);
    free(n);
}

static void test_a_block_upload_with_every_mailbox_busy_by_identifier(void)
{
    block_upload_with_mailboxes_busy(false);
}

static void test_a_block_upload_with_every_mailbox_busy_in_request_order(void)
{
    block_upload_with_mailboxes_busy(true);
}

/* ---- (b) */

static void test_b_rx_fifo_overrun_during_a_burst(void)
{
    net_t *n = net_new(false, 0);
    run(n, 5 * MS);
    start_device(n);
    uint64_t t0 = n->bus.now_us;
    /* a higher-priority interrupt keeps the CAN interrupt waiting for 2 ms while 10 RPDOs
     * arrive back to back (about 1 ms at 1 Mbit/s): three fit the FIFO */
    cm_host_hold(true);
    for (uint8_t i = 1; i <= 10; i++) {
        co_frame_t f = {.id = 0x205, .len = 4, .data = {i, i, i, i}};
        while (co_sim_send(&n->burst_port, &f) != CO_OK) {
            run(n, 50);
        }
    }
    run(n, 2 * MS);
    CHECK(n->dut.model->rx_lost >= 7);
    cm_host_hold(false);
    run(n, 5 * MS);
    CHECK_EQ(cm_host_storms(), 0);
    uint64_t at = emcy_at(n, 0x8110, t0);
    CHECK(at != 0);
    CHECK(co_emcy_active(&n->dut.node, 0x8110));
    /* the device goes on: an RPDO after the burst is applied, SDO answers */
    co_frame_t after = {.id = 0x205, .len = 4, .data = {0x55, 0x66, 0x77, 0x88}};
    CHECK_EQ(co_sim_send(&n->burst_port, &after), CO_OK);
    run(n, 2 * MS);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&n->dut.node, 0x6200, 1, &v), CO_OK);
    CHECK_EQ(v, 0x55);
    uint8_t buf[4];
    CHECK_EQ(co_sdo_upload(&n->master.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, sizeof buf,
                           sdo_result_done, &n->result),
             CO_OK);
    run(n, 10 * MS);
    CHECK_EQ(n->result.calls, 1);
    CHECK_EQ(n->result.abort, CO_ABORT_NONE);
    CHECK_EQ(n->dut.model->violations, 0);
    free(n);
}

/* ---- (c) */

static void test_c_bus_off_and_recovery(void)
{
    net_t *n = net_new(false, 10);
    run(n, 5 * MS);
    start_device(n);
    run(n, 30 * MS);
    CHECK(rig_monitor_count(&n->mon, 0x705, 0) >= 3);
    uint64_t t0 = n->bus.now_us;
    can_model_tx_errors(n->dut.model, 32); /* TEC 256: bus-off */
    CHECK(n->dut.model->bus_off);
    run(n, 100 * MS);
    /* the error behaviour (0x1029 sub 1 = 0): pre-operational */
    CHECK_EQ(co_nmt_state(&n->dut.node), CO_NMT_PRE_OPERATIONAL);
    CHECK(!n->dut.model->bus_off);
    /* back on the bus no sooner than 128 x 11 bits (1.4 ms at 1 Mbit/s), and soon after */
    uint64_t first = 0;
    for (uint32_t i = 0; i < n->mon.count && !first; i++) {
        if (n->mon.at_us[i] >= t0 && (n->mon.frames[i].id & 0x7F) == 5 &&
            n->mon.frames[i].id != 0x605) {
            first = n->mon.at_us[i];
        }
    }
    CHECK(first >= t0 + 1408);
    CHECK(first != 0 && first < t0 + 20 * MS);
    CHECK(emcy_at(n, 0x8140, t0) != 0);
    /* heartbeats resume, pre-operational */
    CHECK(rig_monitor_count(&n->mon, 0x705, t0 + 20 * MS) >= 5);
    bool preop = false;
    for (uint32_t i = 0; i < n->mon.count; i++) {
        preop |= n->mon.frames[i].id == 0x705 && n->mon.at_us[i] > t0 + 20 * MS &&
                 n->mon.frames[i].data[0] == 0x7F;
    }
    CHECK(preop);
    check_nothing_lost(n);
    CHECK_EQ(n->dut.model->violations, 0);
    free(n);
}

static void test_c_error_passive_and_back(void)
{
    net_t *n = net_new(false, 10);
    run(n, 5 * MS);
    uint64_t t0 = n->bus.now_us;
    can_model_tx_errors(n->dut.model, 16); /* TEC 128: error passive, still sending */
    run(n, 5 * MS);
    CHECK(emcy_at(n, 0x8120, t0) != 0);
    /* frames sent since took TEC below 128 again: error active, the EMCY reset */
    run(n, 30 * MS);
    CHECK(n->dut.model->tec < 128);
    CHECK(!co_emcy_active(&n->dut.node, 0x8120));
    CHECK(emcy_at(n, 0x0000, t0) > emcy_at(n, 0x8120, t0));
    free(n);
}

/* ---- (d) */

typedef struct race {
    rig_dut_t dut;
    co_frame_t wire[32];
    uint32_t wire_count;
    uint32_t inject_at; /* the point at which the transmission completes (0: none) */
    uint32_t injected;
    uint32_t points_from; /* points before the send phase */
    uint32_t unsorted;    /* the port's queue seen out of arbitration order */
} race_t;

static void race_wire(void *ctx, const co_frame_t *frame)
{
    race_t *r = ctx;
    if (r->wire_count < 32) {
        r->wire[r->wire_count++] = *frame;
    }
}

static void race_point(void *ctx)
{
    race_t *r = ctx;
    const co_cm_can_t *can = &r->dut.port.can;
    for (uint32_t i = 1; i < can->tx_count; i++) {
        r->unsorted += can_model_key(&can->tx_queue[i]) < can_model_key(&can->tx_queue[i - 1]);
    }
    if (r->inject_at && cm_host_points() - r->points_from == r->inject_at) {
        r->injected++;
        (void)can_model_complete(r->dut.model); /* the interrupt runs at this point */
    }
}

/* A frame waits in the port's queue only while the mailbox it needs is busy: every mailbox,
 * or (by identifier) the one holding a frame with its identifier. */
static bool queue_waits_rightly(const race_t *r)
{
    const co_cm_can_t *can = &r->dut.port.can;
    const can_model_t *m = r->dut.model;
    if (can->tx_count == 0) {
        return true;
    }
    bool all_busy = true, same_busy = false;
    for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
        all_busy &= m->slot_pending[i];
        same_busy |= m->slot_pending[i] && m->slot_frame[i].id == can->tx_queue[0].id;
    }
    return all_busy || (!m->request_order && same_busy);
}

/* Fill `fill` mailboxes, send four frames (two of one identifier, one above and one below
 * the rest in priority) with a transmission completing at point `inject_at` of the send,
 * then let every frame out. Returns the points the send passed. */
static uint32_t race_once(bool request_order, uint32_t fill, uint32_t inject_at)
{
    race_t *r = calloc(1, sizeof *r);
    rig_options_t o = {.ctrl = g_ctrl, .request_order = request_order};
    CHECK_EQ(rig_dut_init(&r->dut, NULL, &o), CO_OK);
    r->dut.model->on_wire = race_wire;
    r->dut.model->on_wire_ctx = r;
    co_driver_t drv = co_cm_can_driver(&r->dut.port.can);
    uint8_t tag = 0;
    for (uint32_t i = 0; i < fill; i++) {
        co_frame_t f = {.id = 0x300 + i, .len = 1, .data = {tag++}};
        CHECK_EQ(drv.tx(drv.ctx, &f), CO_OK);
    }
    static const uint32_t k_ids[4] = {0x181, 0x181, 0x080, 0x400};
    r->inject_at = inject_at;
    r->points_from = cm_host_points();
    cm_host_at_point(race_point, r);
    bool waits_rightly = true;
    for (uint32_t i = 0; i < 4; i++) {
        co_frame_t f = {.id = k_ids[i], .len = 1, .data = {tag++}};
        CHECK_EQ(drv.tx(drv.ctx, &f), CO_OK);
        waits_rightly &= queue_waits_rightly(r);
    }
    uint32_t points = cm_host_points() - r->points_from;
    cm_host_at_point(NULL, NULL);
    while (can_model_complete(r->dut.model)) {
    }
    /* each frame once; equal identifiers in the order sent */
    CHECK(waits_rightly);
    CHECK_EQ(r->wire_count, fill + 4);
    CHECK_EQ(r->dut.port.can.tx_count, 0);
    uint32_t seen = 0;
    int last181 = -1;
    for (uint32_t i = 0; i < r->wire_count; i++) {
        seen |= 1u << r->wire[i].data[0];
        if (r->wire[i].id == 0x181) {
            CHECK(r->wire[i].data[0] > last181);
            last181 = r->wire[i].data[0];
        }
    }
    CHECK_EQ(seen, (1u << (fill + 4)) - 1u);
    CHECK_EQ(r->unsorted, 0);
    CHECK(inject_at == 0 || r->injected == 1);
    CHECK_EQ(r->dut.model->violations, 0);
    free(r);
    return points;
}

static void race_all_points(bool request_order)
{
    for (uint32_t fill = 0; fill <= 3; fill++) {
        uint32_t points = race_once(request_order, fill, 0);
        CHECK(points >= 8); /* enter and leave of four sends at least */
        for (uint32_t k = 1; k <= points; k++) {
            int failures = check_failures_here;
            race_once(request_order, fill, k);
            if (check_failures_here != failures) {
                printf("    (fill %u, interrupt at point %u of %u)\n", fill, k, points);
                return;
            }
        }
    }
}

/* The interrupt between the main loop's poll and its sleep: the node holds frames the port
 * refused, a mailbox frees, the refill leaves room in the port's queue. The loop must not
 * sleep then (on the chip it would sleep until some other interrupt or deadline, the frames
 * waiting). One pass of the loop (co_cm_port_step, co_cm_port_sleep), the interrupt at
 * each of its points in turn. */
typedef struct loop_race {
    rig_dut_t dut;
    uint32_t inject_at;
    uint32_t points_from;
    uint32_t completed;    /* transmissions done (by the injection, then the drain) */
    uint32_t lost_wakeups; /* WFIs with frames in the node that could go */
} loop_race_t;

static void loop_race_wfi(void *ctx)
{
    loop_race_t *r = ctx;
    r->lost_wakeups += r->dut.node.txq_count > 0 && r->dut.port.can.tx_count < CO_CM_TX_QUEUE_LEN;
}

static void loop_race_point(void *ctx)
{
    loop_race_t *r = ctx;
    if (cm_host_points() - r->points_from == r->inject_at) {
        r->completed += can_model_complete(r->dut.model);
    }
}

static uint32_t loop_race_once(uint32_t inject_at)
{
    loop_race_t *r = calloc(1, sizeof *r);
    rig_options_t o = {.ctrl = g_ctrl};
    CHECK_EQ(rig_dut_init(&r->dut, NULL, &o), CO_OK);
    CHECK_EQ(rig_dut_start(&r->dut, 0), CO_OK); /* the boot-up: a mailbox */
    uint32_t sent = 1;
    for (uint32_t i = 0; i < 2 + CO_CM_TX_QUEUE_LEN + 2; i++, sent++) {
        co_frame_t f = {.id = 0x200 + i, .len = 1, .data = {(uint8_t)i}};
        CHECK_EQ(co_node_send(&r->dut.node, &f), CO_OK);
    }
    CHECK_EQ(r->dut.node.txq_count, 2); /* mailboxes and port queue full: two in the node */
    r->inject_at = inject_at;
    r->points_from = cm_host_points();
    cm_host_at_point(loop_race_point, r);
    rig_on_wfi(loop_race_wfi, r);
    r->dut.now_us = 1000;
    (void)co_cm_port_sleep(&r->dut.port, co_cm_port_step(&r->dut.port));
    uint32_t points = cm_host_points() - r->points_from;
    cm_host_at_point(NULL, NULL);
    rig_on_wfi(NULL, NULL);
    CHECK_EQ(r->lost_wakeups, 0); /* asleep with frames that could go */
    /* and then every frame leaves, each a mailbox at a time */
    for (uint32_t i = 0; i < 64 && r->completed < sent; i++) {
        r->completed += can_model_complete(r->dut.model);
        r->dut.now_us += 100;
        if (!co_cm_port_sleep(&r->dut.port, co_cm_port_step(&r->dut.port) + 1)) {
            (void)co_cm_port_step(&r->dut.port);
        }
    }
    CHECK_EQ(r->completed, sent);
    free(r);
    return points;
}

static void test_d_tx_done_racing_the_main_loop(void)
{
    uint32_t points = loop_race_once(0);
    CHECK(points >= 2); /* the sleep's mask at least */
    for (uint32_t k = 1; k <= points; k++) {
        int failures = check_failures_here;
        loop_race_once(k);
        if (check_failures_here != failures) {
            printf("    (interrupt at point %u of %u)\n", k, points);
            return;
        }
    }
}

static void test_d_tx_done_racing_the_send_by_identifier(void) { race_all_points(false); }

static void test_d_tx_done_racing_the_send_in_request_order(void) { race_all_points(true); }

/* Which of (a)..(d) to run: all, or those whose letters argv[1] names ("ab"). */
static const char *g_only;

static bool wanted(char letter) { return !g_only || strchr(g_only, letter) != NULL; }

#define RUN_CASE(letter, test)                                                                     \
    do {                                                                                           \
        if (wanted(letter)) {                                                                      \
            RUN(test);                                                                             \
        }                                                                                          \
    } while (0)

int main(int argc, char **argv)
{
    const char *names[2] = {"bxCAN", "FDCAN"};
    g_only = argc > 1 ? argv[1] : NULL;
    for (int c = 0; c < 2; c++) {
        int failed_before = check_tests_failed;
        g_ctrl = (rig_ctrl_t)c;
        printf("-- %s\n", names[c]);
        RUN_CASE('a', test_a_block_upload_with_every_mailbox_busy_by_identifier);
        RUN_CASE('a', test_a_block_upload_with_every_mailbox_busy_in_request_order);
        RUN_CASE('b', test_b_rx_fifo_overrun_during_a_burst);
        RUN_CASE('c', test_c_bus_off_and_recovery);
        RUN_CASE('c', test_c_error_passive_and_back);
        RUN_CASE('d', test_d_tx_done_racing_the_send_by_identifier);
        RUN_CASE('d', test_d_tx_done_racing_the_send_in_request_order);
        RUN_CASE('d', test_d_tx_done_racing_the_main_loop);
        printf("%s: %d failed\n", names[c], check_tests_failed - failed_before);
    }
    return check_summary();
}
