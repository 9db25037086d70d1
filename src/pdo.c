/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pdo.c -- the base of the PDO family (see canola/pdo.h): what RPDOs and TPDOs share. The
 * dictionary's PDOs, loading their communication parameters and restarting their state
 * (the event timer's start included), the rules of writes to 0x1400..0x1BFF, routes, and
 * the counts a SYNC and a changed value look at. It calls nothing above it: pdo_timers.c
 * (the timers' decisions), pdo_tx.c (TPDOs) and pdo_rx.c (RPDOs, the SYNC's and the
 * poll's PDO work) call down to it, in that order; mappings are pdo_map.c, below it.
 *
 * Node slot n is PDO number n + 1 (0x1400 + n, 0x1800 + n), CO_RPDO_MAX / CO_TPDO_MAX of
 * them; the slots of PDOs the dictionary lacks stay not present. Parameters are
 * loaded at reset communication and when written through the node; values set natively
 * (co_od_set_uint) count from the next reset communication.
 */
#include "pdo_internal.h"

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

/* The node's PDOs of one direction, `*count` of them. The loops over both directions below
 * run over the two tables in turn (one loop body instead of two: less code). */
static co_pdo_t *pdo_table(co_node_t *node, bool tpdo, unsigned *count)
{
    *count = tpdo ? pdo_tx_count(node) : pdo_rx_count(node);
    return tpdo ? node->tpdo : node->rpdo;
}

static co_pdo_t *pdo_slot(co_node_t *node, bool tpdo, uint16_t num)
{
    unsigned count;
    co_pdo_t *table = pdo_table(node, tpdo, &count);
    return num < count ? &table[num] : NULL;
}

/* ---- loading parameters */

static void load_comm(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    uint16_t idx = pdo_comm_index(tpdo, num);
    const co_od_entry_t *cob = co_od_find(&node->cfg.od, idx, 1, NULL);
    p->flags = cob ? PDO_F_PRESENT : 0;
    p->cob_id = cob ? (uint32_t)co_od_entry_uint(&node->cfg.od, cob) : CO_COB_INVALID;
    p->type = (uint8_t)co_od_u32(node, idx, 2, 255);
#if CO_CONFIG_PDO_TIMERS
    p->event_ms = (uint16_t)co_od_u32(node, idx, 5, 0);
    p->inhibit = tpdo ? (uint16_t)co_od_u32(node, idx, 3, 0) : 0;
#endif
    p->sync_start = tpdo ? (uint8_t)co_od_u32(node, idx, 6, 0) : 0;
}

/* Runtime state from scratch: timers off, nothing pending; in operational the TPDO's
 * event timer starts and RPDO monitoring waits for the first frame. A missed deadline or
 * a length error stays reported until the next RPDO clears it. */
static CO_SIZE_NOINLINE void restart(co_node_t *node, co_pdo_t *p, bool tpdo)
{
    pdo_clear(p, PDO_F_PENDING | PDO_F_SAMPLED | PDO_F_STARTED | PDO_F_WAITING);
    pdo_timers_restart(p);
    p->sync_count = 0;
    if (tpdo) {
        tpdo_start(node, p);
    }
}

#if CO_CONFIG_PDO_TIMERS
void tpdo_start(co_node_t *node, co_pdo_t *p)
{
    p->next_us = CO_TIME_NEVER;
    if (pdo_active(p) && pdo_running(node) && p->type >= 254 && p->event_ms != 0) {
        p->next_us = node->now_us + co_ms_to_us(p->event_ms);
        co_node_schedule(node, p->next_us);
    }
}
#endif

/* Another RPDO than `self` has `flag` set. */
bool rpdo_other_has(const co_node_t *node, const co_pdo_t *self, unsigned flag)
{
    for (unsigned n = 0; n < pdo_rx_count(node); n++) {
        const co_pdo_t *p = &node->rpdo[n];
        if (p != self && pdo_has(p, flag)) {
            return true;
        }
    }
    return false;
}

/* ---- node hooks */

/* Every active RPDO listens to its COB-ID; a TPDO, for its remote requests, when it is sent on
 * request only (types 252 and 253) and its COB-ID allows them. */
static void route(co_node_t *node, const co_pdo_t *p, bool tpdo, uint16_t num)
{
    bool rtr_only = p->type == 252 || p->type == 253;
    bool listens = pdo_active(p) && (!tpdo || (rtr_only && !(p->cob_id & PDO_RTR_NOT_ALLOWED)));
    co_route_set(node, tpdo ? CO_ROUTE_TPDO_RTR : CO_ROUTE_RPDO, (uint8_t)num,
                 listens ? co_cob_key(p->cob_id) : CO_ROUTE_OFF);
}

/* New parameters or a new mapping take effect: the runtime state, the route. */
static CO_SIZE_NOINLINE void take_effect(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    restart(node, p, tpdo);
    route(node, p, tpdo, num);
}

static void load_pdo(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    load_comm(node, p, tpdo, num);
    pdo_load_mapping(node, p, tpdo, num);
    take_effect(node, p, tpdo, num);
}

/* How many TPDOs an object change can trigger (active, type 0 or event-driven): when
 * none, a changed value costs no search; and how far a SYNC needs to look among TPDOs and
 * RPDOs. Counted again whenever a PDO changes. */
static void count_listeners(co_node_t *node)
{
    uint16_t listeners = 0;
    uint16_t sync_end[2] = {0, 0}; /* RPDOs, TPDOs: 1 + the last one a SYNC drives */
    for (int tpdo = 0; tpdo <= 1; tpdo++) {
        unsigned count;
        const co_pdo_t *table = pdo_table(node, tpdo, &count);
        for (unsigned n = 0; n < count; n++) {
            uint8_t type = table[n].type;
            if (!pdo_active(&table[n])) {
                continue;
            }
            if (type <= 240 || (tpdo && type == 252)) {
                sync_end[tpdo] = (uint16_t)(n + 1u);
            }
            listeners = (uint16_t)(listeners + (tpdo && (type == 0 || type >= 254)));
        }
    }
    node->tpdo_listeners = listeners;
    node->rpdo_sync_end = sync_end[0]; /* a SYNC looks at no RPDO past this one */
    node->tpdo_sync_end = sync_end[1]; /* nor at a TPDO past this one */
}

void co_pdo_reset_comm(co_node_t *node)
{
    for (int tpdo = 0; tpdo <= 1; tpdo++) {
        unsigned count;
        co_pdo_t *table = pdo_table(node, tpdo, &count);
        for (unsigned n = 0; n < count; n++) {
            load_pdo(node, &table[n], tpdo, (uint16_t)n);
        }
    }
    count_listeners(node);
}

void co_pdo_state_entered(co_node_t *node)
{
    for (unsigned n = 0; n < pdo_rx_count(node); n++) {
        restart(node, &node->rpdo[n], false);
    }
    for (unsigned n = 0; n < pdo_tx_count(node); n++) {
        restart(node, &node->tpdo[n], true);
    }
}

/* ---- writes to 0x1400..0x1BFF */

static uint32_t od_cob_id(const co_node_t *node, pdo_ref_t r)
{
    return co_od_u32(node, pdo_comm_index(r.tpdo, r.num), 1, CO_COB_INVALID);
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

co_abort_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                              uint32_t len)
{
    pdo_ref_t r = pdo_ref(entry->index);
    if (r.mapping) {
        return pdo_check_mapping(node, r.tpdo, r.num, entry->sub, data, len);
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
    if (CO_CONFIG_PDO_DYNAMIC && r.mapping) {
        pdo_load_mapping(node, p, r.tpdo, r.num);
    } else {
        uint8_t flags = p->flags;
        load_comm(node, p, r.tpdo, r.num);
        p->flags = (uint8_t)(p->flags | (flags & (PDO_F_TIMED_OUT | PDO_F_LEN_ERROR)));
    }
    take_effect(node, p, r.tpdo, r.num);
    count_listeners(node);
}
