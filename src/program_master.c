/* SPDX-License-Identifier: Apache-2.0 */
/*
 * program_master.c -- program download, master side (CiA 302-3): stop, clear, block
 * download of 0x1F50, start, check 0x1F56; progress from the SDO client's count.
 */
#include "manager_internal.h"
#include "sdo_internal.h"

#if CO_CONFIG_MANAGER

static void finish(co_flash_t *f, uint8_t stage, co_abort_t abort)
{
    f->result.stage = stage;
    f->result.abort = abort;
    if (f->node->flash == f) {
        f->node->flash = NULL;
    }
    if (f->req.done) {
        f->req.done(f->req.ctx, &f->result);
    }
}

static uint8_t program_sub(const co_flash_t *f) { return f->req.program ? f->req.program : 1; }

static void run(co_flash_t *f);

static void on_step(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    co_flash_t *f = ctx;
    if (abort != CO_ABORT_NONE) {
        finish(f, f->stage, abort);
        return;
    }
    if (f->stage == CO_FLASH_STAGE_DATA) {
        f->result.bytes = len;
        if (f->req.progress) {
            f->req.progress(f->req.ctx, len, f->req.len);
        }
    }
    f->stage++;
    if (f->stage == CO_FLASH_STAGE_CLEAR && !f->req.clear) {
        f->stage++;
    }
    run(f);
}

static void on_ident(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value, uint32_t len)
{
    (void)channel;
    (void)len;
    co_flash_t *f = ctx;
    if (abort != CO_ABORT_NONE) {
        finish(f, CO_FLASH_STAGE_VERIFY, abort);
        return;
    }
    f->result.ident = (uint32_t)value;
    f->result.ident_ok = !f->req.check_ident || f->result.ident == f->req.ident;
    finish(f, f->result.ident_ok ? CO_FLASH_STAGE_DONE : CO_FLASH_STAGE_VERIFY, CO_ABORT_NONE);
}

static void run(co_flash_t *f)
{
    co_node_t *node = f->node;
    uint8_t ch = f->req.channel;
    uint8_t sub = program_sub(f);
    co_err_t err;
    switch (f->stage) {
    case CO_FLASH_STAGE_STOP:
        err = co_sdo_write_value(node, ch, 0x1F51, sub, CO_PROGRAM_STOP, 1, on_step, f);
        break;
    case CO_FLASH_STAGE_CLEAR:
        err = co_sdo_write_value(node, ch, 0x1F51, sub, CO_PROGRAM_CLEAR, 1, on_step, f);
        break;
    case CO_FLASH_STAGE_DATA:
        err = co_sdo_download(node, ch, 0x1F50, sub, CO_SDO_BLOCK, f->req.data, f->req.len, on_step,
                              f);
        break;
    case CO_FLASH_STAGE_START:
        err = co_sdo_write_value(node, ch, 0x1F51, sub, CO_PROGRAM_START, 1, on_step, f);
        break;
    case CO_FLASH_STAGE_VERIFY:
        err = co_sdo_read_value(node, ch, 0x1F56, sub, on_ident, f);
        break;
    default:
        return;
    }
    if (err != CO_OK) {
        finish(f, f->stage, CO_ABORT_GENERAL);
    }
}

uint64_t co_flash_poll(co_node_t *node, uint64_t now_us)
{
    (void)now_us;
    co_flash_t *f = node->flash;
    if (f != NULL && f->stage == CO_FLASH_STAGE_DATA && f->req.progress) {
        uint32_t done = node->sdo_clients[f->req.channel].done;
        if (done != f->reported && done < f->req.len) {
            f->reported = done;
            f->req.progress(f->req.ctx, done, f->req.len);
        }
    }
    return CO_TIME_NEVER;
}

co_err_t co_flash_start(co_flash_t *flash, co_node_t *node, const co_flash_request_t *request)
{
    if (flash == NULL || node == NULL || request == NULL || request->data == NULL ||
        request->len == 0 || request->server < 1 || request->server > 127 ||
        request->channel >= co_sdo_clients_max()) {
        return CO_ERR_ARG;
    }
    if (node->flash != NULL || co_sdo_client_busy(node, request->channel)) {
        return CO_ERR_BUSY;
    }
    co_err_t err = co_sdo_client_setup(node, request->channel, request->server);
    if (err != CO_OK) {
        return err;
    }
    *flash = (co_flash_t){.req = *request, .node = node, .stage = CO_FLASH_STAGE_STOP};
    node->flash = flash;
    run(flash);
    return CO_OK;
}

#else

co_err_t co_flash_start(co_flash_t *flash, co_node_t *node, const co_flash_request_t *request)
{
    (void)flash;
    (void)node;
    (void)request;
    return CO_ERR_STATE;
}

#endif

const char *co_flash_stage_name(uint8_t stage)
{
    switch (stage) {
    case CO_FLASH_STAGE_STOP:
        return "stop";
    case CO_FLASH_STAGE_CLEAR:
        return "clear";
    case CO_FLASH_STAGE_DATA:
        return "data";
    case CO_FLASH_STAGE_START:
        return "start";
    case CO_FLASH_STAGE_VERIFY:
        return "verify";
    case CO_FLASH_STAGE_DONE:
        return "done";
    default:
        return "unknown";
    }
}
