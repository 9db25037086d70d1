/*
 * node.c -- the node: lifecycle, frame dispatch, the poll loop, and object
 * dictionary access that lets writes take effect on the services.
 */
#include <string.h>

#include "internal.h"

/* ---- lifecycle */

co_err_t co_node_init(co_node_t *node, const co_node_config_t *config)
{
    if (node == NULL || config == NULL || config->driver.tx == NULL || config->od.entries == NULL) {
        return CO_ERR_ARG;
    }
    uint8_t id = config->node_id;
    if ((id < 1 || id > 127) && id != CO_NODE_ID_UNCONFIGURED) {
        return CO_ERR_ARG;
    }
    if (co_od_validate(&config->od, NULL) != CO_OK) {
        return CO_ERR_CONFIG;
    }
    co_zero(node, sizeof *node);
    co_copy(&node->cfg, config, sizeof *config); /* (a struct copy would call memcpy) */
    node->node_id = id;
    node->nmt_state = CO_NMT_INITIALISING;
    node->services = co_nmt_services(CO_NMT_INITIALISING);
    node->next_due_us = CO_TIME_NEVER;
    node->hb_next_us = CO_TIME_NEVER;
    co_guard_bind(node);
    node->error_behaviour = co_od_find(&config->od, 0x1029, 1, NULL);
    co_err_t err = co_hb_bind(node);
    return err == CO_OK ? co_pdo_bind(node) : err;
}

co_err_t co_node_start(co_node_t *node, uint64_t now_us)
{
    if (node->started) {
        return CO_ERR_STATE;
    }
    node->started = true;
    node->now_us = now_us;
    co_nmt_reset(node, true);
    return CO_OK;
}

uint8_t co_node_id(const co_node_t *node) { return node->node_id; }

const co_node_stats_t *co_node_stats(const co_node_t *node) { return &node->stats; }

/* ---- dispatch */

/* The service that takes the frames of each route kind, with the route's slot (a table:
 * less code than a switch). Left-out services are stand-ins that ignore the frame. */
typedef void (*ingest_fn)(co_node_t *node, uint8_t slot, const co_frame_t *frame);
static const ingest_fn k_ingest[] = {
    [CO_ROUTE_NMT] = co_nmt_ingest,
    [CO_ROUTE_GUARD_RTR] = co_guard_rtr,
    [CO_ROUTE_HB_CONSUMER] = co_hb_ingest,
    [CO_ROUTE_GUARD_REPLY] = co_guard_reply,
    [CO_ROUTE_SDO_SERVER] = co_sdo_server_ingest,
    [CO_ROUTE_SDO_CLIENT] = co_sdo_client_ingest,
    [CO_ROUTE_SYNC] = co_sync_ingest,
    [CO_ROUTE_TIME] = co_time_ingest,
    [CO_ROUTE_EMCY] = co_emcy_ingest,
    [CO_ROUTE_RPDO] = co_pdo_rx,
    [CO_ROUTE_TPDO_RTR] = co_pdo_rtr,
    [CO_ROUTE_LSS_SLAVE] = co_lss_slave_ingest,
    [CO_ROUTE_LSS_MASTER] = co_lss_master_ingest,
    [CO_ROUTE_MGR_BOOTUP] = co_manager_bootup,
};

/* Hand a frame to the service its route names (routes hold the kinds above only). */
static CO_INLINE void dispatch(co_node_t *node, const co_route_t *route, const co_frame_t *frame)
{
    k_ingest[route->kind](node, route->slot, frame);
}

/* A frame whose service the NMT state does not allow now: dropped and counted, unless
 * it is the one that ends an LSS quiet time. */
static CO_FAST_NOINLINE void ingest_gated(co_node_t *node, const co_route_t *route,
                                          const co_frame_t *frame)
{
    if (co_lss_slave_resume(node, route->service)) {
        dispatch(node, route, frame);
    } else {
        node->stats.rx_gated++;
    }
}

/* A routed frame: to its service, or to the gate when the NMT state does not allow it. */
static CO_INLINE void deliver(co_node_t *node, const co_route_t *route, const co_frame_t *frame)
{
    if (!(node->services & route->service)) {
        ingest_gated(node, route, frame);
        return;
    }
    dispatch(node, route, frame);
}

/* A frame on another COB-ID than the last one routed: the search, then delivered. */
static CO_FAST_NOINLINE void ingest_searched(co_node_t *node, const co_frame_t *frame, uint32_t key)
{
    const co_route_t *route = co_routes_find(node, key);
    if (route == NULL) {
        if (!(frame->flags & CO_FRAME_EXT) && frame->id > CO_ID_STD_MAX) {
            node->stats.rx_malformed++;
        } else {
            node->stats.rx_unrouted++;
        }
        return;
    }
    node->route_hint = (uint16_t)(route - node->routes);
    deliver(node, route, frame);
}

