/* SPDX-License-Identifier: Apache-2.0 */
/* Streamed DOMAIN entries of a canola.Device (canola.domain.DomainStream; see
 * canola_py.h): the entry gets read/write hooks of its own that hand each piece to Python,
 * so it holds any size (no co_od_domain_t buffer, no CO_SDO_BUF_SIZE limit); the node's
 * "written" hook stays (on_write callbacks). */
#include "canola_py.h"

typedef struct canola_py_stream {
    co_od_hooks_t hooks; /* first: the entry's hooks pointer is the stream */
    void *handle;
} canola_py_stream_t;

static co_abort_t canola_py_stream_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                     uint8_t *buf, uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    return canola_py_stream_read(((const canola_py_stream_t *)(const void *)e->hooks)->handle,
                                 offset, buf, cap, n, total);
}

static co_abort_t canola_py_stream_w(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                     const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)ctx;
    return canola_py_stream_write(((const canola_py_stream_t *)(const void *)e->hooks)->handle,
                                  offset, data, n, total, last);
}

canola_py_stream_t *canola_py_stream_new(co_od_entry_t *entries, uint32_t count, uint16_t index,
                                         uint8_t sub, void *handle)
{
    for (uint32_t i = 0; i < count; i++) {
        co_od_entry_t *e = &entries[i];
        if (e->index != index || e->sub != sub) {
            continue;
        }
        if (e->type != CO_TYPE_DOMAIN) {
            return NULL;
        }
        canola_py_stream_t *s = canola_py_alloc(sizeof *s);
        if (!s) {
            return NULL;
        }
        s->hooks.read = canola_py_stream_r;
        s->hooks.write = canola_py_stream_w;
        s->hooks.written = e->hooks ? e->hooks->written : NULL;
        s->handle = handle;
        e->hooks = &s->hooks;
        e->value = NULL;
        e->dflt = NULL;
        e->size = 0xFFFFFFFFu; /* streamed, any size */
        return s;
    }
    return NULL;
}

void canola_py_stream_free(canola_py_stream_t *s) { canola_py_release(s); }
