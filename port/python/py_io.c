/* SPDX-License-Identifier: Apache-2.0 */
/* A link that owns its bus (see canola_py.h): C reads and writes the socket, Python is
 * entered only for what it asked for.
 *
 * Threads. One thread at a time holds the receive token (rx_busy) and runs receive rounds
 * (io_round: poll() on the bus and the wake-up eventfd without the lock, then under the
 * lock every frame the bus holds, ingested at the time it is read, then the nodes' due
 * work, then what they sent out to the bus). The holder is an application thread that
 * waits in canola_py_io_wait (the answer it waits for reaches it without a hand-off
 * between threads) or, while nobody waits and not for aside_us after the last waiter,
 * the link's own thread. A waiter that finds the link's thread in poll() wakes it through
 * the eventfd and takes the token after its round. Python is called only by the link's
 * thread (canola_py_io_python, with the GIL that cffi takes), after a round, without the
 * lock, when callbacks were queued, frames for listeners were kept or a Python timer is
 * due; a waiter returns CANOLA_PY_IO_PYTHON to its Python caller instead. The C callbacks
 * of the nodes (cffi's extern "Python" ones included) run under the lock, in the thread
 * of the round or of the application's call.
 *
 * Lock order: io->lock, then seen_lock. Nothing here takes the GIL while holding the
 * lock but the nodes' own callbacks, which run in Python under it as on the python-can
 * path; a Python thread waits for the lock only inside a cffi call, which released the
 * GIL. */
#define _GNU_SOURCE

#include "canola_py.h"

#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

/* The link's thread sleeps at most this long (a safety net: every change of a deadline
 * wakes it). */
#define IO_SLEEP_MAX_US 1000000u
/* How long the link's thread leaves the bus to the waiters after the last one left: the
 * next transfer of a program that makes one after another finds the token free. */
#define IO_ASIDE_US 20000u

static uint64_t realtime_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

static struct timespec abs_time(uint64_t us)
{
    struct timespec ts = {.tv_sec = (time_t)(us / 1000000u),
                          .tv_nsec = (long)(us % 1000000u) * 1000};
    return ts;
}

static void timed_wait(pthread_cond_t *cond, pthread_mutex_t *lock, uint64_t until_us)
{
    struct timespec ts = abs_time(until_us);
    (void)pthread_cond_timedwait(cond, lock, &ts);
}

static uint64_t min_u64(uint64_t a, uint64_t b) { return a < b ? a : b; }

static void why_set(char *why, size_t cap, const char *text)
{
    if (why != NULL && cap > 0) {
        (void)snprintf(why, cap, "%s", text);
    }
}

/* ---- life */

static canola_py_io_t *io_new(char *why, size_t cap)
{
    canola_py_io_t *io = canola_py_alloc(sizeof *io);
    if (io == NULL) {
        why_set(why, cap, "out of memory");
        return NULL;
    }
    io->link.due_us = CO_TIME_NEVER;
    io->link.io = io;
    io->py_due_us = CO_TIME_NEVER;
    io->polling_until_us = CO_TIME_NEVER;
    io->aside_us = IO_ASIDE_US;
    io->reading = true;
    pthread_condattr_t attr;
    pthread_condattr_init(&attr);
    pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
    pthread_cond_init(&io->changed, &attr);
    pthread_cond_init(&io->idle, &attr);
    pthread_condattr_destroy(&attr);
    pthread_mutex_init(&io->lock, NULL);
    pthread_mutex_init(&io->seen_lock, NULL);
    io->wake_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (io->wake_fd < 0) {
        why_set(why, cap, strerror(errno));
        canola_py_io_free(io);
        return NULL;
    }
    return io;
}

