/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_linux_loop.c -- the epoll + timerfd event loop, natively (no CAN needed).
 *
 * A node runs on one end of a SOCK_SEQPACKET socketpair (co_socketcan_open_fd: frames in
 * SocketCAN's layout); the test plays the rest of the bus on the other end, watched by
 * the same loop as an application fd. Checks: the loop wakes by itself for each
 * heartbeat deadline and never before it, no busy polling (wake-ups counted per
 * heartbeat), frames answered on arrival (no timer involved), two nodes on two
 * transports, SIGTERM/SIGINT, co_loop_stop, a failed transport, a busy transport retried.
 *
 * The wall clock is unavoidable here, and the machine may be busy: the test waits for
 * events (the loop stops once what it waits for has happened, within a bound of seconds)
 * and checks order and counts, never how late something came (that is bench/'s job).
 * Bounded: alarm(120).
 */
#define _GNU_SOURCE

#include "canola/linux_loop.h"
#include "canola/socketcan.h"
#include "check.h"
#include "example_od.h"
#include "loop_wait.h"

#include <errno.h>
#include <linux/can.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define MS 1000u

typedef struct seen {
    struct can_frame f;
    uint64_t at_us;
} seen_t;

/* One node on a socketpair, the peer end watched by the loop. */
typedef struct rig {
    co_loop_t loop;
    example_od_t od;
    co_node_t node;
    co_node_config_t cfg;
    co_socketcan_t can;
    int peer;
    seen_t seen[512];
    int count;
    co_nmt_state_t states[16];
    int state_count;
    co_ec_event_t events[32];
    int event_count;
    bool (*until)(const struct rig *r); /* the loop stops once this holds (run_until) */
    void (*on_seen)(struct rig *r, const struct can_frame *f); /* the peer's reaction */
} rig_t;

static rig_t R; /* large: not on the stack */

static void peer_ready(void *ctx, int fd, uint32_t events)
{
    rig_t *r = ctx;
    (void)events;
    struct can_frame cf;
    while (read(fd, &cf, sizeof cf) == (ssize_t)sizeof cf) {
        if (r->count < (int)(sizeof r->seen / sizeof r->seen[0])) {
            r->seen[r->count].f = cf;
            r->seen[r->count].at_us = co_linux_now_us();
            r->count++;
        }
        if (r->on_seen != NULL) {
            r->on_seen(r, &cf);
        }
    }
    if (r->until != NULL && r->until(r)) {
        co_loop_stop(&r->loop);
    }
}

static void on_state(void *user, co_nmt_state_t s)
{
    rig_t *r = user;
    if (r->state_count < 16) {
        r->states[r->state_count++] = s;
    }
}

static void on_errctl(void *user, const co_ec_event_t *ev)
{
    rig_t *r = user;
    if (r->event_count < 32) {
        r->events[r->event_count++] = *ev;
    }
}

static void peer_send(rig_t *r, uint32_t id, const uint8_t *data, uint8_t len)
{
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = id;
    cf.len = len;
    memcpy(cf.data, data, len);
    CHECK(write(r->peer, &cf, sizeof cf) == (ssize_t)sizeof cf);
}

/* Node `id` with heartbeat `hb_ms` on a fresh socketpair; not started. */
static void rig_open(rig_t *r, uint8_t id, uint16_t hb_ms)
{
    memset(r, 0, sizeof *r);
    int sv[2];
    CHECK(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv) == 0);
    CHECK_EQ(co_loop_init(&r->loop), CO_OK);
    CHECK_EQ(co_socketcan_open_fd(&r->can, sv[0]), CO_OK);
    r->peer = sv[1];
    CHECK_EQ(co_socketcan_open_fd(&(co_socketcan_t){0}, -1), CO_ERR_ARG);
    r->cfg.node_id = id;
    r->cfg.od = example_od_init(&r->od, hb_ms);
    r->cfg.user = r;
    r->cfg.on_state = on_state;
    r->cfg.on_errctl = on_errctl;
    CHECK_EQ(co_loop_add_node(&r->loop, &r->node, &r->cfg, &r->can.transport), CO_OK);
    CHECK_EQ(co_loop_add_fd(&r->loop, r->peer, EPOLLIN, peer_ready, r), CO_OK);
}

static void rig_close(rig_t *r)
{
    co_loop_close(&r->loop);
    co_socketcan_close(&r->can);
    close(r->peer);
}

static void run_ms(rig_t *r, unsigned ms)
{
    co_loop_reason_t why = co_loop_run_until(&r->loop, co_linux_now_us() + ms * MS);
    CHECK_EQ(why, CO_LOOP_DEADLINE);
}

#define BOUND_MS LOOP_WAIT_BOUND_MS

/* Run the loop until `done` holds for the frames the peer saw (checked as they come), or
 * BOUND_MS passed: whether it holds. */
static bool run_until(rig_t *r, bool (*done)(const rig_t *r))
{
    r->until = done;
    co_loop_reason_t why =
        done(r) ? CO_LOOP_STOPPED : co_loop_run_until(&r->loop, co_linux_now_us() + BOUND_MS * MS);
    r->until = NULL;
    if (!done(r)) {
        printf("  not seen within %u ms (%s)\n", BOUND_MS, co_loop_reason_name(why));
    }
    return done(r);
}

/* How many frames with `id` (and first byte `b0`, or any if b0 < 0) the peer saw from `from`. */
static int seen_count(const rig_t *r, int from, uint32_t id, int b0)
{
    int n = 0;
    for (int i = from; i < r->count; i++) {
        if (r->seen[i].f.can_id == id && (b0 < 0 || r->seen[i].f.data[0] == b0)) {
            n++;
        }
    }
    return n;
}

static int mark; /* frames seen before the part of a test that waits */

static bool has_four_beats(const rig_t *r) { return seen_count(r, 1, 0x705, -1) >= 4; }
static bool has_five_more_beats(const rig_t *r) { return seen_count(r, mark, 0x705, -1) >= 5; }
static bool has_boot_up(const rig_t *r) { return seen_count(r, 0, 0x705, 0x00) >= 1; }
static bool has_sdo_answer(const rig_t *r) { return seen_count(r, mark, 0x585, -1) >= 1; }
static bool has_answer_and_beat(const rig_t *r)
{
    return has_sdo_answer(r) && seen_count(r, mark, 0x705, 0x05) >= 1;
}

static void test_boot_up_and_heartbeat_deadlines(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 100);
    uint64_t t0 = co_linux_now_us();
    CHECK_EQ(co_node_start(&r->node, t0), CO_OK);
    /* Nothing but the loop's own timer wakes it: the heartbeats come by themselves. */
    CHECK(run_until(r, has_four_beats));
    CHECK(r->count >= 5);
    CHECK_EQ(r->seen[0].f.can_id, 0x705);
    CHECK_EQ(r->seen[0].f.data[0], 0x00); /* boot-up first */
    /* Heartbeats every 100 ms from the start (fixed rate): the k-th is due at
     * t0 + k * 100 ms, and the loop never sends one before its deadline. How late one
     * comes depends on the machine's load: not checked here (bench/ measures it). */
    int beats = 0;
    uint64_t last = t0;
    for (int i = 1; i < r->count; i++) {
        if (r->seen[i].f.can_id != 0x705) {
            continue;
        }
        beats++;
        uint64_t due = t0 + (uint64_t)beats * 100 * MS;
        uint64_t at = r->seen[i].at_us;
        if (at < due) {
            printf("  heartbeat %d came %lld us before its deadline\n", beats,
                   (long long)(due - at));
        }
        CHECK(at >= due);
        CHECK(at >= last); /* in order */
        last = at;
        CHECK_EQ(r->seen[i].f.data[0], 0x7F); /* pre-operational */
    }
    CHECK(beats >= 4);
    CHECK(r->state_count >= 1);
    CHECK_EQ(r->states[r->state_count - 1], CO_NMT_PRE_OPERATIONAL);
    rig_close(r);
}

