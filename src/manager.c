/* SPDX-License-Identifier: Apache-2.0 */
/*
 * manager.c -- the CANopen manager (CiA 302-2): boots the listed slaves one after the
 * other over SDO (identity checks, concise DCF, heartbeat), then starts the network.
 *
 * Driven like every service: SDO completions (from ingest) move a slave's boot from
 * step to step; poll picks the next slave, checks the heartbeat wait and starts the
 * network. A boot that ends (booted or failed) only marks the manager free; poll
 * begins the next one, so a chain of failures never recurses.
 */
#include "manager_internal.h"
#include "sdo_internal.h" /* co_sdo_clients_max */

#if CO_CONFIG_MANAGER

enum step {
    STEP_TYPE = 1, /* read 0x1000 */
    STEP_VENDOR,   /* read 0x1018 sub1..4 where expected */
    STEP_PRODUCT,
    STEP_REVISION,
    STEP_SERIAL,
    STEP_DATE, /* read 0x1020 sub1 and sub2 when a date/time is expected */
    STEP_TIME,
    STEP_DCF, /* download the concise DCF */
    STEP_EC,  /* wait for the first heartbeat */
    STEP_DONE,
};

static const co_mgr_slave_t *slave(const co_manager_t *m, uint8_t n)
{
    return &m->cfg.slaves[n - 1];
}

static bool listed(const co_manager_t *m, uint8_t n)
{
    return n >= 1 && n <= 127 && (slave(m, n)->assignment & CO_MGR_SLAVE);
}

static void report(co_manager_t *m, uint8_t n, co_mgr_event_kind_t kind, uint8_t reason,
                   uint32_t abort, uint32_t value)
{
    if (m->cfg.on_event) {
        co_mgr_event_t ev = {
            .node_id = n, .kind = (uint8_t)kind, .reason = reason, .abort = abort, .value = value};
        if (kind == CO_MGR_FAILED) {
            ev.index = m->index;
            ev.sub = m->sub;
        }
        m->cfg.on_event(m->cfg.ctx, &ev);
    }
}

/* The boot of the current slave ends; poll goes on with the next. */
static void release(co_manager_t *m)
{
    m->current = 0;
    co_node_schedule(m->node, m->node->now_us);
}

static void fail(co_manager_t *m, co_boot_reason_t reason, uint32_t abort, uint32_t value)
{
    uint8_t n = m->current;
    m->state[n - 1] = CO_MGR_FAILED_STATE;
    m->reason[n - 1] = (uint8_t)reason;
    report(m, n, CO_MGR_FAILED, (uint8_t)reason, abort, value);
    if ((slave(m, n)->assignment & CO_MGR_MANDATORY) && !m->network_started) {
        report(m, n, CO_MGR_NETWORK_HALTED, (uint8_t)reason, abort, value);
    }
    release(m);
}

static void start_slave(co_manager_t *m, uint8_t n)
{
    (void)m->node->wiring->nmt_send(m->node, CO_NMT_CMD_START, n);
    m->state[n - 1] = CO_MGR_RUNNING;
    report(m, n, CO_MGR_STARTED, CO_BOOT_OK, 0, 0);
}

static void booted(co_manager_t *m)
{
    uint8_t n = m->current;
    m->state[n - 1] = CO_MGR_CONFIGURED;
    m->reason[n - 1] = CO_BOOT_OK;
    report(m, n, CO_MGR_BOOTED, CO_BOOT_OK, 0, 0);
    if (m->network_started && !(m->cfg.nmt_startup & CO_MGR_NO_SLAVE_START)) {
        start_slave(m, n); /* a late slave joins the running network */
    }
    release(m);
}

/* ---- the steps */

static void run_step(co_manager_t *m);

static void next_step(co_manager_t *m)
{
    m->step++;
    run_step(m);
}

