/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pdo_rx.c -- RPDOs: length checks, applying the data to the mapped objects (at once or
 * at the next SYNC) and deadline monitoring (see canola/pdo.h); the top of the PDO family,
 * it hands a SYNC and the node's poll to the TPDOs too (pdo_tx.c).
 *
 * Received values are stored with co_od_store, as a PDO is no SDO: no limits, no check
 * hook, no service effects; the entry's written hook runs, and TPDOs mapping the entry
 * see the change as an event.
 */
#include <string.h>

#include "pdo_internal.h"
#include "sync_internal.h" /* co_sync_window_open */

#define EMCY_PDO_LENGTH 0x8210u   /* not processed: shorter than the mapping */
#define EMCY_PDO_EXCEEDED 0x8220u /* longer than the mapping */

/* A slot's value (entry e, `bits` of it) from the frame at bit `pos`, other than a whole
 * number stored as it travels (apply copies those); false when the object's write hook
 * refused it (then nothing changed). A whole value is stored as it comes; a value mapped
 * with fewer bits keeps the bits the frame does not carry. */
static CO_FAST_NOINLINE bool store_item(co_node_t *node, const co_od_entry_t *e, uint8_t bits,
                                        const uint8_t *data, uint32_t pos)
{
    const co_od_t *od = &node->cfg.od;
    /* without bit mapping always a whole value: `bits` are its size */
    uint32_t size =
        CO_CONFIG_PDO_BIT_MAPPING ? co_type_size((co_type_t)co_od_type(od, e)) : bits / 8u;
    const uint8_t *value = data + pos / 8u;
#if CO_CONFIG_PDO_BIT_MAPPING
    uint8_t wire[PDO_VALUE_MAX] = {0};
    if (pos % 8u != 0 || bits != 8u * size) {
        uint32_t n;
        (void)co_od_read(od, e, 0, wire, sizeof wire, &n, NULL); /* unreadable: zeros */
        pdo_copy_bits(wire, 0, data, pos, bits);
        value = wire;
    }
#endif
    if (co_od_store(od, e, value, size) != CO_ABORT_NONE) {
        return false;
    }
    const co_od_hooks_t *hooks = co_od_hooks_of(e);
    if (hooks && hooks->written) {
        hooks->written(od->hook_ctx, e);
    }
    return true;
}

/* Every value of the frame is stored first, then TPDOs hear of the changes (when some TPDO
 * listens): an event-driven TPDO the first one triggers carries the new values of the
 * others too. */
static void apply(co_node_t *node, uint8_t n, const uint8_t *data)
{
    const co_pdo_t *p = &node->rpdo[n];
    const co_od_t *od = &node->cfg.od;
    const co_od_entry_t *stored[CO_PDO_MAP_MAX];
    uint8_t count = 0;
    uint32_t pos = 0;
    for (unsigned i = 0; i < p->count; i++) {
        const co_od_entry_t *e;
        uint32_t whole;
        uint8_t bits = pdo_item(od, p, i, &e, &whole);
        if (whole != 0 && pos % 8u == 0) {
            co_copy_number(co_od_value(od, e), data + pos / 8u, whole);
            stored[count++] = e;
        } else if (e != NULL && store_item(node, e, bits, data, pos)) { /* NULL: a dummy */
            stored[count++] = e;
        }
        pos += bits;
    }
    for (unsigned i = 0; i < count && node->tpdo_listeners != 0; i++) {
        co_pdo_changed(node, stored[i]);
    }
    if (node->cfg.on_rpdo) {
        node->cfg.on_rpdo(node->cfg.user, n);
    }
}

static void length_error(co_node_t *node, co_pdo_t *p, uint16_t code)
{
    pdo_set(p, PDO_F_LEN_ERROR);
    (void)co_emcy_raise(node, code, NULL);
}

/* A length error of this RPDO is over once it arrives with exactly the mapped length
 * (and the codes clear when no other RPDO still has one). */
