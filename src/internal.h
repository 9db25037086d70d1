/*
 * src/internal.h -- what the core's modules tell each other. Not installed.
 */
#ifndef CANOLA_INTERNAL_H
#define CANOLA_INTERNAL_H

#include "build.h"
#include "canola/node.h"

/* Receive route kinds (co_route_t.kind). */
enum co_route_kind {
    CO_ROUTE_NMT = 1,     /* 0x000: NMT command */
    CO_ROUTE_GUARD_RTR,   /* own 0x700 + id: node guarding request (RTR) */
    CO_ROUTE_HB_CONSUMER, /* 0x700 + n: heartbeat of a consumed node (slot = consumer) */
    CO_ROUTE_GUARD_REPLY, /* 0x700 + n: guarding reply of a guarded node (slot = watch) */
    CO_ROUTE_SDO_SERVER,  /* an SDO server's request COB-ID (slot = channel) */
    CO_ROUTE_SDO_CLIENT,  /* an SDO client's response COB-ID (slot = channel) */
    CO_ROUTE_SYNC,        /* 0x1005 */
    CO_ROUTE_TIME,        /* 0x1012, when consuming */
    CO_ROUTE_EMCY,        /* a COB-ID of 0x1028 (slot = consumer entry) */
    CO_ROUTE_RPDO,        /* an RPDO's COB-ID (slot = RPDO) */
    CO_ROUTE_TPDO_RTR,    /* a TPDO's COB-ID, for remote requests (slot = TPDO) */
    CO_ROUTE_LSS_SLAVE,   /* 0x7E5: LSS request */
    CO_ROUTE_LSS_MASTER,  /* 0x7E4: LSS answer */
    CO_ROUTE_MGR_BOOTUP,  /* 0x700 + n of a slave the manager boots (slot = n) */
};

/* COB-ID objects (0x1200, 0x1280, ...): bit 31 = not valid, bit 29 = 29-bit identifier. */
#define CO_COB_INVALID 0x80000000u
#define CO_COB_EXT 0x20000000u

/* A COB-ID object value that names an identifier of its own format: an 11-bit one
 * (bit 29 clear) has nothing in bits 11..28. */
static inline bool co_cob_valid(uint32_t cob)
{
    return (cob & CO_COB_EXT) || (cob & 0x1FFFF800u) == 0;
}

/* Route key of a COB-ID object value. */
static inline uint32_t co_cob_key(uint32_t cob)
{
    return (cob & CO_COB_EXT) ? ((cob & CO_ID_EXT_MAX) | 0x80000000u) : (cob & CO_ID_STD_MAX);
}

/* Frame addressed by a COB-ID object value. */
static inline co_frame_t co_cob_frame(uint32_t cob, uint8_t len)
{
    co_frame_t f = {.id = (cob & CO_COB_EXT) ? (cob & CO_ID_EXT_MAX) : (cob & CO_ID_STD_MAX),
                    .flags = (cob & CO_COB_EXT) ? CO_FRAME_EXT : 0,
                    .len = len};
    return f;
}

/* Heartbeat consumer watch states (co_hb_consumer_t.watch). */
enum co_hb_watch {
    CO_HB_WATCH_UNUSED = 0, /* entry off (node-ID or time 0) */
    CO_HB_WATCH_WAITING,    /* configured; monitoring starts at the next heartbeat */
    CO_HB_WATCH_ACTIVE,     /* monitoring: deadline_us is the time-out */
    CO_HB_WATCH_LOST,       /* timed out; a heartbeat resumes it */
};

#define CO_STATE_NONE 0xFFu /* "no state heard yet" */

/* Table sizes as values: a configuration may set one to 0, and a loop bound that is a
 * literal 0 would make the compiler warn about an always-false comparison. */
static inline uint8_t co_guard_watch_max(void) { return CO_GUARD_WATCH_MAX; }
static inline uint8_t co_sdo_servers_max(void) { return CO_SDO_SERVERS_MAX; }
static inline uint8_t co_sdo_clients_max(void) { return CO_SDO_CLIENTS_MAX; }

