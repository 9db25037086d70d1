/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_manager.c -- the CANopen manager (CiA 302-2): concise DCF helpers, reason texts,
 * and networks booted from one description on the simulated bus.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define DEVICES 10
#define FIRST 2 /* devices are nodes 2..11, the master node 1 */

typedef struct station {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
    uint32_t ident[4];
} station_t;

typedef struct net {
    co_sim_bus_t bus;
    station_t master;
    station_t dev[DEVICES];
    co_manager_t mgr;
    co_mgr_slave_t slaves[127];
    co_mgr_event_t events[64];
    uint64_t event_at[64];
    uint32_t event_count;
    uint8_t dcf[4][128];
    uint32_t start_frames; /* NMT start commands seen on the bus */
    uint32_t reset_frames; /* NMT reset communication commands */
    uint32_t sdo_requests; /* frames on 0x601..0x67F */
} net_t;

static void on_event(void *ctx, const co_mgr_event_t *ev)
{
    net_t *n = ctx;
    if (n->event_count < 64) {
        n->event_at[n->event_count] = n->bus.now_us;
        n->events[n->event_count++] = *ev;
    }
}

static void on_trace(void *ctx, const char *line)
{
    net_t *n = ctx;
    n->start_frames += strstr(line, " 000#01") != NULL;
    n->reset_frames += strstr(line, " 000#82") != NULL;
    const char *hash = strchr(line, '#');
    n->sdo_requests += hash != NULL && hash - line >= 4 && hash[-4] == ' ' && hash[-3] == '6';
}

static const co_mgr_event_t *find(const net_t *n, uint8_t node, co_mgr_event_kind_t kind)
{
    for (uint32_t i = 0; i < n->event_count; i++) {
        if (n->events[i].node_id == node && n->events[i].kind == kind) {
            return &n->events[i];
        }
    }
    return NULL;
}

/* A station on the example dictionary, without the entries of index `drop` (0: none). */
static void station_without(net_t *n, station_t *s, uint8_t id, uint16_t hb_ms,
                            const uint32_t ident[4], uint16_t drop)
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_init(&s->od, hb_ms)};
    uint32_t kept = 0;
    for (uint32_t e = 0; e < cfg.od.count; e++) {
        if (s->od.entries[e].index != drop) {
            s->od.entries[kept++] = s->od.entries[e];
        }
    }
    cfg.od.count = kept;
    if (ident) {
        memcpy(s->ident, ident, sizeof s->ident);
        for (uint32_t e = 0; e < cfg.od.count; e++) {
            co_od_entry_t *en = &s->od.entries[e];
            if (en->index == 0x1018 && en->sub >= 1) {
                en->dflt = &s->ident[en->sub - 1];
            }
        }
    }
    CHECK_EQ(co_sim_port_attach(&n->bus, &s->port), CO_OK);
    cfg.driver = co_sim_port_driver(&s->port);
    CHECK_EQ(co_node_init(&s->node, &cfg), CO_OK);
    co_sim_port_bind(&s->port, &s->node);
}

static void station(net_t *n, station_t *s, uint8_t id, uint16_t hb_ms, const uint32_t ident[4])
{
    station_without(n, s, id, hb_ms, ident, 0);
}

static co_node_t *dev(net_t *n, uint8_t id) { return &n->dev[id - FIRST].node; }

static uint32_t dcf_u32(uint8_t *buf, uint32_t *off, uint16_t idx, uint8_t sub, uint32_t v)
{
    uint8_t b[4];
    co_put_u32(b, v);
    CHECK_EQ(co_dcf_put(buf, 128, off, idx, sub, b, 4), CO_OK);
    return *off;
}

static uint32_t dcf_u16(uint8_t *buf, uint32_t *off, uint16_t idx, uint8_t sub, uint16_t v)
{
    uint8_t b[2];
    co_put_u16(b, v);
    CHECK_EQ(co_dcf_put(buf, 128, off, idx, sub, b, 2), CO_OK);
    return *off;
}

/* ---- concise DCF and texts */

static void test_dcf_put_and_check(void)
{
    uint8_t buf[32];
    uint32_t off = 0;
    uint8_t v[2] = {0x64, 0x00};
    CHECK_EQ(co_dcf_put(buf, sizeof buf, &off, 0x1017, 0, v, 2), CO_OK);
    CHECK_EQ(off, 4 + 7 + 2);
    static const uint8_t want[] = {1, 0, 0, 0, 0x17, 0x10, 0x00, 2, 0, 0, 0, 0x64, 0x00};
    CHECK(memcmp(buf, want, sizeof want) == 0);
    CHECK_EQ(co_dcf_check(buf, off), CO_OK);
    CHECK_EQ(co_dcf_check(buf, off - 1), CO_ERR_CONFIG); /* cut in a record */
    CHECK_EQ(co_dcf_check(buf, off + 1), CO_ERR_CONFIG); /* bytes after the last */
    CHECK_EQ(co_dcf_check(buf, 3), CO_ERR_CONFIG);
    buf[0] = 2; /* claims a record that is not there */
    CHECK_EQ(co_dcf_check(buf, off), CO_ERR_CONFIG);
    buf[0] = 1;
    uint8_t big[20] = {0};
    CHECK_EQ(co_dcf_put(buf, sizeof buf, &off, 0x2000, 0, big, sizeof big), CO_ERR_FULL);
    CHECK_EQ(co_get_u32(buf), 1);
    /* A size field near 2^32 must not wrap the check. */
    static const uint8_t huge[] = {1, 0, 0, 0, 0, 0x20, 0, 0xFF, 0xFF, 0xFF, 0xFF, 0};
    CHECK_EQ(co_dcf_check(huge, sizeof huge), CO_ERR_CONFIG);
}

static void test_reason_texts(void)
{
    CHECK_STR(co_boot_reason_text(CO_BOOT_VENDOR), "D: vendor-ID does not match");
    CHECK_STR(co_boot_reason_text(CO_BOOT_CONFIG), "J: configuration download failed");
    CHECK_STR(co_boot_reason_text(CO_BOOT_NO_ANSWER),
              "B: no answer to the read of the device type");
    CHECK_STR(co_boot_reason_text(CO_BOOT_OK), "");
    CHECK_STR(co_boot_reason_text('Z'), "unknown reason");
    CHECK_STR(co_mgr_event_name(CO_MGR_NETWORK_HALTED), "network halted");
}

static void test_init_arguments(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 0);
    station(n, &n->master, 1, 0, NULL);
    co_manager_config_t mc = {.nmt_startup = 0, .slaves = n->slaves};
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_ERR_CONFIG);
    mc.nmt_startup = CO_MGR_NMT_MASTER;
    mc.slaves = NULL;
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_ERR_ARG);
    mc.slaves = n->slaves;
    mc.sdo_channel = 1; /* one client channel in this build */
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_ERR_ARG);
    mc.sdo_channel = 0;
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
    CHECK_EQ(co_manager_start(&n->mgr), CO_ERR_STATE); /* node not started */
    free(n);
}

/* ---- ten devices from one description */

static net_t *ten_devices(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    co_sim_set_trace(&n->bus, on_trace, n);
    station(n, &n->master, 1, 0, NULL);
    for (uint8_t i = 0; i < DEVICES; i++) {
        uint8_t id = (uint8_t)(FIRST + i);
        uint32_t ident[4] = {id == 3 ? 0xBADu : 0xCA0u, 0x100u + id, 0x00010000u, 5000u + id};
        station(n, &n->dev[i], id, 100, ident);
        co_mgr_slave_t *s = &n->slaves[id - 1];
        s->assignment = CO_MGR_SLAVE | CO_MGR_BOOT_ON_BOOTUP;
        s->device_type = 0x191;
        s->vendor = 0xCA0;
        s->product = 0x100u + id;
        if (id % 2 == 0) {
            s->serial = 5000u + id;
        }
        if (id == 2 || id == 6) {
            s->assignment |= CO_MGR_MANDATORY;
        }
        if (id == 2 || id == 6 || id == 9 || id == 10) {
            s->heartbeat_ms = 300;
        }
    }
    /* Node 2: a configuration. Node 5: one the device refuses (0x2001 is -100..100). */
    uint32_t off = 0;
    dcf_u32(n->dcf[0], &off, 0x2000, 0, 0xAABBCCDD);
    dcf_u16(n->dcf[0], &off, 0x1017, 0, 50);
    n->slaves[2 - 1].dcf = n->dcf[0];
    n->slaves[2 - 1].dcf_len = off;
    off = 0;
    dcf_u32(n->dcf[1], &off, 0x2000, 0, 7);
    dcf_u16(n->dcf[1], &off, 0x2001, 0, 500);
    dcf_u32(n->dcf[1], &off, 0x2007, 0, 9);
    n->slaves[5 - 1].dcf = n->dcf[1];
    n->slaves[5 - 1].dcf_len = off;
    co_manager_config_t mc = {
        .nmt_startup = CO_MGR_NMT_MASTER, .slaves = n->slaves, .on_event = on_event, .ctx = n};
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
    return n;
}

