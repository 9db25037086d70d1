"""cffi builder of ``canola._core``: the C core of the repository plus the simulated bus.

API mode (a compiled extension). Used by setuptools through ``cffi_modules`` in
``python/setup.py``; can also be run by hand (``python src/canola/_build_core.py``) to build
the module in place. The C sources are the repository's own (``../src``, ``../port/sim``),
found relative to this file, so it builds from a checkout (an editable install, ``pip install
python``, ``python -m build python``); an sdist carries a copy of them in ``csrc/``
(``c_files``, copied by ``python/setup.py``), where they are looked for first.

The core never allocates; the small helper section below does (one calloc per bus and per
node+port), which is what a binding layer is allowed to do.
"""

from __future__ import annotations

import glob
import os

import cffi  # type: ignore[import-untyped]

_HERE = os.path.dirname(os.path.abspath(__file__))
_PROJECT = os.path.normpath(os.path.join(_HERE, "..", ".."))  # python/, or an unpacked sdist
_SDIST_C = os.path.join(_PROJECT, "csrc")
_ROOT = _SDIST_C if os.path.isdir(_SDIST_C) else os.path.dirname(_PROJECT)


def _rel(path: str) -> str:
    """``path`` relative to the working directory (setuptools runs in ``python/``)."""
    return os.path.relpath(path)


_SOURCES = [
    *sorted(glob.glob(os.path.join(_ROOT, "src", "*.c"))),
    os.path.join(_ROOT, "port", "sim", "sim.c"),
    os.path.join(_ROOT, "port", "sim", "sim_storage.c"),
    os.path.join(_ROOT, "port", "linux", "file_storage.c"),
]
_INCLUDES = [os.path.join(_ROOT, "include"), os.path.join(_ROOT, "src"),
             os.path.join(_ROOT, "port", "sim"), os.path.join(_ROOT, "port", "linux")]
_HEADERS = [p for d in _INCLUDES
            for p in sorted(glob.glob(os.path.join(d, "**", "*.h"), recursive=True))]


def c_files() -> tuple[str, list[str]]:
    """The folder of the C sources and the files the extension is built from (its sources and
    the headers of its include folders), relative to it: what an sdist carries in csrc/."""
    return _ROOT, sorted(os.path.relpath(p, _ROOT) for p in {*_SOURCES, *_HEADERS})

# Sizes of the core in the extension: a master watches up to 127 nodes (heartbeat and EMCY
# consumers), talks SDO to several at once, and devices from real EDS files have many PDOs.
# Everything in the extension is compiled with the same values.
_CONFIG = [
    ("CO_HB_CONSUMERS_MAX", "127"),
    ("CO_EMCY_CONSUMERS_MAX", "127"),
    ("CO_SDO_CLIENTS_MAX", "16"),
    ("CO_RPDO_MAX", "64"),
    ("CO_TPDO_MAX", "64"),
    ("CO_TX_QUEUE_LEN", "64"),
    ("CO_EMCY_QUEUE_LEN", "16"),
    ("CO_SDO_BUF_SIZE", "4096"),  # frames a transfer; RAM entries take up to their size
]

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

#define CO_FRAME_EXT ...
#define CO_FRAME_RTR ...
#define CO_TIME_NEVER ...
typedef struct co_frame { uint32_t id; uint8_t flags; uint8_t len; uint8_t data[8]; } co_frame_t;
typedef struct co_ec_event { int kind; uint8_t node_id; uint8_t state; uint8_t previous;
                             ...; } co_ec_event_t;
typedef struct co_emcy_msg { uint32_t cob_id; uint16_t code; uint8_t reg;
                             uint8_t manufacturer[5]; ...; } co_emcy_msg_t;
typedef struct co_time_of_day { uint32_t ms; uint16_t days; ...; } co_time_of_day_t;
typedef enum co_ec_event_kind { CO_EC_BOOT, CO_EC_REMOTE_RESET, CO_EC_STARTED,
    CO_EC_STATE_CHANGED, CO_EC_HB_TIMEOUT, CO_EC_HB_RESUMED, CO_EC_NOT_BOOTED,
    CO_EC_GUARD_TIMEOUT, CO_EC_GUARD_TOGGLE, CO_EC_GUARD_RESUMED, CO_EC_LIFE_GUARD,
    CO_EC_LIFE_GUARD_RESUMED, ... } co_ec_event_kind_t;

