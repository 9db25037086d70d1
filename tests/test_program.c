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

int main(void)
{
    RUN(test_device_objects);
    RUN(test_one_mebibyte_download_verified);
    RUN(test_download_failures_name_their_stage);
    return check_summary();
}
