/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cortex-m/cm_rig.c -- see cm_rig.h. */
#include "cm_rig.h"

#include <string.h>

#define BXCAN_CLOCK_HZ 48000000u /* F0 at 48 MHz: every CiA 301 rate divides it */
#define FDCAN_CLOCK_HZ 80000000u

static void bx_tx(void *ctx) { co_bxcan_isr_tx(ctx); }
static void bx_rx0(void *ctx) { co_bxcan_isr_rx0(ctx); }
static void bx_sce(void *ctx) { co_bxcan_isr_sce(ctx); }
static void fd_it0(void *ctx) { co_fdcan_isr(ctx); }

static uint64_t rig_now(void *ctx) { return ((rig_dut_t *)ctx)->now_us; }

/* cm_port.c's WFI (host builds): what the test wants to look at, then on at once. */
static void (*g_wfi)(void *ctx);
static void *g_wfi_ctx;

void rig_on_wfi(void (*fn)(void *ctx), void *ctx)
{
    g_wfi = fn;
    g_wfi_ctx = ctx;
}

void co_cm_wait_for_interrupt(void);
void co_cm_wait_for_interrupt(void)
{
    if (g_wfi) {
        g_wfi(g_wfi_ctx);
    }
}

static co_err_t driver_init(rig_dut_t *d, const rig_options_t *o, uint32_t bit_rate)
{
    if (o->ctrl == RIG_BXCAN) {
        co_bxcan_config_t cfg = {.regs = (co_bxcan_regs_t *)d->model->regs,
                                 .bank_first = 0,
                                 .bank_count = 14,
                                 .clock_hz = BXCAN_CLOCK_HZ,
                                 .bit_rate = bit_rate,
                                 .request_order = o->request_order,
                                 .port = &d->port};
        can_model_set_isr(d->model, BXCAN_VEC_TX, bx_tx, &d->bx);
        can_model_set_isr(d->model, BXCAN_VEC_RX0, bx_rx0, &d->bx);
        can_model_set_isr(d->model, BXCAN_VEC_SCE, bx_sce, &d->bx);
        return co_bxcan_init(&d->bx, &cfg);
    }
    co_fdcan_config_t cfg = {.regs = (co_fdcan_regs_t *)d->model->regs,
                             .ram = d->fd_model.ram,
                             .clock_hz = FDCAN_CLOCK_HZ,
                             .bit_rate = bit_rate,
                             .request_order = o->request_order,
                             .port = &d->port};
    can_model_set_isr(d->model, FDCAN_VEC_IT0, fd_it0, &d->fd);
    return co_fdcan_init(&d->fd, &cfg);
}

co_err_t rig_dut_init(rig_dut_t *d, co_sim_bus_t *bus, const rig_options_t *o)
{
    memset(d, 0, sizeof *d);
    cm_host_reset();
    can_model_detach_all();
    d->ctrl = o->ctrl;
    uint32_t bit_rate = o->bit_rate ? o->bit_rate : 1000000u;
    /* the controller first (its interrupts are off until the driver enables them) */
    if (o->ctrl == RIG_BXCAN) {
        bxcan_model_init(&d->bx_model);
        d->bx_model.clock_hz = BXCAN_CLOCK_HZ;
        d->model = &d->bx_model.base;
    } else {
        fdcan_model_init(&d->fd_model);
        d->fd_model.clock_hz = FDCAN_CLOCK_HZ;
        d->model = &d->fd_model.base;
    }
    can_model_attach(d->model, bus);
    co_err_t err = driver_init(d, o, bit_rate);
    if (err != CO_OK) {
        return err;
    }
    co_cm_port_init(&d->port, o->ctrl == RIG_BXCAN ? &co_bxcan_ops : &co_fdcan_ops,
                    o->ctrl == RIG_BXCAN ? (void *)&d->bx : (void *)&d->fd,
                    (co_cm_time_t){.now_us = rig_now, .ctx = d});
    co_node_config_t cfg = {.node_id = o->node_id ? o->node_id : 5,
                            .od = example_od_with_domain(&d->od, o->hb_ms, d->entries)};
    cfg.od.hook_ctx = &d->domain;
    cfg.driver = co_cm_can_driver(&d->port.can);
    err = co_node_init(&d->node, &cfg);
    co_cm_port_bind(&d->port, &d->node);
    return err;
}

co_err_t rig_dut_start(rig_dut_t *d, uint64_t now_us)
{
    uint64_t now = d->model->bus ? d->model->bus->now_us : now_us;
    d->now_us = now;
    co_err_t err = co_node_start(&d->node, now);
    rig_dut_loop(d, now);
    return err;
}

void rig_dut_loop(rig_dut_t *d, uint64_t now_us)
{
    d->now_us = now_us;
    d->due_us = co_cm_port_step(&d->port);
}

co_err_t rig_peer_start(rig_peer_t *p, co_sim_bus_t *bus, uint8_t node_id, uint16_t hb_ms)
{
    memset(p, 0, sizeof *p);
    co_node_config_t cfg = {.node_id = node_id,
                            .od = example_od_with_domain(&p->od, hb_ms, p->entries)};
    cfg.od.hook_ctx = &p->domain;
    co_err_t err = co_sim_port_attach(bus, &p->port);
    if (err != CO_OK) {
        return err;
    }
    cfg.driver = co_sim_port_driver(&p->port);
    err = co_node_init(&p->node, &cfg);
    if (err != CO_OK) {
        return err;
    }
    co_sim_port_bind(&p->port, &p->node);
    return co_node_start(&p->node, bus->now_us);
}

void rig_run(co_sim_bus_t *bus, rig_dut_t *d, uint64_t until_us,
             void (*each)(void *ctx, uint64_t now_us), void *ctx)
{
    while (bus->now_us < until_us) {
        uint64_t next = bus->now_us + RIG_STEP_US;
        next = next < until_us ? next : until_us;
        co_sim_run_until(bus, next);
        can_model_tick(d->model, next);
        rig_dut_loop(d, next);
        if (each) {
            each(ctx, next);
        }
    }
}

static void monitor_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    rig_monitor_t *mon = ctx;
    if (mon->count < RIG_MONITOR_MAX) {
        mon->at_us[mon->count] = now_us;
        mon->frames[mon->count++] = *frame;
    }
}

co_err_t rig_monitor_attach(rig_monitor_t *mon, co_sim_bus_t *bus)
{
    mon->count = 0;
    return co_sim_port_attach_raw(bus, &mon->port, monitor_rx, mon);
}

uint32_t rig_monitor_count(const rig_monitor_t *mon, uint32_t id, uint64_t since_us)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < mon->count; i++) {
        n += mon->frames[i].id == id && mon->at_us[i] >= since_us;
    }
    return n;
}
