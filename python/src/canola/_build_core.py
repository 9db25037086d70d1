# SPDX-License-Identifier: Apache-2.0
"""cffi builder of ``canola._core``: the C core of the repository plus the simulated bus.

API mode (a compiled extension). Used by setuptools through ``cffi_modules`` in
``python/setup.py``; can also be run by hand (``python src/canola/_build_core.py``) to build
the module in place. The C sources are the repository's own (``../src``, ``../port/sim``,
and the binding's C side ``../port/python``), found relative to this file, so it builds
from a checkout (an editable install, ``pip install python``, ``python -m build python``);
an sdist carries a copy of them in ``csrc/`` (``c_files``, copied by ``python/setup.py``),
where they are looked for first. This script only declares (CDEF: what Python may call,
and the callbacks cffi defines, ``extern "Python+C"``) and builds; every line of C is in
those folders.
"""

from __future__ import annotations

import glob
import os
import re

import cffi  # type: ignore[import-untyped]

_HERE = os.path.dirname(os.path.abspath(__file__))
_PROJECT = os.path.normpath(os.path.join(_HERE, "..", ".."))  # python/, or an unpacked sdist
_SDIST_C = os.path.join(_PROJECT, "csrc")
_ROOT = _SDIST_C if os.path.isdir(_SDIST_C) else os.path.dirname(_PROJECT)


def version() -> str:
    """canola's version, as include/canola/version.h writes it (the one place it is kept)."""
    with open(os.path.join(_ROOT, "include", "canola", "version.h"), encoding="utf-8") as f:
        found = re.search(r'^#define CANOLA_VERSION "([0-9]+\.[0-9]+\.[0-9]+)"', f.read(), re.M)
    if found is None:
        raise RuntimeError("include/canola/version.h: no CANOLA_VERSION \"X.Y.Z\" line")
    return found.group(1)


def _rel(path: str) -> str:
    """``path`` relative to the working directory (setuptools runs in ``python/``)."""
    return os.path.relpath(path)


_SOURCES = [
    *sorted(glob.glob(os.path.join(_ROOT, "src", "*.c"))),
    *sorted(glob.glob(os.path.join(_ROOT, "port", "python", "*.c"))),
    os.path.join(_ROOT, "port", "sim", "sim.c"),
    os.path.join(_ROOT, "port", "sim", "sim_storage.c"),
    os.path.join(_ROOT, "port", "linux", "file_storage.c"),
]
_INCLUDES = [os.path.join(_ROOT, "include"), os.path.join(_ROOT, "src"),
             os.path.join(_ROOT, "port", "python"),
             os.path.join(_ROOT, "port", "sim"), os.path.join(_ROOT, "port", "linux")]
# Headers and the tables the sources include (src/crc16_tables.inc): an sdist needs them all.
_HEADERS = [p for d in _INCLUDES for pattern in ("*.h", "*.inc")
            for p in sorted(glob.glob(os.path.join(d, "**", pattern), recursive=True))]


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
typedef enum co_reset { CO_RESET_APPLICATION, CO_RESET_COMMUNICATION, ... } co_reset_t;
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
                             CO_NODE_ERR_STORE_FAILED, CO_NODE_ERR_SDO_COB_FIXED,
                             ... } co_node_error_t;
typedef enum co_param_group { CO_PARAMS_COMMUNICATION, CO_PARAMS_APPLICATION,
                              ... } co_param_group_t;
typedef enum co_store_fault { CO_STORE_INTACT, CO_STORE_NONE, CO_STORE_BAD_HEADER,
                              CO_STORE_BAD_LENGTH, CO_STORE_BAD_CRC, CO_STORE_BAD_RECORDS,
                              CO_STORE_READ_ERROR, ... } co_store_fault_t;
#define CO_EMCY_STORE_REJECTED ...
#define CO_EMCY_STORE_FAILED ...
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
co_abort_t co_node_write_app(co_node_t *node, uint16_t index, uint8_t sub, const uint8_t *data,
                             uint32_t len);
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
uint32_t co_sdo_client_progress(const co_node_t *node, uint8_t channel);

