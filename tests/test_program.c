/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_program.c -- program download (CiA 302-3): the device objects 0x1F50, 0x1F51,
 * 0x1F56, 0x1F57 as the network sees them, and a 1 MiB download on the simulated bus
 * with progress and a check of the new software identification.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define IMAGE_LEN (1024u * 1024u)

/* The device's flash: a checksum of what arrived, in order. */
typedef struct flash_app {
    co_program_t prog;
    uint32_t sum;
    uint32_t bytes;
    uint32_t pieces;
    bool broken; /* every write fails */
    bool refuse_start;
    uint8_t refuse_mask; /* bit c: refuse command c with CO_ABORT_DATA_LOCAL */
    uint8_t commands[8];
    uint32_t command_count;
    uint8_t count1, count2, count3, count4; /* sub0 values */
} flash_app_t;

static uint32_t checksum(uint32_t sum, const uint8_t *data, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        sum = (sum << 5) + sum + data[i]; /* djb2: order matters */
    }
    return sum;
}

static co_abort_t app_write(void *ctx, uint32_t offset, const uint8_t *data, uint32_t n,
                            uint32_t total, bool last)
{
    flash_app_t *a = ctx;
    (void)total;
    if (a->broken) {
        return CO_ABORT_HARDWARE;
    }
    if (offset == 0) {
        a->sum = 5381;
        a->bytes = 0;
    }
    if (offset != a->bytes) {
        return CO_ABORT_GENERAL; /* pieces must come in order */
    }
    a->sum = checksum(a->sum, data, n);
    a->bytes += n;
    a->pieces++;
    if (last) {
        co_program_set_ident(&a->prog, a->sum); /* the new program's identification */
    }
    return CO_ABORT_NONE;
}

static co_abort_t app_control(void *ctx, uint8_t command)
{
    flash_app_t *a = ctx;
    if (a->command_count < 8) {
        a->commands[a->command_count++] = command;
    }
    if (a->refuse_mask & (1u << command)) {
        return CO_ABORT_DATA_LOCAL;
    }
    return (a->refuse_start && command == CO_PROGRAM_START) ? CO_ABORT_DATA_LOCAL : CO_ABORT_NONE;
}

/* Put 0x1F50/51/56/57 sub0..1 into an example dictionary and (re)initialise the node. */
static void add_program_objects(example_od_t *od, co_node_config_t *cfg, flash_app_t *a)
{
    static const uint8_t k_one = 1;
    a->count1 = a->count2 = a->count3 = a->count4 = 1;
    co_od_entry_t add[8] = {
        {0x1F50, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &a->count1, &k_one, NULL, NULL},
        {0x1F50, 1, CO_TYPE_DOMAIN, CO_OD_WO, 0xFFFFFFFFu, NULL, NULL, NULL,
         &co_program_data_hooks},
        {0x1F51, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &a->count2, &k_one, NULL, NULL},
        {0x1F51, 1, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, NULL, NULL, NULL, &co_program_control_hooks},
        {0x1F56, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &a->count3, &k_one, NULL, NULL},
        {0x1F56, 1, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, NULL, NULL, NULL, &co_program_ident_hooks},
        {0x1F57, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &a->count4, &k_one, NULL, NULL},
        {0x1F57, 1, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, NULL, NULL, NULL, &co_program_status_hooks},
    };
    uint32_t at = 0;
    while (at < cfg->od.count && od->entries[at].index < 0x1F50) {
        at++;
    }
    memmove(&od->entries[at + 8], &od->entries[at], (cfg->od.count - at) * sizeof add[0]);
    memcpy(&od->entries[at], add, sizeof add);
    cfg->od.count += 8;
    cfg->od.hook_ctx = &a->prog;
    co_program_app_t app = {.write = app_write, .control = app_control, .ctx = a};
    co_program_init(&a->prog, &app, true, 0x11110001);
}

typedef struct device {
    test_node_t t;
    flash_app_t app;
} device_t;

static device_t *device(void)
{
    device_t *d = calloc(1, sizeof *d);
    test_node_init(&d->t, 2, 0);
    add_program_objects(&d->t.od, &d->t.cfg, &d->app);
    CHECK_EQ(co_node_init(&d->t.node, &d->t.cfg), CO_OK);
    co_node_start(&d->t.node, 0);
    return d;
}

