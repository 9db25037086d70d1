/* SPDX-License-Identifier: Apache-2.0 */
/*
 * bench_core.c -- operations of the core, each run inside a never-inlined function
 * measure_<operation> so that callgrind (--toggle-collect=measure_<operation>)
 * counts exactly its instructions. Not a test: it asserts nothing; bench/run runs
 * it under valgrind and divides by the iterations (and, for transfers, by bytes).
 *
 * usage: bench_core OPERATION [ITERATIONS]
 */
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canola/canola.h"
#include "example_od.h"

#define BIG 889u /* one full block: 127 segments of 7 bytes */

/* Keeps the last frame sent, so a run can be checked for an SDO abort at the end. */
static co_err_t tx_sink(void *ctx, const co_frame_t *frame)
{
    *(co_frame_t *)ctx = *frame;
    return CO_OK;
}

typedef struct bench {
    example_od_t od;
    co_node_t node;
    co_frame_t frames[256];
    unsigned frame_count;
    uint64_t now_us;
    /* a bench-only dictionary with one large DOMAIN for transfers */
    uint8_t big[BIG];
    co_od_domain_t big_domain;
    co_od_entry_t big_entries[2];
    uint32_t device_type;
    co_frame_t last_tx;
} bench_t;

static void start(bench_t *b, uint8_t id, co_od_t od, uint16_t hb_ms)
{
    (void)hb_ms;
    co_node_config_t cfg = {.node_id = id, .od = od};
    cfg.driver.tx = tx_sink;
    cfg.driver.ctx = &b->last_tx;
    if (co_node_init(&b->node, &cfg) != CO_OK || co_node_start(&b->node, 0) != CO_OK) {
        fprintf(stderr, "bench_core: node setup failed\n");
        exit(1);
    }
}

static void setup(bench_t *b, uint8_t id, uint16_t hb_ms)
{
    /* keyed, as the generator (canola.odgen) emits dictionaries */
    start(b, id, example_od_keyed(&b->od, example_od_init(&b->od, hb_ms)), hb_ms);
}

static void setup_big(bench_t *b)
{
    b->big_domain = (co_od_domain_t){.data = b->big, .len = BIG};
    for (unsigned i = 0; i < BIG; i++) {
        b->big[i] = (uint8_t)(i * 7u);
    }
    b->big_entries[0] = (co_od_entry_t){.index = 0x1000,
                                        .type = CO_TYPE_UNSIGNED32,
                                        .attr = CO_OD_RO,
                                        .size = 4,
                                        .value = &b->device_type};
    b->big_entries[1] = (co_od_entry_t){.index = 0x2100,
                                        .type = CO_TYPE_DOMAIN,
                                        .attr = CO_OD_RW,
                                        .size = BIG,
                                        .value = &b->big_domain};
    co_od_t od = {.entries = b->big_entries, .count = 2};
    start(b, 5, od, 0);
}

static void set_u32(bench_t *b, uint16_t index, uint8_t sub, uint32_t v)
{
    uint8_t d[4];
    co_put_u32(d, v);
    if (co_node_write_net(&b->node, index, sub, d, 4) != CO_ABORT_NONE) {
        fprintf(stderr, "bench_core: writing 0x%04X sub %u failed\n", index, sub);
        exit(1);
    }
}

static void set_u8(bench_t *b, uint16_t index, uint8_t sub, uint8_t v)
{
    if (co_node_write_net(&b->node, index, sub, &v, 1) != CO_ABORT_NONE) {
        fprintf(stderr, "bench_core: writing 0x%04X sub %u failed\n", index, sub);
        exit(1);
    }
}

/* PDO 1 (communication `comm`, mapping `map`) re-mapped by the CiA 301 procedure to
 * 0x2000 and 0x2007 (2 x u32, 8 bytes), then the node made operational. */
static void map_two_u32(bench_t *b, uint16_t comm, uint16_t map)
{
    uint64_t cob = 0;
    co_node_get_uint(&b->node, comm, 1, &cob);
    set_u32(b, comm, 1, (uint32_t)cob | 0x80000000u);
    set_u8(b, map, 0, 0);
    set_u32(b, map, 1, 0x20000020);
    set_u32(b, map, 2, 0x20070020);
    set_u8(b, map, 0, 2);
    set_u32(b, comm, 1, (uint32_t)cob & 0x7FFFFFFFu);
    co_nmt_apply(&b->node, CO_NMT_CMD_START);
}

static co_frame_t sdo_req(const uint8_t d[8])
{
    co_frame_t f = {.id = 0x605, .len = 8};
    memcpy(f.data, d, 8);
    return f;
}

/* Script of the client's frames for one transfer of BIG bytes of 0x2100. */
static void script_segmented_download(bench_t *b)
{
    uint8_t init[8] = {0x21, 0x00, 0x21, 0x00};
    co_put_u32(&init[4], BIG);
    b->frames[b->frame_count++] = sdo_req(init);
    uint32_t off = 0;
    uint8_t toggle = 0;
    while (off < BIG) {
        uint32_t n = BIG - off < 7 ? BIG - off : 7;
        uint8_t d[8] = {(uint8_t)((toggle << 4) | ((7 - n) << 1) | (off + n >= BIG ? 1 : 0))};
        memcpy(&d[1], &b->big[off], n);
        b->frames[b->frame_count++] = sdo_req(d);
        off += n;
        toggle ^= 1;
    }
}

