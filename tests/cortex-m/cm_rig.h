/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/cortex-m/cm_rig.h -- a device as it runs on an STM32, on the host: a canola node
 * (the example dictionary with the streamed DOMAIN 0x3000) behind port/cortex-m's CAN side
 * (cm_can.c), a register-level driver (bxCAN or FDCAN) and the model of its controller,
 * joined to the simulated bus where ordinary canola nodes are the rest of the network.
 *
 Its main loop is port/cortex-m's (cm_port.c: co_cm_port_step, the CAN side's work then
 * co_node_poll), its time base the bus's clock. rig_run advances the bus in steps of
 * RIG_STEP_US and runs a step of the main loop after each (a main loop woken by the CAN
 * interrupt runs within that); the interrupts themselves run when the model raises them, as
 * on the chip.
 */
#ifndef CANOLA_TEST_CM_RIG_H
#define CANOLA_TEST_CM_RIG_H

#include "canola/sim.h"
#include "canola/stm32_bxcan.h"
#include "canola/stm32_fdcan.h"
#include "cm_host.h"
#include "example_od_domain.h"
#include "model_bxcan.h"
#include "model_fdcan.h"

#define RIG_STEP_US 25u

typedef enum rig_ctrl { RIG_BXCAN, RIG_FDCAN } rig_ctrl_t;

typedef struct rig_options {
    rig_ctrl_t ctrl;
    bool request_order; /* the driver's transmit order (see its header) */
    uint32_t bit_rate;  /* 0: 1 Mbit/s */
    uint8_t node_id;    /* 0: 5 */
    uint16_t hb_ms;     /* the device's heartbeat */
} rig_options_t;

typedef struct rig_dut {
    rig_ctrl_t ctrl;
    bxcan_model_t bx_model;
    co_bxcan_t bx;
    fdcan_model_t fd_model;
    co_fdcan_t fd;
    can_model_t *model;
    co_cm_port_t port;
    example_od_t od;
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 1];
    pattern_domain_t domain;
    co_node_t node;
    uint64_t now_us; /* the time base: the bus's clock at the latest step */
    uint64_t due_us; /* the deadline the latest step returned */
} rig_dut_t;

/** A sim node: the example dictionary with the DOMAIN, on its own sim port. */
typedef struct rig_peer {
    example_od_t od;
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 1];
    pattern_domain_t domain;
    co_node_t node;
    co_sim_port_t port;
} rig_peer_t;

/** A raw port that keeps every frame the others send, with its time. */
#define RIG_MONITOR_MAX 8192
typedef struct rig_monitor {
    co_sim_port_t port;
    co_frame_t frames[RIG_MONITOR_MAX];
    uint64_t at_us[RIG_MONITOR_MAX];
    uint32_t count;
} rig_monitor_t;

co_err_t rig_monitor_attach(rig_monitor_t *mon, co_sim_bus_t *bus);
/** Frames seen with `id` from `since_us` on. */
uint32_t rig_monitor_count(const rig_monitor_t *mon, uint32_t id, uint64_t since_us);

/** Reset the host (cm_host, the models' routing), set the device up on `bus` (NULL: no bus,
 *  by hand) and co_node_init it (not started). Returns the first error. */
co_err_t rig_dut_init(rig_dut_t *d, co_sim_bus_t *bus, const rig_options_t *o);
/** Start the device at the bus's time (or `now_us` by hand). */
co_err_t rig_dut_start(rig_dut_t *d, uint64_t now_us);
/** One turn of the device's main loop at `now_us`. */
void rig_dut_loop(rig_dut_t *d, uint64_t now_us);

/** Call `fn(ctx)` when the main loop's sleep executes its WFI (NULL: nothing; the WFI
 *  itself returns at once here: rig_run is the loop that waits). */
void rig_on_wfi(void (*fn)(void *ctx), void *ctx);

/** Attach and start a sim node with `node_id` (heartbeat `hb_ms`). */
co_err_t rig_peer_start(rig_peer_t *p, co_sim_bus_t *bus, uint8_t node_id, uint16_t hb_ms);

/** Advance to `until_us`: the bus, the model's time, the device's main loop, and `each`
 *  (NULL: none) after every step. */
void rig_run(co_sim_bus_t *bus, rig_dut_t *d, uint64_t until_us,
             void (*each)(void *ctx, uint64_t now_us), void *ctx);

#endif /* CANOLA_TEST_CM_RIG_H */
