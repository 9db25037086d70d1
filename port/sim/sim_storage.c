/* SPDX-License-Identifier: Apache-2.0 */
/* sim_storage.c -- parameter storage in RAM; see canola/sim_storage.h. */
#include "canola/sim_storage.h"

#include <string.h>

static co_sim_image_t *image_of(co_sim_storage_t *st, co_param_group_t group)
{
    return group == CO_PARAMS_COMMUNICATION ? &st->images[0] : &st->images[1];
}

static co_err_t begin(void *ctx, co_param_group_t group)
{
    co_sim_storage_t *st = ctx;
    st->staging.len = 0;
    st->staging.valid = true;
    st->staging_group = group;
    return CO_OK;
}

static co_err_t write(void *ctx, const uint8_t *data, uint32_t len)
{
    co_sim_storage_t *st = ctx;
    if (st->staging.len + len > sizeof st->staging.data) {
        st->staging.valid = false; /* too big: the commit will fail */
        return CO_ERR_FULL;
    }
    memcpy(&st->staging.data[st->staging.len], data, len);
    st->staging.len += len;
    return CO_OK;
}

static co_err_t stage(void *ctx)
{
    co_sim_storage_t *st = ctx;
    if (!st->staging.valid) {
        return CO_ERR_FULL;
    }
    st->staged = st->staging;
    st->staged_group = st->staging_group;
    st->staging.valid = false;
    return CO_OK;
}

static void discard(void *ctx)
{
    co_sim_storage_t *st = ctx;
    st->staging.valid = false;
    st->staged.valid = false;
}

/* The staged image and the one written last replace the stored ones together. */
static co_err_t commit(void *ctx)
{
    co_sim_storage_t *st = ctx;
    if (st->fail_next_commit || !st->staging.valid) {
        st->fail_next_commit = false;
        discard(st);
        return CO_ERR_FULL;
    }
    if (st->staged.valid) {
        *image_of(st, st->staged_group) = st->staged;
    }
    *image_of(st, st->staging_group) = st->staging;
    discard(st);
    st->commits++;
    return CO_OK;
}

static co_err_t read(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf, uint32_t cap,
                     uint32_t *n)
{
    const co_sim_image_t *img = image_of(ctx, group);
    *n = 0;
    if (!img->valid) {
        return CO_ERR_NOT_FOUND;
    }
    if (offset < img->len) {
        *n = img->len - offset < cap ? img->len - offset : cap;
        memcpy(buf, &img->data[offset], *n);
    }
    return CO_OK;
}

static co_err_t erase(void *ctx, co_param_group_t group)
{
    image_of(ctx, group)->valid = false;
    return CO_OK;
}

void co_sim_storage_init(co_sim_storage_t *storage)
{
    memset(storage, 0, sizeof *storage);
    storage->api = (co_storage_t){.begin = begin,
                                  .write = write,
                                  .commit = commit,
                                  .read = read,
                                  .erase = erase,
                                  .ctx = storage,
                                  .discard = discard,
                                  .stage = stage};
}
