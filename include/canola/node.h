/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/node.h -- a CANopen node: the object that owns every service of one
 * device (or master) and the only entry points the driver and the clock use.
 *
 * Data flows one way. The driver hands each received frame to
 * co_node_ingest(); the node finds the frame's COB-ID in its receive routes (a
 * sorted table in which each service keeps the COB-IDs it listens to; O(log
 * routes), no scan over services), checks that the NMT state allows the
 * service, and the service updates its state and the object dictionary. Frames to send go out
 * through the driver's tx callback; when it reports CO_ERR_BUSY they wait in a
 * bounded queue (CO_TX_QUEUE_LEN) ordered by priority (lowest COB-ID first,
 * first-in first-out among equal IDs) and leave on the next co_node_poll().
 * Time moves only when the caller says so: co_node_poll(node, now_us) runs what
 * is due and returns the absolute time at which it next needs to run.
 *
 * A driver port does three things:
 *   1. call co_node_ingest() for every received frame,
 *   2. call co_node_poll() at the time it last returned (a timer), and again
 *      as soon as the CAN controller can take a frame after tx said busy,
 *   3. implement tx(); co_node_accepts() tells it which IDs to let through its
 *      hardware filter (on_routes_changed says when that set changed).
 *
 * The node's clock is the time of the latest co_node_ingest()/co_node_poll(); the
 * functions an application calls in between (start an SDO transfer, write 0x1017, add a
 * guarding watch) time themselves from it. A loop that may have slept long should call
 * co_node_poll(node, now) before such calls: it is cheap and also runs what is due.
 *
 * Threading: none inside. All calls on one node must be serialised by the
 * caller (one task, or one lock). Callbacks run inside the call that caused
 * them and may call co_node_* functions except co_node_ingest/co_node_poll.
 * Memory: all state lives in co_node_t, which the caller owns; no allocation.
 */
#ifndef CANOLA_NODE_H
#define CANOLA_NODE_H

#include "canola/config.h"
#include "canola/emcy.h"
#include "canola/errctl.h"
#include "canola/lss.h"
#include "canola/manager.h"
#include "canola/nmt.h"
#include "canola/od.h"
#include "canola/pdo.h"
#include "canola/program.h"
#include "canola/sdo.h"
#include "canola/storage.h"
#include "canola/sync.h"
#include "canola/time.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Node-ID of a node not configured yet (LSS assigns one later). */
#define CO_NODE_ID_UNCONFIGURED 0xFFu

/** The CAN driver as the core sees it. */
typedef struct co_driver {
    /** Send one frame now. Return CO_OK when the controller took it, CO_ERR_BUSY when it
     *  has no room (the node keeps the frame and retries on the next poll); any other
     *  error drops the frame and counts it in stats.tx_dropped. */
    co_err_t (*tx)(void *ctx, const co_frame_t *frame);
    /** Optional: the set of received COB-IDs changed (reprogram hardware filters). */
    void (*on_routes_changed)(void *ctx);
    void *ctx;
} co_driver_t;

/** What the node reports about itself (besides bus events, which are counters). */
typedef enum co_node_error {
    CO_NODE_ERR_TX_OVERFLOW = 1, /**< the tx queue was full: a frame was lost */
    CO_NODE_ERR_TX_DRIVER,       /**< the driver refused a frame with an error */
    CO_NODE_ERR_STORED_COMM,     /**< stored communication parameters failed their checks:
                                      ignored, defaults in use (canola/storage.h) */
    CO_NODE_ERR_STORED_APP,      /**< the same for the application parameters */
    CO_NODE_ERR_STORE_FAILED,    /**< a save or restore (0x1010/0x1011) failed: the stored
                                      images are as they were, EMCY 0x5530 (storage.h) */
    CO_NODE_ERR_SDO_COB_FIXED,   /**< the dictionary gives 0x1200 sub1/sub2 other COB-IDs
                                      than CiA 301 fixes (0x600/0x580 + node-ID): the
                                      default SDO server serves on those regardless, and
                                      0x1200 reads them (canola/sdo.h); at reset
                                      communication */
} co_node_error_t;

