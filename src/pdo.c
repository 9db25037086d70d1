/*
 * pdo.c -- what RPDOs and TPDOs share (see canola/pdo.h): binding the dictionary's PDOs,
 * loading their communication parameters, resolving mappings, the re-mapping rules of
 * writes to 0x1400..0x1BFF, routes, and handing NMT states, SYNCs and time to
 * pdo_rx.c / pdo_tx.c.
 *
 * Node slot n is PDO number n + 1 (0x1400 + n, 0x1800 + n); rpdo_count / tpdo_count
 * reach up to the highest such PDO below CO_RPDO_MAX / CO_TPDO_MAX that the dictionary
 * has, and slots in gaps stay not present. Parameters are loaded at reset communication
 * and when written through the node; values set natively (co_od_set_uint) count from the
 * next reset communication.
 */
#include "pdo_internal.h"

#define PDO_MAP_BITS_MAX 64u

static inline uint16_t rpdo_max(void) { return CO_RPDO_MAX; }
static inline uint16_t tpdo_max(void) { return CO_TPDO_MAX; }

/* Which PDO an index of 0x1400..0x1BFF belongs to. */
typedef struct pdo_ref {
    bool tpdo;
    bool mapping;
    uint16_t num; /* 0..511: PDO number - 1 */
} pdo_ref_t;

static pdo_ref_t pdo_ref(uint16_t index)
{
    uint16_t off = (uint16_t)(index - 0x1400u);
    return (pdo_ref_t){
        .tpdo = off >= 0x400u, .mapping = (off & 0x200u) != 0, .num = (uint16_t)(off & 0x1FFu)};
}

static uint16_t comm_index(bool tpdo, uint16_t num)
{
    return (uint16_t)((tpdo ? 0x1800u : 0x1400u) + num);
}

static uint16_t map_index(bool tpdo, uint16_t num)
{
    return (uint16_t)((tpdo ? 0x1A00u : 0x1600u) + num);
}

static co_pdo_t *pdo_slot(co_node_t *node, bool tpdo, uint16_t num)
{
    if (tpdo) {
        return num < node->tpdo_count ? &node->tpdo[num] : NULL;
    }
    return num < node->rpdo_count ? &node->rpdo[num] : NULL;
}

/* Integer value of an optional entry; `absent` when the dictionary lacks it. */
static uint64_t od_uint(const co_node_t *node, uint16_t index, uint8_t sub, uint64_t absent)
{
    uint64_t v = absent;
    (void)co_od_get_uint(&node->cfg.od, index, sub, &v);
    return v;
}

void pdo_copy_bits(uint8_t *dst, uint32_t dpos, const uint8_t *src, uint32_t spos, uint32_t n)
{
    /* At most 64 bits per PDO: a bit at a time is simple and cheap enough. */
    for (uint32_t i = 0; i < n; i++) {
        uint32_t s = spos + i;
        uint32_t d = dpos + i;
        unsigned bit = ((unsigned)src[s / 8u] >> (s % 8u)) & 1u;
        unsigned mask = 1u << (d % 8u);
        dst[d / 8u] = (uint8_t)((dst[d / 8u] & ~mask) | (bit << (d % 8u)));
    }
}

/* ---- mapping resolution */

/* An object can carry PDO data in this direction: a fixed size of 1..8 bytes, the PDO
 * attribute, and storage or a hook to read (TPDO) / take (RPDO) the value. */
static bool mappable(const co_od_entry_t *e, bool tpdo)
{
    uint32_t size = co_type_size((co_type_t)e->type);
    if (!(e->attr & (tpdo ? CO_OD_TPDO : CO_OD_RPDO)) || size == 0 || size > 8) {
        return false;
    }
    bool hook = e->hooks && (tpdo ? e->hooks->read != NULL : e->hooks->write != NULL);
    return e->value != NULL || hook;
}

