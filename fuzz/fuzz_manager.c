/* SPDX-License-Identifier: Apache-2.0 */
/*
 * fuzz_manager.c -- libFuzzer target: the CiA 302-2 manager (canola/manager.h) against
 * hostile slaves. A master (node 1) boots slaves 2, 3 and 4 from a description the input
 * chooses (assignment bits, identity checks, a concise DCF, a heartbeat time); the input
 * then plays the slaves: SDO answers (right ones, wrong values, aborts, bad toggles, raw
 * bytes), silence, boot-ups and heartbeats at any time, and restarts of the manager.
 *
 * Input: a header, then a stream of records each starting with an operation byte.
 *   header: 0x1F80 bits (1 byte), reset_slaves (1), then per slave: 0x1F81 bits, which
 *           checks (bit 0..3 identity, bit 4 device type, bit 5 date/time), DCF choice,
 *           heartbeat choice (4 bytes)
 *   0: answer -- slave, style, 4 value bytes: answers the master's last SDO request to
 *                that slave (style: honest, a wrong value, an abort, a wrong toggle, a
 *                segmented answer whose segments are empty, or 8 raw bytes)
 *   1: frame  -- slave, kind (boot-up, heartbeat with a state byte, raw SDO response), 8 bytes
 *   2: time   -- advance the clock by 0..65535 x 100 us, polling at every deadline on the way
 *   3: start  -- co_manager_start() again
 * Missing bytes at the end read as zeros.
 *
 * Invariants (abort() = a finding):
 *   - every boot ends within its time-outs: a slave is never BOOTING longer than the budget
 *     its description allows (SDO time-out per answer the slave may give, for each read and
 *     each DCF record, plus its heartbeat time); after the input, silence ends every boot;
 *   - the master sends only NMT, its boot-up/heartbeat/EMCY and 8-byte SDO requests to
 *     listed slaves;
 *   - events are consistent: BOOTED/FAILED/STARTED name a listed slave; the network starts
 *     only when every mandatory slave is booted; STARTED only for a booted slave.
 *
 *   make fuzz                                                     # short run
 *   build-fuzz/fuzz_manager -max_total_time=3600 fuzz/corpus/manager   # for hours
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canola/canola.h"
#include "example_od.h"
#include "fuzz_reader.h"

#define SLAVES 3
#define FIRST 2          /* slaves are nodes 2..4 */
#define TIMEOUT_MS 100u  /* the master's SDO time-out */
#define READ_ANSWERS 10u /* an 8-byte read: initiate + up to 8 one-byte segments + silence */

typedef struct rig {
    example_od_t od;
    co_node_t node;
    co_manager_t mgr;
    co_mgr_slave_t slaves[127];
    uint8_t dcf[SLAVES][96];
    co_frame_t request[SLAVES]; /* the master's latest SDO request to each slave */
    bool requested[SLAVES];
    uint8_t up_toggle[SLAVES]; /* toggle of the next upload segment the slave sends */
    uint64_t now;
    uint64_t due;
    bool booting[SLAVES];
    uint64_t boot_start[SLAVES];
    uint64_t budget_us[SLAVES];
    bool booted_once[SLAVES];
} rig_t;

static rig_t g_rig; /* the fuzzer's harness, not the core: reinitialised every run */

static void check(int ok)
{
    if (!ok) {
        abort();
    }
}

static bool is_slave(uint8_t n)
{
    return n >= FIRST && n < FIRST + SLAVES && (g_rig.slaves[n - 1].assignment & CO_MGR_SLAVE) != 0;
}

static co_err_t capture(void *ctx, const co_frame_t *frame)
{
    rig_t *r = ctx;
    uint32_t id = frame->id;
    check(frame->flags == 0);
    if (id >= 0x600u + FIRST && id < 0x600u + FIRST + SLAVES) {
        uint8_t n = (uint8_t)(id - 0x600u);
        check(frame->len == 8 && is_slave(n));
        r->request[n - FIRST] = *frame;
        r->requested[n - FIRST] = true;
        return CO_OK;
    }
    check(id == 0x000 || id == 0x701 || id == 0x081);
    return CO_OK;
}