typedef enum co_node_error { CO_NODE_ERR_TX_OVERFLOW, CO_NODE_ERR_TX_DRIVER,
                             CO_NODE_ERR_STORED_COMM, CO_NODE_ERR_STORED_APP,
                             ... } co_node_error_t;
typedef enum co_param_group { CO_PARAMS_COMMUNICATION, CO_PARAMS_APPLICATION,
                              ... } co_param_group_t;
typedef enum co_store_fault { CO_STORE_INTACT, CO_STORE_NONE, CO_STORE_BAD_HEADER,
                              CO_STORE_BAD_LENGTH, CO_STORE_BAD_CRC, CO_STORE_BAD_RECORDS,
                              CO_STORE_READ_ERROR, ... } co_store_fault_t;
#define CO_EMCY_STORE_REJECTED ...
co_store_fault_t co_storage_verify(const co_node_t *node, co_param_group_t group);
void co_node_ingest(co_node_t *node, uint64_t now_us, const co_frame_t *frame);
uint64_t co_node_poll(co_node_t *node, uint64_t now_us);
co_err_t co_node_send(co_node_t *node, const co_frame_t *frame);
co_err_t co_emcy_raise(co_node_t *node, uint16_t code, const uint8_t *manufacturer);
co_err_t co_emcy_clear(co_node_t *node, uint16_t code);
bool co_emcy_active(const co_node_t *node, uint16_t code);
co_err_t co_time_send(co_node_t *node, const co_time_of_day_t *t);
co_time_of_day_t co_time_from_us(uint64_t us_since_1984);
uint32_t co_pdo_event(co_node_t *node, uint16_t index, uint8_t sub);
co_err_t co_tpdo_request(co_node_t *node, uint8_t n);
uint8_t co_hb_remote_state(const co_node_t *node, uint8_t node_id);
co_err_t co_nmt_apply(co_node_t *node, co_nmt_cmd_t cmd);

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
co_err_t co_sdo_client_set_timeout(co_node_t *node, uint8_t channel, uint16_t timeout_ms);
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
typedef struct canola_py_dev canola_py_dev_t;
canola_py_dev_t *canola_py_dev_new(co_sim_bus_t *bus, co_od_entry_t *entries, uint32_t count,
                                   uint8_t node_id, uint16_t sdo_timeout_ms,
                                   const char *store_dir, bool raw_port, void *user,
                                   co_err_t *err);
void canola_py_dev_free(canola_py_dev_t *dev);
co_node_t *canola_py_dev_node(canola_py_dev_t *dev);
void canola_py_dev_touch(canola_py_dev_t *dev);
void canola_py_dev_set_quiet(canola_py_dev_t *dev, bool quiet);
co_abort_t canola_py_app_read(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                              uint32_t cap, uint32_t *len, uint8_t *type);
co_abort_t canola_py_app_write(co_node_t *node, uint16_t index, uint8_t sub,
                               const uint8_t *data, uint32_t len);
int canola_py_entry_key(const co_od_entry_t *entry);
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
extern "Python" co_err_t canola_py_tx(void *ctx, const co_frame_t *frame);
extern "Python" void canola_py_on_state(void *user, co_nmt_state_t state);
extern "Python" void canola_py_on_errctl(void *user, const co_ec_event_t *event);
extern "Python" void canola_py_on_error(void *user, co_node_error_t error);
extern "Python" void canola_py_on_emcy(void *user, const co_emcy_msg_t *emcy);
extern "Python" void canola_py_on_sync(void *user, uint8_t counter);
extern "Python" void canola_py_on_time(void *user, const co_time_of_day_t *time);
extern "Python" void canola_py_on_rpdo(void *user, uint16_t rpdo);
extern "Python" void canola_py_written(void *ctx, const co_od_entry_t *entry);
extern "Python" void canola_py_raw_rx(void *ctx, uint64_t now_us, const co_frame_t *frame);
"""

PREAMBLE = r"""
#include <stdlib.h>
#include <string.h>
#include "canola/canola.h"
#include "canola/sim.h"
#include "canola/file_storage.h"
#include "node_internal.h" /* co_node_write_entry */

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