static void test_ten_devices_boot_from_one_description(void)
{
    net_t *n = ten_devices();
    /* Everybody powers on at 0 except node 4, which is switched on at 8 s. */
    co_node_start(&n->master.node, 0);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        if (id != 4) {
            co_node_start(dev(n, id), 0);
        }
    }
    co_sim_run_until(&n->bus, 10 * MS);
    CHECK_EQ(co_manager_start(&n->mgr), CO_OK);
    co_sim_run_until(&n->bus, 11 * MS);
    CHECK_EQ(co_manager_start(&n->mgr), CO_ERR_BUSY); /* node 2 is being booted */
    co_sim_run_until(&n->bus, 5000 * MS);

    /* Wrong vendor: refused, reported with what it said. */
    const co_mgr_event_t *e = find(n, 3, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'D');
        CHECK_EQ(e->value, 0xBAD);
        CHECK_EQ(e->index, 0x1018);
        CHECK_EQ(e->sub, 1);
    }
    /* Missing optional node: no answer (the SDO time-out). */
    e = find(n, 4, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'B');
        CHECK_EQ(e->abort, CO_ABORT_TIMEOUT);
    }
    /* The refused configuration entry, with its abort code. */
    e = find(n, 5, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'J');
        CHECK_EQ(e->abort, CO_ABORT_VALUE_HIGH);
        CHECK_EQ(e->index, 0x2001);
        CHECK_EQ(e->sub, 0);
    }
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 5), CO_BOOT_CONFIG);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 5), CO_MGR_FAILED_STATE);
    /* The mandatory ones booted: the network runs, the good devices are operational. */
    CHECK(co_manager_network_started(&n->mgr));
    CHECK(find(n, 0, CO_MGR_NETWORK_STARTED) != NULL);
    CHECK(find(n, 2, CO_MGR_NETWORK_HALTED) == NULL);
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        bool good = id != 3 && id != 4 && id != 5;
        CHECK_EQ(co_nmt_state(dev(n, id)) == CO_NMT_OPERATIONAL, good);
        CHECK_EQ(co_manager_slave_state(&n->mgr, id) == CO_MGR_RUNNING, good);
        CHECK_EQ(find(n, id, CO_MGR_STARTED) != NULL, good);
    }
    CHECK_EQ(co_nmt_state(dev(n, 3)), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_nmt_state(dev(n, 5)), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(n->start_frames, DEVICES - 3); /* one NMT start per good slave */
    /* Node 2 got its configuration. */
    CHECK_EQ(n->dev[0].od.app_u32, 0xAABBCCDD);
    CHECK_EQ(n->dev[0].od.hb_period_ms, 50);
    /* Node 5: what came before the refused entry was written, nothing after it. */
    CHECK_EQ(n->dev[3].od.app_u32, 7);
    CHECK_EQ(n->dev[3].od.app_u32b, 0);

    /* Node 4 appears: its boot-up makes the manager boot it and start it. */
    co_node_start(dev(n, 4), n->bus.now_us);
    co_sim_run_until(&n->bus, 7000 * MS);
    e = find(n, 4, CO_MGR_BOOTED);
    CHECK(e != NULL);
    CHECK(find(n, 4, CO_MGR_STARTED) != NULL);
    CHECK_EQ(co_nmt_state(dev(n, 4)), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 4), CO_MGR_RUNNING);

    /* A watched device goes silent: heartbeat lost (E). */
    co_sim_set_bus_off(&n->dev[9 - FIRST].port, true);
    co_sim_run_until(&n->bus, 8000 * MS);
    e = find(n, 9, CO_MGR_LOST);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'E');
    }
    CHECK_EQ(co_manager_slave_state(&n->mgr, 9), CO_MGR_MISSING);

    /* The master resets its communication (its heartbeat watches are gone): the manager
     * starts over by itself, the slaves are booted and watched again, node 9 is still
     * missing. */
    co_sim_set_bus_off(&n->dev[9 - FIRST].port, false);
    co_node_set_uint(dev(n, 9), 0x1017, 0, 0); /* it stays silent */
    co_nmt_apply(&n->master.node, CO_NMT_CMD_RESET_COMMUNICATION);
    uint32_t before = n->event_count;
    co_sim_run_until(&n->bus, n->bus.now_us + 5000 * MS);
    uint32_t booted = 0, k = 0;
    for (uint32_t i = before; i < n->event_count; i++) {
        booted += n->events[i].kind == CO_MGR_BOOTED;
        k += n->events[i].kind == CO_MGR_FAILED && n->events[i].node_id == 9 &&
             n->events[i].reason == 'K';
    }
    CHECK_EQ(booted, DEVICES - 3); /* 3 and 5 refused again, 9 silent */
    CHECK_EQ(k, 1);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
    free(n);
}

static void test_missing_mandatory_keeps_the_network_down(void)
{
    net_t *n = ten_devices();
    co_node_start(&n->master.node, 0);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        if (id != 6) { /* mandatory node 6 is off */
            co_node_start(dev(n, id), 0);
        }
    }
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 6000 * MS);
    const co_mgr_event_t *e = find(n, 6, CO_MGR_NETWORK_HALTED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'B');
    }
    CHECK(!co_manager_network_started(&n->mgr));
    CHECK_EQ(n->start_frames, 0);
    CHECK_EQ(co_nmt_state(dev(n, 2)), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_CONFIGURED);
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_PRE_OPERATIONAL);
    /* It comes (a mandatory slave boots on its boot-up even without bit 2): booted, and
     * the whole network starts. */
    n->slaves[6 - 1].assignment &= ~CO_MGR_BOOT_ON_BOOTUP;
    co_node_start(dev(n, 6), n->bus.now_us);
    co_sim_run_until(&n->bus, 8000 * MS);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(dev(n, 6)), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_nmt_state(dev(n, 2)), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
    free(n);
}

static void test_start_all_when_everyone_booted(void)
{
    net_t *n = ten_devices();
    n->mgr.cfg.nmt_startup = CO_MGR_NMT_MASTER | CO_MGR_START_ALL | CO_MGR_NO_SELF_START;
    n->slaves[3 - 1].vendor = 0xBAD; /* describe node 3 as it is, give node 5 no DCF */
    n->slaves[5 - 1].dcf = NULL;
    co_node_start(&n->master.node, 0);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        co_node_start(dev(n, id), 0);
    }
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 5000 * MS);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(n->start_frames, 1); /* 000#0100: one NMT start for all */
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        CHECK_EQ(co_nmt_state(dev(n, id)), CO_NMT_OPERATIONAL);
        CHECK(find(n, id, CO_MGR_STARTED) != NULL);
    }
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_PRE_OPERATIONAL); /* bit 2: not itself */
    free(n);
}

static void test_start_all_with_a_failure_starts_one_by_one(void)
{
    net_t *n = ten_devices();
    n->mgr.cfg.nmt_startup = CO_MGR_NMT_MASTER | CO_MGR_START_ALL;
    co_node_start(&n->master.node, 0);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        co_node_start(dev(n, id), 0);
    }
    /* Node 10 is watched, but its producer is off: K. */
    CHECK_EQ(co_node_set_uint(dev(n, 10), 0x1017, 0, 0), CO_ABORT_NONE);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 5000 * MS);
    const co_mgr_event_t *e = find(n, 10, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'K');
    }
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(n->start_frames, DEVICES - 3); /* 3, 5 and 10 failed */
    CHECK_EQ(co_nmt_state(dev(n, 3)), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_nmt_state(dev(n, 10)), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
    free(n);
}

/* ---- configuration date and time (0x1020) */

typedef struct dated {
    uint8_t count;
    uint32_t date, time;
} dated_t;

/* Give a device 0x1020 sub0..2 (inserted into its table in order). */
static void add_1020(station_t *s, dated_t *v)
{
    static const uint8_t k_two = 2;
    static const uint32_t k_zero = 0;
    co_od_entry_t add[3] = {
        {.index = 0x1020,
         .sub = 0,
         .type = CO_TYPE_UNSIGNED8,
         .attr = CO_OD_RO,
         .size = 1,
         .value = &v->count,
         .dflt = &k_two},
        {.index = 0x1020,
         .sub = 1,
         .type = CO_TYPE_UNSIGNED32,
         .attr = CO_OD_RW,
         .size = 4,
         .value = &v->date,
         .dflt = &k_zero},
        {.index = 0x1020,
         .sub = 2,
         .type = CO_TYPE_UNSIGNED32,
         .attr = CO_OD_RW,
         .size = 4,
         .value = &v->time,
         .dflt = &k_zero},
    };
    co_node_config_t cfg = s->node.cfg;
    uint32_t at = 0;
    while (at < cfg.od.count && s->od.entries[at].index < 0x1020) {
        at++;
    }
    memmove(&s->od.entries[at + 3], &s->od.entries[at], (cfg.od.count - at) * sizeof add[0]);
    memcpy(&s->od.entries[at], add, sizeof add);
    cfg.od.count += 3;
    CHECK_EQ(co_node_init(&s->node, &cfg), CO_OK); /* again: the table moved under it */
}