static void test_no_busy_polling(void)
{
    /* Heartbeat 200 ms, five beats: each costs at most two wake-ups (the timer and the
     * peer fd that receives it; a busy machine only merges them). A 1 ms tick would be
     * ~1000 over the same second. */
    rig_t *r = &R;
    rig_open(r, 5, 200);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    CHECK(run_until(r, has_boot_up));
    mark = r->count;
    uint32_t w0 = co_loop_stats(&r->loop)->wakeups;
    CHECK(run_until(r, has_five_more_beats));
    uint32_t woke = co_loop_stats(&r->loop)->wakeups - w0;
    printf("  five beats of a 200 ms heartbeat: %u wake-ups\n", woke);
    CHECK(woke <= 14);
    rig_close(r);

    /* No heartbeat at all: nothing to do, nothing wakes the process. */
    rig_open(r, 5, 0);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    run_ms(r, 50);
    w0 = co_loop_stats(&r->loop)->wakeups;
    run_ms(r, 300);
    woke = co_loop_stats(&r->loop)->wakeups - w0;
    printf("  300 ms idle, no heartbeat: %u wake-ups\n", woke);
    CHECK(woke <= 1); /* the run's own end */
    rig_close(r);
}

static void test_frames_in_nmt_and_sdo(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 100);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    CHECK(run_until(r, has_boot_up));
    mark = r->count;
    const uint8_t start[2] = {0x01, 5};
    peer_send(r, 0x000, start, 2);
    const uint8_t req[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    peer_send(r, 0x605, req, 8);
    CHECK(run_until(r, has_answer_and_beat)); /* the SDO answer, an operational heartbeat */
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_OPERATIONAL);
    CHECK(co_loop_stats(&r->loop)->frames_in >= 2);
    for (int i = mark; i < r->count; i++) {
        if (r->seen[i].f.can_id == 0x585) {
            CHECK_EQ(r->seen[i].f.data[0], 0x43);
            CHECK_EQ(r->seen[i].f.data[4], 0x91); /* 0x1000 device type of the example */
            break;
        }
    }
    rig_close(r);
}

