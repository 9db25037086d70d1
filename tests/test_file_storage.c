/* test_file_storage.c -- parameter storage in files: saves survive a power cycle, a save
 * cut off before its commit leaves the old image, restore removes it. */
#define _POSIX_C_SOURCE 200809L

#include <stdlib.h>
#include <unistd.h>

#include "canola/file_storage.h"
#include "check.h"
#include "harness.h"

static char g_dir[64];
static co_file_storage_t g_fs;

static void power_on(test_node_t *t)
{
    CHECK_EQ(test_node_init(t, 5, 100), CO_OK);
    t->node.cfg.storage = &g_fs.api;
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
}

static void fresh_dir(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/canola-fs-XXXXXX");
    CHECK(mkdtemp(g_dir) != NULL);
    CHECK_EQ(co_file_storage_init(&g_fs, g_dir), CO_OK);
}

static void clean_dir(void)
{
    char path[128];
    const char *names[] = {"comm.params", "app.params", "comm.params.tmp", "app.params.tmp"};
    for (unsigned i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/%s", g_dir, names[i]);
        unlink(path);
    }
    rmdir(g_dir);
}

static void test_save_survives_a_power_cycle(void)
{
    static test_node_t t;
    fresh_dir();
    power_on(&t);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    co_node_set_uint(&t.node, 0x1017, 0, 250);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0xCAFE);
    CHECK_EQ(t.od.hb_period_ms, 250);
    clean_dir();
}

static void test_save_cut_before_commit_keeps_the_old_image(void)
{
    static test_node_t t;
    fresh_dir();
    power_on(&t);
    co_node_set_uint(&t.node, 0x2000, 0, 0x1111);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    /* A new save starts and writes, then the power goes before the commit. */
    CHECK_EQ(g_fs.api.begin(g_fs.api.ctx, CO_PARAMS_APPLICATION), CO_OK);
    const uint8_t junk[] = {0x00, 0x20, 0x00, 4, 0x22, 0x22, 0, 0};
    CHECK_EQ(g_fs.api.write(g_fs.api.ctx, junk, sizeof junk), CO_OK);
    CHECK_EQ(co_file_storage_init(&g_fs, g_dir), CO_OK); /* the process restarts */
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0x1111);
    /* The next save replaces the stray temporary file. */
    co_node_set_uint(&t.node, 0x2000, 0, 0x3333);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0x3333);
    clean_dir();
}

static void test_restore_removes_the_image(void)
{
    static test_node_t t;
    fresh_dir();
    power_on(&t);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE);
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0x12345678);
    uint32_t n = 9;
    uint8_t b[4];
    CHECK_EQ(g_fs.api.read(g_fs.api.ctx, CO_PARAMS_APPLICATION, 0, b, 4, &n), CO_ERR_NOT_FOUND);
    clean_dir();
}

static void test_bad_folder_refused(void)
{
    co_file_storage_t fs;
    CHECK_EQ(co_file_storage_init(&fs, "/nonexistent/canola"), CO_ERR_ARG);
    CHECK_EQ(co_file_storage_init(&fs, ""), CO_ERR_ARG);
}

int main(void)
{
    RUN(test_save_survives_a_power_cycle);
    RUN(test_save_cut_before_commit_keeps_the_old_image);
    RUN(test_restore_removes_the_image);
    RUN(test_bad_folder_refused);
    return check_summary();
}
