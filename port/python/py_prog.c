/* SPDX-License-Identifier: Apache-2.0 */
/* Program download, device side, on a canola.Device (see canola_py.h): the node's
 * hook_ctx is the dev (its written hook), so the entries 0x1F50/51/56/57 get hooks of their own
 * that find their co_program_t from the hooks pointer, and the program's callbacks go to
 * Python. */
#include "canola_py.h"

#include <stddef.h>

typedef struct canola_py_prog {
    co_od_hooks_t data, control, ident, status;
    co_program_t prog;
} canola_py_prog_t;

#define CANOLA_PY_PROG(entry, member)                                                              \
    ((canola_py_prog_t *)(void *)((char *)(entry)->hooks - offsetof(canola_py_prog_t, member)))

static co_abort_t canola_py_prog_data_w(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                        const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)ctx;
    return co_program_data_hooks.write(&CANOLA_PY_PROG(e, data)->prog, e, offset, data, n, total,
                                       last);
}

static co_abort_t canola_py_prog_control_w(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                           const uint8_t *data, uint32_t n, uint32_t total,
                                           bool last)
{
    (void)ctx;
    return co_program_control_hooks.write(&CANOLA_PY_PROG(e, control)->prog, e, offset, data, n,
                                          total, last);
}

static co_abort_t canola_py_prog_control_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                           uint8_t *buf, uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    return co_program_control_hooks.read(&CANOLA_PY_PROG(e, control)->prog, e, offset, buf, cap, n,
                                         total);
}

static co_abort_t canola_py_prog_ident_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                         uint8_t *buf, uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    return co_program_ident_hooks.read(&CANOLA_PY_PROG(e, ident)->prog, e, offset, buf, cap, n,
                                       total);
}

static co_abort_t canola_py_prog_status_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                          uint8_t *buf, uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    return co_program_status_hooks.read(&CANOLA_PY_PROG(e, status)->prog, e, offset, buf, cap, n,
                                        total);
}

canola_py_prog_t *canola_py_prog_new(co_od_entry_t *entries, uint32_t count, uint8_t program,
                                     bool running, uint32_t ident, void *handle)
{
    bool data = false, control = false;
    for (uint32_t i = 0; i < count; i++) {
        if (entries[i].sub == program) {
            data = data || entries[i].index == 0x1F50;
            control = control || entries[i].index == 0x1F51;
        }
    }
    canola_py_prog_t *p = data && control ? canola_py_alloc(sizeof *p) : NULL;
    if (!p) {
        return NULL;
    }
    co_program_app_t app = {
        .write = canola_py_prog_write, .control = canola_py_prog_control, .ctx = handle};
    co_program_init(&p->prog, &app, running, ident);
    p->data.write = canola_py_prog_data_w;
    p->control.read = canola_py_prog_control_r;
    p->control.write = canola_py_prog_control_w;
    p->ident.read = canola_py_prog_ident_r;
    p->status.read = canola_py_prog_status_r;
    for (uint32_t i = 0; i < count; i++) {
        co_od_entry_t *e = &entries[i];
        const co_od_hooks_t *h = NULL;
        if (e->sub != program) {
            continue;
        }
        switch (e->index) {
        case 0x1F50:
            h = &p->data;
            e->size = 0xFFFFFFFFu;
            break; /* streamed, any size */
        case 0x1F51:
            h = &p->control;
            break;
        case 0x1F56:
            h = &p->ident;
            break;
        case 0x1F57:
            h = &p->status;
            break;
        default:
            continue;
        }
        e->hooks = h;
        e->value = NULL;
        e->dflt = NULL;
    }
    return p;
}

void canola_py_prog_free(canola_py_prog_t *p) { canola_py_release(p); }
void canola_py_prog_set_ident(canola_py_prog_t *p, uint32_t ident)
{
    co_program_set_ident(&p->prog, ident);
}
uint32_t canola_py_prog_ident(const canola_py_prog_t *p) { return p->prog.ident; }
uint32_t canola_py_prog_status(const canola_py_prog_t *p) { return p->prog.status; }
uint8_t canola_py_prog_state(const canola_py_prog_t *p) { return p->prog.state; }