void co_node_ingest(co_node_t *node, uint64_t now_us, const co_frame_t *frame)
{
    node->now_us = now_us;
    node->stats.rx_frames++;
    /* Above 29 bits or 8 bytes: malformed. An identifier of 12..29 bits without the EXT
     * flag is malformed too, but matches no route (routes hold valid keys only), so it is
     * told apart from the unrouted ones off the common path. */
    if (frame->len > 8 || frame->id > CO_ID_EXT_MAX) {
        node->stats.rx_malformed++; /* no controller delivers this: never let it match */
        return;
    }
    /* A stream of frames on one COB-ID (an SDO transfer, a busy PDO) finds its route in
     * the one the last frame took; this path makes no call but the service's (a short
     * path: without it every frame takes the search). */
    uint32_t key = co_route_key(frame);
    const co_route_t *route = &node->routes[node->route_hint];
    if (!CO_SHORT_PATHS || node->route_hint >= node->route_count || route->key != key) {
        ingest_searched(node, frame, key);
        return;
    }
    deliver(node, route, frame);
}

/* ---- time */

void co_node_schedule(co_node_t *node, uint64_t due_us)
{
    if (due_us < node->next_due_us) {
        node->next_due_us = due_us;
    }
}

static uint64_t poll_due(co_node_t *node, uint64_t now_us)
{
    node->now_us = now_us;
    if (node->txq_count) {
        co_txq_flush(node);
    }
    if (!node->started) {
        return CO_TIME_NEVER;
    }
    /* Services may schedule work while they run (a reset, a new watch): start from
     * "never" and let co_node_schedule lower it, then add what the services return.
     * Work one service scheduled for now while the pass ran (an SDO time-out that ends a
     * manager's boot step) is done by another pass, so the deadline returned lies ahead. */
    for (uint32_t pass = 0; pass < 3; pass++) {
        node->next_due_us = CO_TIME_NEVER;
        uint64_t next = co_lss_slave_poll(node, now_us); /* first: it may end a quiet time */
        next = co_min_u64(next, co_hb_poll(node, now_us));
        next = co_min_u64(next, co_guard_poll(node, now_us));
        next = co_min_u64(next, co_sdo_server_poll(node, now_us));
        next = co_min_u64(next, co_sdo_client_poll(node, now_us));
        next = co_min_u64(next, co_sync_poll(node, now_us));
        next = co_min_u64(next, co_emcy_poll(node, now_us));
        next = co_min_u64(next, co_pdo_poll(node, now_us));
        next = co_min_u64(next, co_lss_master_poll(node, now_us));
        next = co_min_u64(next, co_manager_poll(node, now_us));
        next = co_min_u64(next, co_flash_poll(node, now_us));
        co_node_schedule(node, next);
        if (node->next_due_us > now_us) {
            break;
        }
    }
    return node->next_due_us;
}

uint64_t co_node_poll(co_node_t *node, uint64_t now_us)
{
    node->now_us = now_us; /* the clock the application's calls in between will use */
    if (now_us < node->next_due_us && node->txq_count == 0) {
        return node->next_due_us;
    }
    return poll_due(node, now_us);
}

/* ---- events and error behaviour */

void co_node_ec_event(co_node_t *node, co_ec_event_kind_t kind, uint8_t node_id, uint8_t state,
                      uint8_t previous)
{
    co_ec_event_t ev = {.kind = kind, .node_id = node_id, .state = state, .previous = previous};
    if (node->cfg.on_errctl) {
        node->cfg.on_errctl(node->cfg.user, &ev);
    }
    co_manager_ec_event(node, &ev); /* the manager boots slaves on boot-up, watches losses */
}

void co_node_error_behaviour(co_node_t *node)
{
    switch (co_entry_uint(node->error_behaviour)) {
    case 0:
        if (node->nmt_state == CO_NMT_OPERATIONAL) {
            (void)co_nmt_apply(node, CO_NMT_CMD_ENTER_PRE_OPERATIONAL);
        }
        break;
    case 2:
        (void)co_nmt_apply(node, CO_NMT_CMD_STOP);
        break;
    default: /* 1 and manufacturer-specific values: no change */
        break;
    }
}

void co_node_comm_lost(co_node_t *node)
{
    (void)co_emcy_raise(node, 0x8130, NULL);
    co_node_error_behaviour(node);
}