static void script_segmented_upload(bench_t *b)
{
    uint8_t init[8] = {0x40, 0x00, 0x21, 0x00};
    b->frames[b->frame_count++] = sdo_req(init);
    for (unsigned i = 0; i < (BIG + 6) / 7; i++) {
        uint8_t d[8] = {(uint8_t)(0x60 | ((i & 1) << 4))};
        b->frames[b->frame_count++] = sdo_req(d);
    }
}

static void script_block_download(bench_t *b)
{
    uint8_t init[8] = {0xC6, 0x00, 0x21, 0x00};
    co_put_u32(&init[4], BIG);
    b->frames[b->frame_count++] = sdo_req(init);
    for (unsigned seq = 1; seq <= 127; seq++) {
        uint8_t d[8] = {(uint8_t)(seq | (seq == 127 ? 0x80 : 0))};
        memcpy(&d[1], &b->big[(seq - 1) * 7], 7);
        b->frames[b->frame_count++] = sdo_req(d);
    }
    uint16_t crc = 0;
    for (unsigned i = 0; i < BIG; i++) { /* bitwise CRC-16-CCITT, independent of the core */
        crc ^= (uint16_t)(b->big[i] << 8);
        for (int k = 0; k < 8; k++) {
            crc = (uint16_t)((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
        }
    }
    uint8_t end[8] = {0xC1, (uint8_t)crc, (uint8_t)(crc >> 8)};
    b->frames[b->frame_count++] = sdo_req(end);
}

static void script_block_upload(bench_t *b)
{
    uint8_t init[8] = {0xA4, 0x00, 0x21, 0x00, 127, 0};
    uint8_t start_[8] = {0xA3};
    uint8_t ack[8] = {0xA2, 127, 127};
    uint8_t end[8] = {0xA1};
    b->frames[b->frame_count++] = sdo_req(init);
    b->frames[b->frame_count++] = sdo_req(start_);
    b->frames[b->frame_count++] = sdo_req(ack);
    b->frames[b->frame_count++] = sdo_req(end);
}

__attribute__((noinline)) uint64_t measure_poll_idle(bench_t *b)
{
    return co_node_poll(&b->node, b->now_us);
}

/* One frame into the node. */
__attribute__((noinline)) void measure_ingest(bench_t *b, unsigned i)
{
    co_node_ingest(&b->node, b->now_us, &b->frames[i % b->frame_count]);
}

/* A whole scripted transfer. */
__attribute__((noinline)) void measure_transfer(bench_t *b)
{
    for (unsigned i = 0; i < b->frame_count; i++) {
        co_node_ingest(&b->node, b->now_us, &b->frames[i]);
    }
}

static void run_ingest(bench_t *b, unsigned n)
{
    for (unsigned i = 0; i < n; i++) {
        b->now_us = 1000 + i;
        measure_ingest(b, i);
    }
}

/* Node 3's heartbeat (0x703, consumed: 0x1016 sub 1 watches node 3) reaches the node before
 * every measured frame, outside the measurement: the frame after it is on another route
 * than the last one, as on a bus with other traffic. */
static void consume_heartbeats(bench_t *b)
{
    uint8_t v[4];
    co_put_u32(v, (3u << 16) | 1000u);
    if (co_node_write_net(&b->node, 0x1016, 1, v, 4) != CO_ABORT_NONE) {
        fprintf(stderr, "bench_core: no heartbeat consumer\n");
        exit(1);
    }
}

/* Node 5 on the example dictionary, consuming node 3's heartbeats when `after_hb`. */
static void setup_traffic(bench_t *b, bool after_hb)
{
    setup(b, 5, 0);
    if (after_hb) {
        consume_heartbeats(b);
    }
}

static void run_ingest_after_heartbeat(bench_t *b, unsigned n)
{
    const co_frame_t hb = {.id = 0x703, .len = 1, .data = {0x05}};
    uint32_t consumed = co_node_stats(&b->node)->rx_unrouted;
    for (unsigned i = 0; i < n; i++) {
        b->now_us = 1000 + i;
        co_node_ingest(&b->node, b->now_us, &hb);
        measure_ingest(b, i);
    }
    if (co_node_stats(&b->node)->rx_unrouted != consumed) {
        fprintf(stderr, "bench_core: the heartbeat was not routed: the figure is void\n");
        exit(1);
    }
}

int main(int argc, char **argv)
{
    static bench_t b;
    char op[64] = "";
    unsigned n = argc > 2 ? (unsigned)strtoul(argv[2], NULL, 10) : 1000;
    volatile uint64_t sink = 0;
    /* OPERATION_after_hb: the operation with a consumed heartbeat before each frame */
    snprintf(op, sizeof op, "%s", argc > 1 ? argv[1] : "");
    size_t len = strlen(op);
    bool after_hb = len > 9 && strcmp(op + len - 9, "_after_hb") == 0;
    if (after_hb) {
        op[len - 9] = '\0';
    }
    void (*run)(bench_t *, unsigned) = after_hb ? run_ingest_after_heartbeat : run_ingest;
    if (after_hb && strcmp(op, "sdo_expedited_upload") != 0 &&
        strcmp(op, "sdo_expedited_download") != 0 && strcmp(op, "rpdo_2x_u32") != 0) {
        fprintf(stderr, "bench_core: no _after_hb variant of '%s'\n", op);
        return 2;
    }
    if (strcmp(op, "poll_idle") == 0) {
        setup(&b, 5, 1000); /* heartbeat due in 1 s: every poll below finds nothing due */
        for (unsigned i = 0; i < n; i++) {
            b.now_us = 1 + i;
            sink += measure_poll_idle(&b);
        }
    } else if (strcmp(op, "heartbeat_consumed") == 0) {
        setup(&b, 1, 0);
        uint8_t v[4];
        co_put_u32(v, (3u << 16) | 1000u);
        co_node_write_net(&b.node, 0x1016, 1, v, 4);
        b.frames[b.frame_count++] = (co_frame_t){.id = 0x703, .len = 1, .data = {0x05}};
        co_node_ingest(&b.node, 0, &b.frames[0]); /* monitoring starts at the first one */
        run_ingest(&b, n);
    } else if (strcmp(op, "nmt_command") == 0) {
        setup(&b, 5, 0);
        b.frames[b.frame_count++] = (co_frame_t){.id = 0x000, .len = 2, .data = {0x01, 0x05}};
        b.frames[b.frame_count++] = (co_frame_t){.id = 0x000, .len = 2, .data = {0x80, 0x00}};
        run_ingest(&b, n);
    } else if (strcmp(op, "sdo_expedited_upload") == 0) {
        setup_traffic(&b, after_hb);
        b.frames[b.frame_count++] = sdo_req((const uint8_t[8]){0x40, 0x00, 0x20, 0x00});
        run(&b, n);
    } else if (strcmp(op, "sdo_expedited_download") == 0) {
        setup_traffic(&b, after_hb);
        b.frames[b.frame_count++] =
            sdo_req((const uint8_t[8]){0x23, 0x00, 0x20, 0x00, 0x78, 0x56, 0x34, 0x12});
        run(&b, n);
    } else if (strcmp(op, "rpdo_2x_u32") == 0) {
        setup_traffic(&b, after_hb);
        set_u32(&b, 0x1800, 1, 0x80000185u); /* TPDO1 maps 0x2000: off, so only the RPDO counts */
        map_two_u32(&b, 0x1400, 0x1600);
        b.frames[b.frame_count++] =
            (co_frame_t){.id = 0x205, .len = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
        run(&b, n);
        if (b.od.app_u32 != 0x04030201u || b.od.app_u32b != 0x08070605u) {
            fprintf(stderr, "bench_core: the RPDO was not applied: the figure is void\n");
            return 1;
        }
    } else if (strcmp(op, "sync_tpdo") == 0) {
        setup(&b, 5, 0);
        map_two_u32(&b, 0x1800, 0x1A00);
        set_u8(&b, 0x1800, 2, 1); /* synchronous, every SYNC */
        b.frames[b.frame_count++] = (co_frame_t){.id = 0x080, .len = 0};
        b.od.app_u32 = 0x11223344;
        run_ingest(&b, n);
        if (b.last_tx.id != 0x185 || b.last_tx.len != 8 || b.last_tx.data[0] != 0x44) {
            fprintf(stderr, "bench_core: no TPDO followed the SYNC: the figure is void\n");
            return 1;
        }
    } else if (strncmp(op, "sdo_", 4) == 0) {
        setup_big(&b);
        if (strcmp(op, "sdo_segmented_download") == 0) {
            script_segmented_download(&b);
        } else if (strcmp(op, "sdo_segmented_upload") == 0) {
            script_segmented_upload(&b);
        } else if (strcmp(op, "sdo_block_download") == 0) {
            script_block_download(&b);
        } else if (strcmp(op, "sdo_block_upload") == 0) {
            script_block_upload(&b);
        } else {
            fprintf(stderr, "bench_core: unknown operation '%s'\n", op);
            return 2;
        }
        for (unsigned i = 0; i < n; i++) {
            b.now_us = 1000 + i;
            measure_transfer(&b);
        }
    } else {
        fprintf(stderr, "bench_core: unknown operation '%s'\n", op);
        return 2;
    }
    if (b.last_tx.id >= 0x580 && b.last_tx.id <= 0x5FF && b.last_tx.data[0] == 0x80) {
        fprintf(stderr, "bench_core: %s ended in SDO abort 0x%08X: the figure is void\n", op,
                (unsigned)co_get_u32(&b.last_tx.data[4]));
        return 1;
    }
    return sink == 42 ? 1 : 0;
}
