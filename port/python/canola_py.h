/* SPDX-License-Identifier: Apache-2.0 */
/* The binding layer between the core and the Python package (canola._core, built by
 * python/src/canola/_build_core.py with cffi): what Python allocates, and the C ends of
 * the callbacks that go to Python.
 *
 * The core never allocates; these helpers do (one block per bus, link, node, program or
 * stream, through canola_py_alloc, which counts them), which is what a binding layer is
 * allowed to do. Every function here is
 * declared again, for cffi, in _build_core.py's CDEF.
 *
 * One kind of node, canola_py_dev_t (canola.Device, canola.Master, canola.simnode.Node):
 * every callback routed to Python, on a simulated bus or on a python-can bus through a
 * link (canola_py_link_t), which joins the devs on one python-can bus object: a frame one
 * of them sends is delivered to the others in C, at once, and queued for python-can. */
#ifndef CANOLA_PY_H
#define CANOLA_PY_H

#include "canola/canola.h"
#include "canola/file_storage.h"
#include "canola/sim.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* ---- callbacks into Python (cffi defines them: extern "Python+C" in the CDEF) */

void canola_py_trace(void *ctx, const char *line);
void canola_py_sdo_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len);
void canola_py_on_state(void *user, co_nmt_state_t state);
void canola_py_on_reset(void *user, co_reset_t what);
void canola_py_on_errctl(void *user, const co_ec_event_t *event);
void canola_py_on_error(void *user, co_node_error_t error);
void canola_py_on_emcy(void *user, const co_emcy_msg_t *emcy);
void canola_py_on_sync(void *user, uint8_t counter);
void canola_py_on_time(void *user, const co_time_of_day_t *time);
void canola_py_on_rpdo(void *user, uint16_t rpdo);
/* Who wrote an entry (canola_py_written): the network (an SDO server, an RPDO, the
 * services) or the application through canola_py_dev_write. */
typedef enum canola_py_origin { CANOLA_PY_BY_NETWORK = 0, CANOLA_PY_BY_APP = 1 } canola_py_origin_t;
void canola_py_written(void *user, const co_od_entry_t *entry, canola_py_origin_t origin);
void canola_py_raw_rx(void *ctx, uint64_t now_us, const co_frame_t *frame);
void canola_py_sent(void *ctx, const co_frame_t *frame);
co_abort_t canola_py_prog_write(void *ctx, uint32_t offset, const uint8_t *data, uint32_t n,
                                uint32_t total, bool last);
co_abort_t canola_py_prog_control(void *ctx, uint8_t command);
co_abort_t canola_py_stream_read(void *handle, uint32_t offset, uint8_t *buf, uint32_t cap,
                                 uint32_t *n, uint32_t *total);
co_abort_t canola_py_stream_write(void *handle, uint32_t offset, const uint8_t *data, uint32_t n,
                                  uint32_t total, bool last);

/* ---- memory (py_alloc.c): every allocation of this layer, counted */

/* calloc(1, size) / free(p), counting the blocks alive: a leak of the binding shows as a
 * count that does not come back (canola_py_live_allocs, read by the tests). */
void *canola_py_alloc(size_t size);
void canola_py_release(void *p);
long canola_py_live_allocs(void);

/* ---- the simulated bus (py_sim.c) */

co_sim_bus_t *canola_py_bus_new(uint32_t bitrate);
void canola_py_bus_free(co_sim_bus_t *bus);
uint64_t canola_py_bus_now(const co_sim_bus_t *bus);

/* ---- canola.Device / canola.Master (py_dev.c) */

typedef struct canola_py_link canola_py_link_t;

/* canola_py_dev_t.abort_sent_id: the last frame sent was no SDO abort. */
#define CANOLA_PY_NO_ABORT 0xFFFFFFFFu

/* Frames a dev sent on the simulated bus that its raw port has not seen come back. */
#define CANOLA_PY_OWN_FRAMES 64