co_err_t co_sim_run_until(co_sim_bus_t *bus, uint64_t until_us);
void co_sim_set_trace(co_sim_bus_t *bus, co_sim_trace_fn fn, void *ctx);
double co_sim_load(const co_sim_bus_t *bus);

/* helpers of the binding (port/python/canola_py.h) */
typedef struct canola_py_dev canola_py_dev_t;
typedef struct canola_py_link canola_py_link_t;
canola_py_dev_t *canola_py_dev_new(co_sim_bus_t *bus, canola_py_link_t *link,
                                   co_od_entry_t *entries, uint32_t count, uint8_t node_id,
                                   uint16_t sdo_timeout_ms, const char *store_dir, bool raw_port,
                                   void *user, co_err_t *err);
void canola_py_dev_free(canola_py_dev_t *dev);
co_node_t *canola_py_dev_node(canola_py_dev_t *dev);
co_err_t canola_py_stored_node_id(const char *store_dir, uint8_t *node_id);
void canola_py_dev_touch(canola_py_dev_t *dev);
void canola_py_dev_set_quiet(canola_py_dev_t *dev, bool quiet);
bool canola_py_dev_sent_abort(const canola_py_dev_t *dev, uint32_t cob_id);
void canola_py_dev_set_active(canola_py_dev_t *dev, bool active);
void canola_py_dev_set_raw(canola_py_dev_t *dev, bool raw);
void canola_py_dev_set_sent(canola_py_dev_t *dev, bool sent);
#define CANOLA_PY_LINK_FRAMES ...
#define CANOLA_PY_LINK_DEVS ...
struct canola_py_link { co_frame_t frames[...]; uint32_t count; uint32_t dev_count;
                        uint64_t due_us; ...; };
canola_py_link_t *canola_py_link_new(void);
void canola_py_link_free(canola_py_link_t *link);
void canola_py_link_detach(canola_py_link_t *link, canola_py_dev_t *dev);
void canola_py_link_ingest(canola_py_link_t *link, uint64_t now_us, const co_frame_t *frame);
uint64_t canola_py_link_poll(canola_py_link_t *link, uint64_t now_us);
uint32_t canola_py_link_run(canola_py_link_t *link, uint64_t now_us);
bool canola_py_link_clear(canola_py_link_t *link);
co_abort_t canola_py_app_read(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                              uint32_t cap, uint32_t *len, uint8_t *type);
co_abort_t canola_py_dev_write(canola_py_dev_t *dev, uint16_t index, uint8_t sub,
                               const uint8_t *data, uint32_t len);
int canola_py_sdo_client_server(const co_node_t *node, uint8_t channel);
co_sim_bus_t *canola_py_bus_new(uint32_t bitrate);
void canola_py_bus_free(co_sim_bus_t *bus);
uint64_t canola_py_bus_now(const co_sim_bus_t *bus);
long canola_py_live_allocs(void);

/* callbacks into Python */
extern "Python+C" void canola_py_trace(void *ctx, const char *line);
extern "Python+C" void canola_py_sdo_done(void *ctx, uint8_t channel, co_abort_t abort,
                                        uint32_t len);
extern "Python+C" void canola_py_on_state(void *user, co_nmt_state_t state);
extern "Python+C" void canola_py_on_reset(void *user, co_reset_t what);
extern "Python+C" void canola_py_on_errctl(void *user, const co_ec_event_t *event);
extern "Python+C" void canola_py_on_error(void *user, co_node_error_t error);
extern "Python+C" void canola_py_on_emcy(void *user, const co_emcy_msg_t *emcy);
extern "Python+C" void canola_py_on_sync(void *user, uint8_t counter);
extern "Python+C" void canola_py_on_time(void *user, const co_time_of_day_t *time);
extern "Python+C" void canola_py_on_rpdo(void *user, uint16_t rpdo);
typedef enum canola_py_origin { CANOLA_PY_BY_NETWORK = 0, CANOLA_PY_BY_APP = 1
} canola_py_origin_t;
extern "Python+C" void canola_py_written(void *user, const co_od_entry_t *entry,
                                       canola_py_origin_t origin);