/* canola.Device / canola.Master: a node with every callback routed to Python (`user` is
 * the Python object's handle), on a simulated bus (`bus`, with an optional raw port that
 * sees every frame) or on a driver whose tx is Python (bus NULL: python-can). */
static co_err_t canola_py_tx(void *ctx, const co_frame_t *frame);
static void canola_py_on_state(void *user, co_nmt_state_t state);
static void canola_py_on_errctl(void *user, const co_ec_event_t *event);
static void canola_py_on_error(void *user, co_node_error_t error);
static void canola_py_on_emcy(void *user, const co_emcy_msg_t *emcy);
static void canola_py_on_sync(void *user, uint8_t counter);
static void canola_py_on_time(void *user, const co_time_of_day_t *time);
static void canola_py_on_rpdo(void *user, uint16_t rpdo);
static void canola_py_written(void *ctx, const co_od_entry_t *entry);
static void canola_py_raw_rx(void *ctx, uint64_t now_us, const co_frame_t *frame);

typedef struct canola_py_dev {
    co_node_t node;
    co_sim_port_t port;
    co_sim_port_t raw;
    co_file_storage_t fs;
    co_od_hooks_t hooks;
    void *user;
    bool sim;   /* on the simulated bus, else python-can (canola_py_tx) */
    bool quiet; /* a tool, not a network member: no boot-up, heartbeat or guarding answer */
    /* frames this node sent on the simulated bus and its raw port has not seen come back:
     * the raw port skips them (python-can does not hand a bus its own frames either) */
    co_frame_t own[64];
    uint32_t own_head, own_count;
} canola_py_dev_t;

static co_err_t canola_py_sim_tx(void *ctx, const co_frame_t *frame)
{
    canola_py_dev_t *d = ctx;
    co_err_t err = co_sim_send(&d->port, frame);
    if (err == CO_OK && d->raw.bus) {
        if (d->own_count == 64) { /* forget the oldest */
            d->own_head = (d->own_head + 1) % 64;
            d->own_count--;
        }
        d->own[(d->own_head + d->own_count++) % 64] = *frame;
    }
    return err;
}

/* Every frame the node sends: a quiet node's error control frames (0x700 + its node-ID:
 * boot-up, heartbeat, guarding answers) stay off the bus. */
static co_err_t canola_py_dev_tx(void *ctx, const co_frame_t *frame)
{
    canola_py_dev_t *d = ctx;
    if (d->quiet && !(frame->flags & CO_FRAME_EXT) &&
        frame->id == 0x700u + co_node_id(&d->node)) {
        return CO_OK;
    }
    return d->sim ? canola_py_sim_tx(d, frame) : canola_py_tx(d->user, frame);
}

/* The node's routes changed: the bus's delivery index follows (see canola/sim.h). */
static void canola_py_sim_routes_changed(void *ctx)
{
    canola_py_dev_t *d = ctx;
    co_sim_port_routes_changed(&d->port);
}

static bool same_frame(const co_frame_t *a, const co_frame_t *b)
{
    return a->id == b->id && a->flags == b->flags && a->len == b->len &&
           ((a->flags & CO_FRAME_RTR) || memcmp(a->data, b->data, a->len) == 0);
}

static void canola_py_sim_raw_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    canola_py_dev_t *d = ctx;
    for (uint32_t i = 0; i < d->own_count; i++) {
        co_frame_t *f = &d->own[(d->own_head + i) % 64];
        if (same_frame(f, frame)) { /* drop it and everything sent before it */
            d->own_head = (d->own_head + i + 1) % 64;
            d->own_count -= i + 1;
            return;
        }
    }
    canola_py_raw_rx(d->user, now_us, frame);
}

