/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_cm_drivers.c -- the STM32 bxCAN and FDCAN drivers against the models of their
 * controllers: a device that boots and serves SDO on the simulated bus, the acceptance
 * filters from the node's routes (and accept-all when they do not fit), the transmit
 * order by identifier and by request, bit timing and the LSS switch, error counters, a
 * controller that never answers. Every test runs on both controllers.
 */
#include <stdlib.h>

#include "check.h"
#include "cm_rig.h"
#include "harness.h"

#define MS 1000ull

static rig_ctrl_t g_ctrl; /* the controller of the test that runs */

static const co_cm_can_ops_t *ops_of(const rig_dut_t *d)
{
    return d->ctrl == RIG_BXCAN ? &co_bxcan_ops : &co_fdcan_ops;
}

static void *hw_of(rig_dut_t *d) { return d->ctrl == RIG_BXCAN ? (void *)&d->bx : (void *)&d->fd; }

typedef struct net {
    co_sim_bus_t bus;
    rig_dut_t dut;
    rig_peer_t master;
    rig_monitor_t mon;
    sdo_result_t result;
} net_t;

static net_t *net_new(rig_options_t o)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, o.bit_rate ? o.bit_rate : 1000000u);
    o.ctrl = g_ctrl;
    CHECK_EQ(rig_dut_init(&n->dut, &n->bus, &o), CO_OK);
    CHECK_EQ(rig_monitor_attach(&n->mon, &n->bus), CO_OK);
    CHECK_EQ(rig_peer_start(&n->master, &n->bus, 1, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&n->master.node, 0, co_node_id(&n->dut.node)), CO_OK);
    CHECK_EQ(rig_dut_start(&n->dut, 0), CO_OK);
    return n;
}

/* ---- on the bus */

static void test_device_boots_and_serves_sdo(void)
{
    net_t *n = net_new((rig_options_t){.hb_ms = 100});
    rig_run(&n->bus, &n->dut, 10 * MS, NULL, NULL);
    CHECK_EQ(rig_monitor_count(&n->mon, 0x705, 0), 1); /* boot-up */

    uint8_t buf[4] = {0};
    CHECK_EQ(co_sdo_upload(&n->master.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, sizeof buf,
                           sdo_result_done, &n->result),
             CO_OK);
    rig_run(&n->bus, &n->dut, n->bus.now_us + 10 * MS, NULL, NULL);
    CHECK_EQ(n->result.calls, 1);
    CHECK_EQ(n->result.abort, CO_ABORT_NONE);
    CHECK_EQ(buf[0] | buf[1] << 8 | buf[2] << 16 | (uint32_t)buf[3] << 24, n->dut.od.device_type);

    /* 4 KiB by block upload */
    static uint8_t big[4096];
    n->dut.domain = (pattern_domain_t){.length = sizeof big, .up_seed = 3};
    n->result.calls = 0;
    CHECK_EQ(co_sdo_upload(&n->master.node, 0, 0x3000, 0, CO_SDO_BLOCK, big, sizeof big,
                           sdo_result_done, &n->result),
             CO_OK);
    rig_run(&n->bus, &n->dut, n->bus.now_us + 300 * MS, NULL, NULL);
    CHECK_EQ(n->result.calls, 1);
    CHECK_EQ(n->result.abort, CO_ABORT_NONE);
    CHECK_EQ(n->result.len, sizeof big);
    CHECK(pattern_matches(big, 3, sizeof big));
    /* heartbeats every 100 ms from the boot-up on */
    CHECK_EQ(rig_monitor_count(&n->mon, 0x705, 0), 1 + n->bus.now_us / (100 * MS));
    CHECK_EQ(n->dut.model->violations, 0);
    CHECK_EQ(co_node_stats(&n->dut.node)->tx_overflow, 0);
    free(n);
}

/* The filters take the node's identifiers, data and remote frames, and nothing else. */
static void test_filters_take_the_routes_only(void)
{
    net_t *n = net_new((rig_options_t){0});
    rig_run(&n->bus, &n->dut, 5 * MS, NULL, NULL);
    can_model_t *m = n->dut.model;
    uint32_t accepted = m->rx_accepted, rejected = m->rx_rejected;
    co_frame_t other = frm(0x123, "01");
    co_frame_t nmt = frm(0x000, "80 05");        /* NMT: routed */
    co_frame_t rtr = frm(0x705, "R1");           /* node guarding's remote request: routed */
    co_frame_t ext = frm(0x1ABCDEF, "01 02");    /* 29-bit: not routed */
    co_frame_t near = frm(0x604, "40 00 10 00"); /* another node's SDO */
    const co_frame_t *sent[] = {&other, &nmt, &rtr, &ext, &near};
    for (uint32_t i = 0; i < 5; i++) {
        CHECK_EQ(co_sim_send(&n->mon.port, sent[i]), CO_OK);
        rig_run(&n->bus, &n->dut, n->bus.now_us + 1 * MS, NULL, NULL);
    }
    CHECK_EQ(m->rx_accepted - accepted, 2);
    CHECK_EQ(m->rx_rejected - rejected, 3);
    CHECK_EQ(co_nmt_state(&n->dut.node), CO_NMT_PRE_OPERATIONAL); /* the 0x80 was taken */
    CHECK_EQ(m->violations, 0);
    free(n);
}

