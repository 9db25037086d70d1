/* SPDX-License-Identifier: Apache-2.0 */
/*
 * lss_slave.c -- the LSS slave (CiA 305): answers the master on 0x7E5, keeps the
 * pending node-ID and bit timing, and boots an unconfigured node once it has an ID.
 */
#include "lss_internal.h"

#if CO_CONFIG_LSS_SLAVE

#define NO_BIT_TIMING 0xFFu
#define FASTSCAN_RESET 0x80u

static bool valid_node_id(uint8_t id) { return (id >= 1 && id <= 127) || id == 0xFF; }

/* The LSS address is the identity object; a missing sub-index counts as 0. */
static uint32_t address_part(const co_node_t *node, uint8_t part)
{
    uint64_t v = 0;
    (void)co_od_get_uint(&node->cfg.od, 0x1018, (uint8_t)(part + 1), &v);
    return (uint32_t)v;
}

static void answer(co_node_t *node, uint8_t cs, const uint8_t *payload, uint8_t n)
{
    co_frame_t f = {.id = CO_LSS_COB_SLAVE, .len = CO_LSS_FRAME_LEN, .data = {cs}};
    for (uint8_t i = 0; i < n && i < CO_LSS_FRAME_LEN - 1u; i++) {
        f.data[1 + i] = payload[i];
    }
    (void)co_node_send_as(node, &f, CO_SVC_LSS);
}

static void answer_error(co_node_t *node, uint8_t cs, uint8_t error)
{
    uint8_t p[2] = {error, 0};
    answer(node, cs, p, 2);
}

static void answer_u32(co_node_t *node, uint8_t cs, uint32_t v)
{
    uint8_t p[4];
    co_put_u32(p, v);
    answer(node, cs, p, 4);
}

static void switch_global(co_node_t *node, uint8_t mode)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (mode == CO_LSS_CONFIGURATION) {
        s->mode = CO_LSS_CONFIGURATION;
        return;
    }
    s->mode = CO_LSS_WAITING;
    /* A node without an ID boots as soon as it has one (reset communication takes it). */
    if (node->node_id == CO_NODE_ID_UNCONFIGURED && s->pending_id != CO_NODE_ID_UNCONFIGURED) {
        node->wiring->nmt_reset(node, false); /* NMT's reset communication (kernel.h) */
    }
}

/* 0x40..0x43 must arrive in order, each matching, for the 0x43 to switch. */
static void switch_selective(co_node_t *node, uint8_t part, uint32_t value)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (part == 0) {
        s->selective = 0;
    }
    if (s->selective != part || value != address_part(node, part)) {
        s->selective = 0;
        return;
    }
    s->selective = (uint8_t)(part + 1);
    if (s->selective == 4) {
        s->selective = 0;
        s->mode = CO_LSS_CONFIGURATION;
        answer(node, CO_LSS_CS_SWITCH_SEL_ANSWER, NULL, 0);
    }
}

/* 0x46..0x4B: vendor, product equal; revision and serial within [low, high]. */
static void identify(co_node_t *node, uint8_t step, uint32_t value)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (step == 0) {
        s->ident = 0;
    }
    uint8_t part = step < 2 ? step : (uint8_t)(2u + (step - 2u) / 2u);
    uint32_t mine = address_part(node, part);
    bool low = step == 2 || step == 4;
    bool ok = step < 2 ? mine == value : (low ? mine >= value : mine <= value);
    if (s->ident != step || !ok) {
        s->ident = 0;
        return;
    }
    s->ident = (uint8_t)(step + 1);
    if (s->ident == 6) {
        s->ident = 0;
        answer(node, CO_LSS_CS_IDENT_ANSWER, NULL, 0);
    }
}

