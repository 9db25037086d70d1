/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/manager.h -- the CANopen manager of CiA 302-2: an NMT master that boots the
 * network from one description -- checks each slave's identity, downloads its
 * configuration, sets up its heartbeat and starts it -- and reports every failure with
 * the CiA 302 reason.
 *
 * The network description is plain data, one record per node-ID, holding what CiA 302
 * keeps in the master's objects:
 *   0x1F80 NMT start-up: bit 0 NMT master (must be set); bit 1 start all nodes with one
 *          NMT command (node-ID 0) instead of one per slave, used only when every
 *          listed slave booted (so the refused ones stay stopped); bit 2 the master
 *          does not enter operational by itself; bit 3 the master does not start the
 *          slaves (the application does: the manager stops after configuring them);
 *   0x1F81 slave assignment: bit 0 the node is a slave; bit 2 boot it again when it
 *          sends a boot-up later; bit 3 mandatory (the network is not started without
 *          it); bit 4 keep-alive (reset_slaves spares it); other bits are not used;
 *   0x1F84..0x1F88 expected device type, vendor-ID, product code, revision and serial
 *          number (0 = not checked);
 *   0x1F22 concise DCF: the configuration, downloaded entry by entry;
 *   0x1F26/0x1F27 expected configuration date and time: when the slave's 0x1020 sub1
 *          and sub2 hold exactly these, the download is skipped (0/0 = always download);
 *   the heartbeat consumer time the master uses for the slave (its 0x1016 entry).
 *
 * Boot of one slave (the "boot slave" process), in order; the first failure ends it
 * with its reason:
 *   1. read 0x1000: no answer -> B; not the expected device type -> C;
 *   2. read 0x1018 sub1..4 where expected: D vendor, M product, N revision, O serial;
 *   3. read 0x1020 sub1/sub2 when a date/time is expected: equal -> skip step 4;
 *   4. download the concise DCF: a refused entry -> J with the SDO abort code, index
 *      and sub-index (a DCF that ends in the middle of a record: J with abort 0);
 *   5. with a heartbeat time: write the master's 0x1016 entry for the slave (the first
 *      unused one, or the one already naming it; none free -> K) and wait up to that
 *      time for its first heartbeat: none -> K;
 *   6. booted; started (NMT start) when the network runs and 0x1F80 bit 3 is clear.
 * Slaves boot one after the other over SDO client channel `sdo_channel`.
 *
 * The network: co_manager_start() boots every listed slave once. When all mandatory
 * slaves booted, the network starts (0x1F80) and CO_MGR_NETWORK_STARTED is reported;
 * while a mandatory slave failed, CO_MGR_NETWORK_HALTED names it and nothing is started.
 * A slave that failed or was missing and then sends its boot-up is booted again when bit 2
 * of 0x1F81 is set, and always when it is mandatory and the network waits for it; a late
 * slave is started as soon as it is booted if the network runs.
 * A booted slave's heartbeat loss is reported (reason E) and the slave counts as missing
 * until its next boot-up. With reset_slaves, co_manager_start() first sends NMT reset
 * communication to each listed slave without keep-alive, one command per slave (never
 * to all: that would reset the master and unlisted nodes too). Not done: the check
 * that a keep-alive slave is operational (L), software checks (0x1F53/0x1F54), node
 * guarding, boot time (0x1F89), flying master.
 *
 * Memory: co_manager_t (336 bytes on x86-64) and the description table (127 records)
 * belong to the caller; the node keeps a pointer. With a manager the node routes 0x700 + n of every
 * listed slave (CO_RX_ROUTES_MAX grows by 127 when CO_CONFIG_MANAGER is 1). Threading and
 * callbacks as the node's (canola/node.h).
 */
#ifndef CANOLA_MANAGER_H
#define CANOLA_MANAGER_H

#include "canola/config.h"
#include "canola/od.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/* 0x1F80 bits. */
#define CO_MGR_NMT_MASTER 0x01u
#define CO_MGR_START_ALL 0x02u
#define CO_MGR_NO_SELF_START 0x04u
#define CO_MGR_NO_SLAVE_START 0x08u

/* 0x1F81 bits. */
#define CO_MGR_SLAVE 0x01u
#define CO_MGR_BOOT_ON_BOOTUP 0x04u
#define CO_MGR_MANDATORY 0x08u
#define CO_MGR_KEEP_ALIVE 0x10u

