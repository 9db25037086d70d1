/*
 * sdo_server.c -- the SDO server: expedited, segmented and block transfer in
 * both directions (see canola/sdo.h for the behaviour).
 *
 * One state machine per channel. Downloads collect into the channel buffer and
 * are stored whole at the end, unless the entry streams through a write hook;
 * uploads read the dictionary piece by piece at an offset, so a retransmission
 * in block upload simply reads the same offset again.
 */
#include <string.h>

#include "internal.h"

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

#define SEG_BYTES 7u
#define BLOCK_SIZE_MAX (CO_SDO_BUF_SIZE / SEG_BYTES < 127 ? CO_SDO_BUF_SIZE / SEG_BYTES : 127)

/* ---- channels and their COB-IDs */

static uint32_t cob_from_od(const co_node_t *node, uint8_t ch, uint8_t sub, uint32_t fallback)
{
    uint64_t v = 0;
    if (co_od_get_uint(&node->cfg.od, (uint16_t)(0x1200 + ch), sub, &v) == CO_OK) {
        return (uint32_t)v;
    }
    return fallback;
}

static void load_channel(co_node_t *node, uint8_t ch)
{
    co_sdo_server_t *s = &node->sdo_servers[ch];
    bool configured = node->node_id >= 1 && node->node_id <= 127;
    uint32_t rx = (ch == 0 && configured) ? 0x600u + node->node_id : CO_COB_INVALID;
    uint32_t tx = (ch == 0 && configured) ? 0x580u + node->node_id : CO_COB_INVALID;
    s->cob_rx = cob_from_od(node, ch, 1, rx);
    s->cob_tx = cob_from_od(node, ch, 2, tx);
    if (s->cob_tx & CO_COB_INVALID) {
        s->cob_rx = CO_COB_INVALID; /* a server that cannot answer does not listen */
    }
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

/* Take new COB-IDs into use. A channel reconfigured by a request it is serving itself
 * answers that request on the old COB-ID first: the reload waits for the answer. */
static void apply_reloads(co_node_t *node)
{
    if (!node->sdo_reload) {
        return;
    }
    node->sdo_reload = false;
    bool changed = false;
    for (uint8_t ch = 0; ch < co_sdo_servers_max(); ch++) {
        co_sdo_server_t *s = &node->sdo_servers[ch];
        if (s->reload) {
            s->reload = false;
            s->state = IDLE;
            load_channel(node, ch);
            changed = true;
        }
    }
    if (changed) {
        co_routes_rebuild(node);
    }
}

void co_sdo_server_written(co_node_t *node, const co_od_entry_t *entry)
{
    uint32_t ch = entry->index - 0x1200u;
    if (ch < co_sdo_servers_max() && (entry->sub == 1 || entry->sub == 2)) {
        node->sdo_servers[ch].reload = true;
        node->sdo_reload = true;
        if (!node->sdo_serving) {
            apply_reloads(node);
        }
    }
}

/* ---- sending */

static void refresh(co_node_t *node, co_sdo_server_t *s)
{
    s->deadline_us = node->now_us + co_sdo_timeout_us(node);
    co_node_schedule(node, s->deadline_us);
}

static CO_INLINE void send(co_node_t *node, co_sdo_server_t *s, const uint8_t data[8])
{
    if (s->cob_tx & CO_COB_INVALID) {
        return; /* never on a COB-ID marked not valid */
    }
    co_frame_t f = co_cob_frame(s->cob_tx, 8);
    memcpy(f.data, data, 8);
    (void)co_node_send_hot(node, &f, CO_SVC_SDO);
}

/* A response carrying the transfer's index and sub-index: cmd, index, sub, then `tail`
 * (built in the frame itself: the expedited answers are the hot ones). */
static CO_INLINE void respond(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, uint32_t tail)
{
    if (s->cob_tx & CO_COB_INVALID) {
        return; /* never on a COB-ID marked not valid */
    }
    co_frame_t f = co_cob_frame(s->cob_tx, 8);
    f.data[0] = cmd;
    co_put_u16(&f.data[1], s->index);
    f.data[3] = s->sub;
    co_put_u32(&f.data[4], tail);
    (void)co_node_send_hot(node, &f, CO_SVC_SDO);
}

static CO_NOINLINE void abort_transfer(co_node_t *node, co_sdo_server_t *s, co_abort_t code)
{
    respond(node, s, 0x80, code);
    s->state = IDLE;
}

/* ---- download */

static bool streams(const co_sdo_server_t *s)
{
    return s->entry->value == NULL && s->entry->hooks && s->entry->hooks->write;
}

/* Size checks at initiate: what the entry and the buffer can take. */
static co_abort_t check_download_size(const co_sdo_server_t *s)
{
    uint32_t fixed = co_type_size((co_type_t)s->entry->type);
    if (!s->size_known) {
        return CO_ABORT_NONE;
    }
    if (fixed != 0 && s->size != fixed) {
        return s->size > fixed ? CO_ABORT_LEN_HIGH : CO_ABORT_LEN_LOW;
    }
    if (fixed == 0 && s->entry->value != NULL && s->size > s->entry->size) {
        return CO_ABORT_LEN_HIGH;
    }
    if (!streams(s) && s->size > CO_SDO_BUF_SIZE) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    return CO_ABORT_NONE;
}

/* Pass the buffered bytes on: to the write hook as a piece, or (last) store them whole. */
static co_abort_t flush(co_node_t *node, co_sdo_server_t *s, bool last)
{
    co_abort_t abort = CO_ABORT_NONE;
    if (streams(s)) {
        uint32_t total = s->size_known ? s->size : CO_OD_SIZE_UNKNOWN;
        abort =
            co_od_write_piece(&node->cfg.od, s->entry, s->done, s->buf, s->buf_len, total, last);
    } else if (last) {
        abort = co_node_write_entry(node, s->entry, s->buf, s->buf_len);
    }
    if (streams(s)) {
        s->done += s->buf_len;
        s->buf_len = 0;
    }
    return abort;
}

/* Append received bytes; when the buffer is full, stream it on or fail. */
static co_abort_t collect(co_node_t *node, co_sdo_server_t *s, const uint8_t *data, uint32_t n)
{
    /* a block's last segment may carry up to 6 bytes of padding past the value */
    uint32_t room = s->state == BLOCK_DOWN ? sizeof s->buf : CO_SDO_BUF_SIZE;
    if (s->buf_len + n > room) {
        if (!streams(s)) {
            return s->entry->value && co_type_size((co_type_t)s->entry->type) == 0 &&
                           s->buf_len + n > s->entry->size
                       ? CO_ABORT_LEN_HIGH
                       : CO_ABORT_OUT_OF_MEMORY;
        }
        if (CO_CONFIG_SDO_BLOCK && s->crc_on) { /* the CRC covers data as it leaves the buffer */
            s->crc = co_crc16(s->crc, s->buf, s->buf_len);
        }
        co_abort_t abort = flush(node, s, false);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
    }
    if (n == SEG_BYTES) {
        memcpy(&s->buf[s->buf_len], data, SEG_BYTES); /* the usual case, copied inline */
    } else {
        memcpy(&s->buf[s->buf_len], data, n);
    }
    s->buf_len += n;
    return CO_ABORT_NONE;
}

static uint32_t received(const co_sdo_server_t *s) { return s->done + s->buf_len; }

static void initiate_download(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    bool expedited = d[0] & 0x02u;
    bool sized = d[0] & 0x01u;
    if (expedited) {
        uint32_t fixed = co_type_size((co_type_t)s->entry->type);
        uint32_t len = sized ? 4u - ((d[0] >> 2) & 3u) : (fixed && fixed < 4 ? fixed : 4u);
        co_abort_t abort = co_node_write_entry(node, s->entry, &d[4], len);
        if (abort != CO_ABORT_NONE) {
            abort_transfer(node, s, abort);
            return;
        }
        respond(node, s, 0x60, 0);
        return;
    }
    s->size_known = sized;
    s->size = co_get_u32(&d[4]);
    s->crc_on = false;
    co_abort_t abort = check_download_size(s);
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    s->state = DOWN_SEGMENTED;
    respond(node, s, 0x60, 0);
}

/* The end of a download: sizes agree, then the value goes to the dictionary. */
static co_abort_t finish_download(co_node_t *node, co_sdo_server_t *s)
{
    if (s->size_known && received(s) != s->size) {
        return received(s) > s->size ? CO_ABORT_LEN_HIGH : CO_ABORT_LEN_LOW;
    }
    if (!streams(s) && s->buf_len > CO_SDO_BUF_SIZE) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    return flush(node, s, true);
}

static void download_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t toggle = (d[0] >> 4) & 1u;
    if ((d[0] & 0xE0u) != 0x00) {
        abort_transfer(node, s, CO_ABORT_COMMAND);
        return;
    }
    if (toggle != s->toggle) {
        abort_transfer(node, s, CO_ABORT_TOGGLE);
        return;
    }
    uint32_t n = SEG_BYTES - ((d[0] >> 1) & 7u);
    bool last = d[0] & 0x01u;
    co_abort_t abort = CO_ABORT_NONE;
    if (s->size_known && received(s) + n > s->size) {
        abort = CO_ABORT_LEN_HIGH;
    }
    if (abort == CO_ABORT_NONE && s->buf_len + SEG_BYTES <= CO_SDO_BUF_SIZE) {
        memcpy(&s->buf[s->buf_len], &d[1], SEG_BYTES); /* the usual case: room for 7 */
        s->buf_len += n;
    } else if (abort == CO_ABORT_NONE) {
        abort = collect(node, s, &d[1], n);
    }
    if (abort == CO_ABORT_NONE && last) {
        abort = finish_download(node, s);
    }
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    s->toggle ^= 1u;
    uint8_t r[8] = {(uint8_t)(0x20u | ((unsigned)toggle << 4))};
    send(node, s, r);
    if (last) {
        s->state = IDLE;
    }
}