static void on_value(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value, uint32_t len)
{
    (void)channel;
    (void)len;
    co_manager_t *m = ctx;
    if (m->current == 0) {
        return; /* ended by the master's own reset: that boot is over */
    }
    const co_mgr_slave_t *d = slave(m, m->current);
    uint32_t v = (uint32_t)value;
    static const uint8_t letter[] = {CO_BOOT_VENDOR, CO_BOOT_PRODUCT, CO_BOOT_REVISION,
                                     CO_BOOT_SERIAL};
    const uint32_t expected[] = {d->vendor, d->product, d->revision, d->serial};
    switch (m->step) {
    case STEP_TYPE:
        if (abort != CO_ABORT_NONE) {
            fail(m, CO_BOOT_NO_ANSWER, abort, 0);
        } else if (d->device_type != 0 && v != d->device_type) {
            fail(m, CO_BOOT_DEVICE_TYPE, 0, v);
        } else {
            next_step(m);
        }
        return;
    case STEP_VENDOR:
    case STEP_PRODUCT:
    case STEP_REVISION:
    case STEP_SERIAL: {
        uint8_t i = (uint8_t)(m->step - STEP_VENDOR);
        if (abort != CO_ABORT_NONE || v != expected[i]) {
            fail(m, (co_boot_reason_t)letter[i], abort, v);
        } else {
            next_step(m);
        }
        return;
    }
    case STEP_DATE:
        if (abort != CO_ABORT_NONE) {
            m->step = STEP_DCF; /* no date to compare: download */
            run_step(m);
            return;
        }
        m->date = v;
        next_step(m);
        return;
    case STEP_TIME:
        if (abort == CO_ABORT_NONE && m->date == d->config_date && v == d->config_time) {
            m->step = STEP_DCF; /* the slave has this configuration already */
        }
        next_step(m);
        return;
    default:
        return;
    }
}

static void read_entry(co_manager_t *m, uint16_t index, uint8_t sub)
{
    m->index = index;
    m->sub = sub;
    co_err_t err = co_sdo_read_value(m->node, m->cfg.sdo_channel, index, sub, on_value, m);
    if (err != CO_OK) {
        fail(m, CO_BOOT_NO_ANSWER, CO_ABORT_GENERAL, 0);
    }
}

static void download_next(co_manager_t *m);

static void on_downloaded(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    (void)len;
    co_manager_t *m = ctx;
    if (m->current == 0) {
        return; /* ended by the master's own reset: that boot is over */
    }
    if (abort != CO_ABORT_NONE) {
        fail(m, CO_BOOT_CONFIG, abort, 0);
    } else if (m->dcf_left == 0) {
        next_step(m);
    } else {
        download_next(m);
    }
}

/* The next record of the concise DCF (dcf_left > 0); on_downloaded carries on. */
static void download_next(co_manager_t *m)
{
    const co_mgr_slave_t *d = slave(m, m->current);
    const uint8_t *p = d->dcf + m->dcf_off;
    uint32_t size = co_get_u32(p + 3);
    m->index = co_get_u16(p);
    m->sub = p[2];
    m->dcf_off += 7 + size;
    m->dcf_left--;
    co_err_t err = co_sdo_download(m->node, m->cfg.sdo_channel, m->index, m->sub, CO_SDO_AUTO,
                                   p + 7, size, on_downloaded, m);
    if (err != CO_OK) {
        fail(m, CO_BOOT_CONFIG, CO_ABORT_GENERAL, 0);
    }
}

/* The master's 0x1016 entry for slave n: the one naming it, else the first unused; written
 * through the node, so that the consumer takes it at once. */
static bool watch_heartbeat(co_manager_t *m, uint8_t n, uint16_t ms)
{
    const co_od_t *od = &m->node->cfg.od;
    uint64_t count = 0;
    if (co_od_get_uint(od, 0x1016, 0, &count) != CO_OK) {
        return false;
    }
    uint8_t free_sub = 0;
    for (uint32_t i = 1; i <= count && i <= 0xFF; i++) { /* 32 bits: 255 entries end the loop */
        uint8_t sub = (uint8_t)i;
        uint64_t v = 0;
        (void)co_od_get_uint(od, 0x1016, sub, &v);
        if (((v >> 16) & 0xFF) == n) {
            free_sub = sub;
            break;
        }
        if (free_sub == 0 && (((v >> 16) & 0xFF) == 0 || (v & 0xFFFF) == 0)) {
            free_sub = sub;
        }
    }
    const co_od_entry_t *e = free_sub != 0 ? co_od_find(od, 0x1016, free_sub, NULL) : NULL;
    uint8_t value[4];
    co_put_u32(value, ((uint32_t)n << 16) | ms);
    return e != NULL && co_od_size(od, e) == sizeof value &&
           co_node_write(m->node, e, value, sizeof value) == CO_ABORT_NONE;
}

