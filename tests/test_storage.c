/* SPDX-License-Identifier: Apache-2.0 */
/* test_storage.c -- stored parameters: 0x1010 save, 0x1011 restore defaults, power cycles. */
#include "canola/sim_storage.h"
#include "check.h"
#include "harness.h"
#include "store_image.h"

#include <stdio.h>
#include <string.h>

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
    CHECK_EQ(g_storage.commits, 1); /* both groups, in one step */
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
    img->len = store_image_seal(img->data, CO_PARAMS_APPLICATION, records, sizeof records);
    img->valid = true;
    power_on(&t, 5, true);
    CHECK_EQ(t.od.app_u32, 0xBEEF);
    CHECK_EQ(t.od.app_i16, 0);
    CHECK_EQ(t.od.app_wo, 9);
}

/* ---- damaged images: refused whole, the node says so */

/* The node after a power-on refused its stored communication parameters with `fault`:
 * defaults in use, EMCY 0xFF11 (manufacturer byte 0 = the fault) sent after boot-up and
 * active, on_error told. */
static void check_comm_refused(test_node_t *t, co_store_fault_t fault)
{
    CHECK_EQ(co_storage_verify(&t->node, CO_PARAMS_COMMUNICATION), fault);
    CHECK_EQ(t->od.hb_period_ms, 100); /* the default, not 777 nor any flipped value */
    CHECK(co_emcy_active(&t->node, 0xFF11));
    CHECK_EQ(t->error_count, 1);
    CHECK_EQ(t->errors[0], CO_NODE_ERR_STORED_COMM);
    co_node_poll(&t->node, 0);
    char buf[64];
    char want[32];
    snprintf(want, sizeof want, "085#11FF81%02X00000000", (unsigned)fault);
    bool sent = false;
    for (uint32_t i = 0; i < t->bus.count; i++) {
        sent |= strcmp(frame_str(&t->bus.frames[i], buf, sizeof buf), want) == 0;
    }
    CHECK(sent);
}

/* A saved communication image with 0x1017 = 777 (and the application one intact). */
static void save_777(test_node_t *t)
{
    co_sim_storage_init(&g_storage);
    power_on(t, 5, true);
    CHECK_EQ(co_node_set_uint(&t->node, 0x1017, 0, 777), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&t->node, 0x2000, 0, 0xCAFE), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    power_on(t, 5, true);
    CHECK_EQ(t->od.hb_period_ms, 777);
    CHECK_EQ(co_storage_verify(&t->node, CO_PARAMS_COMMUNICATION), CO_STORE_INTACT);
    CHECK_EQ(t->error_count, 0);
}

static void test_every_flipped_bit_is_refused(void)
{
    static test_node_t t;
    save_777(&t);
    co_sim_image_t *img = &g_storage.images[0];
    uint32_t refused = 0;
    for (uint32_t bit = 0; bit < img->len * 8u; bit++) {
        img->data[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        power_on(&t, 5, true);
        co_store_fault_t fault = co_storage_verify(&t.node, CO_PARAMS_COMMUNICATION);
        refused += fault != CO_STORE_INTACT && t.od.hb_period_ms == 100 &&
                   co_emcy_active(&t.node, 0xFF11) && t.od.app_u32 == 0xCAFE;
        img->data[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
    }
    CHECK_EQ(refused, img->len * 8u);
    /* the damage once seen in the field: 0x1017's own bit 8, which turned 777 into 521 */
    const uint8_t record[] = {0x17, 0x10, 0x00, 2, 0x09, 0x03};
    uint32_t at = 0;
    while (at + sizeof record <= img->len && memcmp(&img->data[at], record, sizeof record) != 0) {
        at++;
    }
    CHECK(at + sizeof record <= img->len);
    img->data[at + 5u] ^= 0x01u;
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_CRC);
}

static void test_truncated_images_are_refused(void)
{
    static test_node_t t;
    save_777(&t);
    co_sim_image_t *img = &g_storage.images[0];
    uint32_t whole = img->len;
    for (uint32_t len = 0; len < whole; len++) {
        img->len = len;
        power_on(&t, 5, true);
        CHECK_EQ(t.od.hb_period_ms, 100);
        CHECK(co_emcy_active(&t.node, 0xFF11));
    }
    img->len = whole - 1u;
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_LENGTH);
    img->len = 5; /* a cut inside the header */
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_HEADER);
    img->len = whole + 1u; /* a stray byte after the records */
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_LENGTH);
}

