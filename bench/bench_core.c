/* SPDX-License-Identifier: Apache-2.0 */
/*
 * bench_core.c -- operations of a device on the firmware's own build, each run inside a
 * never-inlined function measure_<kind> so that callgrind (--toggle-collect=measure_<kind>)
 * counts exactly its instructions; bench/run divides by the iterations (and, for
 * transfers, by the bytes).
 *
 * The device is the one the size rows link (bench/size_firmware.c): the core in a profile's
 * configuration (configs/minimal.h or configs/default.h) with the compact dictionary that
 * canola.odgen generates from the size rows' EDS (ds301.h), driven through the public API
 * only. The transfer rows add one DOMAIN to that dictionary (0x2100, BIG bytes; built with
 * BENCH_DOMAIN): the profile has no object longer than 4 bytes.
 *
 * Every operation checks what the node answered: a wrong answer ends the program with
 * status 1 and no figure is taken. `bench_core check` runs every operation of the build a
 * few times with every frame the node sends checked (tests/CMakeLists.txt runs it as the
 * test of each profile's firmware build).
 *
 * usage: bench_core OPERATION [ITERATIONS] | bench_core check
 */
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canola/canola.h"
#include "ds301.h"

#define NODE_ID 1u
#define BIG 889u           /* one full block: 127 segments of 7 bytes */
#define VENDOR 0x12345678u /* 0x1018 sub 1, uploaded */
#define OTHER_NODE 3u      /* the node of the frame before each measured one (route miss) */
#define SDO_RX (0x600u + NODE_ID)
#define SDO_TX (0x580u + NODE_ID)
#define UPLOAD_HEAD (0x43u | 0x1018u << 8 | 0x01u << 24) /* 4 bytes of 0x1018 sub 1 */
#define DOWNLOAD_HEAD (0x60u | 0x1017u << 8)             /* 0x1017 sub 0 written */
#ifndef BENCH_DOMAIN
#define BENCH_DOMAIN 0
#endif

typedef struct bench {
    co_node_t node;
    co_frame_t frames[BIG / 7u + 8u];
    unsigned frame_count;
    uint64_t now_us;
    co_frame_t last_tx;
    /* check mode: every frame sent is logged, then compared */
    bool check;
    co_frame_t sent[BIG / 7u + 8u];
    unsigned sent_count;
    uint8_t big[BIG];
} bench_t;

static bench_t b;

static void fail(const char *op, const char *what)
{
    fprintf(stderr, "bench_core: %s: %s: the figure is void\n", op, what);
    exit(1);
}

/* Keeps the last frame sent (the measured runs: a store, as a driver's register write). */
static co_err_t tx_sink(void *ctx, const co_frame_t *frame)
{
    ((bench_t *)ctx)->last_tx = *frame;
    return CO_OK;
}

/* Logs every frame sent (check mode). */
static co_err_t tx_log(void *ctx, const co_frame_t *frame)
{
    bench_t *self = ctx;
    self->last_tx = *frame;
    if (self->sent_count < sizeof self->sent / sizeof self->sent[0]) {
        self->sent[self->sent_count] = *frame;
    }
    self->sent_count++;
    return CO_OK;
}

/* The configuration bench/bench_dictionary.py gives the dictionary (its power-on values,
 * as a DCF gives them): RPDO 1 writes 0x1280 sub 1 and 2, TPDO 1 reads 0x1200 sub 1 and 2
 * at every SYNC, 0x1018 sub 1 is VENDOR, a heartbeat every second (the idle poll has a
 * deadline), node 3's heartbeat consumed where the profile has a consumer. */
static void expect_configured(void)
{
    static const uint32_t k_values[][3] = {
        {0x1018, 1, VENDOR},
        {0x1017, 0, 1000},
        {0x1400, 1, 0x200u + NODE_ID},
        {0x1600, 0, 2},
        {0x1600, 1, 0x12800120u},
        {0x1600, 2, 0x12800220u},
        {0x1800, 2, 1},
        {0x1A00, 0, 2},
        {0x1A00, 1, 0x12000120u},
        {0x1A00, 2, 0x12000220u},
        {0x1016, 1, (OTHER_NODE << 16) | 1000u},
    };
    for (unsigned i = 0; i < sizeof k_values / sizeof k_values[0]; i++) {
        uint64_t v = 0;
        if (co_node_get_uint(&b.node, (uint16_t)k_values[i][0], (uint8_t)k_values[i][1], &v) !=
                CO_OK ||
            v != k_values[i][2]) {
            fprintf(stderr, "bench_core: 0x%04X sub %u is not configured (bench_dictionary.py)\n",
                    (unsigned)k_values[i][0], (unsigned)k_values[i][1]);
            exit(2);
        }
    }
}