static void test_answered_on_arrival(void)
{
    /* No heartbeat, so no deadline of the node's: only the request's arrival can wake
     * the loop, and the answer comes without the timer firing (no tick). */
    rig_t *r = &R;
    rig_open(r, 5, 0);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    CHECK(run_until(r, has_boot_up));
    mark = r->count;
    uint32_t timer0 = co_loop_stats(&r->loop)->timer_wakeups;
    const uint8_t req[8] = {0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};
    peer_send(r, 0x605, req, 8);
    CHECK(run_until(r, has_sdo_answer));
    CHECK_EQ(co_loop_stats(&r->loop)->timer_wakeups, timer0);
    rig_close(r);
}

/* ---- a process starved past a deadline with the frame that meets it already received
 *
 * The peer's callback plays the bus and the scheduler at once: it puts the frame that meets
 * the node's deadline into the node's socket, then sleeps past that deadline (the process
 * does not run, the frame waits in the kernel). The loop must take the frame before it
 * judges the deadline. (Before: it polled first, and the time-out won.) */

static void sleep_ms(unsigned ms)
{
    struct timespec ts = {(time_t)(ms / 1000u), (long)(ms % 1000u) * 1000000L};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

/* The SDO server's answer to the initiate: the last segment goes out, then a stall of
 * twice the server's time-out. */
static void segment_then_stall(rig_t *r, const struct can_frame *f)
{
    if (f->can_id == 0x585 && f->data[0] == 0x60) {
        const uint8_t segment[8] = {0x07, 0x44, 0x33, 0x22, 0x11, 0, 0, 0}; /* 4 bytes, last */
        peer_send(r, 0x605, segment, 8);
        sleep_ms(400);
    }
}

static bool has_segment_answer(const rig_t *r)
{
    return seen_count(r, mark, 0x585, 0x20) + seen_count(r, mark, 0x585, 0x80) >= 1;
}

static void test_sdo_segment_received_before_the_time_out_counts(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 0);
    r->node.cfg.sdo_timeout_ms = 200;
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    CHECK(run_until(r, has_boot_up));
    mark = r->count;
    r->on_seen = segment_then_stall;
    const uint8_t initiate[8] = {0x21, 0x00, 0x20, 0x00, 4, 0, 0, 0}; /* 0x2000, 4 bytes */
    peer_send(r, 0x605, initiate, 8);
    CHECK(run_until(r, has_segment_answer));
    r->on_seen = NULL;
    CHECK_EQ(seen_count(r, mark, 0x585, 0x80), 0); /* no abort: neither time-out nor cs */
    CHECK_EQ(seen_count(r, mark, 0x585, 0x20), 1);
    CHECK_EQ(r->od.app_u32, 0x11223344u);
    rig_close(r);
}

/* Node 9's heartbeats answer node 5's (100 ms); the third comes, then a stall of 450 ms,
 * past node 5's 300 ms consumer time. */
static int beats_seen;

