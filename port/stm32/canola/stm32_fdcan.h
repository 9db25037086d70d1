/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/stm32_fdcan.h -- a register-level driver for the STM32 FDCAN in classic CAN mode,
 * written from the reference manual (RM0440 for G4, "FD controller area network (FDCAN)").
 * The parts whose message RAM has the fixed layout of G4: G0, G4, L5, U5 (0x350 bytes per
 * controller from SRAMCAN: 28 11-bit filters, 8 29-bit filters, two receive FIFOs of 3,
 * a transmit event FIFO of 3, 3 transmit buffers). H7's configurable message RAM (and its
 * M_CAN register layout, whose interrupt bits differ) is not supported here.
 *
 * What it does for port/cortex-m (canola/cm_can.h, co_fdcan_ops):
 *   transmit   the 3 transmit buffers as a queue: the controller sends the one with the
 *              lowest identifier first (TXBC.TFQM = 1) and the driver keeps one frame per
 *              identifier in them (equal identifiers would leave by buffer number); with
 *              `request_order` a FIFO (TFQM = 0), any identifiers. Classic frames only
 *              (CCCR.FDOE = 0), automatic retransmission.
 *   receive    FIFO 0 in blocking mode: its interrupt hands each frame to the port and
 *              acknowledges it; a lost frame (a fourth while three wait: IR.RF0L) is
 *              reported.
 *   filters    the node's identifiers as dual-ID filter elements: two 11-bit per standard
 *              element (28), two 29-bit per extended element (8); frames no element takes
 *              are rejected. More than they hold: none, and every frame accepted.
 *   bit timing from the FDCAN kernel clock for the CiA 301 rates (canola/cm_bit_timing.h);
 *              the controller leaves the bus while it switches (LSS).
 *   bus-off    the controller sets CCCR.INIT; the interrupt clears it again, which starts
 *              the recovery (129 x 11 recessive bits). Warning, passive and bus-off raise an
 *              interrupt when they begin and when they end.
 *
 * Interrupts: every source on interrupt line 0 (FDCANx_IT0 -> co_fdcan_isr); line 1 unused.
 * The application enables the kernel clock (RCC CCIPR FDCANSEL) and the pins first.
 *
 * Threading: co_fdcan_init from the main loop with the interrupt off; the ops as
 * canola/cm_can.h says. Memory: co_fdcan_t, the caller's. No allocation.
 */
#ifndef CANOLA_STM32_FDCAN_H
#define CANOLA_STM32_FDCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/cm_can.h"

/** The FDCAN registers of G0/G4/L5/U5 (offsets from RM0440 44.4). */
typedef struct co_fdcan_regs {
    volatile uint32_t crel; /**< 0x000 core release */
    volatile uint32_t endn; /**< 0x004 endian */
    uint32_t reserved0;
    volatile uint32_t dbtp; /**< 0x00C data bit timing (FD only) */
    volatile uint32_t test; /**< 0x010 test */
    volatile uint32_t rwd;  /**< 0x014 RAM watchdog */
    volatile uint32_t cccr; /**< 0x018 CC control */
    volatile uint32_t nbtp; /**< 0x01C nominal bit timing */
    volatile uint32_t tscc; /**< 0x020 timestamp counter configuration */
    volatile uint32_t tscv; /**< 0x024 timestamp counter value */
    volatile uint32_t tocc; /**< 0x028 timeout counter configuration */
    volatile uint32_t tocv; /**< 0x02C timeout counter value */
    uint32_t reserved1[4];
    volatile uint32_t ecr;  /**< 0x040 error counters */
    volatile uint32_t psr;  /**< 0x044 protocol status */
    volatile uint32_t tdcr; /**< 0x048 transmitter delay compensation */
    uint32_t reserved2;
    volatile uint32_t ir;  /**< 0x050 interrupt flags (write 1 to clear) */
    volatile uint32_t ie;  /**< 0x054 interrupt enable */
    volatile uint32_t ils; /**< 0x058 interrupt line select */
    volatile uint32_t ile; /**< 0x05C interrupt line enable */
    uint32_t reserved3[8];
    volatile uint32_t rxgfc; /**< 0x080 global filter configuration */
    volatile uint32_t xidam; /**< 0x084 extended ID and mask */
    volatile uint32_t hpms;  /**< 0x088 high priority message status */
    uint32_t reserved4;
    volatile uint32_t rxf0s; /**< 0x090 Rx FIFO 0 status */
    volatile uint32_t rxf0a; /**< 0x094 Rx FIFO 0 acknowledge */
    volatile uint32_t rxf1s; /**< 0x098 Rx FIFO 1 status */
    volatile uint32_t rxf1a; /**< 0x09C Rx FIFO 1 acknowledge */
    uint32_t reserved5[8];
    volatile uint32_t txbc;   /**< 0x0C0 Tx buffer configuration */
    volatile uint32_t txfqs;  /**< 0x0C4 Tx FIFO/queue status */
    volatile uint32_t txbrp;  /**< 0x0C8 Tx buffer request pending */
    volatile uint32_t txbar;  /**< 0x0CC Tx buffer add request */
    volatile uint32_t txbcr;  /**< 0x0D0 Tx buffer cancellation request */
    volatile uint32_t txbto;  /**< 0x0D4 Tx buffer transmission occurred */
    volatile uint32_t txbcf;  /**< 0x0D8 Tx buffer cancellation finished */
    volatile uint32_t txbtie; /**< 0x0DC Tx buffer transmission interrupt enable */
    volatile uint32_t txbcie; /**< 0x0E0 Tx buffer cancellation finished interrupt enable */
    volatile uint32_t txefs;  /**< 0x0E4 Tx event FIFO status */
    volatile uint32_t txefa;  /**< 0x0E8 Tx event FIFO acknowledge */
} co_fdcan_regs_t;

