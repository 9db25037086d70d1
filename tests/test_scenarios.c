/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_scenarios.c -- a master and devices on the simulated bus walking through the
 * procedures of the seeds: power-on and boot-up, NMT commands to one node and to all,
 * resets, heartbeat loss, a node that never boots.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define MAX_DEVICES 3
#define TRACE_MAX 4096

typedef struct station {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
} station_t;

typedef struct event_at {
    co_ec_event_t ev;
    uint64_t t_us;
} event_at_t;

typedef struct network {
    co_sim_bus_t bus;
    station_t master;
    station_t devices[MAX_DEVICES];
    char trace[TRACE_MAX][48];
    uint32_t trace_count;
    event_at_t events[128];
    uint32_t event_count;
} network_t;

static void on_trace(void *ctx, const char *line)
{
    network_t *net = ctx;
    if (net->trace_count < TRACE_MAX) {
        snprintf(net->trace[net->trace_count++], sizeof net->trace[0], "%s", line);
    }
}

static void on_master_event(void *user, const co_ec_event_t *ev)
{
    network_t *net = user;
    if (net->event_count < 128) {
        net->events[net->event_count++] = (event_at_t){.ev = *ev, .t_us = net->bus.now_us};
    }
}

static void attach(network_t *net, station_t *s, uint8_t id, uint16_t hb_ms, bool master)
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_init(&s->od, hb_ms)};
    CHECK_EQ(co_sim_port_attach(&net->bus, &s->port), CO_OK);
    cfg.driver = co_sim_port_driver(&s->port);
    if (master) {
        cfg.user = net;
        cfg.on_errctl = on_master_event;
        cfg.boot_time_ms = 2000;
    }
    CHECK_EQ(co_node_init(&s->node, &cfg), CO_OK);
    co_sim_port_bind(&s->port, &s->node);
}

/* Master 1 consuming devices 2..4 (250 ms), devices beating every 100 ms. All power on at 0. */
static network_t *network_up(uint32_t bitrate)
{
    network_t *net = calloc(1, sizeof *net);
    co_sim_bus_init(&net->bus, bitrate);
    co_sim_set_trace(&net->bus, on_trace, net);
    attach(net, &net->master, 1, 0, true);
    for (uint8_t i = 0; i < MAX_DEVICES; i++) {
        attach(net, &net->devices[i], (uint8_t)(2 + i), 100, false);
    }
    CHECK_EQ(co_node_start(&net->master.node, 0), CO_OK);
    for (uint8_t i = 0; i < MAX_DEVICES; i++) {
        uint8_t v[4];
        co_put_u32(v, hb_consumer_value((uint8_t)(2 + i), 250));
        CHECK_EQ(co_node_write_net(&net->master.node, 0x1016, (uint8_t)(i + 1), v, 4),
                 CO_ABORT_NONE);
    }
    for (uint8_t i = 0; i < MAX_DEVICES; i++) {
        CHECK_EQ(co_node_start(&net->devices[i].node, 0), CO_OK);
    }
    return net;
}

/* Count trace lines whose frame part ("701#05") equals `frame`, from line `from` on. */
static uint32_t count_frames(const network_t *net, uint32_t from, const char *frame)
{
    uint32_t n = 0;
    for (uint32_t i = from; i < net->trace_count; i++) {
        const char *p = strstr(net->trace[i], "sim0 ");
        n += p && strcmp(p + 5, frame) == 0;
    }
    return n;
}

static const event_at_t *find_event(const network_t *net, co_ec_event_kind_t kind, uint8_t id)
{
    for (uint32_t i = 0; i < net->event_count; i++) {
        if (net->events[i].ev.kind == kind && net->events[i].ev.node_id == id) {
            return &net->events[i];
        }
    }
    return NULL;
}

static void test_power_on_three_bootups_once_each(void)
{
    network_t *net = network_up(0);
    co_sim_run_until(&net->bus, 1000 * MS);
    CHECK_EQ(count_frames(net, 0, "701#00"), 1);
    CHECK_EQ(count_frames(net, 0, "702#00"), 1);
    CHECK_EQ(count_frames(net, 0, "703#00"), 1);
    CHECK_EQ(count_frames(net, 0, "704#00"), 1);
    /* The first lines are the boot-ups at t = 0, byte-exact in candump format. */
    CHECK_STR(net->trace[0], "(0.000000) sim0 701#00");
    CHECK_STR(net->trace[1], "(0.000000) sim0 702#00");
    /* Then heartbeats every 100 ms in pre-operational: 10 each in the first second. */
    CHECK_EQ(count_frames(net, 0, "702#7F"), 10);
    CHECK_EQ(count_frames(net, 0, "704#7F"), 10);
    CHECK(find_event(net, CO_EC_BOOT, 2) != NULL);
    CHECK(find_event(net, CO_EC_STARTED, 4) != NULL);
    CHECK_EQ(co_hb_remote_state(&net->master.node, 3), CO_NMT_PRE_OPERATIONAL);
    free(net);
}

