/* SPDX-License-Identifier: Apache-2.0 */
/*
 * lss_master.c -- the LSS master (CiA 305): one request at a time on 0x7E5, answers on
 * 0x7E4, time-outs from the node's poll, fastscan as a walk over the address bits.
 */
#include "lss_internal.h"

#if CO_CONFIG_LSS_MASTER

#define DEFAULT_TIMEOUT_MS 100u
#define SCAN_RESET_PART 0xFFu /* fastscan: the reset step, before part 0 */
#define SCAN_PROBE_PART 4u    /* fastscan: the final verify repeated, after part 3 */

static uint32_t timeout_ms(const co_lss_master_t *m)
{
    return m->timeout_ms ? m->timeout_ms : DEFAULT_TIMEOUT_MS;
}

static void send(co_node_t *node, uint8_t cs, const uint8_t *payload, uint8_t n)
{
    co_frame_t f = {.id = CO_LSS_COB_MASTER, .len = CO_LSS_FRAME_LEN, .data = {cs}};
    for (uint8_t i = 0; i < n && i < CO_LSS_FRAME_LEN - 1u; i++) {
        f.data[1 + i] = payload[i];
    }
    (void)co_node_send_as(node, &f, CO_SVC_LSS);
}

static void send_u32(co_node_t *node, uint8_t cs, uint32_t v)
{
    uint8_t p[4];
    co_put_u32(p, v);
    send(node, cs, p, 4);
}

/* Each step waits one time-out from now. */
static void arm(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    m->heard = false;
    m->deadline_us = node->now_us + co_long_ms_to_us(timeout_ms(m));
    co_node_schedule(node, m->deadline_us);
}

static co_err_t begin(co_node_t *node, uint8_t op, co_lss_done_fn done, void *ctx)
{
    co_lss_master_t *m = &node->lss_master;
    if (m->op != 0) {
        return CO_ERR_BUSY;
    }
    if (!m->listening) { /* 0x7E4 is routed from the first request on */
        m->listening = true;
        co_route_set(node, CO_ROUTE_LSS_MASTER, 0, CO_LSS_COB_SLAVE);
    }
    m->op = op;
    m->done = done;
    m->ctx = ctx;
    m->result = (co_lss_result_t){.cs = op};
    arm(node);
    return CO_OK;
}

static void finish(co_node_t *node, co_lss_status_t status)
{
    co_lss_master_t *m = &node->lss_master;
    co_lss_result_t r = m->result;
    r.status = (uint8_t)status;
    m->op = 0;
    if (m->done) {
        m->done(m->ctx, &r);
    }
}

/* Requests answered by any number of slaves wait out the whole time-out. */
static bool counts_answers(uint8_t op)
{
    return op == CO_LSS_CS_IDENT_SERIAL_HIGH || op == CO_LSS_CS_IDENT_NON_CONFIGURED ||
           op == CO_LSS_CS_FASTSCAN;
}

static uint8_t expected_answer(uint8_t op)
{
    switch (op) {
    case CO_LSS_CS_SWITCH_SEL_SERIAL:
        return CO_LSS_CS_SWITCH_SEL_ANSWER;
    case CO_LSS_CS_IDENT_SERIAL_HIGH:
    case CO_LSS_CS_FASTSCAN:
        return CO_LSS_CS_IDENT_ANSWER;
    case CO_LSS_CS_IDENT_NON_CONFIGURED:
        return CO_LSS_CS_NON_CONFIGURED_ANSWER;
    default:
        return op;
    }
}

