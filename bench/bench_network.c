/* SPDX-License-Identifier: Apache-2.0 */
/*
 * bench_network.c -- a full network on the simulated bus, as fast as one core runs it:
 * how many times faster than real time canola simulates a busy 1 Mbit/s network.
 * Not a test: it prints one line of figures (bench/run formats them); a network that
 * does not reach the expected traffic ends with exit status 1 and no figure.
 *
 * usage: bench_network [SIM_SECONDS [NODES]]  -> nodes=.. sim_s=.. wall_s=.. cpu_s=.. load=..
 *
 * CANopen has 127 node-IDs, so "127 devices + master" is 127 nodes here (the default;
 * NODES 2..127 for fewer): the master (node-ID 1: NMT master, SYNC producer every 20 ms,
 * and a TPDO of its own like every device) and the devices (node-IDs 2..NODES). Every
 * node runs examples/example_od.c with TPDO1 re-mapped by the CiA 301 procedure to
 * 0x2000 + 0x2007 (2 x u32, 8 bytes), transmission type 1: one TPDO per node after each
 * SYNC. The device changes 0x2000 every SYNC (on_sync) so the data moves. Bus at
 * 1 Mbit/s on the timing model (stuff bits, arbitration, interframe space).
 *
 * Timed: only the co_sim_run_until() calls of the measured span (setup, boot-up and NMT
 * start excluded), by CLOCK_MONOTONIC (wall) and CLOCK_PROCESS_CPUTIME_ID (one thread).
 */
#define _POSIX_C_SOURCE 199309L

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "canola/canola.h"
#include "canola/sim.h"
#include "example_od.h"

#define NODES_MAX 127u
#define BITRATE 1000000u
#define SYNC_PERIOD_US 20000u
#define MS 1000u

typedef struct station {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
} station_t;

static void die(const char *what)
{
    fprintf(stderr, "bench_network: %s: no figure\n", what);
    exit(1);
}

static void on_sync(void *user, uint8_t counter)
{
    station_t *s = user;
    s->od.app_u32 += 1u + counter; /* fresh data for the next TPDO */
}

static void set_u32(station_t *s, uint16_t index, uint8_t sub, uint32_t v)
{
    uint8_t d[4];
    co_put_u32(d, v);
    if (co_node_write_net(&s->node, index, sub, d, 4) != CO_ABORT_NONE) {
        die("configuration write refused");
    }
}

static void set_u8(station_t *s, uint16_t index, uint8_t sub, uint8_t v)
{
    if (co_node_write_net(&s->node, index, sub, &v, 1) != CO_ABORT_NONE) {
        die("configuration write refused");
    }
}

/* TPDO1: 2 x u32, synchronous every SYNC (the CiA 301 re-mapping procedure). */
static void map_tpdo(station_t *s)
{
    uint64_t cob = 0;
    co_node_get_uint(&s->node, 0x1800, 1, &cob);
    set_u32(s, 0x1800, 1, (uint32_t)cob | 0x80000000u);
    set_u8(s, 0x1A00, 0, 0);
    set_u32(s, 0x1A00, 1, 0x20000020);
    set_u32(s, 0x1A00, 2, 0x20070020);
    set_u8(s, 0x1A00, 0, 2);
    set_u8(s, 0x1800, 2, 1);
    set_u32(s, 0x1800, 1, (uint32_t)cob & 0x7FFFFFFFu);
}

static void start_station(co_sim_bus_t *bus, station_t *s, uint8_t id)
{
    co_node_config_t cfg = {.node_id = id,
                            .od = example_od_keyed(&s->od, example_od_init(&s->od, 0))};
    if (co_sim_port_attach(bus, &s->port) != CO_OK) {
        die("port attach failed");
    }
    cfg.driver = co_sim_port_driver(&s->port);
    cfg.user = s;
    cfg.on_sync = on_sync;
    if (co_node_init(&s->node, &cfg) != CO_OK) {
        die("node init failed");
    }
    co_sim_port_bind(&s->port, &s->node);
    if (co_node_start(&s->node, bus->now_us) != CO_OK) {
        die("node start failed");
    }
    map_tpdo(s);
}

/* The measured span, in steps of one second as a host loop would run it (bench/run has
 * callgrind count the instructions of this function only). */
__attribute__((noinline)) static void measured_span(co_sim_bus_t *bus, uint64_t span)
{
    uint64_t t0 = bus->now_us;
    for (uint64_t t = t0; t < t0 + span;) {
        t = t + 1000000u < t0 + span ? t + 1000000u : t0 + span;
        if (co_sim_run_until(bus, t) != CO_OK) {
            die("the simulated bus stopped");
        }
    }
}

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv)
{
    double sim_s = argc > 1 ? strtod(argv[1], NULL) : 60.0;
    unsigned long nodes = argc > 2 ? strtoul(argv[2], NULL, 10) : NODES_MAX;
    if (!(sim_s > 0.0)) {
        die("simulated seconds must be positive");
    }
    if (nodes < 2 || nodes > NODES_MAX) {
        die("nodes must be 2..127");
    }
    const uint32_t count = (uint32_t)nodes;
    co_sim_bus_t *bus = calloc(1, sizeof *bus);
    station_t *st = calloc(count, sizeof *st);
    if (bus == NULL || st == NULL || co_sim_bus_init(bus, BITRATE) != CO_OK) {
        die("setup failed");
    }
    for (uint32_t i = 0; i < count; i++) {
        start_station(bus, &st[i], (uint8_t)(i + 1u));
    }
    station_t *master = &st[0];
    co_sim_run_until(bus, 100 * MS); /* boot-up frames gone */
    if (co_nmt_send(&master->node, CO_NMT_CMD_START, 0) != CO_OK) {
        die("NMT start failed");
    }
    set_u32(master, 0x1006, 0, SYNC_PERIOD_US);
    set_u32(master, 0x1005, 0, 0x40000080u); /* the master produces SYNC */
    co_sim_run_until(bus, 200 * MS);
    for (uint32_t i = 0; i < count; i++) {
        if (st[i].node.nmt_state != CO_NMT_OPERATIONAL) {
            die("a node is not operational");
        }
    }

    co_sim_stats_t before = *co_sim_stats(bus);
    uint64_t span = (uint64_t)(sim_s * 1e6);
    double w0 = clock_s(CLOCK_MONOTONIC);
    double c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    measured_span(bus, span);
    double wall = clock_s(CLOCK_MONOTONIC) - w0;
    double cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;

    const co_sim_stats_t *after = co_sim_stats(bus);
    uint64_t frames = after->frames - before.frames;
    double load = (double)(after->busy_us - before.busy_us) / (double)span;
    uint64_t syncs = span / SYNC_PERIOD_US;
    if (frames < syncs * (count + 1u) * 99u / 100u || after->overflow != 0) {
        fprintf(stderr, "bench_network: %llu frames for %llu SYNCs (overflow %llu)\n",
                (unsigned long long)frames, (unsigned long long)syncs,
                (unsigned long long)after->overflow);
        die("the network did not carry one TPDO per node per SYNC");
    }
    for (uint32_t i = 0; i < count; i++) {
        if (co_node_stats(&st[i].node)->tx_overflow != 0) {
            die("a node lost frames");
        }
    }
    printf("nodes=%u sim_s=%.1f wall_s=%.3f cpu_s=%.3f speed=%.1f frames=%llu load=%.3f\n", count,
           (double)span / 1e6, wall, cpu, (double)span / 1e6 / wall, (unsigned long long)frames,
           load);
    free(st);
    free(bus);
    return 0;
}