static canola_py_dev_t *canola_py_dev_new(co_sim_bus_t *bus, co_od_entry_t *entries,
                                          uint32_t count, uint8_t node_id,
                                          uint16_t sdo_timeout_ms, const char *store_dir,
                                          bool raw_port, void *user, co_err_t *err)
{
    canola_py_dev_t *d = calloc(1, sizeof *d);
    if (!d) {
        *err = CO_ERR_FULL;
        return NULL;
    }
    co_node_config_t cfg = {0};
    cfg.node_id = node_id;
    cfg.od.entries = entries;
    cfg.od.count = count;
    cfg.od.hook_ctx = user;
    cfg.sdo_timeout_ms = sdo_timeout_ms;
    cfg.user = user;
    cfg.on_state = canola_py_on_state;
    cfg.on_errctl = canola_py_on_errctl;
    cfg.on_error = canola_py_on_error;
    cfg.on_emcy = canola_py_on_emcy;
    cfg.on_sync = canola_py_on_sync;
    cfg.on_time = canola_py_on_time;
    cfg.on_rpdo = canola_py_on_rpdo;
    d->hooks.written = canola_py_written;
    d->user = user;
    for (uint32_t i = 0; i < count; i++) {
        if (entries[i].hooks == NULL) {
            entries[i].hooks = &d->hooks;
        }
    }
    if (store_dir) {
        *err = co_file_storage_init(&d->fs, store_dir);
        if (*err != CO_OK) {
            free(d);
            return NULL;
        }
        cfg.storage = &d->fs.api;
    }
    if (bus) {
        *err = co_sim_port_attach(bus, &d->port);
        if (*err == CO_OK && raw_port) {
            *err = co_sim_port_attach_raw(bus, &d->raw, canola_py_sim_raw_rx, d);
        }
        if (*err != CO_OK) {
            return d; /* attached ports stay with the bus: the caller keeps d with it */
        }
        d->sim = true;
        cfg.driver.on_routes_changed = canola_py_sim_routes_changed;
    }
    cfg.driver.tx = canola_py_dev_tx;
    cfg.driver.ctx = d;
    *err = co_node_init(&d->node, &cfg);
    if (*err != CO_OK) {
        d->port.bus_off = true;
        return d;
    }
    if (bus) {
        co_sim_port_bind(&d->port, &d->node);
    }
    return d;
}

static void canola_py_dev_free(canola_py_dev_t *dev) { free(dev); }

static co_node_t *canola_py_dev_node(canola_py_dev_t *dev) { return &dev->node; }

/* The application changed the node between two runs of the simulated bus: poll it at the
 * next instant the bus runs (its deadline may have moved). */
static void canola_py_dev_touch(canola_py_dev_t *dev) { dev->port.node_due_us = 0; }

static void canola_py_dev_set_quiet(canola_py_dev_t *dev, bool quiet) { dev->quiet = quiet; }

/* Application access: no access rights; writes take the node's path (limits, service
 * checks, event-driven TPDOs mapping the entry). */
static co_abort_t canola_py_app_read(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                                     uint32_t cap, uint32_t *len, uint8_t *type)
{
    co_abort_t abort;
    const co_od_entry_t *e = co_od_find(&node->cfg.od, index, sub, &abort);
    if (!e) {
        return abort;
    }
    *type = e->type;
    uint32_t total = 0;
    abort = co_od_read(&node->cfg.od, e, 0, buf, cap, len, &total);
    if (abort == CO_ABORT_NONE && total != CO_OD_SIZE_UNKNOWN && total > *len) {
        return CO_ABORT_LEN_HIGH;
    }
    return abort;
}

static co_abort_t canola_py_app_write(co_node_t *node, uint16_t index, uint8_t sub,
                                      const uint8_t *data, uint32_t len)
{
    co_abort_t abort;
    const co_od_entry_t *e = co_od_find(&node->cfg.od, index, sub, &abort);
    return e ? co_node_write_entry(node, e, data, len) : abort;
}

static int canola_py_entry_key(const co_od_entry_t *entry)
{
    return (int)((uint32_t)entry->index << 8 | entry->sub);
}
"""

# ---------------------------------------------------------------------------------------
# Issue 7 (py302 branch): LSS master (CiA 305), CANopen manager (CiA 302-2) and program
# download (CiA 302-3). One self-contained block: cdefs of lss.h, manager.h, program.h and
# the helpers canola.lss / canola.manager / canola.program use. The core builds them with
# CO_CONFIG_LSS_MASTER, CO_CONFIG_LSS_SLAVE and CO_CONFIG_MANAGER (all 1 by default).

CDEF += """
typedef struct co_lss_address { uint32_t vendor; uint32_t product; uint32_t revision;
                                uint32_t serial; } co_lss_address_t;