/* More identifiers than the banks (bxCAN: 14 banks, 28 11-bit) or elements (FDCAN: 28
 * elements, 56 11-bit) hold: set_filters says so, and every frame is taken. */
static void test_too_many_identifiers_accept_all(void)
{
    rig_dut_t *d = calloc(1, sizeof *d);
    CHECK_EQ(rig_dut_init(d, NULL, &(rig_options_t){.ctrl = g_ctrl}), CO_OK);
    uint32_t ids[60];
    for (uint32_t i = 0; i < 60; i++) {
        ids[i] = 0x100 + i;
    }
    size_t fits = d->ctrl == RIG_BXCAN ? 28 : 56;
    CHECK(ops_of(d)->set_filters(hw_of(d), ids, fits));
    co_frame_t f = frm(0x100 + (uint32_t)fits, "01"); /* one past the list */
    d->model->cls->received(d->model, &f);
    CHECK_EQ(d->model->rx_rejected, 1);
    CHECK(!ops_of(d)->set_filters(hw_of(d), ids, fits + 1));
    d->model->cls->received(d->model, &f);
    co_frame_t stranger = frm(0x7FF, "01");
    d->model->cls->received(d->model, &stranger);
    co_frame_t ext = frm(0x1ABCDEF, "01");
    d->model->cls->received(d->model, &ext);
    CHECK_EQ(d->model->rx_accepted, 3);
    /* 29-bit identifiers: one a bank (bxCAN), two an element (FDCAN: 8 elements) */
    uint32_t ext_ids[17];
    for (uint32_t i = 0; i < 17; i++) {
        ext_ids[i] = 0x80000000u | (0x10000u + i);
    }
    size_t ext_fit = d->ctrl == RIG_BXCAN ? 14 : 16;
    CHECK(ops_of(d)->set_filters(hw_of(d), ext_ids, ext_fit));
    CHECK(!ops_of(d)->set_filters(hw_of(d), ext_ids, ext_fit + 1));
    CHECK(ops_of(d)->set_filters(hw_of(d), NULL, 0)); /* accept-all asked for */
    CHECK_EQ(d->model->violations, 0);
    free(d);
}

/* Filter contents: mixed 11-bit and 29-bit identifiers, an odd number of each. */
static void test_mixed_identifiers(void)
{
    rig_dut_t *d = calloc(1, sizeof *d);
    CHECK_EQ(rig_dut_init(d, NULL, &(rig_options_t){.ctrl = g_ctrl}), CO_OK);
    uint32_t ids[] = {0x000, 0x080, 0x605, 0x80000000u | 0x18FF0005u, 0x80000000u | 0x0u};
    CHECK(ops_of(d)->set_filters(hw_of(d), ids, 5));
    co_frame_t f;
    for (uint32_t i = 0; i < 5; i++) {
        f = frm(0, "");
        f.id = ids[i] & 0x1FFFFFFFu;
        f.flags = (ids[i] & 0x80000000u) ? CO_FRAME_EXT : 0;
        d->model->cls->received(d->model, &f);
        f.flags |= CO_FRAME_RTR;
        d->model->cls->received(d->model, &f);
    }
    CHECK_EQ(d->model->rx_accepted, 10);
    f = (co_frame_t){.id = 0x605, .flags = CO_FRAME_EXT}; /* 29-bit 0x605: not the same */
    d->model->cls->received(d->model, &f);
    f = (co_frame_t){.id = 0x606};
    d->model->cls->received(d->model, &f);
    f = (co_frame_t){.id = 0x18FF0004, .flags = CO_FRAME_EXT};
    d->model->cls->received(d->model, &f);
    CHECK_EQ(d->model->rx_rejected, 3);
    free(d);
}

/* ---- transmit order, by hand */

typedef struct wire {
    co_frame_t frames[64];
    uint32_t count;
} wire_t;

