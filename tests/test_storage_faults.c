/* SPDX-License-Identifier: Apache-2.0 */
/* test_storage_faults.c -- stored parameters against a storage that fails and images that
 * are damaged or written by another firmware: saves report 0x06060000, raise EMCY 0x5530
 * and leave nothing behind (a save of both groups is one step with a storage that
 * stages), loads apply an image whole or not at all, and of an intact image only records
 * in their group and valid for the entry. */
#include "check.h"
#include "harness.h"
#include "store_image.h"

/* A scripted storage: one image per group, failures on demand, call counts. */
typedef struct script {
    uint8_t image[3][2048];
    uint32_t len[3];
    bool stored[3];
    uint8_t records[3][2048]; /* add_record's records, sealed into image at power-on */
    uint32_t records_len[3];
    uint8_t staging[2048];
    uint32_t staging_len;
    co_param_group_t group;
    uint8_t staged[2048]; /* the first image of a save of both groups */
    uint32_t staged_len;
    co_param_group_t staged_group;
    bool has_staged;
    int stages;
    bool fail_begin;
    int fail_write_at; /* 1-based write call that fails; 0 = none */
    int writes;
    bool fail_erase;
    int fail_read_at; /* 1-based read call that fails; 0 = none */
    int reads;
    bool cannot_save; /* can_save answers false */
    int commits;
    int discards;
    int erased[3];
} script_t;

static script_t g_s;

static co_err_t s_begin(void *ctx, co_param_group_t group)
{
    script_t *s = ctx;
    s->group = group;
    s->staging_len = 0;
    return s->fail_begin ? CO_ERR_STATE : CO_OK;
}

static co_err_t s_write(void *ctx, const uint8_t *data, uint32_t len)
{
    script_t *s = ctx;
    if (++s->writes == s->fail_write_at || s->staging_len + len > sizeof s->staging) {
        return CO_ERR_FULL;
    }
    memcpy(&s->staging[s->staging_len], data, len);
    s->staging_len += len;
    return CO_OK;
}

static co_err_t s_stage(void *ctx)
{
    script_t *s = ctx;
    memcpy(s->staged, s->staging, s->staging_len);
    s->staged_len = s->staging_len;
    s->staged_group = s->group;
    s->has_staged = true;
    s->stages++;
    return CO_OK;
}

static co_err_t s_commit(void *ctx)
{
    script_t *s = ctx;
    if (s->has_staged) {
        memcpy(s->image[s->staged_group], s->staged, s->staged_len);
        s->len[s->staged_group] = s->staged_len;
        s->stored[s->staged_group] = true;
        s->has_staged = false;
    }
    memcpy(s->image[s->group], s->staging, s->staging_len);
    s->len[s->group] = s->staging_len;
    s->stored[s->group] = true;
    s->commits++;
    return CO_OK;
}

static co_err_t s_read(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf,
                       uint32_t cap, uint32_t *n)
{
    script_t *s = ctx;
    if (!s->stored[group]) {
        return CO_ERR_NOT_FOUND;
    }
    if (++s->reads == s->fail_read_at) {
        return CO_ERR_STATE;
    }
    uint32_t left = offset < s->len[group] ? s->len[group] - offset : 0;
    *n = left < cap ? left : cap;
    memcpy(buf, &s->image[group][offset], *n);
    return CO_OK;
}

static co_err_t s_erase(void *ctx, co_param_group_t group)
{
    script_t *s = ctx;
    if (s->fail_erase) {
        return CO_ERR_STATE;
    }
    s->erased[group]++;
    s->stored[group] = false;
    return CO_OK;
}

static bool s_can_save(void *ctx) { return !((script_t *)ctx)->cannot_save; }

static void s_discard(void *ctx)
{
    script_t *s = ctx;
    s->discards++;
    s->has_staged = false;
}

static const co_storage_t k_storage = {.begin = s_begin,
                                       .write = s_write,
                                       .commit = s_commit,
                                       .read = s_read,
                                       .erase = s_erase,
                                       .ctx = &g_s,
                                       .can_save = s_can_save,
                                       .discard = s_discard,
                                       .stage = s_stage};

static void power_on(test_node_t *t)
{
    CHECK_EQ(test_node_init(t, 5, 0), CO_OK);
    t->node.cfg.storage = &k_storage;
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
}