static void fastscan(co_node_t *node, const uint8_t *d)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (s->mode != CO_LSS_WAITING || node->node_id != CO_NODE_ID_UNCONFIGURED) {
        return;
    }
    uint8_t bit = d[5], sub = d[6], next = d[7];
    if (bit == FASTSCAN_RESET) {
        s->fastscan_pos = 0;
        answer(node, CO_LSS_CS_IDENT_ANSWER, NULL, 0);
        return;
    }
    if (bit > 31 || sub > 3 || next > 3 || sub != s->fastscan_pos) {
        return;
    }
    uint32_t mask = 0xFFFFFFFFu << bit; /* bits bit..31 are checked */
    if (((co_get_u32(d + 1) ^ address_part(node, sub)) & mask) != 0) {
        return;
    }
    answer(node, CO_LSS_CS_IDENT_ANSWER, NULL, 0);
    if (bit == 0) {
        s->fastscan_pos = next;
        if (next < sub) { /* the whole address matched */
            s->mode = CO_LSS_CONFIGURATION;
        }
    }
}

static void configure(co_node_t *node, const uint8_t *d)
{
    co_lss_slave_t *s = &node->lss_slave;
    switch (d[0]) {
    case CO_LSS_CS_CONFIG_NODE_ID:
        if (valid_node_id(d[1])) {
            s->pending_id = d[1];
        }
        answer_error(node, d[0], valid_node_id(d[1]) ? 0 : 1);
        break;
    case CO_LSS_CS_CONFIG_BIT_TIMING: {
        bool ok = d[1] == 0 && d[2] < 16 && (((unsigned)s->cfg.bit_timings >> d[2]) & 1u);
        if (ok) {
            s->bit_timing = d[2];
        }
        answer_error(node, d[0], ok ? 0 : 1);
        break;
    }
    case CO_LSS_CS_ACTIVATE_BIT_TIMING:
        if (s->bit_timing != NO_BIT_TIMING) {
            uint64_t delay = co_ms_to_us(co_get_u16(d + 1));
            s->bit_timing_due_us = node->now_us + delay;
            s->quiet_until_us = node->now_us + 2 * delay;
            s->bit_timing_armed = true;
            /* CiA 305: no service sends (or takes) a frame until the second delay has
             * passed; what waits in the queue would leave at the wrong bit rate. */
            node->services = 0;
            co_txq_purge(node);
            co_node_schedule(node, s->bit_timing_due_us);
        }
        break;
    case CO_LSS_CS_STORE: {
        uint8_t err = 1; /* not supported */
        if (s->cfg.store) {
            err = s->cfg.store(s->cfg.ctx, s->pending_id, s->bit_timing) == CO_OK ? 0 : 2;
        }
        if (err == 0) {
            s->stored_id = s->pending_id;
        }
        answer_error(node, d[0], err);
        break;
    }
    case CO_LSS_CS_INQUIRE_NODE_ID: {
        uint8_t id[1] = {node->node_id};
        answer(node, d[0], id, 1);
        break;
    }
    default: /* inquire vendor .. serial */
        answer_u32(node, d[0], address_part(node, (uint8_t)(d[0] - CO_LSS_CS_INQUIRE_VENDOR)));
        break;
    }
}