/** Why a slave's boot failed: the CiA 302-2 letters. */
typedef enum co_boot_reason {
    CO_BOOT_OK = 0,
    CO_BOOT_NOT_LISTED = 'A',      /**< not a slave in 0x1F81 */
    CO_BOOT_NO_ANSWER = 'B',       /**< no answer to the read of 0x1000 */
    CO_BOOT_DEVICE_TYPE = 'C',     /**< 0x1000 is not 0x1F84 */
    CO_BOOT_VENDOR = 'D',          /**< 0x1018 sub1 is not 0x1F85 */
    CO_BOOT_HEARTBEAT = 'E',       /**< heartbeat lost */
    CO_BOOT_GUARDING = 'F',        /**< node guarding: no answer */
    CO_BOOT_CONFIG = 'J',          /**< configuration download failed */
    CO_BOOT_HEARTBEAT_START = 'K', /**< no heartbeat when error control started */
    CO_BOOT_WAS_OPERATIONAL = 'L', /**< the slave was operational already */
    CO_BOOT_PRODUCT = 'M',         /**< 0x1018 sub2 is not 0x1F86 */
    CO_BOOT_REVISION = 'N',        /**< 0x1018 sub3 is not 0x1F87 */
    CO_BOOT_SERIAL = 'O',          /**< 0x1018 sub4 is not 0x1F88 */
} co_boot_reason_t;

/** What the manager reports. */
typedef enum co_mgr_event_kind {
    CO_MGR_BOOTED = 1,      /**< the slave passed its checks and is configured */
    CO_MGR_STARTED,         /**< the slave was sent NMT start */
    CO_MGR_FAILED,          /**< the slave's boot failed: reason (and abort, index, sub) */
    CO_MGR_LOST,            /**< a booted slave's heartbeat was lost (reason E) */
    CO_MGR_NETWORK_STARTED, /**< every mandatory slave booted; the network was started */
    CO_MGR_NETWORK_HALTED,  /**< a mandatory slave (node) failed: the network waits */
} co_mgr_event_kind_t;

/** One report. Plain data: copy what you need, the pointer dies with the callback. */
typedef struct co_mgr_event {
    uint8_t node_id; /**< the slave (0 for CO_MGR_NETWORK_STARTED) */
    uint8_t kind;    /**< co_mgr_event_kind_t */
    uint8_t reason;  /**< co_boot_reason_t, CO_BOOT_OK when none */
    uint8_t sub;     /**< J: the refused entry's sub-index; C..O: the sub-index read */
    uint16_t index;  /**< J: the refused entry's index; C..O: the index read */
    uint32_t abort;  /**< B, J: the SDO abort code */
    uint32_t value;  /**< C, D, M, N, O: the value the slave reported */
} co_mgr_event_t;

/** The description of one node-ID (all zero: not a slave). */
typedef struct co_mgr_slave {
    uint32_t assignment;  /**< 0x1F81 */
    uint32_t device_type; /**< 0x1F84, 0 = not checked */
    uint32_t vendor;      /**< 0x1F85 */
    uint32_t product;     /**< 0x1F86 */
    uint32_t revision;    /**< 0x1F87 */
    uint32_t serial;      /**< 0x1F88 */
    const uint8_t *dcf;   /**< 0x1F22 concise DCF (must outlive the boot), or NULL */
    uint32_t dcf_len;
    uint32_t config_date;  /**< 0x1F26 */
    uint32_t config_time;  /**< 0x1F27 */
    uint16_t heartbeat_ms; /**< consumer time for this slave, 0 = no heartbeat watch */
} co_mgr_slave_t;

typedef struct co_manager_config {
    uint32_t nmt_startup;         /**< 0x1F80 */
    const co_mgr_slave_t *slaves; /**< 127 records: node-ID n at slaves[n - 1] */
    uint8_t sdo_channel;          /**< SDO client channel the manager may use */
    bool reset_slaves;            /**< reset communication of the slaves before booting */
    void (*on_event)(void *ctx, const co_mgr_event_t *event);
    void *ctx;
} co_manager_config_t;

