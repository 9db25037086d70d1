/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/sdo.h -- service data objects: the SDO server of a device and the SDO
 * client of a master or tool. Expedited, segmented and block transfer, both
 * directions, several channels at once.
 *
 * Server. Channel 0 is the default server on 0x600 + node-ID (requests) and
 * 0x580 + node-ID (responses), fixed by CiA 301 whatever the dictionary says: 0x1200 sub1
 * and sub2 with other values (a DCF that marks them not valid, say) are overruled at reset
 * communication, made to read the fixed ones and reported (on_error
 * CO_NODE_ERR_SDO_COB_FIXED); a write of another value is refused (0x06010002). Channel
 * i >= 1 takes its COB-IDs from 0x1200 + i
 * (sub1 client->server, sub2 server->client, bit 31 = not valid) and is off until
 * configured. SDO runs in pre-operational and operational only. Every request
 * frame must be 8 bytes long; other lengths are ignored and counted as
 * malformed. A transfer that sees no frame for the time-out (co_node_config_t
 * .sdo_timeout_ms, default 1000 ms) is aborted with 0x05040000. An abort from
 * the client ends the transfer silently. A new initiate request while a
 * transfer is open ends the open one (no abort is sent for it; the client has
 * evidently given it up) and starts the new one. Any other request that does not
 * fit the transfer's state is answered with 0x05040001 and ends the transfer.
 *
 * Downloads of values up to CO_SDO_BUF_SIZE bytes are collected in the channel's
 * buffer and handed to the object dictionary whole, when the transfer completes:
 * an aborted transfer changes nothing. A DOMAIN or string kept in RAM takes values
 * up to its own size: what does not fit the buffer is received into the entry's
 * storage, and the whole value is checked and stored at the end as usual (its
 * check hook sees all of it; a DOMAIN's length changes only then), but an aborted
 * or refused transfer of that size leaves the bytes received so far in storage.
 * Entries that take their value through a write hook (co_od_hooks_t.write) get it
 * in pieces as it arrives, so a DOMAIN of any size streams through a buffer of a
 * few hundred bytes. Uploads read the
 * dictionary piece by piece (co_od_read with an offset), so read hooks stream too.
 *
 * Block transfer: CRC-16-CCITT (0x1021, initial 0) when both sides support it;
 * the server offers a block size of min(127, CO_SDO_BUF_SIZE / 7); lost or
 * reordered segments are answered by acknowledging the last in-order sequence
 * number so the client repeats from there. A block upload whose size is at most
 * the client's protocol switch threshold is answered as a normal upload.
 *
 * Client. Channel i talks to one server: co_sdo_client_setup() sets its server
 * node-ID and the default COB-IDs (0x600 + n, 0x580 + n); 0x1280 + i in the OD,
 * when present, is kept in step both ways (a write to it reconfigures the channel,
 * and reset communication reloads it from its power-on values, as it does every
 * communication object; a channel without 0x1280 + i keeps its setup). Transfers are asynchronous:
 * start one, the node's ingest/poll drive it, and a completion callback reports the abort code
 * (CO_ABORT_NONE on success) and the bytes transferred. While a transfer waits for the
 * answer to its initiate request, a frame naming another object (index, sub-index) is
 * not its answer: a server's late answer to an earlier request, or another client's
 * answer, is ignored (only the time-out ends the wait). A channel whose server is
 * the node itself reads and writes the node's own dictionary, with no frames.
 *
 * Memory: each server channel holds a CO_SDO_BUF_SIZE + 6 byte buffer and 68 bytes of
 * state on 32-bit targets (76 on 64-bit hosts), rounded up to a multiple of 8; a client channel 80
 * bytes (112), as it works in the caller's buffers. Cost: an expedited request is the look-up (O(1)
 * expected with the dictionary's hash, O(log entries) without) plus O(1); a segment of an open
 * transfer is O(1).
 */
#ifndef CANOLA_SDO_H
#define CANOLA_SDO_H

#include "canola/config.h"
#include "canola/od.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** How a client transfers (the server follows whatever the client asks). */
typedef enum co_sdo_mode {
    CO_SDO_AUTO = 0,      /**< expedited when it fits in 4 bytes, else segmented */
    CO_SDO_EXPEDITED = 1, /**< downloads of 1..4 bytes; for uploads the same as AUTO */
    CO_SDO_SEGMENTED = 2,
    CO_SDO_BLOCK = 3,
} co_sdo_mode_t;

/** Completion of a typed read (co_sdo_read_value): `value` holds the `len` (1..8) bytes
 *  received, little-endian, zero-extended (sign-extend signed types yourself). */
typedef void (*co_sdo_value_fn)(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value,
                                uint32_t len);

/** Completion of a client transfer: `abort` is CO_ABORT_NONE on success, `len` the bytes
 *  uploaded into the caller's buffer or downloaded from it. */
typedef void (*co_sdo_done_fn)(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len);

/** One SDO server channel (embedded in the node; fields are internal). The byte fields come
 *  first (Cortex-M reaches the first 32 bytes of a struct with the short byte loads), the
 *  words in an order without holes, and the one byte field left over after the buffer,
 *  where the struct's padding would be. */
typedef struct co_sdo_server {
    uint8_t sub;
    uint8_t state;
    uint8_t toggle;
    uint8_t blksize;
    uint8_t seq; /**< block: last in-order sequence number (download) / sent (upload) */
    bool size_known;
    bool crc_on;
    bool last_sent;
    uint16_t index;
    uint16_t crc;
    co_frame_t reply; /**< the next response, its header (cob_tx, 8 bytes) set at load */
    const co_od_entry_t *entry;
    uint64_t last_us; /**< time of the transfer's last progress: the time-out counts from it */
#if CO_CONFIG_SDO_SEGMENTED
    const uint8_t *wire; /**< segmented upload: the value's wire bytes in storage, or NULL */
#endif
    uint32_t cob_rx; /**< client -> server; bit 31 = off */
    uint32_t cob_tx; /**< server -> client */
    uint32_t size;   /**< indicated or known total size */
    uint32_t done;   /**< bytes transferred so far */
    uint32_t buf_len;
    /** Segmented and block transfers' data (+ room for a block's last segment padding);
     *  an expedited-only server needs none. */
    uint8_t buf[CO_CONFIG_SDO_SEGMENTED || CO_CONFIG_SDO_BLOCK ? CO_SDO_BUF_SIZE + 6 : 1];
    uint8_t last_len; /**< block upload: bytes in the final segment sent */
    bool resent;      /**< block upload: the client acknowledged nothing of the sub-block sent */
} co_sdo_server_t;

/** One SDO client channel (embedded in the node; fields are internal). */
typedef struct co_sdo_client {
    co_sdo_done_fn done_fn;
    void *done_ctx;
    uint8_t *up_buf;        /**< upload destination */
    const uint8_t *dn_data; /**< download source */
    uint64_t deadline_us;
    uint32_t cob_tx; /**< client -> server (0x600 + n); bit 31 = off */
    uint32_t cob_rx; /**< server -> client (0x580 + n) */
    uint32_t cap;    /**< upload buffer capacity / download length */
    uint32_t size;   /**< indicated size (upload) */
    uint32_t done;   /**< bytes transferred so far */
    uint16_t index;
    uint8_t sub;
    uint8_t server_id;
    uint8_t state;
    uint8_t mode;
    union {
        uint8_t toggle; /**< segmented: the toggle bit of the next segment */
        uint8_t seen;   /**< block upload: highest seqno seen, block download: sub-blocks
                             repeated, both since the last progress (time-out rule) */
    };
    uint8_t blksize; /**< block size asked for (uploads) / granted (downloads) */
    uint8_t seq;
    bool size_known;
    bool crc_on;
    bool use_crc;         /**< offer CRC in block transfers (default true) */
    uint8_t want_blksize; /**< block size to ask for, 1..127 (default 127) */
    uint8_t pst;          /**< protocol switch threshold for block uploads (default 0) */
    uint16_t timeout_ms;  /**< time-out per answer; 0: the node's (co_node_config_t) */
    /* co_sdo_read_value / co_sdo_write_value */
    co_sdo_value_fn value_fn;
    co_sdo_done_fn value_done_fn;
    void *value_ctx;
    uint8_t value[8];
} co_sdo_client_t;

/* ---- client */

/** Point client channel `channel` at server `server_id` (1..127) with the default COB-IDs.
 *  Returns CO_ERR_ARG for a bad channel or node-ID, CO_ERR_BUSY during a transfer,
 *  CO_ERR_STATE when another channel already talks to that server (both would listen to
 *  the same response COB-ID). */
co_err_t co_sdo_client_setup(co_node_t *node, uint8_t channel, uint8_t server_id);

/** Block transfer options of a channel: block size 1..127 asked for, CRC offered, protocol
 *  switch threshold for uploads (0 = never switch). Returns CO_ERR_ARG on a bad value. */
co_err_t co_sdo_client_block_options(co_node_t *node, uint8_t channel, uint8_t blksize, bool crc,
                                     uint8_t pst);

/** The channel's time-out per answer: a transfer whose server stays silent `timeout_ms`
 *  after the last frame is aborted with 0x05040000 (also sent to the server). A block
 *  transfer's server that makes no progress is timed out all the same: in an upload a
 *  segment restarts the time-out only when it is kept or numbered beyond all seen since
 *  the last acknowledged progress (a sequence number outside 1..blksize is aborted at once
 *  with 0x05040003); in a download an acknowledgement of no segment restarts it once, for
 *  one repetition of the sub-block, not again until one is acknowledged. 0 returns to
 *  the node's co_node_config_t.sdo_timeout_ms. Takes effect with the next frame; kept
 *  across setups and resets. Returns CO_ERR_ARG for a bad channel. */
co_err_t co_sdo_client_set_timeout(co_node_t *node, uint8_t channel, uint16_t timeout_ms);

/** Start reading (index, sub) of the channel's server into `buf` (capacity `cap`; must stay
 *  valid until `done` runs). A value longer than `cap` aborts with 0x05040005 (also sent to
 *  the server). Returns CO_ERR_BUSY when the channel is in a transfer, CO_ERR_STATE when it
 *  is not set up, CO_ERR_ARG for bad arguments. With the node itself as server `done` runs
 *  before this returns. */
co_err_t co_sdo_upload(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                       co_sdo_mode_t mode, uint8_t *buf, uint32_t cap, co_sdo_done_fn done,
                       void *ctx);

/** Start writing `len` bytes of `data` (valid until `done` runs) to (index, sub). Errors as
 *  co_sdo_upload; CO_SDO_EXPEDITED with len 0 or > 4 is CO_ERR_ARG. */
co_err_t co_sdo_download(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                         co_sdo_mode_t mode, const uint8_t *data, uint32_t len, co_sdo_done_fn done,
                         void *ctx);

/* ---- one-call typed access for C masters */

/** Read a value of up to 8 bytes (any integer, REAL or BOOLEAN entry) of the channel's
 *  server; `done` gets it decoded. A longer value aborts with 0x05040005. Errors as
 *  co_sdo_upload. */
co_err_t co_sdo_read_value(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                           co_sdo_value_fn done, void *ctx);

/** Write the low `size` (1..8) bytes of `value` to (index, sub), little-endian, expedited
 *  when size <= 4. Returns CO_ERR_ARG for another size, else as co_sdo_download. */
co_err_t co_sdo_write_value(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                            uint64_t value, uint8_t size, co_sdo_done_fn done, void *ctx);

/** Abort the channel's transfer with `code` (sent to the server); `done` runs with it.
 *  Returns CO_ERR_STATE when no transfer is open. */
co_err_t co_sdo_client_abort(co_node_t *node, uint8_t channel, co_abort_t code);

/** True while the channel has a transfer open. */
bool co_sdo_client_busy(const co_node_t *node, uint8_t channel);

/** Progress of the channel's transfer: the bytes moved so far (uploads: received; downloads:
 *  sent, and in a block download those the server acknowledged), for a progress display
 *  polled from outside. After the transfer's end the figure of its last step stays until
 *  the next transfer begins. 0 for a bad channel. Cost: a field read. */
uint32_t co_sdo_client_progress(const co_node_t *node, uint8_t channel);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_SDO_H */
