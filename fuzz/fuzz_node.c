/* SPDX-License-Identifier: Apache-2.0 */
/*
 * fuzz_node.c -- libFuzzer target: any sequence of frames, time steps and network writes
 * into a node with every service enabled (the example dictionary), then the invariants a
 * node must keep whatever it was fed.
 *
 * Input: a stream of records, each starting with an operation byte:
 *   0: frame  -- id (2 bytes, 11-bit; bit 15 of the pair makes it 29-bit), flags, len,
 *                8 data bytes; fed to co_node_ingest
 *   1: time   -- advance the clock by 0..65535 x 100 us and poll
 *   2: write  -- index (2), sub, len (0..8), 8 bytes: co_node_write_net, as an SDO would
 *   3: nmt    -- one command byte applied locally
 * Missing bytes at the end read as zeros.
 *
 * Invariants after every frame: in pre-operational and operational, with no SDO transfer
 * open, the node answers an SDO read of 0x1000 at once. After every time step: the next
 * deadline lies ahead, and no later than one heartbeat period while the producer runs. Invariants
 * after the stream (abort() = a finding): after a reset node the node sends its boot-up, in
 * pre-operational it answers an SDO read of 0x1000 with the device type, and its heartbeat (0x1017
 * back at its power-on 100 ms) comes on time. The sanitizers check every step for memory errors and
 * undefined behaviour.
 *
 *   make fuzz                 # builds and runs for FUZZ_SECONDS (default 30)
 *   build-fuzz/fuzz_node -max_total_time=3600 fuzz/corpus/node   # for hours
 */
#include <stdlib.h>
#include <string.h>

#include "canola/canola.h"
#include "example_od.h"
#include "fuzz_reader.h"

typedef struct rig {
    example_od_t od;
    co_node_t node;
    co_frame_t last;
    unsigned sent;
    unsigned heartbeats; /* pre-operational heartbeats sent */
} rig_t;

static co_err_t capture(void *ctx, const co_frame_t *frame)
{
    rig_t *r = ctx;
    r->last = *frame;
    r->sent++;
    r->heartbeats +=
        frame->id == 0x705 && frame->len == 1 && frame->data[0] == CO_NMT_PRE_OPERATIONAL;
    return CO_OK;
}

static void feed_frame(rig_t *r, reader_t *in, uint64_t now)
{
    uint16_t raw = (uint16_t)(take(in) | (take(in) << 8));
    co_frame_t f = {.flags = (uint8_t)(take(in) & (CO_FRAME_EXT | CO_FRAME_RTR))};
    f.len = take(in);
    f.id = (raw & 0x8000u) ? (uint32_t)(raw & 0x7FFFu) << 14 : raw & CO_ID_STD_MAX;
    if (raw & 0x8000u) {
        f.flags |= CO_FRAME_EXT;
    }
    for (int i = 0; i < 8; i++) {
        f.data[i] = take(in);
    }
    co_node_ingest(&r->node, now, &f);
}

static void feed_write(rig_t *r, reader_t *in)
{
    uint16_t index = (uint16_t)(take(in) | (take(in) << 8));
    uint8_t sub = take(in);
    uint8_t len = (uint8_t)(take(in) % 9);
    uint8_t data[8];
    for (int i = 0; i < 8; i++) {
        data[i] = take(in);
    }
    (void)co_node_write_net(&r->node, index, sub, data, len);
}

/* After every poll: the next deadline lies ahead (a poll never asks to be called again at
 * once), and a running heartbeat producer is never scheduled later than one period. */
static void check_step(const rig_t *r, uint64_t now, uint64_t next)
{
    if (next <= now) {
        abort();
    }
    uint64_t period_us = 1000u * (uint64_t)r->od.hb_period_ms;
    if (period_us != 0 && r->node.nmt_state != CO_NMT_INITIALISING && next > now + period_us) {
        abort();
    }
}

/* After every frame: a node whose state allows SDO and whose server is between transfers
 * answers an expedited read of 0x1000 at once. (Asking is part of the input from then on:
 * it ends no transfer, since none is open.) */
static void check_sdo_answers(rig_t *r, uint64_t now)
{
    bool sdo =
        r->node.nmt_state == CO_NMT_PRE_OPERATIONAL || r->node.nmt_state == CO_NMT_OPERATIONAL;
    if (!sdo || r->node.sdo_servers[0].state != 0) {
        return;
    }
    /* LSS may have given the node another ID: ask the one it has now. */
    uint8_t id = co_node_id(&r->node);
    co_frame_t req = {.id = 0x600u + id, .len = 8, .data = {0x40, 0x00, 0x10, 0x00}};
    r->sent = 0;
    co_node_ingest(&r->node, now, &req);
    if (r->sent == 0 || r->last.id != 0x580u + id || r->last.data[0] != 0x43 ||
        co_get_u32(&r->last.data[4]) != r->od.device_type) {
        abort();
    }
}

/* The node is not wedged: a reset brings the boot-up, and SDO answers in pre-operational. */
static void check_alive(rig_t *r, uint64_t now)
{
    r->sent = 0;
    co_nmt_apply(&r->node, CO_NMT_CMD_RESET_NODE);
    co_node_poll(&r->node, now);
    uint8_t id = co_node_id(&r->node);
    if (id == CO_NODE_ID_UNCONFIGURED) {
        /* LSS set the ID to 0xFF: CiA 305 wants LSS-only operation, silent, no boot-up. */
        if (r->sent != 0 || r->node.nmt_state != CO_NMT_INITIALISING) {
            abort();
        }
        return;
    }
    if (r->sent == 0 || r->node.nmt_state != CO_NMT_PRE_OPERATIONAL) {
        abort();
    }
    co_frame_t req = {.id = 0x600u + id, .len = 8, .data = {0x40, 0x00, 0x10, 0x00}};
    r->sent = 0;
    co_node_ingest(&r->node, now, &req);
    co_node_poll(&r->node, now);
    if (r->sent == 0 || r->last.id != 0x580u + id || r->last.data[0] != 0x43 ||
        co_get_u32(&r->last.data[4]) != r->od.device_type) {
        abort();
    }
    r->heartbeats = 0;
    co_node_poll(&r->node, now + 100000u);
    if (r->heartbeats != 1) {
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static rig_t r; /* the fuzzer's harness, not the core: reinitialised every run */
    memset(&r, 0, sizeof r);
    /* keyed and hashed, as canola.odgen emits dictionaries: the look-up the firmware runs */
    co_node_config_t cfg = {.node_id = 5,
                            .od = example_od_keyed(&r.od, example_od_init(&r.od, 100))};
    cfg.driver.tx = capture;
    cfg.driver.ctx = &r;
    cfg.boot_time_ms = 500;
    if (co_node_init(&r.node, &cfg) != CO_OK || co_node_start(&r.node, 0) != CO_OK) {
        abort();
    }
    co_sdo_client_setup(&r.node, 0, 6);
    reader_t in = {data, size};
    uint64_t now = 0;
    while (in.n > 0) {
        switch (take(&in) % 4) {
        case 0:
            feed_frame(&r, &in, now);
            check_sdo_answers(&r, now);
            break;
        case 1:
            now += 100u * (uint64_t)(take(&in) | (take(&in) << 8));
            check_step(&r, now, co_node_poll(&r.node, now));
            break;
        case 2:
            feed_write(&r, &in);
            break;
        default:
            (void)co_nmt_apply(&r.node, (co_nmt_cmd_t)take(&in));
            break;
        }
    }
    check_alive(&r, now + 1);
    return 0;
}
