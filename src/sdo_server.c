/* SPDX-License-Identifier: Apache-2.0 */
/*
 * sdo_server.c -- the SDO server: expedited, segmented and block transfer in
 * both directions (see canola/sdo.h for the behaviour).
 *
 * One state machine per channel, in the SDO client's shape: co_sdo_server_ingest switches
 * once on the state, each step is a handler that answers and returns CO_ABORT_NONE or the
 * abort code, and one failure path (fail) sends the abort and ends the transfer. A request
 * that fits no step of the state (an initiate, the client's abort, anything else) goes to
 * on_request.
 *
 * Downloads collect into the channel buffer and are stored whole at the end, unless the
 * entry streams through a write hook or is a DOMAIN/string in RAM larger than the buffer
 * (received into its storage); uploads read the dictionary piece by piece at an offset, so
 * a retransmission in block upload simply reads the same offset again.
 *
 * The time-out counts from the transfer's last progress (last_us): a frame that moves it
 * on (data received or requested, a sub-block acknowledged) restarts it, one that moves
 * nothing does not: a client that sends empty download segments, or repeats block
 * segments, holds the channel for one time-out, not for ever, and then hears 0x05040000
 * (SDO protocol timed out), the code of a transfer that made no progress for the time-out.
 * A frame only stores the time; poll works out the deadline.
 */
#include <string.h>

#include "crc16.h"
#include "sdo_internal.h"
#include "sdo_protocol.h"

enum server_state {
    IDLE = 0,
    DOWN_SEGMENTED, /* expect a download segment */
    UP_SEGMENTED,   /* expect an upload segment request */
    BLOCK_DOWN,     /* receiving a sub-block */
    BLOCK_DOWN_END, /* expect the end of a block download */
    BLOCK_UP_START, /* initiate answered, expect the client's start */
    BLOCK_UP,       /* sending a sub-block, then expect its acknowledgement */
    BLOCK_UP_END,   /* end sent, expect the client's end response */
};

/* A sub-block fits the channel buffer. */
#define BLOCK_SIZE_MAX                                                                             \
    (CO_SDO_BUF_SIZE / CO_SDO_SEG_BYTES < CO_SDO_BLKSIZE_MAX ? CO_SDO_BUF_SIZE / CO_SDO_SEG_BYTES  \
                                                             : CO_SDO_BLKSIZE_MAX)

/* ---- channels and their COB-IDs */

static uint32_t cob_from_od(const co_node_t *node, uint8_t ch, uint8_t sub, uint32_t fallback)
{
    return co_od_u32(node, (uint16_t)(0x1200 + ch), sub, fallback);
}

/* The default server's COB-IDs are fixed by CiA 301 (0x600/0x580 + node-ID; 0x1200 sub1
 * and sub2 read-only): a dictionary that gives others is overruled, made to read the
 * fixed ones, and reported (once its node has an ID; not a reason to be unreachable). */
static void fix_default_channel(co_node_t *node, co_sdo_server_t *s, uint32_t rx, uint32_t tx)
{
    if (rx != CO_COB_INVALID) {
        (void)co_od_set_uint(&node->cfg.od, 0x1200, 1, rx);
        (void)co_od_set_uint(&node->cfg.od, 0x1200, 2, tx);
        if (node->cfg.on_error) {
            node->cfg.on_error(node->cfg.user, CO_NODE_ERR_SDO_COB_FIXED);
        }
    }
    s->cob_rx = rx;
    s->cob_tx = tx;
}

static void load_channel(co_node_t *node, uint8_t ch)
{
    co_sdo_server_t *s = &node->sdo_servers[ch];
    bool configured = node->node_id >= 1 && node->node_id <= 127;
    uint32_t rx = (ch == 0 && configured) ? 0x600u + node->node_id : CO_COB_INVALID;
    uint32_t tx = (ch == 0 && configured) ? 0x580u + node->node_id : CO_COB_INVALID;
    s->cob_rx = cob_from_od(node, ch, 1, rx);
    s->cob_tx = cob_from_od(node, ch, 2, tx);
    if (ch == 0 && (s->cob_rx != rx || s->cob_tx != tx)) {
        fix_default_channel(node, s, rx, tx);
    }
    if (s->cob_tx & CO_COB_INVALID) {
        s->cob_rx = CO_COB_INVALID; /* a server that cannot answer does not listen */
    }
    co_frame_address(&s->reply, s->cob_tx, CO_SDO_FRAME_LEN);
    co_route_set(node, CO_ROUTE_SDO_SERVER, ch, co_cob_route(s->cob_rx));
}

void co_sdo_server_reset_comm(co_node_t *node)
{
    for (uint8_t ch = 0; ch < co_sdo_servers_max(); ch++) {
        node->sdo_servers[ch].state = IDLE;
        load_channel(node, ch);
    }
}

