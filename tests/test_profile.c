/* SPDX-License-Identifier: Apache-2.0 */
/* test_profile.c -- a device built in one of the bench's size profiles (configs/minimal.h
 * or configs/default.h, the core compiled in that configuration: tests/CMakeLists.txt builds
 * this file once per profile) on the simulated bus, seen from a raw port: it boots, answers
 * expedited SDO, sends and takes its PDOs, takes SYNC, sends EMCY and heartbeats; and what
 * the profile leaves out (canola/config.h's switches) is shown to be left out as documented,
 * what it keeps to work. The dictionary is built here: both profiles leave out the types
 * wider than 32 bits, which the example dictionary has. */
#include "canola/sim.h"
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define ID 5

/* The profile's features, from the configuration the core was built with. */
#define HAS_HB_CONSUMER (CO_HB_CONSUMERS_MAX > 0)
#define HAS_EMCY_INHIBIT (CO_EMCY_QUEUE_LEN > 0)

typedef struct dict {
    uint32_t device_type, sync_cob, sync_period, emcy_cob, hb_cons[1], history[2], vendor, save;
    uint8_t reg, save_count, history_count, hb_cons_count, id_count, rpdo_comm_n[2], tpdo_comm_n[2];
    uint16_t emcy_inhibit, hb_ms;
    char name[16];
    struct {
        uint32_t cob;
        uint8_t type;
        uint16_t inhibit, event_ms;
        uint8_t map_n;
        uint32_t map[2];
    } rpdo[2], tpdo[2];
    uint32_t out_u32; /* 0x2000: TPDO1 */
    uint16_t out_u16; /* 0x2001: TPDO2 */
    uint32_t in_u32;  /* 0x2100: RPDO1 */
    uint16_t in_u16;  /* 0x2100: RPDO1 */
    uint8_t in_u8;    /* 0x2102: RPDO2, 4 bits of it */
    co_od_entry_t e[64];
    uint32_t n;
} dict_t;

static const uint32_t k_sync_cob = 0x80, k_emcy_cob = 0x80, k_rpdo_cob[2] = {0x200, 0x300},
                      k_tpdo_cob[2] = {0x180, 0x280}, k_zero32 = 0, k_one32 = 1, k_vendor = 0xCA0;
static const uint32_t k_rpdo_map[2][2] = {{0x21000020, 0x21010010}, {0x21020004, 0}};
static const uint32_t k_tpdo_map[2][2] = {{0x20000020, 0}, {0x20010010, 0}};
static const uint8_t k_zero8 = 0, k_one8 = 1, k_five8 = 5, k_six8 = 6, k_type_sync = 1,
                     k_type_event = 255, k_rpdo_map_n[2] = {2, 1};
static const uint16_t k_zero16 = 0, k_hb_ms = 100, k_event_ms = 10;
static const char k_name[16] = "canola profile";

static void put(dict_t *d, uint16_t index, uint8_t sub, uint8_t type, uint8_t attr, void *value,
                const void *dflt)
{
    d->e[d->n++] = (co_od_entry_t){
        .index = index,
        .sub = sub,
        .type = type,
        .attr = attr,
        .size = type == CO_TYPE_VISIBLE_STRING ? 16u : co_type_size((co_type_t)type),
        .value = value,
        .dflt = dflt};
}

#define U8 CO_TYPE_UNSIGNED8
#define U16 CO_TYPE_UNSIGNED16
#define U32 CO_TYPE_UNSIGNED32

