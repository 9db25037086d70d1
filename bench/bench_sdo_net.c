/* SPDX-License-Identifier: Apache-2.0 */
/*
 * bench_sdo_net.c -- SDO between a canola client node and a canola server node: block
 * transfer throughput on the simulated bus's timing model, and expedited round trips per
 * second of wall-clock time. Not a test: it prints figures and bench/run formats them; but
 * a transfer that aborts or delivers wrong data ends the run with exit status 1 and a
 * message on stderr, so a broken stack never produces a figure.
 *
 * usage: bench_sdo_net block_download [BYTES]   -> bytes=.. sim_us=.. limit_us=.. ...
 *        bench_sdo_net block_upload [BYTES]
 *        bench_sdo_net expedited_rtt [ROUND_TRIPS [RUNS]] -> round_trips=.. best_ns=.. ...
 *
 * Block rows: client node 1 and server node 5 on co_sim_bus_init(&bus, 1000000); the
 * client asks for block size 127 with CRC; the server's 0x3000 is a DOMAIN with no storage
 * whose read hook produces a pattern (seed 17) and whose write hook checks it
 * (examples/pattern_domain.h). sim_us is simulated time from the call that starts the
 * transfer to the end of the transfer's last frame on the bus (interframe space included),
 * as a listening raw port sees it; done_us is the time to the done callback. They are
 * equal for a download (the server's end response is the last frame); a block upload's
 * client reports done when it sends its end response, one frame before the bus is through,
 * so sim_us is the figure comparable with the limit, which counts that frame too.
 * Deterministic: no repetition needed.
 *
 * The limit: the bus time of exactly the frames the protocol needs, back to back. Every
 * frame is built here as the protocol defines it, with the transfer's real payload bytes,
 * sequence numbers and CRC (unused bytes zero, as canola sends them), and measured with
 * co_sim_frame_bits(), so each frame carries its actual stuff bits:
 *   download: initiate (0xC6, size) + response (0xA4, blksize), ceil(N/7) segments,
 *             one acknowledgement per sub-block of 127 segments (the last one shorter),
 *             end (0xC1 | n << 2, CRC) + end response (0xA1);
 *   upload:   the same plus the client's start frame (0xA3), which block upload needs
 *             between the initiate response and the first segment.
 * The sum of bits divided by the bit rate is the shortest time any implementation can take.
 *
 * Round-trip row: the stack alone, not the simulator. The two nodes are joined by a pair of
 * direct drivers: each tx appends the frame to one small FIFO tagged with the other node,
 * and the main loop delivers the FIFO with co_node_ingest() (a FIFO rather than a nested
 * ingest, because a driver must not call back into ingest and 200,000 nested round trips
 * would exhaust the stack). No acceptance filter, no timing model, no poll: time is a
 * counter that advances one microsecond per delivered frame, so no deadline ever falls due.
 * The client uploads 0x1000 sub 0 (a u32) from the server, and starts the next upload from
 * the done callback. Wall-clock time by clock_gettime(CLOCK_MONOTONIC); best of RUNS.
 */
#define _POSIX_C_SOURCE 199309L

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "canola/canola.h"
#include "canola/sim.h"
#include "pattern_domain.h"

#define CLIENT_ID 1u
#define SERVER_ID 5u
#define REQ_ID (0x600u + SERVER_ID) /* client -> server */
#define RSP_ID (0x580u + SERVER_ID) /* server -> client */
#define STREAM_INDEX 0x3000u
#define BLKSIZE 127u
#define BITRATE 1000000u
#define DEVICE_TYPE 0x00020192u
#define PATTERN_SEED 17u /* the data of block transfers */

static const char *g_op = "";

static void die(const char *what)
{
    fprintf(stderr, "bench_sdo_net: %s: %s: no figure\n", g_op, what);
    exit(1);
}