typedef struct canola_py_dev {
    co_node_t node;
    co_sim_port_t port;
    co_sim_port_t raw;
    co_file_storage_t fs;
    co_od_hooks_t hooks;
    void *user;
    bool sim;         /* on the simulated bus, else on a link (python-can) */
    bool quiet;       /* a tool, not a network member: no boot-up, heartbeat or guarding answer */
    bool raw_frames;  /* on a link: the frames of the others go to canola_py_raw_rx too */
    bool active;      /* on a link: receives and is polled (canola.Device.start .. stop) */
    bool sent_frames; /* every frame the node puts on the bus goes to canola_py_sent too */
    canola_py_link_t *link;
    /* the COB-ID of the last frame the node sent when that frame was an SDO abort, else
     * CANOLA_PY_NO_ABORT (canola_py_dev_sent_abort) */
    uint32_t abort_sent_id;
    uint32_t app_writes; /* canola_py_dev_write calls in progress (they may nest) */
    /* the raw port skips the node's own frames (python-can does not hand a bus its own
     * frames either) */
    co_frame_t own[CANOLA_PY_OWN_FRAMES];
    uint32_t own_head, own_count;
} canola_py_dev_t;

/* A node with every callback routed to Python (`user` is the Python object's handle), on
 * the simulated bus `bus` (with a raw port that sees every frame when `raw_port`), or
 * attached to `link` (bus NULL; under the link's lock). NULL with *err set, nothing kept,
 * when out of memory, the storage folder fails or the link is full (CO_ERR_FULL, with
 * CANOLA_PY_LINK_DEVS devs on it); otherwise *err is co_node_init's result (the dev must
 * then be kept, not used, and freed with canola_py_dev_free). */
canola_py_dev_t *canola_py_dev_new(co_sim_bus_t *bus, canola_py_link_t *link,
                                   co_od_entry_t *entries, uint32_t count, uint8_t node_id,
                                   uint16_t sdo_timeout_ms, const char *store_dir, bool raw_port,
                                   void *user, co_err_t *err);
void canola_py_dev_free(canola_py_dev_t *dev);
co_node_t *canola_py_dev_node(canola_py_dev_t *dev);
/* The node-ID an LSS store configuration left in `store_dir` (canola/file_storage.h):
 * CO_OK with *node_id set, CO_ERR_NOT_FOUND (none), CO_ERR_STATE (lss.params damaged), or
 * CO_ERR_ARG (not a folder). */
co_err_t canola_py_stored_node_id(const char *store_dir, uint8_t *node_id);
/* The application changed the node between two runs of the simulated bus: poll it at the
 * next instant the bus runs (its deadline may have moved). */
void canola_py_dev_touch(canola_py_dev_t *dev);
void canola_py_dev_set_quiet(canola_py_dev_t *dev, bool quiet);
/* Every frame the node puts on the bus (the simulated bus or its link) goes to
 * canola_py_sent too (true), in the order sent; frames a quiet node keeps off the bus and
 * frames refused (the core sends them again later) do not. */
void canola_py_dev_set_sent(canola_py_dev_t *dev, bool sent);
/* True when the last frame the node put on the bus was an SDO abort on `cob_id`: an SDO
 * client's transfer that ends with an abort was ended by the node itself (it sends the
 * abort just before the transfer's completion runs), not by the server's abort frame.
 * A frame the bus refused and the core sends later is not yet counted. */
bool canola_py_dev_sent_abort(const canola_py_dev_t *dev, uint32_t cob_id);

/* Application access: no access rights; writes take the node's path (co_node_write_app:
 * limits, service checks, event-driven TPDOs mapping the entry) and reach
 * canola_py_written as the application's (CANOLA_PY_BY_APP). */
co_abort_t canola_py_app_read(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                              uint32_t cap, uint32_t *len, uint8_t *type);
co_abort_t canola_py_dev_write(canola_py_dev_t *dev, uint16_t index, uint8_t sub,
                               const uint8_t *data, uint32_t len);

/* ---- a python-can bus object and the devs on it (py_link.c) */

