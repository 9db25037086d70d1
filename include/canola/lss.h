/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/lss.h -- layer setting services (CiA 305): give a node its node-ID and bit
 * rate over the bus, and find devices that have none.
 *
 * Two fixed COB-IDs, every frame 8 bytes, byte 0 the command specifier (cs):
 * master -> slaves on 0x7E5, slave -> master on 0x7E4. Frames of another length and
 * RTRs are ignored and counted in stats.rx_malformed, as are unknown specifiers on 0x7E5
 * (the master ignores answers it does not wait for). LSS runs in every NMT state,
 * initialisation included.
 *
 *   cs    request (0x7E5)                        answer (0x7E4)
 *   0x04  switch state global [mode]             none (0 = waiting, 1 = configuration)
 *   0x40  switch state selective: vendor u32     -
 *   0x41  ... product u32                        -
 *   0x42  ... revision u32                       -
 *   0x43  ... serial u32                         0x44 when all four matched
 *   0x11  configure node-ID [id]                 0x11 [error, spec error]
 *   0x13  configure bit timing [table, index]    0x13 [error, spec error]
 *   0x15  activate bit timing [delay ms u16]     none
 *   0x17  store configuration                    0x17 [error, spec error]
 *   0x46..0x4B identify remote slave: vendor, product, revision low/high, serial
 *         low/high (u32 each)                    0x4F from every slave in the ranges
 *   0x4C  identify non-configured remote slave   0x50 from every slave without node-ID
 *   0x51  fastscan [id u32, bit checked, sub, next]  0x4F
 *   0x5A..0x5D inquire vendor/product/revision/serial  same cs, u32
 *   0x5E  inquire node-ID                        0x5E [active node-ID]
 *
 * Slave. Built in with CO_CONFIG_LSS_SLAVE (default 1): every node answers on 0x7E5. Its
 * LSS address is 0x1018 sub1..4 (vendor, product, revision, serial) of its dictionary.
 * It is in the LSS waiting state until a switch state command puts it in
 * configuration; the configure, inquire and store commands only work there (ignored in
 * waiting). A configured node-ID is pending: 1..127, or 0xFF to make the node
 * unconfigured; anything else is refused with error 1. The pending node-ID becomes the
 * node's node-ID
 *   - at once when the node has none (0xFF) and the master switches it back to
 *     waiting: the node then runs reset communication and boots with it (boot-up
 *     0x700 + id, every COB-ID derived from it);
 *   - otherwise at the next reset communication.
 * Reset application (reset node) restores the pending node-ID to the stored one (the
 * node_id the node was initialised with, or the last one stored by 0x17): a node-ID that
 * must outlive a reset node or a power cycle must be stored (store configuration), and the
 * application must start the node with the stored one (co_node_config_t.node_id; the Linux
 * port keeps it in lss.params: co_file_storage_store_lss / _load_lss, which canola-node
 * --store and canola.Device(store_dir=...) use).
 * Bit timing: table 0 only (CiA 301 rates: index 0 = 1000, 1 = 800, 2 = 500, 3 = 250,
 * 4 = 125, 6 = 50, 7 = 20, 8 = 10 kbit/s); a rate is accepted when its bit is set in
 * co_lss_slave_config_t.bit_timings. Activate: no service of the node sends or takes a
 * frame for 2 x `delay` ms (frames waiting in the queue are dropped; the application's
 * own co_node_send frames are its business); after the first `delay` the slave calls
 * on_bit_timing (the application switches its controller). Store: through the application's store
 * callback; none = error 1. 0x4C is answered by every slave without node-ID (0xFF), fastscan only
 * by those that are also in waiting; a fastscan that completes the 128-bit match (bit checked 0,
 * sub 3 -> next 0) puts that slave in configuration.
 *
 * Master. Built in with CO_CONFIG_LSS_MASTER (default 1). One request at a time, asynchronous
 * like the SDO client: start it, the node's ingest/poll drive it, a completion callback
 * gets a co_lss_result_t. Every request with an answer times out after the master's
 * time-out (co_lss_master_set_timeout, default 100 ms); requests whose answer may come
 * from several slaves (identify, fastscan steps) always wait the whole time-out, so an
 * answer that arrives late never counts for the next step. Fastscan costs 134 time-outs
 * per device (the reset, 32 bits and a verify per address part, the last verify once
 * more); a part given as known skips its 32 bit checks. A fastscan above an address (the
 * way past slaves that answer fastscan in configuration) costs at most 7 + 2 x b
 * time-outs when only the serial numbers differ, b the highest bit in which they do, and
 * at most 270.
 *
 * Threading and memory as the node (canola/node.h): the slave's state is 56 bytes and
 * the master's 80 bytes inside co_node_t (x86-64); no allocation.
 */
