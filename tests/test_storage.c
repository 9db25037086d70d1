/* test_storage.c -- stored parameters: 0x1010 save, 0x1011 restore defaults, power cycles. */
#include "canola/sim_storage.h"
#include "check.h"
#include "harness.h"

static co_sim_storage_t g_storage;

/* A power-on: fresh values (the example's defaults), the same storage. */
static void power_on(test_node_t *t, uint8_t id, bool with_storage)
{
    CHECK_EQ(test_node_init(t, id, 100), CO_OK);
    t->node.cfg.storage = with_storage ? &g_storage.api : NULL;
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
}

static void test_capability_reads(void)
{
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    power_on(&t, 5, true);
    uint64_t v = 9;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1010, 1, &v), CO_OK);
    CHECK_EQ(v, 1);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1011, 3, &v), CO_OK);
    CHECK_EQ(v, 1);
    power_on(&t, 5, false);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1010, 1, &v), CO_OK);
    CHECK_EQ(v, 0);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_DATA_STORE);
}

static void test_save_survives_a_power_cycle(void)
{
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    power_on(&t, 5, true);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&t.node, 0x1017, 0, 250), CO_ABORT_NONE);
    CHECK_EQ(co_node_write_net(&t.node, 0x2002, 0, (const uint8_t *)"xyz", 3), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(g_storage.commits, 2); /* both groups */
    /* The entry reads as the capability again, not as the signature. */
    CHECK_EQ(t.od.store[0], 1);

    power_on(&t, 5, true);
    CHECK_EQ(t.od.app_u32, 0xCAFE);
    CHECK_EQ(t.od.hb_period_ms, 250);
    CHECK_STR(t.od.app_string, "xyz");
    CHECK_EQ(t.od.app_i16, 0); /* never changed: its default */
    /* A stored value is a power-on value: reset communication brings it back too. */
    CHECK_EQ(co_node_set_uint(&t.node, 0x1017, 0, 500), CO_ABORT_NONE);
    co_nmt_apply(&t.node, CO_NMT_CMD_RESET_COMMUNICATION);
    CHECK_EQ(t.od.hb_period_ms, 250);
    /* ...and the heartbeat runs with it. */
    CHECK_EQ(co_node_poll(&t.node, 0), 250000);
}

static void test_save_one_group(void)
{
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    power_on(&t, 5, true);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    co_node_set_uint(&t.node, 0x1017, 0, 250);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE); /* communication */
    power_on(&t, 5, true);
    CHECK_EQ(t.od.hb_period_ms, 250);
    CHECK_EQ(t.od.app_u32, 0x12345678);
    co_node_set_uint(&t.node, 0x2000, 0, 0xBEEF);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE); /* application */
    power_on(&t, 5, true);
    CHECK_EQ(t.od.app_u32, 0xBEEF);
    CHECK_EQ(t.od.hb_period_ms, 250);
}

static void test_wrong_signature_and_sub_index(void)
{
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    power_on(&t, 5, true);
    CHECK_EQ(write_u32(&t, 0x1010, 1, 0x65766174), CO_ABORT_DATA_STORE);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_RESTORE_SIGNATURE), CO_ABORT_DATA_STORE);
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_STORE_SIGNATURE), CO_ABORT_DATA_STORE);
    CHECK_EQ(write_u32(&t, 0x1010, 4, CO_STORE_SIGNATURE), CO_ABORT_NO_SUB);
    CHECK_EQ(g_storage.commits, 0);
    CHECK_EQ(t.od.store[0], 1);
}

static void test_restore_defaults_takes_effect_at_next_reset(void)
{
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    power_on(&t, 5, true);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    co_node_set_uint(&t.node, 0x1017, 0, 250);
    write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE);
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(t.od.app_u32, 0xCAFE); /* nothing changes before the reset */
    CHECK_EQ(t.od.restore[0], 1);
    co_nmt_apply(&t.node, CO_NMT_CMD_RESET_NODE);
    CHECK_EQ(t.od.app_u32, 0x12345678);
    CHECK_EQ(t.od.hb_period_ms, 100);
    power_on(&t, 5, true);
    CHECK_EQ(t.od.app_u32, 0x12345678);
}

static void test_failed_save_keeps_the_old_image(void)
{
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    power_on(&t, 5, true);
    co_node_set_uint(&t.node, 0x2000, 0, 0x1111);
    write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE);
    co_node_set_uint(&t.node, 0x2000, 0, 0x2222);
    g_storage.fail_next_commit = true;
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    power_on(&t, 5, true);
    CHECK_EQ(t.od.app_u32, 0x1111);
}

static void test_stored_values_of_another_dictionary_are_skipped(void)
{
    /* A record whose entry is not writable in this dictionary, or whose length differs,
     * is not applied. */
    static test_node_t t;
    co_sim_storage_init(&g_storage);
    co_sim_image_t *img = &g_storage.images[1];
    const uint8_t records[] = {
        0x00, 0x20, 0x00, 4, 0xEF, 0xBE, 0x00, 0x00, /* 0x2000 = 0xBEEF: applied */
        0x01, 0x20, 0x00, 4, 1,    2,    3,    4,    /* 0x2001 is 2 bytes: skipped */
        0x00, 0x30, 0x00, 1, 7,                      /* 0x3000 does not exist */
        0x04, 0x20, 0x00, 1, 9,                      /* 0x2004 is write-only: applied */
    };
    memcpy(img->data, records, sizeof records);
    img->len = sizeof records;
    img->valid = true;
    power_on(&t, 5, true);
    CHECK_EQ(t.od.app_u32, 0xBEEF);
    CHECK_EQ(t.od.app_i16, 0);
    CHECK_EQ(t.od.app_wo, 9);
}

int main(void)
{
    RUN(test_capability_reads);
    RUN(test_save_survives_a_power_cycle);
    RUN(test_save_one_group);
    RUN(test_wrong_signature_and_sub_index);
    RUN(test_restore_defaults_takes_effect_at_next_reset);
    RUN(test_failed_save_keeps_the_old_image);
    RUN(test_stored_values_of_another_dictionary_are_skipped);
    return check_summary();
}
