/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pdo_tx.c -- TPDOs: packing the mapped values and sending them by transmission type
 * (see canola/pdo.h), the events of changed values, the event timer's and inhibit time's
 * due work. Values come from co_od_read, so read hooks produce them.
 */
#include <string.h>

#include "pdo_internal.h"

static bool event_driven(const co_pdo_t *p) { return p->type >= 254; }

/* A slot's value (entry e, `bits` of it) into the frame at bit `pos`, other than a whole
 * number stored as it travels (pack copies those): whole bytes straight from co_od_read,
 * anything else through a bit copy of the value's low bits. */
static CO_FAST_NOINLINE void pack_item(const co_od_t *od, const co_od_entry_t *e, uint8_t bits,
                                       uint8_t *out, uint32_t pos)
{
    uint32_t n;
    if (!CO_CONFIG_PDO_BIT_MAPPING || (pos % 8u == 0 && bits % 8u == 0)) {
        (void)co_od_read(od, e, 0, out + pos / 8u, bits / 8u, &n, NULL);
        return;
    }
#if CO_CONFIG_PDO_BIT_MAPPING
    uint8_t wire[PDO_VALUE_MAX] = {0};
    (void)co_od_read(od, e, 0, wire, sizeof wire, &n, NULL);
    pdo_copy_bits(out, pos, wire, 0, bits);
#endif
}

/* The mapped values into `out` (zeroed: bits no item fills stay 0). TPDOs map no dummy
 * entries. */
static void pack(const co_node_t *node, const co_pdo_t *p, uint8_t out[CO_FRAME_DATA_MAX])
{
    const co_od_t *od = &node->cfg.od;
    uint32_t pos = 0;
    for (unsigned i = 0; i < p->count; i++) {
        const co_od_entry_t *e;
        uint32_t whole;
        uint8_t bits = pdo_item(od, p, i, &e, &whole);
        if (whole != 0 && pos % 8u == 0) {
            co_copy_number(out + pos / 8u, co_od_value(od, e), whole);
        } else {
            pack_item(od, e, bits, out, pos);
        }
        pos += bits;
    }
}

/* The TPDO's frame: `data` (a sample), or the mapped values read now (NULL). */
static CO_SIZE_NOINLINE void send_data(co_node_t *node, const co_pdo_t *p, const uint8_t *data)
{
    co_frame_t f;
    co_frame_address(&f, p->cob_id, pdo_bytes(p));
    if (data != NULL) {
        co_copy_fixed(f.data, data, sizeof f.data);
    } else {
        co_zero_fixed(f.data, sizeof f.data);
        pack(node, p, f.data);
    }
    (void)co_node_send_as(node, &f, CO_SVC_PDO);
}

static void send_fresh(co_node_t *node, const co_pdo_t *p) { send_data(node, p, NULL); }

/* An event-driven transmission: the inhibit time and the event timer count from it. */
void tpdo_send_event(co_node_t *node, co_pdo_t *p)
{
    pdo_clear(p, PDO_F_PENDING);
    send_fresh(node, p);
    tpdo_event_sent(node, p);
}

bool tpdo_event(co_node_t *node, co_pdo_t *p)
{
    if (!pdo_active(p) || !pdo_running(node) || (p->type != 0 && !event_driven(p))) {
        return false;
    }
    pdo_set(p, PDO_F_PENDING); /* type 0: goes at the next SYNC */
    if (event_driven(p) && !tpdo_inhibited(node, p)) {
        tpdo_send_event(node, p);
    }
    return true;
}

/* Type 1..240: the n-th SYNC counted (from the one whose counter equals the SYNC start
 * value, when that and the counter are not 0). */
static bool cyclic_due(co_pdo_t *p, uint8_t counter)
{
    if (p->sync_start != 0 && counter != 0 && !pdo_has(p, PDO_F_STARTED)) {
        if (counter != p->sync_start) {
            return false;
        }
        pdo_set(p, PDO_F_STARTED);
        p->sync_count = 0;
        return true;
    }
    p->sync_count++;
    if (p->sync_count < p->type) {
        return false;
    }
    p->sync_count = 0;
    return true;
}