extern "Python+C" void canola_py_raw_rx(void *ctx, uint64_t now_us, const co_frame_t *frame);
extern "Python+C" void canola_py_sent(void *ctx, const co_frame_t *frame);
"""


# LSS master (CiA 305), CANopen manager (CiA 302-2) and program download (CiA 302-3):
# lss.h, manager.h, program.h and the helpers canola.lss / canola.manager / canola.program
# use. The core builds them with CO_CONFIG_LSS_MASTER, CO_CONFIG_LSS_SLAVE and
# CO_CONFIG_MANAGER (all 1 by default).

CDEF += """
typedef struct co_lss_address { uint32_t vendor; uint32_t product; uint32_t revision;
                                uint32_t serial; } co_lss_address_t;
typedef struct co_lss_result { uint8_t cs; uint8_t status; uint8_t error; uint8_t spec_error;
                               uint32_t value; uint16_t answers; bool keeps_answering;
                               co_lss_address_t address; ...; } co_lss_result_t;
typedef struct co_lss_fastscan { co_lss_address_t address; uint8_t known; bool above;
                                  ...; }
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

/* helpers: the device side of program download on a canola.Device */
typedef struct canola_py_prog canola_py_prog_t;
canola_py_prog_t *canola_py_prog_new(co_od_entry_t *entries, uint32_t count, uint8_t program,
                                     bool running, uint32_t ident, void *handle);
void canola_py_prog_free(canola_py_prog_t *p);
void canola_py_prog_set_ident(canola_py_prog_t *p, uint32_t ident);
uint32_t canola_py_prog_ident(const canola_py_prog_t *p);
uint32_t canola_py_prog_status(const canola_py_prog_t *p);
uint8_t canola_py_prog_state(const canola_py_prog_t *p);

extern "Python+C" void canola_py_mgr_event(void *ctx, const co_mgr_event_t *event);
extern "Python+C" void canola_py_lss_done(void *ctx, const co_lss_result_t *result);
extern "Python+C" void canola_py_flash_progress(void *ctx, uint32_t done, uint32_t total);
extern "Python+C" void canola_py_flash_done(void *ctx, const co_flash_result_t *result);
extern "Python+C" co_abort_t canola_py_prog_write(void *ctx, uint32_t offset, const uint8_t *data,
                                                uint32_t n, uint32_t total, bool last);
extern "Python+C" co_abort_t canola_py_prog_control(void *ctx, uint8_t command);
"""


# Streamed DOMAIN entries of a canola.Device (canola.domain.DomainStream).

CDEF += """
typedef struct canola_py_stream canola_py_stream_t;
canola_py_stream_t *canola_py_stream_new(co_od_entry_t *entries, uint32_t count,
                                         uint16_t index, uint8_t sub, void *handle);
void canola_py_stream_free(canola_py_stream_t *s);
extern "Python+C" co_abort_t canola_py_stream_read(void *handle, uint32_t offset, uint8_t *buf,
                                                 uint32_t cap, uint32_t *n, uint32_t *total);
extern "Python+C" co_abort_t canola_py_stream_write(void *handle, uint32_t offset,
                                                  const uint8_t *data, uint32_t n,
                                                  uint32_t total, bool last);
