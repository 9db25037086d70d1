/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/linux/loop_wait.h -- waiting on the wall clock for something the event loop does,
 * as a busy machine allows: the loop runs in short slices until the awaited state holds,
 * within a bound of seconds. A test checks what happened and in which order, never how
 * soon (latency is bench/'s business).
 */
#ifndef CANOLA_TEST_LOOP_WAIT_H
#define CANOLA_TEST_LOOP_WAIT_H

#include <stdbool.h>
#include <stdio.h>

#include "canola/linux_loop.h"

/** How long a test waits for an event before it counts as missing (ms). */
#define LOOP_WAIT_BOUND_MS 20000u

/** Run `loop` in 10 ms slices until `done(ctx)` holds or LOOP_WAIT_BOUND_MS passed, or
 *  the loop stopped for another reason than a slice's end. Whether `done(ctx)` holds;
 *  the number of slices run (each costs one wake-up of its own) into `*slices` if set. */
static inline bool loop_wait(co_loop_t *loop, bool (*done)(void *ctx), void *ctx, unsigned *slices)
{
    uint64_t end = co_linux_now_us() + LOOP_WAIT_BOUND_MS * 1000u;
    unsigned n = 0;
    co_loop_reason_t why = CO_LOOP_DEADLINE;
    while (!done(ctx) && why == CO_LOOP_DEADLINE && co_linux_now_us() < end) {
        why = co_loop_run_until(loop, co_linux_now_us() + 10000u);
        n++;
    }
    if (slices != NULL) {
        *slices = n;
    }
    if (!done(ctx)) {
        printf("  waited in vain (%s after %u slices)\n", co_loop_reason_name(why), n);
    }
    return done(ctx);
}

#endif /* CANOLA_TEST_LOOP_WAIT_H */
