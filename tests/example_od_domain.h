/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/example_od_domain.h -- the example dictionary with a streamed DOMAIN at 0x3000
 * (pattern_domain.h), for the tests that move large SDO transfers over the simulated bus.
 */
#ifndef CANOLA_TEST_EXAMPLE_OD_DOMAIN_H
#define CANOLA_TEST_EXAMPLE_OD_DOMAIN_H

#include "example_od.h"
#include "pattern_domain.h"

/** example_od_init(od, hb_ms)'s entries copied into `entries`, with
 *  pattern_domain_entry(0x3000) inserted in index order (after 0x2006, before 0x6200); a
 *  dictionary over `entries`. Point its hook_ctx at a pattern_domain_t. */
static inline co_od_t example_od_with_domain(example_od_t *od, uint16_t hb_ms,
                                             co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 1])
{
    co_od_t base = example_od_init(od, hb_ms);
    uint32_t n = 0;
    for (uint32_t i = 0; i < base.count; i++) {
        if (base.entries[i].index > 0x3000 && n == i) {
            entries[n++] = pattern_domain_entry(0x3000);
        }
        entries[n++] = base.entries[i];
    }
    return (co_od_t){.entries = entries, .count = n};
}

#endif /* CANOLA_TEST_EXAMPLE_OD_DOMAIN_H */