void co_sdo_server_stop(co_node_t *node)
{
    for (uint8_t ch = 0; ch < co_sdo_servers_max(); ch++) {
        node->sdo_servers[ch].state = IDLE; /* no frame: SDO may not be sent now */
    }
}

/* The default server's COB-IDs cannot change (CiA 301): a write of others is refused. */
co_abort_t co_sdo_server_check_write(co_node_t *node, const co_od_entry_t *entry,
                                     const uint8_t *data, uint32_t len)
{
    (void)len; /* 4: the dictionary's own check came first */
    const co_sdo_server_t *s = &node->sdo_servers[0];
    bool cob = entry->index == 0x1200 && (entry->sub == 1 || entry->sub == 2);
    if (cob && co_get_u32(data) != (entry->sub == 1 ? s->cob_rx : s->cob_tx)) {
        return CO_ABORT_READ_ONLY;
    }
    return CO_ABORT_NONE;
}

/* New COB-IDs take effect at once: a transfer open on the channel ends (without a frame). */
void co_sdo_server_written(co_node_t *node, const co_od_entry_t *entry)
{
    uint32_t ch = entry->index - 0x1200u;
    if (ch < co_sdo_servers_max() && (entry->sub == 1 || entry->sub == 2)) {
        node->sdo_servers[ch].state = IDLE;
        load_channel(node, (uint8_t)ch);
    }
}

/* ---- time and sending */

/* The transfer moved on: its time-out counts from now. */
static void progress(const co_node_t *node, co_sdo_server_t *s) { s->last_us = node->now_us; }

/* A transfer opens (or goes on in a new state): poll must look at it by the time-out. */
static CO_SIZE_NOINLINE void enter(co_node_t *node, co_sdo_server_t *s, uint8_t state)
{
    s->state = state;
    progress(node, s);
    co_node_schedule(node, s->last_us + co_sdo_timeout_us(node));
}

/* The response in s->reply to the client (its data filled by the caller). */
static void send_reply(co_node_t *node, co_sdo_server_t *s)
{
    if (s->cob_tx & CO_COB_INVALID) {
        return; /* never on a COB-ID marked not valid */
    }
    (void)co_node_send_as(node, &s->reply, CO_SVC_SDO);
}

/* A whole frame to the client. */
static void send(co_node_t *node, co_sdo_server_t *s, const uint8_t data[CO_SDO_FRAME_LEN])
{
    co_copy_fixed(s->reply.data, data, CO_SDO_FRAME_LEN);
    send_reply(node, s);
}

/* A frame of two little-endian words: bytes 0..3 and 4..7, built in the frame itself. */
static CO_SIZE_NOINLINE void send_words(co_node_t *node, co_sdo_server_t *s, uint32_t head,
                                        uint32_t tail)
{
    co_put_u32(&s->reply.data[0], head);
    co_put_u32(&s->reply.data[4], tail);
    send_reply(node, s);
}

/* The first word of a response naming the transfer's object: cmd, index, sub-index. */
static uint32_t head(const co_sdo_server_t *s, uint8_t cmd)
{
    return cmd | ((uint32_t)s->index << 8) | ((uint32_t)s->sub << 24);
}

/* A response naming the transfer's object, then `tail`. */
static void respond(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, uint32_t tail)
{
    send_words(node, s, head(s, cmd), tail);
}

/* The one failure path: the abort to the client, and the transfer is over. */
static CO_NOINLINE void fail(co_node_t *node, co_sdo_server_t *s, co_abort_t code)
{
    respond(node, s, CO_SDO_CS_ABORT, code);
    s->state = IDLE;
}

/* A whole value from the network into the dictionary with the services' effects, then the
 * confirmation (`ok`, its first word; the second is 0). The write may move this very channel
 * (0x1200 sub 1 or 2 written through it): it takes effect at once, and the confirmation
 * still leaves where the client waits for it, on the COB-ID the request was served on. */
static co_abort_t store(co_node_t *node, co_sdo_server_t *s, const uint8_t *data, uint32_t len,
                        uint32_t ok)
{
    co_frame_t *r = &s->reply;
    uint32_t served_id = r->id; /* (valid: else the request had not come) */
    uint8_t served_flags = r->flags;
    co_abort_t abort = co_node_write(node, s->entry, data, len);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    uint32_t id = r->id; /* the channel's address from now on */
    uint8_t flags = r->flags;
    /* (the default channel's COB-IDs never change: a node with one server skips this) */
    // cppcheck-suppress knownConditionTrueFalse
    if (co_sdo_servers_max() > 1) {
        r->id = served_id;
        r->flags = served_flags;
    }
    co_put_u32(&r->data[0], ok);
    co_put_u32(&r->data[4], 0);
    (void)co_node_send_as(node, r, CO_SVC_SDO);
    r->id = id;
    r->flags = flags;
    return CO_ABORT_NONE;
}