static void length_ok(co_node_t *node, co_pdo_t *p)
{
    if (!pdo_has(p, PDO_F_LEN_ERROR)) {
        return;
    }
    pdo_clear(p, PDO_F_LEN_ERROR);
    if (!rpdo_other_has(node, p, PDO_F_LEN_ERROR)) {
        (void)co_emcy_clear(node, EMCY_PDO_LENGTH); /* (CO_ERR_NOT_FOUND when not active) */
        (void)co_emcy_clear(node, EMCY_PDO_EXCEEDED);
    }
}

/* Synchronous data waits for the next SYNC; a frame outside the window after the last
 * SYNC is dropped (before any SYNC it waits). */
static CO_SIZE_NOINLINE void hold_for_sync(co_node_t *node, co_pdo_t *p, const co_frame_t *frame)
{
    bool synced = node->sync.last_us != CO_TIME_NEVER;
    if (synced && !co_sync_window_open(node, node->now_us)) {
        return;
    }
    co_copy(p->data, frame->data, frame->len); /* at least the mapped bits (co_pdo_rx) */
    pdo_set(p, PDO_F_WAITING);
}

void co_pdo_rx(co_node_t *node, uint8_t rpdo, const co_frame_t *frame)
{
    if (frame->flags & CO_FRAME_RTR) {
        CO_COUNT(node, rx_malformed); /* RPDOs are not requested */
        return;
    }
    /* `rpdo` comes from a route; the bound is checked all the same before the array is read */
    co_pdo_t *p = rpdo < pdo_rx_count(node) ? &node->rpdo[rpdo] : NULL;
    if (p == NULL || !pdo_active(p)) {
        return;
    }
    if (8u * frame->len < p->bits) {
        length_error(node, p, EMCY_PDO_LENGTH);
        return;
    }
    rpdo_received(node, p);
    if (p->type <= 240) {
        hold_for_sync(node, p, frame);
    } else {
        apply(node, rpdo, frame->data);
    }
    if (frame->len > pdo_bytes(p)) {
        length_error(node, p, EMCY_PDO_EXCEEDED);
    } else {
        length_ok(node, p);
    }
}

/* RPDO n's held data (PDO_F_WAITING) at a SYNC. */
static void rpdo_sync(co_node_t *node, uint8_t n)
{
    co_pdo_t *p = &node->rpdo[n];
    pdo_clear(p, PDO_F_WAITING);
    if (pdo_active(p)) {
        apply(node, n, p->data);
    }
}

/* ---- a SYNC, the poll: RPDOs here, TPDOs in pdo_tx.c */

void co_pdo_sync(co_node_t *node, uint8_t counter)
{
    /* Called as the SYNC is taken (sync.c sets last_us = now_us first): its window is
     * open whatever 0x1007 says, so synchronous PDOs are sent and applied without asking.
     * Both loops test the NMT state first (an application callback may change it). */
    /* The loops end at the last PDO a SYNC drives (count_listeners; read again at each step:
     * an application callback may change the PDOs). */
    for (unsigned n = 0; n < node->rpdo_sync_end && pdo_running(node); n++) {
        if (pdo_has(&node->rpdo[n], PDO_F_WAITING)) { /* only held data has work at a SYNC */
            rpdo_sync(node, (uint8_t)n);
        }
    }
    for (unsigned n = 0; n < node->tpdo_sync_end && pdo_running(node); n++) {
        tpdo_sync(node, &node->tpdo[n], counter);
    }
}

#if CO_CONFIG_PDO_TIMERS
void co_pdo_poll(co_node_t *node, uint64_t now_us)
{
    for (unsigned n = 0; n < pdo_rx_count(node) && pdo_running(node); n++) {
        rpdo_deadline(node, &node->rpdo[n], now_us);
    }
    for (unsigned n = 0; n < pdo_tx_count(node) && pdo_running(node); n++) {
        tpdo_poll(node, &node->tpdo[n], now_us);
    }
}
#endif