static uint32_t read_u32(device_t *d, uint16_t idx, uint8_t sub)
{
    uint8_t b[4] = {0};
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&d->t.node, idx, sub, b, 4, &len), CO_ABORT_NONE);
    return len == 1 ? b[0] : co_get_u32(b);
}

static void test_device_objects(void)
{
    device_t *d = device();
    uint8_t piece[3] = {1, 2, 3};
    CHECK_EQ(read_u32(d, 0x1F51, 1), CO_PROGRAM_START);
    CHECK_EQ(read_u32(d, 0x1F56, 1), 0x11110001);
    CHECK_EQ(read_u32(d, 0x1F57, 1), 0);
    /* Running: no data, no clear. */
    CHECK_EQ(co_node_write_net(&d->t.node, 0x1F50, 1, piece, 3), CO_ABORT_DATA_STATE);
    CHECK_EQ(write_u8(&d->t, 0x1F51, 1, CO_PROGRAM_CLEAR), CO_ABORT_DATA_STATE);
    CHECK_EQ(write_u8(&d->t, 0x1F51, 1, 4), CO_ABORT_VALUE);
    CHECK_EQ(write_u16(&d->t, 0x1F51, 1, 0), CO_ABORT_LEN_HIGH);
    /* Stop, clear: no valid program (status code 1 in bits 1..7). */
    CHECK_EQ(write_u8(&d->t, 0x1F51, 1, CO_PROGRAM_STOP), CO_ABORT_NONE);
    CHECK_EQ(read_u32(d, 0x1F51, 1), CO_PROGRAM_STOP);
    CHECK_EQ(write_u8(&d->t, 0x1F51, 1, CO_PROGRAM_CLEAR), CO_ABORT_NONE);
    CHECK_EQ(read_u32(d, 0x1F57, 1), 0x02);
    /* A whole small image, then start. */
    CHECK_EQ(co_node_write_net(&d->t.node, 0x1F50, 1, piece, 3), CO_ABORT_NONE);
    CHECK_EQ(d->app.bytes, 3);
    CHECK_EQ(read_u32(d, 0x1F57, 1), 0);
    CHECK_EQ(read_u32(d, 0x1F56, 1), checksum(5381, piece, 3));
    d->app.refuse_start = true;
    CHECK_EQ(write_u8(&d->t, 0x1F51, 1, CO_PROGRAM_START), CO_ABORT_DATA_LOCAL);
    CHECK_EQ(read_u32(d, 0x1F51, 1), CO_PROGRAM_STOP);
    d->app.refuse_start = false;
    CHECK_EQ(write_u8(&d->t, 0x1F51, 1, CO_PROGRAM_RESET), CO_ABORT_NONE);
    CHECK_EQ(read_u32(d, 0x1F51, 1), CO_PROGRAM_START);
    static const uint8_t want[] = {CO_PROGRAM_STOP, CO_PROGRAM_CLEAR, CO_PROGRAM_START,
                                   CO_PROGRAM_RESET};
    CHECK_EQ(d->app.command_count, 4);
    CHECK(memcmp(d->app.commands, want, 4) == 0);
    /* A flash that fails: the write is refused and 0x1F57 says write error (5). */
    write_u8(&d->t, 0x1F51, 1, CO_PROGRAM_STOP);
    d->app.broken = true;
    CHECK_EQ(co_node_write_net(&d->t.node, 0x1F50, 1, piece, 3), CO_ABORT_HARDWARE);
    CHECK_EQ(read_u32(d, 0x1F57, 1), 0x0A);
    free(d);
}

/* ---- master and device on the simulated bus */

typedef struct bench {
    co_sim_bus_t bus;
    example_od_t mod;
    co_node_t master;
    co_sim_port_t mport;
    example_od_t dod;
    co_node_t dev;
    co_sim_port_t dport;
    flash_app_t app;
    co_flash_t flash;
    co_flash_result_t result;
    uint32_t results;
    uint32_t progress_calls;
    uint32_t last_progress;
    uint32_t last_total;
    bool progress_monotonic;
    uint8_t image[IMAGE_LEN];
} bench_t;

static void on_progress(void *ctx, uint32_t done, uint32_t total)
{
    bench_t *b = ctx;
    b->last_total = total;
    if (done < b->last_progress) {
        b->progress_monotonic = false;
    }
    b->last_progress = done;
    b->progress_calls++;
}

static void on_flashed(void *ctx, const co_flash_result_t *r)
{
    bench_t *b = ctx;
    b->result = *r;
    b->results++;
}

