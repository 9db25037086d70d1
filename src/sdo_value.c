/* SPDX-License-Identifier: Apache-2.0 */
/*
 * sdo_value.c -- typed one-call reads and writes over an SDO client channel, for C
 * masters: the value travels in the channel's own 8-byte buffer, so the caller keeps
 * no buffer alive.
 */
#include "sdo_internal.h"

#if CO_SDO_CLIENTS_MAX > 0

static co_sdo_client_t *channel_of(co_node_t *node, uint8_t channel)
{
    return channel < co_sdo_clients_max() ? &node->sdo_clients[channel] : NULL;
}

static void read_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    co_node_t *node = ctx;
    co_sdo_client_t *c = &node->sdo_clients[channel];
    uint64_t value = 0;
    for (uint32_t i = 0; abort == CO_ABORT_NONE && i < len && i < 8; i++) {
        value |= (uint64_t)c->value[i] << (8u * i);
    }
    c->value_fn(c->value_ctx, channel, abort, value, abort == CO_ABORT_NONE ? len : 0);
}

co_err_t co_sdo_read_value(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                           co_sdo_value_fn done, void *ctx)
{
    co_sdo_client_t *c = node ? channel_of(node, channel) : NULL;
    if (c == NULL || done == NULL) {
        return CO_ERR_ARG;
    }
    if (co_sdo_client_busy(node, channel)) {
        return CO_ERR_BUSY;
    }
    c->value_fn = done;
    c->value_ctx = ctx;
    return co_sdo_upload(node, channel, index, sub, CO_SDO_AUTO, c->value, sizeof c->value,
                         read_done, node);
}

static void write_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    co_node_t *node = ctx;
    co_sdo_client_t *c = &node->sdo_clients[channel];
    c->value_done_fn(c->value_ctx, channel, abort, len);
}

co_err_t co_sdo_write_value(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                            uint64_t value, uint8_t size, co_sdo_done_fn done, void *ctx)
{
    co_sdo_client_t *c = node ? channel_of(node, channel) : NULL;
    if (c == NULL || done == NULL || size < 1 || size > 8) {
        return CO_ERR_ARG;
    }
    if (co_sdo_client_busy(node, channel)) {
        return CO_ERR_BUSY;
    }
    for (uint8_t i = 0; i < size; i++) {
        c->value[i] = (uint8_t)(value >> (8u * i));
    }
    c->value_done_fn = done;
    c->value_ctx = ctx;
    return co_sdo_download(node, channel, index, sub, CO_SDO_AUTO, c->value, size, write_done,
                           node);
}

#else /* no client channel */

co_err_t co_sdo_read_value(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                           co_sdo_value_fn done, void *ctx)
{
    (void)node;
    (void)channel;
    (void)index;
    (void)sub;
    (void)done;
    (void)ctx;
    return CO_ERR_ARG;
}

co_err_t co_sdo_write_value(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                            uint64_t value, uint8_t size, co_sdo_done_fn done, void *ctx)
{
    (void)node;
    (void)channel;
    (void)index;
    (void)sub;
    (void)value;
    (void)size;
    (void)done;
    (void)ctx;
    return CO_ERR_ARG;
}

#endif