/* Bitwise CRC-16-CCITT (0x1021, initial 0), independent of the core's. */
static uint16_t crc16(const uint8_t *d, uint32_t n)
{
    uint16_t crc = 0;
    for (uint32_t i = 0; i < n; i++) {
        crc ^= (uint16_t)(d[i] << 8);
        for (int k = 0; k < 8; k++) {
            crc = (uint16_t)((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
        }
    }
    return crc;
}

/* ---- the nodes' dictionaries */

typedef struct peer {
    uint32_t device_type;
    co_od_entry_t entries[2];
    pattern_domain_t stream;
    co_node_t node;
    co_sim_port_t port;
} peer_t;

/* 0x1000 (u32, read-only) and, for the server, 0x3000 (streamed DOMAIN). */
static co_od_t peer_od(peer_t *p, bool server)
{
    p->device_type = DEVICE_TYPE;
    p->entries[0] = (co_od_entry_t){.index = 0x1000,
                                    .type = CO_TYPE_UNSIGNED32,
                                    .attr = CO_OD_RO,
                                    .size = 4,
                                    .value = &p->device_type};
    p->entries[1] = pattern_domain_entry(STREAM_INDEX);
    return (co_od_t){.entries = p->entries, .count = server ? 2u : 1u, .hook_ctx = &p->stream};
}

static void peer_start(peer_t *p, uint8_t id, bool server, co_driver_t driver, uint64_t now)
{
    co_node_config_t cfg = {.node_id = id, .od = peer_od(p, server), .driver = driver};
    if (co_node_init(&p->node, &cfg) != CO_OK || co_node_start(&p->node, now) != CO_OK) {
        die("node setup failed");
    }
}

/* ---- block transfer on the timing model */

typedef struct result {
    bool done;
    co_abort_t abort;
    uint32_t len;
    uint64_t at_us;
    const co_sim_bus_t *bus;
} result_t;

/* A raw port that only listens (it sends nothing, so the timing is unchanged): the time at
 * which the latest frame left the bus. */
static void on_monitor(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    (void)frame;
    *(uint64_t *)ctx = now_us;
}

static void on_block_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    result_t *r = ctx;
    r->done = true;
    r->abort = abort;
    r->len = len;
    r->at_us = r->bus->now_us;
}

/* Bits of one 8-byte SDO frame. */
static uint64_t bits8(uint32_t id, const uint8_t d[8])
{
    co_frame_t f = {.id = id, .len = 8};
    memcpy(f.data, d, 8);
    return co_sim_frame_bits(&f);
}

typedef struct limit {
    uint64_t bits;
    uint64_t frames;
} limit_t;

static void add(limit_t *l, uint32_t id, const uint8_t d[8])
{
    l->bits += bits8(id, d);
    l->frames++;
}

/* The frames of a block transfer of `data` (see the top of the file). `seg_id` carries the
 * segments and the end request, `ack_id` the acknowledgements and the end response. */
static limit_t block_limit(const uint8_t *data, uint32_t n, bool upload)
{
    limit_t l = {0};
    uint8_t lo = (uint8_t)STREAM_INDEX, hi = (uint8_t)(STREAM_INDEX >> 8);
    uint32_t seg_id = upload ? RSP_ID : REQ_ID;
    uint32_t ack_id = upload ? REQ_ID : RSP_ID;
    uint8_t size[4] = {(uint8_t)n, (uint8_t)(n >> 8), (uint8_t)(n >> 16), (uint8_t)(n >> 24)};
    if (upload) {
        add(&l, REQ_ID, (const uint8_t[8]){0xA4, lo, hi, 0, BLKSIZE, 0});
        add(&l, RSP_ID, (const uint8_t[8]){0xC6, lo, hi, 0, size[0], size[1], size[2], size[3]});
        add(&l, REQ_ID, (const uint8_t[8]){0xA3});
    } else {
        add(&l, REQ_ID, (const uint8_t[8]){0xC6, lo, hi, 0, size[0], size[1], size[2], size[3]});
        add(&l, RSP_ID, (const uint8_t[8]){0xA4, lo, hi, 0, BLKSIZE});
    }
    uint32_t segments = (n + 6) / 7;
    uint32_t seq = 0;
    for (uint32_t s = 0; s < segments; s++) {
        uint32_t off = s * 7;
        uint32_t k = n - off < 7 ? n - off : 7;
        bool last = s + 1 == segments;
        uint8_t d[8] = {(uint8_t)(++seq | (last ? 0x80u : 0u))};
        memcpy(&d[1], &data[off], k);
        add(&l, seg_id, d);
        if (seq == BLKSIZE || last) {
            add(&l, ack_id, (const uint8_t[8]){0xA2, (uint8_t)seq, BLKSIZE});
            seq = 0;
        }
    }
    uint16_t crc = crc16(data, n);
    uint8_t unused = (uint8_t)((7 - n % 7) % 7);
    add(&l, seg_id,
        (const uint8_t[8]){(uint8_t)(0xC1 | unused << 2), (uint8_t)crc, (uint8_t)(crc >> 8)});
    add(&l, ack_id, (const uint8_t[8]){0xA1});
    return l;
}

static int run_block(bool upload, uint32_t n)
{
    co_sim_bus_t *bus = calloc(1, sizeof *bus);
    peer_t *srv = calloc(1, sizeof *srv);
    peer_t *cli = calloc(1, sizeof *cli);
    uint8_t *buf = malloc(n ? n : 1);
    co_sim_port_t monitor;
    uint64_t last_frame_us = 0;
    if (!bus || !srv || !cli || !buf) {
        die("out of memory");
    }
    if (upload) {
        memset(buf, 0, n);
    } else {
        pattern_fill(buf, PATTERN_SEED, n);
    }
    if (co_sim_bus_init(bus, BITRATE) != CO_OK || co_sim_port_attach(bus, &srv->port) != CO_OK ||
        co_sim_port_attach(bus, &cli->port) != CO_OK ||
        co_sim_port_attach_raw(bus, &monitor, on_monitor, &last_frame_us) != CO_OK) {
        die("bus setup failed");
    }
    peer_start(srv, SERVER_ID, true, co_sim_port_driver(&srv->port), 0);
    co_sim_port_bind(&srv->port, &srv->node);
    peer_start(cli, CLIENT_ID, false, co_sim_port_driver(&cli->port), 0);
    co_sim_port_bind(&cli->port, &cli->node);
    if (co_sdo_client_setup(&cli->node, 0, SERVER_ID) != CO_OK ||
        co_sdo_client_block_options(&cli->node, 0, BLKSIZE, true, 0) != CO_OK) {
        die("client setup failed");
    }
    co_sim_run_until(bus, 10000); /* boot-up frames gone, bus idle */

    srv->stream =
        (pattern_domain_t){.length = n, .up_seed = PATTERN_SEED, .down_seed = PATTERN_SEED};
    result_t r = {.bus = bus};
    uint64_t t0 = bus->now_us;
    uint64_t boot_frames = co_sim_stats(bus)->frames;
    co_err_t err = upload ? co_sdo_upload(&cli->node, 0, STREAM_INDEX, 0, CO_SDO_BLOCK, buf, n,
                                          on_block_done, &r)
                          : co_sdo_download(&cli->node, 0, STREAM_INDEX, 0, CO_SDO_BLOCK, buf, n,
                                            on_block_done, &r);
    if (err != CO_OK) {
        die("the transfer did not start");
    }
    /* The bus needs about 19 us per payload byte (a 1 MiB transfer: 20 s of simulated
     * time); 150 us per byte and a second more means the transfer hung. */
    uint64_t limit_us = t0 + 1000000u + (uint64_t)n * 150u;
    while (!r.done && bus->now_us < limit_us) {
        if (co_sim_run_until(bus, bus->now_us + 100000u) != CO_OK) {
            die("the simulated bus stopped");
        }
    }
    if (!r.done) {
        die("the transfer never finished");
    }
    co_sim_run_until(bus, bus->now_us + 10000u); /* the last frame may still be on the bus */
    if (r.abort != CO_ABORT_NONE) {
        fprintf(stderr, "bench_sdo_net: %s: transfer aborted with 0x%08X: no figure\n", g_op,
                (unsigned)r.abort);
        exit(1);
    }
    if (r.len != n) {
        die("the transfer reported a wrong length");
    }
    if (upload) {
        if (!pattern_matches(buf, PATTERN_SEED, n)) {
            die("the uploaded data is wrong");
        }
    } else if (!pattern_domain_received(&srv->stream, n)) {
        die("the server received wrong data");
    }

    limit_t l = block_limit(buf, n, upload);
    const co_sim_stats_t *st = co_sim_stats(bus);
    printf("bytes=%u sim_us=%llu limit_us=%.1f done_us=%llu frames=%llu limit_frames=%llu "
           "bitrate=%u\n",
           n, (unsigned long long)(last_frame_us - t0), (double)l.bits * 1e6 / BITRATE,
           (unsigned long long)(r.at_us - t0), (unsigned long long)(st->frames - boot_frames),
           (unsigned long long)l.frames, BITRATE);
    free(buf);
    free(cli);
    free(srv);
    free(bus);
    return 0;
}

/* ---- expedited round trips through a pair of direct drivers */

#define FIFO_LEN 64u /* power of two */

typedef struct hop {
    co_node_t *to;
    co_frame_t frame;
} hop_t;

static struct {
    hop_t q[FIFO_LEN];
    uint32_t head, tail;
} g_fifo;

/* Driver context: the node on the other end of the wire. */
static co_err_t direct_tx(void *ctx, const co_frame_t *frame)
{
    if (g_fifo.tail - g_fifo.head == FIFO_LEN) {
        return CO_ERR_BUSY;
    }
    hop_t *h = &g_fifo.q[g_fifo.tail++ % FIFO_LEN];
    h->to = *(co_node_t **)ctx;
    h->frame = *frame;
    return CO_OK;
}

typedef struct rtt {
    co_node_t *client;
    uint32_t left;
    uint32_t value;
    uint8_t buf[4];
    bool failed;
    co_abort_t abort;
} rtt_t;

static void start_upload(rtt_t *t);

static void on_rtt_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    rtt_t *t = ctx;
    if (abort != CO_ABORT_NONE || len != 4 || co_get_u32(t->buf) != DEVICE_TYPE) {
        t->failed = true;
        t->abort = abort;
        return;
    }
    if (--t->left > 0) {
        start_upload(t);
    }
}