static void test_nmt_to_one_and_to_all_shows_in_heartbeats(void)
{
    network_t *net = network_up(0);
    co_sim_run_until(&net->bus, 150 * MS);
    co_nmt_send(&net->master.node, CO_NMT_CMD_START, 3);
    uint32_t from = net->trace_count;
    co_sim_run_until(&net->bus, 350 * MS);
    CHECK_EQ(count_frames(net, from, "703#05"), 2);
    CHECK_EQ(count_frames(net, from, "702#7F"), 2);
    CHECK_EQ(count_frames(net, from, "704#7F"), 2);

    co_nmt_send(&net->master.node, CO_NMT_CMD_START, 0);
    from = net->trace_count;
    co_sim_run_until(&net->bus, 550 * MS);
    CHECK_EQ(count_frames(net, from, "702#05"), 2);
    CHECK_EQ(count_frames(net, from, "704#05"), 2);

    co_nmt_send(&net->master.node, CO_NMT_CMD_STOP, 4);
    from = net->trace_count;
    co_sim_run_until(&net->bus, 750 * MS);
    CHECK_EQ(count_frames(net, from, "704#04"), 2);
    CHECK_EQ(count_frames(net, from, "702#05"), 2);

    co_nmt_send(&net->master.node, CO_NMT_CMD_ENTER_PRE_OPERATIONAL, 0);
    from = net->trace_count;
    co_sim_run_until(&net->bus, 950 * MS);
    CHECK_EQ(count_frames(net, from, "702#7F"), 2);
    CHECK_EQ(count_frames(net, from, "703#7F"), 2);
    CHECK_EQ(count_frames(net, from, "704#7F"), 2);
    /* The commands themselves, byte-exact. */
    CHECK_EQ(count_frames(net, 0, "000#0103"), 1);
    CHECK_EQ(count_frames(net, 0, "000#0100"), 1);
    CHECK_EQ(count_frames(net, 0, "000#0204"), 1);
    CHECK_EQ(count_frames(net, 0, "000#8000"), 1);
    /* The master saw each change. */
    const event_at_t *e = find_event(net, CO_EC_STATE_CHANGED, 4);
    CHECK(e != NULL && e->ev.state == CO_NMT_OPERATIONAL);
    free(net);
}

static void test_reset_node_and_reset_communication_over_the_bus(void)
{
    network_t *net = network_up(0);
    station_t *dev = &net->devices[0]; /* node 2 */
    co_sim_run_until(&net->bus, 50 * MS);
    co_node_set_uint(&dev->node, 0x2000, 0, 0xABCD);
    co_node_set_uint(&dev->node, 0x1017, 0, 40);
    co_nmt_send(&net->master.node, CO_NMT_CMD_START, 2);
    co_sim_run_until(&net->bus, 200 * MS);

    /* Reset communication: 0x1017 back to 100 ms, the application value kept. */
    co_nmt_send(&net->master.node, CO_NMT_CMD_RESET_COMMUNICATION, 2);
    uint32_t from = net->trace_count;
    co_sim_run_until(&net->bus, 400 * MS);
    CHECK_EQ(count_frames(net, from, "702#00"), 1);
    CHECK_EQ(dev->od.hb_period_ms, 100);
    CHECK_EQ(dev->od.app_u32, 0xABCD);
    CHECK_EQ(count_frames(net, from, "702#7F"), 2);
    const event_at_t *e = find_event(net, CO_EC_REMOTE_RESET, 2);
    CHECK(e != NULL && e->ev.previous == CO_NMT_OPERATIONAL);

    /* Reset node: the application value back to its default too. */
    co_nmt_send(&net->master.node, CO_NMT_CMD_RESET_NODE, 2);
    from = net->trace_count;
    co_sim_run_until(&net->bus, 600 * MS);
    CHECK_EQ(count_frames(net, from, "702#00"), 1);
    CHECK_EQ(dev->od.app_u32, 0x12345678);
    /* The other devices did not reset. */
    CHECK_EQ(count_frames(net, 0, "703#00"), 1);
    free(net);
}

