/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_sdo_network.c -- SDO clients and servers on the simulated bus: large transfers in
 * every mode, many transfers at once, and transfers through a lossy bus.
 *
 * The server's object 0x3000 is a DOMAIN with no storage (pattern_domain.h): its read hook
 * produces a pattern of a chosen length and its write hook checks what arrives against the
 * same pattern, so transfers of any size need no buffer on either side but the client's.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "example_od_domain.h"
#include "harness.h"
#include "pattern_domain.h"

#define MS 1000ull

/* ---- a server: the example dictionary plus 0x3000 */

typedef struct server {
    example_od_t od;
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 1];
    pattern_domain_t obj;
    co_node_t node;
    co_sim_port_t port;
} server_t;

typedef struct client {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
    uint8_t *buf;
    uint32_t cap;
    int done_calls;
    co_abort_t abort;
    uint32_t len;
    uint64_t done_at;
    co_sim_bus_t *bus;
} client_t;

static void on_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    client_t *c = ctx;
    c->done_calls++;
    c->abort = abort;
    c->len = len;
    c->done_at = c->bus->now_us;
}

static void server_start(co_sim_bus_t *bus, server_t *s, uint8_t id)
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_with_domain(&s->od, 0, s->entries)};
    cfg.od.hook_ctx = &s->obj;
    CHECK_EQ(co_sim_port_attach(bus, &s->port), CO_OK);
    cfg.driver = co_sim_port_driver(&s->port);
    CHECK_EQ(co_node_init(&s->node, &cfg), CO_OK);
    co_sim_port_bind(&s->port, &s->node);
    CHECK_EQ(co_node_start(&s->node, bus->now_us), CO_OK);
}

static void client_start(co_sim_bus_t *bus, client_t *c, uint8_t id, uint8_t server_id,
                         uint32_t cap)
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_init(&c->od, 0)};
    CHECK_EQ(co_sim_port_attach(bus, &c->port), CO_OK);
    cfg.driver = co_sim_port_driver(&c->port);
    CHECK_EQ(co_node_init(&c->node, &cfg), CO_OK);
    co_sim_port_bind(&c->port, &c->node);
    CHECK_EQ(co_node_start(&c->node, bus->now_us), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&c->node, 0, server_id), CO_OK);
    c->bus = bus;
    c->cap = cap;
    c->buf = malloc(cap ? cap : 1);
}

static bool upload_matches(const client_t *c, const pattern_domain_t *obj)
{
    return c->len == obj->length && pattern_matches(c->buf, obj->up_seed, c->len);
}

/* Run until the client's transfer is done (or `limit_us` of simulated time passed). */
static void run_until_done(co_sim_bus_t *bus, client_t *c, uint64_t limit_us)
{
    uint64_t end = bus->now_us + limit_us;
    while (c->done_calls == 0 && bus->now_us < end) {
        co_sim_run_until(bus, bus->now_us + 10 * MS);
    }
}

/* ---- a client (node 1) and a server (node 5) on one bus, past their boot-ups */

typedef struct pair {
    co_sim_bus_t bus;
    server_t srv;
    client_t cli;
} pair_t;

static pair_t *pair_up(uint32_t bitrate, uint32_t cap)
{
    pair_t *p = calloc(1, sizeof *p);
    co_sim_bus_init(&p->bus, bitrate);
    server_start(&p->bus, &p->srv, 5);
    client_start(&p->bus, &p->cli, 1, 5, cap);
    co_sim_run_until(&p->bus, 1 * MS);
    return p;
}

static void pair_free(pair_t *p)
{
    free(p->cli.buf);
    free(p);
}

/* ---- tests */