static void on_event(void *ctx, const co_mgr_event_t *ev)
{
    rig_t *r = ctx;
#ifdef FUZZ_TRACE /* -DFUZZ_TRACE: what a seed reaches */
    fprintf(stderr, "%8.3f s  node %u %s %c\n", (double)r->now / 1e6, ev->node_id,
            co_mgr_event_name(ev->kind), ev->reason ? ev->reason : ' ');
#endif
    switch (ev->kind) {
    case CO_MGR_BOOTED:
        check(is_slave(ev->node_id));
        r->booted_once[ev->node_id - FIRST] = true;
        r->booting[ev->node_id - FIRST] = false;
        break;
    case CO_MGR_FAILED:
        check(is_slave(ev->node_id) && ev->reason != CO_BOOT_OK);
        r->booting[ev->node_id - FIRST] = false;
        break;
    case CO_MGR_STARTED:
        check(is_slave(ev->node_id) && r->booted_once[ev->node_id - FIRST]);
        check(co_manager_slave_state(&r->mgr, ev->node_id) == CO_MGR_RUNNING);
        break;
    case CO_MGR_LOST:
    case CO_MGR_NETWORK_HALTED:
        check(is_slave(ev->node_id));
        break;
    case CO_MGR_NETWORK_STARTED:
        for (uint8_t n = FIRST; n < FIRST + SLAVES; n++) {
            co_mgr_slave_state_t s = co_manager_slave_state(&r->mgr, n);
            check(!is_slave(n) || !(r->slaves[n - 1].assignment & CO_MGR_MANDATORY) ||
                  s == CO_MGR_CONFIGURED || s == CO_MGR_RUNNING);
        }
        break;
    default:
        check(0);
    }
}

/* A boot seen in progress must end within its budget. */
static void watch_boots(rig_t *r)
{
    for (uint8_t i = 0; i < SLAVES; i++) {
        bool now_booting = co_manager_slave_state(&r->mgr, (uint8_t)(FIRST + i)) == CO_MGR_BOOTING;
        if (now_booting && !r->booting[i]) {
            r->boot_start[i] = r->now;
        }
        r->booting[i] = now_booting;
        check(!now_booting || r->now - r->boot_start[i] <= r->budget_us[i]);
    }
}

/* Time passes as in a real loop: the node is polled at each deadline on the way. A poll
 * may ask to run again at once (work it scheduled while it ran), but not forever. */
static void advance(rig_t *r, uint64_t until)
{
    unsigned same_instant = 0;
    while (r->due <= until) {
        same_instant = r->due > r->now ? 0 : same_instant + 1;
        check(same_instant < 16);
        r->now = r->due > r->now ? r->due : r->now;
        r->due = co_node_poll(&r->node, r->now);
        watch_boots(r);
    }
    r->now = until;
}

static void deliver(rig_t *r, const co_frame_t *f)
{
    co_node_ingest(&r->node, r->now, f);
    r->due = co_node_poll(&r->node, r->now);
    watch_boots(r);
}

/* ---- the description */

static const uint32_t k_identity[4] = {0x1234u, 0x10u, 3u, 7u}; /* vendor, product, rev, serial */
#define DEVICE_TYPE 0x00020192u
#define CONFIG_DATE 100u
#define CONFIG_TIME 200u

/* A concise DCF of choice 1..3 for slave i (0: none); returns its records' SDO answers. */
static uint32_t build_dcf(rig_t *r, uint8_t i, uint8_t choice, co_mgr_slave_t *s)
{
    uint8_t *buf = r->dcf[i];
    uint32_t off = 0;
    uint8_t v[40];
    memset(v, 0x5A, sizeof v);
    uint32_t answers = 0;
    switch (choice % 4u) {
    case 1: /* two expedited records */
        check(co_dcf_put(buf, sizeof r->dcf[i], &off, 0x1017, 0, v, 2) == CO_OK);
        check(co_dcf_put(buf, sizeof r->dcf[i], &off, 0x2000, 0, v, 4) == CO_OK);
        answers = 2u * 2u;
        break;
    case 2: /* a segmented record, then an expedited one */
        check(co_dcf_put(buf, sizeof r->dcf[i], &off, 0x2002, 0, v, sizeof v) == CO_OK);
        check(co_dcf_put(buf, sizeof r->dcf[i], &off, 0x1017, 0, v, 2) == CO_OK);
        answers = (2u + (sizeof v + 6u) / 7u) + 2u;
        break;
    case 3: /* malformed: claims a record more than it has */
        check(co_dcf_put(buf, sizeof r->dcf[i], &off, 0x1017, 0, v, 2) == CO_OK);
        buf[0] = 2;
        break;
    default:
        return 0;
    }
    s->dcf = buf;
    s->dcf_len = off;
    return answers;
}