typedef struct co_node_config {
    uint8_t node_id;         /**< 1..127, or CO_NODE_ID_UNCONFIGURED */
    bool self_start;         /**< enter OPERATIONAL by itself after boot-up */
    uint16_t boot_time_ms;   /**< report consumed nodes not heard this long after reset
                                  communication (CO_EC_NOT_BOOTED); 0 = off */
    uint16_t sdo_timeout_ms; /**< SDO server and client time-out; 0 = 1000 ms */
    co_od_t od;              /**< the object dictionary; its entries must outlive the node */
    co_driver_t driver;
    const co_storage_t *storage; /**< parameter storage (0x1010/0x1011), or NULL */
    void *user;                  /**< first argument of every callback below */
    /** Optional callbacks. */
    void (*on_state)(void *user, co_nmt_state_t state);
    void (*on_reset)(void *user, co_reset_t what);
    void (*on_errctl)(void *user, const co_ec_event_t *event);
    void (*on_error)(void *user, co_node_error_t error);
    void (*on_emcy)(void *user, const co_emcy_msg_t *emcy);    /**< EMCY consumer (0x1028) */
    void (*on_sync)(void *user, uint8_t counter);              /**< every SYNC handled */
    void (*on_time)(void *user, const co_time_of_day_t *time); /**< TIME consumed */
    void (*on_rpdo)(void *user, uint16_t rpdo);                /**< RPDO (0-based) applied */
} co_node_config_t;

/** Counters, never reset by the node (CO_CONFIG_STATS: without it the node keeps none). */
typedef struct co_node_stats {
    uint32_t rx_frames;    /**< frames passed to co_node_ingest */
    uint32_t rx_unrouted;  /**< no service listens to that COB-ID */
    uint32_t rx_gated;     /**< the NMT state does not allow the service */
    uint32_t rx_malformed; /**< wrong length or form for the service: ignored */
    uint32_t tx_frames;    /**< frames the driver took */
    uint32_t tx_queued;    /**< frames that had to wait for the driver */
    uint32_t tx_overflow;  /**< frames lost because the queue was full */
    uint32_t tx_dropped;   /**< frames the driver refused with an error */
    uint32_t tx_gated;     /**< service frames the NMT state no longer allowed to send */
} co_node_stats_t;

/** A frame waiting in the transmit queue and the service that sent it (0: none), kept in
 *  the frame's padding where it has some (2 bytes on the usual targets). Internal. */
typedef union co_txq_slot {
    co_frame_t frame;
    struct {
        uint8_t frame_bytes[offsetof(co_frame_t, data) + CO_FRAME_DATA_MAX];
        uint16_t service;
    } tag;
} co_txq_slot_t;

struct co_node_wiring; /* internal (src/kernel.h) */

/** The node. Fields are internal; read them through the functions below. The small fields
 *  the services use most come first, then the configuration, then the tables: Cortex-M
 *  loads and stores reach the first 32 (bytes), 64 (halfwords) or 128 (words) bytes of a
 *  struct with one short instruction, fields further in cost an instruction more or a
 *  longer one at every use (a few hundred bytes of code in all). */