static void run_step(co_manager_t *m)
{
    uint8_t n = m->current;
    const co_mgr_slave_t *d = slave(m, n);
    const uint32_t expected[] = {d->vendor, d->product, d->revision, d->serial};
    for (;;) {
        switch (m->step) {
        case STEP_TYPE:
            read_entry(m, 0x1000, 0);
            return;
        case STEP_VENDOR:
        case STEP_PRODUCT:
        case STEP_REVISION:
        case STEP_SERIAL: {
            uint8_t i = (uint8_t)(m->step - STEP_VENDOR);
            if (expected[i] != 0) {
                read_entry(m, 0x1018, (uint8_t)(i + 1));
                return;
            }
            break;
        }
        case STEP_DATE:
            if (d->dcf != NULL && (d->config_date != 0 || d->config_time != 0)) {
                read_entry(m, 0x1020, 1);
                return;
            }
            m->step = STEP_TIME; /* and on past it */
            break;
        case STEP_TIME:
            read_entry(m, 0x1020, 2);
            return;
        case STEP_DCF:
            if (d->dcf != NULL) {
                m->index = 0;
                m->sub = 0;
                if (co_dcf_check(d->dcf, d->dcf_len) != CO_OK) {
                    fail(m, CO_BOOT_CONFIG, 0, 0);
                    return;
                }
                m->dcf_off = 4;
                m->dcf_left = co_get_u32(d->dcf);
                if (m->dcf_left != 0) {
                    download_next(m);
                    return;
                }
            }
            break;
        case STEP_EC:
            if (d->heartbeat_ms != 0) {
                m->index = 0x1016;
                m->sub = 0;
                if (!watch_heartbeat(m, n, d->heartbeat_ms)) {
                    fail(m, CO_BOOT_HEARTBEAT_START, 0, 0);
                    return;
                }
                m->deadline_us = m->node->now_us + co_ms_to_us(d->heartbeat_ms);
                co_node_schedule(m->node, m->deadline_us);
                return;
            }
            break;
        default:
            booted(m);
            return;
        }
        m->step++;
    }
}

/* ---- the network */

/* "Start all" with node-ID 0 would also start slaves that failed their checks. */
static bool all_configured(const co_manager_t *m)
{
    for (uint8_t n = 1; n <= 127; n++) {
        if (m->state[n - 1] != CO_MGR_UNLISTED && m->state[n - 1] != CO_MGR_CONFIGURED) {
            return false;
        }
    }
    return true;
}

static void start_network(co_manager_t *m)
{
    uint32_t startup = m->cfg.nmt_startup;
    if (!all_configured(m)) {
        startup &= ~CO_MGR_START_ALL;
    }
    m->network_started = true;
    if (!(startup & CO_MGR_NO_SLAVE_START)) {
        if (startup & CO_MGR_START_ALL) {
            uint8_t all[2] = {CO_NMT_CMD_START, 0}; /* (not nmt_send: it would start us too) */
            (void)co_node_send_cob(m->node, 0x000, all, sizeof all, 0);
        }
        for (uint8_t n = 1; n <= 127; n++) {
            if (m->state[n - 1] != CO_MGR_CONFIGURED) {
                continue;
            }
            if (startup & CO_MGR_START_ALL) {
                m->state[n - 1] = CO_MGR_RUNNING;
                report(m, n, CO_MGR_STARTED, CO_BOOT_OK, 0, 0);
            } else {
                start_slave(m, n);
            }
        }
    }
    if (!(startup & CO_MGR_NO_SELF_START)) {
        (void)m->node->wiring->nmt_apply(m->node, CO_NMT_CMD_START);
    }
    report(m, 0, CO_MGR_NETWORK_STARTED, CO_BOOT_OK, 0, 0);
}