static void test_configuration_skipped_when_date_matches(void)
{
    net_t *n = ten_devices();
    static dated_t d2, d7;
    memset(&d2, 0, sizeof d2);
    memset(&d7, 0, sizeof d7);
    add_1020(&n->dev[2 - FIRST], &d2);
    add_1020(&n->dev[7 - FIRST], &d7);
    /* Both described with the same DCF and date; node 2 has it already, node 7 not. */
    n->slaves[7 - 1].dcf = n->slaves[2 - 1].dcf;
    n->slaves[7 - 1].dcf_len = n->slaves[2 - 1].dcf_len;
    for (uint8_t id = 2; id <= 7; id += 5) {
        n->slaves[id - 1].config_date = 0x1234;
        n->slaves[id - 1].config_time = 0x5678;
    }
    co_node_start(&n->master.node, 0);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        co_node_start(dev(n, id), 0);
    }
    d2.date = 0x1234; /* after start: reset communication cleared it */
    d2.time = 0x5678;
    d7.date = 0x1234;
    d7.time = 0x5679;
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 5000 * MS);
    CHECK(find(n, 2, CO_MGR_BOOTED) != NULL);
    CHECK(find(n, 7, CO_MGR_BOOTED) != NULL);
    CHECK_EQ(n->dev[2 - FIRST].od.app_u32, 0x12345678); /* untouched: skipped */
    CHECK_EQ(n->dev[7 - FIRST].od.app_u32, 0xAABBCCDD); /* time differs: downloaded */
    free(n);
}

static void test_reset_slaves_spares_keep_alive(void)
{
    net_t *n = ten_devices();
    n->mgr.cfg.reset_slaves = true;
    n->slaves[9 - 1].assignment |= CO_MGR_KEEP_ALIVE;
    co_node_start(&n->master.node, 0);
    for (uint8_t id = FIRST; id < FIRST + DEVICES; id++) {
        co_node_start(dev(n, id), 0);
    }
    /* Both stop their heartbeat; the reset brings node 10's back, node 9 is spared. */
    CHECK_EQ(co_node_set_uint(dev(n, 9), 0x1017, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(dev(n, 10), 0x1017, 0, 0), CO_ABORT_NONE);
    co_sim_run_until(&n->bus, 10 * MS);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 5000 * MS);
    CHECK_EQ(n->reset_frames, DEVICES - 1);
    const co_mgr_event_t *e = find(n, 9, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, 'K');
    }
    CHECK(find(n, 10, CO_MGR_FAILED) == NULL);
    CHECK(find(n, 10, CO_MGR_STARTED) != NULL);
    CHECK(co_manager_network_started(&n->mgr));
    free(n);
}

/* ---- LSS then manager: unconfigured devices get node-IDs, and their boot-ups boot them */

typedef struct lss_log {
    co_lss_result_t last;
    uint32_t count;
} lss_log_t;

static void on_lss(void *ctx, const co_lss_result_t *r)
{
    lss_log_t *log = ctx;
    log->last = *r;
    log->count++;
}

static void lss_wait(net_t *n)
{
    for (int i = 0; i < 1000 && co_lss_master_busy(&n->master.node); i++) {
        co_sim_run_until(&n->bus, n->bus.now_us + 10 * MS);
    }
}

static void test_lss_assigned_devices_are_booted_by_the_manager(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    station(n, &n->master, 1, 0, NULL);
    /* Four devices without node-ID; serials 0x300, 0x100, 0x400, 0x200. */
    static const uint32_t serials[4] = {0x300, 0x100, 0x400, 0x200};
    for (uint8_t i = 0; i < 4; i++) {
        uint32_t ident[4] = {0xCA0, 0x77, 0x00010000, serials[i]};
        station(n, &n->dev[i], 0xFF, 100, ident);
    }
    /* Nodes 20..23 as the plant wants them: fastscan finds the lowest address first. */
    for (uint8_t k = 0; k < 4; k++) {
        co_mgr_slave_t *s = &n->slaves[20 + k - 1];
        s->assignment = CO_MGR_SLAVE | CO_MGR_BOOT_ON_BOOTUP;
        s->vendor = 0xCA0;
        s->serial = 0x100u * (k + 1u);
        s->heartbeat_ms = 300;
    }
    co_manager_config_t mc = {
        .nmt_startup = CO_MGR_NMT_MASTER, .slaves = n->slaves, .on_event = on_event, .ctx = n};
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
    co_node_start(&n->master.node, 0);
    for (uint8_t i = 0; i < 4; i++) {
        co_node_start(&n->dev[i].node, 0);
    }
    co_lss_master_set_timeout(&n->master.node, 5);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 6000 * MS); /* four times no answer: B, network started */
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 20), CO_BOOT_NO_ANSWER);
    lss_log_t log = {0};
    for (uint8_t k = 0; k < 4; k++) {
        CHECK_EQ(co_lss_fastscan(&n->master.node, NULL, on_lss, &log), CO_OK);
        lss_wait(n);
        CHECK_EQ(log.last.status, CO_LSS_OK);
        CHECK_EQ(log.last.address.serial, 0x100u * (k + 1u));
        CHECK_EQ(co_lss_configure_node_id(&n->master.node, (uint8_t)(20 + k), on_lss, &log), CO_OK);
        lss_wait(n);
        CHECK_EQ(log.last.status, CO_LSS_OK);
        co_lss_switch_global(&n->master.node, CO_LSS_WAITING);
    }
    co_sim_run_until(&n->bus, n->bus.now_us + 3000 * MS);
    for (uint8_t i = 0; i < 4; i++) {
        uint8_t id = co_node_id(&n->dev[i].node);
        CHECK_EQ(id, 20 + serials[i] / 0x100 - 1);
        CHECK_EQ(co_manager_slave_state(&n->mgr, id), CO_MGR_RUNNING);
        CHECK_EQ(co_nmt_state(&n->dev[i].node), CO_NMT_OPERATIONAL);
    }
    free(n);
}

/* ---- the description in the master's own dictionary */

typedef struct master_objects {
    uint8_t count;
    uint32_t startup;
    uint32_t assign[2];  /* 0x1F81 sub2, sub3 */
    uint32_t vendor3;    /* 0x1F85 sub3 */
    co_od_domain_t dcf2; /* 0x1F22 sub2 */
} master_objects_t;

static void add_master_objects(station_t *s, master_objects_t *o)
{
    o->count = 127;
    co_od_entry_t add[8] = {
        {0x1F22, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &o->count, NULL, NULL, NULL},
        {0x1F22, 2, CO_TYPE_DOMAIN, CO_OD_RW, 128, &o->dcf2, NULL, NULL, NULL},
        {0x1F80, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &o->startup, NULL, NULL, NULL},
        {0x1F81, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &o->count, NULL, NULL, NULL},
        {0x1F81, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &o->assign[0], NULL, NULL, NULL},
        {0x1F81, 3, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &o->assign[1], NULL, NULL, NULL},
        {0x1F85, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &o->count, NULL, NULL, NULL},
        {0x1F85, 3, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &o->vendor3, NULL, NULL, NULL},
    };
    co_node_config_t cfg = s->node.cfg;
    uint32_t at = 0;
    while (at < cfg.od.count && s->od.entries[at].index < 0x1F22) {
        at++;
    }
    memmove(&s->od.entries[at + 8], &s->od.entries[at], (cfg.od.count - at) * sizeof add[0]);
    memcpy(&s->od.entries[at], add, sizeof add);
    cfg.od.count += 8;
    CHECK_EQ(co_node_init(&s->node, &cfg), CO_OK);
}

static void test_description_from_the_master_dictionary(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    station(n, &n->master, 1, 0, NULL);
    static master_objects_t o;
    memset(&o, 0, sizeof o);
    o.dcf2.data = n->dcf[0]; /* a DOMAIN in RAM has its buffer from the start */
    add_master_objects(&n->master, &o);
    static const uint32_t ident[4] = {0xCA0, 1, 0x10000, 0};
    station(n, &n->dev[0], 2, 100, ident);
    station(n, &n->dev[1], 3, 100, ident);
    co_node_start(&n->master.node, 0);
    /* As a DCF of the master would set them (after its reset communication). */
    o.startup = CO_MGR_NMT_MASTER;
    o.assign[0] = CO_MGR_SLAVE | CO_MGR_MANDATORY;
    o.assign[1] = CO_MGR_SLAVE;
    o.vendor3 = 0x1234;
    uint32_t off = 0;
    dcf_u32(n->dcf[0], &off, 0x2000, 0, 0xFEEDF00D);
    o.dcf2.len = off;
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 1, (2u << 16) | 250), CO_ABORT_NONE);
    uint32_t startup = 0;
    CHECK_EQ(co_manager_load_od(&n->master.node.cfg.od, n->slaves, &startup), CO_OK);
    CHECK_EQ(startup, CO_MGR_NMT_MASTER);
    CHECK_EQ(n->slaves[2 - 1].assignment, CO_MGR_SLAVE | CO_MGR_MANDATORY);
    CHECK(n->slaves[2 - 1].dcf == n->dcf[0]);
    CHECK_EQ(n->slaves[2 - 1].dcf_len, off);
    CHECK_EQ(n->slaves[2 - 1].heartbeat_ms, 250);
    CHECK_EQ(n->slaves[3 - 1].vendor, 0x1234);
    CHECK_EQ(n->slaves[4 - 1].assignment, 0);
    co_manager_config_t mc = {
        .nmt_startup = startup, .slaves = n->slaves, .on_event = on_event, .ctx = n};
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
    co_node_start(&n->dev[0].node, 0);
    co_node_start(&n->dev[1].node, 0);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 3000 * MS);
    CHECK_EQ(n->dev[0].od.app_u32, 0xFEEDF00D);
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 3), CO_BOOT_VENDOR);
    /* A dictionary without 0x1F80 describes no network. */
    example_od_t plain;
    co_od_t od = example_od_init(&plain, 0);
    CHECK_EQ(co_manager_load_od(&od, n->slaves, &startup), CO_ERR_NOT_FOUND);
    free(n);
}