struct co_node { // NOLINT(clang-analyzer-optin.performance.Padding)
    uint8_t node_id;
    uint8_t nmt_state;
    bool started;
    uint8_t txq_count;
    uint16_t services;       /**< co_service_t bits the current NMT state allows */
    uint16_t route_count;    /**< receive routes, sorted by key (routes[] below) */
    uint16_t tpdo_listeners; /**< active TPDOs a changed value can trigger */
    uint16_t tpdo_sync_end;  /**< 1 + the last active TPDO a SYNC drives (0: none) */
    uint16_t rpdo_sync_end;  /**< 1 + the last active synchronous RPDO (0: none) */
    uint32_t route_groups;   /**< bit (key >> 6) % 32 of every route (and gone): a quick "no" */
    const co_od_entry_t *hb_period;       /**< heartbeat producer: 0x1017 or NULL */
    const struct co_node_wiring *wiring;  /**< the services' calls up (src/kernel.h) */
    uint64_t now_us;                      /**< time of the latest ingest/poll */
    uint64_t next_due_us;                 /**< earliest deadline of any service */
    uint64_t hb_next_us;                  /**< heartbeat producer: the next heartbeat */
    const co_od_entry_t *error_behaviour; /**< 0x1029 sub1 or NULL */

#if CO_CONFIG_STATS
    co_node_stats_t stats;
#endif
    co_sync_t sync;
    co_node_config_t cfg;
    co_time_t time;
    co_emcy_t emcy;
    /* The owners of the receive routes (route_keys below): route kind and slot. Here, after
     * the 2-byte fields, where they fill what would be padding. */
    uint8_t route_kind[CO_RX_ROUTES_MAX];
    uint8_t route_slot[CO_RX_ROUTES_MAX];

#if CO_HB_CONSUMERS_MAX > 0
    /* Heartbeat consumer (0x1016). */
    uint8_t hb_consumer_count; /**< sub-indices of 0x1016 bound (<= CO_HB_CONSUMERS_MAX) */
    uint64_t boot_deadline_us; /**< CO_EC_NOT_BOOTED check, CO_TIME_NEVER when done */
    co_hb_consumer_t hb_consumers[CO_HB_CONSUMERS_MAX];
#endif

#if CO_CONFIG_GUARDING
    /* Node guarding, slave side (0x100C, 0x100D) and master side. */
    const co_od_entry_t *guard_time;
    const co_od_entry_t *life_factor;
    uint64_t life_deadline_us;
    uint8_t guard_toggle;
    bool life_guarding; /**< monitoring started by a first RTR */
    bool life_lost;
    co_guard_watch_t guard_watch[CO_GUARD_WATCH_MAX > 0 ? CO_GUARD_WATCH_MAX : 1];
#endif

    /* Transmit queue, sorted by COB-ID (ties in arrival order). */
    co_txq_slot_t txq[CO_TX_QUEUE_LEN];
    /* Receive routes, sorted by key (then owner): the keys (id, bit 31 set for 29-bit ids);
     * their owners are route_kind and route_slot above (not padded into each). */
    uint32_t route_keys[CO_RX_ROUTES_MAX];

    co_pdo_t rpdo[CO_RPDO_MAX > 0 ? CO_RPDO_MAX : 1];
    co_pdo_t tpdo[CO_TPDO_MAX > 0 ? CO_TPDO_MAX : 1];

    /* SDO channels. */
    co_sdo_server_t sdo_servers[CO_SDO_SERVERS_MAX > 0 ? CO_SDO_SERVERS_MAX : 1];
#if CO_SDO_CLIENTS_MAX > 0
    co_sdo_client_t sdo_clients[CO_SDO_CLIENTS_MAX];
#endif

#if CO_CONFIG_LSS_SLAVE
    co_lss_slave_t lss_slave;
#endif
#if CO_CONFIG_LSS_MASTER
    co_lss_master_t lss_master;
#endif
#if CO_CONFIG_MANAGER
    co_manager_t *manager; /**< attached by co_manager_init, or NULL */
    co_flash_t *flash;     /**< program download in progress, or NULL */
#endif
};

/** Prepare a node: check the config and the object dictionary (co_od_validate), bind the
 *  communication objects it finds. Sends nothing. Returns CO_ERR_ARG for a NULL argument,
 *  a missing tx or a node-ID outside 1..127 and not 0xFF, CO_ERR_CONFIG for a bad OD or
 *  more 0x1016 entries than CO_HB_CONSUMERS_MAX. O(OD entries). */
co_err_t co_node_init(co_node_t *node, const co_node_config_t *config);

/** Power on at `now_us`: reset application, reset communication, boot-up frame,
 *  pre-operational (operational with self_start). An unconfigured node (0xFF) stops
 *  after reset communication and stays INITIALISING. Returns CO_ERR_STATE if already
 *  started. */