/* The first bytes of a new transfer's bookkeeping (expedited requests need none). */
static void begin(co_sdo_server_t *s)
{
    s->done = 0;
    s->buf_len = 0;
    s->toggle = 0;
    s->crc = 0;
}

/* ---- download */

static uint32_t received(const co_sdo_server_t *s) { return s->done + s->buf_len; }

static bool streams(const co_od_t *od, const co_sdo_server_t *s)
{
    const co_od_hooks_t *hooks = co_od_hooks_of(s->entry);
    return co_od_value(od, s->entry) == NULL && hooks && hooks->write;
}

/* The RAM bytes of a DOMAIN or string (a value of no fixed size, kept in storage): a
 * download larger than the buffer is received straight into them, up to the entry's
 * size (the buffer frames the transfer, it does not bound the value). NULL otherwise. */
static uint8_t *own_storage(const co_od_t *od, const co_sdo_server_t *s)
{
    const co_od_entry_t *e = s->entry;
    void *value = co_od_value(od, e);
    if (value == NULL || co_type_size((co_type_t)co_od_type(od, e)) != 0) {
        return NULL;
    }
    return co_od_type(od, e) == CO_TYPE_DOMAIN ? ((co_od_domain_t *)value)->data : (uint8_t *)value;
}

/* Move the buffered bytes into the entry's own storage (own_storage), after those moved
 * before: false when they would not fit. */
static bool spill(const co_od_t *od, co_sdo_server_t *s)
{
    uint8_t *storage = own_storage(od, s);
    if (storage == NULL || s->done + s->buf_len > co_od_size(od, s->entry)) {
        return false;
    }
    co_copy(storage + s->done, s->buf, s->buf_len);
    s->done += s->buf_len;
    s->buf_len = 0;
    return true;
}

/* Size checks at initiate: what the entry and the buffer can take. */
static co_abort_t check_download_size(const co_od_t *od, const co_sdo_server_t *s)
{
    uint32_t fixed = co_type_size((co_type_t)co_od_type(od, s->entry));
    if (!s->size_known) {
        return CO_ABORT_NONE;
    }
    if (fixed != 0 && s->size != fixed) {
        return s->size > fixed ? CO_ABORT_LEN_HIGH : CO_ABORT_LEN_LOW;
    }
    if (fixed == 0 && co_od_value(od, s->entry) != NULL && s->size > co_od_size(od, s->entry)) {
        return CO_ABORT_LEN_HIGH;
    }
    if (!streams(od, s) && s->size > CO_SDO_BUF_SIZE && own_storage(od, s) == NULL) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    return CO_ABORT_NONE;
}

/* Pass the buffered bytes on: to the write hook as a piece, or (a DOMAIN or string in RAM
 * larger than the buffer) into the entry's own storage before the last piece (spill). */
static co_abort_t flush(co_node_t *node, co_sdo_server_t *s, bool last)
{
    if (!streams(&node->cfg.od, s)) {
        return spill(&node->cfg.od, s) ? CO_ABORT_NONE : CO_ABORT_LEN_HIGH;
    }
    uint32_t total = s->size_known ? s->size : CO_OD_SIZE_UNKNOWN;
    co_abort_t abort =
        co_od_write_piece(&node->cfg.od, s->entry, s->done, s->buf, s->buf_len, total, last);
    s->done += s->buf_len;
    s->buf_len = 0;
    return abort;
}

/* Append a segment's bytes (`n` of the 7 at `data`; the buffer has room for 7 past its size:
 * a block's last segment may carry up to 6 bytes of padding past the value). A full buffer
 * is streamed on first, or the transfer fails. */
static co_abort_t collect(co_node_t *node, co_sdo_server_t *s, const uint8_t *data, uint32_t n)
{
    if (n == 0) {
        return CO_ABORT_NONE; /* (the copy below writes 7 bytes: none past the buffer) */
    }
    uint32_t room = CO_CONFIG_SDO_BLOCK && s->state == BLOCK_DOWN ? sizeof s->buf : CO_SDO_BUF_SIZE;
    if (s->buf_len + n > room) {
        if (!streams(&node->cfg.od, s) && own_storage(&node->cfg.od, s) == NULL) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
        if (CO_CONFIG_SDO_BLOCK && s->crc_on) { /* the CRC covers data as it leaves the buffer */
            s->crc = co_crc16(s->crc, s->buf, s->buf_len);
        }
        co_abort_t abort = flush(node, s, false);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
    }
    co_copy_fixed(&s->buf[s->buf_len], data, CO_SDO_SEG_BYTES); /* (a fixed size: no loop) */
    s->buf_len += n;
    return CO_ABORT_NONE;
}

