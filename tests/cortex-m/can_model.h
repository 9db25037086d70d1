/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/cortex-m/can_model.h -- what the host tests' models of the STM32 CAN controllers
 * (model_bxcan.c, model_fdcan.c) share: the parts of a controller that do not depend on
 * its registers.
 *
 *   registers    the drivers' accesses (co_stm32_read / co_stm32_write, stm32_reg.h) go to
 *                the model whose register block or message RAM they address; the model gives
 *                them their hardware meaning. A write the hardware would ignore (a
 *                protected register, a busy mailbox) is ignored and counted (violations).
 *   the bus      a raw port on the simulated bus (port/sim): frames from the others arrive
 *                (received), the controller's pending transmit slots are offered to the bus
 *                as the hardware would (by identifier: every pending slot but a later one of
 *                an identifier an earlier slot has; in request order: the oldest alone) and
 *                come back when they left the wire (sent). Or no bus ("by hand"): the test
 *                completes the transmission the controller would send next itself.
 *   faults       ISO 11898-1 fault confinement: the error counters (a transmit error +8, a
 *                success -1; a receive success -1), the states (warning at 96, passive at
 *                128, bus-off past 255), bus-off (the port leaves the bus, its slots stay
 *                pending) and the recovery, which the model starts when its hardware would
 *                and which lasts 128 (bxCAN) or 129 (M_CAN) times 11 bit times.
 *   interrupts   a cm_host source: the model runs the driver's handler of a pending vector.
 *
 * Not modelled: bit-level errors on the wire (the test injects their outcome: transmit
 * errors), arbitration loss (the simulated bus arbitrates), time stamps, sleep modes.
 */
#ifndef CANOLA_TEST_CAN_MODEL_H
#define CANOLA_TEST_CAN_MODEL_H

#include <stddef.h>

#include "canola/cm_can.h"
#include "canola/sim.h"

#define CAN_MODEL_SLOTS 3
#define CAN_MODEL_VECTORS 4

typedef struct can_model can_model_t;

/** What a model adds to the shared part. */
typedef struct can_model_class {
    uint32_t (*read)(can_model_t *m, uint32_t offset);
    void (*write)(can_model_t *m, uint32_t offset, uint32_t value);
    /** A frame another node sent (the controller is on the bus). */
    void (*received)(can_model_t *m, const co_frame_t *frame);
    /** Transmit slot `slot` left the wire. */
    void (*sent)(can_model_t *m, uint32_t slot);
    /** The fault confinement state changed from `was`. */
    void (*state_changed)(can_model_t *m, co_cm_can_state_t was);
    /** The interrupt vector `v` is pending (enabled and flagged). */
    bool (*pending)(can_model_t *m, uint32_t v);
} can_model_class_t;

typedef void (*can_model_isr_fn)(void *ctx);

struct can_model {
    const can_model_class_t *cls;
    void *regs; /* the block the driver's register pointers point into */
    size_t regs_size;
    uint32_t *ram; /* message RAM (NULL: none), plain memory the driver reads and writes */
    size_t ram_words;
    /* transmit slots (mailboxes, buffers) as the bus sees them */
    co_frame_t slot_frame[CAN_MODEL_SLOTS];
    bool slot_pending[CAN_MODEL_SLOTS];
    bool slot_offered[CAN_MODEL_SLOTS];
    uint32_t slot_seq[CAN_MODEL_SLOTS];
    uint32_t seq;
    bool request_order; /* the slots leave in request order, else by identifier */
    bool transmit_held; /* the hardware sends nothing now (initialisation mode) */
    /* the bus, or none */
    co_sim_bus_t *bus;
    co_sim_port_t port;
    uint64_t by_hand_us;                                 /* without a bus: the time the test says */
    void (*on_wire)(void *ctx, const co_frame_t *frame); /* by hand: what left */
    void *on_wire_ctx;
    /* fault confinement */
    uint32_t tec, rec;
    bool bus_off;
    bool recovering;
    uint64_t recovered_at_us;
    uint32_t bit_rate;
    uint32_t recovery_bits; /* 128 x 11 or 129 x 11 */
    /* the driver's interrupt handlers, by vector */
    can_model_isr_fn isr[CAN_MODEL_VECTORS];
    void *isr_ctx;
    uint32_t vectors;
    /* what the tests read */
    uint32_t violations;    /* writes the hardware would have ignored */
    uint32_t rx_accepted;   /* frames the filters took */
    uint32_t rx_rejected;   /* frames the filters rejected */
    uint32_t rx_lost;       /* frames lost to a full receive FIFO */
    uint32_t tx_sent;       /* frames that left the wire */
    uint32_t max_pending;   /* the most slots pending at once */
    uint32_t full_requests; /* transmit requests that made every slot pending */
    /* A driver that waits on its controller reads registers with nothing changing: the
     * reads since the latest write or bus event, and the longest such run. */
    uint32_t reads_in_a_row;
    uint32_t max_reads_in_a_row;
};

/** Prepare the shared part (zeroes the model's counters; the class fills in the rest). */
void can_model_init(can_model_t *m, const can_model_class_t *cls, void *regs, size_t regs_size,
                    uint32_t *ram, size_t ram_words, uint32_t recovery_bits);
/** Join `bus` as a raw port (NULL: by hand); enter the model in the register routing and
 *  as a cm_host interrupt source. */
void can_model_attach(can_model_t *m, co_sim_bus_t *bus);
/** Forget every model (between tests). */
void can_model_detach_all(void);
/** The driver's handler of vector `v` (the model's numbering). */
void can_model_set_isr(can_model_t *m, uint32_t v, can_model_isr_fn fn, void *ctx);

/** The time: the bus's, or the one the test set by hand. */
uint64_t can_model_now(const can_model_t *m);
/** Time moved (the recovery ends on time). */
void can_model_tick(can_model_t *m, uint64_t now_us);

/** The class: slot `slot` was requested with `frame`. */
void can_model_request(can_model_t *m, uint32_t slot, const co_frame_t *frame);
/** The class: a pending slot's request withdrawn (an abort that came in time): false when
 *  it had already left. */
bool can_model_abort(can_model_t *m, uint32_t slot);
/** The class: offer what may go now (after a request, a hold lifted, recovery). */
void can_model_offer(can_model_t *m);
/** By hand: the slot the controller sends next leaves the wire. False when none waits. */
bool can_model_complete(can_model_t *m);
/** The slot that would leave next, or -1. */
int can_model_next_slot(const can_model_t *m);

/** `n` transmit errors (ISO 11898-1: +8 each): warning, passive, bus-off on the way. */
void can_model_tx_errors(can_model_t *m, uint32_t n);
/** The class: start the bus-off recovery now (its hardware's trigger came). */
void can_model_start_recovery(can_model_t *m);
/** The fault confinement state. */
co_cm_can_state_t can_model_state(const can_model_t *m);

/** The arbitration field of a frame as a number: the lower wins. */
uint32_t can_model_key(const co_frame_t *frame);

#endif /* CANOLA_TEST_CAN_MODEL_H */
