/* SPDX-License-Identifier: Apache-2.0 */
/* transport.c -- what every transport shares; see canola/transport.h. */
#define _POSIX_C_SOURCE 200809L

#include "canola/transport.h"

#include <stdarg.h>
#include <stdio.h>
#include <time.h>

uint64_t co_linux_now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

void co_transport_close(co_transport_t *t)
{
    if (t != NULL && t->ops != NULL && t->ops->close != NULL) {
        t->ops->close(t);
    }
}

void co_transport_fail(co_transport_t *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(t->error, sizeof t->error, fmt, ap);
    va_end(ap);
    for (char *c = t->error; *c; c++) {
        if (*c == '\n' || *c == '\r') {
            *c = ' '; /* one line, whatever the peer sent */
        }
    }
}