/* One mapping entry value (index << 16 | sub << 8 | bits) to an item. */
static co_abort_t resolve_item(const co_od_t *od, uint32_t value, bool tpdo, co_pdo_item_t *item)
{
    uint16_t index = (uint16_t)(value >> 16);
    uint8_t bits = (uint8_t)value;
    item->entry = NULL;
    item->direct = false;
    item->bits = bits;
    if (bits == 0) {
        return CO_ABORT_NO_MAP;
    }
    if (index >= CO_TYPE_BOOLEAN && index <= CO_TYPE_UNSIGNED32) {
        /* a dummy entry: skips bits of a received frame */
        bool fits = bits <= 8u * co_type_size((co_type_t)index);
        return (!tpdo && fits) ? CO_ABORT_NONE : CO_ABORT_NO_MAP;
    }
    const co_od_entry_t *e = co_od_find(od, index, (uint8_t)(value >> 8), NULL);
    if (e == NULL || !mappable(e, tpdo) || bits > 8u * co_type_size((co_type_t)e->type)) {
        return CO_ABORT_NO_MAP;
    }
    item->entry = e;
    /* A whole number stored as it travels (and no hook to run): copied straight to and
     * from the frame. */
    uint32_t len = 0;
    uint32_t size = co_type_size((co_type_t)e->type);
    bool whole = bits == 8u * size && size != 0;
    bool plain = e->hooks == NULL && co_od_wire_data(od, e, &len) == e->value && len == size;
    item->direct = whole && plain;
    return CO_ABORT_NONE;
}

/* Every item is copied straight between the frame and storage (no dummy entry, no bit
 * offset): the frame then packs and unpacks with plain copies (pdo_rx.c, pdo_tx.c). */
static bool all_direct(const co_pdo_t *p)
{
    for (uint8_t i = 0; i < p->count; i++) {
        if (!p->items[i].direct || p->items[i].bits % 8u != 0) {
            return false;
        }
    }
    return true;
}

/* Resolve entries 1..n of mapping object `index` into out's items, count and bits. */
static co_abort_t resolve_mapping(const co_od_t *od, uint16_t index, uint8_t n, bool tpdo,
                                  co_pdo_t *out)
{
    out->count = 0;
    out->bits = 0;
    out->plain = false;
    if (n == 0) {
        return CO_ABORT_NONE;
    }
    if (co_od_find(od, index, n, NULL) == NULL) {
        return CO_ABORT_VALUE_HIGH; /* more entries than the object has */
    }
    if (n > CO_PDO_MAP_MAX) {
        return CO_ABORT_MAP_LEN;
    }
    uint32_t total = 0;
    for (uint8_t k = 0; k < n; k++) {
        const co_od_entry_t *e = co_od_find(od, index, (uint8_t)(k + 1u), NULL);
        if (e == NULL) {
            return CO_ABORT_VALUE_HIGH;
        }
        co_abort_t abort = resolve_item(od, (uint32_t)co_od_entry_uint(e), tpdo, &out->items[k]);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
        total += out->items[k].bits;
        if (total > PDO_MAP_BITS_MAX) {
            return CO_ABORT_MAP_LEN;
        }
    }
    out->count = n;
    out->bits = (uint8_t)total;
    out->plain = n > 0 && all_direct(out);
    return CO_ABORT_NONE;
}

/* ---- loading parameters */

static void load_comm(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    uint16_t idx = comm_index(tpdo, num);
    const co_od_entry_t *cob = co_od_find(&node->cfg.od, idx, 1, NULL);
    p->flags = cob ? PDO_F_PRESENT : 0;
    p->cob_id = cob ? (uint32_t)co_od_entry_uint(cob) : CO_COB_INVALID;
    p->type = (uint8_t)od_uint(node, idx, 2, 255);
    pdo_timers_load(node, p, tpdo, idx);
    p->sync_start = tpdo ? (uint8_t)od_uint(node, idx, 6, 0) : 0;
}

