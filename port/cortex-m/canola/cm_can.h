/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/cm_can.h -- the CAN controller as port/cortex-m sees it: what a register-level
 * driver gives the port (co_cm_can_ops_t), and the calls its interrupt handlers make into
 * the port (co_cm_isr_*). The contract between port/cortex-m (cm_can.c: the receive ring,
 * the transmit queue behind the mailboxes, bus states) and the drivers (port/stm32: bxCAN,
 * FDCAN in classic mode; the QEMU examples' SLCAN-over-UART stand-in).
 *
 * The split of work:
 *   interrupt handlers (driver)  read a received frame from the controller's FIFO and hand
 *                                it to co_cm_isr_rx; a freed transmit mailbox to
 *                                co_cm_isr_tx_done; a changed error state to
 *                                co_cm_isr_bus_state; a FIFO overrun to co_cm_isr_rx_overrun.
 *   the port (cm_can.c)          keeps a single-producer single-consumer receive ring (the
 *                                CAN interrupt fills it, the main loop drains it: no lock)
 *                                and a small transmit queue in arbitration order behind the
 *                                mailboxes (the core's own queue, CO_TX_QUEUE_LEN, behind
 *                                that); the transmit-complete interrupt puts the highest
 *                                priority waiting frame into the freed mailbox.
 *   the main loop                drains the ring into co_node_ingest, hands bus events to
 *                                co_node_bus_event, calls co_node_poll, sleeps (WFI) until
 *                                the deadline poll returned or an interrupt.
 * A full mailbox set never blocks the main loop: the node's tx callback queues or answers
 * CO_ERR_BUSY (the core keeps the frame), it never waits.
 *
 * Threading: the ops below marked "critical section" are called with the port's critical
 * section held (interrupts masked, cm_critical.h); the others from the main loop only. The
 * driver calls co_cm_isr_rx and co_cm_isr_rx_overrun from one interrupt priority (the ring
 * has one producer); the other co_cm_isr_* calls from any CAN interrupt.
 * Memory: the driver's state is its own (hw); the port's CAN side is a co_cm_can_t in
 * co_cm_port_t (cm_port.h), where the interrupt calls find it. No allocation.
 */
#ifndef CANOLA_CM_CAN_H
#define CANOLA_CM_CAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "canola/node.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The controller's error state (ISO 11898-1 fault confinement). */
typedef enum co_cm_can_state {
    CO_CM_CAN_ERROR_ACTIVE = 0, /**< both error counters below 96 (or back below 128) */
    CO_CM_CAN_ERROR_WARNING,    /**< a counter at 96 or more: reported, no EMCY of its own */
    CO_CM_CAN_ERROR_PASSIVE,    /**< a counter at 128 or more -> CO_BUS_ERROR_PASSIVE */
    CO_CM_CAN_BUS_OFF,          /**< transmit counter past 255 -> CO_BUS_OFF */
} co_cm_can_state_t;

/** What a CAN controller driver gives the port. `hw` is the driver's own state. */
typedef struct co_cm_can_ops {
    /** Put `frame` into a free transmit mailbox and request its transmission. Returns
     *  true when a mailbox took it, false when every mailbox is busy. Critical section
     *  (from the main loop's send and from the transmit-complete interrupt). */
    bool (*mailbox_put)(void *hw, const co_frame_t *frame);
    /** Program the acceptance filters to pass the `n` identifiers in `ids` (bit 31 set:
     *  29-bit identifier; the list may hold one twice), data and remote frames alike.
     *  `ids` NULL: accept every frame. Returns false when they do not fit the controller's
     *  filter banks: the driver then accepts every frame. Main loop. */
    bool (*set_filters)(void *hw, const uint32_t *ids, size_t n);
    /** Switch to `bit_rate` bit/s (a CiA 301 rate, 10 k..1 M) from the driver's peripheral
     *  clock; the controller leaves the bus while it switches (LSS's bit-timing switch).
     *  Returns CO_ERR_ARG when no bit timing fits. Main loop. */
    co_err_t (*set_bit_rate)(void *hw, uint32_t bit_rate);
    /** The transmit and receive error counters as the controller holds them. */
    void (*error_counters)(void *hw, uint8_t *tec, uint8_t *rec);
} co_cm_can_ops_t;

/** Frames the receive ring holds: a power of two, 2..32768. A frame waits in it from the
 *  interrupt until the main loop's next co_cm_can_process (16 frames: 1.8 ms at 1 Mbit/s). */
#ifndef CO_CM_RX_RING_LEN
#define CO_CM_RX_RING_LEN 16
#endif
/** Frames the port queues behind a full mailbox set (1..255), in arbitration order; the
 *  core's own queue (CO_TX_QUEUE_LEN) holds what comes after. */
#ifndef CO_CM_TX_QUEUE_LEN
#define CO_CM_TX_QUEUE_LEN 4
#endif
/** Identifiers co_cm_can_process hands set_filters at most (a list on its stack, 4 bytes
 *  each); a node with more routes gets accept-all. 64 covers the biggest bank sets of the
 *  drivers (bxCAN 28 banks: 56 identifiers; FDCAN on G4: 56 11-bit and 16 29-bit). */
#ifndef CO_CM_FILTER_IDS_MAX
#define CO_CM_FILTER_IDS_MAX 64
#endif

#if CO_CM_RX_RING_LEN < 2 || CO_CM_RX_RING_LEN > 32768 ||                                          \
    (CO_CM_RX_RING_LEN & (CO_CM_RX_RING_LEN - 1)) != 0
#error "CO_CM_RX_RING_LEN must be a power of two, 2..32768"
#endif
#if CO_CM_TX_QUEUE_LEN < 1 || CO_CM_TX_QUEUE_LEN > 255
#error "CO_CM_TX_QUEUE_LEN must be 1..255"
#endif

/** The port's CAN side. Fields are internal. */
typedef struct co_cm_can {
    /* Receive ring: the interrupt writes a slot, then rx_head; the main loop reads the slot
     * at rx_tail, then moves rx_tail. Both count frames from 0 and wrap. */
    co_frame_t rx_ring[CO_CM_RX_RING_LEN];
    volatile uint16_t rx_head;
    volatile uint16_t rx_tail;
    volatile uint32_t rx_lost; /* overruns seen by the interrupt (ring full, FIFO overrun) */
    uint32_t rx_lost_told;     /* the main loop's: rx_lost when it last told the node */
    /* Transmit queue behind the mailboxes, in arbitration order (critical section). */
    co_frame_t tx_queue[CO_CM_TX_QUEUE_LEN];
    uint8_t tx_count;
    bool tx_refused;         /* tx answered CO_ERR_BUSY: the node holds frames */
    volatile bool tx_room;   /* the interrupt made room since: the node should poll */
    volatile uint8_t state;  /* co_cm_can_state_t as the interrupt saw it last */
    volatile uint8_t events; /* bus events the interrupt saw, for the main loop */
    bool filters_stale;      /* the node's routes changed: program the filters */
    const co_cm_can_ops_t *ops;
    void *hw;
    co_node_t *node;
} co_cm_can_t;

typedef struct co_cm_port co_cm_port_t; /* cm_port.h */

/* ---- The main loop's calls. */

/** Prepare the CAN side for the driver `ops` on `hw` (the driver's own init comes first).
 *  The controller must not raise its interrupts before this. */
void co_cm_can_init(co_cm_can_t *can, const co_cm_can_ops_t *ops, void *hw);

/** The node's driver (co_node_config_t.driver): its tx puts a frame into a free mailbox, or
 *  queues it behind them in arbitration order, or answers CO_ERR_BUSY (the node keeps it);
 *  it never waits. Its on_routes_changed marks the filters for co_cm_can_process. */
co_driver_t co_cm_can_driver(co_cm_can_t *can);

/** The node the received frames and bus events go to (after co_node_init, before
 *  co_node_start: the routes its start sets program the filters). */
void co_cm_can_bind(co_cm_can_t *can, co_node_t *node);

/** The main loop's share: program the filters if the routes changed; hand the frames of
 *  the ring to co_node_ingest at `now_us` (at most one ring's worth: a flood does not keep
 *  the loop here); tell the node of lost frames (CO_BUS_RX_OVERRUN) and of changed bus
 *  states (CO_BUS_ERROR_PASSIVE / _ACTIVE, CO_BUS_OFF, CO_BUS_OFF_RECOVERED). Returns
 *  true when it did something (call co_node_poll before sleeping). Cost: the frames'
 *  ingest; filters O(routes) plus the driver's programming when they changed. */
bool co_cm_can_process(co_cm_can_t *can, uint64_t now_us);

/** True when nothing waits for co_cm_can_process. The main loop asks with interrupts
 *  masked and sleeps (WFI) only when it is true: an interrupt after the question still
 *  wakes it. O(1). */
bool co_cm_can_idle(const co_cm_can_t *can);

/** Switch the controller's bit rate (ops.set_bit_rate): CO_ERR_ARG when no bit timing
 *  fits the peripheral clock. Main loop. */
co_err_t co_cm_can_set_bit_rate(co_cm_can_t *can, uint32_t bit_rate);

/** The CiA 301 bit rate (bit/s) of LSS bit timing table 0 `index` (0 = 1000 k .. 8 = 10 k),
 *  0 for an index without one. */
uint32_t co_cm_lss_bit_rate(uint8_t index);

/** For co_lss_slave_config_t.on_bit_timing with ctx = the co_cm_can_t: switches to the
 *  table-0 rate `index`. */
void co_cm_can_lss_bit_timing(void *ctx, uint8_t index);

/* ---- Calls from the driver's interrupt handlers (interrupt context). */

/** A frame was received: into the receive ring, or counted as lost when it is full. */
void co_cm_isr_rx(co_cm_port_t *port, const co_frame_t *frame);
/** The controller's receive FIFO overran: frames were lost before the ring (EMCY 0x8110). */
void co_cm_isr_rx_overrun(co_cm_port_t *port);
/** A transmit mailbox became free: the port puts the highest-priority waiting frame in. */
void co_cm_isr_tx_done(co_cm_port_t *port);
/** The controller's error state changed (reported to the node from the main loop). */
void co_cm_isr_bus_state(co_cm_port_t *port, co_cm_can_state_t state);

#ifdef __cplusplus
}
#endif

#endif /* CANOLA_CM_CAN_H */
