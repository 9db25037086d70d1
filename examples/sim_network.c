/*
 * sim_network.c -- a master and three devices on the simulated bus.
 *
 * The master (node 1) consumes the heartbeats of devices 2, 3 and 4 (each
 * produces one every 100 ms) and walks the network through the NMT states:
 * start all, stop one, back to pre-operational, reset one; then device 2 drops
 * off the bus and the master reports the lost heartbeat. Every frame is printed
 * in candump log format, every event the master sees as a comment line.
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
        /* The master consumes each device's heartbeat with a 250 ms time-out. */
        uint8_t v[4];
        co_put_u32(v, ((uint32_t)(2 + i) << 16) | 250u);
        err = co_node_write_net(&master.node, 0x1016, (uint8_t)(i + 1), v, 4) ? -1 : 0;
    }
    if (err != 0) {
        fprintf(stderr, "sim_network: setting up the network failed\n");
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
