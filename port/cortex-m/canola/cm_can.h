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
 * section held (interrupts masked, see cm_port.h); the others from the main loop only.
 * Memory: the driver's state is its own (hw); the port's lives in co_cm_port_t.
 */
#ifndef CANOLA_CM_CAN_H
#define CANOLA_CM_CAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

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
     *  29-bit identifier; the list may hold one twice). Returns false when they do not fit
     *  the controller's filter banks: the driver then accepts every frame. Main loop. */
    bool (*set_filters)(void *hw, const uint32_t *ids, size_t n);
    /** Switch to `bit_rate` bit/s (a CiA 301 rate, 10 k..1 M) from the driver's peripheral
     *  clock; the controller leaves the bus while it switches (LSS's bit-timing switch).
     *  Returns CO_ERR_ARG when no bit timing fits. Main loop. */
    co_err_t (*set_bit_rate)(void *hw, uint32_t bit_rate);
    /** The transmit and receive error counters as the controller holds them. */
    void (*error_counters)(void *hw, uint8_t *tec, uint8_t *rec);
} co_cm_can_ops_t;

typedef struct co_cm_port co_cm_port_t; /* cm_port.h */

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