canola_py_io_t *canola_py_io_socketcan(const char *ifname, char *why, size_t why_cap)
{
    canola_py_io_t *io = io_new(why, why_cap);
    if (io == NULL) {
        return NULL;
    }
    if (co_socketcan_open(&io->tr.can, ifname) != CO_OK ||
        co_socketcan_pass_all(&io->tr.can) != CO_OK) {
        why_set(why, why_cap,
                io->tr.can.transport.error[0] ? io->tr.can.transport.error
                                              : "the kernel refused the filter");
        co_socketcan_close(&io->tr.can);
        canola_py_io_free(io);
        return NULL;
    }
    io->t = &io->tr.can.transport;
    return io;
}

canola_py_io_t *canola_py_io_socketcand(const char *url, const char *token, unsigned timeout_ms,
                                        char *why, size_t why_cap)
{
    canola_py_io_t *io = io_new(why, why_cap);
    if (io == NULL) {
        return NULL;
    }
    if (co_socketcand_open_auth(&io->tr.scd, url, token, timeout_ms) != CO_OK) {
        why_set(why, why_cap, io->tr.scd.transport.error);
        canola_py_io_free(io);
        return NULL;
    }
    io->t = &io->tr.scd.transport;
    return io;
}

static void fail(canola_py_io_t *io, const char *why)
{
    if (!io->failed) {
        io->failed = true;
        (void)snprintf(io->error, sizeof io->error, "%s", why[0] ? why : "the bus failed");
    }
    pthread_cond_broadcast(&io->changed);
    pthread_cond_signal(&io->idle);
}

/* The holder of the token leaves poll() (under the lock). */
static void wake(canola_py_io_t *io)
{
    if (io->polling) {
        uint64_t one = 1;
        ssize_t n = write(io->wake_fd, &one, sizeof one);
        (void)n; /* a full counter wakes it as well */
        io->polling = false;
    }
}

void canola_py_io_close(canola_py_io_t *io)
{
    pthread_mutex_lock(&io->lock);
    if (io->t != NULL) {
        fail(io, "the bus was closed");
        wake(io);
        if (!io->rx_busy) { /* else its holder closes it after its round */
            co_transport_close(io->t);
        }
    }
    pthread_mutex_unlock(&io->lock);
}

void canola_py_io_free(canola_py_io_t *io)
{
    if (io->thread_on && !canola_py_io_stop(io, 2000)) {
        return; /* the thread still runs (a Python callback that does not return): kept */
    }
    if (io->t != NULL) {
        co_transport_close(io->t);
    }
    while (io->link.dev_count > 0) { /* the devs of nodes that outlived nothing */
        canola_py_dev_free(io->link.devs[0]);
    }
    if (io->wake_fd >= 0) {
        close(io->wake_fd);
    }
    pthread_cond_destroy(&io->changed);
    pthread_cond_destroy(&io->idle);
    pthread_mutex_destroy(&io->lock);
    pthread_mutex_destroy(&io->seen_lock);
    canola_py_release(io);
}

canola_py_link_t *canola_py_io_link(canola_py_io_t *io) { return &io->link; }

const char *canola_py_io_error(const canola_py_io_t *io) { return io->error; }

/* ---- the nodes' clock and output (under the lock) */

static uint64_t io_clock(canola_py_io_t *io)
{
    uint64_t now = co_linux_now_us();
    if (now < io->clock_us) {
        now = io->clock_us;
    }
    io->clock_us = now;
    return now;
}

/* Hand the frames the nodes queued (link.frames[sent, count)) to the bus, in order. */
static void send_out(canola_py_io_t *io, uint64_t now_us)
{
    canola_py_link_t *link = &io->link;
    for (;;) {
        while (io->sent < link->count && !io->failed) {
            co_err_t err = io->t->ops->send(io->t, &link->frames[io->sent]);
            if (err == CO_ERR_BUSY) {
                return; /* the rest when the bus takes more (POLLOUT) */
            }
            if (err == CO_ERR_STATE) {
                fail(io, io->t->error);
                break;
            }
            io->sent++; /* CO_ERR_ARG: a frame the bus cannot carry, dropped */
            io->frames_out++;
        }
        io->sent = 0;
        if (!canola_py_link_clear(link)) {
            return;
        }
        canola_py_link_poll(link, now_us); /* frames refused meanwhile wait in the cores */
    }
}