static void heartbeat_then_stall(rig_t *r, const struct can_frame *f)
{
    if (f->can_id == 0x705 && f->data[0] == 0x7F) {
        const uint8_t alive[1] = {0x7F};
        peer_send(r, 0x709, alive, 1);
        if (++beats_seen == 3) {
            sleep_ms(450);
        }
    }
}

static bool has_eight_beats(const rig_t *r) { return seen_count(r, mark, 0x705, 0x7F) >= 8; }

static void test_heartbeat_received_before_the_time_out_counts(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 100);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1016, 1, (9u << 16) | 300u), CO_ABORT_NONE);
    beats_seen = 0;
    r->on_seen = heartbeat_then_stall;
    mark = 0;
    CHECK(run_until(r, has_eight_beats));
    r->on_seen = NULL;
    CHECK(beats_seen >= 8);
    CHECK_EQ(co_hb_remote_state(&r->node, 9), CO_NMT_PRE_OPERATIONAL); /* watched */
    for (int i = 0; i < r->event_count; i++) {
        CHECK(r->events[i].kind != CO_EC_HB_TIMEOUT);
    }
    rig_close(r);
}

/* ---- two nodes, two transports, one loop */

static example_od_t od6;
static co_node_t node6;
static co_socketcan_t can6;
static int ec_started;

static bool node5_heard_by_6(void *ctx)
{
    (void)ctx;

    return ec_started == 1 && co_node_stats(&node6)->rx_frames >= 3;
}

static void on_errctl6(void *user, const co_ec_event_t *ev)
{
    (void)user;
    if (ev->kind == CO_EC_STARTED && ev->node_id == 5) {
        ec_started++;
    }
}

static void test_two_nodes_two_transports(void)
{
    /* Node 5 on end A, node 6 on end B of one socketpair: a two-station bus. Node 6
     * consumes node 5's heartbeat. */
    rig_t *r = &R;
    memset(r, 0, sizeof *r);
    int sv[2];
    CHECK(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv) == 0);
    CHECK_EQ(co_loop_init(&r->loop), CO_OK);
    CHECK_EQ(co_socketcan_open_fd(&r->can, sv[0]), CO_OK);
    CHECK_EQ(co_socketcan_open_fd(&can6, sv[1]), CO_OK);
    r->cfg.node_id = 5;
    r->cfg.od = example_od_init(&r->od, 50);
    CHECK_EQ(co_loop_add_node(&r->loop, &r->node, &r->cfg, &r->can.transport), CO_OK);
    co_node_config_t c6;
    memset(&c6, 0, sizeof c6);
    c6.node_id = 6;
    c6.od = example_od_init(&od6, 0);
    c6.on_errctl = on_errctl6;
    /* The same transport or the same node twice is refused. */
    CHECK_EQ(co_loop_add_node(&r->loop, &node6, &c6, &r->can.transport), CO_ERR_ARG);
    CHECK_EQ(co_loop_add_node(&r->loop, &node6, &c6, &can6.transport), CO_OK);
    uint64_t now = co_linux_now_us();
    CHECK_EQ(co_node_start(&node6, now), CO_OK);
    const uint8_t hb[4] = {0xF4, 0x01, 0x05, 0x00}; /* node 5, 500 ms */
    CHECK_EQ(co_node_write_net(&node6, 0x1016, 1, hb, 4), CO_ABORT_NONE);
    CHECK_EQ(co_node_start(&r->node, now), CO_OK);
    CHECK(loop_wait(&r->loop, node5_heard_by_6, NULL, NULL)); /* boot-up and two 50 ms beats */
    CHECK_EQ(ec_started, 1);
    CHECK(co_node_stats(&node6)->rx_frames >= 3);
    co_loop_close(&r->loop);
    co_socketcan_close(&r->can);
    co_socketcan_close(&can6);
}

/* ---- stopping */