static bool mandatory_ready(const co_manager_t *m)
{
    for (uint8_t n = 1; n <= 127; n++) {
        uint8_t s = m->state[n - 1];
        if (listed(m, n) && n != m->node->node_id && (slave(m, n)->assignment & CO_MGR_MANDATORY) &&
            s != CO_MGR_CONFIGURED && s != CO_MGR_RUNNING) {
            return false;
        }
    }
    return true;
}

static uint8_t next_waiting(const co_manager_t *m)
{
    for (uint8_t n = 1; n <= 127; n++) {
        if (m->state[n - 1] == CO_MGR_WAITING) {
            return n;
        }
    }
    return 0;
}

static void begin(co_manager_t *m);

uint64_t co_manager_poll(co_node_t *node, uint64_t now_us)
{
    co_manager_t *m = node->manager;
    if (m == NULL || !m->running) {
        return CO_TIME_NEVER;
    }
    if (m->restart) { /* after the master's reset, once its boot-up is out */
        m->restart = false;
        begin(m);
    }
    if (m->current != 0 && m->step == STEP_EC && now_us >= m->deadline_us) {
        fail(m, CO_BOOT_HEARTBEAT_START, 0, 0);
    }
    while (m->current == 0) {
        uint8_t n = next_waiting(m);
        if (n == 0) {
            if (!m->network_started && mandatory_ready(m)) {
                start_network(m);
            }
            break;
        }
        m->current = n;
        m->state[n - 1] = CO_MGR_BOOTING;
        m->step = STEP_TYPE;
        m->index = 0x1000;
        m->sub = 0;
        if (co_sdo_client_setup(node, m->cfg.sdo_channel, n) != CO_OK) {
            fail(m, CO_BOOT_NO_ANSWER, CO_ABORT_GENERAL, 0); /* the channel is not ours */
            continue;
        }
        run_step(m);
    }
    return m->current != 0 && m->step == STEP_EC ? m->deadline_us : CO_TIME_NEVER;
}

/* The master's own reset communication (before the services forget their state): the
 * boot in progress ends without a verdict on its slave, and the manager starts over at
 * the next poll (CiA 302-2: the master's start-up follows its reset; the heartbeat
 * watches it set up are gone with the reset). */
void co_manager_reset_comm(co_node_t *node)
{
    co_manager_t *m = node->manager;
    if (m != NULL && m->running) {
        m->current = 0;
        m->restart = true;
        co_node_schedule(node, node->now_us);
    }
}

/* A boot-up (or a heartbeat event) from slave n. */
static void slave_booted_up(co_manager_t *m, uint8_t n)
{
    uint8_t s = m->state[n - 1];
    if (!m->running || !listed(m, n) || s == CO_MGR_BOOTING || s == CO_MGR_WAITING) {
        return;
    }
    uint32_t a = slave(m, n)->assignment;
    /* A mandatory slave the halted network waits for is always worth another try. */
    if ((a & CO_MGR_BOOT_ON_BOOTUP) || ((a & CO_MGR_MANDATORY) && !m->network_started)) {
        m->state[n - 1] = CO_MGR_WAITING;
        co_node_schedule(m->node, m->node->now_us);
    }
}

void co_manager_bootup(co_node_t *node, uint8_t n, const co_frame_t *frame)
{
    co_manager_t *m = node->manager;
    if (m != NULL && frame->len == 1 && frame->data[0] == 0 && !(frame->flags & CO_FRAME_RTR)) {
        slave_booted_up(m, n);
    }
}

void co_manager_ec_event(co_node_t *node, const co_ec_event_t *ev)
{
    co_manager_t *m = node->manager;
    uint8_t n = ev->node_id;
    if (m == NULL || !m->running || !listed(m, n)) {
        return;
    }
    switch (ev->kind) {
    case CO_EC_BOOT:
    case CO_EC_REMOTE_RESET:
        slave_booted_up(m, n);
        break;
    case CO_EC_STARTED:
    case CO_EC_HB_RESUMED:
        if (m->current == n && m->step == STEP_EC) {
            m->step = STEP_DONE;
            booted(m);
        }
        break;
    case CO_EC_HB_TIMEOUT:
        if (m->state[n - 1] == CO_MGR_CONFIGURED || m->state[n - 1] == CO_MGR_RUNNING) {
            m->state[n - 1] = CO_MGR_MISSING;
            m->reason[n - 1] = CO_BOOT_HEARTBEAT;
            report(m, n, CO_MGR_LOST, CO_BOOT_HEARTBEAT, 0, 0);
        }
        break;
    default:
        break;
    }
}

