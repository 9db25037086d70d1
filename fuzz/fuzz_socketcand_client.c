/* SPDX-License-Identifier: Apache-2.0 */
/*
 * fuzz_socketcand_client.c -- libFuzzer target: canola's socketcand client
 * (port/linux/socketcand.c, the transport canola-node uses) against a hostile server on
 * the other end of a socketpair, which sends its bytes in chunks of any size.
 *
 * Input: a mode byte, then records:
 *   L (0..0xEF), then L bytes: a chunk the server writes; the client then reads all it can
 *   0xF0..0xFF, then 14 bytes: the client sends a frame (id u32, flags, len, 8 data bytes)
 * Mode bit 0 set: the whole rest is what the server says from the start, then it closes:
 * the handshake itself is fuzzed (it must end at once, in success or in a failure that
 * says why). Otherwise the server greets properly and the records follow in raw mode.
 *
 * Invariants (abort() = a finding):
 *   - every frame the client hands over is one CAN can carry (id in range, len <= 8,
 *     only the EXT and RTR flags), its receive buffer never holds more than its size,
 *     and a failure always says why (transport.error);
 *   - chunking does not matter: the same bytes written one at a time give the same
 *     frames and events, and the same failure at the same place;
 *   - sending never blocks and never fails while the connection is up: a full output
 *     buffer answers CO_ERR_BUSY (the server may not read at all);
 *   - nothing waits: the handshake ends as soon as the server has said all it will.
 *
 *   make fuzz                                                     # short run
 *   build-fuzz/fuzz_socketcand_client -max_total_time=3600 fuzz/corpus/socketcand_client
 */
#define _GNU_SOURCE
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "canola/socketcand.h"
#include "fuzz_reader.h"

#define OUT_MAX 512

/* What the client reported, in order. */
typedef struct outcome {
    co_frame_t frames[OUT_MAX];
    uint32_t events[OUT_MAX];
    uint8_t kinds[OUT_MAX]; /* CO_RX_FRAME or CO_RX_EVENTS */
    size_t count;           /* reports (only the first OUT_MAX kept) */
    size_t failed_at;       /* count when recv failed, or SIZE_MAX */
} outcome_t;

static co_socketcand_t g_sc;
static outcome_t g_out[2];
static uint8_t g_stream[1 << 16]; /* the chunks' bytes, in order, for the second run */

static void check(int ok)
{
    if (!ok) {
        abort();
    }
}

static void check_frame(const co_frame_t *f)
{
    check(f->len <= 8);
    check((f->flags & ~(CO_FRAME_EXT | CO_FRAME_RTR)) == 0);
    check(f->id <= ((f->flags & CO_FRAME_EXT) ? CO_ID_EXT_MAX : CO_ID_STD_MAX));
}

/* Read everything the client can make of what it has now. */
static void drain(co_socketcand_t *sc, outcome_t *o)
{
    while (o->failed_at == SIZE_MAX) {
        co_frame_t f;
        uint32_t ev = 0;
        co_rx_t rx = sc->transport.ops->recv(&sc->transport, &f, &ev);
        check(sc->rx_len <= sizeof sc->rx);
        if (rx == CO_RX_AGAIN) {
            return;
        }
        if (rx == CO_RX_ERROR) {
            check(sc->transport.error[0] != '\0');
            o->failed_at = o->count;
            return;
        }
        check(rx == CO_RX_FRAME || rx == CO_RX_EVENTS);
        if (rx == CO_RX_FRAME) {
            check_frame(&f);
        } else {
            check(ev != 0);
        }
        if (o->count < OUT_MAX) {
            o->kinds[o->count] = (uint8_t)rx;
            o->frames[o->count] = f;
            o->events[o->count] = rx == CO_RX_EVENTS ? ev : 0;
        }
        o->count++;
    }
}

static void write_all(int fd, const uint8_t *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        check(w > 0); /* the socketpair's buffer holds any input the fuzzer gives */
        p += w;
        n -= (size_t)w;
    }
}

/* The client connected to a server that greeted properly (the server's end in *server). */
static void connect_pair(co_socketcand_t *sc, int *server)
{
    int sv[2];
    check(socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) == 0);
    static const char greeting[] = "< hi >< ok >< ok >";
    write_all(sv[1], (const uint8_t *)greeting, sizeof greeting - 1);
    check(co_socketcand_open_fd(sc, sv[0], "bus0", 5000) == CO_OK);
    check(fcntl(sv[1], F_SETFL, O_NONBLOCK) == 0);
    *server = sv[1];
}