/* ---- edges: arguments, each identity check, malformed DCFs, heartbeat set-up, start modes */

static void test_arguments_and_texts(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 0);
    station(n, &n->master, 1, 0, NULL);
    co_manager_config_t mc = {.nmt_startup = CO_MGR_NMT_MASTER, .slaves = n->slaves};
    CHECK_EQ(co_manager_init(NULL, &n->master.node, &mc), CO_ERR_ARG);
    CHECK_EQ(co_manager_init(&n->mgr, NULL, &mc), CO_ERR_ARG);
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, NULL), CO_ERR_ARG);
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
    /* Node-IDs outside 1..127 are never slaves. */
    CHECK_EQ(co_manager_slave_state(&n->mgr, 0), CO_MGR_UNLISTED);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 128), CO_MGR_UNLISTED);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 0), CO_BOOT_NOT_LISTED);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 200), CO_BOOT_NOT_LISTED);
    CHECK(!co_manager_network_started(&n->mgr));
    /* Every reason and event kind has its text. */
    static const struct {
        uint8_t r;
        const char *text;
    } reasons[] = {
        {CO_BOOT_NOT_LISTED, "A: not in the network list"},
        {CO_BOOT_DEVICE_TYPE, "C: device type does not match"},
        {CO_BOOT_HEARTBEAT, "E: heartbeat lost"},
        {CO_BOOT_GUARDING, "F: no answer to node guarding"},
        {CO_BOOT_HEARTBEAT_START, "K: no heartbeat when error control started"},
        {CO_BOOT_WAS_OPERATIONAL, "L: the slave was operational already"},
        {CO_BOOT_PRODUCT, "M: product code does not match"},
        {CO_BOOT_REVISION, "N: revision number does not match"},
        {CO_BOOT_SERIAL, "O: serial number does not match"},
    };
    for (uint32_t i = 0; i < sizeof reasons / sizeof reasons[0]; i++) {
        CHECK_STR(co_boot_reason_text(reasons[i].r), reasons[i].text);
    }
    CHECK_STR(co_mgr_event_name(CO_MGR_BOOTED), "booted");
    CHECK_STR(co_mgr_event_name(CO_MGR_STARTED), "started");
    CHECK_STR(co_mgr_event_name(CO_MGR_FAILED), "failed");
    CHECK_STR(co_mgr_event_name(CO_MGR_LOST), "lost");
    CHECK_STR(co_mgr_event_name(CO_MGR_NETWORK_STARTED), "network started");
    CHECK_STR(co_mgr_event_name(0), "unknown");
    CHECK_STR(co_mgr_event_name(99), "unknown");
    free(n);
}

static void test_dcf_put_arguments(void)
{
    uint8_t buf[16];
    uint8_t v[1] = {7};
    uint32_t off = 0;
    CHECK_EQ(co_dcf_put(NULL, sizeof buf, &off, 0x2000, 0, v, 1), CO_ERR_ARG);
    CHECK_EQ(co_dcf_put(buf, sizeof buf, NULL, 0x2000, 0, v, 1), CO_ERR_ARG);
    CHECK_EQ(co_dcf_put(buf, sizeof buf, &off, 0x2000, 0, NULL, 1), CO_ERR_ARG);
    CHECK_EQ(off, 0);
    /* Not even room for the count. */
    CHECK_EQ(co_dcf_put(buf, 3, &off, 0x2000, 0, v, 1), CO_ERR_FULL);
    CHECK_EQ(off, 0);
    /* The count fits, the record header does not. */
    CHECK_EQ(co_dcf_put(buf, 10, &off, 0x2000, 0, v, 1), CO_ERR_FULL);
    CHECK_EQ(co_get_u32(buf), 0);
    /* An empty record (no data) is a record. */
    off = 0;
    CHECK_EQ(co_dcf_put(buf, sizeof buf, &off, 0x2000, 1, NULL, 0), CO_OK);
    CHECK_EQ(off, 4 + 7);
    CHECK_EQ(co_get_u32(buf), 1);
    CHECK_EQ(co_dcf_check(buf, off), CO_OK);
    /* `off` past the capacity: refused, nothing written. */
    off = 20;
    CHECK_EQ(co_dcf_put(buf, sizeof buf, &off, 0x2000, 0, v, 1), CO_ERR_FULL);
    CHECK_EQ(co_get_u32(buf), 1);
    /* Checks: NULL, empty DCF, a header cut short. */
    CHECK_EQ(co_dcf_check(NULL, 4), CO_ERR_CONFIG);
    static const uint8_t empty[4] = {0};
    CHECK_EQ(co_dcf_check(empty, 4), CO_OK);
    static const uint8_t cut[8] = {1, 0, 0, 0, 0x00, 0x20, 0, 1};
    CHECK_EQ(co_dcf_check(cut, sizeof cut), CO_ERR_CONFIG);
}

/* Devices 2..1+count (identity {0xCA0, 0x100 + id, 0x10000, 5000 + id}, heartbeat 100 ms),
 * each listed as a plain slave without checks. */
static net_t *small_net(uint8_t count)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    co_sim_set_trace(&n->bus, on_trace, n);
    station(n, &n->master, 1, 0, NULL);
    for (uint8_t i = 0; i < count; i++) {
        uint8_t id = (uint8_t)(FIRST + i);
        uint32_t ident[4] = {0xCA0u, 0x100u + id, 0x00010000u, 5000u + id};
        station(n, &n->dev[i], id, 100, ident);
        n->slaves[id - 1].assignment = CO_MGR_SLAVE;
    }
    return n;
}

static void small_init(net_t *n, uint32_t startup)
{
    co_manager_config_t mc = {
        .nmt_startup = startup, .slaves = n->slaves, .on_event = on_event, .ctx = n};
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
}

static void small_start_all(net_t *n, uint8_t count)
{
    co_node_start(&n->master.node, 0);
    for (uint8_t i = 0; i < count; i++) {
        co_node_start(&n->dev[i].node, 0);
    }
    co_sim_run_until(&n->bus, 10 * MS);
}

static void check_failed(const net_t *n, uint8_t id, uint8_t reason, uint16_t index, uint8_t sub,
                         uint32_t value)
{
    const co_mgr_event_t *e = find(n, id, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, reason);
        CHECK_EQ(e->index, index);
        CHECK_EQ(e->sub, sub);
        CHECK_EQ(e->value, value);
    }
    CHECK_EQ(co_manager_slave_state(&n->mgr, id), CO_MGR_FAILED_STATE);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, id), reason);
    CHECK(find(n, id, CO_MGR_BOOTED) == NULL);
}

static void test_each_identity_check(void)
{
    net_t *n = small_net(6);
    n->slaves[2 - 1].device_type = 0x192; /* C */
    n->slaves[3 - 1].product = 0x999;     /* M */
    n->slaves[4 - 1].product = 0x104;     /* right */
    n->slaves[4 - 1].revision = 0x20000;  /* N */
    n->slaves[5 - 1].serial = 1;          /* O */
    n->slaves[6 - 1].device_type = 0x191; /* all right */
    n->slaves[6 - 1].vendor = 0xCA0;
    n->slaves[6 - 1].product = 0x106;
    n->slaves[6 - 1].revision = 0x10000;
    n->slaves[6 - 1].serial = 5006;
    n->slaves[7 - 1].assignment |= CO_MGR_MANDATORY; /* C, and the network waits */
    n->slaves[7 - 1].device_type = 0x1234;
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 6);
    CHECK_EQ(co_manager_start(&n->mgr), CO_OK);
    co_sim_run_until(&n->bus, 2000 * MS);
    check_failed(n, 2, CO_BOOT_DEVICE_TYPE, 0x1000, 0, 0x191);
    check_failed(n, 3, CO_BOOT_PRODUCT, 0x1018, 2, 0x103);
    check_failed(n, 4, CO_BOOT_REVISION, 0x1018, 3, 0x10000);
    check_failed(n, 5, CO_BOOT_SERIAL, 0x1018, 4, 5005);
    check_failed(n, 7, CO_BOOT_DEVICE_TYPE, 0x1000, 0, 0x191);
    const co_mgr_event_t *h = find(n, 7, CO_MGR_NETWORK_HALTED);
    CHECK(h != NULL);
    if (h) {
        CHECK_EQ(h->reason, CO_BOOT_DEVICE_TYPE);
    }
    CHECK(find(n, 6, CO_MGR_BOOTED) != NULL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 6), CO_MGR_CONFIGURED);
    CHECK(!co_manager_network_started(&n->mgr));
    CHECK_EQ(n->start_frames, 0);
    CHECK_EQ(co_nmt_state(&n->dev[6 - FIRST].node), CO_NMT_PRE_OPERATIONAL);
    /* Node 7 boots again (a mandatory slave the network waits for) and still fails. */
    uint32_t before = n->event_count;
    co_nmt_apply(&n->dev[7 - FIRST].node, CO_NMT_CMD_RESET_COMMUNICATION);
    co_sim_run_until(&n->bus, 3000 * MS);
    uint32_t again = 0;
    for (uint32_t i = before; i < n->event_count; i++) {
        again += n->events[i].node_id == 7 && n->events[i].kind == CO_MGR_FAILED;
    }
    CHECK_EQ(again, 1);
    /* Node 2 is not mandatory and has no bit 2: its boot-up changes nothing. */
    before = n->event_count;
    co_nmt_apply(&n->dev[2 - FIRST].node, CO_NMT_CMD_RESET_COMMUNICATION);
    co_sim_run_until(&n->bus, 4000 * MS);
    CHECK_EQ(n->event_count, before);
    free(n);
}