static inline uint64_t co_min_u64(uint64_t a, uint64_t b) { return a < b ? a : b; }
/* Milliseconds of a 16-bit object (a period, a time-out) in microseconds: they fit 32 bits,
 * so the multiply is a 32-bit one (no 64-bit helper call on Cortex-M0). */
static inline uint64_t co_ms_to_us(uint16_t ms)
{
    uint32_t us = (uint32_t)ms * 1000u;
    return us;
}
/* Any 32-bit count of milliseconds (guard time x life time factor) in microseconds. */
static inline uint64_t co_long_ms_to_us(uint32_t ms) { return (uint64_t)ms * 1000u; }

/* SDO server and client time-out (co_node_config_t.sdo_timeout_ms, default 1 s). */
static inline uint64_t co_sdo_timeout_us(const co_node_t *node)
{
    uint16_t ms = node->cfg.sdo_timeout_ms;
    return co_ms_to_us(ms ? ms : (uint16_t)1000u);
}

/* Integer value of an optional entry (0 when the OD lacks it). */
static inline uint64_t co_entry_uint(const co_od_entry_t *entry)
{
    if (entry == NULL) {
        return 0;
    }
    /* The communication objects read on every SYNC or poll are u8/u16/u32 in storage:
     * read them in place (a short path); any other type takes the general one. */
    if (CO_SHORT_PATHS && entry->value != NULL) {
        switch (entry->type) {
        case CO_TYPE_UNSIGNED8:
            return *(const uint8_t *)entry->value;
        case CO_TYPE_UNSIGNED16:
            return *(const uint16_t *)entry->value;
        case CO_TYPE_UNSIGNED32:
            return *(const uint32_t *)entry->value;
        default:
            break;
        }
    }
    return co_od_entry_uint(entry);
}

/* The types whose native storage is their wire form (as in od.c: numbers as wide as their
 * wire form, on a little-endian host; BOOLEAN is left to the general paths, which check
 * that a written value is 0 or 1), as bits of a mask indexed by type code. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define CO_WIRE_NATIVE_TYPES                                                                       \
    ((1u << CO_TYPE_INTEGER8) | (1u << CO_TYPE_INTEGER16) | (1u << CO_TYPE_INTEGER32) |            \
     (1u << CO_TYPE_UNSIGNED8) | (1u << CO_TYPE_UNSIGNED16) | (1u << CO_TYPE_UNSIGNED32) |         \
     (1u << CO_TYPE_REAL32) | (1u << CO_TYPE_REAL64) | (1u << CO_TYPE_INTEGER64) |                 \
     (1u << CO_TYPE_UNSIGNED64))
#else
#define CO_WIRE_NATIVE_TYPES 0u
#endif

/* A readable entry of a validated table whose storage is its wire value (`size` bytes at
 * `value`): the SDO server answers from it without co_od_read. */
static inline bool co_od_reads_plain(const co_od_entry_t *e)
{
    return ((CO_WIRE_NATIVE_TYPES >> (e->type & 31u)) & 1u) &&
           (e->hooks == NULL || e->hooks->read == NULL);
}

/* A writable entry whose new value is just its `size` wire bytes copied into storage: no
 * hook, no limits (co_od_check would accept any value of the right length, co_od_store
 * would copy it). */
static inline bool co_od_writes_plain(const co_od_entry_t *e)
{
    return ((CO_WIRE_NATIVE_TYPES >> (e->type & 31u)) & 1u) && e->hooks == NULL &&
           e->limits == NULL && e->value != NULL;
}

/* Copy a number of 1, 2, 4 or 8 bytes (anything else copies 8): fixed-size moves, no
 * library call, so a loop around it needs no saved registers (the short paths' copies). */
static inline void co_copy_number(void *dst, const void *src, uint32_t bytes)
{
    switch (bytes) {
    case 1:
        memcpy(dst, src, 1);
        break;
    case 2:
        memcpy(dst, src, 2);
        break;
    case 4:
        memcpy(dst, src, 4);
        break;
    default:
        memcpy(dst, src, 8);
        break;
    }
}