/* The length of an expedited download that does not indicate it: the type's, else 4. */
static uint32_t unsized_length(const co_od_t *od, const co_od_entry_t *e)
{
    uint32_t fixed = co_type_size((co_type_t)co_od_type(od, e));
    return fixed && fixed < CO_SDO_EXPEDITED_MAX ? fixed : CO_SDO_EXPEDITED_MAX;
}

static co_abort_t initiate_download(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t cmd = d[0];
    if (cmd & CO_SDO_INI_EXPEDITED) {
        uint32_t len = (cmd & CO_SDO_INI_SIZE) ? CO_SDO_EXPEDITED_MAX - CO_SDO_INI_N(cmd)
                                               : unsized_length(&node->cfg.od, s->entry);
        return store(node, s, &d[4], len, head(s, CO_SDO_SCS_DN_INI));
    }
    if (!CO_CONFIG_SDO_SEGMENTED) {
        return CO_ABORT_COMMAND; /* segmented transfer is left out */
    }
    begin(s);
    s->size_known = cmd & CO_SDO_INI_SIZE;
    s->size = co_get_u32(&d[4]);
    s->crc_on = false;
    co_abort_t abort = check_download_size(&node->cfg.od, s);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    enter(node, s, DOWN_SEGMENTED);
    respond(node, s, CO_SDO_SCS_DN_INI, 0);
    return CO_ABORT_NONE;
}

/* The end of a download (the transfer is over): sizes agree, then the value goes to the
 * dictionary, and the client hears `ok` (the confirmation's first word) or the abort. The
 * value is stored whole: from the buffer, or from the entry's own storage when earlier parts
 * went there (spill). */
static co_abort_t finish_download(co_node_t *node, co_sdo_server_t *s, uint32_t ok)
{
    s->state = IDLE;
    uint32_t len = received(s);
    if (s->size_known && len != s->size) {
        return len > s->size ? CO_ABORT_LEN_HIGH : CO_ABORT_LEN_LOW;
    }
    if (streams(&node->cfg.od, s)) {
        co_abort_t abort = flush(node, s, true);
        if (abort == CO_ABORT_NONE) {
            send_words(node, s, ok, 0);
        }
        return abort;
    }
    if (CO_CONFIG_SDO_BLOCK && s->done == 0 && s->buf_len > CO_SDO_BUF_SIZE &&
        own_storage(&node->cfg.od, s) == NULL) { /* (only a block fills past the size) */
        return CO_ABORT_OUT_OF_MEMORY;
    }
    if (s->done == 0) {
        return store(node, s, s->buf, s->buf_len, ok);
    }
    if (!spill(&node->cfg.od, s)) {
        return CO_ABORT_LEN_HIGH;
    }
    return store(node, s, own_storage(&node->cfg.od, s), len, ok);
}

/* A download segment (command 000t nnnc) of an open segmented download. One with no data
 * and more to come moves nothing: it is answered, but the time-out goes on. */
static co_abort_t on_download_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t cmd = d[0];
    uint8_t toggle = cmd & CO_SDO_SEG_TOGGLE;
    if (toggle != s->toggle) {
        return CO_ABORT_TOGGLE;
    }
    uint32_t n = CO_SDO_SEG_BYTES - CO_SDO_SEG_N(cmd);
    if (s->size_known && received(s) + n > s->size) {
        return CO_ABORT_LEN_HIGH;
    }
    co_abort_t abort = collect(node, s, &d[1], n);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    s->toggle = (uint8_t)(toggle ^ CO_SDO_SEG_TOGGLE);
    if (cmd & CO_SDO_SEG_LAST) {
        return finish_download(node, s, CO_SDO_SCS_DN_SEG | toggle);
    }
    if (n != 0) {
        progress(node, s);
    }
    send_words(node, s, CO_SDO_SCS_DN_SEG | toggle, 0);
    return CO_ABORT_NONE;
}

/* ---- upload */

/* Whether a read told the value's size: always without hooks (the compact form has none). */
static bool size_told(uint32_t total)
{
    return CO_CONFIG_OD_COMPACT || total != CO_OD_SIZE_UNKNOWN;
}

/* Read the value from `offset` until `cap` bytes or its end: a read hook may hand out
 * fewer bytes per call than asked (an empty piece ends a value of unknown size). */
static co_abort_t read_at(co_node_t *node, co_sdo_server_t *s, uint32_t offset, uint8_t *buf,
                          uint32_t cap, uint32_t *n, uint32_t *total)
{
    *n = 0;
    *total = CO_OD_SIZE_UNKNOWN;
    while (*n < cap) {
        uint32_t got = 0;
        co_abort_t abort =
            co_od_read(&node->cfg.od, s->entry, offset + *n, buf + *n, cap - *n, &got, total);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
        *n += got;
        /* (without hooks, as in the compact form, the first read is the whole piece) */
        if (CO_CONFIG_OD_COMPACT || got == 0 || (size_told(*total) && offset + *n >= *total)) {
            break;
        }
    }
    return CO_ABORT_NONE;
}