static co_od_t dict_init(dict_t *d)
{
    memset(d, 0, sizeof *d);
    put(d, 0x1000, 0, U32, CO_OD_RO, &d->device_type, &k_zero32);
    put(d, 0x1001, 0, U8, CO_OD_RO, &d->reg, &k_zero8);
    put(d, 0x1003, 0, U8, CO_OD_RW, &d->history_count, &k_zero8);
    put(d, 0x1003, 1, U32, CO_OD_RO, &d->history[0], &k_zero32);
    put(d, 0x1003, 2, U32, CO_OD_RO, &d->history[1], &k_zero32);
    put(d, 0x1005, 0, U32, CO_OD_RW, &d->sync_cob, &k_sync_cob);
    put(d, 0x1006, 0, U32, CO_OD_RW, &d->sync_period, &k_zero32);
    put(d, 0x1008, 0, CO_TYPE_VISIBLE_STRING, CO_OD_CO, d->name, k_name);
    put(d, 0x1010, 0, U8, CO_OD_CO, &d->save_count, &k_one8);
    put(d, 0x1010, 1, U32, CO_OD_RW, &d->save, &k_one32); /* "saves on command" */
    put(d, 0x1014, 0, U32, CO_OD_RW | CO_OD_NODEID, &d->emcy_cob, &k_emcy_cob);
    put(d, 0x1015, 0, U16, CO_OD_RW, &d->emcy_inhibit, &k_zero16);
    put(d, 0x1016, 0, U8, CO_OD_CO, &d->hb_cons_count, &k_one8);
    put(d, 0x1016, 1, U32, CO_OD_RW, &d->hb_cons[0], &k_zero32);
    put(d, 0x1017, 0, U16, CO_OD_RW, &d->hb_ms, &k_hb_ms);
    put(d, 0x1018, 0, U8, CO_OD_CO, &d->id_count, &k_one8);
    put(d, 0x1018, 1, U32, CO_OD_RO, &d->vendor, &k_vendor);
    for (uint8_t i = 0; i < 2; i++) {
        uint16_t c = (uint16_t)(0x1400 + i);
        put(d, c, 0, U8, CO_OD_CO, &d->rpdo_comm_n[i], &k_five8);
        put(d, c, 1, U32, CO_OD_RW | CO_OD_NODEID, &d->rpdo[i].cob, &k_rpdo_cob[i]);
        put(d, c, 2, U8, CO_OD_RW, &d->rpdo[i].type, &k_type_event);
        put(d, c, 5, U16, CO_OD_RW, &d->rpdo[i].event_ms, &k_zero16);
    }
    for (uint8_t i = 0; i < 2; i++) {
        uint16_t m = (uint16_t)(0x1600 + i);
        put(d, m, 0, U8, CO_OD_RW, &d->rpdo[i].map_n, &k_rpdo_map_n[i]);
        put(d, m, 1, U32, CO_OD_RW, &d->rpdo[i].map[0], &k_rpdo_map[i][0]);
        put(d, m, 2, U32, CO_OD_RW, &d->rpdo[i].map[1], &k_rpdo_map[i][1]);
    }
    for (uint8_t i = 0; i < 2; i++) {
        uint16_t c = (uint16_t)(0x1800 + i);
        put(d, c, 0, U8, CO_OD_CO, &d->tpdo_comm_n[i], &k_six8);
        put(d, c, 1, U32, CO_OD_RW | CO_OD_NODEID, &d->tpdo[i].cob, &k_tpdo_cob[i]);
        put(d, c, 2, U8, CO_OD_RW, &d->tpdo[i].type, i == 0 ? &k_type_sync : &k_type_event);
        put(d, c, 3, U16, CO_OD_RW, &d->tpdo[i].inhibit, &k_zero16);
        put(d, c, 5, U16, CO_OD_RW, &d->tpdo[i].event_ms, i == 0 ? &k_zero16 : &k_event_ms);
    }
    for (uint8_t i = 0; i < 2; i++) {
        uint16_t m = (uint16_t)(0x1A00 + i);
        put(d, m, 0, U8, CO_OD_RW, &d->tpdo[i].map_n, &k_one8);
        put(d, m, 1, U32, CO_OD_RW, &d->tpdo[i].map[0], &k_tpdo_map[i][0]);
        put(d, m, 2, U32, CO_OD_RW, &d->tpdo[i].map[1], &k_tpdo_map[i][1]);
    }
    put(d, 0x2000, 0, U32, CO_OD_RW | CO_OD_TPDO, &d->out_u32, &k_zero32);
    put(d, 0x2001, 0, U16, CO_OD_RW | CO_OD_TPDO, &d->out_u16, &k_zero16);
    put(d, 0x2100, 0, U32, CO_OD_RW | CO_OD_RPDO, &d->in_u32, &k_zero32);
    put(d, 0x2101, 0, U16, CO_OD_RW | CO_OD_RPDO, &d->in_u16, &k_zero16);
    put(d, 0x2102, 0, U8, CO_OD_RW | CO_OD_RPDO, &d->in_u8, &k_zero8);
    co_od_t od = {.entries = d->e, .count = d->n};
    co_od_reset(&od, 0x1000, 0xFFFF, 0);
    return od;
}

