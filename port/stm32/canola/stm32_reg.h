/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/stm32_reg.h -- how the STM32 drivers touch their peripheral: every register (and
 * FDCAN message RAM word) access is one of these two, a plain volatile access.
 *
 * CO_STM32_REG_EXTERN: they are functions defined elsewhere: the host tests, whose models
 * of the controllers give registers their hardware behaviour (write-1-to-clear flags,
 * requests that start a transmission, a FIFO's output that moves on release).
 */
#ifndef CANOLA_STM32_REG_H
#define CANOLA_STM32_REG_H

#include <stdint.h>

#if defined(CO_STM32_REG_EXTERN)
uint32_t co_stm32_read(const volatile uint32_t *reg);
void co_stm32_write(volatile uint32_t *reg, uint32_t value);
#else
static inline uint32_t co_stm32_read(const volatile uint32_t *reg) { return *reg; }
static inline void co_stm32_write(volatile uint32_t *reg, uint32_t value) { *reg = value; }
#endif

/* Bounded waits on the controller (entering and leaving its initialisation mode take a few
 * CAN bit times; a controller without clock or with its RX pin held dominant never
 * answers): this many reads, then the driver reports the failure. */
#define CO_STM32_WAIT_READS 1000000u

#endif /* CANOLA_STM32_REG_H */
