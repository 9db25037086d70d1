/*
 * emcy.c -- emergency objects: the EMCY producer (with the error register 0x1001
 * and the error history 0x1003) and the EMCY consumer (0x1028). See canola/emcy.h.
 */
#include <string.h>

#include "internal.h"

#define EMCY_COB_BASE 0x80u
#define EMCY_CODE_RESET 0x0000u /* "error reset / no error" */
#define EMCY_INHIBIT_UNIT_US 100u

#define REG_GENERIC 0x01u

/* ---- error register */

uint8_t co_emcy_register_bit(uint16_t code)
{
    switch (code >> 12) {
    case 0x2:
        return 0x02; /* current */
    case 0x3:
        return 0x04; /* voltage */
    case 0x4:
        return 0x08; /* temperature */
    default:
        break;
    }
    if (code >= 0x8100u && code <= 0x8FFFu) {
        return 0x10; /* communication */
    }
    if (code >= 0xFF00u) {
        return 0x80; /* manufacturer-specific */
    }
    return 0;
}

/* The register as the active errors make it. */
static uint8_t register_of_active(const co_node_t *node)
{
    const co_emcy_t *e = &node->emcy;
    uint8_t reg = e->active_count ? REG_GENERIC : 0;
    for (uint8_t i = 0; i < e->active_count; i++) {
        reg = (uint8_t)(reg | co_emcy_register_bit(e->active[i]));
    }
    return reg;
}

static void register_store(co_node_t *node, uint8_t reg)
{
    (void)co_od_set_uint(&node->cfg.od, 0x1001, 0, reg); /* no 0x1001: nothing to keep */
}

/* ---- active errors */

static int active_find(const co_node_t *node, uint16_t code)
{
    for (uint8_t i = 0; i < node->emcy.active_count; i++) {
        if (node->emcy.active[i] == code) {
            return i;
        }
    }
    return -1;
}

bool co_emcy_active(const co_node_t *node, uint16_t code) { return active_find(node, code) >= 0; }

/* ---- error history 0x1003 */

/* The recorded value: error code in the low 16 bits, the first two manufacturer bytes
 * (little-endian) as the "additional information" in the high 16 bits. */
static uint32_t history_value(uint16_t code, const uint8_t mfr[5])
{
    return (uint32_t)code | ((uint32_t)co_get_u16(mfr) << 16);
}

/* Newest at sub1: every recorded value moves one sub down; the oldest falls off the end
 * of what the OD holds. */
static void history_record(co_node_t *node, uint32_t value)
{
    const co_od_t *od = &node->cfg.od;
    uint64_t count = 0;
    if (co_od_get_uint(od, 0x1003, 0, &count) != CO_OK) {
        return; /* no history in this dictionary */
    }
    uint64_t carry = value;
    uint8_t subs = 0;
    for (uint8_t sub = 1; sub != 0; sub++) {
        uint64_t old = 0;
        if (co_od_get_uint(od, 0x1003, sub, &old) != CO_OK) {
            break;
        }
        (void)co_od_set_uint(od, 0x1003, sub, carry);
        carry = old;
        subs = sub;
    }
    (void)co_od_set_uint(od, 0x1003, 0, count < subs ? count + 1 : subs);
}

static void history_clear(co_node_t *node)
{
    const co_od_t *od = &node->cfg.od;
    (void)co_od_set_uint(od, 0x1003, 0, 0);
    for (uint8_t sub = 1; sub != 0; sub++) {
        if (co_od_set_uint(od, 0x1003, sub, 0) != CO_OK) {
            break;
        }
    }
}

/* ---- producer: frames, inhibit time and queue */

/* The COB-ID object 0x1014; without one, the pre-defined 0x80 + node-ID. */
static uint32_t producer_cob(const co_node_t *node)
{
    uint64_t cob = EMCY_COB_BASE + node->node_id;
    (void)co_od_get_uint(&node->cfg.od, 0x1014, 0, &cob);
    return (uint32_t)cob;
}

static bool producer_off(const co_node_t *node)
{
    return (producer_cob(node) & CO_COB_INVALID) != 0;
}

static uint64_t inhibit_us(const co_node_t *node)
{
    uint64_t units = 0;
    (void)co_od_get_uint(&node->cfg.od, 0x1015, 0, &units);
    return units * EMCY_INHIBIT_UNIT_US;
}

/* Earliest time the next frame may leave (the inhibit time counts from the latest frame,
 * with the value 0x1015 has now, so a new inhibit time applies at once). */
