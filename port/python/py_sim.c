/* Simulated bus and bare nodes for canola.core (see canola_py.h). */
#include "canola_py.h"

#include <stdlib.h>

co_sim_bus_t *canola_py_bus_new(uint32_t bitrate)
{
    co_sim_bus_t *bus = calloc(1, sizeof *bus);
    if (bus && co_sim_bus_init(bus, bitrate) != CO_OK) {
        free(bus);
        return NULL;
    }
    return bus;
}

void canola_py_bus_free(co_sim_bus_t *bus) { free(bus); }

uint64_t canola_py_bus_now(const co_sim_bus_t *bus) { return bus->now_us; }

canola_py_node_t *canola_py_node_new(co_sim_bus_t *bus, const co_od_entry_t *entries,
                                     uint32_t count, uint8_t node_id, co_err_t *err)
{
    canola_py_node_t *n = calloc(1, sizeof *n);
    if (!n) {
        *err = CO_ERR_FULL;
        return NULL;
    }
    *err = co_sim_port_attach(bus, &n->port);
    if (*err != CO_OK) {
        free(n);
        return NULL;
    }
    co_node_config_t cfg = {0};
    cfg.node_id = node_id;
    cfg.od.entries = entries;
    cfg.od.count = count;
    cfg.driver = co_sim_port_driver(&n->port);
    *err = co_node_init(&n->node, &cfg);
    if (*err != CO_OK) {
        /* attached but unbound: a port without node sends and receives nothing */
        n->port.bus_off = true;
        return n;
    }
    co_sim_port_bind(&n->port, &n->node);
    return n;
}

void canola_py_node_free(canola_py_node_t *node) { free(node); }

co_node_t *canola_py_node_ptr(canola_py_node_t *node) { return &node->node; }
