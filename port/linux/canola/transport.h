/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/transport.h -- a CAN transport for the Linux event loop (port/linux).
 *
 * A transport is one file descriptor that carries CAN frames, with functions to read a
 * frame and write a frame: a SocketCAN raw socket (canola/socketcan.h), a TCP connection
 * to a socketcand server or hub (canola/socketcand.h), or anything a test makes. The
 * event loop (canola/linux_loop.h) waits for the fd to become readable and then calls
 * recv until it answers CO_RX_AGAIN; it never blocks inside a transport.
 *
 * A concrete transport embeds co_transport_t as its first member and fills `ops` and
 * `fd` when it opens. One node per transport: a second node on the same bus gets its own
 * socket or connection (the kernel or the hub delivers frames between them, as the
 * bus would).
 *
 * Not part of the portable core: Linux only. Not thread-safe.
 */
#ifndef CANOLA_TRANSPORT_H
#define CANOLA_TRANSPORT_H

#include "canola/node.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What recv found. */
typedef enum co_rx {
    CO_RX_ERROR = -1, /**< the transport failed or the peer closed: see co_transport_t.error */
    CO_RX_AGAIN = 0,  /**< nothing more to read now */
    CO_RX_FRAME = 1,  /**< *frame holds a received frame */
    CO_RX_EVENTS = 2, /**< *events holds bus events: bit (1u << co_bus_event_t) per event */
} co_rx_t;

typedef struct co_transport co_transport_t;

typedef struct co_transport_ops {
    /** Read the next frame or bus events without blocking. */
    co_rx_t (*recv)(co_transport_t *t, co_frame_t *frame, uint32_t *events);
    /** Write one frame without blocking: CO_OK (taken), CO_ERR_BUSY (no room now: try
     *  again when `pending` is false or after a short while), CO_ERR_ARG (this frame
     *  cannot be carried: the node drops it), CO_ERR_STATE (broken: set error). */
    co_err_t (*send)(co_transport_t *t, const co_frame_t *frame);
    /** Optional: true while output waits in the transport's own buffer (the loop then
     *  waits for the fd to become writable and calls flush). */
    bool (*pending)(const co_transport_t *t);
    /** Optional: true while whole received messages wait in the transport's own buffer
     *  (the fd will not become readable for them: the loop calls recv anyway). */
    bool (*buffered)(const co_transport_t *t);
    /** Optional: write buffered output. CO_OK when all of it went, CO_ERR_BUSY when
     *  some is left, CO_ERR_STATE when the transport broke. */
    co_err_t (*flush)(co_transport_t *t);
    /** Optional: the node's receive routes changed; reprogram a filter. */
    void (*set_filter)(co_transport_t *t, const co_node_t *node);
    /** Close the fd (safe to call twice). */
    void (*close)(co_transport_t *t);
} co_transport_ops_t;

#define CO_TRANSPORT_ERROR_MAX 128

struct co_transport {
    const co_transport_ops_t *ops;
    int fd;                             /**< -1 when closed */
    char error[CO_TRANSPORT_ERROR_MAX]; /**< why it failed: one line, empty when fine */
};

/** Microseconds of CLOCK_MONOTONIC: the clock to give co_node_start, co_node_ingest and
 *  co_node_poll on Linux (the event loop's clock, canola/linux_loop.h). Never fails. */
uint64_t co_linux_now_us(void);

/** Close a transport through its ops (NULL-safe). */
void co_transport_close(co_transport_t *t);

/** For transport writers: record why `t` failed (printf format, cut to one line of
 *  CO_TRANSPORT_ERROR_MAX - 1 characters). */
void co_transport_fail(co_transport_t *t, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_TRANSPORT_H */
