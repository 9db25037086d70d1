/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/linux_loop.h -- one event loop per process: nodes, transports and the
 * application's own file descriptors on one epoll (port/linux).
 *
 * The loop sleeps in epoll_wait until something happens: a transport has a frame, the
 * earliest node deadline comes (the value co_node_poll returned, armed on a timerfd as an
 * absolute CLOCK_MONOTONIC time, the clock of co_linux_now_us), an application fd is
 * ready, or SIGTERM/SIGINT arrives (a signalfd, when co_loop_handle_signals was called).
 * There is no periodic tick: an idle node with a 1 s heartbeat wakes the process once a
 * second. On each wake-up it runs the application's fd callbacks, then reads every frame
 * the transports hold (co_node_ingest, each with the time it was read; bus events to
 * co_node_bus_event), and only then polls each node, at the time its transport was found
 * empty: the node sends what is due and returns the next deadline.
 *
 * So a time-out (SDO server and client, LSS, heartbeat consumer, guarding) is judged only
 * after the frames that had arrived were processed: a process that was starved past a
 * deadline, with the answer waiting in its socket, takes the answer first. (Each frame is
 * ingested at the time it is read, not at the time the kernel received it: the core counts
 * a service's own next time-out from the ingest, e.g. the SDO server's wait for the client
 * after its answer, and an answer sent late must not start that wait in the past. A
 * heartbeat consumer's verdict can so come late by a stall, never early.) A flood that
 * keeps CO_LOOP_RX_DRAIN_MAX frames waiting on one transport has its deadlines judged
 * after that many.
 *
 * When a transport cannot take a frame (CO_ERR_BUSY) the node keeps it queued; the loop
 * polls that node again when the transport's buffer drains (EPOLLOUT) or, for
 * transports without their own buffer (a full SocketCAN queue), after
 * CO_LOOP_RETRY_US. A transport that fails (the socketcand server closed, the CAN
 * interface went away) stops the loop with CO_LOOP_TRANSPORT_FAILED; its error text is
 * in the transport (co_loop_failed). Its node is left alone from then on (no more polls,
 * its fd out of the epoll set): running the loop again goes on with the other nodes.
 *
 * Use:
 *     co_loop_t loop;
 *     co_loop_init(&loop);
 *     co_loop_handle_signals(&loop);                   // SIGTERM/SIGINT stop the loop
 *     co_socketcan_open(&can, "can0");
 *     co_loop_add_node(&loop, &node, &config, &can.transport);   // co_node_init inside
 *     co_node_start(&node, co_linux_now_us());        // the loop's clock (transport.h)
 *     co_loop_run(&loop);                              // returns why it stopped
 *     co_loop_close(&loop);
 *
 * Threading: one thread runs the loop and every call on its nodes; callbacks run inside
 * co_loop_run. co_loop_stop may be called from a callback. Memory: everything lives in
 * co_loop_t (fixed tables); no allocation. Linux only.
 */
#ifndef CANOLA_LINUX_LOOP_H
#define CANOLA_LINUX_LOOP_H

#include "canola/node.h"
#include "canola/transport.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef CO_LOOP_NODES_MAX
#define CO_LOOP_NODES_MAX 8 /**< nodes (each with its transport) per loop */
#endif
#ifndef CO_LOOP_FDS_MAX
#define CO_LOOP_FDS_MAX 8 /**< application fds per loop */
#endif
/** Retry delay after a transport without its own buffer said busy. */
#define CO_LOOP_RETRY_US 1000u
/** Frames read from one transport in one turn before the others get theirs. */
#define CO_LOOP_RX_BURST 64
/** Frames read from one transport at most before its node's deadlines are judged. */
#define CO_LOOP_RX_DRAIN_MAX 1024

/** Why co_loop_run / co_loop_run_until returned. */
typedef enum co_loop_reason {
    CO_LOOP_RUNNING = 0,
    CO_LOOP_STOPPED,          /**< co_loop_stop was called */
    CO_LOOP_SIGNAL,           /**< SIGTERM or SIGINT (co_loop_signal says which) */
    CO_LOOP_DEADLINE,         /**< co_loop_run_until reached its time */
    CO_LOOP_TRANSPORT_FAILED, /**< a transport failed: co_loop_failed */
    CO_LOOP_SYSTEM_ERROR,     /**< epoll/timerfd failed (errno) */
} co_loop_reason_t;

/** An application fd is ready: `events` are EPOLLIN/EPOLLOUT/EPOLLERR/EPOLLHUP bits. */
typedef void (*co_loop_fd_fn)(void *ctx, int fd, uint32_t events);

typedef struct co_loop co_loop_t;

/** One node and its transport. Internal. */
typedef struct co_loop_node {
    co_loop_t *loop;
    co_node_t *node;
    co_transport_t *transport;
    uint64_t next_us;    /**< what co_node_poll returned last */
    uint64_t drained_us; /**< when the transport was last found empty: the poll's time */
    uint64_t retry_us;   /**< poll again then (a busy transport), CO_TIME_NEVER: none */
    bool watch_out;      /**< EPOLLOUT is armed for the transport's buffer */
    bool failed;         /**< the transport failed: the node is left alone */
} co_loop_node_t;

/** One application fd. Internal. */
typedef struct co_loop_fd {
    int fd;
    co_loop_fd_fn fn;
    void *ctx;
} co_loop_fd_t;

/** Counters, for tests and diagnostics. */
typedef struct co_loop_stats {
    uint32_t wakeups;       /**< epoll_wait returns */
    uint32_t timer_wakeups; /**< ... of which the deadline timer fired */
    uint32_t frames_in;     /**< frames handed to nodes */
    uint32_t frames_out;    /**< frames transports took */
    uint32_t busy;          /**< sends a transport refused for now */
    uint32_t timer_sets;    /**< timerfd re-armings */
} co_loop_stats_t;

struct co_loop {
    int epfd;
    int timerfd;
    int sigfd; /**< -1 unless co_loop_handle_signals */
    /** The signal mask before co_loop_handle_signals (a sigset_t; kept opaque so that
     *  this header needs no POSIX feature macros). */
    unsigned long old_mask[128 / sizeof(unsigned long)];
    uint64_t armed_us; /**< the timerfd's absolute deadline, CO_TIME_NEVER: disarmed */
    uint64_t until_us; /**< co_loop_run_until's end, CO_TIME_NEVER otherwise */
    co_loop_node_t nodes[CO_LOOP_NODES_MAX];
    unsigned node_count;
    co_loop_fd_t fds[CO_LOOP_FDS_MAX];
    unsigned fd_count;
    co_loop_reason_t reason;
    int signo;
    co_transport_t *failed; /**< the transport that failed last */
    bool failure_news;      /**< a failure not reported by a run yet (it may come first) */
    co_loop_stats_t stats;
};

/** Create the epoll and the timer. Returns CO_ERR_ARG for NULL, CO_ERR_STATE when the
 *  kernel refused (errno). */
co_err_t co_loop_init(co_loop_t *loop);

/** Let SIGTERM and SIGINT stop the loop (CO_LOOP_SIGNAL) instead of killing the process:
 *  blocks them in the calling thread and reads them from a signalfd. Call before other
 *  threads start so that they inherit the mask. Returns CO_ERR_STATE on failure. */
co_err_t co_loop_handle_signals(co_loop_t *loop);

/** Run `node` on `transport`: sets config->driver to the loop's driver (tx through the
 *  transport, filters following the routes), calls co_node_init(node, config) and
 *  watches the transport's fd. Start the node afterwards (co_node_start). Returns what
 *  co_node_init returns, CO_ERR_FULL when CO_LOOP_NODES_MAX nodes run, CO_ERR_ARG for a
 *  NULL argument, a closed transport or one already in use, CO_ERR_STATE when epoll
 *  refused the fd. */
co_err_t co_loop_add_node(co_loop_t *loop, co_node_t *node, co_node_config_t *config,
                          co_transport_t *transport);

/** Watch an application fd for `events` (EPOLLIN, EPOLLOUT, level-triggered); `fn` runs
 *  inside the loop when it is ready. Returns CO_ERR_FULL when CO_LOOP_FDS_MAX are
 *  watched, CO_ERR_ARG for a bad argument or an fd already watched, CO_ERR_STATE when
 *  epoll refused it. */
co_err_t co_loop_add_fd(co_loop_t *loop, int fd, uint32_t events, co_loop_fd_fn fn, void *ctx);

/** Stop watching an application fd (it stays open). Returns CO_ERR_NOT_FOUND if unknown. */
co_err_t co_loop_remove_fd(co_loop_t *loop, int fd);

/** Run until stopped (co_loop_stop, a signal, a failed transport). Returns the reason. */
co_loop_reason_t co_loop_run(co_loop_t *loop);

/** Run until CLOCK_MONOTONIC reaches `until_us` (co_linux_now_us time) or the loop is
 *  stopped, whichever comes first. Returns the reason (CO_LOOP_DEADLINE when the time
 *  came). */
co_loop_reason_t co_loop_run_until(co_loop_t *loop, uint64_t until_us);

/** Make co_loop_run return CO_LOOP_STOPPED after the current wake-up. */
void co_loop_stop(co_loop_t *loop);

/** The signal that stopped the loop (SIGTERM, SIGINT), 0 if none. */
int co_loop_signal(const co_loop_t *loop);

/** The transport that failed last (its .error says why), NULL if none. */
co_transport_t *co_loop_failed(const co_loop_t *loop);

/** Counters. */
const co_loop_stats_t *co_loop_stats(const co_loop_t *loop);

/** Close the loop's own fds (not the transports, not the application's fds) and restore
 *  the signal mask co_loop_handle_signals changed. Safe to call twice. */
void co_loop_close(co_loop_t *loop);

/** A short name for a reason ("signal", "transport failed", ...). */
const char *co_loop_reason_name(co_loop_reason_t reason);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_LINUX_LOOP_H */
