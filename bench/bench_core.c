/*
 * bench_core.c -- operations of the core, each in its own never-inlined function
 * so callgrind (--toggle-collect=measure_<name>) counts exactly its instructions.
 * Not a test: it asserts nothing and is run by bench/run under valgrind.
 *
 * usage: bench_core OPERATION [ITERATIONS]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canola/canola.h"
#include "example_od.h"

static co_err_t tx_sink(void *ctx, const co_frame_t *frame)
{
    (void)ctx;
    (void)frame;
    return CO_OK;
}

typedef struct bench {
    example_od_t od;
    co_node_t node;
    co_frame_t frames[2];
    uint64_t now_us;
} bench_t;

static void setup(bench_t *b, uint8_t id, uint16_t hb_ms)
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_init(&b->od, hb_ms)};
    cfg.driver.tx = tx_sink;
    if (co_node_init(&b->node, &cfg) != CO_OK || co_node_start(&b->node, 0) != CO_OK) {
        fprintf(stderr, "bench_core: node setup failed\n");
        exit(1);
    }
}

__attribute__((noinline)) uint64_t measure_poll_idle(bench_t *b)
{
    return co_node_poll(&b->node, b->now_us);
}

__attribute__((noinline)) void measure_heartbeat_consumed(bench_t *b)
{
    co_node_ingest(&b->node, b->now_us, &b->frames[0]);
}

__attribute__((noinline)) void measure_nmt_command(bench_t *b, unsigned i)
{
    co_node_ingest(&b->node, b->now_us, &b->frames[i & 1u]);
}

int main(int argc, char **argv)
{
    static bench_t b;
    const char *op = argc > 1 ? argv[1] : "";
    unsigned n = argc > 2 ? (unsigned)strtoul(argv[2], NULL, 10) : 1000;
    volatile uint64_t sink = 0;
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
        b.frames[0] = (co_frame_t){.id = 0x703, .len = 1, .data = {0x05}};
        co_node_ingest(&b.node, 0, &b.frames[0]); /* monitoring starts at the first one */
        for (unsigned i = 0; i < n; i++) {
            b.now_us = 1000 + i;
            measure_heartbeat_consumed(&b);
        }
    } else if (strcmp(op, "nmt_command") == 0) {
        setup(&b, 5, 0);
        b.frames[0] = (co_frame_t){.id = 0x000, .len = 2, .data = {0x01, 0x05}};
        b.frames[1] = (co_frame_t){.id = 0x000, .len = 2, .data = {0x80, 0x00}};
        for (unsigned i = 0; i < n; i++) {
            b.now_us = 1000 + i;
            measure_nmt_command(&b, i);
        }
    } else {
        fprintf(stderr,
                "bench_core: unknown operation '%s' (poll_idle, heartbeat_consumed, "
                "nmt_command)\n",
                op);
        return 2;
    }
    return sink == 42 ? 1 : 0;
}