/* Route key: the identifier, bit 31 marking 29-bit identifiers. */
static inline uint32_t co_route_key(const co_frame_t *frame)
{
    return frame->id | ((frame->flags & CO_FRAME_EXT) ? 0x80000000u : 0u);
}

/* Bit of a route key in co_node_t.route_groups: its block of 64 identifiers, modulo 32. */
static inline uint32_t co_route_group(uint32_t key) { return 1u << ((key >> 6) & 31u); }

/* co_sync_in_window, inline for the PDO paths that ask at every SYNC and synchronous RPDO. */
static inline bool co_sync_window_open(const co_node_t *node, uint64_t now_us)
{
    uint64_t last = node->sync.last_us;
    if (last == CO_TIME_NEVER || now_us < last) {
        return false;
    }
    uint32_t window = (uint32_t)co_entry_uint(node->sync.window);
    return window == 0 || now_us - last < window;
}

/* Stand-ins for the functions of a feature left out of the build (canola/config.h): the
 * feature's header part below maps each of its functions onto one of these no-ops. */
static inline void co_none_node(co_node_t *node) { (void)node; }
static inline uint64_t co_none_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
static inline void co_none_slot_frame(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)node;
    (void)slot;
    (void)frame;
}
static inline void co_none_entry(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
static inline co_abort_t co_none_check(co_node_t *node, const co_od_entry_t *entry,
                                       const uint8_t *data, uint32_t len)
{
    (void)node;
    (void)entry;
    (void)data;
    (void)len;
    return CO_ABORT_NONE;
}
static inline bool co_none_node_id(const co_node_t *node, uint8_t node_id)
{
    (void)node;
    (void)node_id;
    return false;
}
static inline bool co_none_state(const co_node_t *node)
{
    (void)node;
    return false;
}

/* node.c */
void co_node_schedule(co_node_t *node, uint64_t due_us);
void co_node_ec_event(co_node_t *node, co_ec_event_kind_t kind, uint8_t node_id, uint8_t state,
                      uint8_t previous);
/* Communication lost (heartbeat or life guarding): EMCY 0x8130 and the error behaviour
 * of 0x1029 sub1. Resumed: 0x8130 clears once nothing is lost any more. */
void co_node_comm_lost(co_node_t *node);
void co_node_comm_resumed(co_node_t *node);
/* Apply the communication error behaviour of 0x1029 sub1 (also for bus-off). */
void co_node_error_behaviour(co_node_t *node);
void co_node_state_changed(co_node_t *node);
/* The dictionary's value of an optional integer entry, `absent` when it lacks it (or it is
 * no integer): the services' parameters, 32 bits at most. */
uint32_t co_od_u32(const co_node_t *node, uint16_t index, uint8_t sub, uint32_t absent);
/* A whole new value for an entry, with checks, service effects and hooks (no access rights). */
co_abort_t co_node_write_entry(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len);

/* routes.c */
void co_routes_rebuild(co_node_t *node);
/* Add a route while rebuilding (services call it from their co_*_add_routes). A key
 * already routed keeps its first owner; a full table drops the route. */
void co_routes_add(co_node_t *node, uint32_t key, uint8_t kind, uint8_t slot);
/* co_routes_add for the identifier a COB-ID object value names (the key of co_cob_key). */
void co_routes_add_cob(co_node_t *node, uint32_t cob, uint8_t kind, uint8_t slot);
const co_route_t *co_routes_find(const co_node_t *node, uint32_t key);

/* txq.c */
void co_txq_flush(co_node_t *node);
/* Drop the waiting frames of services the current NMT state does not allow (at every state
 * change: a reset must not let stale heartbeats or SDO answers out after its boot-up). */
void co_txq_purge(co_node_t *node);
/* co_node_send for a service's frame (`service`: a co_service_t bit, 0 = none): refused
 * with CO_ERR_STATE when the NMT state does not allow it now, and dropped from the queue
 * if the state stops allowing it before the driver takes it. */
co_err_t co_node_send_as(co_node_t *node, const co_frame_t *frame, uint16_t service);
/* Address a frame of `len` bytes to the identifier a COB-ID object value names (its id,
 * flags and length; the data is left as it is). */
void co_frame_address(co_frame_t *frame, uint32_t cob, uint8_t len);
/* Send `len` (0..8) bytes of `data` (NULL: none) on the identifier a COB-ID object value
 * names (an 11-bit identifier is its own COB-ID value), as co_node_send_as does; the
 * frame's other data bytes are zero. The services' frames are built here, in one place. */
co_err_t co_node_send_cob(co_node_t *node, uint32_t cob, const uint8_t *data, uint8_t len,
                          uint16_t service);
/* The driver did not take a frame handed to it directly (co_node_send_hot): queue it
 * (CO_ERR_BUSY) or count it dropped, as co_node_send_as does. */
co_err_t co_txq_refused(co_node_t *node, const co_frame_t *frame, uint16_t service, co_err_t err);
/* co_node_send_hot for a sender that knows the queue is empty (co_txq_idle): a run of
 * frames (block transfer) tests the queue once per frame, not twice. */
static inline co_err_t co_node_send_idle(co_node_t *node, const co_frame_t *frame, uint16_t service)
{
#if !CO_SHORT_PATHS
    return co_node_send_as(node, frame, service); /* a build for size: one send path */
#else
    if (!(node->services & service)) {
        return co_node_send_as(node, frame, service);
    }
    co_err_t err = node->cfg.driver.tx(node->cfg.driver.ctx, frame);
    if (err != CO_OK) {
        return co_txq_refused(node, frame, service, err);
    }
    node->stats.tx_frames++;
    return CO_OK;
#endif
}

/* co_node_send_as for the per-frame paths (PDO, SDO): with the queue empty, the driver
 * is called from here, without a call into txq.c. `service` is not 0. */
static inline co_err_t co_node_send_hot(co_node_t *node, const co_frame_t *frame, uint16_t service)
{
    if (node->txq_count != 0) {
        return co_node_send_as(node, frame, service);
    }
    return co_node_send_idle(node, frame, service);
}
/* True when nothing waits in the transmit queue: a sender of many frames (block
 * transfer) sends only then, so it never floods the queue; poll resumes it. */
static inline bool co_txq_idle(const co_node_t *node) { return node->txq_count == 0; }

/* crc16.c: CRC-16-CCITT (polynomial 0x1021, no reflection, no final XOR), continued
 * from `crc` (start with 0). */
uint16_t co_crc16(uint16_t crc, const uint8_t *data, uint32_t len);

/* sdo_server.c */
void co_sdo_server_reset_comm(co_node_t *node);
/* The NMT state no longer allows SDO: open transfers end without a frame. */
void co_sdo_server_stop(co_node_t *node);
void co_sdo_server_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame);
#if CO_CONFIG_SDO_SEGMENTED || CO_CONFIG_SDO_BLOCK
uint64_t co_sdo_server_poll(co_node_t *node, uint64_t now_us);
#else
#define co_sdo_server_poll co_none_poll /* expedited transfers leave nothing open */
#endif
void co_sdo_server_written(co_node_t *node, const co_od_entry_t *entry);
void co_sdo_server_add_routes(co_node_t *node);