co_err_t co_node_start(co_node_t *node, uint64_t now_us);

/** Feed one received frame. Frames nobody listens to, frames a state forbids and
 *  malformed frames are counted and ignored. O(log routes) + the service's cost. */
void co_node_ingest(co_node_t *node, uint64_t now_us, const co_frame_t *frame);

/** Run what is due at `now_us` and retry queued frames. Returns the absolute time of the
 *  next deadline (CO_TIME_NEVER if none). With nothing due: O(1), a few instructions. */
uint64_t co_node_poll(co_node_t *node, uint64_t now_us);

/** True when the node listens to this frame's COB-ID (a perfect acceptance filter). */
bool co_node_accepts(const co_node_t *node, const co_frame_t *frame);

/** Number of receive routes and the i-th routed COB-ID (bit 31 set for 29-bit), for
 *  drivers that program hardware filters (a COB-ID two services listen to comes twice). */
uint32_t co_node_route_count(const co_node_t *node);
uint32_t co_node_route_id(const co_node_t *node, uint32_t i);

/** This node's node-ID (CO_NODE_ID_UNCONFIGURED if none). */
uint8_t co_node_id(const co_node_t *node);

/** The node's counters. In a build without them (CO_CONFIG_STATS 0) counters that are all
 *  zero, always: a tool that prints them links and runs in every configuration. */
const co_node_stats_t *co_node_stats(const co_node_t *node);

/** Queue a frame for sending (or send it now when the queue is empty and the driver
 *  free). Never blocks. Returns CO_ERR_FULL when the queue was full (the frame is lost
 *  and counted), CO_OK otherwise. For the application's own frames (services send theirs
 *  tagged with their service, so that a state change drops what they left waiting). */
co_err_t co_node_send(co_node_t *node, const co_frame_t *frame);

/* ---- Object dictionary access through the node, so that writes take effect on the
 * services (a new 0x1017 period at once, 0x1016 entries reloaded, ...). */

/** Write a wire value as the network would (access rights, length, limits, hooks,
 *  service checks). Returns CO_ABORT_NONE or the CiA abort code. */
co_abort_t co_node_write_net(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len);

/** Read a wire value as the network would: up to `cap` bytes into `buf`, `*len` = bytes
 *  copied. Returns CO_ABORT_NONE or the CiA abort code (CO_ABORT_LEN_HIGH when the value
 *  does not fit into `cap`; CO_ABORT_NO_DATA for a sub-index of 0x1003 above the number
 *  of errors recorded). */
co_abort_t co_node_read_net(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                            uint32_t cap, uint32_t *len);

/** Application write of a wire value: as co_node_write_net but without access rights (the
 *  application may set read-only objects such as the error register); length, limits,
 *  hooks and service checks apply, the new value takes effect on the services at once and
 *  event-driven TPDOs mapping the object are triggered. Hooks see it as any write: a
 *  binding that must tell the application's writes from the network's marks its own
 *  calls. Returns CO_ABORT_NONE or the CiA abort code (CO_ABORT_NO_OBJECT /
 *  CO_ABORT_NO_SUB for an entry the dictionary lacks). Cost: one dictionary look-up and
 *  the write; no allocation, callbacks as for a network write. */
co_abort_t co_node_write_app(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len);

/** Application write of an unsigned/signed integer value (no access rights: the
 *  application may set read-only objects such as the error register). Limits, hooks and
 *  service checks apply. Returns CO_ABORT_NONE or the abort code. */
co_abort_t co_node_set_uint(co_node_t *node, uint16_t index, uint8_t sub, uint64_t value);

/** Application read of an integer entry. Returns CO_ERR_NOT_FOUND / CO_ERR_ARG (not an
 *  integer type) or CO_OK. */
co_err_t co_node_get_uint(const co_node_t *node, uint16_t index, uint8_t sub, uint64_t *value);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_NODE_H */
