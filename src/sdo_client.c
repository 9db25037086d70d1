/* SPDX-License-Identifier: Apache-2.0 */
/*
 * sdo_client.c -- the SDO client: expedited, segmented and block transfer in
 * both directions (see canola/sdo.h for the behaviour).
 *
 * One state machine per channel, driven by the server's responses (ingest) and
 * by the clock and the transmit queue (poll). Uploads land directly in the
 * caller's buffer, downloads are sent straight from the caller's data, so the
 * channel needs no buffer of its own. Block download sends a segment only while
 * the node's transmit queue is empty and resumes from poll: a sub-block of up to
 * 127 frames never floods the small queue.
 *
 * Choices where CiA 301 leaves room: a response naming another index/sub-index
 * than the request is aborted with 0x08000000; a server abort carrying code 0 is
 * reported as 0x08000000 (0 would read as success); an expedited upload response
 * without size (0x42) counts as 4 bytes; on failure `done` reports 0 bytes.
 */
#include <string.h>

#include "crc16.h"
#include "sdo_internal.h"
#include "sdo_protocol.h"

#if CO_SDO_CLIENTS_MAX > 0

enum client_state {
    IDLE = 0,
    UP_INIT,  /* initiate upload sent, expect its response */
    UP_SEG,   /* upload segment requested */
    DN_INIT,  /* initiate download sent, expect its response */
    DN_SEG,   /* download segment sent, expect its confirmation */
    BUP_INIT, /* block upload initiate sent (a normal response is a protocol switch) */
    BUP_DATA, /* receiving sub-blocks */
    BUP_END,  /* last segment received, expect the server's end */
    BDN_INIT, /* block download initiate sent, expect the block size */
    BDN_DATA, /* sending a sub-block (paced by the tx queue), then expect its ack */
    BDN_END,  /* end sent, expect the server's end */
};

static uint8_t channel_of(const co_node_t *node, const co_sdo_client_t *c)
{
    return (uint8_t)(c - node->sdo_clients);
}

/* Block options default to "ask for 127, offer CRC, never switch"; 0 marks unset. */
static void apply_defaults(co_sdo_client_t *c)
{
    if (c->want_blksize == 0) {
        c->want_blksize = CO_SDO_BLKSIZE_MAX;
        c->use_crc = true;
        c->pst = 0;
    }
}

/* ---- ending a transfer */

/* The channel is idle before `done` runs, so the callback may start the next transfer. */
static void finish(co_node_t *node, co_sdo_client_t *c, co_abort_t code, uint32_t len)
{
    co_sdo_done_fn fn = c->done_fn;
    void *ctx = c->done_ctx;
    c->state = IDLE;
    c->done_fn = NULL;
    c->done_ctx = NULL;
    c->up_buf = NULL;
    c->dn_data = NULL;
    c->deadline_us = CO_TIME_NEVER;
    if (fn) {
        fn(ctx, channel_of(node, c), code, code == CO_ABORT_NONE ? len : 0);
    }
}

/* ---- sending */

/* Restart the time-out: it runs from the last frame sent or received. */
static void touch(co_node_t *node, co_sdo_client_t *c)
{
    uint64_t timeout = c->timeout_ms ? co_ms_to_us(c->timeout_ms) : co_sdo_timeout_us(node);
    c->deadline_us = node->now_us + timeout;
    co_node_schedule(node, c->deadline_us);
}

static void transmit(co_node_t *node, const co_sdo_client_t *c, const uint8_t d[CO_SDO_FRAME_LEN])
{
    co_frame_t f;
    co_frame_address(&f, c->cob_tx, CO_SDO_FRAME_LEN);
    memcpy(f.data, d, CO_SDO_FRAME_LEN);
    (void)co_node_send_as(node, &f, CO_SVC_SDO); /* a lost frame ends in the time-out */
}

static void send8(co_node_t *node, co_sdo_client_t *c, const uint8_t d[CO_SDO_FRAME_LEN])
{
    transmit(node, c, d);
    touch(node, c);
}

/* Command byte, the transfer's index and sub-index, and a 32-bit value. */
static void cmd_frame(const co_sdo_client_t *c, uint8_t d[CO_SDO_FRAME_LEN], uint8_t cmd,
                      uint32_t value)
{
    d[0] = cmd;
    co_put_u16(&d[1], c->index);
    d[3] = c->sub;
    co_put_u32(&d[4], value);
}