static void describe(rig_t *r, reader_t *in, co_manager_config_t *mc)
{
    static const uint16_t k_hb[4] = {0, 50, 200, 1000};
    mc->nmt_startup = CO_MGR_NMT_MASTER | (take(in) & 0x0Eu);
    mc->reset_slaves = (take(in) & 1u) != 0;
    for (uint8_t i = 0; i < SLAVES; i++) {
        co_mgr_slave_t *s = &r->slaves[FIRST + i - 1];
        s->assignment = take(in) & (CO_MGR_SLAVE | CO_MGR_BOOT_ON_BOOTUP | CO_MGR_MANDATORY |
                                    CO_MGR_KEEP_ALIVE);
        uint8_t checks = take(in);
        uint32_t reads = 1;
        if (checks & 0x10u) {
            s->device_type = DEVICE_TYPE;
        }
        uint32_t *expected[4] = {&s->vendor, &s->product, &s->revision, &s->serial};
        for (uint8_t k = 0; k < 4; k++) {
            if (checks & (1u << k)) {
                *expected[k] = k_identity[k] + i;
                reads++;
            }
        }
        uint32_t dcf_answers = build_dcf(r, i, take(in), s);
        if (s->dcf != NULL && (checks & 0x20u)) {
            s->config_date = CONFIG_DATE;
            s->config_time = CONFIG_TIME;
            reads += 2;
        }
        s->heartbeat_ms = k_hb[take(in) % 4u];
        uint64_t answers = reads * READ_ANSWERS + dcf_answers + 1u;
        r->budget_us[i] = answers * TIMEOUT_MS * 1000u + s->heartbeat_ms * 1000u + 1000u;
    }
}

/* ---- the slaves */

/* The value an honest slave i holds at index/sub. */
static uint32_t honest_value(uint8_t i, uint16_t index, uint8_t sub)
{
    if (index == 0x1000) {
        return DEVICE_TYPE;
    }
    if (index == 0x1018 && sub >= 1 && sub <= 4) {
        return k_identity[sub - 1] + i;
    }
    if (index == 0x1020) {
        return sub == 1 ? CONFIG_DATE : CONFIG_TIME;
    }
    return 0;
}

