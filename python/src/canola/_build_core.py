"""cffi builder of ``canola._core``: the C core of the repository plus the simulated bus.

API mode (a compiled extension). Used by setuptools through ``cffi_modules`` in
``python/setup.py``; can also be run by hand (``python src/canola/_build_core.py``) to build
the module in place. The C sources are the repository's own (``../src``, ``../port/sim``),
found relative to this file, so it builds from a checkout (an editable install).

The core never allocates; the small helper section below does (one calloc per bus and per
node+port), which is what a binding layer is allowed to do.
"""

from __future__ import annotations

import glob
import os

import cffi  # type: ignore[import-untyped]

_HERE = os.path.dirname(os.path.abspath(__file__))
_ROOT = os.path.normpath(os.path.join(_HERE, "..", "..", ".."))


def _rel(path: str) -> str:
    """``path`` relative to the working directory (setuptools runs in ``python/``)."""
    return os.path.relpath(path)


_SOURCES = [
    *sorted(glob.glob(os.path.join(_ROOT, "src", "*.c"))),
    os.path.join(_ROOT, "port", "sim", "sim.c"),
    os.path.join(_ROOT, "port", "sim", "sim_storage.c"),
]
_INCLUDES = [os.path.join(_ROOT, "include"), os.path.join(_ROOT, "src"),
             os.path.join(_ROOT, "port", "sim")]

CDEF = """
typedef uint32_t co_abort_t;
typedef enum co_err { CO_OK, CO_ERR_ARG, CO_ERR_BUSY, CO_ERR_CONFIG, CO_ERR_STATE,
                      CO_ERR_NOT_FOUND, CO_ERR_FULL, CO_ERR_ABORT, ... } co_err_t;
typedef enum co_nmt_state { CO_NMT_INITIALISING, CO_NMT_STOPPED, CO_NMT_OPERATIONAL,
                            CO_NMT_PRE_OPERATIONAL, ... } co_nmt_state_t;
typedef enum co_nmt_cmd { CO_NMT_CMD_START, CO_NMT_CMD_STOP, CO_NMT_CMD_ENTER_PRE_OPERATIONAL,
                          CO_NMT_CMD_RESET_NODE, CO_NMT_CMD_RESET_COMMUNICATION,
                          ... } co_nmt_cmd_t;
typedef enum co_sdo_mode { CO_SDO_AUTO, CO_SDO_EXPEDITED, CO_SDO_SEGMENTED, CO_SDO_BLOCK,
                           ... } co_sdo_mode_t;

#define CO_OD_READ ...
#define CO_OD_WRITE ...
#define CO_OD_CONST ...
#define CO_OD_TPDO ...
#define CO_OD_RPDO ...
#define CO_OD_NODEID ...
#define CO_OD_RO ...
#define CO_OD_WO ...
#define CO_OD_RW ...
#define CO_OD_RWR ...
#define CO_OD_RWW ...
#define CO_OD_CO ...

typedef union co_od_num { int64_t i; uint64_t u; double f; } co_od_num_t;
typedef struct co_od_limits { co_od_num_t low; co_od_num_t high; } co_od_limits_t;
typedef struct co_od_domain { uint8_t *data; uint32_t len; } co_od_domain_t;
typedef struct co_od_hooks co_od_hooks_t;
typedef struct co_od_entry {
    uint16_t index;
    uint8_t sub;
    uint8_t type;
    uint8_t attr;
    uint32_t size;
    void *value;
    const void *dflt;
    const co_od_limits_t *limits;
    const co_od_hooks_t *hooks;
    ...;
} co_od_entry_t;
typedef struct co_od { const co_od_entry_t *entries; uint32_t count; void *hook_ctx; ...; } co_od_t;

typedef struct co_node co_node_t;
typedef struct co_sim_bus co_sim_bus_t;
typedef struct canola_py_node canola_py_node_t;

typedef void (*co_sdo_done_fn)(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len);
typedef void (*co_sim_trace_fn)(void *ctx, const char *line);

co_err_t co_od_validate(const co_od_t *od, uint32_t *bad);

co_err_t co_node_start(co_node_t *node, uint64_t now_us);
uint8_t co_node_id(const co_node_t *node);
co_abort_t co_node_write_net(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len);
co_abort_t co_node_read_net(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                            uint32_t cap, uint32_t *len);
co_abort_t co_node_set_uint(co_node_t *node, uint16_t index, uint8_t sub, uint64_t value);
co_err_t co_node_get_uint(const co_node_t *node, uint16_t index, uint8_t sub, uint64_t *value);

co_nmt_state_t co_nmt_state(const co_node_t *node);
const char *co_nmt_state_name(uint8_t state);
co_err_t co_nmt_send(co_node_t *node, co_nmt_cmd_t cmd, uint8_t target);

co_err_t co_sdo_client_setup(co_node_t *node, uint8_t channel, uint8_t server_id);
co_err_t co_sdo_upload(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                       co_sdo_mode_t mode, uint8_t *buf, uint32_t cap, co_sdo_done_fn done,
                       void *ctx);
co_err_t co_sdo_download(co_node_t *node, uint8_t channel, uint16_t index, uint8_t sub,
                         co_sdo_mode_t mode, const uint8_t *data, uint32_t len,
                         co_sdo_done_fn done, void *ctx);
co_err_t co_sdo_client_abort(co_node_t *node, uint8_t channel, co_abort_t code);
bool co_sdo_client_busy(const co_node_t *node, uint8_t channel);

co_err_t co_sim_run_until(co_sim_bus_t *bus, uint64_t until_us);
void co_sim_set_trace(co_sim_bus_t *bus, co_sim_trace_fn fn, void *ctx);
double co_sim_load(const co_sim_bus_t *bus);

/* helpers of the binding (preamble below) */
co_sim_bus_t *canola_py_bus_new(uint32_t bitrate);
void canola_py_bus_free(co_sim_bus_t *bus);
uint64_t canola_py_bus_now(const co_sim_bus_t *bus);
canola_py_node_t *canola_py_node_new(co_sim_bus_t *bus, const co_od_entry_t *entries,
                                     uint32_t count, uint8_t node_id, co_err_t *err);
void canola_py_node_free(canola_py_node_t *node);
co_node_t *canola_py_node_ptr(canola_py_node_t *node);

/* callbacks into Python */
extern "Python" void canola_py_trace(void *ctx, const char *line);
extern "Python" void canola_py_sdo_done(void *ctx, uint8_t channel, co_abort_t abort,
                                        uint32_t len);
"""

