/* SPDX-License-Identifier: Apache-2.0 */
/*
 * node_od.c -- the dictionary as the node reads and writes it: access rights as the network
 * has them, and the effects of a write on the services that own the object (a table).
 * co_node_write_entry is the node's wiring for every service's co_node_write (kernel.h).
 */
#include "node_internal.h"

/* ---- The services' objects: which service checks a write to which communication object,
 * and takes the new value into effect. A table, searched on each write to 0x1000..0x1FFF,
 * instead of a switch per step: less code. */

typedef co_abort_t (*write_check_fn)(co_node_t *node, const co_od_entry_t *entry,
                                     const uint8_t *data, uint32_t len);
typedef void (*written_fn)(co_node_t *node, const co_od_entry_t *entry);

/* Which sub-indices of an object hold a COB-ID (bit 31 valid, bit 29 frame format, the
 * identifier): a new one must name an identifier of its own format. */
/* A bit per sub-index 0..6, bit 7 for 7 and above (a mask: one test). */
enum { COB_NONE = 0x00, COB_SUB0 = 0x01, COB_SUB1_2 = 0x06, COB_SUB1_UP = 0xFE };

/* The indices first..last as offsets into the communication profile area (12 bits each, one
 * word with `cob`: 12 bytes an object, not 16). */
#define AREA 0x1000u
#define OBJECTS(first, last) ((first)-AREA), ((last)-AREA)

typedef struct service_object {
    unsigned first : 12; /* indices AREA + first..last */
    unsigned last : 12;
    unsigned cob : 8;     /* COB_*: the sub-indices holding a COB-ID */
    write_check_fn check; /* refuse a value the service cannot take (NULL: none) */
    written_fn written;   /* the new value takes effect (NULL: nothing to do) */
} service_object_t;

/* Objects of left-out features stay (for their COB-ID check) or go (with no effect). */
static const service_object_t k_service_objects[] = {
#if CO_CONFIG_EMCY_HISTORY
    {OBJECTS(0x1003, 0x1003), COB_NONE, co_emcy_check_write, co_emcy_written},
#endif
    {OBJECTS(0x1005, 0x1005), COB_SUB0, NULL, co_sync_written},
#if CO_CONFIG_SYNC_PRODUCER
    {OBJECTS(0x1006, 0x1007), COB_NONE, NULL, co_sync_written},
#endif
#if CO_CONFIG_GUARDING
    {OBJECTS(0x100C, 0x100D), COB_NONE, NULL, co_guard_written},
#endif
#if CO_CONFIG_STORAGE
    {OBJECTS(0x1010, 0x1011), COB_NONE, co_storage_check_write, co_storage_show_capability},
#else
    {OBJECTS(0x1010, 0x1011), COB_NONE, co_storage_check_write, NULL}, /* every command refused */
#endif
    {OBJECTS(0x1012, 0x1012), COB_SUB0, NULL, CO_CONFIG_TIME ? co_time_written : NULL},
    {OBJECTS(0x1014, 0x1014), COB_SUB0, co_emcy_cob_check_write,
     CO_EMCY_QUEUE_LEN > 0 ? co_emcy_written : NULL},
#if CO_EMCY_QUEUE_LEN > 0
    {OBJECTS(0x1015, 0x1015), COB_NONE, NULL, co_emcy_written},
#endif
#if CO_HB_CONSUMERS_MAX > 0
    {OBJECTS(0x1016, 0x1016), COB_NONE, co_hb_check_write, co_hb_written},
#endif
    {OBJECTS(0x1017, 0x1017), COB_NONE, NULL, co_hb_written},
    {OBJECTS(0x1019, 0x1019), COB_NONE, co_sync_check_write, co_sync_written},
    {OBJECTS(0x1028, 0x1028), COB_SUB1_UP, NULL,
     CO_EMCY_CONSUMERS_MAX > 0 ? co_emcy_written : NULL},
#if CO_SDO_CLIENTS_MAX > 0
    {OBJECTS(0x1200, 0x127F), COB_SUB1_2, NULL, co_sdo_server_written},
    {OBJECTS(0x1280, 0x12FF), COB_SUB1_2, NULL, co_sdo_client_written},
#else /* without clients 0x1280.. have no effect: no server channel is 0x1200 + 0x80 or more */
    {OBJECTS(0x1200, 0x12FF), COB_SUB1_2, NULL, co_sdo_server_written},
#endif
    {OBJECTS(0x1400, 0x1BFF), COB_NONE, co_pdo_check_write, co_pdo_written},
};

/* The service object of an entry of 0x1000..0x1FFF, or NULL. */
static const service_object_t *service_object(const co_od_entry_t *entry)
{
    for (size_t i = 0; i < sizeof k_service_objects / sizeof k_service_objects[0]; i++) {
        const service_object_t *o = &k_service_objects[i];
        unsigned at = entry->index - AREA; /* (wraps below the area: above every last) */
        if (at >= o->first && at <= o->last) {
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
    bool cob = (o->cob >> (sub < 7u ? sub : 7u)) & 1u;
    if (len == 4 && cob && !co_cob_valid(co_get_u32(data))) {
        return CO_ABORT_VALUE;
    }
    return o->check != NULL ? o->check(node, entry, data, len) : CO_ABORT_NONE;
}

co_abort_t co_node_write_entry(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len)
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
    const co_od_hooks_t *hooks = co_od_hooks_of(entry);
    if (hooks && hooks->written) {
        hooks->written(od->hook_ctx, entry);
    }
    return CO_ABORT_NONE;
}

/* ---- the public access (canola/node.h) */

co_abort_t co_node_write_net(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len)
{
    co_abort_t abort;
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, &abort);
    if (entry == NULL) {
        return abort;
    }
    abort = co_od_access(&node->cfg.od, entry, true);
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
    abort = co_od_access(&node->cfg.od, entry, false);
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
    unsigned type = co_od_type(&node->cfg.od, entry);
    uint32_t size = co_type_size((co_type_t)type);
    if (size == 0 || size > 8 || type == CO_TYPE_REAL32 || type == CO_TYPE_REAL64 ||
        type == CO_TYPE_TIME_OF_DAY || type == CO_TYPE_TIME_DIFFERENCE) {
        return CO_ABORT_TYPE_MISMATCH;
    }
    uint8_t wire[8];
    for (uint32_t i = 0; i < size; i++) {
        wire[i] = (uint8_t)(value >> (8 * i));
    }
    return co_node_write_entry(node, entry, wire, size);
}

co_err_t co_node_get_uint(const co_node_t *node, uint16_t index, uint8_t sub, uint64_t *value)
{
    return co_od_get_uint(&node->cfg.od, index, sub, value);
}