/* sdo_client.c (CO_SDO_CLIENTS_MAX 0: no client, nothing routed, polled or kept). */
#if CO_SDO_CLIENTS_MAX > 0
void co_sdo_client_reset_comm(co_node_t *node);
void co_sdo_client_stop(co_node_t *node);
void co_sdo_client_written(co_node_t *node, const co_od_entry_t *entry);
void co_sdo_client_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame);
uint64_t co_sdo_client_poll(co_node_t *node, uint64_t now_us);
void co_sdo_client_add_routes(co_node_t *node);
#else
#define co_sdo_client_reset_comm co_none_node
#define co_sdo_client_stop co_none_node
#define co_sdo_client_written co_none_entry
#define co_sdo_client_ingest co_none_slot_frame
#define co_sdo_client_poll co_none_poll
#define co_sdo_client_add_routes co_none_node
#endif

/* nmt.c */
void co_nmt_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
void co_nmt_reset(co_node_t *node, bool application);

/* heartbeat.c: the producer (0x1017), and what the consumer's files need. */
void co_hb_reset_comm(co_node_t *node);
void co_hb_state_entered(co_node_t *node);
uint64_t co_hb_poll(co_node_t *node, uint64_t now_us);
void co_hb_written(co_node_t *node, const co_od_entry_t *entry);
co_err_t co_hb_bind(co_node_t *node);
/* The frame on 0x700 + node-ID: a heartbeat (the state) or the boot-up (0, service 0). */
void co_hb_frame_send(co_node_t *node, uint8_t state, uint16_t service);