/* ---- upload */

/* Read the value from `offset`: up to `cap` bytes into `buf`; `*total` is its size. */
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
        if (got == 0 || (*total != CO_OD_SIZE_UNKNOWN && offset + *n >= *total)) {
            break;
        }
    }
    return CO_ABORT_NONE;
}

static void initiate_upload(co_node_t *node, co_sdo_server_t *s)
{
    uint8_t first[4] = {0};
    uint32_t n = 0;
    uint32_t total = 0;
    const uint8_t *wire = co_od_wire_data(&node->cfg.od, s->entry, &total);
    if (wire != NULL && total >= 1 && total <= 4) { /* stored in wire form: answer from it */
        for (uint32_t i = 0; i < total; i++) {
            first[i] = wire[i]; /* at most 4 bytes: no call to memcpy */
        }
        respond(node, s, (uint8_t)(0x43u | ((4u - total) << 2)), co_get_u32(first));
        return;
    }
    co_abort_t abort = read_at(node, s, 0, first, sizeof first, &n, &total);
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    if (total != CO_OD_SIZE_UNKNOWN && total >= 1 && total <= 4) {
        respond(node, s, (uint8_t)(0x43u | ((4u - total) << 2)), co_get_u32(first));
        return;
    }
    s->size_known = total != CO_OD_SIZE_UNKNOWN;
    s->size = s->size_known ? total : 0;
    s->state = UP_SEGMENTED;
    respond(node, s, s->size_known ? 0x41 : 0x40, s->size);
}