static bench_t *bench_up(void)
{
    bench_t *b = calloc(1, sizeof *b);
    co_sim_bus_init(&b->bus, 1000000);
    co_node_config_t mc = {.node_id = 1, .od = example_od_init(&b->mod, 0)};
    co_sim_port_attach(&b->bus, &b->mport);
    mc.driver = co_sim_port_driver(&b->mport);
    CHECK_EQ(co_node_init(&b->master, &mc), CO_OK);
    co_sim_port_bind(&b->mport, &b->master);
    co_node_config_t dc = {.node_id = 2, .od = example_od_init(&b->dod, 0)};
    add_program_objects(&b->dod, &dc, &b->app);
    co_sim_port_attach(&b->bus, &b->dport);
    dc.driver = co_sim_port_driver(&b->dport);
    CHECK_EQ(co_node_init(&b->dev, &dc), CO_OK);
    co_sim_port_bind(&b->dport, &b->dev);
    co_node_start(&b->master, 0);
    co_node_start(&b->dev, 0);
    uint32_t x = 12345;
    for (uint32_t i = 0; i < IMAGE_LEN; i++) {
        x = x * 1103515245u + 12345u;
        b->image[i] = (uint8_t)(x >> 16);
    }
    b->progress_monotonic = true;
    return b;
}

static co_flash_request_t request(bench_t *b, uint32_t ident)
{
    co_flash_request_t r = {.channel = 0,
                            .server = 2,
                            .clear = true,
                            .check_ident = true,
                            .ident = ident,
                            .data = b->image,
                            .len = IMAGE_LEN,
                            .progress = on_progress,
                            .done = on_flashed,
                            .ctx = b};
    return r;
}

static void test_one_mebibyte_download_verified(void)
{
    bench_t *b = bench_up();
    co_sim_run_until(&b->bus, 10 * MS);
    uint32_t want = checksum(5381, b->image, IMAGE_LEN);
    co_flash_request_t r = request(b, want);
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_ERR_BUSY);
    co_sim_run_until(&b->bus, 60000 * MS);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_DONE);
    CHECK_EQ(b->result.abort, CO_ABORT_NONE);
    CHECK(b->result.ident_ok);
    CHECK_EQ(b->result.ident, want);
    CHECK_EQ(b->result.bytes, IMAGE_LEN);
    CHECK_EQ(b->app.bytes, IMAGE_LEN);
    CHECK_EQ(b->app.sum, want);
    CHECK(b->app.pieces > 1); /* streamed, not buffered */
    CHECK(b->progress_calls > 10);
    CHECK(b->progress_monotonic);
    CHECK_EQ(b->last_progress, IMAGE_LEN);
    CHECK_EQ(b->last_total, IMAGE_LEN);
    CHECK_EQ(b->app.prog.state, CO_PROGRAM_START);
    static const uint8_t want_cmds[] = {CO_PROGRAM_STOP, CO_PROGRAM_CLEAR, CO_PROGRAM_START};
    CHECK_EQ(b->app.command_count, 3);
    CHECK(memcmp(b->app.commands, want_cmds, 3) == 0);
    CHECK_STR(co_flash_stage_name(b->result.stage), "done");
    free(b);
}

static void test_download_failures_name_their_stage(void)
{
    bench_t *b = bench_up();
    co_sim_run_until(&b->bus, 10 * MS);
    /* The identification read back is not the one expected. */
    co_flash_request_t r = request(b, 0xDEADBEEF);
    r.len = 1000;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 2000 * MS);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_VERIFY);
    CHECK(!b->result.ident_ok);
    CHECK_EQ(b->result.ident, checksum(5381, b->image, 1000));
    /* The flash breaks: the data stage fails with the device's abort code. */
    b->app.broken = true;
    r.clear = false;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 4000 * MS);
    CHECK_EQ(b->results, 2);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_DATA);
    CHECK_EQ(b->result.abort, CO_ABORT_HARDWARE);
    /* The device refuses to start. */
    b->app.broken = false;
    b->app.refuse_start = true;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 6000 * MS);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_START);
    CHECK_EQ(b->result.abort, CO_ABORT_DATA_LOCAL);
    /* Nobody there. */
    r.server = 9;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 9000 * MS);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_STOP);
    CHECK_EQ(b->result.abort, CO_ABORT_TIMEOUT);
    r.len = 0;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_ERR_ARG);
    free(b);
}

/* ---- device side without an application, and the hooks called directly */

