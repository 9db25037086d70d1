/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/cortex-m/model_fdcan.h -- a model of the STM32 FDCAN (G0/G4/L5/U5: the fixed message
 * RAM) in classic CAN for the host tests, written from the reference manual (RM0440
 * chapter 44): what the driver sees of it through its registers and message RAM.
 *
 *   modes      initialisation (CCCR.INIT reads back set at once; CCE only while INIT; no
 *              frame in or out); configuration registers (NBTP, RXGFC, XIDAM, TXBC) written
 *              only with INIT and CCE, else ignored (a violation).
 *   transmit   three buffers: TXBAR adds the requests of the buffers whose bits it sets (a
 *              pending one: ignored); the element is read from message RAM then. Queue mode
 *              (TXBC.TFQM 1): by identifier (equal ones by buffer number), the put index
 *              the lowest free buffer; FIFO mode: in request order, the put index the next
 *              one round. Done: TXBRP bit cleared, TXBTO set, IR.TC (with the buffer's
 *              TXBTIE bit). TXFQS: free level, get and put index, full.
 *   receive    the filter list (RXGFC.LSS standard, LSE extended elements: range, dual,
 *              classic, disabled; store in FIFO 0 or 1, reject), then RXGFC.ANFS / ANFE for
 *              the rest, RRFS / RRFE for remote frames. FIFO 0 of three elements written to
 *              message RAM: new message IR.RF0N, full IR.RF0F; a fourth in blocking mode is
 *              lost (IR.RF0L, RXF0S.RF0L), in overwrite mode replaces the oldest. RXF0A
 *              acknowledges up to an index. FIFO 1: not modelled (counted as lost).
 *   errors     ECR, PSR.EW / EP / BO from the shared fault confinement; each change of EW, EP
 *              or BO sets its IR flag, in both directions. Bus-off sets CCCR.INIT; clearing
 *              it starts the recovery (129 x 11 bit times).
 *   interrupts IR & IE, by ILS to line 0 or 1, each line enabled by ILE (vectors 0 and 1).
 */
#ifndef CANOLA_TEST_MODEL_FDCAN_H
#define CANOLA_TEST_MODEL_FDCAN_H

#include "can_model.h"
#include "canola/stm32_fdcan.h"

enum { FDCAN_VEC_IT0, FDCAN_VEC_IT1 };

typedef struct fdcan_model {
    can_model_t base;     /* first: a can_model_t * is a fdcan_model_t * */
    co_fdcan_regs_t regs; /* the address the driver uses; its contents are never read */
    uint32_t ram[CO_FDCAN_RAM_WORDS];
    uint32_t cccr, nbtp, ir, ie, ils, ile, rxgfc, xidam, txbc, txbtie, txbto, txbcf;
    uint32_t rx_get, rx_fill;
    uint32_t tx_put;    /* FIFO mode: the next buffer round */
    uint32_t clock_hz;  /* the kernel clock NBTP divides (80 MHz unless the test says) */
    bool stuck_in_init; /* test: INIT never follows (no kernel clock) */
} fdcan_model_t;

/** An FDCAN after reset (initialisation mode, message RAM undefined: filled with junk). */
void fdcan_model_init(fdcan_model_t *m);

#endif /* CANOLA_TEST_MODEL_FDCAN_H */