/* The device as the firmware starts it, then operational. */
static void setup(void)
{
    co_od_reset(&ds301_od, 0x0000, 0xFFFF, NODE_ID);
    co_node_config_t cfg = {.node_id = NODE_ID, .od = ds301_od};
    cfg.driver.tx = b.check ? tx_log : tx_sink;
    cfg.driver.ctx = &b;
    co_err_t err = co_node_init(&b.node, &cfg);
    if (err != CO_OK) {
        fprintf(stderr, "bench_core: co_node_init refused the dictionary: %d\n", (int)err);
        exit(1);
    }
    if (co_node_start(&b.node, 0) != CO_OK || co_nmt_apply(&b.node, CO_NMT_CMD_START) != CO_OK) {
        fail("setup", "the node did not start");
    }
    expect_configured();
    b.sent_count = 0;
}

static co_frame_t sdo_req(const uint8_t d[8])
{
    co_frame_t f = {.id = SDO_RX, .len = 8};
    memcpy(f.data, d, 8);
    return f;
}

static void expect_sdo(const char *op, const co_frame_t *f, uint32_t head, uint32_t tail)
{
    if (f->id != SDO_TX || f->len != 8 || co_get_u32(&f->data[0]) != head ||
        co_get_u32(&f->data[4]) != tail) {
        fprintf(stderr, "bench_core: %s: answer %03X [%u] %08X %08X, expected %08X %08X\n", op,
                (unsigned)f->id, f->len, (unsigned)co_get_u32(&f->data[0]),
                (unsigned)co_get_u32(&f->data[4]), (unsigned)head, (unsigned)tail);
        exit(1);
    }
}

/* ---- the measured spans */

__attribute__((noinline)) uint64_t measure_poll_idle(bench_t *self)
{
    return co_node_poll(&self->node, self->now_us);
}

/* One frame into the node. */
__attribute__((noinline)) void measure_ingest(bench_t *self, unsigned i)
{
    co_node_ingest(&self->node, self->now_us, &self->frames[i % self->frame_count]);
}

/* A whole scripted transfer. */
__attribute__((noinline)) void measure_transfer(bench_t *self)
{
    for (unsigned i = 0; i < self->frame_count; i++) {
        co_node_ingest(&self->node, self->now_us, &self->frames[i]);
    }
}

/* ---- the operations: each sets up, runs `n` times (after another route's frame when
 * `miss`), and checks */

/* Frame i of the script into the node, after another node's NMT command (routed to NMT,
 * ignored: the measured frame is then on another route than the frame before it). */
static void run_ingest(unsigned n, bool miss)
{
    const co_frame_t other = {.id = 0x000, .len = 2, .data = {CO_NMT_CMD_START, OTHER_NODE}};
    for (unsigned i = 0; i < n; i++) {
        b.now_us = 1000u + i;
        if (miss) {
            co_node_ingest(&b.node, b.now_us, &other);
        }
        uint32_t sent = b.sent_count;
        measure_ingest(&b, i);
        if (b.check && b.sent_count != sent + 1u && b.frame_count != 0 &&
            b.frames[0].id == SDO_RX) {
            fail("sdo", "not one answer per request");
        }
    }
}

static void op_upload(const char *op, unsigned n, bool miss)
{
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0x40, 0x18, 0x10, 0x01});
    b.sent_count = 0;
    run_ingest(n, miss);
    expect_sdo(op, &b.last_tx, UPLOAD_HEAD, VENDOR);
    for (unsigned i = 0; b.check && i < b.sent_count; i++) {
        expect_sdo(op, &b.sent[i], UPLOAD_HEAD, VENDOR);
    }
}

