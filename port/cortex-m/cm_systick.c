/* SPDX-License-Identifier: Apache-2.0 */
/* cm_systick.c -- SysTick as port/cortex-m's time base; see canola/cm_systick.h. */
#include "canola/cm_systick.h"

#include "canola/cm_critical.h"

#define CSR_ENABLE 1u
#define CSR_TICKINT 2u
#define CSR_CLKSOURCE 4u /* the core clock */
#define ICSR_PENDSTSET (1u << 26)
#define RELOAD_MAX 0xFFFFFFu

co_err_t co_cm_systick_start_at(co_cm_systick_t *t, co_cm_systick_regs_t *regs,
                                volatile uint32_t *icsr, volatile uint32_t *shpr3, uint32_t cpu_hz,
                                uint32_t period_us)
{
    uint32_t per_us = cpu_hz / 1000000u;
    if (per_us == 0 || per_us * 1000000u != cpu_hz || period_us == 0 ||
        period_us > (RELOAD_MAX + 1u) / per_us) {
        return CO_ERR_ARG;
    }
    t->regs = regs;
    t->icsr = icsr;
    t->shpr3 = shpr3;
    t->base_us = 0;
    t->ticks_per_us = per_us;
    t->period_us = period_us;
    *shpr3 |= 0xFFu << 24; /* the lowest priority: every critical section masks it */
    regs->csr = 0;
    regs->rvr = per_us * period_us - 1u;
    regs->cvr = 0; /* any write clears it: the count starts from the reload */
    regs->csr = CSR_ENABLE | CSR_TICKINT | CSR_CLKSOURCE;
    return CO_OK;
}

co_err_t co_cm_systick_start(co_cm_systick_t *t, uint32_t cpu_hz, uint32_t period_us)
{
    return co_cm_systick_start_at(t, (co_cm_systick_regs_t *)0xE000E010u,
                                  (volatile uint32_t *)0xE000ED04u,
                                  (volatile uint32_t *)0xE000ED20u, cpu_hz, period_us);
}

void co_cm_systick_isr(co_cm_systick_t *t) { t->base_us += t->period_us; }

uint64_t co_cm_systick_now_us(void *ctx)
{
    co_cm_systick_t *t = ctx;
    co_cm_irq_t irq = co_cm_critical_enter();
    uint64_t base = t->base_us;
    uint32_t count = t->regs->cvr;
    if (*t->icsr & ICSR_PENDSTSET) {
        /* wrapped, the interrupt not run yet: the count read may be from before the wrap
         * or after it; one read now is after it */
        count = t->regs->cvr;
        base += t->period_us;
    }
    co_cm_critical_leave(irq);
    return base + (t->regs->rvr - count) / t->ticks_per_us;
}

co_cm_time_t co_cm_systick_time(co_cm_systick_t *t)
{
    return (co_cm_time_t){.now_us = co_cm_systick_now_us, .wake_at = NULL, .ctx = t};
}