static uint64_t producer_free_at(const co_node_t *node)
{
    if (node->emcy.last_us == CO_TIME_NEVER) {
        return 0;
    }
    return node->emcy.last_us + inhibit_us(node);
}

static void frame_send(co_node_t *node, const uint8_t data[8], uint64_t now_us)
{
    co_frame_t f = co_cob_frame(producer_cob(node), 8);
    memcpy(f.data, data, 8);
    (void)co_node_send_as(node, &f, CO_SVC_EMCY); /* a full tx queue counts the loss itself */
    node->emcy.last_us = now_us;
}

static void queue_pop(co_emcy_t *e)
{
    e->queue_count--;
    memmove(e->queue[0], e->queue[1], (size_t)e->queue_count * sizeof e->queue[0]);
}

/* Send what waits and may leave now; returns when the next waiting frame may leave
 * (CO_TIME_NEVER when none waits, or while the NMT state holds EMCY back). */
static uint64_t queue_drain(co_node_t *node, uint64_t now_us)
{
    co_emcy_t *e = &node->emcy;
    if (e->queue_count == 0 || !(node->services & CO_SVC_EMCY)) {
        return CO_TIME_NEVER;
    }
    if (producer_off(node)) {
        e->queue_count = 0; /* 0x1014 set invalid behind the node's back: send nothing */
        return CO_TIME_NEVER;
    }
    while (e->queue_count > 0) {
        uint64_t free_at = producer_free_at(node);
        if (now_us < free_at) {
            return free_at;
        }
        frame_send(node, e->queue[0], now_us);
        queue_pop(e);
    }
    return CO_TIME_NEVER;
}

/* One EMCY frame: out now when nothing waits before it, else into the queue. */
static void emit(co_node_t *node, uint16_t code, uint8_t reg, const uint8_t mfr[5])
{
    if (producer_off(node)) {
        return; /* EMCY off: errors and history are kept, nothing is sent */
    }
    uint8_t data[8];
    co_put_u16(data, code);
    data[2] = reg;
    memcpy(&data[3], mfr, 5);
    co_emcy_t *e = &node->emcy;
    (void)queue_drain(node, node->now_us); /* make room: frames due may leave first */
    if (e->queue_count >= CO_EMCY_QUEUE_LEN) {
        e->dropped++; /* the newest is the one lost: the queue keeps the order of events */
        return;
    }
    memcpy(e->queue[e->queue_count], data, 8);
    e->queue_count++;
    co_node_schedule(node, queue_drain(node, node->now_us));
}

/* ---- raise and clear */

co_err_t co_emcy_raise(co_node_t *node, uint16_t code, const uint8_t *manufacturer)
{
    static const uint8_t zeros[5] = {0};
    if (code == EMCY_CODE_RESET) {
        return CO_ERR_ARG;
    }
    const uint8_t *mfr = manufacturer ? manufacturer : zeros;
    co_emcy_t *e = &node->emcy;
    co_err_t err = CO_OK;
    if (active_find(node, code) < 0) {
        if (e->active_count < CO_EMCY_ACTIVE_MAX) {
            e->active[e->active_count++] = code;
        } else {
            err = CO_ERR_FULL;
        }
    }
    /* An error the table could not keep still shows in the register until the next
     * change recomputes it from the errors kept. */
    uint8_t reg = (uint8_t)(register_of_active(node) | REG_GENERIC | co_emcy_register_bit(code));
    register_store(node, reg);
    history_record(node, history_value(code, mfr));
    emit(node, code, reg, mfr);
    return err;
}

co_err_t co_emcy_clear(co_node_t *node, uint16_t code)
{
    static const uint8_t zeros[5] = {0};
    int at = active_find(node, code);
    if (at < 0) {
        return CO_ERR_NOT_FOUND;
    }
    co_emcy_t *e = &node->emcy;
    e->active_count--;
    e->active[at] = e->active[e->active_count]; /* order does not matter */
    uint8_t reg = register_of_active(node);
    register_store(node, reg);
    if (e->active_count == 0) {
        emit(node, EMCY_CODE_RESET, reg, zeros);
    }
    return CO_OK;
}

/* ---- bus events */