/* Frames of block transfer without index: command and two parameter bytes. */
static void send_short(co_node_t *node, co_sdo_client_t *c, uint8_t cmd, uint8_t p1, uint8_t p2)
{
    uint8_t d[CO_SDO_FRAME_LEN] = {cmd, p1, p2};
    send8(node, c, d);
}

/* Abort towards the server, then report the code. */
static void fail(co_node_t *node, co_sdo_client_t *c, co_abort_t code)
{
    uint8_t d[CO_SDO_FRAME_LEN];
    cmd_frame(c, d, CO_SDO_CS_ABORT, code);
    transmit(node, c, d);
    finish(node, c, code, 0);
}

/* ---- upload */

/* Copy received bytes to the caller's buffer at `done`, never past `cap`. */
static void store(co_sdo_client_t *c, const uint8_t *src, uint32_t n)
{
    if (c->done < c->cap) {
        uint32_t room = c->cap - c->done;
        memcpy(c->up_buf + c->done, src, n < room ? n : room);
    }
}

static bool same_object(const co_sdo_client_t *c, const uint8_t *d)
{
    return co_get_u16(&d[1]) == c->index && d[3] == c->sub;
}

/* The request that opens a transfer is out: its answer (or abort) names the object. */
static bool awaits_initiate_answer(const co_sdo_client_t *c)
{
    return c->state == UP_INIT || c->state == BUP_INIT || c->state == DN_INIT ||
           c->state == BDN_INIT;
}

