/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_cm_flash_storage.c -- port/cortex-m's stored parameters on flash (two slots written
 * in turn), on the flash model of flash_model.h in the geometries of the families it
 * serves: saves and restores survive power-ons, and a power cut at every operation of a
 * save or restore, in every partial state, leaves each group's previous image or its new
 * one, whole, never a rejected image.
 */
#include "canola/cm_flash_storage.h"
#include "check.h"
#include "flash_model.h"
#include "harness.h"

typedef struct geometry {
    const char *name;
    uint32_t page_size;
    uint8_t unit;
    uint32_t pages_per_slot;
} geometry_t;

static const geometry_t k_geometries[] = {
    {"nRF51: 1 KB pages, 4-byte words", 1024, 4, 2},
    {"STM32F0/F1/F3: 1 KB pages, half-words", 1024, 2, 2},
    {"STM32L4/G0/G4: 2 KB pages, double words", 2048, 8, 1},
    {"STM32F4: a 16 KB sector per slot, words", 16384, 4, 1},
    {"STM32H7: 32-byte flash words (2 KB of a sector)", 2048, 32, 1},
};

/* The flash: a page of something else between the two slots, as a real layout may have. */
static uint8_t g_mem[16384 * 3] __attribute__((aligned(16384)));
static uint8_t g_snapshot[sizeof g_mem];
static flash_model_t g_flash;
static co_cm_flash_storage_t g_store;
static const geometry_t *g_geo;

static uint32_t slot_size(void) { return g_geo->page_size * g_geo->pages_per_slot; }

static void blank_flash(const geometry_t *geo)
{
    g_geo = geo;
    uint32_t size = slot_size();
    flash_model_init(&g_flash, g_mem, 2 * size + geo->page_size, geo->page_size, geo->unit);
    g_flash.slots[0] = (uintptr_t)g_mem;
    g_flash.slots[1] = (uintptr_t)g_mem + size + geo->page_size;
}

/* A power-on of the device: the power back, the storage found anew, the node started with
 * fresh values (the example's defaults: 0x1017 = 100, 0x2000 = 0x12345678). */
static void power_on(test_node_t *t)
{
    flash_power_on(&g_flash);
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &g_flash.api, g_flash.slots[0], g_flash.slots[1],
                                      slot_size()),
             CO_OK);
    CHECK_EQ(test_node_init(t, 5, 100), CO_OK);
    t->node.cfg.storage = &g_store.api;
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
}

/* The values of each group a test sets: 0x1017 (communication), 0x2000 (application). */
enum { DEFAULTS, FIRST, SECOND, OTHER };
static const uint16_t k_hb[] = {100, 250, 333};
static const uint32_t k_app[] = {0x12345678, 0xCAFE, 0xBEEF};

static void set_values(test_node_t *t, int which)
{
    CHECK_EQ(co_node_set_uint(&t->node, 0x1017, 0, k_hb[which]), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&t->node, 0x2000, 0, k_app[which]), CO_ABORT_NONE);
}

static int comm_values(const test_node_t *t)
{
    for (int v = DEFAULTS; v <= SECOND; v++) {
        if (t->od.hb_period_ms == k_hb[v]) {
            return v;
        }
    }
    return OTHER;
}

static int app_values(const test_node_t *t)
{
    for (int v = DEFAULTS; v <= SECOND; v++) {
        if (t->od.app_u32 == k_app[v]) {
            return v;
        }
    }
    return OTHER;
}

static co_abort_t command(test_node_t *t, bool restore)
{
    return write_u32(t, restore ? 0x1011 : 0x1010, 1,
                     restore ? CO_RESTORE_SIGNATURE : CO_STORE_SIGNATURE);
}

static void test_geometry_refused(void)
{
    blank_flash(&k_geometries[0]);
    co_cm_flash_t flash = g_flash.api;
    uintptr_t a = g_flash.slots[0];
    uintptr_t b = g_flash.slots[1];
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, b, 2048), CO_OK);
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, a + 1024, 2048),
             CO_ERR_ARG);                                                         /* overlap */
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, b, 1536), CO_ERR_ARG); /* half a page */
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a + 4, b, 2048),
             CO_ERR_ARG); /* unaligned */
    flash.unit = 3;
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, b, 2048), CO_ERR_ARG);
    flash.unit = 64;
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, b, 2048), CO_ERR_ARG);
    flash.unit = 4;
    flash.page_size = 32;
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, a + 64, 64), CO_ERR_ARG); /* no room */
    flash.program = NULL;
    CHECK_EQ(co_cm_flash_storage_init(&g_store, &flash, a, b, 2048), CO_ERR_ARG);
}