/* The device and a raw port that sees (and records) everything it sends. */
typedef struct rig {
    co_sim_bus_t bus;
    co_sim_port_t dev_port, tap_port;
    co_node_t node;
    dict_t d;
    fake_bus_t seen; /* what the tap received */
    co_ec_event_t events[16];
    uint32_t event_count;
    char dump[4096];
} rig_t;

static rig_t g_rig;

static void tap_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    (void)now_us;
    fake_bus_t *b = ctx;
    if (b->count < FAKE_MAX_FRAMES) {
        b->frames[b->count++] = *frame;
    }
}

static void on_errctl(void *user, const co_ec_event_t *ev)
{
    rig_t *r = user;
    if (r->event_count < 16) {
        r->events[r->event_count++] = *ev;
    }
}

/* A started device (pre-operational), its boot-up and first frames left in `seen`. */
static rig_t *rig_start(void)
{
    rig_t *r = &g_rig;
    memset(r, 0, sizeof *r);
    CHECK_EQ(co_sim_bus_init(&r->bus, 0), CO_OK);
    CHECK_EQ(co_sim_port_attach(&r->bus, &r->dev_port), CO_OK);
    CHECK_EQ(co_sim_port_attach_raw(&r->bus, &r->tap_port, tap_rx, &r->seen), CO_OK);
    co_node_config_t cfg = {.node_id = ID, .od = dict_init(&r->d), .user = r};
    cfg.driver = co_sim_port_driver(&r->dev_port);
    cfg.on_errctl = on_errctl;
    CHECK_EQ(co_node_init(&r->node, &cfg), CO_OK);
    co_sim_port_bind(&r->dev_port, &r->node);
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    CHECK_EQ(co_sim_run_until(&r->bus, 1), CO_OK);
    return r;
}

static void run(rig_t *r, uint64_t until_us)
{
    CHECK_EQ(co_sim_run_until(&r->bus, until_us), CO_OK);
}

static void send(rig_t *r, uint32_t id, const char *hex)
{
    co_frame_t f = frm(id, hex);
    CHECK_EQ(co_sim_send(&r->tap_port, &f), CO_OK);
    run(r, r->bus.now_us + 1); /* delivered, answered */
}

static const char *seen(rig_t *r) { return fake_dump(&r->seen, r->dump, sizeof r->dump); }

static void clear(rig_t *r) { fake_clear(&r->seen); }

static void operational(rig_t *r)
{
    send(r, 0x000, "01 05");
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_OPERATIONAL);
    clear(r);
}

/* ---- what every profile does */

static void test_boots_and_sends_heartbeats(void)
{
    rig_t *r = rig_start();
    CHECK_STR(seen(r), "705#00");
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_PRE_OPERATIONAL);
    run(r, 250 * MS);
    CHECK_STR(seen(r), "705#00 705#7F 705#7F");
}

static void test_expedited_sdo_both_ways(void)
{
    rig_t *r = rig_start();
    clear(r);
    send(r, 0x605, "40 18 10 01 00 00 00 00");
    CHECK_STR(seen(r), "585#43181001A00C0000");
    clear(r);
    send(r, 0x605, "23 00 20 00 78 56 34 12");
    CHECK_STR(seen(r), "585#6000200000000000");
    CHECK_EQ(r->d.out_u32, 0x12345678u);
    clear(r);
    send(r, 0x605, "2B 01 20 00 34 12 00 00");
    CHECK_STR(seen(r), "585#6001200000000000");
    CHECK_EQ(r->d.out_u16, 0x1234u);
}

/* Block transfer is in neither profile: abort 0x05040001 (command not valid). */
static void test_block_transfer_refused(void)
{
    rig_t *r = rig_start();
    clear(r);
    send(r, 0x605, "A4 08 10 00 7F 00 00 00"); /* block upload initiate */
    CHECK_STR(seen(r), "585#8008100001000405");
    clear(r);
    send(r, 0x605, "C6 00 20 00 04 00 00 00"); /* block download initiate */
    CHECK_STR(seen(r), "585#8000200001000405");
}