/* An initiate upload request: the value in the answer when it has 1..4 bytes (expedited),
 * else its size, and segments follow. */
static co_abort_t initiate_upload(co_node_t *node, co_sdo_server_t *s)
{
    uint8_t first[CO_SDO_EXPEDITED_MAX] = {0};
    uint32_t n = 0;
    uint32_t total = 0;
    co_abort_t abort = read_at(node, s, 0, first, sizeof first, &n, &total);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    if (size_told(total) && total >= 1 && total <= CO_SDO_EXPEDITED_MAX) {
        /* 1..4 bytes, little-endian in the last word (a read hook may have left bytes after
         * the value: they are not part of it) */
        uint32_t unused = CO_SDO_EXPEDITED_MAX - total;
        uint32_t cmd = CO_SDO_SCS_UP_INI | CO_SDO_INI_EXPEDITED | CO_SDO_INI_SIZE;
        respond(node, s, (uint8_t)(cmd | (unused << CO_SDO_INI_N_SHIFT)),
                co_get_u32(first) & (0xFFFFFFFFu >> (8u * unused)));
        return CO_ABORT_NONE;
    }
    if (!CO_CONFIG_SDO_SEGMENTED) {
        return CO_ABORT_UNSUPPORTED; /* too long without segments */
    }
    begin(s); /* segments follow */
#if CO_CONFIG_SDO_SEGMENTED
    /* a string or DOMAIN in storage, with no read hook: its bytes are the wire's */
    const co_od_hooks_t *hooks = co_od_hooks_of(s->entry);
    s->wire = hooks == NULL || hooks->read == NULL ? own_storage(&node->cfg.od, s) : NULL;
#endif
    s->size_known = size_told(total);
    s->size = s->size_known ? total : 0;
    enter(node, s, UP_SEGMENTED);
    respond(node, s, CO_SDO_SCS_UP_INI | (s->size_known ? CO_SDO_INI_SIZE : 0u), s->size);
    return CO_ABORT_NONE;
}

/* An upload segment request (command 011t 0000) of an open segmented upload: the next 7
 * bytes at most, read into the reply. */
static co_abort_t on_upload_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t toggle = d[0] & CO_SDO_SEG_TOGGLE;
    if (toggle != s->toggle) {
        return CO_ABORT_TOGGLE;
    }
    uint8_t *r = s->reply.data; /* (an abort rewrites it) */
    co_put_u32(&r[0], 0);
    co_put_u32(&r[4], 0);
    uint32_t n = 0;
    uint32_t total = s->size;
#if CO_CONFIG_SDO_SEGMENTED
    if (s->wire != NULL) { /* in storage: copied from there (the segmented upload row: 54 -> 38
                            * Ir a byte in the default set, -Os) */
        n = total - s->done < CO_SDO_SEG_BYTES ? total - s->done : CO_SDO_SEG_BYTES;
        if (n == CO_SDO_SEG_BYTES) {
            co_copy_fixed(&r[1], s->wire + s->done, CO_SDO_SEG_BYTES);
        } else {
            co_copy(&r[1], s->wire + s->done, n); /* the last: none past the value */
        }
    } else
#endif
    {
        co_abort_t abort = read_at(node, s, s->done, &r[1], CO_SDO_SEG_BYTES, &n, &total);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
    }
    s->done += n;
    bool last = size_told(total) ? s->done >= total : n < CO_SDO_SEG_BYTES;
    r[0] = (uint8_t)(CO_SDO_SCS_UP_SEG | toggle | ((CO_SDO_SEG_BYTES - n) << CO_SDO_SEG_N_SHIFT) |
                     (last ? CO_SDO_SEG_LAST : 0u));
    s->toggle = (uint8_t)(toggle ^ CO_SDO_SEG_TOGGLE);
    progress(node, s);
    send_reply(node, s);
    if (last) {
        s->state = IDLE;
    }
    return CO_ABORT_NONE;
}

/* ---- block download */

static co_abort_t initiate_block_download(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    begin(s);
    s->crc_on = d[0] & CO_SDO_BLK_CRC;
    s->size_known = d[0] & CO_SDO_BLK_SIZE;
    s->size = co_get_u32(&d[4]);
    co_abort_t abort = check_download_size(&node->cfg.od, s);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    s->blksize = BLOCK_SIZE_MAX;
    s->seq = 0;
    enter(node, s, BLOCK_DOWN);
    /* sc = 1: this server checks CRCs */
    respond(node, s, CO_SDO_SCS_BLK_DN | CO_SDO_BLK_INI | CO_SDO_BLK_CRC, s->blksize);
    return CO_ABORT_NONE;
}

