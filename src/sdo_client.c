/*
 * src/sdo_client.c -- SDO client (work in progress stub).
 */
#include "internal.h"

void co_sdo_client_reset_comm(co_node_t *node) { (void)node; }

void co_sdo_client_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame)
{
    (void)node;
    (void)channel;
    (void)frame;
}

uint64_t co_sdo_client_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}

co_err_t co_sdo_client_setup(co_node_t *node, uint8_t channel, uint8_t server_id)
{
    (void)node;
    (void)channel;
    (void)server_id;
    return CO_ERR_ARG;
}

co_err_t co_sdo_client_block_options(co_node_t *node, uint8_t channel, uint8_t blksize,
                                     bool crc, uint8_t pst)
{
    (void)node;
    (void)channel;
    (void)blksize;
    (void)crc;
    (void)pst;
    return CO_ERR_ARG;
}

co_err_t co_sdo_upload(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                       co_sdo_mode_t mode, uint8_t *buf, uint32_t cap, co_sdo_done_fn done,
                       void *ctx)
{
    (void)node;
    (void)channel;
    (void)index;
    (void)sub;
    (void)mode;
    (void)buf;
    (void)cap;
    (void)done;
    (void)ctx;
    return CO_ERR_STATE;
}

co_err_t co_sdo_download(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                         co_sdo_mode_t mode, const uint8_t *data, uint32_t len,
                         co_sdo_done_fn done, void *ctx)
{
    (void)node;
    (void)channel;
    (void)index;
    (void)sub;
    (void)mode;
    (void)data;
    (void)len;
    (void)done;
    (void)ctx;
    return CO_ERR_STATE;
}

co_err_t co_sdo_client_abort(co_node_t *node, uint8_t channel, co_abort_t code)
{
    (void)node;
    (void)channel;
    (void)code;
    return CO_ERR_STATE;
}

bool co_sdo_client_busy(const co_node_t *node, uint8_t channel)
{
    (void)node;
    (void)channel;
    return false;
}