static void upload_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t toggle = (d[0] >> 4) & 1u;
    if ((d[0] & 0xEFu) != 0x60) {
        abort_transfer(node, s, CO_ABORT_COMMAND);
        return;
    }
    if (toggle != s->toggle) {
        abort_transfer(node, s, CO_ABORT_TOGGLE);
        return;
    }
    uint8_t r[8] = {0};
    uint32_t n = 0;
    uint32_t total = 0;
    const uint8_t *wire = co_od_wire_data(&node->cfg.od, s->entry, &total);
    if (wire != NULL && s->done <= total) { /* stored in wire form: copy the piece */
        n = total - s->done < SEG_BYTES ? total - s->done : SEG_BYTES;
        if (n == SEG_BYTES) {
            memcpy(&r[1], wire + s->done, SEG_BYTES); /* the usual case, copied inline */
        } else {
            memcpy(&r[1], wire + s->done, n);
        }
    } else {
        co_abort_t abort = read_at(node, s, s->done, &r[1], SEG_BYTES, &n, &total);
        if (abort != CO_ABORT_NONE) {
            abort_transfer(node, s, abort);
            return;
        }
    }
    s->done += n;
    bool last = total != CO_OD_SIZE_UNKNOWN ? s->done >= total : n < SEG_BYTES;
    r[0] = (uint8_t)(((unsigned)toggle << 4) | ((SEG_BYTES - n) << 1) | (last ? 1u : 0u));
    s->toggle ^= 1u;
    send(node, s, r);
    if (last) {
        s->state = IDLE;
    }
}