/* One segment of a sub-block. Only the next in-order sequence number is taken (progress);
 * the acknowledgement, at the sub-block's end, names the last one taken, so the client
 * repeats what was lost. */
static co_abort_t on_block_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t seqno = d[0] & CO_SDO_BLK_SEQ_MASK;
    bool last = d[0] & CO_SDO_BLK_LAST;
    if (seqno == 0 || seqno > s->blksize) {
        return CO_ABORT_SEQUENCE;
    }
    bool in_order = seqno == s->seq + 1u;
    if (in_order) {
        co_abort_t abort = collect(node, s, &d[1], CO_SDO_SEG_BYTES);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
        s->seq = seqno;
        progress(node, s);
    }
    if (!(last || seqno >= s->blksize)) {
        return CO_ABORT_NONE;
    }
    uint8_t ack[CO_SDO_FRAME_LEN] = {CO_SDO_SCS_BLK_DN | CO_SDO_BLK_ACK, s->seq, s->blksize};
    send(node, s, ack);
    s->seq = 0;
    if (last && in_order) {
        s->state = BLOCK_DOWN_END;
    }
    return CO_ABORT_NONE;
}

static co_abort_t on_block_download_end(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint32_t unused = CO_SDO_BLK_END_N(d[0]);
    if (unused > s->buf_len) { /* n = 7: an empty value's only segment */
        return CO_ABORT_COMMAND;
    }
    s->buf_len -= unused; /* the last segment's padding */
    if (s->crc_on && co_crc16(s->crc, s->buf, s->buf_len) != co_get_u16(&d[1])) {
        return CO_ABORT_CRC;
    }
    return finish_download(node, s, CO_SDO_SCS_BLK_DN | CO_SDO_BLK_END);
}

/* ---- block upload */

static uint32_t chunk_cap(const co_sdo_server_t *s)
{
    return (uint32_t)s->blksize * CO_SDO_SEG_BYTES;
}

/* Load the next sub-block's data from the dictionary at the current offset. */
static co_abort_t load_sub_block(co_node_t *node, co_sdo_server_t *s, uint32_t *total_out)
{
    uint32_t total = 0;
    co_abort_t abort = read_at(node, s, s->done, s->buf, chunk_cap(s), &s->buf_len, &total);
    *total_out = total;
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    s->last_sent = size_told(total) ? s->done + s->buf_len >= total : s->buf_len < chunk_cap(s);
    s->seq = 0;
    return CO_ABORT_NONE;
}

/* Segments in the loaded sub-block: full ones, and on the final sub-block one more for
 * the remainder (an empty value still sends one segment). */
static uint8_t sub_block_segments(const co_sdo_server_t *s)
{
    uint32_t n = s->buf_len / CO_SDO_SEG_BYTES;
    if (s->last_sent && (s->buf_len % CO_SDO_SEG_BYTES != 0 || s->buf_len == 0)) {
        n++;
    }
    return (uint8_t)n;
}

/* Send the sub-block's segments while the transmit queue is idle; poll resumes. The
 * full segments before the final one go out from a short loop. Sending a sub-block that
 * an acknowledgement moved on is progress (on a slow bus it may take longer than the
 * time-out); sending one again that the client acknowledged nothing of is not. */
static void pump_sub_block(co_node_t *node, co_sdo_server_t *s)
{
    uint8_t segments = sub_block_segments(s);
    uint8_t plain = s->last_sent ? (uint8_t)(segments - 1u) : segments; /* 7 bytes, not final */
    uint8_t seq = s->seq;
    if (seq >= segments || (s->cob_tx & CO_COB_INVALID)) {
        return; /* (a channel without a valid COB-ID is never in a transfer) */
    }
    const uint8_t *next = &s->buf[(size_t)seq * CO_SDO_SEG_BYTES];
    while (seq < plain && co_txq_idle(node)) {
        s->reply.data[0] = ++seq;
        co_copy_fixed(&s->reply.data[1], next, CO_SDO_SEG_BYTES);
        next += CO_SDO_SEG_BYTES;
        (void)co_node_send_as(node, &s->reply, CO_SVC_SDO);
    }
    if (seq == plain && seq < segments && co_txq_idle(node)) { /* the final segment */
        uint32_t offset = (uint32_t)seq * CO_SDO_SEG_BYTES;
        uint32_t n = s->buf_len - offset;
        uint8_t d[CO_SDO_FRAME_LEN] = {(uint8_t)(CO_SDO_BLK_LAST | ++seq)};
        co_copy(&d[1], &s->buf[offset], n);
        s->last_len = (uint8_t)n;
        send(node, s, d);
    }
    if (seq != s->seq && !s->resent) {
        progress(node, s);
    }
    s->seq = seq;
}

