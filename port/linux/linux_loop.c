/* SPDX-License-Identifier: Apache-2.0 */
/* linux_loop.c -- the epoll + timerfd event loop; see canola/linux_loop.h. */
#define _GNU_SOURCE

#include "canola/linux_loop.h"

#include <errno.h>
#include <signal.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

/* epoll tags: kind in the upper half, node index or application fd in the lower. */
enum { TAG_TIMER = 1, TAG_SIGNAL, TAG_NODE, TAG_APP };
#define TAG(kind, value) (((uint64_t)(kind) << 32) | (uint32_t)(value))

_Static_assert(sizeof(((co_loop_t *)0)->old_mask) >= sizeof(sigset_t),
               "co_loop_t.old_mask holds a sigset_t");

static uint64_t min_u64(uint64_t a, uint64_t b) { return a < b ? a : b; }

co_err_t co_loop_init(co_loop_t *loop)
{
    if (loop == NULL) {
        return CO_ERR_ARG;
    }
    memset(loop, 0, sizeof *loop);
    loop->sigfd = -1;
    loop->armed_us = CO_TIME_NEVER;
    loop->until_us = CO_TIME_NEVER;
    loop->epfd = epoll_create1(EPOLL_CLOEXEC);
    loop->timerfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = TAG(TAG_TIMER, 0)};
    if (loop->epfd < 0 || loop->timerfd < 0 ||
        epoll_ctl(loop->epfd, EPOLL_CTL_ADD, loop->timerfd, &ev) != 0) {
        int saved = errno;
        co_loop_close(loop);
        errno = saved;
        return CO_ERR_STATE;
    }
    return CO_OK;
}

co_err_t co_loop_handle_signals(co_loop_t *loop)
{
    if (loop == NULL || loop->epfd < 0) {
        return CO_ERR_ARG;
    }
    if (loop->sigfd >= 0) {
        return CO_OK;
    }
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    if (sigprocmask(SIG_BLOCK, &set, (sigset_t *)(void *)loop->old_mask) != 0) {
        return CO_ERR_STATE;
    }
    loop->sigfd = signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = TAG(TAG_SIGNAL, 0)};
    if (loop->sigfd < 0 || epoll_ctl(loop->epfd, EPOLL_CTL_ADD, loop->sigfd, &ev) != 0) {
        int saved = errno;
        if (loop->sigfd >= 0) {
            close(loop->sigfd);
            loop->sigfd = -1;
        }
        sigprocmask(SIG_SETMASK, (sigset_t *)(void *)loop->old_mask, NULL);
        errno = saved;
        return CO_ERR_STATE;
    }
    return CO_OK;
}

static void fail(co_loop_t *loop, co_loop_node_t *ep)
{
    ep->failed = true;
    loop->failed = ep->transport;
    loop->failure_news = true;
    loop->reason = CO_LOOP_TRANSPORT_FAILED;
    if (ep->transport->fd >= 0) {
        /* Out of the epoll set, so that a loop that goes on with its other nodes does not
         * wake for the broken fd again and again. */
        (void)epoll_ctl(loop->epfd, EPOLL_CTL_DEL, ep->transport->fd, NULL);
    }
}

static bool transport_pending(const co_transport_t *t)
{
    return t->ops->pending != NULL && t->ops->pending(t);
}

static bool transport_buffered(const co_transport_t *t)
{
    return t->ops->buffered != NULL && t->fd >= 0 && t->ops->buffered(t);
}

static co_err_t loop_tx(void *ctx, const co_frame_t *frame)
{
    co_loop_node_t *ep = ctx;
    co_transport_t *t = ep->transport;
    if (ep->failed) {
        return CO_ERR_STATE;
    }
    co_err_t rc = t->ops->send(t, frame);
    if (rc == CO_OK) {
        ep->loop->stats.frames_out++;
    } else if (rc == CO_ERR_BUSY) {
        ep->loop->stats.busy++;
        if (!transport_pending(t)) {
            /* No buffer whose draining would tell us: try again a little later. */
            ep->retry_us = min_u64(ep->retry_us, co_linux_now_us() + CO_LOOP_RETRY_US);
        }
    } else if (rc == CO_ERR_STATE) {
        fail(ep->loop, ep);
    }
    return rc; /* other errors: the node drops this frame and counts it */
}

static void loop_routes_changed(void *ctx)
{
    co_loop_node_t *ep = ctx;
    if (ep->transport->ops->set_filter != NULL && ep->transport->fd >= 0) {
        ep->transport->ops->set_filter(ep->transport, ep->node);
    }
}

