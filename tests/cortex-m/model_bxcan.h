/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/cortex-m/model_bxcan.h -- a model of the STM32 bxCAN for the host tests, written
 * from the reference manual (RM0090 chapter 32, RM0008 chapter 24): what the driver sees
 * of it through its registers.
 *
 *   modes      initialisation (MCR.INRQ -> MSR.INAK at once; no frame in or out), normal.
 *   transmit   three mailboxes: a request (TIxR.TXRQ) in an empty mailbox (TSR.TMEx) makes
 *              it pending; by identifier (TXFP 0; equal identifiers by mailbox number) or in
 *              request order (TXFP 1); done: RQCPx and TXOKx set, TMEx set again; RQCPx
 *              written 1 clears the four flags of its mailbox. A write to a pending mailbox
 *              is ignored (a violation). Automatic retransmission.
 *   receive    the filter banks as the driver set them (16/32-bit, mask/list, active,
 *              FIFO), in bank order; FIFO 0 holds three frames: a fourth sets FOVR0 and,
 *              with RFLM 0, replaces the newest (RFLM 1: is lost). RFOM0 releases the
 *              output; FULL0 and FOVR0 are cleared by writing 1. No frame is taken while
 *              the filters are in initialisation (FMR.FINIT). FIFO 1: not modelled (frames
 *              a filter sends there are counted as lost).
 *   filters    bank registers, FM1R, FS1R, FFA1R written only with FINIT set or (banks) the
 *              bank inactive; anything else is a violation.
 *   errors     ESR's EWGF, EPVF, BOFF, TEC and REC from the shared fault confinement; a state
 *              that begins sets MSR.ERRI (with ERRIE and the state's own enable); none is
 *              raised when it ends. Bus-off recovery starts at once with ABOM, else when
 *              the software enters and leaves initialisation.
 *   interrupts vectors TX (TMEIE and a RQCPx), RX0 (FMPIE0 and a frame, FFIE0 and FULL0,
 *              FOVIE0 and FOVR0), SCE (ERRIE and ERRI).
 */
#ifndef CANOLA_TEST_MODEL_BXCAN_H
#define CANOLA_TEST_MODEL_BXCAN_H

#include "can_model.h"
#include "canola/stm32_bxcan.h"

enum { BXCAN_VEC_TX, BXCAN_VEC_RX0, BXCAN_VEC_SCE };

typedef struct bxcan_model {
    can_model_t base;     /* first: a can_model_t * is a bxcan_model_t * */
    co_bxcan_regs_t regs; /* the address the driver uses; its contents are never read */
    uint32_t mcr, msr, tsr, ier, esr_lec, btr;
    co_bxcan_mailbox_t tx[3]; /* the mailboxes' registers as written */
    co_frame_t fifo[3];
    uint32_t fifo_count;
    bool full, overrun;
    uint32_t fmr, fm1r, fs1r, ffa1r, fa1r;
    uint32_t fr1[28], fr2[28];
    uint32_t clock_hz;  /* the CAN clock BTR divides (42 MHz unless the test says) */
    bool stuck_in_init; /* test: INAK never answers (no clock, RX pin dominant) */
} bxcan_model_t;

/** A bxCAN after reset (sleep mode, every filter bank inactive). */
void bxcan_model_init(bxcan_model_t *m);

#endif /* CANOLA_TEST_MODEL_BXCAN_H */