static co_abort_t initiate_block_upload(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t blksize = d[4];
    uint8_t pst = d[5];
    if (blksize < 1 || blksize > CO_SDO_BLKSIZE_MAX) {
        return CO_ABORT_BLOCK_SIZE;
    }
    begin(s);
    s->crc_on = d[0] & CO_SDO_BLK_CRC;
    s->resent = false;
    s->blksize = blksize <= BLOCK_SIZE_MAX ? blksize : (uint8_t)BLOCK_SIZE_MAX;
    uint32_t total = 0;
    co_abort_t abort = load_sub_block(node, s, &total);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    if (pst != 0 && size_told(total) && total <= pst) {
        return initiate_upload(node, s); /* protocol switch: a normal upload serves it better */
    }
    s->size_known = size_told(total);
    s->size = s->size_known ? total : 0;
    enter(node, s, BLOCK_UP_START);
    uint8_t size = s->size_known ? CO_SDO_BLK_SIZE : 0u; /* sc = 1: a CRC is offered */
    respond(node, s, CO_SDO_SCS_BLK_UP | CO_SDO_BLK_INI | CO_SDO_BLK_CRC | size, s->size);
    return CO_ABORT_NONE;
}

static co_abort_t on_block_upload_start(co_node_t *node, co_sdo_server_t *s)
{
    s->state = BLOCK_UP;
    progress(node, s);
    pump_sub_block(node, s);
    return CO_ABORT_NONE;
}

static co_abort_t on_block_upload_ack(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t ackseq = d[1];
    uint8_t blksize = d[2];
    if (ackseq > s->seq) {
        return CO_ABORT_SEQUENCE;
    }
    if (blksize < 1 || blksize > CO_SDO_BLKSIZE_MAX) {
        return CO_ABORT_BLOCK_SIZE;
    }
    uint32_t acked = (uint32_t)ackseq * CO_SDO_SEG_BYTES;
    if (acked > s->buf_len) {
        acked = s->buf_len;
    }
    bool all_acked = ackseq == sub_block_segments(s);
    if (s->crc_on) {
        s->crc = co_crc16(s->crc, s->buf, acked);
    }
    s->done += acked;
    s->resent = ackseq == 0; /* the same data again: no progress */
    if (!s->resent) {
        progress(node, s);
    }
    if (all_acked && s->last_sent) {
        uint8_t unused = (uint8_t)(CO_SDO_SEG_BYTES - s->last_len);
        uint8_t cmd = CO_SDO_SCS_BLK_UP | CO_SDO_BLK_END;
        uint8_t end[CO_SDO_FRAME_LEN] = {(uint8_t)(cmd | (unused << CO_SDO_BLK_END_N_SHIFT)),
                                         (uint8_t)s->crc, (uint8_t)(s->crc >> 8)};
        send(node, s, end);
        s->state = BLOCK_UP_END;
        return CO_ABORT_NONE;
    }
    s->blksize = blksize <= BLOCK_SIZE_MAX ? blksize : (uint8_t)BLOCK_SIZE_MAX;
    uint32_t total = 0;
    co_abort_t abort = load_sub_block(node, s, &total);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    pump_sub_block(node, s);
    return CO_ABORT_NONE;
}

/* ---- requests */

/* A new transfer's object: found and accessible in that direction, else the abort code.
 * A transfer still open ends here. */
static co_abort_t open_entry(co_node_t *node, co_sdo_server_t *s, const uint8_t *d, bool write)
{
    s->state = IDLE;
    s->index = co_get_u16(&d[1]);
    s->sub = d[3];
    co_abort_t abort = CO_ABORT_NO_OBJECT;
    s->entry = co_od_find(&node->cfg.od, s->index, s->sub, &abort);
    if (s->entry == NULL) {
        return abort;
    }
    abort = co_od_access(&node->cfg.od, s->entry, write);
    /* readable, but has it data now (0x1003)? */
    return abort != CO_ABORT_NONE || write ? abort : co_od_read_check(node, s->entry);
}

/* Block initiate requests: 110x x0x0 download, 101x x000 upload. */
static bool is_block_initiate(uint8_t cmd)
{
    uint8_t cs = cmd & CO_SDO_CS_MASK;
    return (cs == CO_SDO_CCS_BLK_DN && (cmd & CO_SDO_BLK_END) == 0) ||
           (cs == CO_SDO_CCS_BLK_UP && (cmd & CO_SDO_BLK_SUB_MASK) == CO_SDO_BLK_INI);
}

/* A request that is no step of the open transfer: an initiate (a transfer still open ends
 * there), the client's abort (ends it silently), or one that fits no state. */