/* ---- block download */

static void initiate_block_download(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    s->crc_on = d[0] & 0x04u;
    s->size_known = d[0] & 0x02u;
    s->size = co_get_u32(&d[4]);
    co_abort_t abort = check_download_size(s);
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    s->blksize = BLOCK_SIZE_MAX;
    s->seq = 0;
    s->state = BLOCK_DOWN;
    respond(node, s, 0xA4, s->blksize); /* sc = 1: this server checks CRCs */
}

/* One segment of a sub-block. Only the next in-order sequence number is taken; the
 * acknowledgement names the last one taken, so the client repeats what was lost. */
static void block_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t seqno = d[0] & 0x7Fu;
    bool last = d[0] & 0x80u;
    if (seqno == 0 || seqno > s->blksize) {
        abort_transfer(node, s, CO_ABORT_SEQUENCE);
        return;
    }
    bool in_order = seqno == s->seq + 1u;
    if (in_order) {
        if (s->buf_len + SEG_BYTES <= sizeof s->buf) { /* the usual case: room in the buffer */
            memcpy(&s->buf[s->buf_len], &d[1], SEG_BYTES);
            s->buf_len += SEG_BYTES;
        } else {
            co_abort_t abort = collect(node, s, &d[1], SEG_BYTES);
            if (abort != CO_ABORT_NONE) {
                abort_transfer(node, s, abort);
                return;
            }
        }
        s->seq = seqno;
    }
    if (!(last || seqno >= s->blksize)) {
        return;
    }
    uint8_t ack[8] = {0xA2, s->seq, s->blksize};
    send(node, s, ack);
    s->seq = 0;
    if (last && in_order) {
        s->state = BLOCK_DOWN_END;
    }
}

static void block_download_end(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    if ((d[0] & 0xE3u) != 0xC1) {
        abort_transfer(node, s, CO_ABORT_COMMAND);
        return;
    }
    uint32_t unused = (d[0] >> 2) & 7u;
    if (unused > s->buf_len) { /* n = 7: an empty value's only segment */
        abort_transfer(node, s, CO_ABORT_COMMAND);
        return;
    }
    s->buf_len -= unused; /* the last segment's padding */
    if (s->crc_on && co_crc16(s->crc, s->buf, s->buf_len) != co_get_u16(&d[1])) {
        abort_transfer(node, s, CO_ABORT_CRC);
        return;
    }
    co_abort_t abort = finish_download(node, s);
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    uint8_t r[8] = {0xA1};
    send(node, s, r);
    s->state = IDLE;
}

/* ---- block upload */

static uint32_t chunk_cap(const co_sdo_server_t *s) { return (uint32_t)s->blksize * SEG_BYTES; }

/* Load the next sub-block's data from the dictionary at the current offset. */
static co_abort_t load_sub_block(co_node_t *node, co_sdo_server_t *s, uint32_t *total_out)
{
    uint32_t total = 0;
    co_abort_t abort = read_at(node, s, s->done, s->buf, chunk_cap(s), &s->buf_len, &total);
    *total_out = total;
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    s->last_sent =
        total != CO_OD_SIZE_UNKNOWN ? s->done + s->buf_len >= total : s->buf_len < chunk_cap(s);
    s->seq = 0;
    return CO_ABORT_NONE;
}

/* Segments in the loaded sub-block: full ones, and on the final sub-block one more for
 * the remainder (an empty value still sends one segment). */
static uint8_t sub_block_segments(const co_sdo_server_t *s)
{
    uint32_t n = s->buf_len / SEG_BYTES;
    if (s->last_sent && (s->buf_len % SEG_BYTES != 0 || s->buf_len == 0)) {
        n++;
    }
    return (uint8_t)n;
}