static void test_malformed_and_empty_dcf(void)
{
    net_t *n = small_net(3);
    /* Node 2: a DCF cut in its second record: J with abort 0, nothing downloaded. */
    uint32_t off = 0;
    dcf_u32(n->dcf[0], &off, 0x2000, 0, 0x11);
    dcf_u32(n->dcf[0], &off, 0x2000, 0, 0x22);
    n->slaves[2 - 1].dcf = n->dcf[0];
    n->slaves[2 - 1].dcf_len = off - 1;
    /* Node 3: a record without data, which the device refuses. */
    off = 0;
    CHECK_EQ(co_dcf_put(n->dcf[1], 128, &off, 0x2000, 0, NULL, 0), CO_OK);
    n->slaves[3 - 1].dcf = n->dcf[1];
    n->slaves[3 - 1].dcf_len = off;
    /* Node 4: a DCF of no records: nothing to do, booted. */
    off = 0;
    CHECK_EQ(co_dcf_put(n->dcf[2], 128, &off, 0x2000, 0, NULL, 0), CO_OK);
    n->dcf[2][0] = 0;
    n->slaves[4 - 1].dcf = n->dcf[2];
    n->slaves[4 - 1].dcf_len = 4;
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 3);
    uint32_t app2 = n->dev[0].od.app_u32;
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_CONFIG);
        CHECK_EQ(e->abort, 0);
        CHECK_EQ(e->index, 0);
        CHECK_EQ(e->sub, 0);
    }
    CHECK_EQ(n->dev[0].od.app_u32, app2);
    e = find(n, 3, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_CONFIG);
        CHECK(e->abort != 0);
        CHECK_EQ(e->index, 0x2000);
        CHECK_EQ(e->sub, 0);
    }
    CHECK(find(n, 4, CO_MGR_BOOTED) != NULL);
    CHECK(find(n, 4, CO_MGR_STARTED) != NULL);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->dev[4 - FIRST].node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_nmt_state(&n->dev[2 - FIRST].node), CO_NMT_PRE_OPERATIONAL);
    free(n);
}

static void test_no_event_callback(void)
{
    net_t *n = small_net(2);
    n->slaves[3 - 1].vendor = 0xBAD;
    co_manager_config_t mc = {.nmt_startup = CO_MGR_NMT_MASTER, .slaves = n->slaves};
    CHECK_EQ(co_manager_init(&n->mgr, &n->master.node, &mc), CO_OK);
    small_start_all(n, 2);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK_EQ(n->event_count, 0);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_RUNNING);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 3), CO_BOOT_VENDOR);
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_nmt_state(&n->dev[1].node), CO_NMT_PRE_OPERATIONAL);
    free(n);
}

static void test_no_free_heartbeat_entry(void)
{
    net_t *n = small_net(2);
    n->slaves[2 - 1].heartbeat_ms = 300;
    n->slaves[3 - 1].heartbeat_ms = 300;
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 2);
    /* Every 0x1016 entry of the master watches someone else, one of them node 3. */
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 1, hb_consumer_value(50, 1000)),
             CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 2, hb_consumer_value(51, 1000)),
             CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 3, hb_consumer_value(3, 1000)),
             CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 4, hb_consumer_value(52, 1000)),
             CO_ABORT_NONE);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_HEARTBEAT_START);
        CHECK_EQ(e->index, 0x1016);
    }
    /* Node 3: its own entry is reused with the described time. */
    CHECK(find(n, 3, CO_MGR_BOOTED) != NULL);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&n->master.node, 0x1016, 3, &v), CO_OK);
    CHECK_EQ(v, hb_consumer_value(3, 300));
    CHECK_EQ(co_node_get_uint(&n->master.node, 0x1016, 1, &v), CO_OK);
    CHECK_EQ(v, hb_consumer_value(50, 1000));
    free(n);
}

static void test_no_slave_start_and_late_slave(void)
{
    net_t *n = small_net(3);
    n->slaves[4 - 1].assignment |= CO_MGR_BOOT_ON_BOOTUP;
    /* The master itself in the list: it is no slave of its own. */
    n->slaves[1 - 1].assignment = CO_MGR_SLAVE | CO_MGR_MANDATORY;
    small_init(n, CO_MGR_NMT_MASTER | CO_MGR_NO_SLAVE_START | CO_MGR_START_ALL);
    co_node_start(&n->master.node, 0);
    co_node_start(&n->dev[0].node, 0);
    co_node_start(&n->dev[1].node, 0);
    co_sim_run_until(&n->bus, 10 * MS);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 3000 * MS);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 1), CO_MGR_UNLISTED);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK(find(n, 0, CO_MGR_NETWORK_STARTED) != NULL);
    CHECK_EQ(n->start_frames, 0); /* bit 3: the application starts the slaves */
    CHECK(find(n, 2, CO_MGR_STARTED) == NULL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_CONFIGURED);
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 4), CO_MGR_FAILED_STATE);
    /* Node 4 comes late: booted, and still not started. */
    co_node_start(&n->dev[2].node, n->bus.now_us);
    co_sim_run_until(&n->bus, 5000 * MS);
    CHECK(find(n, 4, CO_MGR_BOOTED) != NULL);
    CHECK(find(n, 4, CO_MGR_STARTED) == NULL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 4), CO_MGR_CONFIGURED);
    CHECK_EQ(co_nmt_state(&n->dev[2].node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(n->start_frames, 0);
    free(n);
}

static void test_mandatory_failure_after_start_does_not_halt(void)
{
    net_t *n = small_net(2);
    n->slaves[2 - 1].assignment |= CO_MGR_MANDATORY | CO_MGR_BOOT_ON_BOOTUP;
    n->slaves[2 - 1].vendor = 0xCA0;
    n->slaves[2 - 1].heartbeat_ms = 300;
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 2);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_OPERATIONAL);
    /* Node 2 is replaced by one of another vendor, which boots up. */
    n->dev[0].ident[0] = 0xBAD;
    co_nmt_apply(&n->dev[0].node, CO_NMT_CMD_RESET_NODE);
    co_sim_run_until(&n->bus, 4000 * MS);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_VENDOR);
        CHECK_EQ(e->value, 0xBAD);
    }
    CHECK(find(n, 2, CO_MGR_NETWORK_HALTED) == NULL); /* the network runs already */
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_PRE_OPERATIONAL);
    /* The master still watches its heartbeat: silence, then heartbeats again. A slave
     * that failed is not "lost", and its heartbeat coming back does not boot it. */
    uint32_t before = n->event_count;
    co_sim_set_bus_off(&n->dev[0].port, true);
    co_sim_run_until(&n->bus, 5000 * MS);
    co_sim_set_bus_off(&n->dev[0].port, false);
    co_sim_run_until(&n->bus, 6000 * MS);
    CHECK_EQ(n->event_count, before);
    CHECK(find(n, 2, CO_MGR_LOST) == NULL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_FAILED_STATE);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 2), CO_BOOT_VENDOR);
    free(n);
}

static void test_frames_that_are_not_boot_ups(void)
{
    net_t *n = small_net(1);
    n->slaves[2 - 1].assignment |= CO_MGR_BOOT_ON_BOOTUP;
    n->slaves[2 - 1].vendor = 0xBAD;
    small_init(n, CO_MGR_NMT_MASTER);
    co_node_start(&n->master.node, 0);
    /* Before co_manager_start a boot-up boots nobody. */
    co_frame_t boot = frm(0x702, "00");
    co_node_ingest(&n->master.node, 1 * MS, &boot);
    co_sim_run_until(&n->bus, 500 * MS);
    CHECK_EQ(n->event_count, 0);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_UNLISTED);
    co_node_start(&n->dev[0].node, n->bus.now_us);
    co_sim_run_until(&n->bus, 600 * MS);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 2), CO_BOOT_VENDOR);
    uint32_t before = n->event_count;
    /* A heartbeat (state 0x7F), a two-byte frame and a remote request are no boot-ups. */
    static const char *not_boot[] = {"7F", "00 00", "R1"};
    for (uint32_t i = 0; i < 3; i++) {
        co_frame_t f = frm(0x702, not_boot[i]);
        co_node_ingest(&n->master.node, n->bus.now_us, &f);
        co_sim_run_until(&n->bus, n->bus.now_us + 500 * MS);
    }
    CHECK_EQ(n->event_count, before);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_FAILED_STATE);
    /* The real one boots it again. */
    co_node_ingest(&n->master.node, n->bus.now_us, &boot);
    co_sim_run_until(&n->bus, n->bus.now_us + 500 * MS);
    CHECK_EQ(n->event_count, before + 1);
    CHECK_EQ(n->events[before].kind, CO_MGR_FAILED);
    free(n);
}

static void on_sdo_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    (void)len;
    *(co_abort_t *)ctx = abort;
}

