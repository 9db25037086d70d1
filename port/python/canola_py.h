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
 * of them sends is delivered to the others in C, at once, and queued for python-can.
 *
 * A link may own its bus itself (canola_py_io_t, py_io.c: a SocketCAN socket or a
 * socketcand connection, for the buses canola opens by URL): then C reads and writes the
 * socket, in a thread of its own or in the application thread that waits for an answer,
 * with Python's GIL released, and enters Python only for what Python asked for. */
#ifndef CANOLA_PY_H
#define CANOLA_PY_H

#include "canola/canola.h"
#include "canola/file_storage.h"
#include "canola/sim.h"
#include "canola/socketcan.h"
#include "canola/socketcand.h"

#include <pthread.h>
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
typedef struct canola_py_io canola_py_io_t;

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
    bool refused;       /* a tx found the queue full: the core keeps the frame, poll again */
    uint64_t due_us;    /* the earliest deadline of the active devs at the last poll */
    canola_py_io_t *io; /* the link's own bus (py_io.c), NULL on a python-can bus object */
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

/* ---- an SDO client's transfer, as its completion leaves it (py_sdo.c) */

/* One transfer of an SDO client channel: give canola_py_xfer_done as the co_sdo_upload /
 * co_sdo_download completion with the transfer as its ctx. The completion runs under the
 * node's lock and records the end in C, where a thread waiting for it in C sees it
 * (canola_py_io_wait) without entering Python; Python reads the fields afterwards. */
typedef struct canola_py_xfer {
    bool done;
    bool by_server;   /* the server sent the abort (not the client's own time-out or abort) */
    co_abort_t abort; /* 0: none */
    uint32_t len;     /* bytes moved */
    const canola_py_dev_t *dev; /* the client's dev: which side ended the transfer */
    uint32_t request_id;        /* 0x600 + the server's node-ID */
    void *notify; /* a Python handle: canola_py_sdo_done(notify, ...) at the end; NULL: none */
} canola_py_xfer_t;

/* co_sdo_done_fn of a canola_py_xfer_t (ctx). Never fails; constant time. */
void canola_py_xfer_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len);

/* ---- a link that owns its bus (py_io.c, Linux) */

/* Frames the link reads from its bus in one round before the nodes' deadlines are judged
 * (and frames kept for Python's listeners between two of Python's turns, at most). */
#define CANOLA_PY_IO_DRAIN 256
/* Frames kept for python-can readers of the bus object (canola.bus.native.NativeBus):
 * the oldest go when nobody reads (counted in ring_dropped). */
#define CANOLA_PY_IO_RING 4096

/* What canola_py_io_wait returned. */
typedef enum canola_py_io_rc {
    CANOLA_PY_IO_TIMEOUT = 0, /* `until_us` came first */
    CANOLA_PY_IO_DONE = 1,    /* the transfer ended (or a frame for a reader is there) */
    CANOLA_PY_IO_PYTHON = 2,  /* Python has work: callbacks queued, frames for listeners, a
                                 Python timer due (canola_py_io_python_begin) */
    CANOLA_PY_IO_ROUND = 3,   /* a receive round ran (waits without a transfer) */
    CANOLA_PY_IO_FAILED = -1, /* the bus failed or was closed: canola_py_io_error */
} canola_py_io_rc_t;

/* The link's state, shared by its thread, the application's threads and Python. Every
 * field after `link` is guarded by `lock` unless said otherwise. Opaque to Python but
 * for the counters at its end. */
struct canola_py_io {
    canola_py_link_t link; /* the devs on the bus (first: io->link.io == io) */
    co_transport_t *t;     /* tr.can or tr.scd */
    union {
        co_socketcan_t can;
        co_socketcand_t scd;
    } tr;
    pthread_mutex_t lock;   /* the nodes' lock (Python's Engine.lock on this link) */
    pthread_cond_t changed; /* a round ended, the token came free, a transfer ended */
    pthread_cond_t idle;    /* the link's thread sleeps on it while it stands aside */
    pthread_t thread;
    int wake_fd;       /* an eventfd: the receiving thread leaves poll() */
    bool rx_busy;      /* the receive token: one thread at a time reads the bus */
    bool polling;      /* its holder is in poll() until polling_until_us */
    bool thread_holds; /* ... and it is the link's thread */
    bool thread_on;    /* the link's thread runs (canola_py_io_start .. stop) */
    bool stop;         /* the link's thread is asked to end */
    bool failed;       /* the bus failed or was closed: error says why */
    bool progress;     /* a transfer ended in an application's call: wake the waiters */
    bool py_events;    /* Python queued callbacks (canola_py_io_note) */
    bool reading;      /* frames are kept for python-can readers (the ring) */
    bool listen_all;   /* every frame goes to Python's listeners */
    uint32_t waiters;  /* threads in canola_py_io_wait */
    uint32_t sent;     /* link.frames[0, sent) went to the bus already */
    uint64_t polling_until_us;
    uint64_t aside_until_us; /* the link's thread leaves the bus to the waiters until then */
    uint64_t aside_us;
    uint64_t clock_us;           /* the latest time handed to the nodes */
    uint64_t py_due_us;          /* the next Python timer, CO_TIME_NEVER: none */
    void *user;                  /* Python's handle: canola_py_io_python */
    uint32_t listen[0x800 / 32]; /* 11-bit COB-IDs Python's listeners want */
    /* frames for Python's listeners, in order (guarded by seen_lock) */
    pthread_mutex_t seen_lock;
    co_frame_t seen[CANOLA_PY_IO_DRAIN];
    uint64_t seen_us[CANOLA_PY_IO_DRAIN];
    uint32_t seen_count;
    /* frames for python-can readers: ring[head .. head + count) */
    co_frame_t ring[CANOLA_PY_IO_RING];
    uint64_t ring_us[CANOLA_PY_IO_RING]; /* when each was read (CLOCK_REALTIME, us) */
    uint32_t ring_head, ring_count;
    char error[CO_TRANSPORT_ERROR_MAX];
    /* counters (for tests and the benchmarks; read without the lock) */
    uint64_t rounds;         /* receive rounds */
    uint64_t waiter_rounds;  /* ... of them run by a waiting application thread */
    uint64_t thread_wakeups; /* times the link's thread woke up */
    uint64_t frames_in, frames_out, ring_dropped;
};