/* Send the sub-block's segments while the transmit queue is idle; poll resumes. */
static void pump_sub_block(co_node_t *node, co_sdo_server_t *s)
{
    uint8_t segments = sub_block_segments(s);
    while (s->seq < segments && co_txq_idle(node)) {
        uint32_t offset = (uint32_t)s->seq * SEG_BYTES;
        uint32_t n = s->buf_len - offset < SEG_BYTES ? s->buf_len - offset : SEG_BYTES;
        s->seq++;
        bool final = s->last_sent && s->seq == segments;
        uint8_t d[8] = {(uint8_t)((final ? 0x80u : 0u) | s->seq)};
        memcpy(&d[1], &s->buf[offset], n);
        if (final) {
            s->last_len = (uint8_t)n;
        }
        send(node, s, d);
        refresh(node, s);
    }
}

static void initiate_block_upload(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t blksize = d[4];
    uint8_t pst = d[5];
    if (blksize < 1 || blksize > 127) {
        abort_transfer(node, s, CO_ABORT_BLOCK_SIZE);
        return;
    }
    s->crc_on = d[0] & 0x04u;
    s->blksize = blksize <= BLOCK_SIZE_MAX ? blksize : (uint8_t)BLOCK_SIZE_MAX;
    s->done = 0;
    uint32_t total = 0;
    co_abort_t abort = load_sub_block(node, s, &total);
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    if (pst != 0 && total != CO_OD_SIZE_UNKNOWN && total <= pst) {
        initiate_upload(node, s); /* protocol switch: a normal upload serves it better */
        return;
    }
    s->size_known = total != CO_OD_SIZE_UNKNOWN;
    s->size = s->size_known ? total : 0;
    s->state = BLOCK_UP_START;
    respond(node, s, s->size_known ? 0xC6 : 0xC4, s->size);
}

static void block_upload_ack(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t ackseq = d[1];
    uint8_t blksize = d[2];
    if (ackseq > s->seq) {
        abort_transfer(node, s, CO_ABORT_SEQUENCE);
        return;
    }
    if (blksize < 1 || blksize > 127) {
        abort_transfer(node, s, CO_ABORT_BLOCK_SIZE);
        return;
    }
    uint32_t acked = (uint32_t)ackseq * SEG_BYTES;
    if (acked > s->buf_len) {
        acked = s->buf_len;
    }
    bool all_acked = ackseq == sub_block_segments(s);
    if (s->crc_on) {
        s->crc = co_crc16(s->crc, s->buf, acked);
    }
    s->done += acked;
    if (all_acked && s->last_sent) {
        uint8_t unused = (uint8_t)(SEG_BYTES - s->last_len);
        uint8_t end[8] = {(uint8_t)(0xC1u | ((unsigned)unused << 2)), (uint8_t)s->crc,
                          (uint8_t)(s->crc >> 8)};
        send(node, s, end);
        s->state = BLOCK_UP_END;
        return;
    }
    s->blksize = blksize <= BLOCK_SIZE_MAX ? blksize : (uint8_t)BLOCK_SIZE_MAX;
    uint32_t total = 0;
    co_abort_t abort = load_sub_block(node, s, &total);
    if (abort != CO_ABORT_NONE) {
        abort_transfer(node, s, abort);
        return;
    }
    pump_sub_block(node, s);
}

/* ---- dispatch */

static bool is_initiate(uint8_t cmd)
{
    uint8_t cs = cmd >> 5;
    return cs == 1 || cs == 2 || (cs == 6 && (cmd & 0x01u) == 0) || (cs == 5 && (cmd & 0x03u) == 0);
}