/* Append one record (index, sub, value bytes) to the image of `group`, sealed anew. */
static void add_record(co_param_group_t group, uint16_t index, uint8_t sub, const uint8_t *v,
                       uint8_t len)
{
    uint8_t *p = &g_s.records[group][g_s.records_len[group]];
    co_put_u16(p, index);
    p[2] = sub;
    p[3] = len;
    memcpy(p + 4, v, len);
    g_s.records_len[group] += 4u + len;
    g_s.len[group] =
        store_image_seal(g_s.image[group], group, g_s.records[group], g_s.records_len[group]);
    g_s.stored[group] = true;
}

static void test_failing_storage_aborts_with_hardware_error(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    power_on(&t);
    g_s.fail_begin = true;
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(g_s.commits, 0);
    g_s.fail_begin = false;
    g_s.fail_write_at = 2; /* the second record */
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(g_s.commits, 0); /* a failed save is never committed */
    g_s.fail_erase = true;
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_HARDWARE);
    /* The command objects read as the capability afterwards, whatever happened. */
    CHECK_EQ(t.od.store[0], 1);
}

static void test_save_and_restore_by_group(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    power_on(&t);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK(g_s.stored[CO_PARAMS_COMMUNICATION] && !g_s.stored[CO_PARAMS_APPLICATION]);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK(g_s.stored[CO_PARAMS_APPLICATION]);
    CHECK_EQ(write_u32(&t, 0x1011, 3, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(g_s.erased[CO_PARAMS_APPLICATION], 1);
    CHECK_EQ(g_s.erased[CO_PARAMS_COMMUNICATION], 0);
    CHECK_EQ(write_u32(&t, 0x1011, 2, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(g_s.erased[CO_PARAMS_COMMUNICATION], 1);
    CHECK_EQ(g_s.erased[CO_PARAMS_APPLICATION], 1);
    /* The API: groups 1..3 only, and only with storage. */
    CHECK_EQ(co_storage_save(&t.node, 0), CO_ERR_ARG);
    CHECK_EQ(co_storage_save(&t.node, 4), CO_ERR_ARG);
    t.node.cfg.storage = NULL;
    CHECK_EQ(co_storage_save(&t.node, 1), CO_ERR_STATE);
    /* A signature of the wrong length is refused by the length check. */
    t.node.cfg.storage = &k_storage;
    CHECK_EQ(write_u16(&t, 0x1010, 1, 0x6173), CO_ABORT_LEN_LOW);
}

static void test_load_applies_only_valid_records(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    uint8_t u32[4];
    co_put_u32(u32, 0xCAFEu);
    add_record(CO_PARAMS_APPLICATION, 0x2000, 0, u32, 4); /* good */
    uint8_t big[2];
    co_put_u16(big, 500);
    add_record(CO_PARAMS_APPLICATION, 0x2001, 0, big, 2);   /* above 0x2001's limit of 100 */
    add_record(CO_PARAMS_APPLICATION, 0x1017, 0, big, 2);   /* not of this group */
    add_record(CO_PARAMS_APPLICATION, 0x2007, 0, u32, 3);   /* wrong length */
    add_record(CO_PARAMS_COMMUNICATION, 0x1000, 0, u32, 4); /* device type: not a parameter */
    add_record(CO_PARAMS_COMMUNICATION, 0x2007, 0, u32, 4); /* not of this group either */
    uint8_t hb[2];
    co_put_u16(hb, 300);
    add_record(CO_PARAMS_COMMUNICATION, 0x1017, 0, hb, 2); /* good */
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0xCAFEu);
    CHECK_EQ(t.od.app_i16, 0);
    CHECK_EQ(t.od.app_u32b, 0);
    CHECK(t.od.device_type != 0xCAFEu);
    CHECK_EQ(t.od.hb_period_ms, 300);
}

static void test_truncated_image_is_refused_whole(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    uint8_t u32[4];
    co_put_u32(u32, 0x1234u);
    add_record(CO_PARAMS_APPLICATION, 0x2007, 0, u32, 4);
    co_put_u32(u32, 0xBEEFu);
    add_record(CO_PARAMS_APPLICATION, 0x2000, 0, u32, 4);
    g_s.len[CO_PARAMS_APPLICATION] -= 2; /* power cut in the middle of the last value */
    power_on(&t);
    CHECK_EQ(t.od.app_u32b, 0); /* the whole record before the cut is not applied either */
    CHECK_EQ(t.od.app_u32, 0x12345678u);
    CHECK(co_emcy_active(&t.node, 0xFF12));
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_APPLICATION), CO_STORE_BAD_LENGTH);
}

/* A storage that fails to read: while checking, or while applying what it checked. Either
 * way the group ends with its defaults, none of the records. */
static void test_read_error_refuses_the_image(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    uint8_t u32[4];
    co_put_u32(u32, 0x1234u);
    add_record(CO_PARAMS_APPLICATION, 0x2007, 0, u32, 4);
    co_put_u32(u32, 0xBEEFu);
    add_record(CO_PARAMS_APPLICATION, 0x2000, 0, u32, 4);
    g_s.fail_read_at = 2; /* the first chunk of records */
    power_on(&t);
    CHECK_EQ(t.od.app_u32b, 0);
    CHECK(co_emcy_active(&t.node, 0xFF12));
    /* Checking reads the header, one chunk and the byte after: 3 reads. Applying reads
     * the header (4), the first record (5, 6), the second record's head (7). */
    g_s.reads = 0;
    g_s.fail_read_at = 7;
    power_on(&t);
    CHECK_EQ(g_s.reads, 7);
    CHECK_EQ(t.od.app_u32b, 0); /* applied, then the defaults again */
    CHECK_EQ(t.od.app_u32, 0x12345678u);
    CHECK(co_emcy_active(&t.node, 0xFF12));
    CHECK_EQ(t.error_count, 1);
    /* the same image read without failure loads */
    g_s.fail_read_at = 0;
    power_on(&t);
    CHECK_EQ(t.od.app_u32b, 0x1234u);
    CHECK_EQ(t.od.app_u32, 0xBEEFu);
    CHECK_EQ(t.error_count, 0);
}

/* A failed save leaves nothing half-written: the storage hears discard, never commit. */
static void test_failed_write_discards_the_save(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    power_on(&t);
    g_s.fail_write_at = 3;
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(g_s.discards, 1);
    CHECK_EQ(g_s.commits, 0);
}

/* 0x1010/0x1011 read what the storage can do now: 0 while it cannot save (a read-only
 * folder), 1 again once it can; a command is still tried while they read 0. */
static void test_capability_follows_the_storage(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    g_s.cannot_save = true;
    power_on(&t);
    uint64_t v = 9;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1010, 1, &v), CO_OK);
    CHECK_EQ(v, 0);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1011, 2, &v), CO_OK);
    CHECK_EQ(v, 0);
    g_s.cannot_save = false;
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1010, 1, &v), CO_OK);
    CHECK_EQ(v, 1);
    CHECK_EQ(co_node_get_uint(&t.node, 0x1010, 3, &v), CO_OK);
    CHECK_EQ(v, 1);
    /* the storage fails and says it cannot save any more: every sub-index follows */
    g_s.cannot_save = true;
    g_s.fail_begin = true;
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    for (uint8_t sub = 1; sub <= 3; sub++) {
        CHECK_EQ(co_node_get_uint(&t.node, 0x1010, sub, &v), CO_OK);
        CHECK_EQ(v, 0);
        CHECK_EQ(co_node_get_uint(&t.node, 0x1011, sub, &v), CO_OK);
        CHECK_EQ(v, 0);
    }
}