static bool listens(const canola_py_io_t *io, const co_frame_t *f)
{
    if (io->listen_all) {
        return true;
    }
    return !(f->flags & CO_FRAME_EXT) && f->id < 0x800u &&
           (io->listen[f->id / 32u] >> (f->id % 32u) & 1u);
}

static void keep_for_readers(canola_py_io_t *io, const co_frame_t *f, uint64_t stamp)
{
    if (io->ring_count == CANOLA_PY_IO_RING) { /* nobody reads: the oldest goes */
        io->ring_head = (io->ring_head + 1) % CANOLA_PY_IO_RING;
        io->ring_count--;
        io->ring_dropped++;
    }
    uint32_t at = (io->ring_head + io->ring_count++) % CANOLA_PY_IO_RING;
    io->ring[at] = *f;
    io->ring_us[at] = stamp;
}

static void bus_events(canola_py_io_t *io, uint32_t events)
{
    for (uint32_t i = 0; i < io->link.dev_count; i++) {
        canola_py_dev_t *d = io->link.devs[i];
        for (int e = CO_BUS_RX_OVERRUN; d->active && e <= CO_BUS_OFF_RECOVERED; e++) {
            if (events & (1u << e)) {
                co_node_bus_event(&d->node, (co_bus_event_t)e);
            }
        }
    }
}

/* Read what the bus holds (up to the room Python's listeners have left), each frame to
 * the nodes at the time it is read; then their due work; then what they sent. */
static void take_frames(canola_py_io_t *io)
{
    uint64_t now = io_clock(io);
    pthread_mutex_lock(&io->seen_lock);
    uint32_t room = CANOLA_PY_IO_DRAIN - io->seen_count;
    pthread_mutex_unlock(&io->seen_lock);
    for (uint32_t n = 0; n < room && !io->failed; n++) {
        co_frame_t f;
        uint32_t events = 0;
        co_rx_t r = io->t->ops->recv(io->t, &f, &events);
        if (r == CO_RX_AGAIN) {
            break;
        }
        if (r == CO_RX_ERROR) {
            fail(io, io->t->error);
            break;
        }
        if (r == CO_RX_EVENTS) {
            bus_events(io, events);
            continue;
        }
        io->frames_in++;
        now = io_clock(io);
        bool seen = listens(io, &f);
        uint64_t stamp = seen || io->reading ? realtime_us() : 0;
        if (seen) { /* before the nodes' callbacks: Python's later() takes it first */
            pthread_mutex_lock(&io->seen_lock);
            io->seen[io->seen_count] = f;
            io->seen_us[io->seen_count++] = stamp;
            pthread_mutex_unlock(&io->seen_lock);
        }
        if (io->reading) {
            keep_for_readers(io, &f, stamp);
        }
        canola_py_link_ingest(&io->link, now, &f);
        send_out(io, now);
    }
    canola_py_link_poll(&io->link, now);
    send_out(io, now);
}

static bool python_due(canola_py_io_t *io)
{
    if (io->py_events || co_linux_now_us() >= io->py_due_us) {
        return true;
    }
    pthread_mutex_lock(&io->seen_lock);
    bool seen = io->seen_count > 0;
    pthread_mutex_unlock(&io->seen_lock);
    return seen;
}

/* One receive round of the token's holder (called without the lock): wait for the bus
 * until `until_us`, the nodes' next deadline or a wake-up, then take what came. */