/* 0x1017 (producer heartbeat time) written with 1000 and 2000 ms in turn. */
static void op_download(const char *op, unsigned n, bool miss)
{
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0x2B, 0x17, 0x10, 0x00, 0xE8, 0x03});
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0x2B, 0x17, 0x10, 0x00, 0xD0, 0x07});
    run_ingest(n, miss);
    expect_sdo(op, &b.last_tx, DOWNLOAD_HEAD, 0);
    for (unsigned i = 0; b.check && i < b.sent_count; i++) {
        if (b.sent[i].id != SDO_TX) {
            continue; /* the heartbeat the new time sends */
        }
        expect_sdo(op, &b.sent[i], DOWNLOAD_HEAD, 0);
    }
    uint64_t v = 0;
    if (co_node_get_uint(&b.node, 0x1017, 0, &v) != CO_OK || v != (n % 2 ? 1000u : 2000u)) {
        fail(op, "0x1017 does not hold the value written last");
    }
}

static void op_rpdo(const char *op, unsigned n, bool miss)
{
    b.frames[b.frame_count++] =
        (co_frame_t){.id = 0x200u + NODE_ID, .len = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
    b.frames[b.frame_count++] =
        (co_frame_t){.id = 0x200u + NODE_ID, .len = 8, .data = {8, 7, 6, 5, 4, 3, 2, 1}};
    run_ingest(n, miss);
    uint64_t v1 = 0;
    uint64_t v2 = 0;
    (void)co_node_get_uint(&b.node, 0x1280, 1, &v1);
    (void)co_node_get_uint(&b.node, 0x1280, 2, &v2);
    bool odd = n % 2 != 0;
    if (v1 != (odd ? 0x04030201u : 0x05060708u) || v2 != (odd ? 0x08070605u : 0x01020304u)) {
        fail(op, "the RPDO was not applied");
    }
    if (b.check && b.sent_count != 0) {
        fail(op, "an RPDO was answered");
    }
}

static void op_sync_tpdo(const char *op, unsigned n)
{
    b.frames[b.frame_count++] = (co_frame_t){.id = 0x080, .len = 0};
    run_ingest(n, false);
    const co_frame_t *f = &b.last_tx;
    if (f->id != 0x180u + NODE_ID || f->len != 8 || co_get_u32(&f->data[0]) != SDO_RX ||
        co_get_u32(&f->data[4]) != SDO_TX) {
        fail(op, "no TPDO of 0x1200 sub 1 and 2 followed the SYNC");
    }
    if (b.check && b.sent_count != n) {
        fail(op, "not one TPDO per SYNC");
    }
}

static void op_nmt(const char *op, unsigned n)
{
    /* start, then pre-operational, all nodes: both change the state */
    b.frames[b.frame_count++] = (co_frame_t){.id = 0x000, .len = 2, .data = {0x80, 0x00}};
    b.frames[b.frame_count++] = (co_frame_t){.id = 0x000, .len = 2, .data = {0x01, 0x00}};
    run_ingest(n, false);
    co_nmt_state_t want = n % 2 ? CO_NMT_PRE_OPERATIONAL : CO_NMT_OPERATIONAL;
    if (co_nmt_state(&b.node) != want) {
        fail(op, "the NMT command was not applied");
    }
}

#if CO_HB_CONSUMERS_MAX > 0
static void op_heartbeat(const char *op, unsigned n)
{
    b.frames[b.frame_count++] = (co_frame_t){.id = 0x700u + OTHER_NODE, .len = 1, .data = {0x05}};
    co_node_ingest(&b.node, 0, &b.frames[0]); /* monitoring starts at the first one */
    uint32_t unrouted = co_node_stats(&b.node)->rx_unrouted;
    run_ingest(n, false);
    if (co_node_stats(&b.node)->rx_unrouted != unrouted || b.sent_count != 0) {
        fail(op, "the heartbeat was not consumed");
    }
}
#endif

static void op_poll(const char *op, unsigned n)
{
    (void)co_node_poll(&b.node, 1); /* the start's due work */
    uint64_t next = co_node_poll(&b.node, 2);
    uint64_t sink = 0;
    for (unsigned i = 0; i < n && next > 3u + n; i++) {
        b.now_us = 3u + i;
        sink += measure_poll_idle(&b);
    }
    if (next <= 3u + n || sink != (uint64_t)n * next || b.sent_count != 0) {
        fail(op, "a poll found work due");
    }
}

#if BENCH_DOMAIN
/* ---- transfers of 0x2100 (a DOMAIN of BIG bytes) */

static void script_segmented_download(void)
{
    uint8_t init[8] = {0x21, 0x00, 0x21, 0x00};
    co_put_u32(&init[4], BIG);
    b.frames[b.frame_count++] = sdo_req(init);
    uint32_t off = 0;
    uint8_t toggle = 0;
    while (off < BIG) {
        uint32_t n = BIG - off < 7 ? BIG - off : 7;
        uint8_t d[8] = {
            (uint8_t)((uint32_t)toggle << 4 | (7u - n) << 1 | (off + n >= BIG ? 1u : 0u))};
        memcpy(&d[1], &b.big[off], n);
        b.frames[b.frame_count++] = sdo_req(d);
        off += n;
        toggle ^= 1;
    }
}

static void script_segmented_upload(void)
{
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0x40, 0x00, 0x21, 0x00});
    for (unsigned i = 0; i < (BIG + 6) / 7; i++) {
        uint8_t d[8] = {(uint8_t)(0x60 | ((i & 1) << 4))};
        b.frames[b.frame_count++] = sdo_req(d);
    }
}