/* A new transfer: find the entry, check the access, and hand over to its initiator. */
static void initiate(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    uint8_t cs = d[0] >> 5;
    bool write = cs == 1 || cs == 6;
    s->state = IDLE;
    s->index = co_get_u16(&d[1]);
    s->sub = d[3];
    s->done = 0;
    s->buf_len = 0;
    s->toggle = 0;
    s->crc = 0;
    co_abort_t abort = CO_ABORT_NO_OBJECT;
    s->entry = co_od_find(&node->cfg.od, s->index, s->sub, &abort);
    if (s->entry != NULL) {
        abort = co_od_access(s->entry, write);
    }
    if (s->entry == NULL || abort != CO_ABORT_NONE) { /* no entry is never served */
        abort_transfer(node, s, abort);
        return;
    }
    if (!CO_CONFIG_SDO_BLOCK && (cs == 5 || cs == 6)) {
        abort_transfer(node, s, CO_ABORT_COMMAND); /* block transfer is left out */
        return;
    }
    switch (cs) {
    case 1:
        initiate_download(node, s, d);
        break;
    case 2:
        initiate_upload(node, s);
        break;
    case 6:
        initiate_block_download(node, s, d);
        break;
    default:
        initiate_block_upload(node, s, d);
        break;
    }
}

/* A frame inside an open transfer. */
static void continue_transfer(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    if (!CO_CONFIG_SDO_BLOCK && s->state >= BLOCK_DOWN) {
        abort_transfer(node, s, CO_ABORT_COMMAND); /* unreachable: no block state is entered */
        return;
    }
    switch (s->state) { /* the segmented states are served before (serve) */
    case BLOCK_DOWN_END:
        block_download_end(node, s, d);
        break;
    case BLOCK_UP_START:
        if (d[0] != 0xA3) {
            abort_transfer(node, s, CO_ABORT_COMMAND);
            break;
        }
        s->state = BLOCK_UP;
        pump_sub_block(node, s);
        break;
    case BLOCK_UP:
        if (d[0] != 0xA2) {
            abort_transfer(node, s, CO_ABORT_COMMAND);
            break;
        }
        block_upload_ack(node, s, d);
        break;
    case BLOCK_UP_END:
        if (d[0] != 0xA1) {
            abort_transfer(node, s, CO_ABORT_COMMAND);
            break;
        }
        s->state = IDLE;
        break;
    default:
        abort_transfer(node, s, CO_ABORT_COMMAND);
        break;
    }
}

static void serve(co_node_t *node, co_sdo_server_t *s, const uint8_t *d);

void co_sdo_server_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame)
{
    if (frame->len != 8 || (frame->flags & CO_FRAME_RTR)) {
        node->stats.rx_malformed++;
        return;
    }
    co_sdo_server_t *s = &node->sdo_servers[channel];
    const uint8_t *d = frame->data;
    if (d[0] == 0x80) { /* abort from the client: end silently */
        s->state = IDLE;
        return;
    }
    node->sdo_serving = true;
    serve(node, s, d);
    node->sdo_serving = false;
    apply_reloads(node);
}

/* One request of an open or new transfer. */
static void serve(co_node_t *node, co_sdo_server_t *s, const uint8_t *d)
{
    if (CO_CONFIG_SDO_BLOCK && s->state == BLOCK_DOWN) { /* every frame a segment */
        block_segment(node, s, d);
    } else if (is_initiate(d[0])) {
        initiate(node, s, d);
    } else if (s->state == IDLE) {
        s->index = 0;
        s->sub = 0;
        abort_transfer(node, s, CO_ABORT_COMMAND);
    } else if (s->state == DOWN_SEGMENTED) { /* the usual segments: no state switch */
        download_segment(node, s, d);
    } else if (s->state == UP_SEGMENTED) {
        upload_segment(node, s, d);
    } else {
        continue_transfer(node, s, d);
    }
    if (s->state != IDLE) {
        refresh(node, s);
    }
}

uint64_t co_sdo_server_poll(co_node_t *node, uint64_t now_us)
{
    uint64_t next = CO_TIME_NEVER;
    for (uint8_t ch = 0; ch < co_sdo_servers_max(); ch++) {
        co_sdo_server_t *s = &node->sdo_servers[ch];
        if (s->state == IDLE) {
            continue;
        }
        if (now_us >= s->deadline_us) {
            abort_transfer(node, s, CO_ABORT_TIMEOUT);
        } else {
            if (CO_CONFIG_SDO_BLOCK && s->state == BLOCK_UP) {
                pump_sub_block(node, s);
            }
            next = co_min_u64(next, s->deadline_us);
        }
    }
    return next;
}
