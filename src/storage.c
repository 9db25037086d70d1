/*
 * storage.c -- stored parameters (0x1010, 0x1011); see canola/storage.h.
 */
#include "storage_internal.h"

/* The storage given, or none when the feature is left out (CO_CONFIG_STORAGE 0): every
 * path below then is the "no storage" one, and the compiler drops the rest. */
static inline const co_storage_t *storage_of(const co_node_t *node)
{
    return CO_CONFIG_STORAGE ? node->cfg.storage : NULL;
}

#define RECORD_HEAD 4u /* index (2), sub-index (1), length (1) */

static const uint16_t k_first[3] = {0, 0x1000, 0x2000};
static const uint16_t k_last[3] = {0, 0x1FFF, 0x9FFF};

/* Entries a save records: writable from the network, with storage, not a DOMAIN, short
 * enough, and not one of the objects that are commands or logs rather than parameters. */
static bool is_parameter(const co_od_entry_t *e)
{
    if (!(e->attr & CO_OD_WRITE) || (e->attr & CO_OD_CONST) || e->value == NULL ||
        e->type == CO_TYPE_DOMAIN) {
        return false;
    }
    return e->index != 0x1003 && e->index != 0x1010 && e->index != 0x1011;
}

/* ---- saving */

static co_err_t save_group(co_node_t *node, co_param_group_t group)
{
    const co_storage_t *st = storage_of(node);
    const co_od_t *od = &node->cfg.od;
    co_err_t err = st->begin(st->ctx, group);
    for (uint32_t i = 0; i < od->count && err == CO_OK; i++) {
        const co_od_entry_t *e = &od->entries[i];
        if (e->index < k_first[group] || e->index > k_last[group] || !is_parameter(e)) {
            continue;
        }
        uint8_t rec[RECORD_HEAD + CO_STORE_VALUE_MAX];
        uint32_t n = 0;
        uint32_t total = 0;
        co_abort_t abort = co_od_read(od, e, 0, &rec[RECORD_HEAD], CO_STORE_VALUE_MAX, &n, &total);
        if (abort != CO_ABORT_NONE || total != n) {
            continue; /* unreadable or too long to store */
        }
        co_put_u16(rec, e->index);
        rec[2] = e->sub;
        rec[3] = (uint8_t)n;
        err = st->write(st->ctx, rec, RECORD_HEAD + n);
    }
    return err == CO_OK ? st->commit(st->ctx) : err;
}

co_err_t co_storage_save(co_node_t *node, uint8_t which)
{
    if (storage_of(node) == NULL) {
        return CO_ERR_STATE;
    }
    if (which < 1 || which > 3) {
        return CO_ERR_ARG;
    }
    co_err_t err = CO_OK;
    if (which != 3) {
        err = save_group(node, CO_PARAMS_COMMUNICATION);
    }
    if (err == CO_OK && which != 2) {
        err = save_group(node, CO_PARAMS_APPLICATION);
    }
    return err;
}

static co_err_t restore_defaults(co_node_t *node, uint8_t which)
{
    const co_storage_t *st = storage_of(node);
    co_err_t err = CO_OK;
    if (which != 3) {
        err = st->erase(st->ctx, CO_PARAMS_COMMUNICATION);
    }
    if (err == CO_OK && which != 2) {
        err = st->erase(st->ctx, CO_PARAMS_APPLICATION);
    }
    return err;
}

/* ---- loading */

#if CO_CONFIG_STORAGE

void co_storage_load(co_node_t *node, co_param_group_t group)
{
    const co_storage_t *st = storage_of(node);
    if (st == NULL) {
        return;
    }
    const co_od_t *od = &node->cfg.od;
    uint32_t offset = 0;
    for (;;) {
        uint8_t rec[RECORD_HEAD + 255];
        uint32_t n = 0;
        if (st->read(st->ctx, group, offset, rec, RECORD_HEAD, &n) != CO_OK || n < RECORD_HEAD) {
            return; /* nothing stored, or the end */
        }
        uint32_t len = rec[3];
        if (st->read(st->ctx, group, offset + RECORD_HEAD, &rec[RECORD_HEAD], len, &n) != CO_OK ||
            n < len) {
            return; /* a truncated image: keep what was applied */
        }
        offset += RECORD_HEAD + len;
        uint16_t index = co_get_u16(rec);
        const co_od_entry_t *e = co_od_find(od, index, rec[2], NULL);
        if (e != NULL && index >= k_first[group] && index <= k_last[group] && is_parameter(e) &&
            co_od_check(od, e, &rec[RECORD_HEAD], len) == CO_ABORT_NONE) {
            (void)co_od_store(od, e, &rec[RECORD_HEAD], len);
        }
    }
}
#endif

/* ---- 0x1010 and 0x1011 */

co_abort_t co_storage_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                  uint32_t len)
{
    if (entry->sub == 0 || len != 4) {
        return CO_ABORT_NONE; /* sub0 is read-only in any sane dictionary; length is checked */
    }
    bool store = entry->index == 0x1010;
    uint32_t want = store ? CO_STORE_SIGNATURE : CO_RESTORE_SIGNATURE;
    if (storage_of(node) == NULL || entry->sub > 3 || co_get_u32(data) != want) {
        return CO_ABORT_DATA_STORE;
    }
    co_err_t err = store ? co_storage_save(node, entry->sub) : restore_defaults(node, entry->sub);
    return err == CO_OK ? CO_ABORT_NONE : CO_ABORT_HARDWARE;
}

#if CO_CONFIG_STORAGE
/* After the command: the entry reads as the capability again, not as the signature. */
void co_storage_show_capability(co_node_t *node, const co_od_entry_t *entry)
{
    if (entry->sub != 0 && entry->value != NULL) {
        (void)co_od_set_uint(&node->cfg.od, entry->index, entry->sub,
                             storage_of(node) != NULL ? 1u : 0u);
    }
}

void co_storage_reset_comm(co_node_t *node)
{
    for (uint8_t sub = 1; sub <= 3; sub++) {
        const co_od_entry_t *e;
        if ((e = co_od_find(&node->cfg.od, 0x1010, sub, NULL)) != NULL) {
            co_storage_show_capability(node, e);
        }
        if ((e = co_od_find(&node->cfg.od, 0x1011, sub, NULL)) != NULL) {
            co_storage_show_capability(node, e);
        }
    }
}
#endif