static uint16_t crc16(const uint8_t *data, uint32_t len)
{
    uint16_t crc = 0;
    for (uint32_t i = 0; i < len; i++) { /* bitwise CRC-16-CCITT, independent of the core */
        crc ^= (uint16_t)(data[i] << 8);
        for (int k = 0; k < 8; k++) {
            crc = (uint16_t)((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
        }
    }
    return crc;
}

static void script_block_download(void)
{
    uint8_t init[8] = {0xC6, 0x00, 0x21, 0x00};
    co_put_u32(&init[4], BIG);
    b.frames[b.frame_count++] = sdo_req(init);
    for (unsigned seq = 1; seq <= 127; seq++) {
        uint8_t d[8] = {(uint8_t)(seq | (seq == 127 ? 0x80 : 0))};
        memcpy(&d[1], &b.big[(seq - 1) * 7], 7);
        b.frames[b.frame_count++] = sdo_req(d);
    }
    uint16_t crc = crc16(b.big, BIG);
    b.frames[b.frame_count++] =
        sdo_req((const uint8_t[8]){0xC1, (uint8_t)crc, (uint8_t)(crc >> 8)});
}

static void script_block_upload(void)
{
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0xA4, 0x00, 0x21, 0x00, 127, 0});
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0xA3});
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0xA2, 127, 127});
    b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0xA1});
}

/* The DOMAIN holds `big` (uploads read it). */
static void fill_domain(const char *op)
{
    if (co_node_write_net(&b.node, 0x2100, 0, b.big, BIG) != CO_ABORT_NONE) {
        fail(op, "0x2100 cannot be written");
    }
}

static void expect_domain(const char *op)
{
    uint8_t got[BIG];
    uint32_t len = 0;
    if (co_node_read_net(&b.node, 0x2100, 0, got, sizeof got, &len) != CO_ABORT_NONE ||
        len != BIG || memcmp(got, b.big, BIG) != 0) {
        fail(op, "0x2100 does not hold the bytes downloaded");
    }
}

/* The segments an upload sent (check mode) carry the DOMAIN's bytes. */
static void expect_uploaded(const char *op, bool block)
{
    uint8_t got[BIG + 7];
    uint32_t at = 0;
    for (unsigned i = 0; i < b.sent_count && i < sizeof b.sent / sizeof b.sent[0]; i++) {
        const uint8_t *d = b.sent[i].data;
        bool segment = block ? (i >= 1 && i <= 127) : i >= 1;
        if (segment && at + 7 <= sizeof got) {
            memcpy(&got[at], &d[1], 7);
            at += 7;
        }
    }
    if (at < BIG || memcmp(got, b.big, BIG) != 0) {
        fail(op, "the segments do not carry the DOMAIN's bytes");
    }
}

