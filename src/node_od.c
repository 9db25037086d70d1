/* SPDX-License-Identifier: Apache-2.0 */
/*
 * node_od.c -- the dictionary as the node reads and writes it: access rights as the network
 * has them, and the effects of a write on the services that own the object (a table).
 * co_node_write_entry is the node's wiring for every service's co_node_write (kernel.h).
 */
#include "node_internal.h"

/* ---- The services' objects: which service checks a write to which communication object
 * and takes the new value into effect. Each service lists its own (its internal header's
 * CO_*_OBJECT_ROWS, kernel.h's co_object_row_t); the table is their lists put together, in
 * no particular order, and searched on each write to 0x1000..0x1FFF: less code than a
 * switch per step. A new service adds its list here. */
static const co_object_row_t k_objects[] = {
    CO_ERRCTL_OBJECT_ROWS CO_EMCY_OBJECT_ROWS CO_SYNC_OBJECT_ROWS CO_TIME_OBJECT_ROWS
        CO_STORAGE_OBJECT_ROWS CO_SDO_OBJECT_ROWS CO_PDO_OBJECT_ROWS};

/* The row of an entry of 0x1000..0x1FFF, or NULL. */
static const co_object_row_t *object_row(const co_od_entry_t *entry)
{
    unsigned at = entry->index - 0x1000u; /* (wraps below the area: past every row) */
    for (size_t i = 0; i < sizeof k_objects / sizeof k_objects[0]; i++) {
        if (at - k_objects[i].first <= k_objects[i].span) {
            return &k_objects[i];
        }
    }
    return NULL;
}

/* Service side of a write: refuse values a service cannot take. */
static co_abort_t service_check(co_node_t *node, const co_object_row_t *o,
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
    const co_object_row_t *o = entry->index < 0x2000u ? object_row(entry) : NULL;
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

co_abort_t co_node_write_app(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len)
{
    co_abort_t abort;
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, &abort);
    return entry != NULL ? co_node_write_entry(node, entry, data, len) : abort;
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
    if (abort == CO_ABORT_NONE) {
        abort = co_od_read_check(node, entry);
    }
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