/** The message RAM of one controller, in words (RM0440 44.3.3). */
#define CO_FDCAN_RAM_WORDS 212u        /* 0x350 bytes */
#define CO_FDCAN_RAM_STD_FILTERS 0u    /* 28 elements of 1 word */
#define CO_FDCAN_RAM_EXT_FILTERS 28u   /* 8 elements of 2 words */
#define CO_FDCAN_RAM_RX_FIFO0 44u      /* 3 elements of 18 words */
#define CO_FDCAN_RAM_RX_FIFO1 98u      /* 3 elements of 18 words */
#define CO_FDCAN_RAM_TX_EVENTS 152u    /* 3 elements of 2 words */
#define CO_FDCAN_RAM_TX_BUFFERS 158u   /* 3 elements of 18 words */
#define CO_FDCAN_RAM_ELEMENT_WORDS 18u /* a receive or transmit element */
#define CO_FDCAN_STD_FILTERS 28u
#define CO_FDCAN_EXT_FILTERS 8u

typedef struct co_fdcan_config {
    co_fdcan_regs_t *regs;  /**< the controller (FDCAN1 0x40006400 on G4) */
    volatile uint32_t *ram; /**< its message RAM: SRAMCAN (0x4000A400 on G4) + 0x350 x n */
    uint32_t clock_hz;      /**< the FDCAN kernel clock, after CKDIV */
    uint32_t bit_rate;      /**< bit/s, a CiA 301 rate */
    bool request_order;     /**< transmit buffers as a FIFO (TFQM = 0), see above */
    co_cm_port_t *port;     /**< where the interrupts go */
} co_fdcan_config_t;

typedef struct co_fdcan {
    co_fdcan_config_t cfg;
    co_cm_can_state_t state; /**< the error state last told to the port */
} co_fdcan_t;

/** The driver's side of canola/cm_can.h: co_cm_can_init(can, &co_fdcan_ops, drv). */
extern const co_cm_can_ops_t co_fdcan_ops;

/** Put the controller into its configuration (message RAM cleared, classic CAN, bit timing,
 *  accept-all, interrupts on line 0), then onto the bus. Returns CO_ERR_ARG for a missing
 *  register block or RAM, or a bit rate no timing fits; CO_ERR_STATE when the controller
 *  does not enter or leave initialisation. Waits a few bit times. */
co_err_t co_fdcan_init(co_fdcan_t *drv, const co_fdcan_config_t *cfg);

/** The interrupt handler of line 0. A few register accesses, plus the port's work per
 *  frame. */
void co_fdcan_isr(co_fdcan_t *drv);

#endif /* CANOLA_STM32_FDCAN_H */
