/* SPDX-License-Identifier: Apache-2.0 */
/* Every allocation of the binding layer (see canola_py.h), counted. */
#include "canola_py.h"

#include <stdatomic.h>
#include <stdlib.h>

/* Live allocations: buses, links, devs, programs and streams are made and freed by different
 * threads (a SimBus's owner, a python-can bus thread, the garbage collector). */
static atomic_long live_allocs;

void *canola_py_alloc(size_t size)
{
    void *p = calloc(1, size);
    if (p) {
        atomic_fetch_add(&live_allocs, 1);
    }
    return p;
}

void canola_py_release(void *p)
{
    if (p) {
        atomic_fetch_sub(&live_allocs, 1);
        free(p);
    }
}

long canola_py_live_allocs(void) { return atomic_load(&live_allocs); }