static void test_sdo_channel_taken(void)
{
    net_t *n = small_net(2);
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 2);
    /* The application holds the manager's channel in a transfer when the boot begins. */
    co_abort_t done = 1;
    CHECK_EQ(co_sdo_client_setup(&n->master.node, 0, 3), CO_OK);
    CHECK_EQ(co_sdo_write_value(&n->master.node, 0, 0x2000, 0, 0x77, 4, on_sdo_done, &done), CO_OK);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK_EQ(done, CO_ABORT_NONE);
    CHECK_EQ(n->dev[1].od.app_u32, 0x77);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_NO_ANSWER);
        CHECK_EQ(e->abort, CO_ABORT_GENERAL);
    }
    free(n);
}

/* ---- co_manager_load_od: the entries it takes, and the ones it leaves */

static void test_load_od_edges(void)
{
    static uint32_t startup = CO_MGR_NMT_MASTER | CO_MGR_START_ALL;
    static uint8_t count = 200; /* more than 127 entries claimed */
    static uint32_t dcf_u32_value = 0x12345678;
    static uint8_t dcf_bytes[4 + 7 + 1] = {1, 0, 0, 0, 0x00, 0x20, 0, 1, 0, 0, 0, 9};
    static co_od_domain_t empty_domain = {.data = dcf_bytes, .len = 0};
    static co_od_domain_t full_domain = {.data = dcf_bytes, .len = sizeof dcf_bytes};
    static uint32_t hb[6] = {
        (2u << 16) | 0,     /* names node 2 but time 0: not watched */
        (0u << 16) | 500,   /* node 0 */
        (200u << 16) | 500, /* no node-ID */
        (5u << 16) | 700,   /* node 5, 700 ms */
        (6u << 16) | 800,   /* node 6 */
        (7u << 16) | 900,   /* sub 127 */
    };
    static uint32_t assign[5] = {CO_MGR_SLAVE, CO_MGR_SLAVE, CO_MGR_SLAVE, CO_MGR_SLAVE,
                                 CO_MGR_SLAVE | CO_MGR_MANDATORY};
    co_od_entry_t e[] = {
        {0x1016, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &count, NULL, NULL, NULL},
        {0x1016, 1, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &hb[0], NULL, NULL, NULL},
        {0x1016, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &hb[1], NULL, NULL, NULL},
        {0x1016, 3, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &hb[2], NULL, NULL, NULL},
        {0x1016, 4, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &hb[3], NULL, NULL, NULL},
        {0x1016, 5, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &hb[4], NULL, NULL, NULL},
        {0x1016, 127, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &hb[5], NULL, NULL, NULL},
        /* 0x1F22: sub2 not a DOMAIN, sub3 a DOMAIN without storage, sub4 an empty one,
         * sub5 a real one. */
        {0x1F22, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &dcf_u32_value, NULL, NULL, NULL},
        {0x1F22, 3, CO_TYPE_DOMAIN, CO_OD_RW, 64, NULL, NULL, NULL, NULL},
        {0x1F22, 4, CO_TYPE_DOMAIN, CO_OD_RW, 64, &empty_domain, NULL, NULL, NULL},
        {0x1F22, 5, CO_TYPE_DOMAIN, CO_OD_RW, 64, &full_domain, NULL, NULL, NULL},
        {0x1F80, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &startup, NULL, NULL, NULL},
        {0x1F81, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &assign[0], NULL, NULL, NULL},
        {0x1F81, 3, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &assign[1], NULL, NULL, NULL},
        {0x1F81, 4, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &assign[2], NULL, NULL, NULL},
        {0x1F81, 5, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &assign[3], NULL, NULL, NULL},
        {0x1F81, 6, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &assign[4], NULL, NULL, NULL},
    };
    co_od_t od = {.entries = e, .count = sizeof e / sizeof e[0]};
    co_mgr_slave_t *slaves = calloc(127, sizeof *slaves);
    uint32_t got = 0;
    CHECK_EQ(co_manager_load_od(NULL, slaves, &got), CO_ERR_ARG);
    CHECK_EQ(co_manager_load_od(&od, NULL, &got), CO_ERR_ARG);
    CHECK_EQ(co_manager_load_od(&od, slaves, NULL), CO_ERR_ARG);
    CHECK_EQ(got, 0);
    CHECK_EQ(co_manager_load_od(&od, slaves, &got), CO_OK);
    CHECK_EQ(got, startup);
    for (uint8_t n = 2; n <= 4; n++) {
        CHECK(slaves[n - 1].dcf == NULL);
        CHECK_EQ(slaves[n - 1].dcf_len, 0);
    }
    CHECK(slaves[5 - 1].dcf == dcf_bytes);
    CHECK_EQ(slaves[5 - 1].dcf_len, sizeof dcf_bytes);
    CHECK_EQ(co_dcf_check(slaves[5 - 1].dcf, slaves[5 - 1].dcf_len), CO_OK);
    CHECK_EQ(slaves[2 - 1].heartbeat_ms, 0);
    CHECK_EQ(slaves[5 - 1].heartbeat_ms, 700);
    CHECK_EQ(slaves[6 - 1].heartbeat_ms, 800);
    CHECK_EQ(slaves[7 - 1].heartbeat_ms, 900); /* sub 127, read under a count of 200 */
    CHECK_EQ(slaves[6 - 1].assignment, CO_MGR_SLAVE | CO_MGR_MANDATORY);
    CHECK_EQ(slaves[7 - 1].assignment, 0);
    for (uint8_t n = 8; n <= 127; n++) {
        CHECK_EQ(slaves[n - 1].heartbeat_ms, 0);
    }
    /* A small count limits what is read. */
    count = 4;
    CHECK_EQ(co_manager_load_od(&od, slaves, &got), CO_OK);
    CHECK_EQ(slaves[5 - 1].heartbeat_ms, 700);
    CHECK_EQ(slaves[6 - 1].heartbeat_ms, 0);
    CHECK_EQ(slaves[7 - 1].heartbeat_ms, 0);
    free(slaves);
}

static void set_attr(station_t *s, uint16_t index, uint8_t sub, uint8_t attr)
{
    for (uint32_t e = 0; e < s->node.cfg.od.count; e++) {
        if (s->od.entries[e].index == index && s->od.entries[e].sub == sub) {
            s->od.entries[e].attr = attr;
        }
    }
}

static void test_configuration_date_cannot_be_compared(void)
{
    net_t *n = small_net(4);
    static dated_t d3, d4;
    memset(&d3, 0, sizeof d3);
    memset(&d4, 0, sizeof d4);
    add_1020(&n->dev[3 - FIRST], &d3);
    add_1020(&n->dev[4 - FIRST], &d4);
    set_attr(&n->dev[4 - FIRST], 0x1020, 2, CO_OD_WO); /* its time cannot be read */
    /* Node 5 cannot tell its product code. */
    set_attr(&n->dev[5 - FIRST], 0x1018, 2, CO_OD_WO);
    n->slaves[5 - 1].product = 0x105;
    uint32_t off = 0;
    dcf_u32(n->dcf[0], &off, 0x2000, 0, 0xC0FFEE);
    for (uint8_t id = 2; id <= 4; id++) {
        n->slaves[id - 1].dcf = n->dcf[0];
        n->slaves[id - 1].dcf_len = off;
        n->slaves[id - 1].config_date = 0x1234;
        n->slaves[id - 1].config_time = 0x5678;
    }
    n->slaves[4 - 1].config_date = 0; /* a time only */
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 4);
    d3.date = 0x1233; /* another date, the same time */
    d3.time = 0x5678;
    d4.date = 0;
    d4.time = 0x5678;
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 3000 * MS);
    /* Node 2 has no 0x1020, node 3 another date, node 4 no readable time: all three get
     * the configuration. */
    for (uint8_t id = 2; id <= 4; id++) {
        CHECK(find(n, id, CO_MGR_BOOTED) != NULL);
        CHECK_EQ(n->dev[id - FIRST].od.app_u32, 0xC0FFEE);
    }
    /* Node 5: the refused read is a failed check, with the abort code. */
    const co_mgr_event_t *e = find(n, 5, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_PRODUCT);
        CHECK_EQ(e->abort, CO_ABORT_WRITE_ONLY);
        CHECK_EQ(e->index, 0x1018);
        CHECK_EQ(e->sub, 2);
    }
    free(n);
}

static void test_heartbeat_entry_without_time_is_free(void)
{
    net_t *n = small_net(2);
    n->slaves[2 - 1].heartbeat_ms = 250;
    n->slaves[3 - 1].assignment = 0; /* node 3 is on the bus, not in the list */
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 2);
    /* Entry 1 watches node 50, entry 2 names node 51 with time 0 (not watching). */
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 1, hb_consumer_value(50, 1000)),
             CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 2, hb_consumer_value(51, 0)), CO_ABORT_NONE);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK(find(n, 2, CO_MGR_BOOTED) != NULL);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&n->master.node, 0x1016, 2, &v), CO_OK);
    CHECK_EQ(v, hb_consumer_value(2, 250));
    CHECK_EQ(co_node_get_uint(&n->master.node, 0x1016, 1, &v), CO_OK);
    CHECK_EQ(v, hb_consumer_value(50, 1000));
    /* The master watches unlisted node 3 too: its boot-up and heartbeat are none of the
     * manager's business. */
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 3, hb_consumer_value(3, 1000)),
             CO_ABORT_NONE);
    uint32_t before = n->event_count;
    co_nmt_apply(&n->dev[3 - FIRST].node, CO_NMT_CMD_RESET_COMMUNICATION);
    co_sim_run_until(&n->bus, 3000 * MS);
    CHECK_EQ(n->event_count, before);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 3), CO_MGR_UNLISTED);
    CHECK_EQ(co_nmt_state(&n->dev[3 - FIRST].node), CO_NMT_PRE_OPERATIONAL);
    free(n);
}

