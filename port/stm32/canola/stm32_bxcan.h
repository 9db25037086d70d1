/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/stm32_bxcan.h -- a register-level driver for the STM32 bxCAN (F0, F1, F3, F4, F7,
 * L4), written from the reference manuals (RM0090 for F4, RM0008 for F1: "Controller area
 * network (bxCAN)"). No vendor HAL: the registers are the struct below.
 *
 * What it does for port/cortex-m (canola/cm_can.h, co_bxcan_ops):
 *   transmit   three mailboxes. By default the controller sends the one with the lowest
 *              identifier first (MCR.TXFP = 0) and the driver keeps one frame per
 *              identifier in them (equal identifiers would leave by mailbox number, not
 *              in order); with `request_order` it sends them in the order requested
 *              (TXFP = 1), any identifiers. Automatic retransmission.
 *   receive    FIFO 0: its interrupt hands each frame to the port and releases it; an
 *              overrun (FOVR0: a fourth frame while three wait) is cleared and reported.
 *   filters    the node's identifiers in the controller's banks: two 11-bit identifiers
 *              per bank (16-bit mask mode: the remote request bit ignored), one 29-bit per
 *              bank (32-bit mask mode); more than the banks hold: one accept-all bank.
 *   bit timing from the CAN clock (APB1) for the CiA 301 rates (canola/cm_bit_timing.h):
 *              the controller leaves the bus while it switches (LSS).
 *   bus-off    automatic recovery (MCR.ABOM: 128 x 11 recessive bits). The states: error
 *              warning, passive and bus-off raise the status-change interrupt; the way back
 *              (which raises none) is seen by the next interrupt of any kind.
 *
 * Interrupts: CANx_TX -> co_bxcan_isr_tx, CANx_RX0 -> co_bxcan_isr_rx0, CANx_SCE ->
 * co_bxcan_isr_sce, all at one priority; on parts with one CAN vector (F0: CEC_CAN)
 * co_bxcan_isr does all three. FIFO 1 is not used.
 *
 * Dual CAN (F105/F107, F4, F7): CAN2's filter banks are in CAN1's registers (`filters`)
 * from FMR.CAN2SB on, which the application sets; give each controller its own range.
 * The application enables the clock and the pins before co_bxcan_init.
 *
 * Threading: co_bxcan_init from the main loop with the CAN interrupts off; the ops as
 * canola/cm_can.h says. Memory: co_bxcan_t, the caller's. No allocation.
 */
#ifndef CANOLA_STM32_BXCAN_H
#define CANOLA_STM32_BXCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/cm_can.h"

/** A transmit mailbox and a receive FIFO's output: identifier, length/time, data. */
typedef struct co_bxcan_mailbox {
    volatile uint32_t ir;  /**< TIxR / RIxR: STID[31:21], EXID[20:3], IDE 2, RTR 1, TXRQ 0 */
    volatile uint32_t dtr; /**< TDTxR / RDTxR: DLC[3:0] (RDTxR: FMI[15:8]) */
    volatile uint32_t dlr; /**< data bytes 0..3 */
    volatile uint32_t dhr; /**< data bytes 4..7 */
} co_bxcan_mailbox_t;

/** The bxCAN registers (offsets from RM0090 32.9.5). */
typedef struct co_bxcan_regs {
    volatile uint32_t mcr;  /**< 0x000 master control */
    volatile uint32_t msr;  /**< 0x004 master status */
    volatile uint32_t tsr;  /**< 0x008 transmit status */
    volatile uint32_t rf0r; /**< 0x00C receive FIFO 0 */
    volatile uint32_t rf1r; /**< 0x010 receive FIFO 1 */
    volatile uint32_t ier;  /**< 0x014 interrupt enable */
    volatile uint32_t esr;  /**< 0x018 error status */
    volatile uint32_t btr;  /**< 0x01C bit timing */
    uint32_t reserved0[88];
    co_bxcan_mailbox_t tx[3]; /**< 0x180 transmit mailboxes */
    co_bxcan_mailbox_t rx[2]; /**< 0x1B0 receive FIFO outputs */
    uint32_t reserved1[12];
    volatile uint32_t fmr;  /**< 0x200 filter master */
    volatile uint32_t fm1r; /**< 0x204 filter mode (1: list) */
    uint32_t reserved2;
    volatile uint32_t fs1r; /**< 0x20C filter scale (1: 32-bit) */
    uint32_t reserved3;
    volatile uint32_t ffa1r; /**< 0x214 filter FIFO assignment */
    uint32_t reserved4;
    volatile uint32_t fa1r; /**< 0x21C filter activation */
    uint32_t reserved5[8];
    struct {
        volatile uint32_t fr1, fr2;
    } bank[28]; /**< 0x240 filter banks */
} co_bxcan_regs_t;

typedef struct co_bxcan_config {
    co_bxcan_regs_t *regs;    /**< the controller (CAN1 0x40006400, CAN2 0x40006800 on F4) */
    co_bxcan_regs_t *filters; /**< the filter banks' owner: CAN1 (NULL: regs) */
    uint8_t bank_first;       /**< the first filter bank this controller uses */
    uint8_t bank_count;       /**< how many (14 on single-CAN parts) */
    uint32_t clock_hz;        /**< the CAN clock (APB1) */
    uint32_t bit_rate;        /**< bit/s, a CiA 301 rate */
    bool request_order;       /**< mailboxes in request order (TXFP = 1), see above */
    co_cm_port_t *port;       /**< where the interrupts go */
} co_bxcan_config_t;

typedef struct co_bxcan {
    co_bxcan_config_t cfg;
    co_cm_can_state_t state; /**< the error state last told to the port */
} co_bxcan_t;

/** The driver's side of canola/cm_can.h: co_cm_can_init(can, &co_bxcan_ops, drv). */
extern const co_cm_can_ops_t co_bxcan_ops;

/** Reset the controller into its configuration: bit timing, accept-all filter, interrupts,
 *  automatic bus-off recovery; then onto the bus. Returns CO_ERR_ARG for a missing register
 *  block, a filter range past 28 banks, or a bit rate no timing fits; CO_ERR_STATE when the
 *  controller does not enter or leave initialisation mode (no clock, RX pin not recessive).
 *  Waits a few bit times. */
co_err_t co_bxcan_init(co_bxcan_t *drv, const co_bxcan_config_t *cfg);

/** The interrupt handlers (see above). Each costs a few register accesses, plus the port's
 *  work per frame. */
void co_bxcan_isr_tx(co_bxcan_t *drv);
void co_bxcan_isr_rx0(co_bxcan_t *drv);
void co_bxcan_isr_sce(co_bxcan_t *drv);
void co_bxcan_isr(co_bxcan_t *drv);

#endif /* CANOLA_STM32_BXCAN_H */