static void test_pdos_sync_and_rpdo(void)
{
    rig_t *r = rig_start();
    operational(r);
    send(r, 0x205, "11 22 33 44 55 66");
    CHECK_EQ(r->d.in_u32, 0x44332211u);
    CHECK_EQ(r->d.in_u16, 0x6655u);
    r->d.out_u32 = 0xA1B2C3D4u;
    clear(r);
    send(r, 0x080, ""); /* SYNC: TPDO1 is cyclic, every SYNC */
    CHECK_STR(seen(r), "185#D4C3B2A1");
    CHECK_EQ(co_sync_counter(&r->node), 0);
    /* a change of an event-driven TPDO's object through the node sends it */
    clear(r);
    CHECK_EQ(co_node_set_uint(&r->node, 0x2001, 0, 0xBEEF), CO_ABORT_NONE);
    run(r, r->bus.now_us + 1);
    CHECK_STR(seen(r), "285#EFBE");
}

static void test_emcy_frame_layout(void)
{
    rig_t *r = rig_start();
    clear(r);
    static const uint8_t mfr[5] = {1, 2, 3, 4, 5};
    CHECK_EQ(co_emcy_raise(&r->node, 0x2310, mfr), CO_OK);
    run(r, r->bus.now_us + 1);
    CHECK_STR(seen(r), "085#1023030102030405");
    CHECK_EQ(r->d.reg, 0x03);
    clear(r);
    CHECK_EQ(co_emcy_clear(&r->node, 0x2310), CO_OK);
    run(r, r->bus.now_us + 1);
    CHECK_STR(seen(r), "085#0000000000000000");
}

/* 0x1014 marked not valid: errors and the register are kept, no frame leaves (with or
 * without the EMCY queue of the inhibit time); valid again, the next error is sent. */
static void test_emcy_off(void)
{
    rig_t *r = rig_start();
    clear(r);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1014, 0, 0x80000085u), CO_ABORT_NONE);
    CHECK_EQ(co_emcy_raise(&r->node, 0x2310, NULL), CO_OK);
    run(r, r->bus.now_us + 1000);
    CHECK_STR(seen(r), "");
    CHECK_EQ(r->d.reg, 0x03);
    CHECK(co_emcy_active(&r->node, 0x2310));
    CHECK_EQ(co_node_set_uint(&r->node, 0x1014, 0, 0x85u), CO_ABORT_NONE);
    CHECK_EQ(co_emcy_raise(&r->node, 0x3210, NULL), CO_OK);
    run(r, r->bus.now_us + 1000);
    CHECK_STR(seen(r), "085#1032070000000000");
}

/* No storage is given (minimal: none is built in): "save" is refused with 0x08000020. A
 * core with storage shows that it has none in 0x1010 (0); one without keeps what the
 * dictionary says there. */
static void test_no_parameter_storage(void)
{
    rig_t *r = rig_start();
    clear(r);
    send(r, 0x605, "23 10 10 01 73 61 76 65");
    CHECK_STR(seen(r), "585#8010100120000008");
    clear(r);
    send(r, 0x605, "40 10 10 01 00 00 00 00");
#if CO_CONFIG_STORAGE
    CHECK_STR(seen(r), "585#4310100100000000");
#else
    CHECK_STR(seen(r), "585#4310100101000000");
#endif
}

/* Both profiles leave out the types wider than 32 bits: the example dictionary, which has
 * an INTEGER64 (0x2005), is refused (the minimal profile refuses it earlier: at the
 * limits of 0x2001). */