"""


ffibuilder = cffi.FFI()
ffibuilder.cdef(CDEF)
ffibuilder.set_source(
    "canola._core",
    '#include "canola_py.h"\n',
    # Absolute paths: the objects go under the build's own temporary folder (relative ones
    # climb out of it, to /tmp/src, shared by every checkout built at the same time).
    sources=_SOURCES,
    include_dirs=[_rel(p) for p in _INCLUDES],
    define_macros=_CONFIG,
    # A header change rebuilds the extension (setuptools only compares sources otherwise).
    depends=[_rel(p) for p in _HEADERS],
)


# ---------------------------------------------------------------------------------------
# The typed view of the compiled module for mypy (_core.pyi), written from the CDEF above:
# every function with its arguments' Python types, every constant an int. The tests check
# that the file in the package is this text (regenerate: python _build_core.py --stub).

_STUB_HEAD = '''# SPDX-License-Identifier: Apache-2.0
# Generated by _build_core.py (--stub) from its CDEF: do not edit.
# ruff: noqa: E501
# The typed view of the cffi extension canola._core; only canola._c imports it.
from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

class CData:
    """A C value or pointer (cffi's cdata)."""
    def __getattr__(self, name: str) -> Any: ...
    def __setattr__(self, name: str, value: Any) -> None: ...
    def __getitem__(self, index: int | slice) -> Any: ...
    def __setitem__(self, index: int | slice, value: Any) -> None: ...
    def __len__(self) -> int: ...
    def __bool__(self) -> bool: ...

class FFI:
    NULL: CData
    def new(self, cdecl: str, init: Any = ...) -> CData: ...
    def new_handle(self, obj: object) -> CData: ...
    def from_handle(self, handle: CData) -> Any: ...
    def buffer(self, cdata: CData, size: int = ...) -> Any: ...
    def string(self, cdata: CData, maxlen: int = ...) -> bytes: ...
    def memmove(self, dest: CData | Any, src: CData | bytes | Any, n: int) -> None: ...
    def gc(self, cdata: CData, destructor: Callable[[CData], None] | CData) -> CData: ...
    def sizeof(self, cdecl: str | CData) -> int: ...
    def offsetof(self, cdecl: str, field: str) -> int: ...
    def cast(self, cdecl: str, value: Any) -> CData: ...
    def def_extern(self, name: str = ..., error: Any = ...,
                   onerror: Callable[..., Any] | None = ...) -> Callable[[F], F]: ...

ffi: FFI

class Lib:
'''


def _py_type(t: object, *, arg: bool) -> str:
    from cffi import model  # noqa: PLC0415

    if isinstance(t, model.VoidType):
        return "None"
    if isinstance(t, model.PrimitiveType):
        name = t.name
        return "bool" if name == "_Bool" else "float" if name in ("float", "double") else \
            "bytes" if name == "char" else "int"
    if isinstance(t, model.EnumType):
        return "int"
    if isinstance(t, model.PointerType) and arg:
        target = t.totype
        if isinstance(target, model.VoidType) or (isinstance(target, model.PrimitiveType)
                                                  and target.name in ("uint8_t", "char")):
            return "CData | bytes"
    return "CData"


def stub_text() -> str:
    """The text of _core.pyi for the CDEF."""
    lines = [_STUB_HEAD.rstrip("\n")]
    functions, constants = [], set()
    for key, (decl, _) in sorted(ffibuilder._parser._declarations.items()):
        kind, _, name = key.partition(" ")
        if kind == "function":
            args = ", ".join(f"a{i}: {_py_type(a, arg=True)}" for i, a in enumerate(decl.args))
            functions.append(f"    def {name}(self{', ' if args else ''}{args}, /) -> "
                             f"{_py_type(decl.result, arg=False)}: ...")
        elif kind in ("macro", "extern_python_plus_c"):
            constants.add((name, "int" if kind == "macro" else "CData"))
        elif kind == "enum":
            constants.update((e, "int") for e in decl.enumerators)
    lines += [f"    {name}: {kind}" for name, kind in sorted(constants)]
    lines += functions
    return "\n".join([*lines, "", "lib: Lib", ""])


if __name__ == "__main__":
    import sys

    if sys.argv[1:] == ["--stub"]:
        with open(os.path.join(_HERE, "_core.pyi"), "w") as out:
            out.write(stub_text())
    else:
        ffibuilder.compile(verbose=True)