static void io_round(canola_py_io_t *io, uint64_t until_us, bool by_thread)
{
    pthread_mutex_lock(&io->lock);
    co_transport_t *t = io->t;
    if (io->failed) {
        co_transport_close(t);
        pthread_mutex_unlock(&io->lock);
        return;
    }
    uint64_t due = min_u64(until_us, io->link.due_us);
    bool out = io->sent < io->link.count || (t->ops->pending != NULL && t->ops->pending(t));
    bool buffered = t->ops->buffered != NULL && t->ops->buffered(t);
    io->polling = !buffered;
    io->polling_until_us = due;
    io->thread_holds = by_thread;
    int fd = t->fd;
    pthread_mutex_unlock(&io->lock);

    struct pollfd p[2] = {{.fd = fd, .events = (short)(POLLIN | (out ? POLLOUT : 0))},
                          {.fd = io->wake_fd, .events = POLLIN}};
    if (!buffered) {
        uint64_t now = co_linux_now_us();
        uint64_t wait_us = due > now ? due - now : 0;
        int ms = wait_us >= 0x7FFFFFFFu ? 0x7FFFFFFF : (int)((wait_us + 999u) / 1000u);
        if (poll(p, 2, ms) < 0 && errno != EINTR) {
            p[0].revents = POLLIN; /* let recv say what is wrong */
        }
        if (p[1].revents & POLLIN) {
            uint64_t count;
            ssize_t n = read(io->wake_fd, &count, sizeof count);
            (void)n;
        }
    }

    pthread_mutex_lock(&io->lock);
    io->polling = false;
    io->polling_until_us = CO_TIME_NEVER;
    io->thread_holds = false;
    if (io->failed) { /* closed meanwhile (canola_py_io_close): this thread closes it */
        co_transport_close(t);
        pthread_mutex_unlock(&io->lock);
        return;
    }
    if ((p[0].revents & POLLOUT) && t->ops->flush != NULL && t->ops->flush(t) == CO_ERR_STATE) {
        fail(io, t->error);
    }
    take_frames(io);
    io->rounds++;
    io->waiter_rounds += by_thread ? 0u : 1u;
    io->progress = false;
    pthread_cond_broadcast(&io->changed);
    if (!by_thread && python_due(io)) {
        pthread_cond_signal(&io->idle); /* the link's thread hands it to Python */
    }
    pthread_mutex_unlock(&io->lock);
}

/* ---- the link's thread */

static void *io_thread(void *arg)
{
    canola_py_io_t *io = arg;
    pthread_mutex_lock(&io->lock);
    while (!io->stop) {
        io->thread_wakeups++;
        uint64_t now = co_linux_now_us();
        if (python_due(io)) {
            io->py_events = false;
            pthread_mutex_unlock(&io->lock);
            uint64_t due = canola_py_io_python(io->user, now);
            pthread_mutex_lock(&io->lock);
            io->py_due_us = due;
            continue;
        }
        if (io->failed || io->waiters > 0 || io->rx_busy || now < io->aside_until_us) {
            uint64_t until = io->failed                 ? now + IO_SLEEP_MAX_US
                             : now < io->aside_until_us ? io->aside_until_us
                                                        : now + io->aside_us;
            timed_wait(&io->idle, &io->lock, min_u64(until, io->py_due_us));
            continue;
        }
        io->rx_busy = true;
        pthread_mutex_unlock(&io->lock);
        io_round(io, min_u64(now + IO_SLEEP_MAX_US, io->py_due_us), true);
        pthread_mutex_lock(&io->lock);
        io->rx_busy = false;
        pthread_cond_broadcast(&io->changed);
    }
    pthread_mutex_unlock(&io->lock);
    return NULL;
}

int canola_py_io_start(canola_py_io_t *io, void *user)
{
    pthread_mutex_lock(&io->lock);
    int err = 0;
    if (!io->thread_on) {
        io->user = user;
        io->stop = false;
        err = pthread_create(&io->thread, NULL, io_thread, io);
        io->thread_on = err == 0;
    }
    pthread_mutex_unlock(&io->lock);
    return err;
}

bool canola_py_io_in_thread(const canola_py_io_t *io)
{
    return io->thread_on && pthread_equal(pthread_self(), io->thread);
}