static void test_stopped_device_sends_only_heartbeats(void)
{
    network_t *net = network_up(0);
    co_sim_run_until(&net->bus, 1 * MS); /* past the boot-ups */
    co_nmt_send(&net->master.node, CO_NMT_CMD_STOP, 2);
    uint32_t from = net->trace_count;
    co_sim_run_until(&net->bus, 500 * MS);
    /* A change of TPDO1's object (0x2000, event-driven) sends no PDO while stopped. */
    co_node_set_uint(&net->devices[0].node, 0x2000, 0, 0xCAFE);
    co_sim_run_until(&net->bus, 1000 * MS);
    uint32_t from_node2 = 0;
    for (uint32_t i = from; i < net->trace_count; i++) {
        const char *p = strstr(net->trace[i], "sim0 ");
        if (p && strncmp(p + 5, "702#", 4) == 0) {
            from_node2++;
            CHECK_STR(p + 5, "702#04");
        }
    }
    CHECK_EQ(from_node2, 10);
    CHECK_EQ(count_frames(net, from, "182#FECA0000"), 0);
    /* An SDO request (read 0x1000) gets no answer while stopped... */
    co_frame_t req = frm(0x602, "40 00 10 00 00 00 00 00");
    co_node_send(&net->master.node, &req);
    co_sim_run_until(&net->bus, 1100 * MS);
    CHECK_EQ(count_frames(net, 0, "582#4300100091010000"), 0);
    /* ...and the same request is answered once the node is pre-operational again. */
    co_nmt_send(&net->master.node, CO_NMT_CMD_ENTER_PRE_OPERATIONAL, 2);
    co_node_send(&net->master.node, &req);
    co_sim_run_until(&net->bus, 1200 * MS);
    CHECK_EQ(count_frames(net, 0, "582#4300100091010000"), 1);
    /* Started, the same change does send TPDO1. */
    co_nmt_send(&net->master.node, CO_NMT_CMD_START, 2);
    co_sim_run_until(&net->bus, 1300 * MS);
    co_node_set_uint(&net->devices[0].node, 0x2000, 0, 0xBEEF);
    co_sim_run_until(&net->bus, 1400 * MS);
    CHECK_EQ(count_frames(net, 0, "182#EFBE0000"), 1);
    free(net);
}

static void test_lost_heartbeat_reported_after_consumer_time_never_before(void)
{
    network_t *net = network_up(0);
    co_sim_run_until(&net->bus, 500 * MS);
    /* Node 3's last heartbeat is at 500 ms; it then goes bus-off. */
    co_sim_set_bus_off(&net->devices[1].port, true);
    co_sim_run_until(&net->bus, 749 * MS);
    CHECK(find_event(net, CO_EC_HB_TIMEOUT, 3) == NULL);
    co_sim_run_until(&net->bus, 2000 * MS);
    const event_at_t *e = find_event(net, CO_EC_HB_TIMEOUT, 3);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->t_us, 750 * MS);
        CHECK_EQ(e->ev.state, CO_NMT_PRE_OPERATIONAL);
    }
    CHECK(find_event(net, CO_EC_HB_TIMEOUT, 2) == NULL);
    CHECK(find_event(net, CO_EC_HB_TIMEOUT, 4) == NULL);
    /* Back on the bus: resumed. */
    co_sim_set_bus_off(&net->devices[1].port, false);
    co_sim_run_until(&net->bus, 2200 * MS);
    CHECK(find_event(net, CO_EC_HB_RESUMED, 3) != NULL);
    free(net);
}

static void test_node_that_never_boots_reported_after_boot_time(void)
{
    network_t *net = network_up(0);
    uint8_t v[4];
    co_put_u32(v, hb_consumer_value(9, 250)); /* node 9 is not on the bus */
    CHECK_EQ(co_node_write_net(&net->master.node, 0x1016, 4, v, 4), CO_ABORT_NONE);
    co_sim_run_until(&net->bus, 1999 * MS);
    CHECK(find_event(net, CO_EC_NOT_BOOTED, 9) == NULL);
    co_sim_run_until(&net->bus, 3000 * MS);
    const event_at_t *e = find_event(net, CO_EC_NOT_BOOTED, 9);
    CHECK(e != NULL);
    if (e) {
        CHECK_EQ(e->t_us, 2000 * MS);
    }
    CHECK(find_event(net, CO_EC_NOT_BOOTED, 2) == NULL);
    free(net);
}

static void test_timing_model_orders_simultaneous_bootups_by_id(void)
{
    network_t *net = network_up(125000);
    co_sim_run_until(&net->bus, 10 * MS);
    /* All four boot-ups were queued at t = 0; arbitration lets them out lowest ID first,
     * one frame time (boot-up: 1 data byte) apart. */
    CHECK(strstr(net->trace[0], "701#00") != NULL);
    CHECK(strstr(net->trace[1], "702#00") != NULL);
    CHECK(strstr(net->trace[2], "703#00") != NULL);
    CHECK(strstr(net->trace[3], "704#00") != NULL);
    double t0 = atof(net->trace[0] + 1);
    double t1 = atof(net->trace[1] + 1);
    CHECK(t0 > 0.0 && t1 > t0);
    co_frame_t boot = frm(0x702, "00");
    double frame_s = co_sim_frame_bits(&boot) / 125000.0;
    CHECK(t1 - t0 > frame_s * 0.99 && t1 - t0 < frame_s * 1.01 + 1e-6);
    free(net);
}