co_err_t co_loop_add_node(co_loop_t *loop, co_node_t *node, co_node_config_t *config,
                          co_transport_t *transport)
{
    if (loop == NULL || node == NULL || config == NULL || transport == NULL ||
        transport->ops == NULL || transport->fd < 0 || loop->epfd < 0) {
        return CO_ERR_ARG;
    }
    for (unsigned i = 0; i < loop->node_count; i++) {
        if (loop->nodes[i].transport == transport || loop->nodes[i].node == node) {
            return CO_ERR_ARG;
        }
    }
    if (loop->node_count >= CO_LOOP_NODES_MAX) {
        return CO_ERR_FULL;
    }
    unsigned idx = loop->node_count;
    co_loop_node_t *ep = &loop->nodes[idx];
    memset(ep, 0, sizeof *ep);
    ep->loop = loop;
    ep->node = node;
    ep->transport = transport;
    ep->next_us = 0; /* poll it on the first wake-up */
    ep->retry_us = CO_TIME_NEVER;
    config->driver.tx = loop_tx;
    config->driver.on_routes_changed = loop_routes_changed;
    config->driver.ctx = ep;
    co_err_t rc = co_node_init(node, config);
    if (rc != CO_OK) {
        return rc;
    }
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = TAG(TAG_NODE, idx)};
    if (epoll_ctl(loop->epfd, EPOLL_CTL_ADD, transport->fd, &ev) != 0) {
        return CO_ERR_STATE;
    }
    loop_routes_changed(ep); /* the routes co_node_init bound */
    loop->node_count++;
    return CO_OK;
}

static co_loop_fd_t *find_fd(co_loop_t *loop, int fd)
{
    for (unsigned i = 0; i < loop->fd_count; i++) {
        if (loop->fds[i].fd == fd) {
            return &loop->fds[i];
        }
    }
    return NULL;
}

co_err_t co_loop_add_fd(co_loop_t *loop, int fd, uint32_t events, co_loop_fd_fn fn, void *ctx)
{
    if (loop == NULL || fd < 0 || fn == NULL || events == 0 || find_fd(loop, fd) != NULL) {
        return CO_ERR_ARG;
    }
    if (loop->fd_count >= CO_LOOP_FDS_MAX) {
        return CO_ERR_FULL;
    }
    struct epoll_event ev = {.events = events, .data.u64 = TAG(TAG_APP, fd)};
    if (epoll_ctl(loop->epfd, EPOLL_CTL_ADD, fd, &ev) != 0) {
        return CO_ERR_STATE;
    }
    loop->fds[loop->fd_count++] = (co_loop_fd_t){.fd = fd, .fn = fn, .ctx = ctx};
    return CO_OK;
}

co_err_t co_loop_remove_fd(co_loop_t *loop, int fd)
{
    co_loop_fd_t *f = loop != NULL ? find_fd(loop, fd) : NULL;
    if (f == NULL) {
        return CO_ERR_NOT_FOUND;
    }
    (void)epoll_ctl(loop->epfd, EPOLL_CTL_DEL, fd, NULL);
    *f = loop->fds[--loop->fd_count];
    return CO_OK;
}

/* Arm the timer for `at` (absolute, CLOCK_MONOTONIC), only when it changed. */
static bool arm(co_loop_t *loop, uint64_t at)
{
    if (at == loop->armed_us) {
        return true;
    }
    struct itimerspec its;
    memset(&its, 0, sizeof its);
    if (at != CO_TIME_NEVER) {
        its.it_value.tv_sec = (time_t)(at / 1000000u);
        its.it_value.tv_nsec = (long)(at % 1000000u) * 1000L;
        if (at == 0) {
            its.it_value.tv_nsec = 1; /* 0 would disarm */
        }
    }
    if (timerfd_settime(loop->timerfd, TFD_TIMER_ABSTIME, &its, NULL) != 0) {
        return false;
    }
    loop->armed_us = at;
    loop->stats.timer_sets++;
    return true;
}

/* Poll every node at the time its transport was last found empty (drain): no deadline is
 * judged while a frame that came before it waits unread. Returns the earliest time the
 * loop must wake up. */