#ifndef CANOLA_LSS_H
#define CANOLA_LSS_H

#include "canola/config.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

#define CO_LSS_COB_MASTER 0x7E5u /**< master -> slaves */
#define CO_LSS_COB_SLAVE 0x7E4u  /**< slave -> master */

/** Command specifiers. */
enum {
    CO_LSS_CS_SWITCH_GLOBAL = 0x04,
    CO_LSS_CS_CONFIG_NODE_ID = 0x11,
    CO_LSS_CS_CONFIG_BIT_TIMING = 0x13,
    CO_LSS_CS_ACTIVATE_BIT_TIMING = 0x15,
    CO_LSS_CS_STORE = 0x17,
    CO_LSS_CS_SWITCH_SEL_VENDOR = 0x40,
    CO_LSS_CS_SWITCH_SEL_PRODUCT = 0x41,
    CO_LSS_CS_SWITCH_SEL_REVISION = 0x42,
    CO_LSS_CS_SWITCH_SEL_SERIAL = 0x43,
    CO_LSS_CS_SWITCH_SEL_ANSWER = 0x44,
    CO_LSS_CS_IDENT_VENDOR = 0x46,
    CO_LSS_CS_IDENT_PRODUCT = 0x47,
    CO_LSS_CS_IDENT_REV_LOW = 0x48,
    CO_LSS_CS_IDENT_REV_HIGH = 0x49,
    CO_LSS_CS_IDENT_SERIAL_LOW = 0x4A,
    CO_LSS_CS_IDENT_SERIAL_HIGH = 0x4B,
    CO_LSS_CS_IDENT_NON_CONFIGURED = 0x4C,
    CO_LSS_CS_IDENT_ANSWER = 0x4F,
    CO_LSS_CS_NON_CONFIGURED_ANSWER = 0x50,
    CO_LSS_CS_FASTSCAN = 0x51,
    CO_LSS_CS_INQUIRE_VENDOR = 0x5A,
    CO_LSS_CS_INQUIRE_PRODUCT = 0x5B,
    CO_LSS_CS_INQUIRE_REVISION = 0x5C,
    CO_LSS_CS_INQUIRE_SERIAL = 0x5D,
    CO_LSS_CS_INQUIRE_NODE_ID = 0x5E,
};

/** LSS states of a slave. */
typedef enum co_lss_mode {
    CO_LSS_WAITING = 0,
    CO_LSS_CONFIGURATION = 1,
} co_lss_mode_t;

/** A 128-bit LSS address (0x1018 sub1..4). */
typedef struct co_lss_address {
    uint32_t vendor;
    uint32_t product;
    uint32_t revision;
    uint32_t serial;
} co_lss_address_t;

/* ---- slave */

/** What the application gives the slave; every member may be 0 / NULL. */
typedef struct co_lss_slave_config {
    /** Bit i set: table-0 bit timing index i is supported (configure bit timing). */
    uint16_t bit_timings;
    /** Switch the controller to table-0 index `index` (activate bit timing). */
    void (*on_bit_timing)(void *ctx, uint8_t index);
    /** Store node-ID and bit timing index persistently (store configuration); the bit
     *  timing is 0xFF when none was configured (keep the stored one). Return CO_OK, or an
     *  error (answered as error 2, storage media access error). */
    co_err_t (*store)(void *ctx, uint8_t node_id, uint8_t bit_timing);
    void *ctx;
} co_lss_slave_config_t;

