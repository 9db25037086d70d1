/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/cm_critical.h -- the critical section of port/cortex-m's CAN side: what the main
 * loop and the CAN interrupts both touch (the transmit queue and the mailboxes, the bus
 * events) is changed with interrupts masked.
 *
 * On a Cortex-M (any: M0 to M33) enter saves PRIMASK and masks every interrupt but the
 * NMI and HardFault; leave restores the saved PRIMASK, so sections nest and one entered in
 * an interrupt handler leaves interrupts as the handler found them. A section lasts a
 * mailbox write and a few queue moves: a few hundred cycles at most.
 *
 * CO_CM_BASEPRI (a priority value, e.g. 0x50; 0 or unset: PRIMASK): on ARMv7-M and ARMv8-M
 * Mainline (M3, M4, M7, M33) enter raises BASEPRI to it instead, so that interrupts of a
 * higher priority (a lower value: a motor's current loop, say) stay live; they must not call
 * the port. The CAN, UART and time base interrupts need a value at or above it. ARMv6-M
 * (M0, M0+) has no BASEPRI: PRIMASK there whatever it says.
 *
 * CO_CM_CRITICAL_EXTERN: enter and leave are functions defined elsewhere: the host tests
 * (which interleave a model's interrupts at every enter and leave), or a port that masks
 * through its RTOS.
 *
 * co_cm_barrier() keeps the compiler from moving memory accesses across it: the receive
 * ring's slot is written before its index moves (one core sees its own stores in order).
 */
#ifndef CANOLA_CM_CRITICAL_H
#define CANOLA_CM_CRITICAL_H

#include <stdatomic.h>
#include <stdint.h>

typedef uint32_t co_cm_irq_t; /* what leave restores */

#if defined(CO_CM_CRITICAL_EXTERN)
co_cm_irq_t co_cm_critical_enter(void);
void co_cm_critical_leave(co_cm_irq_t saved);
#elif defined(__ARM_ARCH) && defined(CO_CM_BASEPRI) && CO_CM_BASEPRI != 0 &&                       \
    (defined(__ARM_ARCH_7M__) || defined(__ARM_ARCH_7EM__) || defined(__ARM_ARCH_8M_MAIN__))
static inline co_cm_irq_t co_cm_critical_enter(void)
{
    co_cm_irq_t basepri;
    __asm__ volatile("mrs %0, basepri\n\tmsr basepri_max, %1"
                     : "=&r"(basepri)
                     : "r"((uint32_t)(CO_CM_BASEPRI))
                     : "memory");
    return basepri;
}

static inline void co_cm_critical_leave(co_cm_irq_t saved)
{
    __asm__ volatile("msr basepri, %0" : : "r"(saved) : "memory");
}
#elif defined(__ARM_ARCH)
static inline co_cm_irq_t co_cm_critical_enter(void)
{
    co_cm_irq_t primask;
    __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask) : : "memory");
    return primask;
}

static inline void co_cm_critical_leave(co_cm_irq_t saved)
{
    __asm__ volatile("msr primask, %0" : : "r"(saved) : "memory");
}
#else
#error "cm_critical.h: not a Cortex-M; define CO_CM_CRITICAL_EXTERN and provide enter/leave"
#endif

static inline void co_cm_barrier(void) { atomic_signal_fence(memory_order_seq_cst); }

#endif /* CANOLA_CM_CRITICAL_H */
