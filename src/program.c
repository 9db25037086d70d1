/* SPDX-License-Identifier: Apache-2.0 */
/*
 * program.c -- program download, device side (CiA 302-3): the hooks of 0x1F50 program
 * data, 0x1F51 program control, 0x1F56 software identification and 0x1F57 flash status.
 */
#include "canola/program.h"

void co_program_init(co_program_t *p, const co_program_app_t *app, bool running, uint32_t ident)
{
    *p = (co_program_t){.ident = ident, .state = running ? CO_PROGRAM_START : CO_PROGRAM_STOP};
    if (app != NULL) {
        p->app = *app;
    }
}

void co_program_set_ident(co_program_t *p, uint32_t ident) { p->ident = ident; }

co_abort_t co_program_data_write(co_program_t *p, uint32_t offset, const uint8_t *data, uint32_t n,
                                 uint32_t total, bool last)
{
    if (p->state != CO_PROGRAM_STOP) {
        return CO_ABORT_DATA_STATE; /* never overwrite the program that runs */
    }
    if (p->app.write == NULL) {
        return CO_ABORT_UNSUPPORTED;
    }
    p->status = CO_FLASH_STATUS_BUSY;
    co_abort_t abort = p->app.write(p->app.ctx, offset, data, n, total, last);
    if (abort != CO_ABORT_NONE) {
        p->status = CO_FLASH_STATUS_WRITE_ERROR << 1;
    } else if (last) {
        p->status = 0;
    }
    return abort;
}

co_abort_t co_program_control_write(co_program_t *p, uint8_t command)
{
    if (command > CO_PROGRAM_CLEAR) {
        return CO_ABORT_VALUE;
    }
    if (command == CO_PROGRAM_CLEAR && p->state != CO_PROGRAM_STOP) {
        return CO_ABORT_DATA_STATE;
    }
    co_abort_t abort = p->app.control ? p->app.control(p->app.ctx, command) : CO_ABORT_NONE;
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    if (command == CO_PROGRAM_CLEAR) {
        p->status = CO_FLASH_STATUS_NO_PROGRAM << 1;
    }
    p->state = (command == CO_PROGRAM_START || command == CO_PROGRAM_RESET) ? CO_PROGRAM_START
                                                                            : CO_PROGRAM_STOP;
    return CO_ABORT_NONE;
}

/* ---- the hooks (hook_ctx is the co_program_t) */

static co_abort_t data_write(void *ctx, const co_od_entry_t *entry, uint32_t offset,
                             const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)entry;
    return co_program_data_write(ctx, offset, data, n, total, last);
}

static co_abort_t control_write(void *ctx, const co_od_entry_t *entry, uint32_t offset,
                                const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)entry;
    (void)total;
    if (offset != 0 || n != 1 || !last) {
        return CO_ABORT_TYPE_MISMATCH;
    }
    return co_program_control_write(ctx, data[0]);
}

/* Little-endian bytes of a value of `size` bytes, read from `offset`. */
static co_abort_t read_value(uint32_t v, uint32_t size, uint32_t offset, uint8_t *buf, uint32_t cap,
                             uint32_t *n, uint32_t *total)
{
    uint8_t wire[4];
    co_put_u32(wire, v);
    *total = size;
    *n = 0;
    for (uint32_t i = offset; i < size && *n < cap; i++) {
        buf[(*n)++] = wire[i];
    }
    return CO_ABORT_NONE;
}

static co_abort_t control_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                               uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)entry;
    const co_program_t *p = ctx;
    return read_value(p->state, 1, offset, buf, cap, n, total);
}

static co_abort_t ident_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                             uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)entry;
    const co_program_t *p = ctx;
    return read_value(p->ident, 4, offset, buf, cap, n, total);
}

static co_abort_t status_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                              uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)entry;
    const co_program_t *p = ctx;
    return read_value(p->status, 4, offset, buf, cap, n, total);
}

const co_od_hooks_t co_program_data_hooks = {.write = data_write};
const co_od_hooks_t co_program_control_hooks = {.read = control_read, .write = control_write};
const co_od_hooks_t co_program_ident_hooks = {.read = ident_read};
const co_od_hooks_t co_program_status_hooks = {.read = status_read};