/* The boot-ups of the listed slaves, this node's own ID aside (it may change at a reset). */
void co_manager_routes(co_node_t *node)
{
    const co_manager_t *m = node->manager;
    for (uint8_t n = 1; m != NULL && n <= 127; n++) {
        bool slave_n = listed(m, n) && n != node->node_id;
        co_route_set(node, CO_ROUTE_MGR_BOOTUP, n, slave_n ? 0x700u + n : CO_ROUTE_OFF);
    }
}

/* ---- API */

co_err_t co_manager_init(co_manager_t *mgr, co_node_t *node, const co_manager_config_t *config)
{
    if (mgr == NULL || node == NULL || config == NULL || config->slaves == NULL ||
        config->sdo_channel >= co_sdo_clients_max()) {
        return CO_ERR_ARG;
    }
    if (!(config->nmt_startup & CO_MGR_NMT_MASTER)) {
        return CO_ERR_CONFIG;
    }
    *mgr = (co_manager_t){.cfg = *config, .node = node};
    node->manager = mgr;
    co_manager_routes(node);
    return CO_OK;
}

/* Every listed slave waits for its boot; the network is not started. */
static void begin(co_manager_t *mgr)
{
    mgr->running = true;
    mgr->restart = false;
    mgr->network_started = false;
    for (uint8_t n = 1; n <= 127; n++) {
        bool slave_n = listed(mgr, n) && n != mgr->node->node_id;
        mgr->state[n - 1] = slave_n ? CO_MGR_WAITING : CO_MGR_UNLISTED;
        mgr->reason[n - 1] = slave_n ? CO_BOOT_OK : CO_BOOT_NOT_LISTED;
        if (slave_n && mgr->cfg.reset_slaves &&
            !(mgr->cfg.slaves[n - 1].assignment & CO_MGR_KEEP_ALIVE)) {
            (void)mgr->node->wiring->nmt_send(mgr->node, CO_NMT_CMD_RESET_COMMUNICATION, n);
        }
    }
    co_node_schedule(mgr->node, mgr->node->now_us);
}

co_err_t co_manager_start(co_manager_t *mgr)
{
    if (!mgr->node->started) {
        return CO_ERR_STATE;
    }
    if (mgr->current != 0) {
        return CO_ERR_BUSY; /* a slave's boot is in progress */
    }
    begin(mgr);
    return CO_OK;
}

co_mgr_slave_state_t co_manager_slave_state(const co_manager_t *mgr, uint8_t node_id)
{
    return node_id >= 1 && node_id <= 127 ? (co_mgr_slave_state_t)mgr->state[node_id - 1]
                                          : CO_MGR_UNLISTED;
}

co_boot_reason_t co_manager_slave_reason(const co_manager_t *mgr, uint8_t node_id)
{
    return node_id >= 1 && node_id <= 127 ? (co_boot_reason_t)mgr->reason[node_id - 1]
                                          : CO_BOOT_NOT_LISTED;
}

bool co_manager_network_started(const co_manager_t *mgr) { return mgr->network_started; }

#else

co_err_t co_manager_init(co_manager_t *mgr, co_node_t *node, const co_manager_config_t *config)
{
    (void)mgr;
    (void)node;
    (void)config;
    return CO_ERR_STATE;
}

co_err_t co_manager_start(co_manager_t *mgr)
{
    (void)mgr;
    return CO_ERR_STATE;
}

co_mgr_slave_state_t co_manager_slave_state(const co_manager_t *mgr, uint8_t node_id)
{
    (void)mgr;
    (void)node_id;
    return CO_MGR_UNLISTED;
}

co_boot_reason_t co_manager_slave_reason(const co_manager_t *mgr, uint8_t node_id)
{
    (void)mgr;
    (void)node_id;
    return CO_BOOT_NOT_LISTED;
}

bool co_manager_network_started(const co_manager_t *mgr)
{
    (void)mgr;
    return false;
}

#endif