/* hb_consumer.c: the consumer (0x1016), CO_HB_CONSUMERS_MAX > 0. */
#if CO_HB_CONSUMERS_MAX > 0
co_err_t co_hb_consumers_bind(co_node_t *node);
void co_hb_consumers_reset(co_node_t *node);
void co_hb_consumers_add_routes(co_node_t *node);
void co_hb_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_hb_consumers_poll(co_node_t *node, uint64_t now_us);
co_abort_t co_hb_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                             uint32_t len);
void co_hb_consumer_written(co_node_t *node, const co_od_entry_t *entry);
bool co_hb_consumer_lost(const co_node_t *node);             /* some consumed heartbeat is lost */
bool co_hb_consumes(const co_node_t *node, uint8_t node_id); /* an entry watches it */
#else
static inline co_err_t co_hb_consumers_bind(co_node_t *node)
{
    (void)node;
    return CO_OK; /* 0x1016, if any, is a plain entry */
}
#define co_hb_consumers_reset co_none_node
#define co_hb_consumers_add_routes co_none_node
#define co_hb_ingest co_none_slot_frame
#define co_hb_consumers_poll co_none_poll
#define co_hb_check_write co_none_check
#define co_hb_consumer_written co_none_entry
#define co_hb_consumer_lost co_none_state
#define co_hb_consumes co_none_node_id
#endif

/* guarding.c (CO_CONFIG_GUARDING): without it nothing is routed, polled or kept. */
#if CO_CONFIG_GUARDING
void co_guard_bind(co_node_t *node);
void co_guard_reset_comm(co_node_t *node);
void co_guard_rtr(co_node_t *node, uint8_t slot, const co_frame_t *frame);
void co_guard_reply(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_guard_poll(co_node_t *node, uint64_t now_us);
void co_guard_written(co_node_t *node);
void co_guard_add_routes(co_node_t *node);
bool co_guard_watches(const co_node_t *node, uint8_t node_id); /* a master-side watch */
static inline bool co_guard_life_lost(const co_node_t *node) { return node->life_lost; }
#else
#define co_guard_bind co_none_node
#define co_guard_reset_comm co_none_node
#define co_guard_rtr co_none_slot_frame
#define co_guard_reply co_none_slot_frame
#define co_guard_poll co_none_poll
#define co_guard_written co_none_node
#define co_guard_add_routes co_none_node
#define co_guard_watches co_none_node_id
#define co_guard_life_lost co_none_state
#endif

/* emcy.c */
void co_emcy_reset_comm(co_node_t *node);
void co_emcy_written(co_node_t *node, const co_od_entry_t *entry);
bool co_emcy_producer_off(const co_node_t *node); /* 0x1014 bit 31 */
co_abort_t co_emcy_cob_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                   uint32_t len); /* 0x1014 */
void co_emcy_frame_send(co_node_t *node, const uint8_t data[8]);

