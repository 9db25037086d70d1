/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cortex-m/can_model.c -- see can_model.h. */
#include "can_model.h"

#include <string.h>

#include "canola/stm32_reg.h"
#include "cm_host.h"

#define MODELS_MAX 4

/* The models the drivers' register accesses may address (tests only: one process, one
 * test at a time). */
static can_model_t *g_models[MODELS_MAX];
static uint32_t g_model_count;

void can_model_init(can_model_t *m, const can_model_class_t *cls, void *regs, size_t regs_size,
                    uint32_t *ram, size_t ram_words, uint32_t recovery_bits)
{
    memset(m, 0, sizeof *m);
    m->cls = cls;
    m->regs = regs;
    m->regs_size = regs_size;
    m->ram = ram;
    m->ram_words = ram_words;
    m->recovery_bits = recovery_bits;
    m->bit_rate = 1000000;
}

static bool model_irq(void *ctx)
{
    can_model_t *m = ctx;
    for (uint32_t v = 0; v < m->vectors; v++) {
        if (m->isr[v] && m->cls->pending(m, v)) {
            m->isr[v](m->isr_ctx);
            return true;
        }
    }
    return false;
}

static void port_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    can_model_t *m = ctx;
    can_model_tick(m, now_us);
    m->reads_in_a_row = 0;
    if (m->bus_off) {
        return;
    }
    if (m->rec > 0) {
        m->rec--; /* a frame received without error */
    }
    m->cls->received(m, frame);
    cm_host_raise();
}

static void slot_left(can_model_t *m, uint32_t slot)
{
    m->slot_pending[slot] = false;
    m->slot_offered[slot] = false;
    m->tx_sent++;
    if (m->tec > 0) {
        m->tec--; /* a frame sent without error */
    }
    m->cls->sent(m, slot);
}

static bool frames_equal(const co_frame_t *a, const co_frame_t *b)
{
    return a->id == b->id && a->flags == b->flags && a->len == b->len &&
           memcmp(a->data, b->data, sizeof a->data) == 0;
}

/* The pending slot that holds `frame`, an offered one first (equal frames: the lowest);
 * -1 when none. (A frame on the wire when the controller went bus-off completes, though
 * its slot is no longer offered.) */
static int slot_holding(const can_model_t *m, const co_frame_t *frame)
{
    for (int offered = 1; offered >= 0; offered--) {
        for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
            if (m->slot_pending[i] && m->slot_offered[i] == (bool)offered &&
                frames_equal(&m->slot_frame[i], frame)) {
                return (int)i;
            }
        }
    }
    return -1;
}

/* The sim's word for one of our frames leaving the wire. */
static void port_sent(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    can_model_t *m = ctx;
    can_model_tick(m, now_us);
    m->reads_in_a_row = 0;
    int slot = slot_holding(m, frame);
    if (slot >= 0) {
        slot_left(m, (uint32_t)slot);
    }
    can_model_offer(m);
    cm_host_raise();
}

void can_model_attach(can_model_t *m, co_sim_bus_t *bus)
{
    m->bus = bus;
    if (bus) {
        co_sim_port_attach_raw(bus, &m->port, port_rx, m);
        m->port.sent = port_sent;
    }
    if (g_model_count < MODELS_MAX) {
        g_models[g_model_count++] = m;
    }
    cm_host_add_source(model_irq, m);
}

void can_model_detach_all(void) { g_model_count = 0; }

void can_model_set_isr(can_model_t *m, uint32_t v, can_model_isr_fn fn, void *ctx)
{
    if (v < CAN_MODEL_VECTORS) {
        m->isr[v] = fn;
        m->isr_ctx = ctx;
        m->vectors = v + 1 > m->vectors ? v + 1 : m->vectors;
    }
}

uint64_t can_model_now(const can_model_t *m) { return m->bus ? m->bus->now_us : m->by_hand_us; }

/* ---- Registers: the drivers' accesses, routed. */

static can_model_t *owner(const volatile uint32_t *reg, uint32_t *offset, bool *in_ram)
{
    const uint8_t *at = (const uint8_t *)(uintptr_t)reg;
    for (uint32_t i = 0; i < g_model_count; i++) {
        can_model_t *m = g_models[i];
        const uint8_t *regs = m->regs;
        const uint8_t *ram = (const uint8_t *)m->ram;
        if (at >= regs && at < regs + m->regs_size) {
            *offset = (uint32_t)(at - regs);
            *in_ram = false;
            return m;
        }
        if (ram && at >= ram && at < ram + 4 * m->ram_words) {
            *offset = (uint32_t)(at - ram);
            *in_ram = true;
            return m;
        }
    }
    return NULL;
}

uint32_t co_stm32_read(const volatile uint32_t *reg)
{
    uint32_t offset;
    bool in_ram;
    can_model_t *m = owner(reg, &offset, &in_ram);
    if (!m) {
        return *reg; /* not a model's: plain memory */
    }
    if (++m->reads_in_a_row > m->max_reads_in_a_row) {
        m->max_reads_in_a_row = m->reads_in_a_row;
    }
    return in_ram ? m->ram[offset / 4] : m->cls->read(m, offset);
}

void co_stm32_write(volatile uint32_t *reg, uint32_t value)
{
    uint32_t offset;
    bool in_ram;
    can_model_t *m = owner(reg, &offset, &in_ram);
    if (!m) {
        *reg = value;
        return;
    }
    m->reads_in_a_row = 0;
    if (in_ram) {
        m->ram[offset / 4] = value;
    } else {
        m->cls->write(m, offset, value);
    }
    cm_host_raise(); /* a write may have raised (or been the last to hold off) an interrupt */
}