static void test_64_bit_types_refused(void)
{
    static example_od_t x;
    static co_node_t node;
    co_node_config_t cfg = {.node_id = ID, .od = example_od_init(&x, 0)};
    cfg.driver = co_sim_port_driver(&g_rig.dev_port);
    uint32_t bad = 0;
    CHECK_EQ(co_od_validate(&cfg.od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(cfg.od.entries[bad].type, CO_CONFIG_OD_LIMITS ? CO_TYPE_INTEGER64 : CO_TYPE_INTEGER16);
    CHECK_EQ(co_node_init(&node, &cfg), CO_ERR_CONFIG);
}

static co_abort_t domain_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                              uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    (void)entry;
    (void)offset;
    (void)buf;
    (void)cap;
    *n = 0;
    *total = 0;
    return CO_ABORT_NONE;
}

/* Of the dictionary's features the minimal profile leaves out limits, DOMAIN values kept
 * in RAM and UNICODE_STRING: a dictionary with one of them is refused (a DOMAIN served by
 * hooks is fine). The default profile keeps them. */
static void test_dictionary_features(void)
{
    static const co_od_limits_t limits = {.low = {.u = 1}, .high = {.u = 9}};
    static const co_od_hooks_t hooks = {.read = domain_read};
    static uint8_t u8, bytes[4];
    static uint16_t text[2];
    static co_od_domain_t domain = {.data = bytes, .len = 0};
    co_od_entry_t e = {.index = 0x2000,
                       .type = CO_TYPE_UNSIGNED8,
                       .attr = CO_OD_RW,
                       .size = 1,
                       .value = &u8,
                       .limits = &limits};
    co_od_t od = {.entries = &e, .count = 1};
    CHECK_EQ(co_od_validate(&od, NULL), CO_CONFIG_OD_LIMITS ? CO_OK : CO_ERR_CONFIG);
    e = (co_od_entry_t){
        .index = 0x2000, .type = CO_TYPE_DOMAIN, .attr = CO_OD_RW, .size = 4, .value = &domain};
    CHECK_EQ(co_od_validate(&od, NULL), CO_CONFIG_OD_DOMAIN ? CO_OK : CO_ERR_CONFIG);
    e = (co_od_entry_t){
        .index = 0x2000, .type = CO_TYPE_DOMAIN, .attr = CO_OD_RO, .size = 4, .hooks = &hooks};
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    e = (co_od_entry_t){.index = 0x2000,
                        .type = CO_TYPE_UNICODE_STRING,
                        .attr = CO_OD_RW,
                        .size = 4,
                        .value = text};
    CHECK_EQ(co_od_validate(&od, NULL), CO_CONFIG_OD_UNICODE ? CO_OK : CO_ERR_CONFIG);
}

/* ---- what the profiles differ in */

static void test_segmented_sdo(void)
{
    rig_t *r = rig_start();
    clear(r);
    send(r, 0x605, "40 08 10 00 00 00 00 00"); /* 0x1008: 14 characters */
#if CO_CONFIG_SDO_SEGMENTED
    CHECK_STR(seen(r), "585#410810000E000000");
    clear(r);
    send(r, 0x605, "60 00 00 00 00 00 00 00");
    CHECK_STR(seen(r), "585#0063616E6F6C6120"); /* "canola " */
#else
    /* expedited only: a value longer than 4 bytes cannot be uploaded (0x06010000), a
     * segmented download is an unknown command (0x05040001), expedited ones still work */
    CHECK_STR(seen(r), "585#8008100000000106");
    clear(r);
    send(r, 0x605, "21 00 20 00 04 00 00 00"); /* segmented download of 0x2000, 4 bytes */
    CHECK_STR(seen(r), "585#8000200001000405");
    clear(r);
    send(r, 0x605, "60 00 00 00 00 00 00 00"); /* no transfer is open */
    CHECK_STR(seen(r), "585#8000000001000405");
    clear(r);
    send(r, 0x605, "23 00 20 00 78 56 34 12");
    CHECK_STR(seen(r), "585#6000200000000000");
    clear(r);
    send(r, 0x605, "40 00 20 00 00 00 00 00");
    CHECK_STR(seen(r), "585#4300200078563412");
#endif
}

static void test_error_history(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_emcy_raise(&r->node, 0x4210, NULL), CO_OK);
    uint8_t five = 5;
#if CO_CONFIG_EMCY_HISTORY
    CHECK_EQ(r->d.history_count, 1);
    CHECK_EQ(r->d.history[0], 0x4210u);
    CHECK_EQ(co_node_write_net(&r->node, 0x1003, 0, &five, 1), CO_ABORT_VALUE);
#else
    /* 0x1003 is a plain entry: nothing recorded, any value may be written */
    CHECK_EQ(r->d.history_count, 0);
    CHECK_EQ(r->d.history[0], 0u);
    CHECK_EQ(co_node_write_net(&r->node, 0x1003, 0, &five, 1), CO_ABORT_NONE);
    CHECK_EQ(co_emcy_raise(&r->node, 0x4211, NULL), CO_OK);
    CHECK_EQ(r->d.history_count, 5);
    CHECK_EQ(r->d.history[0], 0u);
#endif
}