typedef struct co_lss_result { uint8_t cs; uint8_t status; uint8_t error; uint8_t spec_error;
                               uint32_t value; uint16_t answers; bool keeps_answering;
                               co_lss_address_t address; ...; } co_lss_result_t;
typedef struct co_lss_fastscan { co_lss_address_t address; uint8_t known; ...; }
    co_lss_fastscan_t;
typedef void (*co_lss_done_fn)(void *ctx, const co_lss_result_t *result);
typedef enum co_lss_mode { CO_LSS_WAITING, CO_LSS_CONFIGURATION, ... } co_lss_mode_t;
typedef enum co_lss_status { CO_LSS_OK, CO_LSS_TIMEOUT, CO_LSS_REFUSED, CO_LSS_SCAN_FAILED,
                             CO_LSS_CANCELLED, ... } co_lss_status_t;
#define CO_LSS_CS_INQUIRE_VENDOR ...
#define CO_LSS_CS_INQUIRE_PRODUCT ...
#define CO_LSS_CS_INQUIRE_REVISION ...
#define CO_LSS_CS_INQUIRE_SERIAL ...
#define CO_LSS_CS_INQUIRE_NODE_ID ...
#define CO_NODE_ID_UNCONFIGURED ...
co_err_t co_lss_master_set_timeout(co_node_t *node, uint32_t timeout_ms);
bool co_lss_master_busy(const co_node_t *node);
co_err_t co_lss_master_cancel(co_node_t *node);
co_err_t co_lss_switch_global(co_node_t *node, co_lss_mode_t mode);
co_err_t co_lss_switch_selective(co_node_t *node, const co_lss_address_t *address,
                                 co_lss_done_fn done, void *ctx);
co_err_t co_lss_configure_node_id(co_node_t *node, uint8_t node_id, co_lss_done_fn done,
                                  void *ctx);
co_err_t co_lss_store(co_node_t *node, co_lss_done_fn done, void *ctx);
co_err_t co_lss_inquire(co_node_t *node, uint8_t cs, co_lss_done_fn done, void *ctx);
co_err_t co_lss_identify_non_configured(co_node_t *node, co_lss_done_fn done, void *ctx);
co_err_t co_lss_fastscan(co_node_t *node, const co_lss_fastscan_t *scan, co_lss_done_fn done,
                         void *ctx);
const char *co_lss_status_name(uint8_t status);
co_lss_mode_t co_lss_slave_mode(const co_node_t *node);

#define CO_MGR_NMT_MASTER ...
#define CO_MGR_START_ALL ...
#define CO_MGR_NO_SELF_START ...
#define CO_MGR_NO_SLAVE_START ...
#define CO_MGR_SLAVE ...
#define CO_MGR_BOOT_ON_BOOTUP ...
#define CO_MGR_MANDATORY ...
#define CO_MGR_KEEP_ALIVE ...
typedef enum co_mgr_event_kind { CO_MGR_BOOTED = 1, CO_MGR_STARTED, CO_MGR_FAILED,
    CO_MGR_LOST, CO_MGR_NETWORK_STARTED, CO_MGR_NETWORK_HALTED, ... } co_mgr_event_kind_t;
typedef enum co_mgr_slave_state { CO_MGR_UNLISTED, CO_MGR_WAITING, CO_MGR_BOOTING,
    CO_MGR_CONFIGURED, CO_MGR_RUNNING, CO_MGR_FAILED_STATE, CO_MGR_MISSING,
    ... } co_mgr_slave_state_t;
typedef struct co_mgr_event { uint8_t node_id; uint8_t kind; uint8_t reason; uint8_t sub;
                              uint16_t index; uint32_t abort; uint32_t value; ...; }
    co_mgr_event_t;
typedef struct co_mgr_slave { uint32_t assignment; uint32_t device_type; uint32_t vendor;
    uint32_t product; uint32_t revision; uint32_t serial; const uint8_t *dcf; uint32_t dcf_len;
    uint32_t config_date; uint32_t config_time; uint16_t heartbeat_ms; ...; } co_mgr_slave_t;