static co_abort_t on_request(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t cmd = d[0];
    uint8_t cs = cmd & CO_SDO_CS_MASK;
    if (cs == CO_SDO_CCS_DN_INI || cs == CO_SDO_CCS_UP_INI) {
        bool write = cs == CO_SDO_CCS_DN_INI;
        co_abort_t abort = open_entry(node, s, d, write);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
        return write ? initiate_download(node, s, d) : initiate_upload(node, s);
    }
    if (cmd == CO_SDO_CS_ABORT) {
        s->state = IDLE;
        return CO_ABORT_NONE;
    }
    if (is_block_initiate(cmd)) {
        bool write = cs == CO_SDO_CCS_BLK_DN;
        co_abort_t abort = open_entry(node, s, d, write);
        if (abort != CO_ABORT_NONE || !CO_CONFIG_SDO_BLOCK) {
            return abort != CO_ABORT_NONE ? abort : CO_ABORT_COMMAND; /* block is left out */
        }
        return write ? initiate_block_download(node, s, d) : initiate_block_upload(node, s, d);
    }
    if (s->state == IDLE) { /* no transfer to name */
        s->index = 0;
        s->sub = 0;
    }
    return CO_ABORT_COMMAND;
}

/* The frame's step in the channel's state, or on_request for a frame that is not one. */
static co_abort_t step(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t cmd = d[0];
    switch (s->state) {
    case DOWN_SEGMENTED:
        if (CO_CONFIG_SDO_SEGMENTED && (cmd & CO_SDO_CS_MASK) == CO_SDO_CCS_DN_SEG) {
            return on_download_segment(node, s, d);
        }
        break;
    case UP_SEGMENTED:
        if (CO_CONFIG_SDO_SEGMENTED && (cmd & ~CO_SDO_SEG_TOGGLE) == CO_SDO_CCS_UP_SEG) {
            return on_upload_segment(node, s, d);
        }
        break;
    case BLOCK_DOWN:
        if (CO_CONFIG_SDO_BLOCK && cmd != CO_SDO_CS_ABORT) { /* in a sub-block: a segment */
            return on_block_segment(node, s, d);
        }
        break;
    case BLOCK_DOWN_END:
        if (CO_CONFIG_SDO_BLOCK && (cmd & (CO_SDO_CS_MASK | CO_SDO_BLK_SUB_MASK)) ==
                                       (CO_SDO_CCS_BLK_DN | CO_SDO_BLK_END)) {
            return on_block_download_end(node, s, d);
        }
        break;
    case BLOCK_UP_START:
        if (CO_CONFIG_SDO_BLOCK && cmd == (CO_SDO_CCS_BLK_UP | CO_SDO_BLK_START)) {
            return on_block_upload_start(node, s);
        }
        break;
    case BLOCK_UP:
        if (CO_CONFIG_SDO_BLOCK && cmd == (CO_SDO_CCS_BLK_UP | CO_SDO_BLK_ACK)) {
            return on_block_upload_ack(node, s, d);
        }
        break;
    case BLOCK_UP_END:
        if (CO_CONFIG_SDO_BLOCK && cmd == (CO_SDO_CCS_BLK_UP | CO_SDO_BLK_END)) {
            s->state = IDLE;
            return CO_ABORT_NONE;
        }
        break;
    default:
        break;
    }
    return on_request(node, s, d);
}

void co_sdo_server_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame)
{
    if (frame->len != CO_SDO_FRAME_LEN || (frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    /* (the routes give channels below co_sdo_servers_max: with one, always 0; the
     * condition is constant in every build, which is the point) */
    // cppcheck-suppress knownConditionTrueFalse
    co_sdo_server_t *s = &node->sdo_servers[co_sdo_servers_max() > 1 ? channel : 0];
    co_abort_t abort = step(node, s, frame->data);
    if (abort != CO_ABORT_NONE) {
        fail(node, s, abort);
    }
}

#if CO_CONFIG_SDO_SEGMENTED || CO_CONFIG_SDO_BLOCK
uint64_t co_sdo_server_poll(co_node_t *node, uint64_t now_us)
{
    uint64_t next = CO_TIME_NEVER;
    for (uint8_t ch = 0; ch < co_sdo_servers_max(); ch++) {
        co_sdo_server_t *s = &node->sdo_servers[ch];
        if (s->state == IDLE) {
            continue;
        }
        if (now_us >= s->last_us + co_sdo_timeout_us(node)) {
            fail(node, s, CO_ABORT_TIMEOUT);
            continue;
        }
        if (CO_CONFIG_SDO_BLOCK && s->state == BLOCK_UP) {
            pump_sub_block(node, s);
        }
        next = co_min_u64(next, s->last_us + co_sdo_timeout_us(node));
    }
    return next;
}
#endif