/* ---- the manager's own failures: no SDO, no heartbeat entry, and events it ignores */

static void test_stopped_master_fails_each_boot(void)
{
    net_t *n = small_net(2);
    small_init(n, CO_MGR_NMT_MASTER | CO_MGR_NO_SELF_START);
    small_start_all(n, 2);
    /* A stopped master may not use SDO: each boot fails at its first read, unsent. */
    CHECK_EQ(co_nmt_apply(&n->master.node, CO_NMT_CMD_STOP), CO_OK);
    CHECK_EQ(co_manager_start(&n->mgr), CO_OK);
    co_sim_run_until(&n->bus, 1000 * MS);
    for (uint8_t id = 2; id <= 3; id++) {
        const co_mgr_event_t *e = find(n, id, CO_MGR_FAILED);
        CHECK(e != NULL);
        if (e) {
            CHECK_EQ(e->reason, CO_BOOT_NO_ANSWER);
            CHECK_EQ(e->abort, CO_ABORT_GENERAL);
            CHECK_EQ(e->index, 0x1000);
            CHECK_EQ(e->sub, 0);
        }
    }
    CHECK_EQ(n->sdo_requests, 0);
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_STOPPED);
    free(n);
}

static void test_master_without_heartbeat_consumers(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    co_sim_set_trace(&n->bus, on_trace, n);
    station_without(n, &n->master, 1, 0, NULL, 0x1016);
    uint32_t ident[4] = {0xCA0u, 0x102u, 0x00010000u, 5002u};
    station(n, &n->dev[0], 2, 100, ident);
    n->slaves[2 - 1].assignment = CO_MGR_SLAVE;
    n->slaves[2 - 1].heartbeat_ms = 300;
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 1);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 1000 * MS);
    /* Checks passed, but there is no 0x1016 to watch its heartbeat with. */
    CHECK(n->sdo_requests > 0);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_HEARTBEAT_START);
        CHECK_EQ(e->index, 0x1016);
        CHECK_EQ(e->sub, 0);
    }
    CHECK(find(n, 2, CO_MGR_BOOTED) == NULL);
    free(n);
}

static void test_guarded_slave_gets_no_heartbeat_watch(void)
{
    net_t *n = small_net(1);
    n->slaves[2 - 1].heartbeat_ms = 300;
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 1);
    /* The application guards node 2 already: one error control per node, so the
     * manager's heartbeat entry for it is refused. */
    CHECK_EQ(co_guard_watch(&n->master.node, 2, 1000, 3), CO_OK);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 500 * MS);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_HEARTBEAT_START);
        CHECK_EQ(e->index, 0x1016);
    }
    for (uint8_t sub = 1; sub <= EXAMPLE_HB_CONSUMERS; sub++) {
        uint64_t v = 1;
        CHECK_EQ(co_node_get_uint(&n->master.node, 0x1016, sub, &v), CO_OK);
        CHECK_EQ(v, 0);
    }
    free(n);
}

static void test_nothing_happens_before_the_manager_starts(void)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    co_sim_set_trace(&n->bus, on_trace, n);
    station(n, &n->master, 1, 50, NULL); /* the master's heartbeat keeps it polled */
    uint32_t ident[4] = {0xCA0u, 0x102u, 0x00010000u, 5002u};
    station(n, &n->dev[0], 2, 100, ident);
    n->slaves[2 - 1].assignment = CO_MGR_SLAVE | CO_MGR_BOOT_ON_BOOTUP | CO_MGR_MANDATORY;
    small_init(n, CO_MGR_NMT_MASTER);
    co_node_start(&n->master.node, 0);
    /* The master watches node 2's heartbeat: its boot-up and first heartbeat are events. */
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 1, hb_consumer_value(2, 500)),
             CO_ABORT_NONE);
    co_node_start(&n->dev[0].node, 10 * MS);
    co_sim_run_until(&n->bus, 1000 * MS);
    CHECK_EQ(n->event_count, 0);
    CHECK_EQ(n->sdo_requests, 0);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_UNLISTED);
    CHECK(!co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_hb_remote_state(&n->master.node, 2), CO_NMT_PRE_OPERATIONAL);
    /* Started, it boots the slave and the network. */
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK(find(n, 2, CO_MGR_BOOTED) != NULL);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_OPERATIONAL);
    free(n);
}

static void test_mandatory_boot_up_after_network_start_changes_nothing(void)
{
    net_t *n = small_net(1);
    n->slaves[2 - 1].assignment |= CO_MGR_MANDATORY; /* without bit 2 */
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 1);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 1000 * MS);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_OPERATIONAL);
    /* The network runs: a mandatory slave's boot-up no longer boots it. */
    uint32_t before = n->event_count;
    uint32_t requests = n->sdo_requests;
    co_nmt_apply(&n->dev[0].node, CO_NMT_CMD_RESET_COMMUNICATION);
    co_sim_run_until(&n->bus, 2000 * MS);
    CHECK_EQ(n->event_count, before);
    CHECK_EQ(n->sdo_requests, requests);
    CHECK_EQ(co_nmt_state(&n->dev[0].node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_RUNNING);
    free(n);
}

static void test_configured_slave_that_falls_silent_is_lost(void)
{
    net_t *n = small_net(1);
    n->slaves[2 - 1].heartbeat_ms = 300;
    small_init(n, CO_MGR_NMT_MASTER | CO_MGR_NO_SLAVE_START);
    small_start_all(n, 1);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 1000 * MS);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_CONFIGURED);
    /* Booted, never started (bit 3): its silence is a loss all the same. */
    co_sim_set_bus_off(&n->dev[0].port, true);
    co_sim_run_until(&n->bus, 2000 * MS);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_LOST);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->reason, CO_BOOT_HEARTBEAT);
    }
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_MISSING);
    CHECK_EQ(co_manager_slave_reason(&n->mgr, 2), CO_BOOT_HEARTBEAT);
    free(n);
}

/* The configuration turns the slave's heartbeat on while the master watches it already:
 * heartbeats that arrive during the download do not end the boot early. */
static void test_heartbeat_during_configuration_does_not_end_the_boot(void)
{
    net_t *n = small_net(1);
    co_node_set_uint(&n->dev[0].node, 0x1017, 0, 0); /* silent until configured */
    uint32_t off = 0;
    dcf_u16(n->dcf[0], &off, 0x1017, 0, 1);
    for (uint32_t v = 1; v <= 8; v++) {
        dcf_u32(n->dcf[0], &off, 0x2000, 0, v);
    }
    n->slaves[2 - 1].dcf = n->dcf[0];
    n->slaves[2 - 1].dcf_len = off;
    n->slaves[2 - 1].heartbeat_ms = 50;
    small_init(n, CO_MGR_NMT_MASTER | CO_MGR_NO_SLAVE_START);
    co_node_start(&n->master.node, 0);
    co_node_start(&n->dev[0].node, 0);
    co_node_set_uint(&n->dev[0].node, 0x1017, 0, 0);
    CHECK_EQ(co_node_set_uint(&n->master.node, 0x1016, 1, hb_consumer_value(2, 1000)),
             CO_ABORT_NONE);
    co_sim_run_until(&n->bus, 10 * MS);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 1000 * MS);
    const co_mgr_event_t *e = find(n, 2, CO_MGR_BOOTED);
    CHECK(e != NULL);
    CHECK_EQ(n->dev[0].od.app_u32, 8); /* the whole configuration */
    uint32_t booted = 0;
    for (uint32_t i = 0; i < n->event_count; i++) {
        booted += n->events[i].node_id == 2 && n->events[i].kind == CO_MGR_BOOTED;
    }
    CHECK_EQ(booted, 1);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&n->master.node, 0x1016, 1, &v), CO_OK);
    CHECK_EQ(v, hb_consumer_value(2, 50));
    free(n);
}

/* ---- late slaves, late answers, the master's own reset */

/* A tap that plays a slow device's late answer: when the slave answers the vendor-ID
 * read, the answer to a device-type read it received before its boot-up follows. */
typedef struct late_tap {
    co_sim_port_t port;
    uint32_t sent;
} late_tap_t;

static void late_tap_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    (void)now_us;
    late_tap_t *tap = ctx;
    if (tap->sent == 0 && frame->id == 0x582 && frame->data[0] == 0x43 && frame->data[1] == 0x18 &&
        frame->data[2] == 0x10 && frame->data[3] == 0x01) {
        co_frame_t stale = frm(0x582, "43 00 10 00 91 01 00 00");
        CHECK_EQ(co_sim_send(&tap->port, &stale), CO_OK);
        tap->sent++;
    }
}

/* A slave missing at boot (B) that boots later and then, being slow, also answers the
 * request it got before its boot-up: booted all the same, optional or mandatory, started
 * with the running network or starting the network (each and all). */