static void test_ten_mebibytes_block_both_ways(void)
{
    const uint32_t size = 10u * 1024u * 1024u;
    pair_t *pair = pair_up(0, size);
    co_sim_bus_t *bus = &pair->bus;
    server_t *srv = &pair->srv;
    client_t *cli = &pair->cli;

    srv->obj = (pattern_domain_t){.length = size, .up_seed = 7};
    CHECK_EQ(
        co_sdo_upload(&cli->node, 0, 0x3000, 0, CO_SDO_BLOCK, cli->buf, cli->cap, on_done, cli),
        CO_OK);
    run_until_done(bus, cli, 100000 * MS);
    CHECK_EQ(cli->done_calls, 1);
    CHECK_EQ(cli->abort, CO_ABORT_NONE);
    CHECK(upload_matches(cli, &srv->obj));

    cli->done_calls = 0;
    srv->obj.down_seed = 11;
    pattern_fill(cli->buf, 11, size);
    CHECK_EQ(co_sdo_download(&cli->node, 0, 0x3000, 0, CO_SDO_BLOCK, cli->buf, size, on_done, cli),
             CO_OK);
    run_until_done(bus, cli, 100000 * MS);
    CHECK_EQ(cli->done_calls, 1);
    CHECK_EQ(cli->abort, CO_ABORT_NONE);
    CHECK_EQ(srv->obj.received, size);
    CHECK(!srv->obj.mismatch);
    CHECK(srv->obj.complete);
    /* The server streamed it through its small buffer: many pieces, none bigger. */
    CHECK(srv->obj.pieces >= size / CO_SDO_BUF_SIZE);
    CHECK_EQ(co_node_stats(&cli->node)->tx_overflow, 0);
    CHECK_EQ(co_node_stats(&srv->node)->tx_overflow, 0);
    pair_free(pair);
}

static void test_segmented_one_mebibyte_both_ways(void)
{
    const uint32_t size = 1024u * 1024u;
    pair_t *pair = pair_up(0, size);
    co_sim_bus_t *bus = &pair->bus;
    server_t *srv = &pair->srv;
    client_t *cli = &pair->cli;
    srv->obj = (pattern_domain_t){.length = size, .up_seed = 3, .down_seed = 3};
    co_sdo_upload(&cli->node, 0, 0x3000, 0, CO_SDO_SEGMENTED, cli->buf, cli->cap, on_done, cli);
    run_until_done(bus, cli, 100000 * MS);
    CHECK_EQ(cli->abort, CO_ABORT_NONE);
    CHECK(upload_matches(cli, &srv->obj));
    cli->done_calls = 0;
    pattern_fill(cli->buf, 3, size);
    co_sdo_download(&cli->node, 0, 0x3000, 0, CO_SDO_SEGMENTED, cli->buf, size, on_done, cli);
    run_until_done(bus, cli, 100000 * MS);
    CHECK_EQ(cli->abort, CO_ABORT_NONE);
    CHECK_EQ(srv->obj.received, size);
    CHECK(!srv->obj.mismatch);
    pair_free(pair);
}

#define PAIRS 10

static void test_ten_clients_ten_servers_at_once(void)
{
    const uint32_t size = 4096;
    co_sim_bus_t *bus = calloc(1, sizeof *bus);
    server_t *srv = calloc(PAIRS, sizeof *srv);
    client_t *cli = calloc(PAIRS, sizeof *cli);
    co_sim_bus_init(bus, 1000000);
    for (uint8_t i = 0; i < PAIRS; i++) {
        server_start(bus, &srv[i], (uint8_t)(20 + i));
        client_start(bus, &cli[i], (uint8_t)(1 + i), (uint8_t)(20 + i), size);
        srv[i].obj = (pattern_domain_t){.length = size - i * 100u, .up_seed = i};
    }
    co_sim_run_until(bus, 10 * MS);
    for (uint8_t i = 0; i < PAIRS; i++) {
        co_sdo_mode_t mode = (i % 2) ? CO_SDO_BLOCK : CO_SDO_SEGMENTED;
        CHECK_EQ(co_sdo_upload(&cli[i].node, 0, 0x3000, 0, mode, cli[i].buf, cli[i].cap, on_done,
                               &cli[i]),
                 CO_OK);
    }
    co_sim_run_until(bus, 5000 * MS);
    for (uint8_t i = 0; i < PAIRS; i++) {
        CHECK_EQ(cli[i].done_calls, 1);
        CHECK_EQ(cli[i].abort, CO_ABORT_NONE);
        CHECK(upload_matches(&cli[i], &srv[i].obj));
        cli[i].done_calls = 0;
        pattern_fill(cli[i].buf, 100u + i, size);
        srv[i].obj.down_seed = 100u + i;
        co_sdo_mode_t mode = (i % 2) ? CO_SDO_SEGMENTED : CO_SDO_BLOCK;
        co_sdo_download(&cli[i].node, 0, 0x3000, 0, mode, cli[i].buf, size, on_done, &cli[i]);
    }
    co_sim_run_until(bus, 10000 * MS);
    for (uint8_t i = 0; i < PAIRS; i++) {
        CHECK_EQ(cli[i].done_calls, 1);
        CHECK_EQ(cli[i].abort, CO_ABORT_NONE);
        CHECK_EQ(srv[i].obj.received, size);
        CHECK(!srv[i].obj.mismatch);
        free(cli[i].buf);
    }
    /* Transfers overlapped: the bus carried them interleaved, not one after another. */
    CHECK(co_sim_load(bus) > 0.0);
    free(cli);
    free(srv);
    free(bus);
}