/* Process data on the 1 Mbit/s bus: the master produces SYNC every 10 ms, device 2
 * answers each with its synchronous TPDO1 right after the SYNC frame, and the master's
 * event-driven TPDO1 lands in device 3's outputs through its RPDO1. */
static void test_sync_and_pdos_on_the_timed_bus(void)
{
    network_t *net = network_up(1000000);
    co_node_t *master = &net->master.node;
    co_node_t *dev2 = &net->devices[0].node;
    co_node_t *dev3 = &net->devices[1].node;
    uint8_t v[4];
    /* Device 2: TPDO1 (0x2000) synchronous, every SYNC. */
    CHECK_EQ(co_node_write_net(dev2, 0x1800, 2, (const uint8_t[]){1}, 1), CO_ABORT_NONE);
    co_node_set_uint(dev2, 0x2000, 0, 0xA1B2C3D4);
    /* Device 3: RPDO1 re-mapped by the CiA 301 procedure to listen to the master's TPDO1. */
    co_put_u32(v, 0x80000203u);
    CHECK_EQ(co_node_write_net(dev3, 0x1400, 1, v, 4), CO_ABORT_NONE);
    co_put_u32(v, 0x181);
    CHECK_EQ(co_node_write_net(dev3, 0x1400, 1, v, 4), CO_ABORT_NONE);
    /* Master: SYNC producer every 10 ms, from now (t = 0, pre-operational allows SYNC). */
    co_put_u32(v, 10000);
    CHECK_EQ(co_node_write_net(master, 0x1006, 0, v, 4), CO_ABORT_NONE);
    co_put_u32(v, 0x40000080u);
    CHECK_EQ(co_node_write_net(master, 0x1005, 0, v, 4), CO_ABORT_NONE);
    co_nmt_send(master, CO_NMT_CMD_START, 0);
    co_sim_run_until(&net->bus, 5 * MS);
    uint32_t from = net->trace_count;
    co_sim_run_until(&net->bus, 45 * MS);
    /* SYNCs go out at 10, 20, 30 and 40 ms (arriving one frame time later); each is
     * followed at once by device 2's TPDO, one TPDO frame time after it. */
    uint32_t syncs = 0;
    for (uint32_t i = from; i + 1 < net->trace_count; i++) {
        if (strstr(net->trace[i], " 080#") == NULL) {
            continue;
        }
        syncs++;
        CHECK(strstr(net->trace[i + 1], " 182#D4C3B2A1") != NULL);
        double t_sync = atof(net->trace[i] + 1);
        double t_pdo = atof(net->trace[i + 1] + 1);
        co_frame_t sync = frm(0x080, "");
        co_frame_t pdo = frm(0x182, "D4 C3 B2 A1");
        double sync_s = co_sim_frame_bits(&sync) / 1e6;
        double pdo_s = co_sim_frame_bits(&pdo) / 1e6;
        CHECK(t_sync - 0.010 * syncs > sync_s - 1.5e-6 && t_sync - 0.010 * syncs < sync_s + 1.5e-6);
        CHECK(t_pdo - t_sync > pdo_s - 1.5e-6 && t_pdo - t_sync < pdo_s + 1.5e-6);
    }
    CHECK_EQ(syncs, 4);
    /* The master writes its 0x2000: TPDO1 (type 255) carries it to device 3's outputs. */
    co_node_set_uint(master, 0x2000, 0, 0x44332211);
    co_sim_run_until(&net->bus, 46 * MS);
    CHECK_EQ(net->devices[1].od.outputs[0], 0x11);
    CHECK_EQ(net->devices[1].od.outputs[3], 0x44);
    free(net);
}

int main(void)
{
    RUN(test_power_on_three_bootups_once_each);
    RUN(test_nmt_to_one_and_to_all_shows_in_heartbeats);
    RUN(test_reset_node_and_reset_communication_over_the_bus);
    RUN(test_stopped_device_sends_only_heartbeats);
    RUN(test_lost_heartbeat_reported_after_consumer_time_never_before);
    RUN(test_node_that_never_boots_reported_after_boot_time);
    RUN(test_timing_model_orders_simultaneous_bootups_by_id);
    RUN(test_sync_and_pdos_on_the_timed_bus);
    return check_summary();
}