/* A mapping that does not resolve (set natively, or stored before the rules) maps
 * nothing: the PDO then does nothing until it is re-mapped. */
static void load_mapping(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    uint16_t idx = map_index(tpdo, num);
    uint8_t n = (uint8_t)od_uint(node, idx, 0, 0);
    if (resolve_mapping(&node->cfg.od, idx, n, tpdo, p) != CO_ABORT_NONE) {
        p->count = 0;
        p->bits = 0;
        p->plain = false;
    }
}

/* Runtime state from scratch: timers off, nothing pending; in operational the TPDO's
 * event timer starts and RPDO monitoring waits for the first frame. A missed deadline or
 * a length error stays reported until the next RPDO clears it. */
static void restart(co_node_t *node, co_pdo_t *p, bool tpdo)
{
    pdo_clear(p, PDO_F_PENDING | PDO_F_SAMPLED | PDO_F_STARTED | PDO_F_WAITING);
    pdo_timers_restart(p);
    p->sync_count = 0;
    p->len = 0;
    if (tpdo) {
        tpdo_start(node, p);
    }
}

/* ---- node hooks */

/* 1 + the highest PDO number below `max` whose communication object exists. */
static uint16_t count_present(const co_od_t *od, uint16_t base, uint16_t max)
{
    uint16_t count = 0;
    for (uint16_t n = 0; n < max; n++) {
        if (co_od_find(od, (uint16_t)(base + n), 1, NULL) != NULL) {
            count = (uint16_t)(n + 1u);
        }
    }
    return count;
}

co_err_t co_pdo_bind(co_node_t *node)
{
    node->rpdo_count = count_present(&node->cfg.od, 0x1400u, rpdo_max());
    node->tpdo_count = count_present(&node->cfg.od, 0x1800u, tpdo_max());
    return CO_OK;
}

/* After parameters or mapping loaded (NMT states do not change it): may a frame of this
 * RPDO take the short path (co_pdo_rx), may this TPDO be sent by co_pdo_sync's? */
static bool fast_widths(const co_pdo_t *p)
{
    for (uint8_t i = 0; i < p->count; i++) {
        uint8_t b = p->items[i].bits;
        if (b != 8 && b != 16 && b != 32 && b != 64) {
            return false; /* pdo_copy_fast copies 1, 2, 4 or 8 bytes */
        }
    }
    return true;
}

static void decide_fast(co_pdo_t *p, bool tpdo)
{
    bool plain = p->plain && fast_widths(p);
    if (tpdo) {
        bool cyclic = p->type >= 1 && p->type <= 240 && p->sync_start == 0;
        co_frame_t f = co_cob_frame(p->cob_id, pdo_bytes(p)); /* the header, built once */
        p->fast = pdo_active(p) && plain && cyclic ? f.len : 0;
        p->frame_id = f.id;
        p->frame_flags = f.flags;
        return;
    }
    bool fast = pdo_active(p) && plain && p->type > 240 && !rpdo_monitored(p);
    p->fast = fast ? pdo_bytes(p) : 0; /* a plain mapping fills at least one byte */
}

static void load_pdo(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    load_comm(node, p, tpdo, num);
    load_mapping(node, p, tpdo, num);
    decide_fast(p, tpdo);
    restart(node, p, tpdo);
}

/* How many TPDOs an object change can trigger (active, type 0 or event-driven): when
 * none, a changed value costs no search; and how far a SYNC needs to look among TPDOs and
 * RPDOs. Counted again whenever a PDO changes. */