typedef struct co_manager_config { uint32_t nmt_startup; const co_mgr_slave_t *slaves;
    uint8_t sdo_channel; bool reset_slaves;
    void (*on_event)(void *ctx, const co_mgr_event_t *event); void *ctx; ...; }
    co_manager_config_t;
typedef struct co_manager { ...; } co_manager_t;
co_err_t co_manager_init(co_manager_t *mgr, co_node_t *node, const co_manager_config_t *config);
co_err_t co_manager_start(co_manager_t *mgr);
int co_manager_slave_state(const co_manager_t *mgr, uint8_t node_id);
int co_manager_slave_reason(const co_manager_t *mgr, uint8_t node_id);
bool co_manager_network_started(const co_manager_t *mgr);
const char *co_boot_reason_text(uint8_t reason);
const char *co_mgr_event_name(uint8_t kind);
co_err_t co_dcf_check(const uint8_t *dcf, uint32_t len);

typedef enum co_flash_stage { CO_FLASH_STAGE_STOP = 1, CO_FLASH_STAGE_CLEAR,
    CO_FLASH_STAGE_DATA, CO_FLASH_STAGE_START, CO_FLASH_STAGE_VERIFY, CO_FLASH_STAGE_DONE,
    ... } co_flash_stage_t;
typedef struct co_flash_result { uint8_t stage; bool ident_ok; co_abort_t abort; uint32_t ident;
                                 uint32_t bytes; ...; } co_flash_result_t;
typedef struct co_flash_request { uint8_t channel; uint8_t server; uint8_t program; bool clear;
    bool check_ident; uint32_t ident; const uint8_t *data; uint32_t len;
    void (*progress)(void *ctx, uint32_t done, uint32_t total);
    void (*done)(void *ctx, const co_flash_result_t *result); void *ctx; ...; }
    co_flash_request_t;
typedef struct co_flash { uint8_t stage; ...; } co_flash_t;
co_err_t co_flash_start(co_flash_t *flash, co_node_t *node, const co_flash_request_t *request);
const char *co_flash_stage_name(uint8_t stage);

/* helpers: the device side of program download on a canola.Device (preamble below) */
typedef struct canola_py_prog canola_py_prog_t;
canola_py_prog_t *canola_py_prog_new(co_od_entry_t *entries, uint32_t count, uint8_t program,
                                     bool running, uint32_t ident, void *handle);
void canola_py_prog_free(canola_py_prog_t *p);
void canola_py_prog_set_ident(canola_py_prog_t *p, uint32_t ident);
uint32_t canola_py_prog_ident(const canola_py_prog_t *p);
uint32_t canola_py_prog_status(const canola_py_prog_t *p);
uint8_t canola_py_prog_state(const canola_py_prog_t *p);
uint32_t canola_py_sdo_client_done(const co_node_t *node, uint8_t channel);

extern "Python" void canola_py_mgr_event(void *ctx, const co_mgr_event_t *event);
extern "Python" void canola_py_lss_done(void *ctx, const co_lss_result_t *result);
extern "Python" void canola_py_flash_progress(void *ctx, uint32_t done, uint32_t total);
extern "Python" void canola_py_flash_done(void *ctx, const co_flash_result_t *result);
extern "Python" co_abort_t canola_py_prog_write(void *ctx, uint32_t offset, const uint8_t *data,
                                                uint32_t n, uint32_t total, bool last);
extern "Python" co_abort_t canola_py_prog_control(void *ctx, uint8_t command);
"""

PREAMBLE += r"""
#include <stddef.h>

/* Program download, device side, on a canola.Device: the node's hook_ctx is the Python
 * engine, so the entries 0x1F50/51/56/57 get hooks of their own that find their
 * co_program_t from the hooks pointer, and the program's callbacks go to Python. */
static co_abort_t canola_py_prog_write(void *ctx, uint32_t offset, const uint8_t *data,
                                       uint32_t n, uint32_t total, bool last);
static co_abort_t canola_py_prog_control(void *ctx, uint8_t command);

typedef struct canola_py_prog {
    co_od_hooks_t data, control, ident, status;
    co_program_t prog;
} canola_py_prog_t;

