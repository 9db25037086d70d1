/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/cm_systick.h -- a time base for port/cortex-m from SysTick, the 24-bit down-counter
 * of the Cortex-M core (every M3/M4/M7/M33; optional on M0/M0+, and absent on some, such as
 * the nRF51's: use a free-running timer there, co_cm_clock_extend).
 *
 * SysTick counts the core clock down from its reload value and interrupts as it wraps, every
 * `period_us`; the interrupt adds the period to a 64-bit count and the time reads between
 * interrupts come from the counter itself: microsecond resolution, no drift, no wrap in the
 * lifetime of a device. A wrap whose interrupt has not run yet (it is masked while the time
 * is read) is seen by its pending bit and counted. The interrupt also ends the main loop's
 * WFI: a deadline is met to within one period (default 1 ms: 1000 short interrupts a second).
 *
 * The board calls co_cm_systick_isr from its SysTick_Handler. SysTick gets the lowest
 * priority, which every critical section masks (PRIMASK, or BASEPRI: cm_critical.h).
 * Cost: a read is a few loads and one 32-bit division (hardware on M3 and up).
 */
#ifndef CANOLA_CM_SYSTICK_H
#define CANOLA_CM_SYSTICK_H

#include <stdint.h>

#include "canola/cm_port.h"

#ifdef __cplusplus
extern "C" {
#endif

/** SysTick's registers (ARMv6-M / ARMv7-M: SYST_CSR at 0xE000E010). */
typedef struct co_cm_systick_regs {
    volatile uint32_t csr; /**< control and status */
    volatile uint32_t rvr; /**< reload value */
    volatile uint32_t cvr; /**< current value */
    volatile uint32_t calib;
} co_cm_systick_regs_t;

typedef struct co_cm_systick {
    co_cm_systick_regs_t *regs;
    volatile uint32_t *icsr;   /**< SCB ICSR (0xE000ED04): PENDSTSET, bit 26 */
    volatile uint32_t *shpr3;  /**< SCB SHPR3 (0xE000ED20): SysTick's priority, bits 31..24 */
    volatile uint64_t base_us; /**< microseconds at the last wrap the interrupt counted */
    uint32_t ticks_per_us;
    uint32_t period_us;
} co_cm_systick_t;

/** Start SysTick on the core clock of `cpu_hz` (a whole number of MHz) with an interrupt
 *  every `period_us` (the reload must fit 24 bits: at 168 MHz up to 99 ms). Returns
 *  CO_ERR_ARG when the clock is not whole MHz or the period does not fit. */
co_err_t co_cm_systick_start(co_cm_systick_t *t, uint32_t cpu_hz, uint32_t period_us);

/** The same on registers elsewhere (the host tests' model). */
co_err_t co_cm_systick_start_at(co_cm_systick_t *t, co_cm_systick_regs_t *regs,
                                volatile uint32_t *icsr, volatile uint32_t *shpr3, uint32_t cpu_hz,
                                uint32_t period_us);

/** From SysTick_Handler: one period has passed. */
void co_cm_systick_isr(co_cm_systick_t *t);

/** The time now (co_cm_time_t.now_us with ctx = the co_cm_systick_t). */
uint64_t co_cm_systick_now_us(void *ctx);

/** The port's time base on `t` (no wake_at: the period's interrupt wakes the loop). */
co_cm_time_t co_cm_systick_time(co_cm_systick_t *t);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_CM_SYSTICK_H */