static uint64_t poll_nodes(co_loop_t *loop)
{
    uint64_t wake = CO_TIME_NEVER;
    for (unsigned i = 0; i < loop->node_count; i++) {
        co_loop_node_t *ep = &loop->nodes[i];
        if (ep->failed) {
            continue;
        }
        uint64_t now = ep->drained_us;
        if (ep->retry_us <= now) {
            ep->retry_us = CO_TIME_NEVER; /* this poll is the retry */
        }
        ep->next_us = co_node_poll(ep->node, now);
        wake = min_u64(wake, min_u64(ep->next_us, ep->retry_us));
        if (transport_buffered(ep->transport)) {
            wake = now; /* input waits in the transport: no sleeping */
        }
        bool want_out = transport_pending(ep->transport);
        if (want_out != ep->watch_out) {
            struct epoll_event ev = {.events = EPOLLIN | (want_out ? EPOLLOUT : 0u),
                                     .data.u64 = TAG(TAG_NODE, i)};
            if (epoll_ctl(loop->epfd, EPOLL_CTL_MOD, ep->transport->fd, &ev) == 0) {
                ep->watch_out = want_out;
            }
        }
    }
    return wake;
}

static void dispatch_events(co_node_t *node, uint32_t events)
{
    for (int e = CO_BUS_RX_OVERRUN; e <= CO_BUS_OFF_RECOVERED; e++) {
        if (events & (1u << e)) {
            co_node_bus_event(node, (co_bus_event_t)e);
        }
    }
}

/* Up to CO_LOOP_RX_BURST frames of one transport, each to its node with the time it was
 * read. True when the burst was full (more may wait); false when the transport was found
 * empty (at ep->drained_us) or failed. */
static bool read_burst(co_loop_t *loop, co_loop_node_t *ep)
{
    co_transport_t *t = ep->transport;
    for (int n = 0; n < CO_LOOP_RX_BURST; n++) {
        uint64_t now = co_linux_now_us(); /* before the read: nothing came later unread */
        co_frame_t frame;
        uint32_t bus = 0;
        co_rx_t r = t->ops->recv(t, &frame, &bus);
        if (r == CO_RX_AGAIN) {
            ep->drained_us = now;
            return false;
        }
        if (r == CO_RX_ERROR) {
            fail(loop, ep);
            return false;
        }
        ep->drained_us = now; /* (a flood that outlasts the drain: the last frame's time) */
        if (r == CO_RX_FRAME) {
            loop->stats.frames_in++;
            co_node_ingest(ep->node, now, &frame);
        } else {
            dispatch_events(ep->node, bus);
        }
        if (ep->failed) {
            return false; /* a send inside the ingest broke it */
        }
    }
    return true;
}

/* Every frame the transports hold, read before any deadline is judged: in turns of a
 * burst per transport (so that one busy bus does not keep the others waiting), until
 * every transport is empty or CO_LOOP_RX_DRAIN_MAX frames were read from one. */
static void drain(co_loop_t *loop)
{
    bool more[CO_LOOP_NODES_MAX];
    for (unsigned i = 0; i < loop->node_count; i++) {
        more[i] = !loop->nodes[i].failed;
    }
    for (unsigned turn = 0; turn < CO_LOOP_RX_DRAIN_MAX / CO_LOOP_RX_BURST; turn++) {
        bool any = false;
        for (unsigned i = 0; i < loop->node_count; i++) {
            if (more[i]) {
                more[i] = read_burst(loop, &loop->nodes[i]);
                any |= more[i];
            }
        }
        if (!any) {
            return;
        }
    }
}

/* A transport's fd is writable again: its buffered output goes (the frames waiting to be
 * read are the drain's). */
static void node_ready(co_loop_t *loop, co_loop_node_t *ep, uint32_t events)
{
    co_transport_t *t = ep->transport;
    if ((events & EPOLLOUT) && t->ops->flush != NULL && t->ops->flush(t) == CO_ERR_STATE) {
        fail(loop, ep);
    }
}

static void handle(co_loop_t *loop, const struct epoll_event *ev)
{
    uint32_t kind = (uint32_t)(ev->data.u64 >> 32);
    uint32_t value = (uint32_t)ev->data.u64;
    switch (kind) {
    case TAG_TIMER: {
        uint64_t expirations;
        (void)!read(loop->timerfd, &expirations, sizeof expirations);
        loop->stats.timer_wakeups++;
        loop->armed_us = CO_TIME_NEVER; /* fired: the next deadline must re-arm it */
        break;
    }
    case TAG_SIGNAL: {
        struct signalfd_siginfo si;
        if (read(loop->sigfd, &si, sizeof si) == (ssize_t)sizeof si) {
            loop->signo = (int)si.ssi_signo;
            loop->reason = CO_LOOP_SIGNAL;
        }
        break;
    }
    case TAG_NODE:
        if (value < loop->node_count && !loop->nodes[value].failed) {
            node_ready(loop, &loop->nodes[value], ev->events);
        }
        break;
    case TAG_APP: {
        co_loop_fd_t *f = find_fd(loop, (int)value);
        if (f != NULL) {
            f->fn(f->ctx, f->fd, ev->events);
        }
        break;
    }
    default:
        break;
    }
}

