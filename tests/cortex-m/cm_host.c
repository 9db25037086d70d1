/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cortex-m/cm_host.c -- see cm_host.h. */
#include "cm_host.h"

#include <stddef.h>

#include "canola/cm_critical.h"

#define SOURCES_MAX 4
#define STORM_RUNS 1000u /* handlers back to back before a raise gives up */

typedef struct host {
    cm_host_irq_fn fn[SOURCES_MAX];
    void *ctx[SOURCES_MAX];
    uint32_t sources;
    bool masked;
    bool held;
    bool in_handler;
    uint32_t points;
    void (*at_point)(void *ctx);
    void *at_point_ctx;
    uint32_t handlers_run;
    uint32_t storms;
} host_t;

static host_t host;

void cm_host_reset(void) { host = (host_t){0}; }

void cm_host_add_source(cm_host_irq_fn fn, void *ctx)
{
    if (host.sources < SOURCES_MAX) {
        host.fn[host.sources] = fn;
        host.ctx[host.sources++] = ctx;
    }
}

/* Run pending handlers, one at a time, until none is pending. */
static void take_interrupts(void)
{
    uint32_t runs = 0;
    bool ran = true;
    while (ran && !host.masked && !host.held && !host.in_handler) {
        ran = false;
        for (uint32_t i = 0; i < host.sources && !ran; i++) {
            host.in_handler = true;
            ran = host.fn[i](host.ctx[i]);
            host.in_handler = false;
        }
        if (ran) {
            host.handlers_run++;
            if (++runs >= STORM_RUNS) {
                host.storms++;
                return;
            }
        }
    }
}

void cm_host_raise(void) { take_interrupts(); }

void cm_host_hold(bool hold)
{
    host.held = hold;
    take_interrupts();
}

bool cm_host_masked(void) { return host.masked; }
bool cm_host_in_handler(void) { return host.in_handler; }
uint32_t cm_host_points(void) { return host.points; }
uint32_t cm_host_handlers_run(void) { return host.handlers_run; }
uint32_t cm_host_storms(void) { return host.storms; }

void cm_host_at_point(void (*fn)(void *ctx), void *ctx)
{
    host.at_point = fn;
    host.at_point_ctx = ctx;
}

static void point(void)
{
    if (host.in_handler || host.masked) {
        return;
    }
    host.points++;
    if (host.at_point) {
        host.at_point(host.at_point_ctx);
    }
    take_interrupts();
}

co_cm_irq_t co_cm_critical_enter(void)
{
    point(); /* the last instant the main loop can be interrupted before it masks */
    co_cm_irq_t was = host.masked;
    host.masked = true;
    return was;
}

void co_cm_critical_leave(co_cm_irq_t saved)
{
    host.masked = saved != 0;
    point(); /* what became pending meanwhile is taken as the mask clears */
}