static void test_blank_flash_holds_nothing(void)
{
    static test_node_t t;
    blank_flash(&k_geometries[0]);
    power_on(&t);
    CHECK_EQ(comm_values(&t), DEFAULTS);
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_COMMUNICATION), CO_STORE_NONE);
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_APPLICATION), CO_STORE_NONE);
    CHECK_EQ(t.error_count, 0);
    /* forgetting what is not stored writes nothing */
    CHECK_EQ(command(&t, true), CO_ABORT_NONE);
    CHECK_EQ(g_flash.ops, 0);
}

/* Saves, one group and both, restore, and many saves in turn: each power-on finds the
 * last of them, every unit programmed once per erase. */
static void saves_and_restores(const geometry_t *geo)
{
    static test_node_t t;
    blank_flash(geo);
    power_on(&t);
    set_values(&t, FIRST);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE); /* communication */
    power_on(&t);
    CHECK_EQ(comm_values(&t), FIRST);
    CHECK_EQ(app_values(&t), DEFAULTS);
    set_values(&t, SECOND);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE); /* application */
    power_on(&t);
    CHECK_EQ(comm_values(&t), FIRST); /* copied over into the new slot */
    CHECK_EQ(app_values(&t), SECOND);
    CHECK_EQ(write_u32(&t, 0x1011, 2, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(comm_values(&t), DEFAULTS);
    CHECK_EQ(app_values(&t), SECOND);
    for (int i = 0; i < 20; i++) {
        set_values(&t, i % 2 ? FIRST : SECOND);
        CHECK_EQ(command(&t, false), CO_ABORT_NONE);
    }
    power_on(&t);
    CHECK_EQ(comm_values(&t), FIRST);
    CHECK_EQ(app_values(&t), FIRST);
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_COMMUNICATION), CO_STORE_INTACT);
    CHECK_EQ(co_storage_verify(&t.node, CO_PARAMS_APPLICATION), CO_STORE_INTACT);
    CHECK_EQ(t.error_count, 0);
    CHECK_EQ(g_flash.misuse, 0);
}

static void test_saves_and_restores(void)
{
    for (size_t i = 0; i < sizeof k_geometries / sizeof k_geometries[0]; i++) {
        printf("  %s\n", k_geometries[i].name);
        saves_and_restores(&k_geometries[i]);
    }
}

/* A power cut at every operation of a save of both groups (or of a restore of both), in
 * each partial state: at the next power-on each group has its old values or its new ones,
 * the new exactly when the cut came after the commit unit of its slot was programmed whole
 * (a save: both groups in one slot, so both old or both new); no image is refused (the
 * slot in use is always a whole one). */
static void cut_every_step(const geometry_t *geo, bool restore)
{
    static test_node_t t;
    blank_flash(geo);
    power_on(&t);
    set_values(&t, FIRST);
    CHECK_EQ(command(&t, false), CO_ABORT_NONE);
    memcpy(g_snapshot, g_mem, sizeof g_mem);
    int fresh = restore ? DEFAULTS : SECOND;

    /* The whole command once, to count its operations and find the two commits. */
    power_on(&t);
    set_values(&t, SECOND);
    g_flash.ops = 0;
    g_flash.commits = 0;
    CHECK_EQ(command(&t, restore), CO_ABORT_NONE);
    uint32_t steps = g_flash.ops;
    /* a save of both groups is one new slot (stage); a restore forgets one group a slot */
    uint32_t commits = g_flash.commits;
    CHECK_EQ(commits, restore ? 2 : 1);
    uint32_t comm_commit = g_flash.commit_ops[0];
    uint32_t app_commit = g_flash.commit_ops[commits - 1];

    uint32_t cases = 0;
    uint32_t right = 0;
    for (uint32_t cut = 0; cut < steps; cut++) {
        for (flash_cut_t how = FLASH_CUT_BEFORE; how <= FLASH_CUT_SCATTER; how++) {
            memcpy(g_mem, g_snapshot, sizeof g_mem);
            power_on(&t);
            set_values(&t, SECOND);
            g_flash.ops = 0;
            g_flash.cut_at = cut;
            g_flash.cut = how;
            co_abort_t abort = command(&t, restore);
            power_on(&t);
            int comm = cut > comm_commit ? fresh : FIRST;
            int app = cut > app_commit ? fresh : FIRST;
            bool ok = abort == CO_ABORT_HARDWARE && comm_values(&t) == comm &&
                      app_values(&t) == app && t.error_count == 0 &&
                      co_storage_verify(&t.node, CO_PARAMS_COMMUNICATION) ==
                          (comm == DEFAULTS ? CO_STORE_NONE : CO_STORE_INTACT) &&
                      co_storage_verify(&t.node, CO_PARAMS_APPLICATION) ==
                          (app == DEFAULTS ? CO_STORE_NONE : CO_STORE_INTACT);
            if (!ok) {
                printf("  %s, %s: cut at operation %u of %u (%d): abort 0x%08x, "
                       "communication %d (want %d), application %d (want %d), errors %u\n",
                       geo->name, restore ? "restore" : "save", (unsigned)cut, (unsigned)steps,
                       (int)how, (unsigned)abort, comm_values(&t), comm, app_values(&t), app,
                       (unsigned)t.error_count);
            }
            cases++;
            right += ok;
        }
    }
    CHECK_EQ(right, cases);
    CHECK(cases >= 3 * 6); /* erases, image units, headers and commits were all cut */
    CHECK_EQ(g_flash.misuse, 0);
}