/** Slave state (embedded in the node; fields are internal). */
typedef struct co_lss_slave {
    co_lss_slave_config_t cfg;
    uint64_t bit_timing_due_us; /**< when to call on_bit_timing (if armed) */
    uint64_t quiet_until_us;    /**< send nothing before this (after a bit rate switch) */
    uint8_t mode;               /**< co_lss_mode_t */
    uint8_t pending_id;         /**< node-ID taken at the next reset communication */
    uint8_t stored_id;          /**< node-ID restored by reset application */
    uint8_t bit_timing;         /**< pending bit timing index (0xFF: none configured) */
    uint8_t selective;          /**< switch state selective: parts matched so far */
    uint8_t ident;              /**< identify remote slave: parts matched so far */
    uint8_t fastscan_pos;       /**< fastscan: address part being checked (LSSPos) */
    bool bit_timing_armed;      /**< activate bit timing received, not yet applied */
} co_lss_slave_t;

/** Set the slave's callbacks and supported bit timings (any time; copied). Returns
 *  CO_ERR_ARG for NULL, CO_ERR_STATE when the slave is not built in. */
co_err_t co_lss_slave_setup(co_node_t *node, const co_lss_slave_config_t *config);

/** The slave's LSS state. */
co_lss_mode_t co_lss_slave_mode(const co_node_t *node);

/* ---- master */

/** How a master request ended. */
typedef enum co_lss_status {
    CO_LSS_OK = 0,      /**< answered (and, for configure/store, accepted) */
    CO_LSS_TIMEOUT,     /**< no answer within the time-out (fastscan: no slave found) */
    CO_LSS_REFUSED,     /**< the slave answered with an error: see error, spec_error */
    CO_LSS_SCAN_FAILED, /**< fastscan: a slave stopped answering half-way */
    CO_LSS_CANCELLED,   /**< co_lss_master_cancel */
} co_lss_status_t;

/** Result of a master request, given to its completion callback. */
typedef struct co_lss_result {
    uint8_t cs;               /**< the request's command specifier */
    uint8_t status;           /**< co_lss_status_t */
    uint8_t error;            /**< configure/store: the slave's error code (0 = success) */
    uint8_t spec_error;       /**< ... and its manufacturer-specific error */
    uint32_t value;           /**< inquire: the value (node-ID in the low byte) */
    uint16_t answers;         /**< identify: answers counted during the time-out */
    bool keeps_answering;     /**< fastscan: the slave found answers fastscan in
                                   configuration too (see co_lss_fastscan) */
    co_lss_address_t address; /**< fastscan: the address found */
} co_lss_result_t;

typedef void (*co_lss_done_fn)(void *ctx, const co_lss_result_t *result);

/** Fastscan request: address parts known in advance (bit i of `known` set: part i of
 *  `address`, 0 vendor .. 3 serial, is checked whole instead of bit by bit); or, with
 *  `above`, the lowest address greater than `address` (`known` unused). */
typedef struct co_lss_fastscan {
    co_lss_address_t address;
    uint8_t known;
    bool above;
} co_lss_fastscan_t;

/** Master state (embedded in the node; fields are internal). */
typedef struct co_lss_master {
    co_lss_done_fn done;
    void *ctx;
    uint64_t deadline_us;
    uint32_t timeout_ms;
    uint32_t scan[4]; /**< fastscan: address being found */
    co_lss_result_t result;
    uint8_t op;     /**< request cs in progress, 0 = idle */
    uint8_t known;  /**< fastscan: known parts */
    uint8_t sub;    /**< fastscan: part being checked, 4 = done */
    int8_t bit;     /**< fastscan: bit being checked, -1 = verify the part */
    uint8_t phase;  /**< fastscan: walk, or (above an address) prefix or ascend */
    uint8_t target; /**< fastscan above an address: the part it may first differ in */
    bool heard;     /**< an answer arrived during this step */
    bool listening; /**< route 0x7E4 installed */
} co_lss_master_t;

