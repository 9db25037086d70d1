/* SPDX-License-Identifier: Apache-2.0 */
/* example_od.c -- see example_od.h. */
#include "example_od.h"

#include <string.h>

_Static_assert(EXAMPLE_OD_HASH_SLOTS >= 2 * EXAMPLE_OD_MAX_ENTRIES,
               "room for co_od_hash_bits(EXAMPLE_OD_MAX_ENTRIES)");

/* Power-on values live in const data; reset copies them into the values. */
static const uint32_t k_device_type = 0x00000191u; /* CiA 401-like generic I/O */
static const uint8_t k_zero_u8 = 0;
static const uint16_t k_zero_u16 = 0;
static const uint32_t k_zero_u32 = 0;
static const uint32_t k_emcy_cob_id = 0x80; /* + $NODEID */
static const uint32_t k_sync_cob_id = 0x80;
static const uint32_t k_time_cob_id = 0x80000100u; /* consumes TIME */
static const uint32_t k_cob_unused = 0x80000000u;
static const uint8_t k_emcy_consumer_count = EXAMPLE_EMCY_CONSUMERS;
static const uint8_t k_hb_consumer_count = EXAMPLE_HB_CONSUMERS;
static const uint8_t k_identity_count = 4;
static const uint32_t k_identity[4] = {0x00000CA0u, 0x00000001u, 0x00010000u, 0x00000000u};
static const uint8_t k_one_u8 = 1;
static const uint8_t k_three_u8 = 3;
static const uint8_t k_five_u8 = 5;
static const uint8_t k_six_u8 = 6;
static const uint8_t k_type_event = 255;
static const uint32_t k_rpdo_cob[EXAMPLE_PDOS] = {0x200, 0x300, 0x400, 0x500}; /* + $NODEID */
static const uint32_t k_tpdo_cob[EXAMPLE_PDOS] = {0x180, 0x280, 0x380, 0x480}; /* + $NODEID */
static const uint8_t k_rpdo_map_count[EXAMPLE_PDOS] = {4, 0, 0, 0};
static const uint8_t k_tpdo_map_count[EXAMPLE_PDOS] = {1, 0, 0, 0};
static const uint32_t k_rpdo1_map[EXAMPLE_PDO_ENTRIES] = {0x62000108, 0x62000208, 0x62000308,
                                                          0x62000408};
static const uint32_t k_tpdo1_map[EXAMPLE_PDO_ENTRIES] = {0x20000020};
static const uint32_t k_app_u32 = 0x12345678u;
static const int16_t k_app_i16 = 0;
static const char k_app_string[16] = "hello";
static const int64_t k_zero_i64 = 0;
static const float k_zero_real = 0.0f;
static const uint8_t k_outputs_count = 4;
static const char k_device_name[16] = "canola example";
static const co_od_limits_t k_i16_limits = {.low = {.i = -100}, .high = {.i = 100}};

static void add(example_od_t *x, uint32_t *n, co_od_entry_t e)
{
    if (*n < EXAMPLE_OD_MAX_ENTRIES) {
        x->entries[(*n)++] = e;
    }
}

#define VAR(idx, s, t, a, sz, val, def)                                                            \
    (co_od_entry_t)                                                                                \
    {                                                                                              \
        .index = (idx), .sub = (s), .type = (t), .attr = (a), .size = (sz), .value = (val),        \
        .dflt = (def)                                                                              \
    }

/* A PDO communication record: sub0, 1, 2, [3], 5, [6] (3 and 6 for TPDOs). */
static void add_pdo_comm(example_od_t *x, uint32_t *n, struct example_pdo *p, uint16_t index,
                         bool tpdo, const uint32_t *cob)
{
    add(x, n,
        VAR(index, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &p->comm_count,
            tpdo ? &k_six_u8 : &k_five_u8));
    add(x, n, VAR(index, 1, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_NODEID, 4, &p->cob_id, cob));
    add(x, n, VAR(index, 2, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &p->type, &k_type_event));
    if (tpdo) {
        add(x, n, VAR(index, 3, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &p->inhibit, &k_zero_u16));
    }
    add(x, n, VAR(index, 5, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &p->event_ms, &k_zero_u16));
    if (tpdo) {
        add(x, n, VAR(index, 6, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &p->sync_start, &k_zero_u8));
    }
}