static void test_late_slave_with_a_late_answer(void)
{
    static const uint32_t startups[] = {0, CO_MGR_START_ALL};
    for (uint32_t mandatory = 0; mandatory <= 1; mandatory++) {
        for (uint32_t k = 0; k < 2; k++) {
            net_t *n = small_net(1);
            static late_tap_t tap;
            memset(&tap, 0, sizeof tap);
            CHECK_EQ(co_sim_port_attach_raw(&n->bus, &tap.port, late_tap_rx, &tap), CO_OK);
            co_mgr_slave_t *s = &n->slaves[2 - 1];
            s->assignment |= CO_MGR_BOOT_ON_BOOTUP | (mandatory ? CO_MGR_MANDATORY : 0u);
            s->device_type = 0x191;
            s->vendor = 0xCA0;
            s->product = 0x102;
            small_init(n, CO_MGR_NMT_MASTER | startups[k]);
            co_node_start(&n->master.node, 0);
            co_sim_run_until(&n->bus, 10 * MS);
            co_manager_start(&n->mgr);
            co_sim_run_until(&n->bus, 2000 * MS);
            const co_mgr_event_t *e = find(n, 2, CO_MGR_FAILED);
            CHECK(e != NULL && e->reason == 'B');
            CHECK_EQ(co_manager_network_started(&n->mgr), !mandatory);
            uint32_t before = n->event_count;
            co_node_start(dev(n, 2), n->bus.now_us);
            co_sim_run_until(&n->bus, 3000 * MS);
            CHECK_EQ(tap.sent, 1);
            uint32_t failed = 0;
            for (uint32_t i = before; i < n->event_count; i++) {
                failed += n->events[i].kind == CO_MGR_FAILED;
            }
            CHECK_EQ(failed, 0);
            CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_RUNNING);
            CHECK_EQ(co_nmt_state(dev(n, 2)), CO_NMT_OPERATIONAL);
            CHECK(co_manager_network_started(&n->mgr));
            CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
            free(n);
        }
    }
}

/* The master's own reset communication (an NMT reset from anyone), with the network
 * running or in the middle of a slave's boot: no failure of a slave; the manager starts
 * over, as CiA 302-2 has the master's start-up follow its reset, and boots and watches
 * every slave again. */
static void test_master_reset_starts_the_boot_over(void)
{
    net_t *n = small_net(2);
    for (uint8_t id = 2; id <= 3; id++) {
        n->slaves[id - 1].assignment |= CO_MGR_MANDATORY;
        n->slaves[id - 1].vendor = 0xCA0;
        n->slaves[id - 1].heartbeat_ms = 300;
    }
    small_init(n, CO_MGR_NMT_MASTER);
    small_start_all(n, 2);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 1000 * MS);
    CHECK(co_manager_network_started(&n->mgr));
    /* an NMT reset communication to all nodes: the master is reset with its slaves */
    co_sim_run_until(&n->bus, 1100 * MS);
    co_frame_t reset_all = frm(0x000, "82 00");
    for (uint8_t i = 0; i < 2; i++) {
        co_node_ingest(&n->dev[i].node, n->bus.now_us, &reset_all);
    }
    co_node_ingest(&n->master.node, n->bus.now_us, &reset_all);
    uint32_t before = n->event_count;
    co_sim_run_until(&n->bus, 3000 * MS);
    uint32_t failed = 0, booted = 0;
    for (uint32_t i = before; i < n->event_count; i++) {
        failed += n->events[i].kind == CO_MGR_FAILED;
        booted += n->events[i].kind == CO_MGR_BOOTED;
    }
    CHECK_EQ(failed, 0);
    CHECK_EQ(booted, 2);
    CHECK(co_manager_network_started(&n->mgr));
    CHECK_EQ(co_nmt_state(&n->master.node), CO_NMT_OPERATIONAL);
    CHECK_EQ(co_nmt_state(dev(n, 2)), CO_NMT_OPERATIONAL);
    /* watched again: node 3 falls silent and is reported lost */
    co_sim_set_bus_off(&n->dev[1].port, true);
    co_sim_run_until(&n->bus, 4000 * MS);
    CHECK(find(n, 3, CO_MGR_LOST) != NULL);

    /* a reset while a slave's boot step waits for its answer */
    net_t *m = small_net(1);
    m->slaves[2 - 1].vendor = 0xCA0;
    small_init(m, CO_MGR_NMT_MASTER);
    co_node_start(&m->master.node, 0);
    co_sim_run_until(&m->bus, 10 * MS);
    co_manager_start(&m->mgr);
    co_sim_run_until(&m->bus, 500 * MS); /* node 2 is off: the device-type read waits */
    CHECK_EQ(co_manager_slave_state(&m->mgr, 2), CO_MGR_BOOTING);
    co_node_start(&m->dev[0].node, m->bus.now_us);
    co_frame_t reset_master = frm(0x000, "82 01");
    co_node_ingest(&m->master.node, m->bus.now_us, &reset_master);
    co_sim_run_until(&m->bus, 1500 * MS);
    for (uint32_t i = 0; i < m->event_count; i++) {
        CHECK(m->events[i].kind != CO_MGR_FAILED);
    }
    CHECK_EQ(co_manager_slave_state(&m->mgr, 2), CO_MGR_RUNNING);

    /* a reset in the middle of the configuration download */
    net_t *k = small_net(1);
    uint32_t off = 0;
    for (uint32_t v = 1; v <= 8; v++) {
        dcf_u32(k->dcf[0], &off, 0x2000, 0, v);
    }
    k->slaves[2 - 1].dcf = k->dcf[0];
    k->slaves[2 - 1].dcf_len = off;
    small_init(k, CO_MGR_NMT_MASTER);
    small_start_all(k, 1);
    co_manager_start(&k->mgr);
    while (k->sdo_requests < 4) { /* the device-type read, then into the download */
        co_sim_run_until(&k->bus, k->bus.now_us + 100);
    }
    co_node_ingest(&k->master.node, k->bus.now_us, &reset_master);
    co_sim_run_until(&k->bus, k->bus.now_us + 1000 * MS);
    for (uint32_t i = 0; i < k->event_count; i++) {
        CHECK(k->events[i].kind != CO_MGR_FAILED); /* of no slave, node 0 neither */
    }
    CHECK_EQ(co_manager_slave_state(&k->mgr, 2), CO_MGR_RUNNING);
    CHECK_EQ(k->dev[0].od.app_u32, 8);
    free(k);
    free(m);
    free(n);
}

/* The deadline poll returns after a boot step ended by the SDO time-out lies ahead: the
 * manager's follow-up runs in the same poll. */
static void test_poll_after_sdo_timeout_returns_a_future_deadline(void)
{
    net_t *n = small_net(2);
    small_init(n, CO_MGR_NMT_MASTER);
    co_node_start(&n->master.node, 0);
    co_node_start(&n->dev[1].node, 0); /* node 3 is there, node 2 is not */
    co_sim_run_until(&n->bus, 10 * MS);
    co_manager_start(&n->mgr);
    co_sim_run_until(&n->bus, 20 * MS);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_BOOTING);
    uint64_t now = 20 * MS;
    for (uint32_t polls = 0; polls < 100 && co_manager_slave_state(&n->mgr, 2) == CO_MGR_BOOTING;
         polls++) {
        uint64_t next = co_node_poll(&n->master.node, now);
        CHECK(next > now);
        now = next;
    }
    CHECK_EQ(co_manager_slave_state(&n->mgr, 2), CO_MGR_FAILED_STATE);
    CHECK_EQ(co_manager_slave_state(&n->mgr, 3), CO_MGR_BOOTING);
    free(n);
}

int main(void)
{
    RUN(test_dcf_put_and_check);
    RUN(test_late_slave_with_a_late_answer);
    RUN(test_master_reset_starts_the_boot_over);
    RUN(test_poll_after_sdo_timeout_returns_a_future_deadline);
    RUN(test_reason_texts);
    RUN(test_init_arguments);
    RUN(test_description_from_the_master_dictionary);
    RUN(test_ten_devices_boot_from_one_description);
    RUN(test_missing_mandatory_keeps_the_network_down);
    RUN(test_start_all_when_everyone_booted);
    RUN(test_reset_slaves_spares_keep_alive);
    RUN(test_lss_assigned_devices_are_booted_by_the_manager);
    RUN(test_configuration_skipped_when_date_matches);
    RUN(test_start_all_with_a_failure_starts_one_by_one);
    RUN(test_arguments_and_texts);
    RUN(test_dcf_put_arguments);
    RUN(test_each_identity_check);
    RUN(test_malformed_and_empty_dcf);
    RUN(test_no_event_callback);
    RUN(test_no_free_heartbeat_entry);
    RUN(test_no_slave_start_and_late_slave);
    RUN(test_mandatory_failure_after_start_does_not_halt);
    RUN(test_frames_that_are_not_boot_ups);
    RUN(test_sdo_channel_taken);
    RUN(test_load_od_edges);
    RUN(test_configuration_date_cannot_be_compared);
    RUN(test_heartbeat_entry_without_time_is_free);
    RUN(test_stopped_master_fails_each_boot);
    RUN(test_master_without_heartbeat_consumers);
    RUN(test_guarded_slave_gets_no_heartbeat_watch);
    RUN(test_nothing_happens_before_the_manager_starts);
    RUN(test_mandatory_boot_up_after_network_start_changes_nothing);
    RUN(test_configured_slave_that_falls_silent_is_lost);
    RUN(test_heartbeat_during_configuration_does_not_end_the_boot);
    return check_summary();
}