#define CANOLA_PY_PROG(entry, member) \
    ((canola_py_prog_t *)(void *)((char *)(entry)->hooks - offsetof(canola_py_prog_t, member)))

static co_abort_t canola_py_prog_data_w(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                        const uint8_t *data, uint32_t n, uint32_t total,
                                        bool last)
{
    (void)ctx;
    return co_program_data_hooks.write(&CANOLA_PY_PROG(e, data)->prog, e, offset, data, n,
                                       total, last);
}

static co_abort_t canola_py_prog_control_w(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                           const uint8_t *data, uint32_t n, uint32_t total,
                                           bool last)
{
    (void)ctx;
    return co_program_control_hooks.write(&CANOLA_PY_PROG(e, control)->prog, e, offset, data,
                                          n, total, last);
}

static co_abort_t canola_py_prog_control_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                           uint8_t *buf, uint32_t cap, uint32_t *n,
                                           uint32_t *total)
{
    (void)ctx;
    return co_program_control_hooks.read(&CANOLA_PY_PROG(e, control)->prog, e, offset, buf,
                                         cap, n, total);
}

static co_abort_t canola_py_prog_ident_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                         uint8_t *buf, uint32_t cap, uint32_t *n,
                                         uint32_t *total)
{
    (void)ctx;
    return co_program_ident_hooks.read(&CANOLA_PY_PROG(e, ident)->prog, e, offset, buf, cap,
                                       n, total);
}

static co_abort_t canola_py_prog_status_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                          uint8_t *buf, uint32_t cap, uint32_t *n,
                                          uint32_t *total)
{
    (void)ctx;
    return co_program_status_hooks.read(&CANOLA_PY_PROG(e, status)->prog, e, offset, buf, cap,
                                        n, total);
}

/* Hook program `program` (sub-index of 0x1F50/51/56/57) of the entries; NULL when 0x1F50
 * or 0x1F51 lacks that sub-index (or no memory). The entries keep pointing to the result:
 * free it only with them. */
static canola_py_prog_t *canola_py_prog_new(co_od_entry_t *entries, uint32_t count,
                                            uint8_t program, bool running, uint32_t ident,
                                            void *handle)
{
    bool data = false, control = false;
    for (uint32_t i = 0; i < count; i++) {
        if (entries[i].sub == program) {
            data = data || entries[i].index == 0x1F50;
            control = control || entries[i].index == 0x1F51;
        }
    }
    canola_py_prog_t *p = data && control ? calloc(1, sizeof *p) : NULL;
    if (!p) {
        return NULL;
    }
    co_program_app_t app = {.write = canola_py_prog_write, .control = canola_py_prog_control,
                            .ctx = handle};
    co_program_init(&p->prog, &app, running, ident);
    p->data.write = canola_py_prog_data_w;
    p->control.read = canola_py_prog_control_r;
    p->control.write = canola_py_prog_control_w;
    p->ident.read = canola_py_prog_ident_r;
    p->status.read = canola_py_prog_status_r;
    for (uint32_t i = 0; i < count; i++) {
        co_od_entry_t *e = &entries[i];
        const co_od_hooks_t *h = NULL;
        if (e->sub != program) {
            continue;
        }
        switch (e->index) {
        case 0x1F50: h = &p->data; e->size = 0xFFFFFFFFu; break; /* streamed, any size */
        case 0x1F51: h = &p->control; break;
        case 0x1F56: h = &p->ident; break;
        case 0x1F57: h = &p->status; break;
        default: continue;
        }
        e->hooks = h;
        e->value = NULL;
        e->dflt = NULL;
    }
    return p;
}

static void canola_py_prog_free(canola_py_prog_t *p) { free(p); }
static void canola_py_prog_set_ident(canola_py_prog_t *p, uint32_t ident)
{
    co_program_set_ident(&p->prog, ident);
}
static uint32_t canola_py_prog_ident(const canola_py_prog_t *p) { return p->prog.ident; }
static uint32_t canola_py_prog_status(const canola_py_prog_t *p) { return p->prog.status; }
static uint8_t canola_py_prog_state(const canola_py_prog_t *p) { return p->prog.state; }

/* Bytes a client channel's transfer has moved so far (the server acknowledged, for a block
 * download): program download progress sampled by the waiting thread. */