static co_abort_t on_block_upload_init(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    c->size_known = (d[0] & CO_SDO_BLK_SIZE) != 0;
    c->size = c->size_known ? co_get_u32(&d[4]) : 0;
    if (c->size_known && c->size > c->cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    c->crc_on = c->use_crc && (d[0] & CO_SDO_BLK_CRC);
    c->done = 0;
    c->seq = 0;
    c->blksize = c->want_blksize;
    c->state = BUP_DATA;
    send_short(node, c, CO_SDO_CCS_BLK_UP | CO_SDO_BLK_START, 0, 0);
    return CO_ABORT_NONE;
}

/* Initiate upload response; in a block upload either the block answer or a protocol switch. */
static co_abort_t on_upload_init(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    uint8_t b = d[0];
    bool block = c->state == BUP_INIT &&
                 (b & ~(CO_SDO_BLK_CRC | CO_SDO_BLK_SIZE)) == (CO_SDO_SCS_BLK_UP | CO_SDO_BLK_INI);
    if (!block && (b & CO_SDO_CS_MASK) != CO_SDO_SCS_UP_INI) {
        return CO_ABORT_COMMAND;
    }
    if (block) {
        return on_block_upload_init(node, c, d);
    }
    if (b & CO_SDO_INI_EXPEDITED) { /* n unused bytes when the size is indicated */
        uint32_t n =
            (b & CO_SDO_INI_SIZE) ? CO_SDO_EXPEDITED_MAX - CO_SDO_INI_N(b) : CO_SDO_EXPEDITED_MAX;
        if (n > c->cap) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
        c->done = 0;
        store(c, &d[4], n);
        finish(node, c, CO_ABORT_NONE, n);
        return CO_ABORT_NONE;
    }
    c->size_known = (b & CO_SDO_INI_SIZE) != 0;
    c->size = c->size_known ? co_get_u32(&d[4]) : 0;
    if (c->size_known && c->size > c->cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    c->done = 0;
    c->toggle = 0;
    c->state = UP_SEG;
    send_short(node, c, CO_SDO_CCS_UP_SEG, 0, 0);
    return CO_ABORT_NONE;
}

/* Upload segment `000t nnnc`: 7 - n bytes, c = last. A segment before the last carries
 * data: empty ones could keep the transfer open forever (each resets the time-out). */
static co_abort_t on_upload_seg(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    uint8_t b = d[0];
    if ((b & CO_SDO_CS_MASK) != CO_SDO_SCS_UP_SEG) {
        return CO_ABORT_COMMAND;
    }
    if ((b & CO_SDO_SEG_TOGGLE) != c->toggle) {
        return CO_ABORT_TOGGLE;
    }
    uint32_t n = CO_SDO_SEG_BYTES - CO_SDO_SEG_N(b);
    if (n == 0 && !(b & CO_SDO_SEG_LAST)) {
        return CO_ABORT_COMMAND;
    }
    uint64_t total = (uint64_t)c->done + n;
    if (c->size_known && total > c->size) {
        return CO_ABORT_LEN_HIGH;
    }
    if (total > c->cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    store(c, &d[1], n);
    c->done = (uint32_t)total;
    if (b & CO_SDO_SEG_LAST) {
        if (c->size_known && c->done < c->size) {
            return CO_ABORT_LEN_LOW;
        }
        finish(node, c, CO_ABORT_NONE, c->done);
        return CO_ABORT_NONE;
    }
    c->toggle ^= CO_SDO_SEG_TOGGLE;
    send_short(node, c, (uint8_t)(CO_SDO_CCS_UP_SEG | c->toggle), 0, 0);
    return CO_ABORT_NONE;
}

/* Block upload segment `c seqno`: only the next in-order one is kept; the end of a
 * sub-block (its last seqno, or c = 1) is acknowledged with the last in-order seqno, so
 * the server repeats what was lost. The final segment's padding is dropped at the end.
 * A segment restarts the time-out when it is kept or numbered beyond every one seen since
 * the last acknowledged progress (`seen`): a server that repeats segments, or sub-blocks
 * without the one the client lacks, makes no progress and cannot hold the channel. */
static co_abort_t on_block_upload_seg(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    uint8_t seqno = d[0] & CO_SDO_BLK_SEQ_MASK;
    bool last = (d[0] & CO_SDO_BLK_LAST) != 0;
    if (seqno == 0 || seqno > c->blksize) {
        return CO_ABORT_SEQUENCE; /* a segment of no sub-block the client asked for */
    }
    bool kept = seqno == c->seq + 1;
    if (kept) {
        uint64_t total = (uint64_t)c->done + CO_SDO_SEG_BYTES;
        if (!last && c->size_known && total > c->size) {
            return CO_ABORT_LEN_HIGH;
        }
        if (!last && total > c->cap) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
        store(c, &d[1], CO_SDO_SEG_BYTES);
        c->done = (uint32_t)co_min_u64(total, UINT32_MAX);
        c->seq = seqno;
        if (last) {
            c->state = BUP_END;
        }
    }
    if (kept || seqno > c->seen) {
        touch(node, c); /* progress, or a sub-block going on past a lost segment */
    }
    c->seen = seqno > c->seen ? seqno : c->seen;
    if (seqno == c->blksize || last) {
        uint8_t ack[CO_SDO_FRAME_LEN] = {CO_SDO_CCS_BLK_UP | CO_SDO_BLK_ACK, c->seq,
                                         c->want_blksize};
        c->seen = c->seq > 0 ? 0 : c->seen; /* a repetition must bring more to count */
        c->seq = 0; /* the next sub-block (or its repetition) counts from 1 again */
        c->blksize = c->want_blksize;
        transmit(node, c, ack); /* no progress of its own: the time-out keeps running */
    }
    return CO_ABORT_NONE;
}

/* Server's end `110n nn01` + CRC: n bytes of the last segment held no data. */
static co_abort_t on_block_upload_end(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    if ((d[0] & (CO_SDO_CS_MASK | CO_SDO_BLK_SUB_MASK)) != (CO_SDO_SCS_BLK_UP | CO_SDO_BLK_END)) {
        return CO_ABORT_COMMAND;
    }
    uint32_t n = CO_SDO_BLK_END_N(d[0]);
    if (n > c->done) {
        return CO_ABORT_COMMAND;
    }
    uint32_t len = c->done - n;
    if (c->size_known && len != c->size) {
        return len > c->size ? CO_ABORT_LEN_HIGH : CO_ABORT_LEN_LOW;
    }
    if (len > c->cap) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    if (c->crc_on && co_crc16(0, c->up_buf, len) != co_get_u16(&d[1])) {
        return CO_ABORT_CRC;
    }
    send_short(node, c, CO_SDO_CCS_BLK_UP | CO_SDO_BLK_END, 0, 0);
    finish(node, c, CO_ABORT_NONE, len);
    return CO_ABORT_NONE;
}

/* ---- download */

/* Next download segment `000t nnnc`; `done` counts the bytes sent. */
static void send_segment(co_node_t *node, co_sdo_client_t *c)
{
    uint32_t left = c->cap - c->done;
    uint32_t n = left < CO_SDO_SEG_BYTES ? left : CO_SDO_SEG_BYTES;
    uint8_t d[CO_SDO_FRAME_LEN] = {0};
    d[0] =
        (uint8_t)(CO_SDO_CCS_DN_SEG | c->toggle | ((CO_SDO_SEG_BYTES - n) << CO_SDO_SEG_N_SHIFT) |
                  (n == left ? CO_SDO_SEG_LAST : 0u));
    if (n) {
        memcpy(&d[1], c->dn_data + c->done, n);
    }
    c->done += n;
    send8(node, c, d);
}

/* Send the current sub-block while the tx queue is empty; `done` = bytes acknowledged,
 * `seq` = segments of this sub-block sent. Poll calls again when the queue drains. Each
 * segment restarts the time-out (the server answers after the last), except in a second
 * repetition without progress in between (`seen`). */
static void pump(co_node_t *node, co_sdo_client_t *c)
{
    while (c->state == BDN_DATA && co_txq_idle(node) && c->seq < c->blksize) {
        uint64_t off = (uint64_t)c->done + (uint64_t)c->seq * CO_SDO_SEG_BYTES;
        if (c->seq > 0 && off >= c->cap) {
            return; /* the last segment is out: wait for the acknowledgement */
        }
        uint32_t left = c->cap - (uint32_t)off;
        uint32_t n = left < CO_SDO_SEG_BYTES ? left : CO_SDO_SEG_BYTES;
        uint8_t d[CO_SDO_FRAME_LEN] = {0};
        c->seq++;
        d[0] = (uint8_t)((n == left ? CO_SDO_BLK_LAST : 0u) | c->seq);
        if (n) {
            memcpy(&d[1], c->dn_data + off, n);
        }
        transmit(node, c, d);
        if (c->seen <= 1) {
            touch(node, c);
        }
    }
}

static co_abort_t on_download_init(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    if (d[0] != CO_SDO_SCS_DN_INI) {
        return CO_ABORT_COMMAND;
    }
    if (c->mode == CO_SDO_EXPEDITED) {
        finish(node, c, CO_ABORT_NONE, c->cap);
        return CO_ABORT_NONE;
    }
    c->done = 0;
    c->toggle = 0;
    c->state = DN_SEG;
    send_segment(node, c);
    return CO_ABORT_NONE;
}

/* Download segment confirmation `001t 0000`. */
static co_abort_t on_download_seg(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    if ((d[0] & CO_SDO_CS_MASK) != CO_SDO_SCS_DN_SEG) {
        return CO_ABORT_COMMAND;
    }
    if ((d[0] & CO_SDO_SEG_TOGGLE) != c->toggle) {
        return CO_ABORT_TOGGLE;
    }
    if (c->done >= c->cap) {
        finish(node, c, CO_ABORT_NONE, c->cap);
        return CO_ABORT_NONE;
    }
    c->toggle ^= CO_SDO_SEG_TOGGLE;
    send_segment(node, c);
    return CO_ABORT_NONE;
}

static co_abort_t on_block_download_init(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    if ((d[0] & ~CO_SDO_BLK_CRC) != (CO_SDO_SCS_BLK_DN | CO_SDO_BLK_INI)) {
        return CO_ABORT_COMMAND;
    }
    if (d[4] == 0 || d[4] > CO_SDO_BLKSIZE_MAX) {
        return CO_ABORT_BLOCK_SIZE;
    }
    c->crc_on = c->use_crc && (d[0] & CO_SDO_BLK_CRC);
    c->blksize = d[4];
    c->done = 0;
    c->seq = 0;
    c->state = BDN_DATA;
    pump(node, c);
    return CO_ABORT_NONE;
}

/* End of a block download: n = bytes of the last segment without data (7 when empty). */
static void send_block_end(co_node_t *node, co_sdo_client_t *c)
{
    uint32_t n = c->cap == 0 ? CO_SDO_SEG_BYTES
                             : (CO_SDO_SEG_BYTES - c->cap % CO_SDO_SEG_BYTES) % CO_SDO_SEG_BYTES;
    uint16_t crc = c->crc_on ? co_crc16(0, c->dn_data, c->cap) : 0;
    c->state = BDN_END;
    uint8_t cmd = (uint8_t)(CO_SDO_CCS_BLK_DN | CO_SDO_BLK_END | (n << CO_SDO_BLK_END_N_SHIFT));
    send_short(node, c, cmd, (uint8_t)crc, (uint8_t)(crc >> 8));
}

/* Sub-block acknowledgement (ackseq, blksize): repeat from ackseq + 1, or end. */
static co_abort_t on_block_download_ack(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    if (d[0] != (CO_SDO_SCS_BLK_DN | CO_SDO_BLK_ACK)) {
        return CO_ABORT_COMMAND;
    }
    uint8_t ackseq = d[1];
    if (ackseq > c->seq) {
        return CO_ABORT_SEQUENCE;
    }
    if (d[2] == 0 || d[2] > CO_SDO_BLKSIZE_MAX) {
        return CO_ABORT_BLOCK_SIZE;
    }
    uint64_t acked = (uint64_t)c->done + (uint64_t)ackseq * CO_SDO_SEG_BYTES;
    bool all = ackseq > 0 && acked >= c->cap;
    c->done = (uint32_t)co_min_u64(acked, c->cap);
    c->seq = 0;
    c->blksize = d[2];
    c->seen = ackseq > 0 ? 0 : (uint8_t)(c->seen < 2 ? c->seen + 1 : 2);
    if (c->seen <= 1) {
        touch(node, c);
    }
    if (all) {
        send_block_end(node, c);
    } else {
        pump(node, c);
    }
    return CO_ABORT_NONE;
}

static co_abort_t on_block_download_end(co_node_t *node, co_sdo_client_t *c, const uint8_t *d)
{
    if (d[0] != (CO_SDO_SCS_BLK_DN | CO_SDO_BLK_END)) {
        return CO_ABORT_COMMAND;
    }
    finish(node, c, CO_ABORT_NONE, c->cap);
    return CO_ABORT_NONE;
}

/* ---- the node's side */

/* The channel listens to its server's responses (a channel to the node itself, or one
 * without valid COB-IDs, to nothing). */
static void route(co_node_t *node, uint8_t ch)
{
    co_route_set(node, CO_ROUTE_SDO_CLIENT, ch, co_cob_route(node->sdo_clients[ch].cob_rx));
}

/* Take the channel's parameters from 0x1280 + ch when the dictionary has them: sub1
 * COB-ID client -> server, sub2 server -> client, sub3 server node-ID. Returns false when
 * it has not. */
static bool load_from_od(co_node_t *node, uint8_t ch)
{
    co_sdo_client_t *c = &node->sdo_clients[ch];
    uint16_t index = (uint16_t)(0x1280u + ch);
    uint64_t tx = 0;
    uint64_t rx = 0;
    uint64_t id = 0;
    if (co_od_get_uint(&node->cfg.od, index, 1, &tx) != CO_OK ||
        co_od_get_uint(&node->cfg.od, index, 2, &rx) != CO_OK) {
        return false;
    }
    (void)co_od_get_uint(&node->cfg.od, index, 3, &id);
    c->cob_tx = (uint32_t)tx;
    c->cob_rx = (uint32_t)rx;
    c->server_id = (uint8_t)id;
    if (c->server_id == node->node_id) {
        c->cob_rx = CO_COB_INVALID; /* served locally */
    }
    return true;
}

void co_sdo_client_reset_comm(co_node_t *node)
{
    for (uint8_t i = 0; i < co_sdo_clients_max(); i++) {
        co_sdo_client_t *c = &node->sdo_clients[i];
        apply_defaults(c);
        if (c->state != IDLE) {
            finish(node, c, CO_ABORT_GENERAL, 0); /* ends locally: no frame */
        }
        if (!load_from_od(node, i) && c->server_id == 0) {
            c->cob_tx = CO_COB_INVALID;
            c->cob_rx = CO_COB_INVALID;
        }
        route(node, i);
    }
}

void co_sdo_client_stop(co_node_t *node)
{
    for (uint8_t i = 0; i < co_sdo_clients_max(); i++) {
        co_sdo_client_t *c = &node->sdo_clients[i];
        if (c->state != IDLE) {
            finish(node, c, CO_ABORT_DATA_STATE, 0); /* no frame: SDO may not be sent now */
        }
    }
}

void co_sdo_client_written(co_node_t *node, const co_od_entry_t *entry)
{
    uint32_t ch = entry->index - 0x1280u;
    if (ch < co_sdo_clients_max() && entry->sub >= 1 && entry->sub <= 3) {
        co_sdo_client_t *c = &node->sdo_clients[ch];
        if (c->state != IDLE) {
            fail(node, c, CO_ABORT_GENERAL); /* its server changed under it */
        }
        (void)load_from_od(node, (uint8_t)ch);
        route(node, (uint8_t)ch);
    }
}

void co_sdo_client_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame)
{
    if (channel >= co_sdo_clients_max()) {
        return;
    }
    co_sdo_client_t *c = &node->sdo_clients[channel];
    if (frame->len != CO_SDO_FRAME_LEN || (frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    if (c->state == IDLE) {
        return;
    }
    const uint8_t *d = frame->data;
    if (awaits_initiate_answer(c) && !same_object(c, d)) {
        return; /* a late answer to an earlier request, or to another client of the server */
    }
    if (d[0] == CO_SDO_CS_ABORT) { /* never a valid block segment: seqno 0 */
        co_abort_t code = co_get_u32(&d[4]);
        finish(node, c, code ? code : CO_ABORT_GENERAL, 0);
        return;
    }
    if (c->state != BUP_DATA && c->state != BDN_DATA) {
        touch(node, c); /* in block transfers only progress does (on_block_upload_seg, ..) */
    }
    co_abort_t err = CO_ABORT_COMMAND;
    switch (c->state) {
    case UP_INIT:
    case BUP_INIT:
        err = on_upload_init(node, c, d);
        break;
    case UP_SEG:
        err = on_upload_seg(node, c, d);
        break;
    case DN_INIT:
        err = on_download_init(node, c, d);
        break;
    case DN_SEG:
        err = on_download_seg(node, c, d);
        break;
    case BUP_DATA:
        err = on_block_upload_seg(node, c, d);
        break;
    case BUP_END:
        err = on_block_upload_end(node, c, d);
        break;
    case BDN_INIT:
        err = on_block_download_init(node, c, d);
        break;
    case BDN_DATA:
        err = on_block_download_ack(node, c, d);
        break;
    case BDN_END:
        err = on_block_download_end(node, c, d);
        break;
    default:
        break;
    }
    if (err != CO_ABORT_NONE) {
        fail(node, c, err);
    }
}

/* Resume paced block sending first (a stalled sender is not a silent server), then
 * time out transfers that saw no frame for the time-out. */
uint64_t co_sdo_client_poll(co_node_t *node, uint64_t now_us)
{
    uint64_t next = CO_TIME_NEVER;
    for (uint8_t i = 0; i < co_sdo_clients_max(); i++) {
        co_sdo_client_t *c = &node->sdo_clients[i];
        if (c->state == BDN_DATA) {
            pump(node, c);
        }
        if (c->state != IDLE && now_us >= c->deadline_us) {
            fail(node, c, CO_ABORT_TIMEOUT);
        }
        if (c->state != IDLE) {
            next = co_min_u64(next, c->deadline_us);
        }
    }
    return next;
}

/* ---- API */

co_err_t co_sdo_client_setup(co_node_t *node, uint8_t channel, uint8_t server_id)
{
    if (node == NULL || channel >= co_sdo_clients_max() || server_id < 1 || server_id > 127) {
        return CO_ERR_ARG;
    }
    co_sdo_client_t *c = &node->sdo_clients[channel];
    if (c->state != IDLE) {
        return CO_ERR_BUSY;
    }
    for (uint8_t i = 0; i < co_sdo_clients_max(); i++) {
        if (i != channel && node->sdo_clients[i].server_id == server_id &&
            server_id != node->node_id) {
            return CO_ERR_STATE; /* its responses would reach only one of the two */
        }
    }
    apply_defaults(c);
    c->server_id = server_id;
    c->cob_tx = 0x600u + server_id;
    /* A channel to the node itself uses no frames, so it listens to nothing. */
    c->cob_rx = server_id == node->node_id ? CO_COB_INVALID : 0x580u + server_id;
    uint16_t index = (uint16_t)(0x1280u + channel);
    (void)co_od_set_uint(&node->cfg.od, index, 1, 0x600u + server_id);
    (void)co_od_set_uint(&node->cfg.od, index, 2, 0x580u + server_id);
    (void)co_od_set_uint(&node->cfg.od, index, 3, server_id);
    route(node, channel);
    return CO_OK;
}

co_err_t co_sdo_client_block_options(co_node_t *node, uint8_t channel, uint8_t blksize, bool crc,
                                     uint8_t pst)
{
    if (node == NULL || channel >= co_sdo_clients_max() || blksize < 1 ||
        blksize > CO_SDO_BLKSIZE_MAX) {
        return CO_ERR_ARG;
    }
    co_sdo_client_t *c = &node->sdo_clients[channel];
    c->want_blksize = blksize;
    c->use_crc = crc;
    c->pst = pst;
    return CO_OK;
}

co_err_t co_sdo_client_set_timeout(co_node_t *node, uint8_t channel, uint16_t timeout_ms)
{
    if (node == NULL || channel >= co_sdo_clients_max()) {
        return CO_ERR_ARG;
    }
    node->sdo_clients[channel].timeout_ms = timeout_ms;
    return CO_OK;
}

/* Checks common to uploads and downloads. */
static co_err_t can_start(const co_node_t *node, uint8_t channel, co_sdo_mode_t mode)
{
    if (node == NULL || channel >= co_sdo_clients_max() || (unsigned)mode > CO_SDO_BLOCK ||
        (!CO_CONFIG_SDO_BLOCK && mode == CO_SDO_BLOCK)) {
        return CO_ERR_ARG;
    }
    const co_sdo_client_t *c = &node->sdo_clients[channel];
    if (c->state != IDLE) {
        return CO_ERR_BUSY;
    }
    if (c->server_id == 0 || !node->started) {
        return CO_ERR_STATE;
    }
    if (c->server_id != node->node_id &&
        ((c->cob_tx | c->cob_rx) & CO_COB_INVALID ||
         !co_nmt_allows((co_nmt_state_t)node->nmt_state, CO_SVC_SDO))) {
        return CO_ERR_STATE;
    }
    return CO_OK;
}

static void begin(co_sdo_client_t *c, uint16_t index, uint8_t sub, co_sdo_done_fn done, void *ctx)
{
    apply_defaults(c);
    c->done_fn = done;
    c->done_ctx = ctx;
    c->index = index;
    c->sub = sub;
    c->done = 0;
    c->size = 0;
    c->size_known = false;
    c->crc_on = false;
    c->toggle = 0;
    c->seq = 0;
}

/* ---- a channel to the node itself: the request is served on its own dictionary as its
 * SDO server would serve it, without frames (writes with their effects: co_node_write) */

/* The entry of a local request, found and accessible in that direction; else NULL and the
 * abort code. */
static const co_od_entry_t *local_entry(co_node_t *node, uint16_t index, uint8_t sub, bool write,
                                        co_abort_t *abort)
{
    const co_od_entry_t *e = co_od_find(&node->cfg.od, index, sub, abort);
    if (e != NULL) {
        *abort = co_od_access(&node->cfg.od, e, write);
    }
    return *abort == CO_ABORT_NONE ? e : NULL;
}

/* A value larger than `cap` is refused whole, as a remote server's would be. */
static co_abort_t local_upload(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                               uint32_t cap, uint32_t *len)
{
    co_abort_t abort = CO_ABORT_NONE;
    const co_od_entry_t *e = local_entry(node, index, sub, false, &abort);
    uint32_t total = 0;
    if (e != NULL) {
        abort = co_od_read(&node->cfg.od, e, 0, buf, cap, len, &total);
    }
    return abort == CO_ABORT_NONE && total != CO_OD_SIZE_UNKNOWN && total > *len
               ? CO_ABORT_OUT_OF_MEMORY
               : abort;
}

co_err_t co_sdo_upload(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                       co_sdo_mode_t mode, uint8_t *buf, uint32_t cap, co_sdo_done_fn done,
                       void *ctx)
{
    co_err_t err = can_start(node, channel, mode);
    if (err == CO_OK && buf == NULL && cap > 0) {
        err = CO_ERR_ARG;
    }
    if (err != CO_OK) {
        return err;
    }
    co_sdo_client_t *c = &node->sdo_clients[channel];
    if (c->server_id == node->node_id) {
        uint8_t none = 0;
        uint32_t len = 0;
        co_abort_t code = local_upload(node, index, sub, buf ? buf : &none, cap, &len);
        if (done) {
            done(ctx, channel, code, code == CO_ABORT_NONE ? len : 0);
        }
        return CO_OK;
    }
    begin(c, index, sub, done, ctx);
    c->up_buf = buf;
    c->cap = cap;
    c->mode = (uint8_t)mode;
    uint8_t d[CO_SDO_FRAME_LEN];
    uint8_t crc = c->use_crc ? CO_SDO_BLK_CRC : 0u;
    uint8_t block = (uint8_t)(CO_SDO_CCS_BLK_UP | CO_SDO_BLK_INI | crc);
    cmd_frame(c, d, mode == CO_SDO_BLOCK ? block : CO_SDO_CCS_UP_INI, 0);
    if (mode == CO_SDO_BLOCK) {
        c->blksize = c->want_blksize;
        d[4] = c->blksize;
        d[5] = c->pst;
    }
    c->state = mode == CO_SDO_BLOCK ? BUP_INIT : UP_INIT;
    send8(node, c, d);
    return CO_OK;
}

co_err_t co_sdo_download(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                         co_sdo_mode_t mode, const uint8_t *data, uint32_t len, co_sdo_done_fn done,
                         void *ctx)
{
    co_err_t err = can_start(node, channel, mode);
    if (err == CO_OK && ((data == NULL && len > 0) ||
                         (mode == CO_SDO_EXPEDITED && (len == 0 || len > CO_SDO_EXPEDITED_MAX)))) {
        err = CO_ERR_ARG;
    }
    if (err != CO_OK) {
        return err;
    }
    co_sdo_client_t *c = &node->sdo_clients[channel];
    if (c->server_id == node->node_id) {
        static const uint8_t none = 0;
        co_abort_t code = CO_ABORT_NONE;
        const co_od_entry_t *e = local_entry(node, index, sub, true, &code);
        code = e != NULL ? co_node_write(node, e, data ? data : &none, len) : code;
        if (done) {
            done(ctx, channel, code, code == CO_ABORT_NONE ? len : 0);
        }
        return CO_OK;
    }
    begin(c, index, sub, done, ctx);
    c->dn_data = data;
    c->cap = len;
    if (mode == CO_SDO_AUTO) {
        mode = (len >= 1 && len <= CO_SDO_EXPEDITED_MAX) ? CO_SDO_EXPEDITED : CO_SDO_SEGMENTED;
    }
    c->mode = (uint8_t)mode;
    uint8_t d[CO_SDO_FRAME_LEN];
    if (mode == CO_SDO_EXPEDITED) {
        uint32_t n = CO_SDO_EXPEDITED_MAX - len; /* bytes that hold no data */
        uint32_t cmd = CO_SDO_CCS_DN_INI | CO_SDO_INI_EXPEDITED | CO_SDO_INI_SIZE;
        cmd_frame(c, d, (uint8_t)(cmd | (n << CO_SDO_INI_N_SHIFT)), 0);
        memcpy(&d[4], data, len);
    } else {
        uint8_t crc = c->use_crc ? CO_SDO_BLK_CRC : 0u;
        uint8_t block = (uint8_t)(CO_SDO_CCS_BLK_DN | CO_SDO_BLK_INI | CO_SDO_BLK_SIZE | crc);
        cmd_frame(c, d, mode == CO_SDO_SEGMENTED ? CO_SDO_CCS_DN_INI | CO_SDO_INI_SIZE : block,
                  len);
    }
    c->state = mode == CO_SDO_BLOCK ? BDN_INIT : DN_INIT;
    send8(node, c, d);
    return CO_OK;
}

co_err_t co_sdo_client_abort(co_node_t *node, uint8_t channel, co_abort_t code)
{
    if (node == NULL || channel >= co_sdo_clients_max()) {
        return CO_ERR_ARG;
    }
    co_sdo_client_t *c = &node->sdo_clients[channel];
    if (c->state == IDLE) {
        return CO_ERR_STATE;
    }
    fail(node, c, code ? code : CO_ABORT_GENERAL); /* 0 would report success */
    return CO_OK;
}

bool co_sdo_client_busy(const co_node_t *node, uint8_t channel)
{
    return node != NULL && channel < co_sdo_clients_max() &&
           node->sdo_clients[channel].state != IDLE;
}

uint32_t co_sdo_client_progress(const co_node_t *node, uint8_t channel)
{
    return node != NULL && channel < co_sdo_clients_max() ? node->sdo_clients[channel].done : 0;
}

#else /* no client channel: every channel number is out of range */

co_err_t co_sdo_client_setup(co_node_t *node, uint8_t channel, uint8_t server_id)
{
    (void)node;
    (void)channel;
    (void)server_id;
    return CO_ERR_ARG;
}

co_err_t co_sdo_client_block_options(co_node_t *node, uint8_t channel, uint8_t blksize, bool crc,
                                     uint8_t pst)
{
    (void)node;
    (void)channel;
    (void)blksize;
    (void)crc;
    (void)pst;
    return CO_ERR_ARG;
}

co_err_t co_sdo_client_set_timeout(co_node_t *node, uint8_t channel, uint16_t timeout_ms)
{
    (void)node;
    (void)channel;
    (void)timeout_ms;
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
    return CO_ERR_ARG;
}

co_err_t co_sdo_download(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                         co_sdo_mode_t mode, const uint8_t *data, uint32_t len, co_sdo_done_fn done,
                         void *ctx)
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
    return CO_ERR_ARG;
}

co_err_t co_sdo_client_abort(co_node_t *node, uint8_t channel, co_abort_t code)
{
    (void)node;
    (void)channel;
    (void)code;
    return CO_ERR_ARG;
}

bool co_sdo_client_busy(const co_node_t *node, uint8_t channel)
{
    (void)node;
    (void)channel;
    return false;
}

uint32_t co_sdo_client_progress(const co_node_t *node, uint8_t channel)
{
    (void)node;
    (void)channel;
    return 0;
}

#endif
