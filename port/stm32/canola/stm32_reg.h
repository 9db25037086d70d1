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

#include "canola/types.h"

#if defined(CO_STM32_REG_EXTERN)
uint32_t co_stm32_read(const volatile uint32_t *reg);
void co_stm32_write(volatile uint32_t *reg, uint32_t value);
#else
static inline uint32_t co_stm32_read(const volatile uint32_t *reg) { return *reg; }
static inline void co_stm32_write(volatile uint32_t *reg, uint32_t value) { *reg = value; }
#endif

/* Both controllers keep a frame's data in two little-endian words: bytes 0..3, 4..7. */
static inline uint32_t co_stm32_data_word(const co_frame_t *frame, uint32_t first)
{
    const uint8_t *b = &frame->data[first];
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static inline void co_stm32_data_set(co_frame_t *frame, uint32_t lo, uint32_t hi)
{
    for (uint32_t i = 0; i < 4; i++) {
        frame->data[i] = (uint8_t)(lo >> (8 * i));
        frame->data[4 + i] = (uint8_t)(hi >> (8 * i));
    }
}

/* Bounded waits on the controller (entering and leaving its initialisation mode take a few
 * CAN bit times; a controller without clock or with its RX pin held dominant never
 * answers): this many reads, then the driver reports the failure. */
#define CO_STM32_WAIT_READS 1000000u

#endif /* CANOLA_STM32_REG_H */