/* emcy_queue.c: the inhibit time (CO_EMCY_QUEUE_LEN > 0); without it frames leave at once. */
#if CO_EMCY_QUEUE_LEN > 0
void co_emcy_queue_emit(co_node_t *node, const uint8_t data[8]);
void co_emcy_queue_reset(co_node_t *node);
void co_emcy_queue_clear(co_node_t *node);
uint64_t co_emcy_poll(co_node_t *node, uint64_t now_us);
void co_emcy_state_entered(co_node_t *node);
#else
static inline void co_emcy_queue_emit(co_node_t *node, const uint8_t data[8])
{
    co_emcy_frame_send(node, data);
}
#define co_emcy_queue_reset co_none_node
#define co_emcy_queue_clear co_none_node
#define co_emcy_poll co_none_poll
#define co_emcy_state_entered co_none_node
#endif

/* emcy_history.c: 0x1003 (CO_CONFIG_EMCY_HISTORY). */
#if CO_CONFIG_EMCY_HISTORY
void co_emcy_history_record(co_node_t *node, uint16_t code, const uint8_t mfr[5]);
void co_emcy_history_clear(co_node_t *node);
co_abort_t co_emcy_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len);
#else
static inline void co_emcy_history_record(co_node_t *node, uint16_t code, const uint8_t mfr[5])
{
    (void)node;
    (void)code;
    (void)mfr;
}
#define co_emcy_history_clear co_none_node
#define co_emcy_check_write co_none_check
#endif

/* emcy_consumer.c: 0x1028 (CO_EMCY_CONSUMERS_MAX > 0). */
#if CO_EMCY_CONSUMERS_MAX > 0
void co_emcy_consumers_bind(co_node_t *node);
void co_emcy_add_routes(co_node_t *node);
void co_emcy_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
#else
#define co_emcy_consumers_bind co_none_node
#define co_emcy_add_routes co_none_node
#define co_emcy_ingest co_none_slot_frame
#endif

/* sync.c: the consumer. */
void co_sync_reset_comm(co_node_t *node);
void co_sync_add_routes(co_node_t *node);
void co_sync_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
co_abort_t co_sync_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len);
void co_sync_written(co_node_t *node, const co_od_entry_t *entry);
/* A SYNC taken (received, or sent by this node's producer). */
void co_sync_handled(co_node_t *node, uint8_t counter);

/* Overflow value when SYNCs carry a counter, 0 when they carry no data (0x1019 is 0, or
 * the refused value 1 set natively). */
static inline uint8_t co_sync_overflow(const co_node_t *node)
{
    uint8_t n = (uint8_t)co_entry_uint(node->sync.overflow);
    return n >= 2 ? n : 0;
}

/* sync_producer.c: the producer (CO_CONFIG_SYNC_PRODUCER). */
#if CO_CONFIG_SYNC_PRODUCER
uint64_t co_sync_poll(co_node_t *node, uint64_t now_us);
void co_sync_state_entered(co_node_t *node);
void co_sync_producer_reset(co_node_t *node);
void co_sync_producer_written(co_node_t *node, uint16_t index);
uint32_t co_sync_producer_period(const co_node_t *node); /* 0x1006, us */
#else
#define co_sync_poll co_none_poll
#define co_sync_state_entered co_none_node
#define co_sync_producer_reset co_none_node
static inline void co_sync_producer_written(co_node_t *node, uint16_t index)
{
    (void)node;
    (void)index;
}
static inline uint32_t co_sync_producer_period(const co_node_t *node)
{
    (void)node;
    return 0; /* 0x1006 has no effect: 0x1019 may always change */
}
#endif

/* pdo.c */
co_err_t co_pdo_bind(co_node_t *node); /* at init: count the PDOs the dictionary has */
void co_pdo_reset_comm(co_node_t *node);
void co_pdo_add_routes(co_node_t *node);
void co_pdo_rx(co_node_t *node, uint8_t rpdo, const co_frame_t *frame);
void co_pdo_rtr(co_node_t *node, uint8_t tpdo, const co_frame_t *frame);
/* Every SYNC handled (own or received), once sync.last_us is the SYNC's time. */
void co_pdo_sync(co_node_t *node, uint8_t counter);
#if CO_CONFIG_PDO_TIMERS
uint64_t co_pdo_poll(co_node_t *node, uint64_t now_us); /* pdo_timers.c */
#else
#define co_pdo_poll co_none_poll /* without timers PDOs have nothing to wait for */
#endif
co_abort_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                              uint32_t len);
void co_pdo_written(co_node_t *node, const co_od_entry_t *entry);
void co_pdo_changed(co_node_t *node, const co_od_entry_t *entry); /* any value written */
void co_pdo_state_entered(co_node_t *node);