static void count_listeners(co_node_t *node)
{
    uint16_t listeners = 0;
    uint16_t sync_end = 0;
    for (uint16_t n = 0; n < node->tpdo_count; n++) {
        const co_pdo_t *p = &node->tpdo[n];
        if (pdo_active(p) && (p->type == 0 || p->type >= 254)) {
            listeners++;
        }
        if (pdo_active(p) && (p->type <= 240 || p->type == 252)) {
            sync_end = (uint16_t)(n + 1u);
        }
    }
    node->tpdo_listeners = listeners;
    node->tpdo_sync_end = sync_end; /* a SYNC looks at no TPDO past this one */
    uint16_t rx_end = 0;
    for (uint16_t n = 0; n < node->rpdo_count; n++) {
        if (pdo_active(&node->rpdo[n]) && node->rpdo[n].type <= 240) {
            rx_end = (uint16_t)(n + 1u);
        }
    }
    node->rpdo_sync_end = rx_end; /* nor at an RPDO past this one */
}

void co_pdo_reset_comm(co_node_t *node)
{
    for (uint16_t n = 0; n < node->rpdo_count; n++) {
        load_pdo(node, &node->rpdo[n], false, n);
    }
    for (uint16_t n = 0; n < node->tpdo_count; n++) {
        load_pdo(node, &node->tpdo[n], true, n);
    }
    count_listeners(node);
}

void co_pdo_add_routes(co_node_t *node)
{
    for (uint16_t n = 0; n < node->rpdo_count; n++) {
        const co_pdo_t *p = &node->rpdo[n];
        if (pdo_active(p)) {
            co_routes_add(node, co_cob_key(p->cob_id), CO_ROUTE_RPDO, (uint8_t)n);
        }
    }
    for (uint16_t n = 0; n < node->tpdo_count; n++) {
        const co_pdo_t *p = &node->tpdo[n];
        bool rtr_only = p->type == 252 || p->type == 253;
        if (pdo_active(p) && rtr_only && !(p->cob_id & PDO_RTR_NOT_ALLOWED)) {
            co_routes_add(node, co_cob_key(p->cob_id), CO_ROUTE_TPDO_RTR, (uint8_t)n);
        }
    }
}

void co_pdo_state_entered(co_node_t *node)
{
    for (uint16_t n = 0; n < node->rpdo_count; n++) {
        restart(node, &node->rpdo[n], false);
    }
    for (uint16_t n = 0; n < node->tpdo_count; n++) {
        restart(node, &node->tpdo[n], true);
    }
}

void co_pdo_sync(co_node_t *node, uint8_t counter)
{
    /* Called as the SYNC is taken (sync.c sets last_us = now_us first): its window is
     * open whatever 0x1007 says, so synchronous PDOs are sent and applied without asking.
     * Both loops test the NMT state first (an application callback may change it). */
    for (uint16_t n = 0; n < node->rpdo_sync_end && pdo_running(node); n++) {
        if (pdo_has(&node->rpdo[n], PDO_F_WAITING)) { /* only held data has work at a SYNC */
            rpdo_sync(node, (uint8_t)n);
        }
    }
    for (uint16_t n = 0; n < node->tpdo_sync_end && pdo_running(node); n++) {
        co_pdo_t *p = &node->tpdo[n];
        if (!p->fast) {
            tpdo_sync(node, p, counter);
        } else if (++p->sync_count >= p->type) { /* the usual one: cyclic, whole values */
            p->sync_count = 0;
            tpdo_send_plain(node, p);
        }
    }
}

/* ---- events */

static bool maps_entry(const co_pdo_t *p, const co_od_entry_t *entry)
{
    for (uint8_t i = 0; i < p->count; i++) {
        if (p->items[i].entry == entry) {
            return true;
        }
    }
    return false;
}

static uint32_t mark_tpdos(co_node_t *node, const co_od_entry_t *entry)
{
    uint32_t marked = 0;
    for (uint16_t n = 0; n < node->tpdo_count && pdo_running(node); n++) {
        co_pdo_t *p = &node->tpdo[n];
        if (maps_entry(p, entry) && tpdo_event(node, p)) {
            marked++;
        }
    }
    return marked;
}

