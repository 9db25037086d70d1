/* SPDX-License-Identifier: Apache-2.0 */
/* cm_port.c -- the main loop of port/cortex-m; see canola/cm_port.h. */
#include "canola/cm_port.h"

#include "canola/cm_critical.h"

#if defined(CO_CM_CRITICAL_EXTERN)
/* The host tests' processor (tests/cortex-m/cm_host.c): the sleep's masking is the critical
 * section, and a WFI ends at the next interrupt the test raises. */
void co_cm_wait_for_interrupt(void);
static co_cm_irq_t mask_all(void) { return co_cm_critical_enter(); }
static void unmask_all(co_cm_irq_t saved) { co_cm_critical_leave(saved); }
#else
/* PRIMASK whatever the critical section uses: a WFI with PRIMASK set still ends on an
 * interrupt that becomes pending, which then runs as soon as PRIMASK is cleared; BASEPRI
 * would keep a masked interrupt from ending it. */
static co_cm_irq_t mask_all(void)
{
    co_cm_irq_t primask;
    __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask) : : "memory");
    return primask;
}

static void unmask_all(co_cm_irq_t saved)
{
    __asm__ volatile("msr primask, %0" : : "r"(saved) : "memory");
}

static void co_cm_wait_for_interrupt(void) { __asm__ volatile("dsb\n\twfi" : : : "memory"); }
#endif

void co_cm_port_init(co_cm_port_t *port, const co_cm_can_ops_t *ops, void *hw, co_cm_time_t time)
{
    co_cm_can_init(&port->can, ops, hw);
    port->time = time;
    port->node = NULL;
}

void co_cm_port_bind(co_cm_port_t *port, co_node_t *node)
{
    port->node = node;
    co_cm_can_bind(&port->can, node);
}

uint64_t co_cm_port_step(co_cm_port_t *port)
{
    uint64_t now = port->time.now_us(port->time.ctx);
    (void)co_cm_can_process(&port->can, now);
    return co_node_poll(port->node, now);
}

bool co_cm_port_sleep(co_cm_port_t *port, uint64_t deadline_us)
{
    bool slept = false;
    co_cm_irq_t saved = mask_all();
    if (co_cm_can_idle(&port->can) && port->time.now_us(port->time.ctx) < deadline_us) {
        if (port->time.wake_at != NULL) {
            port->time.wake_at(port->time.ctx, deadline_us);
        }
        co_cm_wait_for_interrupt();
        slept = true;
    }
    unmask_all(saved);
    return slept;
}

_Noreturn void co_cm_port_run(co_cm_port_t *port)
{
    for (;;) {
        co_cm_port_sleep(port, co_cm_port_step(port));
    }
}
