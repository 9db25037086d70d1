/* SPDX-License-Identifier: Apache-2.0 */
/* pattern_domain.c -- see pattern_domain.h. */
#include "pattern_domain.h"

uint8_t pattern_byte(uint32_t seed, uint32_t i)
{
    uint32_t x = (i + seed) * 2654435761u; /* Knuth's multiplicative hash */
    return (uint8_t)(x >> 24);
}

void pattern_fill(uint8_t *buf, uint32_t seed, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        buf[i] = pattern_byte(seed, i);
    }
}

bool pattern_matches(const uint8_t *buf, uint32_t seed, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        if (buf[i] != pattern_byte(seed, i)) {
            return false;
        }
    }
    return true;
}

static co_abort_t pattern_read(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                               uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)e;
    const pattern_domain_t *d = ctx;
    uint32_t left = offset < d->length ? d->length - offset : 0;
    *n = cap < left ? cap : left;
    for (uint32_t i = 0; i < *n; i++) {
        buf[i] = pattern_byte(d->up_seed, offset + i);
    }
    *total = d->length;
    return CO_ABORT_NONE;
}

static co_abort_t pattern_write(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)e;
    (void)total;
    pattern_domain_t *d = ctx;
    if (offset == 0) {
        d->received = 0;
        d->pieces = 0;
        d->mismatch = false;
        d->complete = false;
    }
    d->mismatch |= offset != d->received;
    for (uint32_t i = 0; i < n; i++) {
        d->mismatch |= data[i] != pattern_byte(d->down_seed, offset + i);
    }
    d->received = offset + n;
    d->pieces++;
    d->complete = last;
    return CO_ABORT_NONE;
}

const co_od_hooks_t pattern_domain_hooks = {.read = pattern_read, .write = pattern_write};

co_od_entry_t pattern_domain_entry(uint16_t index)
{
    return (co_od_entry_t){.index = index,
                           .type = CO_TYPE_DOMAIN,
                           .attr = CO_OD_RW,
                           .size = 0xFFFFFFFFu,
                           .hooks = &pattern_domain_hooks};
}

bool pattern_domain_received(const pattern_domain_t *d, uint32_t len)
{
    return d->received == len && !d->mismatch && d->complete;
}
