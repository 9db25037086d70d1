/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/cortex-m/cm_host.h -- the processor as the host tests of port/cortex-m see it: the
 * critical section of canola/cm_critical.h (CO_CM_CRITICAL_EXTERN) as a flag, and the
 * interrupts of the controller models, taken as a Cortex-M takes them.
 *
 * An interrupt source (a controller model) says whether it has a handler to run; the host
 * runs it at the next point where the processor could take it: at once when the source
 * raises it outside a critical section and outside a handler, else when the critical
 * section ends (PRIMASK cleared) or the handler returns. Handlers do not nest (the CAN
 * interrupts of a port share one priority).
 *
 * Every enter and leave outside a handler is also a "point" (the main loop could be
 * interrupted just before it masks, or just after it unmasks); a test can act at the n-th
 * point (cm_host_at_point): the race tests interleave an interrupt at each in turn.
 */
#ifndef CANOLA_TEST_CM_HOST_H
#define CANOLA_TEST_CM_HOST_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/cm_port.h" /* the port object, co_cm_port_t, whose CAN side the tests use */

/** An interrupt source: run one pending handler and return true, or false when none is
 *  pending (enabled and flagged). */
typedef bool (*cm_host_irq_fn)(void *ctx);

/** Forget every source, hook and count; interrupts enabled, no handler running. */
void cm_host_reset(void);
/** Add an interrupt source (at most 4). */
void cm_host_add_source(cm_host_irq_fn fn, void *ctx);
/** A source's interrupt may be pending: take it now if the processor can. */
void cm_host_raise(void);
/** True inside a critical section. */
bool cm_host_masked(void);
/** True while a handler runs. */
bool cm_host_in_handler(void);
/** Hold interrupts off (a long critical section elsewhere, a higher-priority handler) or
 *  let them come again (the pending ones run at once). */
void cm_host_hold(bool hold);
/** Points passed since the reset. */
uint32_t cm_host_points(void);
/** Call `fn(ctx)` at each point (NULL: none). */
void cm_host_at_point(void (*fn)(void *ctx), void *ctx);
/** Handlers run since the reset, and the most a single raise ran back to back. A storm
 *  (a handler that leaves its interrupt pending) stops after 1000 and counts here. */
uint32_t cm_host_handlers_run(void);
uint32_t cm_host_storms(void);

#endif /* CANOLA_TEST_CM_HOST_H */