static void test_device_without_application(void)
{
    co_program_t p;
    co_program_init(&p, NULL, false, 0x42);
    CHECK_EQ(p.state, CO_PROGRAM_STOP);
    CHECK_EQ(p.ident, 0x42);
    CHECK_EQ(p.status, 0);
    uint8_t piece[2] = {1, 2};
    /* No write callback: nowhere to put the image. */
    CHECK_EQ(co_program_data_write(&p, 0, piece, 2, 2, true), CO_ABORT_UNSUPPORTED);
    CHECK_EQ(p.status, 0);
    /* No control callback: the commands are taken as they are. */
    CHECK_EQ(co_program_control_write(&p, CO_PROGRAM_CLEAR), CO_ABORT_NONE);
    CHECK_EQ(p.status, CO_FLASH_STATUS_NO_PROGRAM << 1);
    CHECK_EQ(co_program_control_write(&p, CO_PROGRAM_START), CO_ABORT_NONE);
    CHECK_EQ(p.state, CO_PROGRAM_START);
    CHECK_EQ(co_program_control_write(&p, CO_PROGRAM_STOP), CO_ABORT_NONE);
    CHECK_EQ(p.state, CO_PROGRAM_STOP);
    CHECK_EQ(co_program_control_write(&p, 0xFF), CO_ABORT_VALUE);
    CHECK_EQ(p.state, CO_PROGRAM_STOP);
}

static void test_hooks_called_directly(void)
{
    flash_app_t a;
    memset(&a, 0, sizeof a);
    co_program_app_t app = {.write = app_write, .control = app_control, .ctx = &a};
    co_program_init(&a.prog, &app, false, 0xA1B2C3D4);
    uint8_t cmd = CO_PROGRAM_START;
    /* 0x1F51 takes one byte in one piece at offset 0, nothing else. */
    CHECK_EQ(co_program_control_hooks.write(&a.prog, NULL, 1, &cmd, 1, 2, true),
             CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(co_program_control_hooks.write(&a.prog, NULL, 0, &cmd, 2, 2, true),
             CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(co_program_control_hooks.write(&a.prog, NULL, 0, &cmd, 1, 2, false),
             CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(a.command_count, 0);
    CHECK_EQ(a.prog.state, CO_PROGRAM_STOP);
    CHECK_EQ(co_program_control_hooks.write(&a.prog, NULL, 0, &cmd, 1, 1, true), CO_ABORT_NONE);
    CHECK_EQ(a.prog.state, CO_PROGRAM_START);
    /* Reads in pieces: the little-endian bytes from `offset`, at most `cap` of them. */
    uint8_t buf[4] = {0};
    uint32_t n = 99, total = 0;
    CHECK_EQ(co_program_ident_hooks.read(&a.prog, NULL, 0, buf, 2, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 2);
    CHECK_EQ(total, 4);
    CHECK_EQ(buf[0], 0xD4);
    CHECK_EQ(buf[1], 0xC3);
    CHECK_EQ(co_program_ident_hooks.read(&a.prog, NULL, 2, buf, 4, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 2);
    CHECK_EQ(buf[0], 0xB2);
    CHECK_EQ(buf[1], 0xA1);
    CHECK_EQ(co_program_control_hooks.read(&a.prog, NULL, 0, buf, 4, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 1);
    CHECK_EQ(total, 1);
    CHECK_EQ(buf[0], CO_PROGRAM_START);
    CHECK_EQ(co_program_status_hooks.read(&a.prog, NULL, 4, buf, 4, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 0); /* past the end: nothing */
    CHECK_EQ(total, 4);
    /* Data through the hook goes to the application; in pieces, the last one ends it. */
    CHECK_EQ(co_program_control_write(&a.prog, CO_PROGRAM_STOP), CO_ABORT_NONE);
    uint8_t img[4] = {9, 8, 7, 6};
    CHECK_EQ(co_program_data_hooks.write(&a.prog, NULL, 0, img, 2, 4, false), CO_ABORT_NONE);
    CHECK_EQ(a.prog.status, CO_FLASH_STATUS_BUSY); /* a download runs */
    CHECK_EQ(co_program_data_hooks.write(&a.prog, NULL, 2, img + 2, 2, 4, true), CO_ABORT_NONE);
    CHECK_EQ(a.prog.status, 0);
    CHECK_EQ(a.bytes, 4);
    CHECK_EQ(a.prog.ident, checksum(5381, img, 4));
}

/* ---- master: argument errors, each stage refused, no callbacks */

static void on_written(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    (void)len;
    *(co_abort_t *)ctx = abort;
}

static void test_flash_start_arguments(void)
{
    bench_t *b = bench_up();
    co_flash_request_t r = request(b, 0);
    r.len = 16;
    co_flash_request_t bad = r;
    CHECK_EQ(co_flash_start(NULL, &b->master, &r), CO_ERR_ARG);
    CHECK_EQ(co_flash_start(&b->flash, NULL, &r), CO_ERR_ARG);
    CHECK_EQ(co_flash_start(&b->flash, &b->master, NULL), CO_ERR_ARG);
    bad.data = NULL;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &bad), CO_ERR_ARG);
    bad = r;
    bad.server = 0;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &bad), CO_ERR_ARG);
    bad.server = 128;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &bad), CO_ERR_ARG);
    bad = r;
    bad.channel = 1; /* one client channel in this build */
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &bad), CO_ERR_ARG);
    CHECK_EQ(b->results, 0);
    CHECK_EQ(b->app.command_count, 0);
    /* The channel busy with another transfer: no download begins. */
    CHECK_EQ(co_sdo_client_setup(&b->master, 0, 2), CO_OK);
    co_abort_t written = 1;
    CHECK_EQ(co_sdo_write_value(&b->master, 0, 0x2000, 0, 5, 4, on_written, &written), CO_OK);
    CHECK(co_sdo_client_busy(&b->master, 0));
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_ERR_BUSY);
    co_sim_run_until(&b->bus, 100 * MS);
    CHECK(!co_sdo_client_busy(&b->master, 0));
    CHECK_EQ(written, CO_ABORT_NONE);
    CHECK_EQ(b->dod.app_u32, 5);
    CHECK_EQ(b->app.command_count, 0);
    CHECK_EQ(b->results, 0);
    free(b);
}