static void test_sigterm_stops_the_loop(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 100);
    CHECK_EQ(co_loop_handle_signals(&r->loop), CO_OK);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    pid_t child = fork();
    if (child == 0) {
        usleep(150 * MS);
        kill(getppid(), SIGTERM);
        _exit(0);
    }
    co_loop_reason_t why = co_loop_run_until(&r->loop, co_linux_now_us() + BOUND_MS * MS);
    CHECK_EQ(why, CO_LOOP_SIGNAL); /* the signal ended the run, not its deadline */
    CHECK_EQ(co_loop_signal(&r->loop), SIGTERM);
    waitpid(child, NULL, 0);

    /* SIGINT too, even when it is already pending when the loop starts. */
    raise(SIGINT);
    why = co_loop_run_until(&r->loop, co_linux_now_us() + BOUND_MS * MS);
    CHECK_EQ(why, CO_LOOP_SIGNAL);
    CHECK_EQ(co_loop_signal(&r->loop), SIGINT);
    rig_close(r); /* restores the mask: the default actions are back */
    sigset_t cur;
    sigprocmask(SIG_BLOCK, NULL, &cur);
    CHECK(!sigismember(&cur, SIGTERM));
}

static void stop_on_first(void *ctx, int fd, uint32_t events)
{
    rig_t *r = ctx;
    peer_ready(ctx, fd, events);
    co_loop_stop(&r->loop);
}

static void test_stop_from_a_callback_and_remove_fd(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 100);
    CHECK_EQ(co_loop_remove_fd(&r->loop, r->peer), CO_OK);
    CHECK_EQ(co_loop_remove_fd(&r->loop, r->peer), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_loop_add_fd(&r->loop, r->peer, EPOLLIN, stop_on_first, r), CO_OK);
    CHECK_EQ(co_loop_add_fd(&r->loop, r->peer, EPOLLIN, stop_on_first, r), CO_ERR_ARG);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK); /* boot-up */
    co_loop_reason_t why = co_loop_run_until(&r->loop, co_linux_now_us() + BOUND_MS * MS);
    CHECK_EQ(why, CO_LOOP_STOPPED);
    CHECK(r->count >= 1);
    rig_close(r);
}

static void test_peer_gone_fails_the_transport(void)
{
    rig_t *r = &R;
    rig_open(r, 5, 100);
    CHECK_EQ(co_loop_remove_fd(&r->loop, r->peer), CO_OK);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    close(r->peer);
    r->peer = -1;
    co_loop_reason_t why = co_loop_run_until(&r->loop, co_linux_now_us() + BOUND_MS * MS);
    CHECK_EQ(why, CO_LOOP_TRANSPORT_FAILED);
    CHECK(co_loop_failed(&r->loop) == &r->can.transport);
    CHECK(strlen(r->can.transport.error) > 0);
    printf("  failed transport says: %s\n", r->can.transport.error);
    co_loop_close(&r->loop);
    co_socketcan_close(&r->can);
}

/* ---- a transport that is busy a few times: the node's frames wait and go out later */

typedef struct busy_transport {
    co_transport_t t;
    int busy_left;
    int sent;
    uint8_t last_state;
} busy_transport_t;

static busy_transport_t bt;

static bool bt_sent_one(void *ctx)
{
    (void)ctx;
    return bt.sent >= 1;
}

static co_rx_t bt_recv(co_transport_t *t, co_frame_t *f, uint32_t *ev)
{
    (void)t;
    (void)f;
    (void)ev;
    return CO_RX_AGAIN;
}

static co_err_t bt_send(co_transport_t *t, const co_frame_t *f)
{
    busy_transport_t *b = (busy_transport_t *)t;
    if (b->busy_left > 0) {
        b->busy_left--;
        return CO_ERR_BUSY;
    }
    b->sent++;
    b->last_state = f->data[0];
    return CO_OK;
}

static const co_transport_ops_t bt_ops = {.recv = bt_recv, .send = bt_send};

static co_err_t broken_send(co_transport_t *t, const co_frame_t *f)
{
    (void)f;
    co_transport_fail(t, "broken on purpose");
    return CO_ERR_STATE;
}

static const co_transport_ops_t broken_ops = {.recv = bt_recv, .send = broken_send};