/* ---- Transmit slots. */

uint32_t can_model_key(const co_frame_t *frame)
{
    uint32_t rtr = (frame->flags & CO_FRAME_RTR) ? 1u : 0u;
    if (frame->flags & CO_FRAME_EXT) {
        return ((frame->id >> 18) & 0x7FFu) << 21 | 3u << 19 | (frame->id & 0x3FFFFu) << 1 | rtr;
    }
    return (frame->id & 0x7FFu) << 21 | rtr << 20;
}

/* Slot a goes before slot b: in request order, or by identifier (then slot number). */
static bool goes_before(const can_model_t *m, uint32_t a, uint32_t b)
{
    if (m->request_order) {
        return (int32_t)(m->slot_seq[a] - m->slot_seq[b]) < 0;
    }
    uint32_t ka = can_model_key(&m->slot_frame[a]);
    uint32_t kb = can_model_key(&m->slot_frame[b]);
    return ka != kb ? ka < kb : a < b;
}

int can_model_next_slot(const can_model_t *m)
{
    int best = -1;
    for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
        if (m->slot_pending[i] && (best < 0 || goes_before(m, i, (uint32_t)best))) {
            best = (int)i;
        }
    }
    return best;
}

/* May slot i compete for the bus now? By identifier: unless an earlier slot has its
 * identifier. In request order: only the oldest. */
static bool may_compete(const can_model_t *m, uint32_t i)
{
    if (m->request_order) {
        return can_model_next_slot(m) == (int)i;
    }
    uint32_t key = can_model_key(&m->slot_frame[i]);
    for (uint32_t j = 0; j < i; j++) {
        if (m->slot_pending[j] && can_model_key(&m->slot_frame[j]) == key) {
            return false;
        }
    }
    return true;
}

void can_model_offer(can_model_t *m)
{
    if (!m->bus || m->bus_off || m->transmit_held) {
        return;
    }
    for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
        if (m->slot_pending[i] && !m->slot_offered[i] && may_compete(m, i)) {
            if (co_sim_send(&m->port, &m->slot_frame[i]) == CO_OK) {
                m->slot_offered[i] = true;
            }
        }
    }
}

void can_model_request(can_model_t *m, uint32_t slot, const co_frame_t *frame)
{
    m->slot_frame[slot] = *frame;
    m->slot_pending[slot] = true;
    m->slot_offered[slot] = false;
    m->slot_seq[slot] = m->seq++;
    uint32_t pending = 0;
    for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
        pending += m->slot_pending[i];
    }
    if (pending > m->max_pending) {
        m->max_pending = pending;
    }
    m->full_requests += pending == CAN_MODEL_SLOTS;
    can_model_offer(m);
}

bool can_model_abort(can_model_t *m, uint32_t slot)
{
    if (!m->slot_pending[slot]) {
        return false;
    }
    if (m->slot_offered[slot]) {
        return false; /* on its way: the sim cannot take it back (it completes) */
    }
    m->slot_pending[slot] = false;
    return true;
}

bool can_model_complete(can_model_t *m)
{
    int slot = can_model_next_slot(m);
    if (slot < 0 || m->bus_off || m->transmit_held) {
        return false;
    }
    co_frame_t frame = m->slot_frame[slot];
    m->reads_in_a_row = 0;
    slot_left(m, (uint32_t)slot);
    if (m->on_wire) {
        m->on_wire(m->on_wire_ctx, &frame);
    }
    cm_host_raise();
    return true;
}

/* ---- Fault confinement. */

co_cm_can_state_t can_model_state(const can_model_t *m)
{
    if (m->bus_off) {
        return CO_CM_CAN_BUS_OFF;
    }
    if (m->tec >= 128 || m->rec >= 128) {
        return CO_CM_CAN_ERROR_PASSIVE;
    }
    if (m->tec >= 96 || m->rec >= 96) {
        return CO_CM_CAN_ERROR_WARNING;
    }
    return CO_CM_CAN_ERROR_ACTIVE;
}

static void go_bus_off(can_model_t *m)
{
    m->bus_off = true;
    m->recovering = false;
    for (uint32_t i = 0; i < CAN_MODEL_SLOTS; i++) {
        m->slot_offered[i] = false; /* withdrawn from the bus; still pending */
    }
    if (m->bus) {
        co_sim_set_bus_off(&m->port, true);
    }
}

void can_model_tx_errors(can_model_t *m, uint32_t n)
{
    for (uint32_t i = 0; i < n && !m->bus_off; i++) {
        co_cm_can_state_t was = can_model_state(m);
        m->tec += 8;
        if (m->tec > 255) {
            go_bus_off(m);
        }
        if (can_model_state(m) != was) {
            m->cls->state_changed(m, was);
        }
    }
    cm_host_raise();
}

void can_model_start_recovery(can_model_t *m)
{
    if (m->bus_off && !m->recovering) {
        m->recovering = true;
        uint64_t bits = (uint64_t)m->recovery_bits * 1000000u;
        m->recovered_at_us = can_model_now(m) + (bits + m->bit_rate - 1u) / m->bit_rate;
    }
}

void can_model_tick(can_model_t *m, uint64_t now_us)
{
    if (!m->bus) {
        m->by_hand_us = now_us;
    }
    if (m->recovering && now_us >= m->recovered_at_us) {
        m->recovering = false;
        m->bus_off = false;
        m->tec = 0;
        m->rec = 0;
        if (m->bus) {
            co_sim_set_bus_off(&m->port, false);
        }
        m->cls->state_changed(m, CO_CM_CAN_BUS_OFF);
        can_model_offer(m);
        cm_host_raise();
    }
}
