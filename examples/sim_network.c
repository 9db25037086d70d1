/* SPDX-License-Identifier: Apache-2.0 */
/*
 * sim_network.c -- a master and three devices on the simulated bus.
 *
 * The master (node 1) consumes the heartbeats of devices 2, 3 and 4 (each
 * produces one every 100 ms), reads device 2's vendor-ID by SDO, produces SYNC
 * every 100 ms (each operational device answers with its synchronous TPDO1) and
 * walks the network through the NMT states: start all, stop one, back to
 * pre-operational, reset one; then device 2 drops off the bus and the master
 * reports the lost heartbeat. Every frame is printed in candump log format, every
 * event the master sees as a comment line.
 *
 * usage: sim_network [BITRATE]   (bit/s, 10000..1000000; default 125000)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canola/sim.h"
#include "example_od.h"

#define DEVICES 3
#define MS 1000ull

typedef struct station {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
} station_t;

static void print_line(void *ctx, const char *line)
{
    (void)ctx;
    printf("%s\n", line);
}

static void master_event(void *user, const co_ec_event_t *ev)
{
    const co_sim_bus_t *bus = user;
    double t = (double)bus->now_us / 1e6;
    switch (ev->kind) {
    case CO_EC_BOOT:
        printf("# %.6f master: node %u booted\n", t, ev->node_id);
        break;
    case CO_EC_REMOTE_RESET:
        printf("# %.6f master: node %u was reset (boot-up after %s)\n", t, ev->node_id,
               co_nmt_state_name(ev->previous));
        break;
    case CO_EC_STARTED:
        printf("# %.6f master: node %u heartbeat monitored, %s\n", t, ev->node_id,
               co_nmt_state_name(ev->state));
        break;
    case CO_EC_STATE_CHANGED:
        printf("# %.6f master: node %u %s -> %s\n", t, ev->node_id, co_nmt_state_name(ev->previous),
               co_nmt_state_name(ev->state));
        break;
    case CO_EC_HB_TIMEOUT:
        printf("# %.6f master: node %u HEARTBEAT LOST (last state %s)\n", t, ev->node_id,
               co_nmt_state_name(ev->state));
        break;
    default:
        printf("# %.6f master: node %u event %d\n", t, ev->node_id, (int)ev->kind);
        break;
    }
}

static void vendor_read(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value, uint32_t len)
{
    (void)channel;
    (void)len;
    const co_sim_bus_t *bus = ctx;
    if (abort != CO_ABORT_NONE) {
        printf("# %.6f master: reading node 2's vendor-ID failed, abort 0x%08X\n",
               (double)bus->now_us / 1e6, (unsigned)abort);
        return;
    }
    printf("# %.6f master: node 2 vendor-ID 0x%08X (SDO upload of 0x1018 sub1)\n",
           (double)bus->now_us / 1e6, (unsigned)value);
}

/* Write a u32 as the network would; false when the device refuses it. */
static bool write_u32(co_node_t *node, uint16_t index, uint8_t sub, uint32_t value)
{
    uint8_t v[4];
    co_put_u32(v, value);
    return co_node_write_net(node, index, sub, v, 4) == CO_ABORT_NONE;
}

static int start_station(co_sim_bus_t *bus, station_t *s, uint8_t id, uint16_t hb_ms,
                         void (*on_errctl)(void *, const co_ec_event_t *))
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_init(&s->od, hb_ms)};
    if (co_sim_port_attach(bus, &s->port) != CO_OK) {
        return -1;
    }
    cfg.driver = co_sim_port_driver(&s->port);
    cfg.user = bus;
    cfg.on_errctl = on_errctl;
    if (co_node_init(&s->node, &cfg) != CO_OK) {
        return -1;
    }
    co_sim_port_bind(&s->port, &s->node);
    return co_node_start(&s->node, bus->now_us) == CO_OK ? 0 : -1;
}

static int parse_bitrate(int argc, char **argv, uint32_t *bitrate)
{
    *bitrate = 125000;
    if (argc < 2) {
        return 0;
    }
    char *end = NULL;
    unsigned long v = strtoul(argv[1], &end, 10);
    if (argc > 2 || end == argv[1] || *end != '\0' || v < 10000 || v > 1000000) {
        return -1;
    }
    *bitrate = (uint32_t)v;
    return 0;
}