static void test_foreign_and_random_images_are_refused(void)
{
    static test_node_t t;
    save_777(&t);
    co_sim_image_t *img = &g_storage.images[0];
    /* the application image where the communication one belongs: wrong group */
    g_storage.images[0] = g_storage.images[1];
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_HEADER);
    /* a later format version */
    save_777(&t);
    img->data[4] = CO_STORE_FORMAT + 1u;
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_HEADER);
    /* records that do not end at the length, under a CRC that matches them */
    const uint8_t records[] = {0x17, 0x10, 0x00, 2, 0x09, 0x03, 0x17, 0x10};
    img->len = store_image_seal(img->data, CO_PARAMS_COMMUNICATION, records, sizeof records);
    power_on(&t, 5, true);
    check_comm_refused(&t, CO_STORE_BAD_RECORDS);
    /* random bytes (a fixed generator: the same every run) */
    uint32_t x = 12345;
    for (int round = 0; round < 200; round++) {
        img->len = (uint32_t)round * 7u % 300u;
        for (uint32_t i = 0; i < img->len; i++) {
            x = x * 1103515245u + 12345u;
            img->data[i] = (uint8_t)(x >> 16);
        }
        power_on(&t, 5, true);
        CHECK_EQ(t.od.hb_period_ms, 100);
        CHECK(co_emcy_active(&t.node, 0xFF11));
    }
}

static void test_a_save_or_restore_ends_the_error(void)
{
    static test_node_t t;
    save_777(&t);
    g_storage.images[0].data[20] ^= 0x10u;
    power_on(&t, 5, true);
    CHECK(co_emcy_active(&t.node, 0xFF11));
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE); /* other group */
    CHECK(co_emcy_active(&t.node, 0xFF11));
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK(!co_emcy_active(&t.node, 0xFF11));
    power_on(&t, 5, true);
    CHECK_EQ(t.error_count, 0);
    g_storage.images[0].data[20] ^= 0x10u;
    power_on(&t, 5, true);
    CHECK(co_emcy_active(&t.node, 0xFF11));
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    CHECK(!co_emcy_active(&t.node, 0xFF11));
    power_on(&t, 5, true);
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_COMMUNICATION), CO_STORE_NONE);
    CHECK_EQ(t.error_count, 0);
}

/* The application group refused on its own: 0xFF12, the communication group still loads. */
static void test_application_image_refused_alone(void)
{
    static test_node_t t;
    save_777(&t);
    g_storage.images[1].data[g_storage.images[1].len - 1u] ^= 0x80u;
    power_on(&t, 5, true);
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_APPLICATION), CO_STORE_BAD_CRC);
    CHECK_EQ(t.od.app_u32, 0x12345678);
    CHECK_EQ(t.od.hb_period_ms, 777);
    CHECK(co_emcy_active(&t.node, 0xFF12));
    CHECK(!co_emcy_active(&t.node, 0xFF11));
    CHECK_EQ(t.error_count, 1);
    CHECK_EQ(t.errors[0], CO_NODE_ERR_STORED_APP);
    /* the error history keeps it: the reset of the communication group (0x1003 among it)
     * that follows the application's does not wipe it */
    CHECK_EQ(t.od.error_count, 1);
    CHECK_EQ(t.od.error_history[0], 0x0004FF12u); /* manufacturer byte 0: CO_STORE_BAD_CRC */
}

/* Both images refused: both EMCYs in the history, the communication group's first. */
static void test_both_refused_images_are_in_the_history(void)
{
    static test_node_t t;
    save_777(&t);
    g_storage.images[0].data[20] ^= 0x10u;
    g_storage.images[1].data[g_storage.images[1].len - 1u] ^= 0x80u;
    power_on(&t, 5, true);
    CHECK(co_emcy_active(&t.node, 0xFF11));
    CHECK(co_emcy_active(&t.node, 0xFF12));
    CHECK_EQ(t.od.error_count, 2);
    CHECK_EQ(t.od.error_history[0] & 0xFFFFu, 0xFF12u);
    CHECK_EQ(t.od.error_history[1] & 0xFFFFu, 0xFF11u);
    CHECK_EQ(t.od.error_register & 0x01u, 0x01u); /* generic error */
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
    RUN(test_every_flipped_bit_is_refused);
    RUN(test_truncated_images_are_refused);
    RUN(test_foreign_and_random_images_are_refused);
    RUN(test_a_save_or_restore_ends_the_error);
    RUN(test_application_image_refused_alone);
    RUN(test_both_refused_images_are_in_the_history);
    return check_summary();
}