void tpdo_sync(co_node_t *node, co_pdo_t *p, uint8_t counter)
{
    if (!pdo_active(p)) {
        return;
    }
    if (p->type == 0) {
        if (pdo_has(p, PDO_F_PENDING)) {
            pdo_clear(p, PDO_F_PENDING);
            send_fresh(node, p);
        }
    } else if (p->type <= 240) {
        if (cyclic_due(p, counter)) {
            send_fresh(node, p);
        }
    } else if (p->type == 252) {
        co_zero_fixed(p->data, sizeof p->data);
        pack(node, p, p->data);
        pdo_set(p, PDO_F_SAMPLED);
    }
}

void co_pdo_rtr(co_node_t *node, uint8_t tpdo, const co_frame_t *frame)
{
    if (!(frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed); /* data on our own TPDO's COB-ID */
        return;
    }
    if (tpdo >= pdo_tx_count(node) || !pdo_active(&node->tpdo[tpdo])) {
        return;
    }
    co_pdo_t *p = &node->tpdo[tpdo];
    if (p->type == 253) {
        send_fresh(node, p);
    } else if (p->type == 252 && pdo_has(p, PDO_F_SAMPLED)) {
        send_data(node, p, p->data); /* before the first SYNC there is nothing to send */
    }
}

co_err_t co_tpdo_request(co_node_t *node, uint8_t n)
{
    if (n >= pdo_tx_count(node) || !pdo_has(&node->tpdo[n], PDO_F_PRESENT)) {
        return CO_ERR_ARG;
    }
    co_pdo_t *p = &node->tpdo[n];
    if (!pdo_active(p) || !pdo_running(node)) {
        return CO_ERR_STATE;
    }
    (void)tpdo_event(node, p);
    return CO_OK;
}

/* ---- events */

static bool maps_entry(const co_od_t *od, const co_pdo_t *p, const co_od_entry_t *entry)
{
    for (unsigned i = 0; i < p->count; i++) {
        if (pdo_entry(od, p, i) == entry) {
            return true;
        }
    }
    return false;
}

static uint32_t mark_tpdos(co_node_t *node, const co_od_entry_t *entry)
{
    uint32_t marked = 0;
    for (unsigned n = 0; n < pdo_tx_count(node) && pdo_running(node); n++) {
        co_pdo_t *p = &node->tpdo[n];
        if (maps_entry(&node->cfg.od, p, entry) && tpdo_event(node, p)) {
            marked++;
        }
    }
    return marked;
}

void co_pdo_changed(co_node_t *node, const co_od_entry_t *entry)
{
    if (node->tpdo_listeners == 0) {
        return; /* no TPDO listens (see count_listeners) */
    }
    if ((co_od_attr(&node->cfg.od, entry) & CO_OD_TPDO) && pdo_running(node)) {
        (void)mark_tpdos(node, entry);
    }
}

uint32_t co_pdo_event(co_node_t *node, uint16_t index, uint8_t sub)
{
    const co_od_entry_t *entry = co_od_find(&node->cfg.od, index, sub, NULL);
    return entry != NULL ? mark_tpdos(node, entry) : 0;
}

#if CO_CONFIG_PDO_TIMERS
/* An event-driven TPDO at the poll: the event timer is an event; a pending event goes once
 * the inhibit time is over. The next deadlines go to co_node_schedule. */
void tpdo_poll(co_node_t *node, co_pdo_t *p, uint64_t now_us)
{
    if (!pdo_active(p) || !event_driven(p)) {
        return;
    }
    if (now_us >= p->next_us) {
        p->next_us = CO_TIME_NEVER;
        pdo_set(p, PDO_F_PENDING);
    }
    if (pdo_has(p, PDO_F_PENDING) && now_us >= p->inhibit_until_us) {
        tpdo_send_event(node, p);
    }
    if (pdo_has(p, PDO_F_PENDING)) {
        co_node_schedule(node, p->inhibit_until_us);
    }
    co_node_schedule(node, p->next_us);
}
#endif