static void test_failure_before_the_run_is_reported(void)
{
    /* The boot-up fails inside co_node_start, before the loop runs: the first run reports
     * it at once; the failed node is then left alone and a second run just runs. */
    rig_t *r = &R;
    memset(r, 0, sizeof *r);
    int pfd[2];
    CHECK(pipe(pfd) == 0);
    busy_transport_t broken = {.t = {.ops = &broken_ops, .fd = pfd[0]}};
    CHECK_EQ(co_loop_init(&r->loop), CO_OK);
    r->cfg.node_id = 9;
    r->cfg.od = example_od_init(&r->od, 100);
    CHECK_EQ(co_loop_add_node(&r->loop, &r->node, &r->cfg, &broken.t), CO_OK);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
    /* Reported at once: before the loop waited for anything. */
    CHECK_EQ(co_loop_run_until(&r->loop, co_linux_now_us() + BOUND_MS * MS),
             CO_LOOP_TRANSPORT_FAILED);
    CHECK_EQ(co_loop_stats(&r->loop)->wakeups, 0);
    CHECK(co_loop_failed(&r->loop) == &broken.t);
    CHECK_STR(broken.t.error, "broken on purpose");
    uint32_t dropped = co_node_stats(&r->node)->tx_dropped;
    CHECK_EQ(co_loop_run_until(&r->loop, co_linux_now_us() + 250 * MS), CO_LOOP_DEADLINE);
    CHECK_EQ(co_node_stats(&r->node)->tx_dropped, dropped); /* not polled any more */
    co_loop_close(&r->loop);
    close(pfd[0]);
    close(pfd[1]);
}

static void test_busy_transport_is_retried(void)
{
    rig_t *r = &R;
    memset(r, 0, sizeof *r);
    int pfd[2];
    CHECK(pipe(pfd) == 0);
    bt = (busy_transport_t){.t = {.ops = &bt_ops, .fd = pfd[0]}, .busy_left = 3};
    CHECK_EQ(co_loop_init(&r->loop), CO_OK);
    r->cfg.node_id = 9;
    r->cfg.od = example_od_init(&r->od, 0);
    CHECK_EQ(co_loop_add_node(&r->loop, &r->node, &r->cfg, &bt.t), CO_OK);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK); /* boot-up: busy */
    CHECK_EQ(bt.sent, 0);
    unsigned slices = 0;
    CHECK(loop_wait(&r->loop, bt_sent_one, NULL, &slices));
    CHECK_EQ(bt.sent, 1); /* the boot-up, after three refusals */
    CHECK_EQ(bt.last_state, 0x00);
    CHECK_EQ(co_loop_stats(&r->loop)->busy, 3);
    /* retried on a timer, not spinning: a wake-up per retry, one per slice, and spare */
    CHECK(co_loop_stats(&r->loop)->wakeups <= 6 + slices);
    co_loop_close(&r->loop);
    close(pfd[0]);
    close(pfd[1]);
}

static void test_bad_arguments(void)
{
    co_loop_t loop;
    CHECK_EQ(co_loop_init(NULL), CO_ERR_ARG);
    CHECK_EQ(co_loop_init(&loop), CO_OK);
    co_node_t node;
    co_node_config_t cfg;
    memset(&cfg, 0, sizeof cfg);
    co_socketcan_t closed;
    memset(&closed, 0, sizeof closed);
    closed.transport.fd = -1;
    CHECK_EQ(co_loop_add_node(&loop, &node, &cfg, &closed.transport), CO_ERR_ARG);
    CHECK_EQ(co_loop_add_node(&loop, &node, &cfg, NULL), CO_ERR_ARG);
    CHECK_EQ(co_loop_add_fd(&loop, -1, EPOLLIN, peer_ready, NULL), CO_ERR_ARG);
    CHECK_EQ(co_loop_add_fd(&loop, 0, EPOLLIN, NULL, NULL), CO_ERR_ARG);
    CHECK_STR(co_loop_reason_name(CO_LOOP_SIGNAL), "signal");
    co_loop_close(&loop);
    co_loop_close(&loop); /* twice is fine */
}

int main(void)
{
    alarm(120); /* bounded run time, even on a starved machine */
    setvbuf(stdout, NULL, _IOLBF, 0);
    RUN(test_boot_up_and_heartbeat_deadlines);
    RUN(test_no_busy_polling);
    RUN(test_frames_in_nmt_and_sdo);
    RUN(test_answered_on_arrival);
    RUN(test_sdo_segment_received_before_the_time_out_counts);
    RUN(test_heartbeat_received_before_the_time_out_counts);
    RUN(test_two_nodes_two_transports);
    RUN(test_sigterm_stops_the_loop);
    RUN(test_stop_from_a_callback_and_remove_fd);
    RUN(test_peer_gone_fails_the_transport);
    RUN(test_busy_transport_is_retried);
    RUN(test_failure_before_the_run_is_reported);
    RUN(test_bad_arguments);
    return check_summary();
}