static void on_wire(void *ctx, const co_frame_t *frame)
{
    wire_t *w = ctx;
    if (w->count < 64) {
        w->frames[w->count++] = *frame;
    }
}

static void put3(rig_dut_t *d, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t ids[3] = {a, b, c};
    for (uint32_t i = 0; i < 3; i++) {
        co_frame_t f = {.id = ids[i], .len = 1, .data = {(uint8_t)i}};
        CHECK(ops_of(d)->mailbox_put(hw_of(d), &f));
    }
}

static void test_mailboxes_by_identifier_or_by_request(void)
{
    for (int order = 0; order < 2; order++) {
        rig_dut_t *d = calloc(1, sizeof *d);
        wire_t w = {0};
        CHECK_EQ(rig_dut_init(d, NULL, &(rig_options_t){.ctrl = g_ctrl, .request_order = order}),
                 CO_OK);
        d->model->on_wire = on_wire;
        d->model->on_wire_ctx = &w;
        put3(d, 0x300, 0x100, 0x200);
        co_frame_t f = {.id = 0x050, .len = 0};
        CHECK(!ops_of(d)->mailbox_put(hw_of(d), &f)); /* full */
        while (can_model_complete(d->model)) {
        }
        CHECK_EQ(w.count, 3);
        uint32_t want_id[2][3] = {{0x100, 0x200, 0x300}, {0x300, 0x100, 0x200}};
        for (uint32_t i = 0; i < 3; i++) {
            CHECK_EQ(w.frames[i].id, want_id[order][i]);
        }
        /* the same identifier twice: by identifier the driver keeps the second out until
         * the first left (it would go by mailbox number); in request order both go */
        f = (co_frame_t){.id = 0x181, .len = 1, .data = {1}};
        CHECK(ops_of(d)->mailbox_put(hw_of(d), &f));
        f.data[0] = 2;
        CHECK_EQ(ops_of(d)->mailbox_put(hw_of(d), &f), order == 1);
        CHECK_EQ(d->model->violations, 0);
        free(d);
    }
}

/* ---- bit timing, counters, a silent controller */

static void test_bit_rates_and_the_lss_switch(void)
{
    const uint32_t rates[] = {10000, 20000, 50000, 125000, 250000, 500000, 800000, 1000000};
    for (uint32_t i = 0; i < 8; i++) {
        rig_dut_t *d = calloc(1, sizeof *d);
        CHECK_EQ(rig_dut_init(d, NULL, &(rig_options_t){.ctrl = g_ctrl, .bit_rate = rates[i]}),
                 CO_OK);
        CHECK_EQ(d->model->bit_rate, rates[i]);
        /* the LSS switch to the next rate up, through the port */
        uint32_t to = rates[(i + 1) % 8];
        CHECK_EQ(co_cm_can_set_bit_rate(&d->port.can, to), CO_OK);
        CHECK_EQ(d->model->bit_rate, to);
        CHECK(!d->model->transmit_held); /* back on the bus */
        CHECK_EQ(co_cm_can_set_bit_rate(&d->port.can, 33333), CO_ERR_ARG);
        CHECK_EQ(d->model->bit_rate, to);
        CHECK_EQ(d->model->violations, 0);
        free(d);
    }
}

static void lss_done(void *ctx, const co_lss_result_t *result)
{
    *(int *)ctx = result->status == CO_LSS_OK ? 1 : -1;
}

/* LSS end to end: a master configures bit timing index 3 (250 kbit/s) and activates it; the
 * device's LSS slave calls co_cm_can_lss_bit_timing, the driver switches the controller;
 * the network follows, and the device answers SDO at the new rate. */