/* Answer the master's latest request to slave i in the given style. */
static void answer(rig_t *r, reader_t *in)
{
    uint8_t i = (uint8_t)(take(in) % SLAVES);
    uint8_t style = take(in);
    uint8_t value[4] = {take(in), take(in), take(in), take(in)};
    if (!r->requested[i]) {
        return;
    }
    const uint8_t *q = r->request[i].data;
    co_frame_t f = {.id = 0x580u + FIRST + i, .len = 8};
    memcpy(&f.data[1], &q[1], 3); /* index and sub-index of the request */
    uint16_t index = (uint16_t)(q[1] | (q[2] << 8));
    switch (style % 6u) {
    case 0: /* honest */
    case 1: /* a wrong value */
        switch (q[0] >> 5) {
        case 2: { /* initiate upload: expedited, 4 bytes */
            uint32_t v = style % 6u == 0 ? honest_value(i, index, q[3])
                                         : (uint32_t)(value[0] | value[1] << 8 | value[2] << 16 |
                                                      (uint32_t)value[3] << 24);
            f.data[0] = 0x43;
            f.data[4] = (uint8_t)v;
            f.data[5] = (uint8_t)(v >> 8);
            f.data[6] = (uint8_t)(v >> 16);
            f.data[7] = (uint8_t)(v >> 24);
            break;
        }
        case 3: /* upload segment request: one byte of data, last when value[0] is odd */
            f.data[0] = (uint8_t)((r->up_toggle[i] << 4) | (6u << 1) | (value[0] & 1u));
            f.data[1] = value[1];
            r->up_toggle[i] ^= 1u;
            break;
        case 1: /* initiate download */
            f.data[0] = 0x60;
            break;
        case 0: /* download segment */
            f.data[0] = (uint8_t)(0x20 | (q[0] & 0x10));
            memset(&f.data[1], 0, 7);
            break;
        default:
            return;
        }
        break;
    case 2: /* an abort */
        f.data[0] = 0x80;
        memcpy(&f.data[4], value, 4);
        break;
    case 3: /* segmented upload answer, size unknown; its segments follow in style 4 */
        f.data[0] = 0x40;
        r->up_toggle[i] = 0;
        break;
    case 4: /* an upload segment without data, not the last */
        f.data[0] = (uint8_t)((r->up_toggle[i] << 4) | (7u << 1));
        memset(&f.data[1], 0, 7);
        r->up_toggle[i] ^= 1u;
        break;
    default: /* 8 raw bytes */
        for (int k = 0; k < 8; k++) {
            f.data[k] = take(in);
        }
        break;
    }
    deliver(r, &f);
}

static void frame(rig_t *r, reader_t *in)
{
    uint8_t i = (uint8_t)(take(in) % SLAVES);
    uint8_t kind = take(in);
    co_frame_t f = {.len = 8};
    for (int k = 0; k < 8; k++) {
        f.data[k] = take(in);
    }
    switch (kind % 3u) {
    case 0: /* boot-up */
        f.id = 0x700u + FIRST + i;
        f.len = 1;
        f.data[0] = 0;
        break;
    case 1: /* heartbeat with a state byte */
        f.id = 0x700u + FIRST + i;
        f.len = 1;
        break;
    default: /* raw SDO response */
        f.id = 0x580u + FIRST + i;
        break;
    }
    deliver(r, &f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rig_t *r = &g_rig;
    memset(r, 0, sizeof *r);
    reader_t in = {data, size};
    co_manager_config_t mc = {
        .slaves = r->slaves, .sdo_channel = 0, .on_event = on_event, .ctx = r};
    describe(r, &in, &mc);
    co_node_config_t cfg = {
        .node_id = 1, .od = example_od_init(&r->od, 0), .sdo_timeout_ms = TIMEOUT_MS};
    cfg.driver.tx = capture;
    cfg.driver.ctx = r;
    check(co_node_init(&r->node, &cfg) == CO_OK);
    check(co_manager_init(&r->mgr, &r->node, &mc) == CO_OK);
    check(co_node_start(&r->node, 0) == CO_OK);
    check(co_manager_start(&r->mgr) == CO_OK);
    r->due = co_node_poll(&r->node, 0);
    watch_boots(r);
    while (in.n > 0) {
        switch (take(&in) % 4u) {
        case 0:
            answer(r, &in);
            break;
        case 1:
            frame(r, &in);
            break;
        case 2:
            advance(r, r->now + 100u * (uint64_t)(take(&in) | (take(&in) << 8)));
            break;
        default: {
            co_err_t err = co_manager_start(&r->mgr);
            check(err == CO_OK || err == CO_ERR_BUSY);
            r->due = co_node_poll(&r->node, r->now);
            watch_boots(r);
            break;
        }
        }
    }
    /* Silence: every boot ends, none waits; the manager accepts a new start. */
    uint64_t longest = 0;
    for (uint8_t i = 0; i < SLAVES; i++) {
        longest += r->budget_us[i];
    }
    advance(r, r->now + longest + 1000000u);
    for (uint8_t n = FIRST; n < FIRST + SLAVES; n++) {
        co_mgr_slave_state_t s = co_manager_slave_state(&r->mgr, n);
        check(s != CO_MGR_BOOTING && s != CO_MGR_WAITING);
    }
    check(co_manager_start(&r->mgr) == CO_OK);
    return 0;
}