/* With 1 % of frames dropped, every transfer either succeeds with the right data or ends
 * with an abort code, and never later than the time-out after its last frame. */
static void test_thousand_transfers_on_a_lossy_bus(void)
{
    pair_t *pair = pair_up(1000000, 2000);
    co_sim_bus_t *bus = &pair->bus;
    server_t *srv = &pair->srv;
    client_t *cli = &pair->cli;
    co_sim_seed(bus, 20261123);
    co_sim_drop_probability(bus, 0.01);
    uint32_t ok = 0;
    uint32_t block_ok = 0;
    uint32_t block_total = 0;
    uint32_t aborted[4] = {0};
    uint32_t wrong = 0;
    uint32_t hung = 0;
    for (uint32_t i = 0; i < 1000; i++) {
        uint32_t size = (i * 37u) % 2000u;
        bool upload = i % 2 == 0;
        co_sdo_mode_t mode = (co_sdo_mode_t)(i / 2 % 3 == 0   ? CO_SDO_AUTO
                                             : i / 2 % 3 == 1 ? CO_SDO_SEGMENTED
                                                              : CO_SDO_BLOCK);
        block_total += mode == CO_SDO_BLOCK;
        srv->obj.length = size;
        srv->obj.up_seed = i;
        srv->obj.down_seed = i;
        srv->obj.received = 0;
        srv->obj.complete = false;
        cli->done_calls = 0;
        co_err_t err;
        if (upload) {
            err = co_sdo_upload(&cli->node, 0, 0x3000, 0, mode, cli->buf, cli->cap, on_done, cli);
        } else {
            pattern_fill(cli->buf, i, size);
            err = co_sdo_download(&cli->node, 0, 0x3000, 0, mode, cli->buf, size, on_done, cli);
        }
        CHECK_EQ(err, CO_OK);
        /* A 2000-byte segmented transfer takes ~570 frames of ~0.1 ms: 60 ms; with a
         * time-out of 1 s a finished or aborted transfer is done well within 3 s. */
        run_until_done(bus, cli, 3000 * MS);
        if (cli->done_calls != 1) {
            hung++;
            continue;
        }
        if (cli->abort == CO_ABORT_NONE) {
            bool right =
                upload ? upload_matches(cli, &srv->obj) : pattern_domain_received(&srv->obj, size);
            if (right) {
                ok++;
                block_ok += mode == CO_SDO_BLOCK;
            } else {
                wrong++;
                printf("  transfer %u (%s, mode %d, %u bytes) reported success with wrong data\n",
                       i, upload ? "upload" : "download", (int)mode, size);
            }
        } else if (cli->abort == CO_ABORT_TIMEOUT) {
            aborted[0]++;
        } else if (cli->abort == CO_ABORT_COMMAND) {
            aborted[1]++;
        } else if (cli->abort == CO_ABORT_TOGGLE) {
            aborted[2]++;
        } else {
            aborted[3]++;
            printf("  transfer %u aborted with unexpected code 0x%08X\n", i, (unsigned)cli->abort);
        }
        /* Let a server that missed the end of the transfer time out before the next. */
        co_sim_run_until(bus, bus->now_us + 1100 * MS);
    }
    printf("  lossy bus: %u ok (%u of %u block transfers), %u timed out, %u bad command, %u "
           "toggle, %u other, %u wrong, "
           "%u hung; %llu frames dropped\n",
           ok, block_ok, block_total, aborted[0], aborted[1], aborted[2], aborted[3], wrong, hung,
           (unsigned long long)co_sim_stats(bus)->dropped);
    CHECK_EQ(wrong, 0);
    CHECK_EQ(hung, 0);
    CHECK_EQ(aborted[3], 0);
    /* Segmented transfers of hundreds of frames rarely survive a 1 % loss (nothing in the
     * protocol repeats a frame); block transfer repeats lost segments, so most get through. */
    CHECK(ok > 0);
    CHECK(block_ok * 10 >= block_total * 8);
    CHECK(co_sim_stats(bus)->dropped > 100);
    pair_free(pair);
}