static void op_transfer(const char *op, unsigned n)
{
    for (unsigned i = 0; i < BIG; i++) {
        b.big[i] = (uint8_t)(i * 7u + 3u);
    }
    bool down = strstr(op, "download") != NULL;
    bool block = strstr(op, "block") != NULL;
    if (!down) {
        fill_domain(op);
    }
    if (block) {
        down ? script_block_download() : script_block_upload();
    } else {
        down ? script_segmented_download() : script_segmented_upload();
    }
    for (unsigned i = 0; i < n; i++) {
        b.now_us = 1000u + i;
        b.sent_count = 0;
        measure_transfer(&b);
        const uint8_t *last = b.last_tx.data;
        bool ok = b.last_tx.id == SDO_TX &&
                  (block ? (down ? last[0] == 0xA1 : (last[0] & 0xE3) == 0xC1)
                         : (down ? (last[0] & 0xEF) == 0x20 : (last[0] & 0xE1) == 0x01));
        if (!ok) {
            fprintf(stderr, "bench_core: %s: last answer %02X (abort %08X)\n", op, last[0],
                    (unsigned)co_get_u32(&last[4]));
            exit(1);
        }
        if (b.check && !down) {
            expect_uploaded(op, block);
        }
    }
    if (down) {
        expect_domain(op);
    }
}
#endif

/* ---- main */

typedef struct op {
    const char *name;
    void (*run)(const char *op, unsigned n); /* NULL: one of the miss-able ones below */
} op_t;

static void op_upload_hit(const char *op, unsigned n) { op_upload(op, n, false); }
static void op_upload_miss(const char *op, unsigned n) { op_upload(op, n, true); }
static void op_download_hit(const char *op, unsigned n) { op_download(op, n, false); }
static void op_download_miss(const char *op, unsigned n) { op_download(op, n, true); }
static void op_rpdo_hit(const char *op, unsigned n) { op_rpdo(op, n, false); }
static void op_rpdo_miss(const char *op, unsigned n) { op_rpdo(op, n, true); }

static const op_t k_ops[] = {
    {"poll_idle", op_poll},
    {"nmt_command", op_nmt},
#if CO_HB_CONSUMERS_MAX > 0
    {"heartbeat_consumed", op_heartbeat},
#endif
    {"sdo_expedited_upload", op_upload_hit},
    {"sdo_expedited_upload_after_other", op_upload_miss},
    {"sdo_expedited_download", op_download_hit},
    {"sdo_expedited_download_after_other", op_download_miss},
    {"rpdo_2x_u32", op_rpdo_hit},
    {"rpdo_2x_u32_after_other", op_rpdo_miss},
    {"sync_tpdo", op_sync_tpdo},
#if BENCH_DOMAIN && CO_CONFIG_SDO_SEGMENTED
    {"sdo_segmented_download", op_transfer},
    {"sdo_segmented_upload", op_transfer},
#endif
#if BENCH_DOMAIN && CO_CONFIG_SDO_BLOCK
    {"sdo_block_download", op_transfer},
    {"sdo_block_upload", op_transfer},
#endif
};
#define OPS (sizeof k_ops / sizeof k_ops[0])

static void run_op(const op_t *op, unsigned n)
{
    memset(&b, 0, offsetof(bench_t, check));
    b.sent_count = 0;
    setup();
    op->run(op->name, n);
}

int main(int argc, char **argv)
{
    const char *name = argc > 1 ? argv[1] : "";
    unsigned n = argc > 2 ? (unsigned)strtoul(argv[2], NULL, 10) : 200;
    if (strcmp(name, "check") == 0) {
        b.check = true;
        for (unsigned i = 0; i < OPS; i++) {
            run_op(&k_ops[i], 5);
            printf("ok %s\n", k_ops[i].name);
        }
        return 0;
    }
    if (strcmp(name, "list") == 0) {
        for (unsigned i = 0; i < OPS; i++) {
            printf("%s\n", k_ops[i].name);
        }
        return 0;
    }
    for (unsigned i = 0; i < OPS; i++) {
        if (strcmp(name, k_ops[i].name) == 0) {
            run_op(&k_ops[i], n);
            return 0;
        }
    }
    fprintf(stderr, "bench_core: no operation '%s' in this build (bench_core list)\n", name);
    return 2;
}
