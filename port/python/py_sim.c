/* SPDX-License-Identifier: Apache-2.0 */
/* The simulated bus for canola.core.SimBus (see canola_py.h). */
#include "canola_py.h"

co_sim_bus_t *canola_py_bus_new(uint32_t bitrate)
{
    co_sim_bus_t *bus = canola_py_alloc(sizeof *bus);
    if (bus && co_sim_bus_init(bus, bitrate) != CO_OK) {
        canola_py_release(bus);
        return NULL;
    }
    return bus;
}

void canola_py_bus_free(co_sim_bus_t *bus) { canola_py_release(bus); }

uint64_t canola_py_bus_now(const co_sim_bus_t *bus) { return bus->now_us; }