bool canola_py_io_stop(canola_py_io_t *io, uint32_t timeout_ms)
{
    pthread_mutex_lock(&io->lock);
    if (!io->thread_on) {
        pthread_mutex_unlock(&io->lock);
        return true;
    }
    io->stop = true;
    pthread_cond_signal(&io->idle);
    if (io->thread_holds) {
        wake(io);
    }
    bool self = pthread_equal(pthread_self(), io->thread);
    pthread_mutex_unlock(&io->lock);
    if (self) {
        return false;
    }
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts); /* pthread_timedjoin_np's clock */
    uint64_t end = (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u +
                   (uint64_t)timeout_ms * 1000u;
    ts = abs_time(end);
    if (pthread_timedjoin_np(io->thread, NULL, &ts) != 0) {
        return false;
    }
    pthread_mutex_lock(&io->lock);
    io->thread_on = false;
    pthread_mutex_unlock(&io->lock);
    return true;
}

/* ---- applications' calls */

void canola_py_io_lock(canola_py_io_t *io) { pthread_mutex_lock(&io->lock); }

void canola_py_io_unlock(canola_py_io_t *io)
{
    if (io->progress) {
        io->progress = false;
        pthread_cond_broadcast(&io->changed);
    }
    pthread_mutex_unlock(&io->lock);
}

uint64_t canola_py_io_enter(canola_py_io_t *io, co_node_t *node)
{
    pthread_mutex_lock(&io->lock);
    uint64_t now = co_linux_now_us();
    uint64_t due = io->link.due_us;
    if (now >= due && due != CO_TIME_NEVER) { /* the receiving thread judges it */
        now = due - 1u;
    }
    if (now < io->clock_us) {
        now = io->clock_us;
    }
    io->clock_us = now;
    if (node != NULL) {
        (void)co_node_poll(node, now);
    }
    return now;
}

void canola_py_io_leave(canola_py_io_t *io, uint64_t now_us)
{
    canola_py_link_poll(&io->link, now_us);
    send_out(io, now_us);
    if (io->link.due_us < io->polling_until_us) {
        wake(io); /* a deadline earlier than the receiving thread's wait */
    }
    canola_py_io_unlock(io);
}

/* ---- waiting */

/* Under the lock, the token free: an application's thread takes it, runs one receive round
 * until `until_us`, gives it back and tells the others. */
static void round_as_waiter(canola_py_io_t *io, uint64_t until_us)
{
    io->rx_busy = true;
    pthread_mutex_unlock(&io->lock);
    io_round(io, until_us, false);
    pthread_mutex_lock(&io->lock);
    io->rx_busy = false;
    pthread_cond_broadcast(&io->changed);
}

canola_py_io_rc_t canola_py_io_wait(canola_py_io_t *io, const canola_py_xfer_t *x,
                                    uint64_t until_us)
{
    pthread_mutex_lock(&io->lock);
    io->waiters++;
    uint64_t rounds = io->rounds;
    canola_py_io_rc_t rc;
    for (;;) {
        if (x != NULL && x->done) {
            rc = CANOLA_PY_IO_DONE;
            break;
        }
        if (python_due(io)) {
            rc = CANOLA_PY_IO_PYTHON;
            break;
        }
        if (io->failed) {
            rc = CANOLA_PY_IO_FAILED;
            break;
        }
        if (x == NULL && io->rounds != rounds) {
            rc = CANOLA_PY_IO_ROUND;
            break;
        }
        if (co_linux_now_us() >= until_us) {
            rc = CANOLA_PY_IO_TIMEOUT;
            break;
        }
        if (!io->rx_busy) {
            round_as_waiter(io, min_u64(until_us, io->py_due_us));
        } else {
            if (io->thread_holds) {
                wake(io); /* the link's thread leaves the bus to this thread */
            }
            timed_wait(&io->changed, &io->lock, until_us);
        }
    }
    io->waiters--;
    io->aside_until_us = co_linux_now_us() + io->aside_us;
    pthread_mutex_unlock(&io->lock);
    return rc;
}