void co_node_bus_event(co_node_t *node, co_bus_event_t event)
{
    switch (event) {
    case CO_BUS_RX_OVERRUN:
        /* An event, not a state the driver reports the end of: it stays active until the
         * application clears it (co_emcy_clear(node, 0x8110)). */
        (void)co_emcy_raise(node, 0x8110, NULL);
        break;
    case CO_BUS_ERROR_PASSIVE:
        if (!co_emcy_active(node, 0x8120)) { /* a state: reported once while it lasts */
            (void)co_emcy_raise(node, 0x8120, NULL);
        }
        break;
    case CO_BUS_ERROR_ACTIVE:
        (void)co_emcy_clear(node, 0x8120);
        break;
    case CO_BUS_OFF:
        co_node_error_behaviour(node); /* nothing can be sent while bus-off: no EMCY */
        break;
    case CO_BUS_OFF_RECOVERED:
        /* Like the overrun, the application clears 0x8140. Recovery restarts the error
         * counters, so the controller is error active again: 0x8120 ends (after the
         * raise, so that this costs one frame, not an error reset and a raise). */
        (void)co_emcy_raise(node, 0x8140, NULL);
        (void)co_emcy_clear(node, 0x8120);
        break;
    }
}

/* ---- consumer */

/* Bind 0x1028 sub1..N (as many as the OD has, up to CO_EMCY_CONSUMERS_MAX). */
static void consumers_bind(co_node_t *node)
{
    co_emcy_t *e = &node->emcy;
    e->consumer_count = 0;
    while (e->consumer_count < co_emcy_consumers_max()) {
        uint64_t cob = 0;
        if (co_od_get_uint(&node->cfg.od, 0x1028, (uint8_t)(e->consumer_count + 1), &cob) !=
            CO_OK) {
            break;
        }
        e->consumer_cob[e->consumer_count++] = (uint32_t)cob;
    }
}

void co_emcy_add_routes(co_node_t *node)
{
    for (uint8_t i = 0; i < node->emcy.consumer_count; i++) {
        uint32_t cob = node->emcy.consumer_cob[i];
        if (!(cob & CO_COB_INVALID)) {
            co_routes_add(node, co_cob_key(cob), CO_ROUTE_EMCY, i);
        }
    }
}

void co_emcy_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot; /* every consumer entry is handled alike */
    if (frame->len != 8 || (frame->flags & CO_FRAME_RTR)) {
        node->stats.rx_malformed++;
        return;
    }
    if (node->cfg.on_emcy == NULL) {
        return;
    }
    /* The sender's COB-ID in the form of a COB-ID object (bit 29 for 29-bit). */
    co_emcy_msg_t msg = {.cob_id = frame->id | ((frame->flags & CO_FRAME_EXT) ? CO_COB_EXT : 0u),
                         .code = co_get_u16(frame->data),
                         .reg = frame->data[2]};
    memcpy(msg.manufacturer, &frame->data[3], sizeof msg.manufacturer);
    node->cfg.on_emcy(node->cfg.user, &msg);
}

/* ---- node hooks */

void co_emcy_reset_comm(co_node_t *node)
{
    co_emcy_t *e = &node->emcy;
    consumers_bind(node);
    e->last_us = CO_TIME_NEVER; /* the producer starts afresh: no inhibit pending */
    if (producer_off(node)) {
        e->queue_count = 0;
    }
    /* The reset restored 0x1001 (and 0x1003) to power-on values; the errors still
     * active set the register again. */
    register_store(node, register_of_active(node));
    /* Reset communication restarts heartbeat and guarding monitoring: what 0x8130
     * reported is over (the error reset EMCY, if it is the last, leaves after boot-up). */
    (void)co_emcy_clear(node, 0x8130);
}

uint64_t co_emcy_poll(co_node_t *node, uint64_t now_us) { return queue_drain(node, now_us); }

void co_emcy_state_entered(co_node_t *node)
{
    co_node_schedule(node, queue_drain(node, node->now_us));
}

co_abort_t co_emcy_check_write(const co_node_t *node, const co_od_entry_t *entry,
                               const uint8_t *data, uint32_t len)
{
    (void)node;
    if (entry->index != 0x1003 || entry->sub != 0) {
        return CO_ABORT_NONE;
    }
    for (uint32_t i = 0; i < len; i++) {
        if (data[i] != 0) {
            return CO_ABORT_VALUE; /* only 0 (clear the history) may be written */
        }
    }
    return CO_ABORT_NONE;
}

void co_emcy_written(co_node_t *node, const co_od_entry_t *entry)
{
    switch (entry->index) {
    case 0x1003:
        if (entry->sub == 0) {
            history_clear(node);
        }
        break;
    case 0x1014:
        if (producer_off(node)) {
            node->emcy.queue_count = 0; /* EMCY off: nothing waits to be sent */
        }
        break;
    case 0x1015:
        /* a shorter inhibit time may let a waiting frame leave earlier */
        co_node_schedule(node, queue_drain(node, node->now_us));
        break;
    case 0x1028:
        consumers_bind(node);
        co_routes_rebuild(node);
        break;
    default:
        break;
    }
}