void co_lss_master_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot;
    co_lss_master_t *m = &node->lss_master;
    const uint8_t *d = frame->data;
    if (frame->len != CO_LSS_FRAME_LEN || (frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    if (m->op == 0 || d[0] != expected_answer(m->op)) {
        return; /* late, or another master's conversation */
    }
    if (counts_answers(m->op)) {
        m->heard = true;
        m->result.answers++;
        return;
    }
    switch (m->op) {
    case CO_LSS_CS_CONFIG_NODE_ID:
    case CO_LSS_CS_CONFIG_BIT_TIMING:
    case CO_LSS_CS_STORE:
        m->result.error = d[1];
        m->result.spec_error = d[2];
        finish(node, d[1] == 0 ? CO_LSS_OK : CO_LSS_REFUSED);
        break;
    case CO_LSS_CS_INQUIRE_NODE_ID:
        m->result.value = d[1];
        finish(node, CO_LSS_OK);
        break;
    case CO_LSS_CS_SWITCH_SEL_SERIAL:
        finish(node, CO_LSS_OK);
        break;
    default: /* inquire vendor .. serial */
        m->result.value = co_get_u32(d + 1);
        finish(node, CO_LSS_OK);
        break;
    }
}

/* ---- fastscan: reset, then per part bits 31..0 (a guess of 0 that nobody confirms
 * means 1), then a verify that moves the matching slave on to the next part.
 *
 * Above an address A (the slaves that answer fastscan in configuration are all back in
 * waiting, A's among them), an attempt per part k = 3..0 looks for the lowest address
 * that shares A's parts 0..k-1 and is greater in part k: reset, verify A's parts 0..k-1
 * (PREFIX), then in part k, from bit 0 up, ask for A's bits above a 0 bit of A with that
 * bit set (ASCEND): the first confirmed is the branch, and the walk goes on below it as in
 * a plain scan. A verify nobody confirms in PREFIX means no slave shares that many parts
 * (attempt that part next); no branch in part k means attempt k-1; none in part 0, no
 * slave above A. Queries within a part keep every slave where it is (next = the part),
 * so they may come in any order. */

enum { SCAN_WALK = 0, SCAN_PREFIX, SCAN_ASCEND };

static void scan_send(co_node_t *node, uint32_t id, uint8_t bit, uint8_t next)
{
    co_lss_master_t *m = &node->lss_master;
    uint8_t p[7];
    co_put_u32(p, id);
    p[4] = bit;
    p[5] = m->sub < 4 ? m->sub : 0;
    p[6] = next;
    send(node, CO_LSS_CS_FASTSCAN, p, 7);
    arm(node);
}

static void scan_reset(co_node_t *node)
{
    node->lss_master.sub = SCAN_RESET_PART;
    scan_send(node, 0, 0x80, 0);
}

/* The current part's verify: its whole value, the slaves matching it move on. */
static void scan_verify(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    m->bit = -1;
    scan_send(node, m->scan[m->sub], 0, (uint8_t)((m->sub + 1) & 3));
}

/* `v`'s bits above `bit`, with `bit` set. */
static uint32_t branch(uint32_t v, int8_t bit)
{
    uint32_t above = bit >= 31 ? 0 : v & (0xFFFFFFFFu << (bit + 1));
    return above | (1u << bit);
}

/* The next 0 bit of A's part, upwards, asked for as the branch; none left: attempt the
 * part before (or no slave is above A). */
static void scan_ascend(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    do {
        m->bit++;
    } while (m->bit <= 31 && ((m->scan[m->sub] >> m->bit) & 1u));
    if (m->bit > 31) {
        if (m->target == 0) {
            finish(node, CO_LSS_TIMEOUT);
            return;
        }
        m->target--;
        m->phase = SCAN_PREFIX;
        scan_reset(node);
        return;
    }
    scan_send(node, branch(m->scan[m->sub], m->bit), (uint8_t)m->bit, m->sub);
}

/* The whole address matched and its slave is in configuration: the final verify once
 * more. No slave in waiting matches it (addresses are unique), so an answer comes from
 * the slave found, which answers fastscan in configuration too (CANopenNode's do). */
static void scan_probe(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    uint8_t p[7] = {0, 0, 0, 0, 0, 3, 0};
    co_put_u32(p, m->scan[3]);
    send(node, CO_LSS_CS_FASTSCAN, p, 7);
    arm(node);
}

static void scan_part(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    if (m->sub == SCAN_PROBE_PART) {
        scan_probe(node);
        return;
    }
    if (m->phase == SCAN_PREFIX) {
        if (m->sub < m->target) {
            scan_verify(node); /* A's part: the slaves sharing it move on */
            return;
        }
        m->phase = SCAN_ASCEND;
        m->bit = -1;
        scan_ascend(node);
        return;
    }
    if (m->known & (1u << m->sub)) {
        scan_verify(node); /* known: straight to the verify */
        return;
    }
    m->scan[m->sub] = 0;
    m->bit = 31;
    scan_send(node, 0, 31, m->sub);
}

/* The walk within a part, one bit lower (its verify after bit 0). */
static void scan_walk(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    if (m->bit > 0) {
        m->bit--;
        scan_send(node, m->scan[m->sub], (uint8_t)m->bit, m->sub);
    } else {
        scan_verify(node);
    }
}

static void scan_step(co_node_t *node)
{
    co_lss_master_t *m = &node->lss_master;
    if (m->sub == SCAN_PROBE_PART) {
        m->result.address = (co_lss_address_t){m->scan[0], m->scan[1], m->scan[2], m->scan[3]};
        m->result.keeps_answering = m->heard;
        finish(node, CO_LSS_OK);
        return;
    }
    if (m->sub == SCAN_RESET_PART) {
        if (!m->heard) {
            finish(node, CO_LSS_TIMEOUT);
            return;
        }
        m->sub = 0;
        scan_part(node);
        return;
    }
    if (m->phase == SCAN_ASCEND) {
        if (!m->heard) {
            scan_ascend(node);
            return;
        }
        m->scan[m->sub] = branch(m->scan[m->sub], m->bit); /* the walk goes on below it */
        m->phase = SCAN_WALK;
        scan_walk(node);
        return;
    }
    if (m->bit < 0) {
        if (!m->heard) {
            if (m->phase == SCAN_PREFIX) { /* nobody shares A's parts 0..sub */
                m->target = m->sub;
                scan_reset(node);
                return;
            }
            finish(node, CO_LSS_SCAN_FAILED);
            return;
        }
        m->sub++;
        scan_part(node);
        return;
    }
    if (!m->heard) {
        m->scan[m->sub] |= 1u << m->bit;
    }
    scan_walk(node);
}

uint64_t co_lss_master_poll(co_node_t *node, uint64_t now_us)
{
    co_lss_master_t *m = &node->lss_master;
    if (m->op == 0) {
        return CO_TIME_NEVER;
    }
    if (now_us < m->deadline_us) {
        return m->deadline_us;
    }
    if (m->op == CO_LSS_CS_FASTSCAN) {
        scan_step(node);
    } else if (counts_answers(m->op)) {
        finish(node, m->result.answers ? CO_LSS_OK : CO_LSS_TIMEOUT);
    } else {
        finish(node, CO_LSS_TIMEOUT);
    }
    return m->op ? m->deadline_us : CO_TIME_NEVER;
}

/* ---- requests */

co_err_t co_lss_master_set_timeout(co_node_t *node, uint32_t timeout_ms)
{
    if (timeout_ms == 0 || timeout_ms > 65535) {
        return CO_ERR_ARG;
    }
    node->lss_master.timeout_ms = timeout_ms;
    return CO_OK;
}

bool co_lss_master_busy(const co_node_t *node) { return node->lss_master.op != 0; }

co_err_t co_lss_master_cancel(co_node_t *node)
{
    if (node->lss_master.op == 0) {
        return CO_ERR_STATE;
    }
    finish(node, CO_LSS_CANCELLED);
    return CO_OK;
}

co_err_t co_lss_switch_global(co_node_t *node, co_lss_mode_t mode)
{
    if (mode != CO_LSS_WAITING && mode != CO_LSS_CONFIGURATION) {
        return CO_ERR_ARG;
    }
    uint8_t p = (uint8_t)mode;
    send(node, CO_LSS_CS_SWITCH_GLOBAL, &p, 1);
    return CO_OK;
}

co_err_t co_lss_activate_bit_timing(co_node_t *node, uint16_t delay_ms)
{
    uint8_t p[2];
    co_put_u16(p, delay_ms);
    send(node, CO_LSS_CS_ACTIVATE_BIT_TIMING, p, 2);
    return CO_OK;
}

co_err_t co_lss_switch_selective(co_node_t *node, const co_lss_address_t *address,
                                 co_lss_done_fn done, void *ctx)
{
    if (address == NULL) {
        return CO_ERR_ARG;
    }
    co_err_t err = begin(node, CO_LSS_CS_SWITCH_SEL_SERIAL, done, ctx);
    if (err == CO_OK) {
        send_u32(node, CO_LSS_CS_SWITCH_SEL_VENDOR, address->vendor);
        send_u32(node, CO_LSS_CS_SWITCH_SEL_PRODUCT, address->product);
        send_u32(node, CO_LSS_CS_SWITCH_SEL_REVISION, address->revision);
        send_u32(node, CO_LSS_CS_SWITCH_SEL_SERIAL, address->serial);
    }
    return err;
}

co_err_t co_lss_configure_node_id(co_node_t *node, uint8_t node_id, co_lss_done_fn done, void *ctx)
{
    if ((node_id < 1 || node_id > 127) && node_id != CO_NODE_ID_UNCONFIGURED) {
        return CO_ERR_ARG;
    }
    co_err_t err = begin(node, CO_LSS_CS_CONFIG_NODE_ID, done, ctx);
    if (err == CO_OK) {
        send(node, CO_LSS_CS_CONFIG_NODE_ID, &node_id, 1);
    }
    return err;
}

co_err_t co_lss_configure_bit_timing(co_node_t *node, uint8_t table, uint8_t index,
                                     co_lss_done_fn done, void *ctx)
{
    co_err_t err = begin(node, CO_LSS_CS_CONFIG_BIT_TIMING, done, ctx);
    if (err == CO_OK) {
        uint8_t p[2] = {table, index};
        send(node, CO_LSS_CS_CONFIG_BIT_TIMING, p, 2);
    }
    return err;
}

co_err_t co_lss_store(co_node_t *node, co_lss_done_fn done, void *ctx)
{
    co_err_t err = begin(node, CO_LSS_CS_STORE, done, ctx);
    if (err == CO_OK) {
        send(node, CO_LSS_CS_STORE, NULL, 0);
    }
    return err;
}

co_err_t co_lss_inquire(co_node_t *node, uint8_t cs, co_lss_done_fn done, void *ctx)
{
    if (cs < CO_LSS_CS_INQUIRE_VENDOR || cs > CO_LSS_CS_INQUIRE_NODE_ID) {
        return CO_ERR_ARG;
    }
    co_err_t err = begin(node, cs, done, ctx);
    if (err == CO_OK) {
        send(node, cs, NULL, 0);
    }
    return err;
}

co_err_t co_lss_identify_remote(co_node_t *node, const co_lss_address_t *low,
                                const co_lss_address_t *high, co_lss_done_fn done, void *ctx)
{
    if (low == NULL || high == NULL) {
        return CO_ERR_ARG;
    }
    co_err_t err = begin(node, CO_LSS_CS_IDENT_SERIAL_HIGH, done, ctx);
    if (err == CO_OK) {
        send_u32(node, CO_LSS_CS_IDENT_VENDOR, low->vendor);
        send_u32(node, CO_LSS_CS_IDENT_PRODUCT, low->product);
        send_u32(node, CO_LSS_CS_IDENT_REV_LOW, low->revision);
        send_u32(node, CO_LSS_CS_IDENT_REV_HIGH, high->revision);
        send_u32(node, CO_LSS_CS_IDENT_SERIAL_LOW, low->serial);
        send_u32(node, CO_LSS_CS_IDENT_SERIAL_HIGH, high->serial);
    }
    return err;
}

co_err_t co_lss_identify_non_configured(co_node_t *node, co_lss_done_fn done, void *ctx)
{
    co_err_t err = begin(node, CO_LSS_CS_IDENT_NON_CONFIGURED, done, ctx);
    if (err == CO_OK) {
        send(node, CO_LSS_CS_IDENT_NON_CONFIGURED, NULL, 0);
    }
    return err;
}

co_err_t co_lss_fastscan(co_node_t *node, const co_lss_fastscan_t *scan, co_lss_done_fn done,
                         void *ctx)
{
    co_err_t err = begin(node, CO_LSS_CS_FASTSCAN, done, ctx);
    if (err != CO_OK) {
        return err;
    }
    co_lss_master_t *m = &node->lss_master;
    bool above = scan && scan->above;
    m->known = scan && !above ? (uint8_t)(scan->known & 0x0F) : 0;
    m->phase = above ? SCAN_PREFIX : SCAN_WALK;
    m->target = 3;
    if (scan) {
        m->scan[0] = scan->address.vendor;
        m->scan[1] = scan->address.product;
        m->scan[2] = scan->address.revision;
        m->scan[3] = scan->address.serial;
    }
    scan_reset(node);
    return CO_OK;
}

#else

co_err_t co_lss_master_set_timeout(co_node_t *node, uint32_t timeout_ms)
{
    (void)node;
    (void)timeout_ms;
    return CO_ERR_STATE;
}

bool co_lss_master_busy(const co_node_t *node)
{
    (void)node;
    return false;
}

co_err_t co_lss_master_cancel(co_node_t *node)
{
    (void)node;
    return CO_ERR_STATE;
}

co_err_t co_lss_switch_global(co_node_t *node, co_lss_mode_t mode)
{
    (void)node;
    (void)mode;
    return CO_ERR_STATE;
}

co_err_t co_lss_activate_bit_timing(co_node_t *node, uint16_t delay_ms)
{
    (void)node;
    (void)delay_ms;
    return CO_ERR_STATE;
}

/* The requests with an answer share one shape when the master is left out. */
#define CO_LSS_ABSENT(...)                                                                         \
    {                                                                                              \
        (void)node;                                                                                \
        (void)done;                                                                                \
        (void)ctx;                                                                                 \
        __VA_ARGS__;                                                                               \
        return CO_ERR_STATE;                                                                       \
    }
co_err_t co_lss_switch_selective(co_node_t *node, const co_lss_address_t *address,
                                 co_lss_done_fn done, void *ctx)
    CO_LSS_ABSENT((void)address) co_err_t
    co_lss_configure_node_id(co_node_t *node, uint8_t node_id, co_lss_done_fn done, void *ctx)
        CO_LSS_ABSENT((void)node_id) co_err_t
    co_lss_configure_bit_timing(co_node_t *node, uint8_t table, uint8_t index, co_lss_done_fn done,
                                void *ctx) CO_LSS_ABSENT((void)table, (void)index) co_err_t
    co_lss_store(co_node_t *node, co_lss_done_fn done, void *ctx) CO_LSS_ABSENT((void)0) co_err_t
    co_lss_inquire(co_node_t *node, uint8_t cs, co_lss_done_fn done, void *ctx)
        CO_LSS_ABSENT((void)cs) co_err_t
    co_lss_identify_remote(co_node_t *node, const co_lss_address_t *low,
                           const co_lss_address_t *high, co_lss_done_fn done, void *ctx)
        CO_LSS_ABSENT((void)low, (void)high) co_err_t
    co_lss_identify_non_configured(co_node_t *node, co_lss_done_fn done, void *ctx)
        CO_LSS_ABSENT((void)0) co_err_t
    co_lss_fastscan(co_node_t *node, const co_lss_fastscan_t *scan, co_lss_done_fn done, void *ctx)
        CO_LSS_ABSENT((void)scan)

#endif

const char *co_lss_status_name(uint8_t status)
{
    switch (status) {
    case CO_LSS_OK:
        return "ok";
    case CO_LSS_TIMEOUT:
        return "time-out";
    case CO_LSS_REFUSED:
        return "refused by the slave";
    case CO_LSS_SCAN_FAILED:
        return "fastscan lost the slave";
    case CO_LSS_CANCELLED:
        return "cancelled";
    default:
        return "unknown";
    }
}