void canola_py_io_note(canola_py_io_t *io) { io->py_events = true; }

uint64_t canola_py_io_python_begin(canola_py_io_t *io)
{
    pthread_mutex_lock(&io->lock);
    io->py_events = false;
    uint64_t now = io_clock(io);
    pthread_mutex_unlock(&io->lock);
    return now;
}

void canola_py_io_set_py_due(canola_py_io_t *io, uint64_t due_us)
{
    pthread_mutex_lock(&io->lock);
    io->py_due_us = due_us;
    if (due_us < io->polling_until_us) {
        wake(io);
    }
    pthread_cond_signal(&io->idle);
    pthread_mutex_unlock(&io->lock);
}

void canola_py_io_listen(canola_py_io_t *io, int cob_id)
{
    pthread_mutex_lock(&io->lock);
    if (cob_id < 0 || cob_id >= 0x800) {
        io->listen_all = true;
    } else {
        io->listen[(unsigned)cob_id / 32u] |= 1u << ((unsigned)cob_id % 32u);
    }
    pthread_mutex_unlock(&io->lock);
}

uint32_t canola_py_io_take_seen(canola_py_io_t *io, co_frame_t *frames, uint64_t *stamps,
                                uint32_t cap)
{
    pthread_mutex_lock(&io->seen_lock);
    uint32_t n = io->seen_count < cap ? io->seen_count : cap;
    memcpy(frames, io->seen, n * sizeof *frames);
    memcpy(stamps, io->seen_us, n * sizeof *stamps);
    memmove(io->seen, io->seen + n, (io->seen_count - n) * sizeof *frames);
    memmove(io->seen_us, io->seen_us + n, (io->seen_count - n) * sizeof *stamps);
    io->seen_count -= n;
    pthread_mutex_unlock(&io->seen_lock);
    return n;
}

/* ---- python-can's side */

co_err_t canola_py_io_send(canola_py_io_t *io, const co_frame_t *frame)
{
    pthread_mutex_lock(&io->lock);
    co_err_t err = CO_ERR_STATE;
    if (!io->failed) {
        send_out(io, io_clock(io)); /* what the nodes queued goes first */
        err = io->sent < io->link.count ? CO_ERR_BUSY : io->t->ops->send(io->t, frame);
        if (err == CO_ERR_STATE) {
            fail(io, io->t->error);
        } else if (err == CO_OK) {
            io->frames_out++;
        }
    }
    pthread_mutex_unlock(&io->lock);
    return err;
}

canola_py_io_rc_t canola_py_io_recv(canola_py_io_t *io, co_frame_t *frame, uint64_t *stamp_us,
                                    uint64_t until_us)
{
    pthread_mutex_lock(&io->lock);
    io->waiters++;
    canola_py_io_rc_t rc;
    bool read_once = false; /* a reader that may not wait still reads what the bus holds */
    for (;;) {
        if (io->ring_count > 0) {
            *frame = io->ring[io->ring_head];
            *stamp_us = io->ring_us[io->ring_head];
            io->ring_head = (io->ring_head + 1) % CANOLA_PY_IO_RING;
            io->ring_count--;
            rc = CANOLA_PY_IO_DONE;
            break;
        }
        if (io->failed) {
            rc = CANOLA_PY_IO_FAILED;
            break;
        }
        bool late = co_linux_now_us() >= until_us;
        if (late && (read_once || io->rx_busy)) {
            rc = CANOLA_PY_IO_TIMEOUT;
            break;
        }
        if (!io->rx_busy) {
            round_as_waiter(io, until_us);
            read_once = true;
        } else {
            timed_wait(&io->changed, &io->lock, until_us);
        }
    }
    io->waiters--;
    pthread_mutex_unlock(&io->lock);
    return rc;
}