PREAMBLE = r"""
#include <stdlib.h>
#include "canola/canola.h"
#include "canola/sim.h"

typedef struct canola_py_node {
    co_node_t node;
    co_sim_port_t port;
} canola_py_node_t;

static co_sim_bus_t *canola_py_bus_new(uint32_t bitrate)
{
    co_sim_bus_t *bus = calloc(1, sizeof *bus);
    if (bus && co_sim_bus_init(bus, bitrate) != CO_OK) {
        free(bus);
        return NULL;
    }
    return bus;
}

static void canola_py_bus_free(co_sim_bus_t *bus) { free(bus); }

static uint64_t canola_py_bus_now(const co_sim_bus_t *bus) { return bus->now_us; }

/* A node on its own port of `bus`; the entries must outlive it. NULL with *err set on
 * failure. The port stays attached to the bus: free the node only with its bus. */
static canola_py_node_t *canola_py_node_new(co_sim_bus_t *bus, const co_od_entry_t *entries,
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

static void canola_py_node_free(canola_py_node_t *node) { free(node); }

static co_node_t *canola_py_node_ptr(canola_py_node_t *node) { return &node->node; }
"""

ffibuilder = cffi.FFI()
ffibuilder.cdef(CDEF)
ffibuilder.set_source(
    "canola._core",
    PREAMBLE,
    sources=[_rel(p) for p in _SOURCES],
    include_dirs=[_rel(p) for p in _INCLUDES],
)

if __name__ == "__main__":
    ffibuilder.compile(verbose=True)