static void on_written(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    sdo_result_value(ctx, channel, abort, 0, len);
}

/* One call reads or writes a typed value of a remote node. */
static void test_typed_values_in_one_call(void)
{
    pair_t *pair = pair_up(1000000, 8);
    co_sim_bus_t *bus = &pair->bus;
    server_t *srv = &pair->srv;
    client_t *cli = &pair->cli;
    sdo_result_t r = {0};
    CHECK_EQ(co_sdo_read_value(&cli->node, 0, 0x2000, 0, sdo_result_value, &r), CO_OK);
    CHECK_EQ(co_sdo_read_value(&cli->node, 0, 0x2000, 0, sdo_result_value, &r), CO_ERR_BUSY);
    co_sim_run_until(bus, 10 * MS);
    CHECK_EQ(r.calls, 1);
    CHECK_EQ(r.abort, CO_ABORT_NONE);
    CHECK_EQ(r.value, 0x12345678);
    CHECK_EQ(r.len, 4);

    r = (sdo_result_t){0};
    CHECK_EQ(co_sdo_write_value(&cli->node, 0, 0x2001, 0, (uint64_t)(int64_t)-5, 2, on_written, &r),
             CO_OK);
    co_sim_run_until(bus, 20 * MS);
    CHECK_EQ(r.abort, CO_ABORT_NONE);
    CHECK_EQ(srv->od.app_i16, -5);

    r = (sdo_result_t){0};
    co_sdo_write_value(&cli->node, 0, 0x2001, 0, 500, 2, on_written, &r);
    co_sim_run_until(bus, 30 * MS);
    CHECK_EQ(r.abort, CO_ABORT_VALUE_HIGH); /* the server's abort code, passed on */
    CHECK_EQ(srv->od.app_i16, -5);

    /* 8 bytes: segmented, still one call. */
    r = (sdo_result_t){0};
    co_sdo_write_value(&cli->node, 0, 0x2005, 0, 0x8877665544332211ull, 8, on_written, &r);
    co_sim_run_until(bus, 40 * MS);
    CHECK_EQ(r.abort, CO_ABORT_NONE);
    r = (sdo_result_t){0};
    co_sdo_read_value(&cli->node, 0, 0x2005, 0, sdo_result_value, &r);
    co_sim_run_until(bus, 50 * MS);
    CHECK_EQ(r.value, 0x8877665544332211ull);
    CHECK_EQ(r.len, 8);

    /* A 14-byte string does not fit a value. */
    r = (sdo_result_t){0};
    co_sdo_read_value(&cli->node, 0, 0x1008, 0, sdo_result_value, &r);
    co_sim_run_until(bus, 60 * MS);
    CHECK_EQ(r.calls, 1);
    CHECK_EQ(r.abort, CO_ABORT_OUT_OF_MEMORY);
    CHECK_EQ(co_sdo_write_value(&cli->node, 0, 0x2000, 0, 1, 9, on_written, &r), CO_ERR_ARG);
    pair_free(pair);
}

int main(void)
{
    RUN(test_ten_mebibytes_block_both_ways);
    RUN(test_segmented_one_mebibyte_both_ways);
    RUN(test_ten_clients_ten_servers_at_once);
    RUN(test_thousand_transfers_on_a_lossy_bus);
    RUN(test_typed_values_in_one_call);
    return check_summary();
}