/* storage.c */
#if CO_CONFIG_STORAGE
void co_storage_load(co_node_t *node, co_param_group_t group);
#else
static inline void co_storage_load(co_node_t *node, co_param_group_t group)
{
    (void)node;
    (void)group; /* nothing is ever stored */
}
#endif
co_abort_t co_storage_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                  uint32_t len);
#if CO_CONFIG_STORAGE
void co_storage_show_capability(co_node_t *node, const co_od_entry_t *entry);
void co_storage_reset_comm(co_node_t *node);
#else /* 0x1010 and 0x1011 keep the dictionary's values; every command is refused */
#define co_storage_reset_comm co_none_node
#endif

/* time.c */
#if CO_CONFIG_TIME
void co_time_reset_comm(co_node_t *node);
void co_time_add_routes(co_node_t *node);
void co_time_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
void co_time_written(co_node_t *node, const co_od_entry_t *entry);
#else /* neither role: time.cob_id stays 0, nothing is routed */
#define co_time_reset_comm co_none_node
#define co_time_add_routes co_none_node
#define co_time_ingest co_none_slot_frame
#define co_time_written co_none_entry
#endif

/* lss_slave.c, lss_master.c: no-ops when left out of the build. */
#if CO_CONFIG_LSS_SLAVE
void co_lss_slave_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_lss_slave_poll(co_node_t *node, uint64_t now_us);
/* At every reset: the node-ID the node runs with from now on (CiA 305 pending node-ID). */
void co_lss_slave_reset(co_node_t *node, bool application);
/* A frame of `service` arrived while the services are off: true when that was the quiet
 * time after a bit rate switch, it is over now (services back), and `service` may run. */
bool co_lss_slave_resume(co_node_t *node, uint16_t service);
#else
static inline bool co_lss_slave_resume(co_node_t *node, uint16_t service)
{
    (void)node;
    (void)service;
    return false;
}
#define co_lss_slave_ingest co_none_slot_frame
#define co_lss_slave_poll co_none_poll
static inline void co_lss_slave_reset(co_node_t *node, bool application)
{
    (void)node;
    (void)application;
}
#endif
#if CO_CONFIG_LSS_MASTER
void co_lss_master_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_lss_master_poll(co_node_t *node, uint64_t now_us);
static inline bool co_lss_master_listening(const co_node_t *node)
{
    return node->lss_master.listening;
}
#else
#define co_lss_master_ingest co_none_slot_frame
#define co_lss_master_poll co_none_poll
#define co_lss_master_listening co_none_state
#endif

/* manager.c: no-ops when left out of the build. */
#if CO_CONFIG_MANAGER
uint64_t co_manager_poll(co_node_t *node, uint64_t now_us);
void co_manager_bootup(co_node_t *node, uint8_t n, const co_frame_t *frame);
void co_manager_ec_event(co_node_t *node, const co_ec_event_t *ev);
void co_manager_add_routes(co_node_t *node);
void co_manager_reset_comm(co_node_t *node);
uint64_t co_flash_poll(co_node_t *node, uint64_t now_us); /* program_master.c: progress */
#else
static inline uint64_t co_manager_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
#define co_manager_bootup co_none_slot_frame
static inline void co_manager_ec_event(co_node_t *node, const co_ec_event_t *ev)
{
    (void)node;
    (void)ev;
}
static inline void co_manager_add_routes(co_node_t *node) { (void)node; }
#define co_manager_reset_comm co_none_node
static inline uint64_t co_flash_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
#endif

#endif /* CANOLA_INTERNAL_H */