/* Read (and drop) what the client sent, so that its output can flow again. */
static void server_reads(int server)
{
    uint8_t sink[4096];
    while (read(server, sink, sizeof sink) > 0) {
    }
}

static void client_sends(co_socketcand_t *sc, reader_t *in, int server)
{
    co_frame_t f;
    f.id = (uint32_t)take(in) | (uint32_t)take(in) << 8 | (uint32_t)take(in) << 16 |
           (uint32_t)take(in) << 24;
    f.flags = take(in);
    f.len = take(in);
    for (int i = 0; i < 8; i++) {
        f.data[i] = take(in);
    }
    /* flag bits other than EXT and RTR mean nothing and are ignored */
    bool carried = f.len <= 8 && f.id <= ((f.flags & CO_FRAME_EXT) ? CO_ID_EXT_MAX : CO_ID_STD_MAX);
    co_err_t err = sc->transport.ops->send(&sc->transport, &f);
    check(carried ? (err == CO_OK || err == CO_ERR_BUSY) : err == CO_ERR_ARG);
    if (f.data[0] & 1u) { /* sometimes the server reads, sometimes it never does */
        server_reads(server);
    }
}

/* Handshake mode: the server says `data` and closes; the client must not wait. */
static void handshake(const uint8_t *data, size_t size)
{
    int sv[2];
    check(socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) == 0);
    write_all(sv[1], data, size);
    check(shutdown(sv[1], SHUT_WR) == 0);
    co_err_t rc = co_socketcand_open_fd(&g_sc, sv[0], "bus0", 60000); /* ends at EOF */
    if (rc == CO_OK) {
        g_out[0].failed_at = SIZE_MAX;
        g_out[0].count = 0;
        drain(&g_sc, &g_out[0]);
        check(g_out[0].failed_at != SIZE_MAX); /* the server has closed */
    } else {
        check(rc == CO_ERR_STATE && g_sc.transport.error[0] != '\0');
    }
    co_socketcand_close(&g_sc);
    close(sv[1]);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0;
    }
    if (data[0] & 1u) {
        handshake(data + 1, size - 1);
        return 0;
    }
    reader_t in = {data + 1, size - 1};
    size_t streamed = 0;
    int server;
    memset(g_out, 0, sizeof g_out);
    g_out[0].failed_at = g_out[1].failed_at = SIZE_MAX;
    /* First run: the chunks as the input cuts them, sends in between. */
    connect_pair(&g_sc, &server);
    while (in.n > 0 && g_out[0].failed_at == SIZE_MAX) {
        uint8_t len = take(&in);
        if (len >= 0xF0) {
            client_sends(&g_sc, &in, server);
            continue;
        }
        uint8_t chunk[0xF0];
        size_t n = 0;
        while (n < len && in.n > 0) {
            chunk[n++] = take(&in);
        }
        memcpy(&g_stream[streamed], chunk, n);
        streamed += n;
        write_all(server, chunk, n);
        drain(&g_sc, &g_out[0]);
    }
    close(server); /* the end: the client sees the connection closed */
    drain(&g_sc, &g_out[0]);
    check(g_out[0].failed_at != SIZE_MAX);
    co_socketcand_close(&g_sc);
    /* Second run: the same bytes one at a time. */
    connect_pair(&g_sc, &server);
    for (size_t i = 0; i < streamed && g_out[1].failed_at == SIZE_MAX; i++) {
        write_all(server, &g_stream[i], 1);
        drain(&g_sc, &g_out[1]);
    }
    close(server);
    drain(&g_sc, &g_out[1]);
    co_socketcand_close(&g_sc);
    const outcome_t *a = &g_out[0], *b = &g_out[1];
    check(a->count == b->count && a->failed_at == b->failed_at);
    for (size_t i = 0; i < a->count && i < OUT_MAX; i++) {
        check(a->kinds[i] == b->kinds[i] && a->events[i] == b->events[i]);
        const co_frame_t *x = &a->frames[i], *y = &b->frames[i];
        if (a->kinds[i] == CO_RX_FRAME) {
            check(x->id == y->id && x->flags == y->flags && x->len == y->len);
            check((x->flags & CO_FRAME_RTR) || memcmp(x->data, y->data, x->len) == 0);
        }
    }
    return 0;
}