int main(int argc, char **argv)
{
    uint32_t bitrate;
    if (parse_bitrate(argc, argv, &bitrate) != 0) {
        fprintf(stderr, "sim_network: BITRATE must be one number of bit/s from 10000 to 1000000\n");
        return 2;
    }
    static co_sim_bus_t bus;
    static station_t master;
    static station_t devices[DEVICES];
    co_sim_bus_init(&bus, bitrate);
    co_sim_set_trace(&bus, print_line, NULL);
    printf("# canola demo: master 1 and devices 2..4 on a simulated bus at %u bit/s\n",
           (unsigned)bitrate);

    int err = start_station(&bus, &master, 1, 0, master_event);
    for (uint8_t i = 0; i < DEVICES && err == 0; i++) {
        err = start_station(&bus, &devices[i], (uint8_t)(2 + i), 100, NULL);
    }
    for (uint8_t i = 0; i < DEVICES && err == 0; i++) {
        uint8_t id = (uint8_t)(2 + i);
        /* The master consumes each device's heartbeat with a 250 ms time-out. */
        err =
            write_u32(&master.node, 0x1016, (uint8_t)(i + 1), ((uint32_t)id << 16) | 250u) ? 0 : -1;
        /* Each device sends 0x2000 in TPDO1 after every SYNC (transmission type 1). */
        uint8_t sync_type = 1;
        err |= co_node_write_net(&devices[i].node, 0x1800, 2, &sync_type, 1) ? -1 : 0;
        err |= co_node_set_uint(&devices[i].node, 0x2000, 0, 0x1000u * id) ? -1 : 0;
    }
    /* The master produces SYNC every 100 ms and reads device 2's vendor-ID by SDO. */
    if (err == 0 && !(write_u32(&master.node, 0x1006, 0, 100000) &&
                      write_u32(&master.node, 0x1005, 0, 0x40000080u) &&
                      co_sdo_client_setup(&master.node, 0, 2) == CO_OK)) {
        err = -1;
    }
    if (err != 0) {
        fprintf(stderr, "sim_network: setting up the network failed\n");
        return 1;
    }

    /* Once the boot-ups are on the bus, the master reads device 2's vendor-ID. */
    co_sim_run_until(&bus, 50 * MS);
    if (co_sdo_read_value(&master.node, 0, 0x1018, 1, vendor_read, &bus) != CO_OK) {
        fprintf(stderr, "sim_network: the SDO read could not start\n");
        return 1;
    }

    /* The script: at each time, the master sends a command (or node 2 drops off). */
    static const struct {
        uint64_t at_ms;
        const char *what;
        co_nmt_cmd_t cmd;
        uint8_t target;
    } script[] = {
        {250, "start all nodes", CO_NMT_CMD_START, 0},
        {450, "stop node 3", CO_NMT_CMD_STOP, 3},
        {650, "all nodes to pre-operational", CO_NMT_CMD_ENTER_PRE_OPERATIONAL, 0},
        {850, "reset node 4", CO_NMT_CMD_RESET_NODE, 4},
        {1050, NULL, 0, 0},
    };
    for (size_t i = 0; i < sizeof script / sizeof script[0]; i++) {
        co_sim_run_until(&bus, script[i].at_ms * MS);
        if (script[i].what == NULL) {
            printf("# node 2 goes bus-off\n");
            co_sim_set_bus_off(&devices[0].port, true);
            continue;
        }
        printf("# master: %s\n", script[i].what);
        co_nmt_send(&master.node, script[i].cmd, script[i].target);
    }
    co_sim_run_until(&bus, 1500 * MS);

    const co_sim_stats_t *st = co_sim_stats(&bus);
    printf("# %llu frames in %.3f s of bus time, bus load %.2f %%\n",
           (unsigned long long)st->frames, (double)bus.now_us / 1e6, 100.0 * co_sim_load(&bus));
    return 0;
}