/* Saved: 0x1017 = 777 (communication) and 0x2000 = 0xCAFE (application); then new values
 * 888 and 0xBEEF are set, not saved. */
static void saved_then_changed(test_node_t *t)
{
    memset(&g_s, 0, sizeof g_s);
    power_on(t);
    co_node_set_uint(&t->node, 0x1017, 0, 777);
    co_node_set_uint(&t->node, 0x2000, 0, 0xCAFE);
    CHECK_EQ(write_u32(t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    co_node_set_uint(&t->node, 0x1017, 0, 888);
    co_node_set_uint(&t->node, 0x2000, 0, 0xBEEF);
    g_s.commits = 0;
    g_s.stages = 0;
    g_s.writes = 0;
}

/* Which values a fresh start finds: 'o' old, 'n' new, per group (communication first). */
static void check_loaded(test_node_t *t, const char *want)
{
    power_on(t);
    CHECK_EQ(t->od.hb_period_ms, want[0] == 'n' ? 888 : 777);
    CHECK_EQ(t->od.app_u32, want[1] == 'n' ? 0xBEEFu : 0xCAFEu);
}

/* A save of both groups that fails in the application group leaves both groups old: the
 * communication image was staged, never committed on its own. (Before: the communication
 * group was committed first, so a failure after it left communication new, application
 * old.) The same failure at each write of the save. */
static void test_save_of_both_groups_is_one_step(void)
{
    static test_node_t t;
    saved_then_changed(&t);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    int writes = g_s.writes; /* of a whole save of both groups */
    CHECK_EQ(g_s.commits, 1);
    CHECK_EQ(g_s.stages, 1);
    check_loaded(&t, "nn");
    for (int at = 1; at <= writes; at++) {
        saved_then_changed(&t);
        g_s.fail_write_at = at;
        CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
        CHECK_EQ(g_s.commits, 0);
        CHECK(!g_s.has_staged); /* discarded with the rest */
        g_s.fail_write_at = 0;
        check_loaded(&t, "oo");
    }
}

/* A storage without `stage` saves each group whole, one after the other: the documented
 * per-group guarantee. */
static void test_storage_without_stage_commits_each_group(void)
{
    static test_node_t t;
    saved_then_changed(&t);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    int comm_writes = g_s.writes;
    saved_then_changed(&t);
    static co_storage_t per_group; /* the same storage without `stage`: a group at a time */
    per_group = k_storage;
    per_group.stage = NULL;
    t.node.cfg.storage = &per_group;
    g_s.fail_write_at = comm_writes + 2; /* in the application group, after a commit */
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(g_s.commits, 1);
    CHECK_EQ(g_s.stages, 0);
    g_s.fail_write_at = 0;
    check_loaded(&t, "no");
}

/* The EMCY of a failed store: 0x5530 with the command's sub-index and object, and
 * on_error; a later command that succeeds ends it. A failed restore raises it too. */
static void test_failed_store_raises_emcy_5530(void)
{
    static test_node_t t;
    memset(&g_s, 0, sizeof g_s);
    power_on(&t);
    fake_clear(&t.bus);
    g_s.fail_begin = true;
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK(co_emcy_active(&t.node, CO_EMCY_STORE_FAILED));
    char dump[256];
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "085#3055010310000000");
    CHECK_EQ(t.error_count, 1);
    CHECK_EQ(t.errors[0], CO_NODE_ERR_STORE_FAILED);
    uint64_t history = 0;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1003, 1, &history), CO_OK);
    CHECK_EQ(history & 0xFFFFu, 0x5530u);
    /* the wrong signature is no storage failure: 0x08000020, no EMCY */
    fake_clear(&t.bus);
    CHECK_EQ(write_u32(&t, 0x1010, 1, 0x12345678u), CO_ABORT_DATA_STORE);
    CHECK_EQ(t.bus.count, 0);
    /* a save that works ends the error (EMCY error reset) */
    g_s.fail_begin = false;
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK(!co_emcy_active(&t.node, CO_EMCY_STORE_FAILED));
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "085#0000000000000000");
    /* a restore that fails: the same code, 0x1011 in byte 4 */
    fake_clear(&t.bus);
    g_s.fail_erase = true;
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "085#3055010111000000");
    /* the API reports its failures the same way */
    g_s.fail_erase = false;
    g_s.fail_begin = true;
    CHECK_EQ(co_storage_save(&t.node, 1), CO_ERR_STATE);
    CHECK(co_emcy_active(&t.node, CO_EMCY_STORE_FAILED));
    CHECK(t.error_count > 0 && t.errors[t.error_count - 1] == CO_NODE_ERR_STORE_FAILED);
}

int main(void)
{
    RUN(test_failing_storage_aborts_with_hardware_error);
    RUN(test_save_and_restore_by_group);
    RUN(test_load_applies_only_valid_records);
    RUN(test_truncated_image_is_refused_whole);
    RUN(test_read_error_refuses_the_image);
    RUN(test_failed_write_discards_the_save);
    RUN(test_capability_follows_the_storage);
    RUN(test_save_of_both_groups_is_one_step);
    RUN(test_storage_without_stage_commits_each_group);
    RUN(test_failed_store_raises_emcy_5530);
    return check_summary();
}