static void test_heartbeat_consumer(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_node_set_uint(&r->node, 0x1016, 1, hb_consumer_value(9, 50)), CO_ABORT_NONE);
    co_frame_t hb = frm(0x709, "05");
    send(r, 0x709, "05");
    clear(r);
    run(r, r->bus.now_us + 120 * MS); /* silent for more than 50 ms */
#if HAS_HB_CONSUMER
    CHECK(co_node_accepts(&r->node, &hb));
    CHECK_EQ(co_hb_remote_state(&r->node, 9), CO_NMT_OPERATIONAL);
    CHECK_EQ(r->event_count, 2);
    CHECK_EQ(r->events[0].kind, CO_EC_STARTED);
    CHECK_EQ(r->events[1].kind, CO_EC_HB_TIMEOUT);
    CHECK_STR(seen(r), "085#3081110000000000 705#7F"); /* EMCY 0x8130, then the heartbeat */
#else
    /* 0x1016 is a plain entry: the value is kept, nothing is watched or routed */
    CHECK_EQ(r->d.hb_cons[0], hb_consumer_value(9, 50));
    CHECK(!co_node_accepts(&r->node, &hb));
    CHECK_EQ(co_hb_remote_state(&r->node, 9), 0xFF);
    CHECK_EQ(r->event_count, 0);
    CHECK_STR(seen(r), "705#7F");
#endif
}

static void test_tpdo_event_timer(void)
{
    rig_t *r = rig_start();
    operational(r);
    run(r, r->bus.now_us + 35 * MS);
#if CO_CONFIG_PDO_TIMERS
    CHECK_EQ(fake_count_id(&r->seen, 0x285), 3); /* every 10 ms */
#else
    CHECK_EQ(fake_count_id(&r->seen, 0x285), 0); /* sub5 has no effect */
#endif
}

static void test_tpdo_inhibit_time(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_node_set_uint(&r->node, 0x1801, 5, 0), CO_ABORT_NONE);  /* no event timer */
    CHECK_EQ(co_node_set_uint(&r->node, 0x1801, 3, 50), CO_ABORT_NONE); /* 5 ms */
    operational(r);
    CHECK_EQ(co_node_set_uint(&r->node, 0x2001, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&r->node, 0x2001, 0, 2), CO_ABORT_NONE);
    run(r, r->bus.now_us + 1);
#if CO_CONFIG_PDO_TIMERS
    CHECK_STR(seen(r), "285#0100"); /* the second waits for the inhibit time */
    run(r, r->bus.now_us + 5 * MS);
    CHECK_STR(seen(r), "285#0100 285#0200");
#else
    CHECK_STR(seen(r), "285#0100 285#0200");     /* sub3 has no effect */
#endif
}

static void test_rpdo_deadline(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_node_set_uint(&r->node, 0x1400, 5, 20), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1801, 5, 0), CO_ABORT_NONE); /* TPDO2 quiet */
    operational(r);
    send(r, 0x205, "11 22 33 44 55 66");
    run(r, r->bus.now_us + 30 * MS);
#if CO_CONFIG_PDO_TIMERS
    CHECK_STR(seen(r), "085#5082110000000000"); /* 0x8250 */
#else
    CHECK_STR(seen(r), "");
#endif
}

static void test_sync_producer(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_node_set_uint(&r->node, 0x1006, 0, 10000), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    clear(r);
    run(r, r->bus.now_us + 35 * MS);
#if CO_CONFIG_SYNC_PRODUCER
    CHECK_EQ(fake_count_id(&r->seen, 0x080), 3);
#else
    CHECK_EQ(fake_count_id(&r->seen, 0x080), 0); /* bit 30 and 0x1006 have no effect */
#endif
    /* a consumer either way */
    operational(r);
    send(r, 0x080, "");
    CHECK_EQ(fake_count_id(&r->seen, 0x185), 1);
}

static void test_emcy_inhibit_time(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_node_set_uint(&r->node, 0x1015, 0, 100), CO_ABORT_NONE); /* 10 ms */
    clear(r);
    CHECK_EQ(co_emcy_raise(&r->node, 0x1000, NULL), CO_OK);
    CHECK_EQ(co_emcy_raise(&r->node, 0x5000, NULL), CO_OK);
    run(r, r->bus.now_us + 1);
#if HAS_EMCY_INHIBIT
    CHECK_STR(seen(r), "085#0010010000000000");
    run(r, r->bus.now_us + 10 * MS);