static void start_upload(rtt_t *t)
{
    memset(t->buf, 0, sizeof t->buf);
    if (co_sdo_upload(t->client, 0, 0x1000, 0, CO_SDO_EXPEDITED, t->buf, sizeof t->buf, on_rtt_done,
                      t) != CO_OK) {
        t->failed = true;
    }
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int run_rtt(uint32_t round_trips, uint32_t runs)
{
    static peer_t srv, cli;
    static co_node_t *to_srv = &srv.node, *to_cli = &cli.node;
    uint64_t now = 0;
    peer_start(&srv, SERVER_ID, true, (co_driver_t){.tx = direct_tx, .ctx = &to_cli}, now);
    peer_start(&cli, CLIENT_ID, false, (co_driver_t){.tx = direct_tx, .ctx = &to_srv}, now);
    if (co_sdo_client_setup(&cli.node, 0, SERVER_ID) != CO_OK) {
        die("client setup failed");
    }
    while (g_fifo.head != g_fifo.tail) { /* the boot-up frames, before any clock runs */
        hop_t h = g_fifo.q[g_fifo.head++ % FIFO_LEN];
        co_node_ingest(h.to, ++now, &h.frame);
    }
    double best = 0;
    uint64_t delivered = 0;
    for (uint32_t run = 0; run < runs; run++) {
        rtt_t t = {.client = &cli.node, .left = round_trips};
        double t0 = now_s();
        start_upload(&t);
        while (g_fifo.head != g_fifo.tail) {
            hop_t h = g_fifo.q[g_fifo.head++ % FIFO_LEN];
            co_node_ingest(h.to, ++now, &h.frame);
            delivered++;
        }
        double s = now_s() - t0;
        if (t.failed) {
            fprintf(stderr, "bench_sdo_net: %s: round trip %u failed (abort 0x%08X): no figure\n",
                    g_op, round_trips - t.left + 1, (unsigned)t.abort);
            exit(1);
        }
        if (t.left != 0) {
            die("the round trips stopped before the end");
        }
        best = run == 0 || s < best ? s : best;
    }
    if (co_node_stats(&cli.node)->tx_overflow || co_node_stats(&srv.node)->tx_overflow) {
        die("frames were lost");
    }
    printf("round_trips=%u runs=%u best_ns=%.0f frames=%llu rate=%.0f\n", round_trips, runs,
           best * 1e9, (unsigned long long)delivered, round_trips / best);
    return 0;
}

int main(int argc, char **argv)
{
    g_op = argc > 1 ? argv[1] : "";
    if (strcmp(g_op, "block_download") == 0 || strcmp(g_op, "block_upload") == 0) {
        uint32_t n = argc > 2 ? (uint32_t)strtoul(argv[2], NULL, 10) : 1024u * 1024u;
        if (n == 0) {
            die("a transfer of at least 1 byte, please");
        }
        return run_block(strcmp(g_op, "block_upload") == 0, n);
    }
    if (strcmp(g_op, "expedited_rtt") == 0) {
        uint32_t n = argc > 2 ? (uint32_t)strtoul(argv[2], NULL, 10) : 200000u;
        uint32_t runs = argc > 3 ? (uint32_t)strtoul(argv[3], NULL, 10) : 3u;
        if (n == 0 || runs == 0) {
            die("round trips and runs must be at least 1");
        }
        return run_rtt(n, runs);
    }
    fprintf(stderr, "bench_sdo_net: unknown operation '%s'\n", g_op);
    return 2;
}