static void test_stop_and_clear_refused(void)
{
    bench_t *b = bench_up();
    co_sim_run_until(&b->bus, 10 * MS);
    co_flash_request_t r = request(b, 0);
    r.len = 100;
    b->app.refuse_mask = 1u << CO_PROGRAM_STOP;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 1000 * MS);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_STOP);
    CHECK_EQ(b->result.abort, CO_ABORT_DATA_LOCAL);
    CHECK_STR(co_flash_stage_name(b->result.stage), "stop");
    CHECK_EQ(b->app.bytes, 0);
    CHECK_EQ(b->app.prog.state, CO_PROGRAM_START); /* still runs the old program */
    /* Stop taken, clear refused: nothing downloaded. */
    b->app.refuse_mask = 1u << CO_PROGRAM_CLEAR;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 2000 * MS);
    CHECK_EQ(b->results, 2);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_CLEAR);
    CHECK_EQ(b->result.abort, CO_ABORT_DATA_LOCAL);
    CHECK_STR(co_flash_stage_name(b->result.stage), "clear");
    CHECK_EQ(b->app.bytes, 0);
    CHECK_EQ(b->app.prog.state, CO_PROGRAM_STOP);
    CHECK_STR(co_flash_stage_name(CO_FLASH_STAGE_DATA), "data");
    CHECK_STR(co_flash_stage_name(CO_FLASH_STAGE_START), "start");
    CHECK_STR(co_flash_stage_name(CO_FLASH_STAGE_VERIFY), "verify");
    CHECK_STR(co_flash_stage_name(0), "unknown");
    free(b);
}

static void test_no_callbacks_no_check_other_program(void)
{
    bench_t *b = bench_up();
    co_sim_run_until(&b->bus, 10 * MS);
    /* No done, no progress, no identification check: the download still runs to the end,
     * and the master is free for the next one afterwards. */
    co_flash_request_t r = request(b, 0);
    r.len = 200000; /* long enough to be polled in the data stage */
    r.done = NULL;
    r.progress = NULL;
    r.check_ident = false;
    r.clear = false;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 20000 * MS);
    CHECK_EQ(b->results, 0);
    CHECK_EQ(b->app.bytes, 200000);
    CHECK_EQ(b->app.sum, checksum(5381, b->image, 200000));
    CHECK_EQ(b->app.prog.state, CO_PROGRAM_START);
    static const uint8_t want[] = {CO_PROGRAM_STOP, CO_PROGRAM_START};
    CHECK_EQ(b->app.command_count, 2);
    CHECK(memcmp(b->app.commands, want, 2) == 0);
    /* Without a check any identification is fine. */
    r = request(b, 0x12345678);
    r.len = 10;
    r.check_ident = false;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 21000 * MS);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_DONE);
    CHECK(b->result.ident_ok);
    CHECK_EQ(b->result.ident, checksum(5381, b->image, 10));
    /* Program 2 does not exist on the device: the stop of 0x1F51 sub2 fails. */
    r.program = 2;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 22000 * MS);
    CHECK_EQ(b->results, 2);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_STOP);
    CHECK_EQ(b->result.abort, CO_ABORT_NO_SUB);
    free(b);
}