/** Slave states as co_manager_slave_state() reports them. */
typedef enum co_mgr_slave_state {
    CO_MGR_UNLISTED = 0, /**< not a slave */
    CO_MGR_WAITING,      /**< waiting for its turn to boot */
    CO_MGR_BOOTING,      /**< boot in progress */
    CO_MGR_CONFIGURED,   /**< booted, not started (yet) */
    CO_MGR_RUNNING,      /**< booted and started */
    CO_MGR_FAILED_STATE, /**< boot failed (co_manager_slave_reason says why) */
    CO_MGR_MISSING,      /**< heartbeat lost; waits for its boot-up */
} co_mgr_slave_state_t;

/** The manager (caller-owned; fields are internal). */
typedef struct co_manager {
    co_manager_config_t cfg;
    co_node_t *node;
    uint64_t deadline_us; /**< waiting for the first heartbeat */
    uint32_t dcf_off;     /**< next record in the DCF */
    uint32_t dcf_left;    /**< records still to download */
    uint32_t date;        /**< 0x1020 sub1 as read */
    uint16_t index;       /**< entry being read or written */
    uint8_t sub;
    uint8_t current; /**< slave being booted, 0 = none */
    uint8_t step;
    bool running;
    bool network_started;
    bool restart; /**< the master was reset: start over at the next poll */
    uint8_t state[127];
    uint8_t reason[127];
} co_manager_t;

/** Attach `mgr` to `node` with `config` (copied; the slave table is not). Returns CO_ERR_ARG
 *  for NULL arguments, a missing table or a bad SDO channel, CO_ERR_CONFIG when 0x1F80
 *  bit 0 is clear, CO_ERR_STATE when the manager is not built in (CO_CONFIG_MANAGER 0). */
co_err_t co_manager_init(co_manager_t *mgr, co_node_t *node, const co_manager_config_t *config);

/** Fill a network description (`slaves`: 127 records) and `*nmt_startup` from a master's
 *  dictionary: 0x1F80 sub0, and for node n sub-index n of 0x1F81, 0x1F84..0x1F88,
 *  0x1F26, 0x1F27 and 0x1F22 (a DOMAIN kept in RAM, used in place: it must stay put
 *  while the manager runs); heartbeat times from the master's 0x1016 entries naming a
 *  slave. Missing entries read as 0. Returns CO_ERR_NOT_FOUND without 0x1F80,
 *  CO_ERR_ARG for NULL. O(127 log entries). */
co_err_t co_manager_load_od(const co_od_t *od, co_mgr_slave_t *slaves, uint32_t *nmt_startup);

/** Start the boot of every listed slave (the node must be started). Called again, it
 *  starts over: every slave booted anew, the network started again once the mandatory
 *  ones are back. The master's own reset (reset communication or reset node, from an NMT
 *  command of anyone) starts it over by itself, as CiA 302-2 has the master's start-up
 *  follow its reset: a boot step that the reset cut short is no failure of its slave.
 *  Returns CO_ERR_STATE when the node is not started, CO_ERR_BUSY while a slave's boot is
 *  in progress. */
co_err_t co_manager_start(co_manager_t *mgr);

/** The state and last failure reason of slave `node_id` (1..127). */
co_mgr_slave_state_t co_manager_slave_state(const co_manager_t *mgr, uint8_t node_id);
co_boot_reason_t co_manager_slave_reason(const co_manager_t *mgr, uint8_t node_id);

/** True once the network was started. */
bool co_manager_network_started(const co_manager_t *mgr);

/** A reason as text, e.g. "D: vendor-ID does not match"; "" for CO_BOOT_OK. */
const char *co_boot_reason_text(uint8_t reason);

/** An event kind as text ("booted", "failed", ...). */
const char *co_mgr_event_name(uint8_t kind);

/* ---- concise DCF (0x1F22 format) */

/* Layout: u32 number of records, then per record u16 index, u8 sub-index, u32 size and
 * `size` data bytes, all little-endian. */

/** Check a concise DCF: CO_OK when every record is whole and nothing follows the last,
 *  else CO_ERR_CONFIG. O(records). */
co_err_t co_dcf_check(const uint8_t *dcf, uint32_t len);

/** Append one record to the DCF in `buf` (capacity `cap`, `*off` bytes used; start with
 *  *off = 0, which writes the count first) and count it. For building DCFs in tests and
 *  tools. Returns CO_ERR_FULL when it does not fit, CO_ERR_ARG for NULL. */
co_err_t co_dcf_put(uint8_t *buf, uint32_t cap, uint32_t *off, uint16_t index, uint8_t sub,
                    const uint8_t *data, uint32_t size);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_MANAGER_H */