static uint32_t canola_py_sdo_client_done(const co_node_t *node, uint8_t channel)
{
    return channel < CO_SDO_CLIENTS_MAX ? node->sdo_clients[channel].done : 0;
}
"""
# ---- end of the issue 7 block

# ---------------------------------------------------------------------------------------
# Streamed DOMAIN entries of a canola.Device (canola.domain.DomainStream): one
# self-contained block. The entry gets read/write hooks of its own that hand each piece to
# Python, so it holds any size (no co_od_domain_t buffer, no CO_SDO_BUF_SIZE limit); the
# node's "written" hook stays (on_write callbacks).

CDEF += """
typedef struct canola_py_stream canola_py_stream_t;
canola_py_stream_t *canola_py_stream_new(co_od_entry_t *entries, uint32_t count,
                                         uint16_t index, uint8_t sub, void *handle);
void canola_py_stream_free(canola_py_stream_t *s);
extern "Python" co_abort_t canola_py_stream_read(void *handle, uint32_t offset, uint8_t *buf,
                                                 uint32_t cap, uint32_t *n, uint32_t *total);
extern "Python" co_abort_t canola_py_stream_write(void *handle, uint32_t offset,
                                                  const uint8_t *data, uint32_t n,
                                                  uint32_t total, bool last);
"""

PREAMBLE += r"""
static co_abort_t canola_py_stream_read(void *handle, uint32_t offset, uint8_t *buf,
                                        uint32_t cap, uint32_t *n, uint32_t *total);
static co_abort_t canola_py_stream_write(void *handle, uint32_t offset, const uint8_t *data,
                                         uint32_t n, uint32_t total, bool last);

typedef struct canola_py_stream {
    co_od_hooks_t hooks; /* first: the entry's hooks pointer is the stream */
    void *handle;
} canola_py_stream_t;

static co_abort_t canola_py_stream_r(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                     uint8_t *buf, uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    return canola_py_stream_read(((const canola_py_stream_t *)(const void *)e->hooks)->handle,
                                 offset, buf, cap, n, total);
}

static co_abort_t canola_py_stream_w(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                     const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)ctx;
    return canola_py_stream_write(((const canola_py_stream_t *)(const void *)e->hooks)->handle,
                                  offset, data, n, total, last);
}

/* Stream DOMAIN entry (index, sub) through Python; NULL when the entry is missing, not a
 * DOMAIN, or no memory. The entry keeps pointing to the result: free it only with it. */
static canola_py_stream_t *canola_py_stream_new(co_od_entry_t *entries, uint32_t count,
                                                uint16_t index, uint8_t sub, void *handle)
{
    for (uint32_t i = 0; i < count; i++) {
        co_od_entry_t *e = &entries[i];
        if (e->index != index || e->sub != sub) {
            continue;
        }
        if (e->type != CO_TYPE_DOMAIN) {
            return NULL;
        }
        canola_py_stream_t *s = calloc(1, sizeof *s);
        if (!s) {
            return NULL;
        }
        s->hooks.read = canola_py_stream_r;
        s->hooks.write = canola_py_stream_w;
        s->hooks.written = e->hooks ? e->hooks->written : NULL;
        s->handle = handle;
        e->hooks = &s->hooks;
        e->value = NULL;
        e->dflt = NULL;
        e->size = 0xFFFFFFFFu; /* streamed, any size */
        return s;
    }
    return NULL;
}

static void canola_py_stream_free(canola_py_stream_t *s) { free(s); }
"""
# ---- end of the streamed DOMAIN block

ffibuilder = cffi.FFI()
ffibuilder.cdef(CDEF)
ffibuilder.set_source(
    "canola._core",
    PREAMBLE,
    # Absolute paths: the objects go under the build's own temporary folder (relative ones
    # climb out of it, to /tmp/src, shared by every checkout built at the same time).
    sources=_SOURCES,
    include_dirs=[_rel(p) for p in _INCLUDES],
    define_macros=_CONFIG,
    # A header change rebuilds the extension (setuptools only compares sources otherwise).
    depends=[_rel(p) for p in _HEADERS],
)

if __name__ == "__main__":
    ffibuilder.compile(verbose=True)