static void test_power_cut_at_every_step_of_a_save(void)
{
    for (size_t i = 0; i < sizeof k_geometries / sizeof k_geometries[0]; i++) {
        cut_every_step(&k_geometries[i], false);
    }
}

static void test_power_cut_at_every_step_of_a_restore(void)
{
    for (size_t i = 0; i < sizeof k_geometries / sizeof k_geometries[0]; i++) {
        cut_every_step(&k_geometries[i], true);
    }
}

/* The controller reports an error (power kept) at each operation in turn: the command is
 * refused with 0x06060000, the old values stay, and the next save works. */
static void test_controller_error_keeps_the_old_image(void)
{
    static test_node_t t;
    blank_flash(&k_geometries[2]);
    power_on(&t);
    set_values(&t, FIRST);
    CHECK_EQ(command(&t, false), CO_ABORT_NONE);
    g_flash.ops = 0;
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    uint32_t steps = g_flash.ops;
    for (uint32_t fail = 0; fail < steps; fail++) {
        power_on(&t);
        set_values(&t, SECOND);
        g_flash.ops = 0;
        g_flash.fail_at = fail;
        CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
        power_on(&t);
        CHECK_EQ(app_values(&t), FIRST);
        CHECK_EQ(t.error_count, 0);
    }
    set_values(&t, SECOND);
    CHECK_EQ(command(&t, false), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(app_values(&t), SECOND);
    CHECK_EQ(g_flash.misuse, 0);
}

/* An image that does not fit the slot (with the other group's) is refused: the old stays. */
static void test_image_too_large_for_the_slot(void)
{
    /* 192 bytes for the images: the example's application image (88 bytes) fits, its
     * communication image (897 bytes) does not */
    static const geometry_t tiny = {"256-byte pages", 256, 4, 1};
    static test_node_t t;
    blank_flash(&tiny);
    power_on(&t);
    set_values(&t, FIRST);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    power_on(&t);
    CHECK_EQ(app_values(&t), FIRST);
    CHECK_EQ(comm_values(&t), DEFAULTS);
    CHECK_EQ(t.error_count, 0);

    /* 960 bytes: the communication image fits alone, not with the application's after it;
     * a save of both is refused whole */
    static const geometry_t snug = {"1 KB pages, one a slot", 1024, 4, 1};
    blank_flash(&snug);
    power_on(&t);
    set_values(&t, FIRST);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    set_values(&t, SECOND);
    CHECK_EQ(command(&t, false), CO_ABORT_HARDWARE);
    power_on(&t);
    CHECK_EQ(comm_values(&t), FIRST);
    CHECK_EQ(app_values(&t), DEFAULTS);
    CHECK_EQ(t.error_count, 0);
    CHECK_EQ(g_flash.misuse, 0);
}

/* The sequence number wraps: the slot written after 0xFFFFFFFF (number 0) is the later. */
static void test_sequence_wraps(void)
{
    static test_node_t t;
    blank_flash(&k_geometries[0]);
    power_on(&t);
    g_store.seq = 0xFFFFFFFEu;
    set_values(&t, FIRST);
    CHECK_EQ(command(&t, false), CO_ABORT_NONE); /* both groups: slot number 0xFFFFFFFF */
    set_values(&t, SECOND);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE); /* number 0 */
    power_on(&t);
    CHECK_EQ(g_store.seq, 0);
    CHECK_EQ(comm_values(&t), SECOND);
    CHECK_EQ(app_values(&t), FIRST);
}

int main(void)
{
    RUN(test_geometry_refused);
    RUN(test_blank_flash_holds_nothing);
    RUN(test_saves_and_restores);
    RUN(test_power_cut_at_every_step_of_a_save);
    RUN(test_power_cut_at_every_step_of_a_restore);
    RUN(test_controller_error_keeps_the_old_image);
    RUN(test_image_too_large_for_the_slot);
    RUN(test_sequence_wraps);
    return check_summary();
}