void co_lss_slave_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot;
    const uint8_t *d = frame->data;
    if (frame->len != CO_LSS_FRAME_LEN || (frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    co_lss_slave_t *s = &node->lss_slave;
    uint8_t cs = d[0];
    switch (cs) {
    case CO_LSS_CS_SWITCH_GLOBAL:
        if (d[1] > CO_LSS_CONFIGURATION) {
            CO_COUNT(node, rx_malformed);
        } else {
            switch_global(node, d[1]);
        }
        return;
    case CO_LSS_CS_SWITCH_SEL_VENDOR:
    case CO_LSS_CS_SWITCH_SEL_PRODUCT:
    case CO_LSS_CS_SWITCH_SEL_REVISION:
    case CO_LSS_CS_SWITCH_SEL_SERIAL:
        if (s->mode == CO_LSS_WAITING) {
            switch_selective(node, (uint8_t)(cs - CO_LSS_CS_SWITCH_SEL_VENDOR), co_get_u32(d + 1));
        }
        return;
    case CO_LSS_CS_IDENT_VENDOR:
    case CO_LSS_CS_IDENT_PRODUCT:
    case CO_LSS_CS_IDENT_REV_LOW:
    case CO_LSS_CS_IDENT_REV_HIGH:
    case CO_LSS_CS_IDENT_SERIAL_LOW:
    case CO_LSS_CS_IDENT_SERIAL_HIGH:
        identify(node, (uint8_t)(cs - CO_LSS_CS_IDENT_VENDOR), co_get_u32(d + 1));
        return;
    case CO_LSS_CS_IDENT_NON_CONFIGURED:
        if (node->node_id == CO_NODE_ID_UNCONFIGURED) {
            answer(node, CO_LSS_CS_NON_CONFIGURED_ANSWER, NULL, 0);
        }
        return;
    case CO_LSS_CS_FASTSCAN:
        fastscan(node, d);
        return;
    case CO_LSS_CS_CONFIG_NODE_ID:
    case CO_LSS_CS_CONFIG_BIT_TIMING:
    case CO_LSS_CS_ACTIVATE_BIT_TIMING:
    case CO_LSS_CS_STORE:
    case CO_LSS_CS_INQUIRE_VENDOR:
    case CO_LSS_CS_INQUIRE_PRODUCT:
    case CO_LSS_CS_INQUIRE_REVISION:
    case CO_LSS_CS_INQUIRE_SERIAL:
    case CO_LSS_CS_INQUIRE_NODE_ID:
        if (s->mode == CO_LSS_CONFIGURATION) {
            configure(node, d);
        }
        return;
    default:
        CO_COUNT(node, rx_malformed);
        return;
    }
}

/* The quiet time after a bit rate switch ends: the NMT state's services again. */
static bool end_quiet_time(co_node_t *node)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (node->now_us < s->quiet_until_us) {
        return false;
    }
    s->quiet_until_us = 0;
    node->services = co_nmt_gate(node->nmt_state);
    return true;
}

uint64_t co_lss_slave_poll(co_node_t *node, uint64_t now_us)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (s->bit_timing_armed) {
        if (now_us < s->bit_timing_due_us) {
            return s->bit_timing_due_us;
        }
        s->bit_timing_armed = false;
        if (s->cfg.on_bit_timing) {
            s->cfg.on_bit_timing(s->cfg.ctx, s->bit_timing);
        }
    }
    if (s->quiet_until_us != 0 && !end_quiet_time(node)) {
        return s->quiet_until_us;
    }
    return CO_TIME_NEVER;
}

bool co_lss_slave_resume(co_node_t *node, uint16_t service)
{
    return node->lss_slave.quiet_until_us != 0 && end_quiet_time(node) &&
           (node->services & service);
}

/* Reset application brings back the stored node-ID; every reset communication takes the
 * pending one (CiA 305). */
void co_lss_slave_reset(co_node_t *node, bool application)
{
    co_lss_slave_t *s = &node->lss_slave;
    if (application) {
        s->pending_id = s->stored_id ? s->stored_id : node->cfg.node_id;
        s->bit_timing = NO_BIT_TIMING;
        s->mode = CO_LSS_WAITING;
        s->selective = 0;
        s->ident = 0;
        s->fastscan_pos = 0;
    }
    node->node_id = s->pending_id;
    co_route_set(node, CO_ROUTE_LSS_SLAVE, 0, CO_LSS_COB_MASTER);
}

co_err_t co_lss_slave_setup(co_node_t *node, const co_lss_slave_config_t *config)
{
    if (node == NULL || config == NULL) {
        return CO_ERR_ARG;
    }
    node->lss_slave.cfg = *config;
    return CO_OK;
}

co_lss_mode_t co_lss_slave_mode(const co_node_t *node)
{
    return (co_lss_mode_t)node->lss_slave.mode;
}

#else

co_err_t co_lss_slave_setup(co_node_t *node, const co_lss_slave_config_t *config)
{
    (void)node;
    (void)config;
    return CO_ERR_STATE;
}

co_lss_mode_t co_lss_slave_mode(const co_node_t *node)
{
    (void)node;
    return CO_LSS_WAITING;
}

#endif