/* Room for frames sent during one run of the link (python-can takes them after it). */
#define CANOLA_PY_LINK_FRAMES 512
#define CANOLA_PY_LINK_DEVS 128

struct canola_py_link {
    canola_py_dev_t *devs[CANOLA_PY_LINK_DEVS];
    uint32_t dev_count;
    /* frames sent, in order: [0, delivered) went to the other devs already; Python takes
     * [0, count) to python-can after each run and empties the queue */
    co_frame_t frames[CANOLA_PY_LINK_FRAMES];
    canola_py_dev_t *senders[CANOLA_PY_LINK_FRAMES];
    uint32_t count, delivered;
    bool refused;    /* a tx found the queue full: the core keeps the frame, poll again */
    uint64_t due_us; /* the earliest deadline of the active devs at the last poll */
};

canola_py_link_t *canola_py_link_new(void);
void canola_py_link_free(canola_py_link_t *link);
/* canola_py_dev_new's: `dev` joins the link (CO_ERR_FULL when it has CANOLA_PY_LINK_DEVS). */
co_err_t canola_py_link_attach(canola_py_link_t *link, canola_py_dev_t *dev);
void canola_py_link_detach(canola_py_link_t *link, canola_py_dev_t *dev);
/* A dev's tx on its link: queue the frame (CO_ERR_BUSY when the queue is full). */
co_err_t canola_py_link_tx(canola_py_dev_t *dev, const co_frame_t *frame);
/* A dev receives and is polled (true) or is left alone (false, stopped). */
void canola_py_dev_set_active(canola_py_dev_t *dev, bool active);
/* The dev's frames from others go to canola_py_raw_rx too (a master's frame listeners). */
void canola_py_dev_set_raw(canola_py_dev_t *dev, bool raw);
/* A frame from python-can: every active dev ingests it, then the link runs. */
void canola_py_link_ingest(canola_py_link_t *link, uint64_t now_us, const co_frame_t *frame);
/* Poll every active dev, then run the link; the earliest deadline of them. */
uint64_t canola_py_link_poll(canola_py_link_t *link, uint64_t now_us);
/* Deliver the queued frames to the other active devs, what they answer too, and poll
 * the active devs after each round until none is left; the number of frames queued for
 * python-can. A frame reaches every dev but its sender, in the order they were sent. */
uint32_t canola_py_link_run(canola_py_link_t *link, uint64_t now_us);
/* Python sent the queue: empty it; true when a tx was refused meanwhile (poll again). */
bool canola_py_link_clear(canola_py_link_t *link);

/* ---- program download, device side, on a canola.Device (py_prog.c) */

typedef struct canola_py_prog canola_py_prog_t;
/* Hook program `program` (sub-index of 0x1F50/51/56/57) of the entries; NULL when 0x1F50
 * or 0x1F51 lacks that sub-index (or no memory). The entries keep pointing to the result:
 * free it only with them. */
canola_py_prog_t *canola_py_prog_new(co_od_entry_t *entries, uint32_t count, uint8_t program,
                                     bool running, uint32_t ident, void *handle);
void canola_py_prog_free(canola_py_prog_t *p);
void canola_py_prog_set_ident(canola_py_prog_t *p, uint32_t ident);
uint32_t canola_py_prog_ident(const canola_py_prog_t *p);
uint32_t canola_py_prog_status(const canola_py_prog_t *p);
uint8_t canola_py_prog_state(const canola_py_prog_t *p);

/* ---- streamed DOMAIN entries of a canola.Device (py_stream.c) */

typedef struct canola_py_stream canola_py_stream_t;
/* Stream DOMAIN entry (index, sub) through Python (canola.domain.DomainStream): any size,
 * no buffer. NULL when the entry is missing, not a DOMAIN, or no memory. The entry keeps
 * pointing to the result: free it only with it. */
canola_py_stream_t *canola_py_stream_new(co_od_entry_t *entries, uint32_t count, uint16_t index,
                                         uint8_t sub, void *handle);
void canola_py_stream_free(canola_py_stream_t *s);

#endif