static void test_lss_switches_the_bit_rate(void)
{
    net_t *n = net_new((rig_options_t){.bit_rate = 500000});
    co_lss_slave_config_t lc = {.bit_timings = 0x1DF, /* table 0 but index 5 */
                                .on_bit_timing = co_cm_can_lss_bit_timing,
                                .ctx = &n->dut.port.can};
    CHECK_EQ(co_lss_slave_setup(&n->dut.node, &lc), CO_OK);
    rig_run(&n->bus, &n->dut, 5 * MS, NULL, NULL);
    CHECK_EQ(n->dut.model->bit_rate, 500000);
    int done = 0;
    CHECK_EQ(co_lss_switch_global(&n->master.node, CO_LSS_CONFIGURATION), CO_OK);
    CHECK_EQ(co_lss_configure_bit_timing(&n->master.node, 0, 3, lss_done, &done), CO_OK);
    rig_run(&n->bus, &n->dut, n->bus.now_us + 20 * MS, NULL, NULL);
    CHECK_EQ(done, 1);
    CHECK_EQ(co_lss_activate_bit_timing(&n->master.node, 10), CO_OK);
    rig_run(&n->bus, &n->dut, n->bus.now_us + 15 * MS, NULL, NULL);
    CHECK_EQ(n->dut.model->bit_rate, 250000);
    n->bus.bitrate = 250000; /* the rest of the network switches too */
    rig_run(&n->bus, &n->dut, n->bus.now_us + 20 * MS, NULL, NULL);
    CHECK_EQ(co_lss_switch_global(&n->master.node, CO_LSS_WAITING), CO_OK);
    uint8_t buf[4];
    CHECK_EQ(co_sdo_upload(&n->master.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, sizeof buf,
                           sdo_result_done, &n->result),
             CO_OK);
    rig_run(&n->bus, &n->dut, n->bus.now_us + 20 * MS, NULL, NULL);
    CHECK_EQ(n->result.calls, 1);
    CHECK_EQ(n->result.abort, CO_ABORT_NONE);
    CHECK_EQ(n->dut.model->violations, 0);
    free(n);
}

static void test_error_counters_are_read(void)
{
    rig_dut_t *d = calloc(1, sizeof *d);
    CHECK_EQ(rig_dut_init(d, NULL, &(rig_options_t){.ctrl = g_ctrl}), CO_OK);
    uint8_t tec = 1, rec = 1;
    ops_of(d)->error_counters(hw_of(d), &tec, &rec);
    CHECK_EQ(tec, 0);
    CHECK_EQ(rec, 0);
    can_model_tx_errors(d->model, 3);
    d->model->rec = 17;
    ops_of(d)->error_counters(hw_of(d), &tec, &rec);
    CHECK_EQ(tec, 24);
    CHECK_EQ(rec, 17);
    free(d);
}

static void test_a_silent_controller_is_an_error(void)
{
    rig_dut_t *d = calloc(1, sizeof *d);
    cm_host_reset();
    can_model_detach_all(); /* the previous test's models are gone */
    if (g_ctrl == RIG_BXCAN) {
        bxcan_model_init(&d->bx_model);
        d->bx_model.stuck_in_init = true;
        can_model_attach(&d->bx_model.base, NULL);
        co_bxcan_config_t cfg = {.regs = &d->bx_model.regs,
                                 .bank_count = 14,
                                 .clock_hz = 48000000,
                                 .bit_rate = 500000,
                                 .port = &d->port};
        CHECK_EQ(co_bxcan_init(&d->bx, &cfg), CO_ERR_STATE);
        cfg.bank_first = 20; /* past the 28 banks */
        CHECK_EQ(co_bxcan_init(&d->bx, &cfg), CO_ERR_ARG);
        cfg.bank_first = 0;
        cfg.clock_hz = 42000000; /* 800 kbit/s does not divide 42 MHz */
        cfg.bit_rate = 800000;
        CHECK_EQ(co_bxcan_init(&d->bx, &cfg), CO_ERR_ARG);
    } else {
        fdcan_model_init(&d->fd_model);
        d->fd_model.cccr = 0; /* out of initialisation, and never again */
        d->fd_model.stuck_in_init = true;
        can_model_attach(&d->fd_model.base, NULL);
        co_fdcan_config_t cfg = {.regs = &d->fd_model.regs,
                                 .ram = d->fd_model.ram,
                                 .clock_hz = 80000000,
                                 .bit_rate = 500000,
                                 .port = &d->port};
        CHECK_EQ(co_fdcan_init(&d->fd, &cfg), CO_ERR_STATE);
        cfg.ram = NULL;
        CHECK_EQ(co_fdcan_init(&d->fd, &cfg), CO_ERR_ARG);
    }
    free(d);
}

int main(void)
{
    const char *names[2] = {"bxCAN", "FDCAN"};
    for (int c = 0; c < 2; c++) {
        g_ctrl = (rig_ctrl_t)c;
        printf("-- %s\n", names[c]);
        RUN(test_device_boots_and_serves_sdo);
        RUN(test_filters_take_the_routes_only);
        RUN(test_too_many_identifiers_accept_all);
        RUN(test_mixed_identifiers);
        RUN(test_mailboxes_by_identifier_or_by_request);
        RUN(test_bit_rates_and_the_lss_switch);
        RUN(test_lss_switches_the_bit_rate);
        RUN(test_error_counters_are_read);
        RUN(test_a_silent_controller_is_an_error);
    }
    return check_summary();
}