void co_pdo_changed(co_node_t *node, const co_od_entry_t *entry)
{
    if (node->tpdo_listeners != 0 && (entry->attr & CO_OD_TPDO) && pdo_running(node)) {
        (void)mark_tpdos(node, entry);
    }
}

uint32_t co_pdo_event(co_node_t *node, uint16_t index, uint8_t sub)
{
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, NULL);
    return entry != NULL ? mark_tpdos(node, entry) : 0;
}

/* ---- writes to 0x1400..0x1BFF */

static uint32_t od_cob_id(const co_node_t *node, pdo_ref_t r)
{
    return (uint32_t)od_uint(node, comm_index(r.tpdo, r.num), 1, CO_COB_INVALID);
}

static bool type_allowed(uint8_t type, bool tpdo)
{
    if (tpdo) {
        return type <= 240 || type >= 252;
    }
    return type <= 240 || type >= 254; /* 241..253 are reserved for RPDOs */
}

static co_abort_t check_comm(const co_node_t *node, pdo_ref_t r, uint8_t sub, const uint8_t *data,
                             uint32_t len)
{
    if (sub == 1 && len == 4) {
        uint32_t cob = co_get_u32(data);
        uint32_t old = od_cob_id(node, r);
        bool both_valid = !(old & CO_COB_INVALID) && !(cob & CO_COB_INVALID);
        return (!co_cob_valid(cob) || (both_valid && cob != old)) ? CO_ABORT_VALUE : CO_ABORT_NONE;
    }
    if (sub == 2 && len == 1) {
        return type_allowed(data[0], r.tpdo) ? CO_ABORT_NONE : CO_ABORT_VALUE;
    }
    return CO_ABORT_NONE;
}

/* The re-mapping procedure: the PDO not valid, sub0 = 0 while entries change, then
 * sub0 = N, checked against the dictionary. */
static co_abort_t check_mapping(const co_node_t *node, pdo_ref_t r, uint8_t sub,
                                const uint8_t *data, uint32_t len)
{
    uint16_t idx = map_index(r.tpdo, r.num);
    if (!(od_cob_id(node, r) & CO_COB_INVALID)) {
        return CO_ABORT_UNSUPPORTED;
    }
    if (sub != 0) {
        return od_uint(node, idx, 0, 0) != 0 ? CO_ABORT_UNSUPPORTED : CO_ABORT_NONE;
    }
    if (len != 1) {
        return CO_ABORT_NONE; /* the length check has refused it already */
    }
    co_pdo_t trial;
    return resolve_mapping(&node->cfg.od, idx, data[0], r.tpdo, &trial);
}

co_abort_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                              uint32_t len)
{
    pdo_ref_t r = pdo_ref(entry->index);
    if (r.mapping) {
        return check_mapping(node, r, entry->sub, data, len);
    }
    return check_comm(node, r, entry->sub, data, len);
}

void co_pdo_written(co_node_t *node, const co_od_entry_t *entry)
{
    pdo_ref_t r = pdo_ref(entry->index);
    co_pdo_t *p = pdo_slot(node, r.tpdo, r.num);
    if (p == NULL || (r.mapping && entry->sub != 0)) {
        return; /* not handled, or a mapping entry: it counts when sub0 is written */
    }
    uint32_t old_cob = p->cob_id;
    uint8_t old_type = p->type;
    bool was_active = pdo_active(p);
    if (r.mapping) {
        load_mapping(node, p, r.tpdo, r.num);
    } else {
        uint8_t flags = p->flags;
        load_comm(node, p, r.tpdo, r.num);
        p->flags = (uint8_t)(p->flags | (flags & (PDO_F_TIMED_OUT | PDO_F_LEN_ERROR)));
    }
    decide_fast(p, r.tpdo);
    restart(node, p, r.tpdo);
    count_listeners(node);
    if (p->cob_id != old_cob || p->type != old_type || pdo_active(p) != was_active) {
        co_routes_rebuild(node);
    }
}
