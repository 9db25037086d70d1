/* SPDX-License-Identifier: Apache-2.0 */
/*
 * fuzz_sdo_client.c -- libFuzzer target: the SDO client state machine against a hostile
 * server. A node (ID 1) runs client channel 0 towards server 6; the fuzzer starts
 * transfers and plays the server's side with arbitrary replies and time steps.
 *
 * Input: a stream of records, each starting with an operation byte:
 *   0: start  -- mode (0..3), direction (bit 0: download), size (2 bytes, 0..1023):
 *                co_sdo_upload into a heap buffer of exactly `size` bytes (so ASan sees
 *                any write past it), or co_sdo_download of `size` bytes
 *   1: reply  -- len, flags, 8 data bytes: a frame on 0x586 (the server's responses)
 *   2: time   -- advance the clock by 0..65535 x 100 us and poll
 *   3: abort  -- co_sdo_client_abort with a 4-byte code
 * Missing bytes at the end read as zeros.
 *
 * Invariants (abort() = a finding): `done` runs exactly once per started transfer, never
 * reports more bytes than the buffer holds, and reports 0 bytes with a non-zero abort
 * code; the client only ever sends 8-byte frames on 0x606 (besides the boot-up); a transfer that
 * hears nothing ends by the time-out (the channel is idle one time-out after the last step, with
 * 0x05040000 when it was still open); an idle channel accepts a new transfer.
 *
 *   make fuzz                 # every target for FUZZ_SECONDS
 *   build-fuzz/fuzz_sdo_client -max_total_time=3600 fuzz/corpus/sdo_client   # for hours
 */
#include <stdlib.h>
#include <string.h>

#include "canola/canola.h"
#include "example_od.h"
#include "fuzz_reader.h"

#define CAP_MAX 1024u
#define TIMEOUT_US 1000000u /* the default SDO time-out (sdo_timeout_ms = 0) */

typedef struct rig {
    example_od_t od;
    co_node_t node;
    uint8_t *buf; /* upload destination / download source, exactly `cap` bytes */
    uint32_t cap;
    unsigned started;   /* transfers started */
    unsigned completed; /* done callbacks */
    co_abort_t last_abort;
} rig_t;

static void check(int ok)
{
    if (!ok) {
        abort();
    }
}

static co_err_t capture(void *ctx, const co_frame_t *frame)
{
    (void)ctx;
    /* Besides its boot-up, the node only sends the client's requests. */
    check(frame->id == 0x701 || (frame->id == 0x606 && frame->len == 8 && frame->flags == 0));
    return CO_OK;
}

static void on_done(void *ctx, uint8_t channel, co_abort_t code, uint32_t len)
{
    rig_t *r = ctx;
    check(channel == 0);
    check(len <= r->cap);
    check(code == CO_ABORT_NONE || len == 0);
    r->completed++;
    r->last_abort = code;
    check(r->completed == r->started);
}

static void start(rig_t *r, reader_t *in)
{
    co_sdo_mode_t mode = (co_sdo_mode_t)(take(in) & 3u);
    bool download = (take(in) & 1u) != 0;
    uint32_t size = (uint32_t)(take(in) | (take(in) << 8)) % CAP_MAX;
    if (co_sdo_client_busy(&r->node, 0)) {
        return;
    }
    free(r->buf);
    r->cap = size;
    r->buf = malloc(size ? size : 1);
    check(r->buf != NULL);
    memset(r->buf, 0xA5, size ? size : 1);
    co_err_t err;
    if (download) {
        err = co_sdo_download(&r->node, 0, 0x2003, 0, mode, r->buf, size, on_done, r);
    } else {
        err = co_sdo_upload(&r->node, 0, 0x2003, 0, mode, r->buf, size, on_done, r);
    }
    /* Only a bad argument may refuse an idle, set-up channel. */
    check(err == CO_OK || err == CO_ERR_ARG);
    check(err != CO_ERR_ARG || (download && mode == CO_SDO_EXPEDITED && (size == 0 || size > 4)));
    if (err == CO_OK) {
        r->started++;
    }
}

static void reply(rig_t *r, reader_t *in, uint64_t now)
{
    co_frame_t f = {.id = 0x586};
    f.len = (uint8_t)(take(in) % 9u);
    if (f.len == 0) {
        f.len = 8; /* mostly well-formed: the state machine is the target, not the length */
    }
    f.flags = (uint8_t)(take(in) & CO_FRAME_RTR);
    for (int i = 0; i < 8; i++) {
        f.data[i] = take(in);
    }
    co_node_ingest(&r->node, now, &f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static rig_t r; /* the fuzzer's harness, not the core: reinitialised every run */
    free(r.buf);
    memset(&r, 0, sizeof r);
    co_node_config_t cfg = {.node_id = 1, .od = example_od_init(&r.od, 0)};
    cfg.driver.tx = capture;
    cfg.driver.ctx = &r;
    check(co_node_init(&r.node, &cfg) == CO_OK && co_node_start(&r.node, 0) == CO_OK);
    check(co_sdo_client_setup(&r.node, 0, 6) == CO_OK);
    reader_t in = {data, size};
    uint64_t now = 0;
    while (in.n > 0) {
        switch (take(&in) % 4) {
        case 0:
            start(&r, &in);
            break;
        case 1:
            reply(&r, &in, now);
            break;
        case 2:
            now += 100u * (uint64_t)(take(&in) | (take(&in) << 8));
            co_node_poll(&r.node, now);
            break;
        default: {
            co_abort_t code = (co_abort_t)(take(&in) | (take(&in) << 8));
            code |= (co_abort_t)(take(&in) | (take(&in) << 8)) << 16;
            bool busy = co_sdo_client_busy(&r.node, 0);
            co_err_t err = co_sdo_client_abort(&r.node, 0, code);
            check(err == (busy ? CO_OK : CO_ERR_STATE));
            break;
        }
        }
        check(r.completed + (co_sdo_client_busy(&r.node, 0) ? 1u : 0u) == r.started);
    }
    /* Never hangs: one time-out of silence ends whatever is open. */
    bool open = co_sdo_client_busy(&r.node, 0);
    now += TIMEOUT_US;
    co_node_poll(&r.node, now);
    check(!co_sdo_client_busy(&r.node, 0));
    check(r.completed == r.started);
    check(!open || r.last_abort == CO_ABORT_TIMEOUT);
    /* And it is usable again. */
    uint8_t one[4];
    r.cap = sizeof one;
    check(co_sdo_upload(&r.node, 0, 0x1000, 0, CO_SDO_AUTO, one, sizeof one, on_done, &r) == CO_OK);
    r.started++;
    co_frame_t ok = {.id = 0x586, .len = 8, .data = {0x43, 0x00, 0x10, 0x00, 1, 2, 3, 4}};
    co_node_ingest(&r.node, now, &ok);
    check(r.completed == r.started && r.last_abort == CO_ABORT_NONE && one[0] == 1);
    return 0;
}