static void test_verify_read_refused(void)
{
    bench_t *b = bench_up();
    co_sim_run_until(&b->bus, 10 * MS);
    /* 0x1F56 sub1 made unreadable: the verify stage fails with the device's abort. */
    for (uint32_t e = 0; e < b->dev.cfg.od.count; e++) {
        co_od_entry_t *en = &b->dod.entries[e];
        if (en->index == 0x1F56 && en->sub == 1) {
            en->attr = CO_OD_WO;
        }
    }
    co_flash_request_t r = request(b, 0);
    r.len = 10;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 2000 * MS);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_VERIFY);
    CHECK_EQ(b->result.abort, CO_ABORT_WRITE_ONLY);
    CHECK(!b->result.ident_ok);
    CHECK_EQ(b->app.bytes, 10);
    /* A node flashing itself (no program objects): the stop fails at once. */
    r.server = 1;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    CHECK_EQ(b->results, 2);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_STOP);
    CHECK_EQ(b->result.abort, CO_ABORT_NO_OBJECT);
    free(b);
}

/* A stopped master may not use SDO: the download ends at once, at the stop, and the
 * master is free for the next one. */
static void test_stopped_master_cannot_download(void)
{
    bench_t *b = bench_up();
    co_sim_run_until(&b->bus, 10 * MS);
    CHECK_EQ(co_nmt_apply(&b->master, CO_NMT_CMD_STOP), CO_OK);
    co_flash_request_t r = request(b, 0);
    r.len = 100;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_STOP);
    CHECK_EQ(b->result.abort, CO_ABORT_GENERAL);
    co_sim_run_until(&b->bus, 100 * MS);
    CHECK_EQ(b->app.command_count, 0);
    CHECK_EQ(b->progress_calls, 0);
    CHECK_EQ(co_nmt_apply(&b->master, CO_NMT_CMD_ENTER_PRE_OPERATIONAL), CO_OK);
    r.check_ident = false;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 1000 * MS);
    CHECK_EQ(b->results, 2);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_DONE);
    CHECK_EQ(b->app.bytes, 100);
    free(b);
}

/* A master polled all along (its heartbeat, every millisecond) on a slow bus: progress
 * comes from the data stage only, never goes back, and ends at the image length. */
static void test_progress_of_a_master_polled_in_every_stage(void)
{
    bench_t *b = bench_up();
    co_sim_delay(&b->bus, 2000); /* every frame leaves 2 ms after it was sent */
    CHECK_EQ(co_node_set_uint(&b->master, 0x1017, 0, 1), CO_ABORT_NONE);
    co_sim_run_until(&b->bus, 10 * MS);
    co_flash_request_t r = request(b, 0);
    r.len = 2000;
    r.check_ident = false;
    CHECK_EQ(co_flash_start(&b->flash, &b->master, &r), CO_OK);
    co_sim_run_until(&b->bus, 5000 * MS);
    CHECK_EQ(b->results, 1);
    CHECK_EQ(b->result.stage, CO_FLASH_STAGE_DONE);
    CHECK_EQ(b->app.bytes, 2000);
    CHECK(b->progress_calls > 2);
    CHECK(b->progress_monotonic);
    CHECK_EQ(b->last_progress, 2000);
    CHECK_EQ(b->last_total, 2000);
    free(b);
}

int main(void)
{
    RUN(test_device_objects);
    RUN(test_one_mebibyte_download_verified);
    RUN(test_download_failures_name_their_stage);
    RUN(test_device_without_application);
    RUN(test_hooks_called_directly);
    RUN(test_flash_start_arguments);
    RUN(test_stop_and_clear_refused);
    RUN(test_no_callbacks_no_check_other_program);
    RUN(test_verify_read_refused);
    RUN(test_stopped_master_cannot_download);
    RUN(test_progress_of_a_master_polled_in_every_stage);
    return check_summary();
}