/* Anything still lost: a consumed heartbeat, or our own life guarding. */
static bool comm_still_lost(const co_node_t *node)
{
    return co_hb_consumer_lost(node) || co_guard_life_lost(node);
}

void co_node_comm_resumed(co_node_t *node)
{
    if (!comm_still_lost(node) && co_emcy_active(node, 0x8130)) {
        (void)co_emcy_clear(node, 0x8130);
    }
}

/* The NMT state changed: services that depend on it start, stop or catch up. */
void co_node_state_changed(co_node_t *node)
{
    co_txq_purge(node);
    if (!(node->services & CO_SVC_SDO)) {
        co_sdo_server_stop(node);
        co_sdo_client_stop(node);
    }
    co_sync_state_entered(node);
    co_emcy_state_entered(node);
    co_pdo_state_entered(node);
}

/* ---- object dictionary access */

/* ---- The services' objects: which service checks a write to which communication object,
 * and takes the new value into effect. A table, searched on each write to 0x1000..0x1FFF,
 * instead of a switch per step: less code. */

typedef co_abort_t (*write_check_fn)(co_node_t *node, const co_od_entry_t *entry,
                                     const uint8_t *data, uint32_t len);
typedef void (*written_fn)(co_node_t *node, const co_od_entry_t *entry);

/* Which sub-indices of an object hold a COB-ID (bit 31 valid, bit 29 frame format, the
 * identifier): a new one must name an identifier of its own format. */
enum { COB_NONE, COB_SUB0, COB_SUB1_2, COB_SUB1_UP };

typedef struct service_object {
    uint16_t first; /* indices first..last */
    uint16_t last;
    uint8_t cob;          /* COB_*: the sub-indices holding a COB-ID */
    write_check_fn check; /* refuse a value the service cannot take (NULL: none) */
    written_fn written;   /* the new value takes effect (NULL: nothing to do) */
} service_object_t;

#if CO_CONFIG_GUARDING
static void guard_written(co_node_t *node, const co_od_entry_t *entry)
{
    (void)entry;
    co_guard_written(node);
}
#endif

/* Objects of left-out features stay (for their COB-ID check) or go (with no effect). */
static const service_object_t k_service_objects[] = {
#if CO_CONFIG_EMCY_HISTORY
    {0x1003, 0x1003, COB_NONE, co_emcy_check_write, co_emcy_written},
#endif
    {0x1005, 0x1005, COB_SUB0, NULL, co_sync_written},
#if CO_CONFIG_SYNC_PRODUCER
    {0x1006, 0x1007, COB_NONE, NULL, co_sync_written},
#endif
#if CO_CONFIG_GUARDING
    {0x100C, 0x100D, COB_NONE, NULL, guard_written},
#endif
#if CO_CONFIG_STORAGE
    {0x1010, 0x1011, COB_NONE, co_storage_check_write, co_storage_show_capability},
#else
    {0x1010, 0x1011, COB_NONE, co_storage_check_write, NULL}, /* every command refused */
#endif
    {0x1012, 0x1012, COB_SUB0, NULL, CO_CONFIG_TIME ? co_time_written : NULL},
    {0x1014, 0x1014, COB_SUB0, co_emcy_cob_check_write,
     CO_EMCY_QUEUE_LEN > 0 ? co_emcy_written : NULL},
#if CO_EMCY_QUEUE_LEN > 0
    {0x1015, 0x1015, COB_NONE, NULL, co_emcy_written},
#endif
#if CO_HB_CONSUMERS_MAX > 0
    {0x1016, 0x1016, COB_NONE, co_hb_check_write, co_hb_written},
#endif
    {0x1017, 0x1017, COB_NONE, NULL, co_hb_written},
    {0x1019, 0x1019, COB_NONE, co_sync_check_write, co_sync_written},
    {0x1028, 0x1028, COB_SUB1_UP, NULL, CO_EMCY_CONSUMERS_MAX > 0 ? co_emcy_written : NULL},
#if CO_SDO_CLIENTS_MAX > 0
    {0x1200, 0x127F, COB_SUB1_2, NULL, co_sdo_server_written},
    {0x1280, 0x12FF, COB_SUB1_2, NULL, co_sdo_client_written},
#else /* without clients 0x1280.. have no effect: no server channel is 0x1200 + 0x80 or more */
    {0x1200, 0x12FF, COB_SUB1_2, NULL, co_sdo_server_written},
#endif
    {0x1400, 0x1BFF, COB_NONE, co_pdo_check_write, co_pdo_written},
};

/* The service object of an entry of 0x1000..0x1FFF, or NULL. */
static const service_object_t *service_object(const co_od_entry_t *entry)
{
    for (size_t i = 0; i < sizeof k_service_objects / sizeof k_service_objects[0]; i++) {
        const service_object_t *o = &k_service_objects[i];
        if (entry->index >= o->first && entry->index <= o->last) {
            return o;
        }
    }
    return NULL;
}