/* A PDO mapping record: sub0 and EXAMPLE_PDO_ENTRIES entries. */
static void add_pdo_map(example_od_t *x, uint32_t *n, struct example_pdo *p, uint16_t index,
                        const uint8_t *count, const uint32_t *defaults)
{
    add(x, n, VAR(index, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &p->map_count, count));
    for (uint8_t i = 0; i < EXAMPLE_PDO_ENTRIES; i++) {
        add(x, n,
            VAR(index, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &p->map[i],
                defaults ? &defaults[i] : &k_zero_u32));
    }
}

co_od_t example_od_init(example_od_t *x, uint16_t hb_period_ms)
{
    memset(x, 0, sizeof *x);
    x->hb_period_default = hb_period_ms;
    x->app_domain.data = x->domain_buf;
    uint32_t n = 0;
    add(x, &n, VAR(0x1000, 0, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &x->device_type, &k_device_type));
    add(x, &n,
        VAR(0x1001, 0, CO_TYPE_UNSIGNED8, CO_OD_RO | CO_OD_TPDO, 1, &x->error_register,
            &k_zero_u8));
    add(x, &n, VAR(0x1003, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &x->error_count, &k_zero_u8));
    for (uint8_t i = 0; i < EXAMPLE_EMCY_HISTORY; i++) {
        add(x, &n,
            VAR(0x1003, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &x->error_history[i],
                &k_zero_u32));
    }
    add(x, &n, VAR(0x1005, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->sync_cob_id, &k_sync_cob_id));
    add(x, &n, VAR(0x1006, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->sync_period_us, &k_zero_u32));
    add(x, &n, VAR(0x1007, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->sync_window_us, &k_zero_u32));
    add(x, &n, VAR(0x1008, 0, CO_TYPE_VISIBLE_STRING, CO_OD_CO, 16, x->device_name, k_device_name));
    add(x, &n, VAR(0x100C, 0, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &x->guard_time_ms, &k_zero_u16));
    add(x, &n, VAR(0x100D, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &x->life_factor, &k_zero_u8));
    add(x, &n, VAR(0x1010, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->store_count, &k_three_u8));
    for (uint8_t i = 0; i < 3; i++) {
        add(x, &n,
            VAR(0x1010, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->store[i],
                &k_zero_u32));
    }
    add(x, &n, VAR(0x1011, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->restore_count, &k_three_u8));
    for (uint8_t i = 0; i < 3; i++) {
        add(x, &n,
            VAR(0x1011, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->restore[i],
                &k_zero_u32));
    }
    add(x, &n, VAR(0x1012, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->time_cob_id, &k_time_cob_id));
    add(x, &n,
        VAR(0x1014, 0, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_NODEID, 4, &x->emcy_cob_id,
            &k_emcy_cob_id));
    add(x, &n, VAR(0x1015, 0, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &x->emcy_inhibit, &k_zero_u16));
    add(x, &n,
        VAR(0x1016, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->hb_consumer_count,
            &k_hb_consumer_count));
    for (uint8_t i = 0; i < EXAMPLE_HB_CONSUMERS; i++) {
        add(x, &n,
            VAR(0x1016, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->hb_consumer[i],
                &k_zero_u32));
    }
    /* The power-on value of 0x1017 is per instance here, so it lives in RAM. */
    add(x, &n,
        VAR(0x1017, 0, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &x->hb_period_ms, &x->hb_period_default));
    add(x, &n,
        VAR(0x1018, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->identity_count, &k_identity_count));
    for (uint8_t i = 0; i < 4; i++) {
        add(x, &n,
            VAR(0x1018, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &x->identity[i],
                &k_identity[i]));
    }
    add(x, &n, VAR(0x1019, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &x->sync_overflow, &k_zero_u8));
    add(x, &n,
        VAR(0x1028, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->emcy_consumer_count,
            &k_emcy_consumer_count));
    for (uint8_t i = 0; i < EXAMPLE_EMCY_CONSUMERS; i++) {
        add(x, &n,
            VAR(0x1028, (uint8_t)(i + 1), CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &x->emcy_consumer[i],
                &k_cob_unused));
    }
    add(x, &n, VAR(0x1029, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->eb_count, &k_one_u8));
    add(x, &n, VAR(0x1029, 1, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &x->eb_comm, &k_zero_u8));
    /* PDOs, in index order: 0x1400.., 0x1600.., 0x1800.., 0x1A00.. */
    for (uint8_t i = 0; i < EXAMPLE_PDOS; i++) {
        add_pdo_comm(x, &n, &x->rpdo[i], (uint16_t)(0x1400 + i), false, &k_rpdo_cob[i]);
    }
    for (uint8_t i = 0; i < EXAMPLE_PDOS; i++) {
        add_pdo_map(x, &n, &x->rpdo[i], (uint16_t)(0x1600 + i), &k_rpdo_map_count[i],
                    i == 0 ? k_rpdo1_map : NULL);
    }
    for (uint8_t i = 0; i < EXAMPLE_PDOS; i++) {
        add_pdo_comm(x, &n, &x->tpdo[i], (uint16_t)(0x1800 + i), true, &k_tpdo_cob[i]);
    }
    for (uint8_t i = 0; i < EXAMPLE_PDOS; i++) {
        add_pdo_map(x, &n, &x->tpdo[i], (uint16_t)(0x1A00 + i), &k_tpdo_map_count[i],
                    i == 0 ? k_tpdo1_map : NULL);
    }
    add(x, &n,
        VAR(0x2000, 0, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_TPDO | CO_OD_RPDO, 4, &x->app_u32,
            &k_app_u32));
    co_od_entry_t i16 = VAR(0x2001, 0, CO_TYPE_INTEGER16, CO_OD_RW, 2, &x->app_i16, &k_app_i16);
    i16.limits = &k_i16_limits;
    add(x, &n, i16);
    add(x, &n, VAR(0x2002, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, 16, x->app_string, k_app_string));
    add(x, &n, VAR(0x2003, 0, CO_TYPE_DOMAIN, CO_OD_RW, EXAMPLE_DOMAIN_CAP, &x->app_domain, NULL));
    add(x, &n, VAR(0x2004, 0, CO_TYPE_UNSIGNED8, CO_OD_WO, 1, &x->app_wo, &k_zero_u8));
    add(x, &n, VAR(0x2005, 0, CO_TYPE_INTEGER64, CO_OD_RW, 8, &x->app_i64, &k_zero_i64));
    add(x, &n, VAR(0x2006, 0, CO_TYPE_REAL32, CO_OD_RW, 4, &x->app_real, &k_zero_real));
    add(x, &n,
        VAR(0x2007, 0, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_TPDO | CO_OD_RPDO, 4, &x->app_u32b,
            &k_zero_u32));
    add(x, &n, VAR(0x6200, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &x->outputs_count, &k_outputs_count));
    for (uint8_t i = 0; i < 4; i++) {
        add(x, &n,
            VAR(0x6200, (uint8_t)(i + 1), CO_TYPE_UNSIGNED8, CO_OD_RWW | CO_OD_RPDO, 1,
                &x->outputs[i], &k_zero_u8));
    }
    /* Values start at their defaults, as after a power-on reset. */
    co_od_t od = {.entries = x->entries, .count = n, .hook_ctx = NULL};
    co_od_reset(&od, 0x1000, 0xFFFF, 0);
    return od;
}

co_od_t example_od_keyed(example_od_t *x, co_od_t od)
{
    for (uint32_t i = 0; i < od.count; i++) {
        x->keys[i] = CO_OD_KEY(od.entries[i].index, od.entries[i].sub);
    }
    od.keys = x->keys;
    (void)co_od_hash_build(&od, x->hash, co_od_hash_bits(od.count)); /* 512 slots: it fits */
    return od;
}