co_loop_reason_t co_loop_run_until(co_loop_t *loop, uint64_t until_us)
{
    if (loop == NULL || loop->epfd < 0) {
        return CO_LOOP_SYSTEM_ERROR;
    }
    /* A transport that failed outside the run (co_node_start's boot-up) is news too. */
    loop->reason = loop->failure_news ? CO_LOOP_TRANSPORT_FAILED : CO_LOOP_RUNNING;
    loop->until_us = until_us;
    while (loop->reason == CO_LOOP_RUNNING) {
        drain(loop); /* first what came: then the deadlines */
        uint64_t wake = min_u64(poll_nodes(loop), until_us);
        if (loop->reason != CO_LOOP_RUNNING) {
            break;
        }
        uint64_t now = co_linux_now_us();
        if (now >= until_us) {
            loop->reason = CO_LOOP_DEADLINE;
            break;
        }
        int timeout = -1;
        if (wake <= now) {
            timeout = 0; /* due already: look at the fds without sleeping */
        } else if (!arm(loop, wake)) {
            loop->reason = CO_LOOP_SYSTEM_ERROR;
            break;
        }
        struct epoll_event evs[16];
        int n = epoll_wait(loop->epfd, evs, 16, timeout);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            loop->reason = CO_LOOP_SYSTEM_ERROR;
            break;
        }
        loop->stats.wakeups++;
        for (int i = 0; i < n; i++) {
            handle(loop, &evs[i]);
        }
        if (loop->reason != CO_LOOP_RUNNING) {
            /* Let the nodes take the last frames and send what they ask for before
             * returning (a transport failing now is news for the next run, not a lost
             * signal). */
            co_loop_reason_t why = loop->reason;
            drain(loop);
            (void)poll_nodes(loop);
            loop->reason = why;
            break;
        }
    }
    loop->until_us = CO_TIME_NEVER;
    if (loop->reason == CO_LOOP_TRANSPORT_FAILED) {
        loop->failure_news = false;
    }
    return loop->reason;
}

co_loop_reason_t co_loop_run(co_loop_t *loop) { return co_loop_run_until(loop, CO_TIME_NEVER); }

void co_loop_stop(co_loop_t *loop)
{
    if (loop != NULL && loop->reason == CO_LOOP_RUNNING) {
        loop->reason = CO_LOOP_STOPPED;
    }
}

int co_loop_signal(const co_loop_t *loop) { return loop != NULL ? loop->signo : 0; }

co_transport_t *co_loop_failed(const co_loop_t *loop) { return loop != NULL ? loop->failed : NULL; }

const co_loop_stats_t *co_loop_stats(const co_loop_t *loop) { return &loop->stats; }

void co_loop_close(co_loop_t *loop)
{
    if (loop == NULL) {
        return;
    }
    if (loop->sigfd >= 0) {
        /* Consume what is pending, so that unblocking does not deliver it now. */
        struct signalfd_siginfo si;
        while (read(loop->sigfd, &si, sizeof si) == (ssize_t)sizeof si) {
        }
        close(loop->sigfd);
        loop->sigfd = -1;
        sigprocmask(SIG_SETMASK, (sigset_t *)(void *)loop->old_mask, NULL);
    }
    if (loop->timerfd >= 0) {
        close(loop->timerfd);
        loop->timerfd = -1;
    }
    if (loop->epfd >= 0) {
        close(loop->epfd);
        loop->epfd = -1;
    }
}

const char *co_loop_reason_name(co_loop_reason_t reason)
{
    switch (reason) {
    case CO_LOOP_RUNNING:
        return "running";
    case CO_LOOP_STOPPED:
        return "stopped";
    case CO_LOOP_SIGNAL:
        return "signal";
    case CO_LOOP_DEADLINE:
        return "deadline";
    case CO_LOOP_TRANSPORT_FAILED:
        return "transport failed";
    case CO_LOOP_SYSTEM_ERROR:
        return "system error";
    }
    return "unknown";
}