#endif
    CHECK_STR(seen(r), "085#0010010000000000 085#0050010000000000");
}

static void test_pdo_remapping(void)
{
    rig_t *r = rig_start();
    CHECK_EQ(co_node_set_uint(&r->node, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
#if CO_CONFIG_PDO_DYNAMIC
    CHECK_EQ(co_node_set_uint(&r->node, 0x1A00, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1A00, 1, 0x20010010), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1A00, 0, 1), CO_ABORT_NONE);
#else
    uint8_t zero = 0;
    CHECK_EQ(co_node_write_net(&r->node, 0x1A00, 0, &zero, 1), CO_ABORT_READ_ONLY);
    CHECK_EQ(co_node_set_uint(&r->node, 0x1A00, 1, 0x20010010), CO_ABORT_READ_ONLY);
    CHECK_EQ(r->d.tpdo[0].map[0], 0x20000020u); /* unchanged */
#endif
    CHECK_EQ(co_node_set_uint(&r->node, 0x1800, 1, 0x185u), CO_ABORT_NONE);
    r->d.out_u16 = 0x0102;
    r->d.out_u32 = 0x03040506;
    operational(r);
    send(r, 0x080, "");
#if CO_CONFIG_PDO_DYNAMIC
    CHECK_STR(seen(r), "185#0201");
#else
    CHECK_STR(seen(r), "185#06050403");
#endif
}

/* RPDO2 maps 4 bits of 0x2102: bit-granular mapping. */
static void test_bit_mapping(void)
{
    rig_t *r = rig_start();
    r->d.in_u8 = 0xA0;
    operational(r);
    send(r, 0x305, "F7");
#if CO_CONFIG_PDO_BIT_MAPPING
    CHECK_EQ(r->d.in_u8, 0xA7); /* the low 4 bits, the others kept */
#else
    CHECK_EQ(r->d.in_u8, 0xA0); /* the mapping is refused: RPDO2 maps nothing */
#endif
}

/* The node's counters (CO_CONFIG_STATS): counted in the default profile; the minimal one
 * keeps none, and co_node_stats answers zeros whatever the traffic. */
static void test_counters(void)
{
    rig_t *r = rig_start();
    co_frame_t unrouted = frm(0x123, "01"); /* (the bus filters it: straight to the node) */
    co_node_ingest(&r->node, r->bus.now_us, &unrouted);
    send(r, 0x000, "01");                      /* NMT command of 1 byte: malformed */
    send(r, 0x605, "40 18 10 01 00 00 00 00"); /* answered */
    const co_node_stats_t *st = co_node_stats(&r->node);
#if CO_CONFIG_STATS
    CHECK_EQ(st->rx_frames, 3);
    CHECK_EQ(st->rx_unrouted, 1);
    CHECK_EQ(st->rx_malformed, 1);
    CHECK_EQ(st->tx_frames, 2); /* the boot-up and the SDO answer */
#else
    CHECK_EQ(st->rx_frames, 0);
    CHECK_EQ(st->rx_unrouted, 0);
    CHECK_EQ(st->rx_malformed, 0);
    CHECK_EQ(st->tx_frames, 0);
#endif
    CHECK_STR(seen(r), "705#00 585#43181001A00C0000"); /* counted or not, the same frames */
}

int main(void)
{
    printf("profile: %s\n", CANOLA_PROFILE);
    RUN(test_boots_and_sends_heartbeats);
    RUN(test_expedited_sdo_both_ways);
    RUN(test_block_transfer_refused);
    RUN(test_pdos_sync_and_rpdo);
    RUN(test_emcy_frame_layout);
    RUN(test_emcy_off);
    RUN(test_no_parameter_storage);
    RUN(test_64_bit_types_refused);
    RUN(test_dictionary_features);
    RUN(test_segmented_sdo);
    RUN(test_error_history);
    RUN(test_heartbeat_consumer);
    RUN(test_tpdo_event_timer);
    RUN(test_tpdo_inhibit_time);
    RUN(test_rpdo_deadline);
    RUN(test_sync_producer);
    RUN(test_emcy_inhibit_time);
    RUN(test_pdo_remapping);
    RUN(test_bit_mapping);
    RUN(test_counters);
    return check_summary();
}