/* Service side of a write: refuse values a service cannot take. */
static co_abort_t service_check(co_node_t *node, const service_object_t *o,
                                const co_od_entry_t *entry, const uint8_t *data, uint32_t len)
{
    uint8_t sub = entry->sub;
    bool cob = (o->cob == COB_SUB0 && sub == 0) ||
               (o->cob == COB_SUB1_2 && (sub == 1 || sub == 2)) ||
               (o->cob == COB_SUB1_UP && sub >= 1);
    if (len == 4 && cob && !co_cob_valid(co_get_u32(data))) {
        return CO_ABORT_VALUE;
    }
    return o->check != NULL ? o->check(node, entry, data, len) : CO_ABORT_NONE;
}

/* co_node_write_entry of anything but a plain application number. */
static CO_NOINLINE co_abort_t write_entry_general(co_node_t *node, const co_od_entry_t *entry,
                                                  const uint8_t *data, uint32_t len)
{
    /* The services own objects of the communication profile area only (0x1000..0x1FFF):
     * an application object needs neither their checks nor their effects. */
    const service_object_t *o = entry->index < 0x2000u ? service_object(entry) : NULL;
    const co_od_t *od = &node->cfg.od;
    co_abort_t abort = co_od_check(od, entry, data, len);
    if (abort == CO_ABORT_NONE && o != NULL) {
        abort = service_check(node, o, entry, data, len);
    }
    if (abort == CO_ABORT_NONE) {
        abort = co_od_store(od, entry, data, len);
    }
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    if (o != NULL && o->written != NULL) {
        o->written(node, entry); /* the new value takes effect at once */
    }
    co_pdo_changed(node, entry); /* change of state: event-driven TPDOs mapping it */
    if (entry->hooks && entry->hooks->written) {
        entry->hooks->written(od->hook_ctx, entry);
    }
    return CO_ABORT_NONE;
}

co_abort_t co_node_write_entry(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len)
{
    if (CO_SHORT_PATHS && entry->index >= 0x2000u && co_od_writes_plain(entry) &&
        len == entry->size) {
        co_copy_number(entry->value, data, len); /* what check + store would come to */
        co_pdo_changed(node, entry);             /* change of state, as below */
        return CO_ABORT_NONE;
    }
    return write_entry_general(node, entry, data, len);
}

co_abort_t co_node_write_net(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len)
{
    co_abort_t abort;
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, &abort);
    if (entry == NULL) {
        return abort;
    }
    abort = co_od_access(entry, true);
    return abort != CO_ABORT_NONE ? abort : co_node_write_entry(node, entry, data, len);
}

co_abort_t co_node_read_net(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                            uint32_t cap, uint32_t *len)
{
    co_abort_t abort;
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, &abort);
    if (entry == NULL) {
        return abort;
    }
    abort = co_od_access(entry, false);
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    uint32_t total = 0;
    abort = co_od_read(&node->cfg.od, entry, 0, buf, cap, len, &total);
    if (abort == CO_ABORT_NONE && total != CO_OD_SIZE_UNKNOWN && total > *len) {
        return CO_ABORT_LEN_HIGH;
    }
    return abort;
}

co_abort_t co_node_set_uint(co_node_t *node, uint16_t index, uint8_t sub, uint64_t value)
{
    co_abort_t abort;
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, &abort);
    if (entry == NULL) {
        return abort;
    }
    uint32_t size = co_type_size((co_type_t)entry->type);
    if (size == 0 || size > 8 || entry->type == CO_TYPE_REAL32 || entry->type == CO_TYPE_REAL64 ||
        entry->type == CO_TYPE_TIME_OF_DAY || entry->type == CO_TYPE_TIME_DIFFERENCE) {
        return CO_ABORT_TYPE_MISMATCH;
    }
    uint8_t wire[8];
    for (uint32_t i = 0; i < size; i++) {
        wire[i] = (uint8_t)(value >> (8 * i));
    }
    return co_node_write_entry(node, entry, wire, size);
}

uint32_t co_od_u32(const co_node_t *node, uint16_t index, uint8_t sub, uint32_t absent)
{
    uint64_t v = absent;
    (void)co_od_get_uint(&node->cfg.od, index, sub, &v);
    return (uint32_t)v;
}

co_err_t co_node_get_uint(const co_node_t *node, uint16_t index, uint8_t sub, uint64_t *value)
{
    return co_od_get_uint(&node->cfg.od, index, sub, value);
}
