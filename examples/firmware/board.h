/* SPDX-License-Identifier: Apache-2.0 */
/*
 * board.h -- what a board file gives the QEMU example firmware (main.c, slcan_uart.c): its
 * start, a time base, flash for the stored parameters, and the UART that carries the CAN
 * stand-in. board_mps2_an386.c (Arm MPS2+ AN386, Cortex-M4) and board_microbit.c (nRF51822,
 * Cortex-M0) implement it; a board with a CAN controller gives port/stm32's driver instead
 * of the UART.
 *
 * The UART's interrupt handler calls board_uart_irq (main.c). The board_uart_* functions
 * are called with the port's critical section held or from that interrupt.
 */
#ifndef CANOLA_EXAMPLE_BOARD_H
#define CANOLA_EXAMPLE_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/cm_flash_storage.h"
#include "canola/cm_port.h"

/** Clocks, pins, the UART and the time base, their interrupt priorities; interrupts of the
 *  UART still off (board_uart_start). */
void board_init(void);

/** The time base (SysTick, or a free-running timer with a compare interrupt). */
co_cm_time_t board_time(void);

/** Where the stored parameters live: the flash driver and the two slots. */
typedef struct board_flash {
    co_cm_flash_t flash;
    uintptr_t slot[2];
    uint32_t slot_size;
    const char *what; /**< the flash, as the firmware's serial number line tells it */
} board_flash_t;
const board_flash_t *board_flash(void);

/** The UART's receive interrupt on. */
void board_uart_start(void);
/** A received byte, if one waits. */
bool board_uart_rx(uint8_t *byte);
/** True when the UART takes a byte now. */
bool board_uart_tx_ready(void);
void board_uart_tx(uint8_t byte);
/** The UART's interrupt when it can take the next byte: on or off. */
void board_uart_tx_irq(bool on);
/** The UART's interrupt handler, to run as soon as interrupts are unmasked. */
void board_uart_pend(void);

/** From the UART's interrupt handler (main.c). */
void board_uart_irq(void);

#endif /* CANOLA_EXAMPLE_BOARD_H */