/** Time-out of every request (ms, 1..65535; default 100). Returns CO_ERR_ARG for 0. */
co_err_t co_lss_master_set_timeout(co_node_t *node, uint32_t timeout_ms);

/** True while a request is in progress. */
bool co_lss_master_busy(const co_node_t *node);

/** End the request in progress; its callback runs with CO_LSS_CANCELLED. CO_ERR_STATE
 *  when idle. */
co_err_t co_lss_master_cancel(co_node_t *node);

/* Requests without an answer: sent at once, CO_OK (CO_ERR_ARG for a bad argument). */

/** Switch every slave to `mode`. */
co_err_t co_lss_switch_global(co_node_t *node, co_lss_mode_t mode);
/** Activate the configured bit timing on every slave in configuration after `delay_ms`. */
co_err_t co_lss_activate_bit_timing(co_node_t *node, uint16_t delay_ms);

/* Requests with an answer. Each returns CO_ERR_BUSY while another request runs,
 * CO_ERR_ARG for a bad argument, CO_ERR_STATE when the master is not built in, else CO_OK;
 * `done` (may be NULL) runs exactly once, later, from the node's ingest or poll. */

/** Switch the slave with this address to configuration (answer 0x44). */
co_err_t co_lss_switch_selective(co_node_t *node, const co_lss_address_t *address,
                                 co_lss_done_fn done, void *ctx);
/** Configure the node-ID (1..127 or 0xFF) of the slave in configuration. */
co_err_t co_lss_configure_node_id(co_node_t *node, uint8_t node_id, co_lss_done_fn done, void *ctx);
/** Configure the bit timing (`table` 0: CiA 301 index) of the slave in configuration. */
co_err_t co_lss_configure_bit_timing(co_node_t *node, uint8_t table, uint8_t index,
                                     co_lss_done_fn done, void *ctx);
/** Make the slave in configuration store its node-ID and bit timing. */
co_err_t co_lss_store(co_node_t *node, co_lss_done_fn done, void *ctx);
/** Inquire one value of the slave in configuration: `cs` is CO_LSS_CS_INQUIRE_VENDOR ..
 *  CO_LSS_CS_INQUIRE_NODE_ID. */
co_err_t co_lss_inquire(co_node_t *node, uint8_t cs, co_lss_done_fn done, void *ctx);
/** Ask whether slaves with low->vendor, low->product, revision in [low->revision,
 *  high->revision] and serial in [low->serial, high->serial] exist: status OK with the
 *  answer count, or TIMEOUT when none answered (high's vendor and product are unused). */
co_err_t co_lss_identify_remote(co_node_t *node, const co_lss_address_t *low,
                                const co_lss_address_t *high, co_lss_done_fn done, void *ctx);
/** Ask whether slaves without node-ID exist (OK with the count, or TIMEOUT). */
co_err_t co_lss_identify_non_configured(co_node_t *node, co_lss_done_fn done, void *ctx);
/** Find one slave without node-ID by fastscan: OK with its address (that slave is now
 *  in configuration), TIMEOUT when no slave answered the reset, SCAN_FAILED when the
 *  answers stopped half-way. `scan` may be NULL (nothing known). A slave that answers
 *  every fastscan request while in configuration (CANopenNode's) would confirm every bit
 *  of the next scan: the final verify is sent once more, and result.keeps_answering says
 *  that it answered; switch that slave back to waiting (co_lss_switch_global) before the
 *  next scan, which then finds it again unless it was given a node-ID, or scan `above`
 *  its address: slaves are found lowest address first, so a scan above the last one found
 *  finds the next. */
co_err_t co_lss_fastscan(co_node_t *node, const co_lss_fastscan_t *scan, co_lss_done_fn done,
                         void *ctx);

/** Name of a status ("ok", "time-out", ...). */
const char *co_lss_status_name(uint8_t status);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_LSS_H */