/* Open a link on SocketCAN interface `ifname` (no kernel filter, error frames on, own
 * frames not received) / on the socketcand server of `url` (socketcand://HOST:PORT/CHANNEL,
 * proving `token` when not NULL or "", each step of the handshake bounded by
 * `timeout_ms`). NULL when it cannot: `why` (of `why_cap` bytes) says why in one line.
 * No thread runs yet: until canola_py_io_start, whoever waits reads the bus. Blocks only
 * in the socketcand handshake. */
canola_py_io_t *canola_py_io_socketcan(const char *ifname, char *why, size_t why_cap);
canola_py_io_t *canola_py_io_socketcand(const char *url, const char *token, unsigned timeout_ms,
                                        char *why, size_t why_cap);
/* Stop the thread (waiting up to 2 s for it), close the bus, free the devs still attached
 * and the link. Not from the link's thread. */
void canola_py_io_free(canola_py_io_t *io);
/* Close the bus: every waiter returns CANOLA_PY_IO_FAILED ("closed"); the devs stay. */
void canola_py_io_close(canola_py_io_t *io);
/* The link's devs (canola_py_dev_new's `link`). */
canola_py_link_t *canola_py_io_link(canola_py_io_t *io);

/* Start the link's thread (it receives while no application thread waits, runs the
 * nodes' deadlines and calls canola_py_io_python for Python's work): 0, or an errno.
 * `user` is the handle canola_py_io_python gets. */
int canola_py_io_start(canola_py_io_t *io, void *user);
/* Stop it: true once it has ended (waits up to `timeout_ms`); from the thread itself it
 * is only asked to end (false). */
bool canola_py_io_stop(canola_py_io_t *io, uint32_t timeout_ms);
/* True in the link's thread. */
bool canola_py_io_in_thread(const canola_py_io_t *io);

/* An application's call on the nodes: canola_py_io_enter takes the lock and returns the
 * nodes' clock (now, but short of their next deadline, which the receiving thread judges
 * after the frames that arrived before it) after polling `node` (NULL: none) at it;
 * canola_py_io_leave delivers and sends what the nodes sent, polls them and releases the
 * lock, waking the receiving thread when a deadline moved earlier. The lock alone:
 * canola_py_io_lock / canola_py_io_unlock. */
uint64_t canola_py_io_enter(canola_py_io_t *io, co_node_t *node);
void canola_py_io_leave(canola_py_io_t *io, uint64_t now_us);
void canola_py_io_lock(canola_py_io_t *io);
void canola_py_io_unlock(canola_py_io_t *io);

/* Wait until transfer `x` ended (NULL: until one receive round ran), Python has work,
 * the bus failed, or CLOCK_MONOTONIC passes `until_us`. While it waits, this thread
 * reads the bus itself when no other does (the link's thread stands aside meanwhile and
 * `aside_us` after), so an answer needs no hand-off between threads. */
canola_py_io_rc_t canola_py_io_wait(canola_py_io_t *io, const canola_py_xfer_t *x,
                                    uint64_t until_us);
/* Python queued callbacks (under the lock): the thread that receives hands them over. */
void canola_py_io_note(canola_py_io_t *io);
/* Python takes its work: clears the note; returns the time (us) for its timers. */
uint64_t canola_py_io_python_begin(canola_py_io_t *io);
/* The next Python timer (CO_TIME_NEVER: none); wakes the receiving thread if earlier. */
void canola_py_io_set_py_due(canola_py_io_t *io, uint64_t due_us);
/* Frames with 11-bit COB-ID `cob_id` go to Python's listeners (cob_id < 0: every frame). */
void canola_py_io_listen(canola_py_io_t *io, int cob_id);
/* Move up to `cap` frames kept for Python's listeners into `frames` and their times
 * (CLOCK_REALTIME, us) into `stamps`; the number moved. With or without the lock. */
uint32_t canola_py_io_take_seen(canola_py_io_t *io, co_frame_t *frames, uint64_t *stamps,
                                uint32_t cap);
/* Called by the link's thread with the GIL (cffi): Python's work; returns the next Python
 * timer (CO_TIME_NEVER: none). */
uint64_t canola_py_io_python(void *user, uint64_t now_us);

/* python-can's side of the bus object: send one frame now (CO_OK; CO_ERR_BUSY: the bus
 * takes nothing now; CO_ERR_ARG: not a frame the bus carries; CO_ERR_STATE: failed), and
 * receive the next frame read from the bus (CANOLA_PY_IO_DONE with *frame and *stamp_us
 * set, TIMEOUT, or FAILED). Frames the link's own nodes send are not received. A call whose
 * `until_us` has passed still reads what the bus holds once when no other thread reads it
 * (python-can's recv(0): what came, without waiting). */
co_err_t canola_py_io_send(canola_py_io_t *io, const co_frame_t *frame);
canola_py_io_rc_t canola_py_io_recv(canola_py_io_t *io, co_frame_t *frame, uint64_t *stamp_us,
                                    uint64_t until_us);
/* Why the bus failed ("" while it works). */
const char *canola_py_io_error(const canola_py_io_t *io);

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
