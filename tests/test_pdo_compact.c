/* SPDX-License-Identifier: Apache-2.0 */
/* test_pdo_compact.c -- PDOs on the compact form of the dictionary (CO_CONFIG_OD_COMPACT 1,
 * the core built so: tests/CMakeLists.txt), where a PDO's mapping slots hold entry positions
 * instead of pointers (canola/pdo.h, co_pdo_item_t): an RPDO with a dummy entry between its
 * values, a TPDO the RPDO's change triggers, a TPDO on SYNC, and co_pdo_event finding the
 * TPDO that maps an entry. */
#include <string.h>

#include "canola/node.h"
#include "check.h"

#if !CO_CONFIG_OD_COMPACT
#error "test_pdo_compact.c needs the core built with CO_CONFIG_OD_COMPACT 1"
#endif

#define NODE_ID 5u

typedef struct values {
    uint32_t sync_cob;
    uint8_t rpdo_n, rpdo_type, rmap_n, tpdo_n[2], tpdo_type[2], tmap_n[2];
    uint32_t rpdo_cob, rmap[3], tpdo_cob[2], tmap[2];
    uint32_t in32;  /* 0x2000: RPDO1 */
    uint16_t in16;  /* 0x2001: RPDO1, TPDO2 */
    uint32_t out32; /* 0x2100: TPDO1 */
} values_t;

static values_t v;

/* The rows the entries name (co_od_entry_t.row): type and attributes. */
enum { U32_RW, U8_CO, U32_RW_NODEID, U8_RW, U32_RW_RPDO, U16_RW_RPDO_TPDO, U32_RW_TPDO };
static const co_od_row_t k_rows[] = {
    [U32_RW] = {.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RW},
    [U8_CO] = {.type = CO_TYPE_UNSIGNED8, .attr = CO_OD_CO},
    [U32_RW_NODEID] = {.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RW | CO_OD_NODEID},
    [U8_RW] = {.type = CO_TYPE_UNSIGNED8, .attr = CO_OD_RW},
    [U32_RW_RPDO] = {.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RW | CO_OD_RPDO},
    [U16_RW_RPDO_TPDO] = {.type = CO_TYPE_UNSIGNED16, .attr = CO_OD_RW | CO_OD_RPDO | CO_OD_TPDO},
    [U32_RW_TPDO] = {.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RW | CO_OD_TPDO},
};

#define ENTRY(idx, s, r, field)                                                                    \
    {                                                                                              \
        .index = (idx), .sub = (s), .row = (r), .offset = (uint16_t)offsetof(values_t, field)      \
    }

static const co_od_entry_t entries[] = {
    ENTRY(0x1005, 0, U32_RW, sync_cob),           /* 0 */
    ENTRY(0x1400, 0, U8_CO, rpdo_n),              /* 1 */
    ENTRY(0x1400, 1, U32_RW_NODEID, rpdo_cob),    /* 2 */
    ENTRY(0x1400, 2, U8_RW, rpdo_type),           /* 3 */
    ENTRY(0x1600, 0, U8_RW, rmap_n),              /* 4 */
    ENTRY(0x1600, 1, U32_RW, rmap[0]),            /* 5 */
    ENTRY(0x1600, 2, U32_RW, rmap[1]),            /* 6 */
    ENTRY(0x1600, 3, U32_RW, rmap[2]),            /* 7 */
    ENTRY(0x1800, 0, U8_CO, tpdo_n[0]),           /* 8 */
    ENTRY(0x1800, 1, U32_RW_NODEID, tpdo_cob[0]), /* 9 */
    ENTRY(0x1800, 2, U8_RW, tpdo_type[0]),        /* 10 */
    ENTRY(0x1801, 0, U8_CO, tpdo_n[1]),           /* 11 */
    ENTRY(0x1801, 1, U32_RW_NODEID, tpdo_cob[1]), /* 12 */
    ENTRY(0x1801, 2, U8_RW, tpdo_type[1]),        /* 13 */
    ENTRY(0x1A00, 0, U8_RW, tmap_n[0]),           /* 14 */
    ENTRY(0x1A00, 1, U32_RW, tmap[0]),            /* 15 */
    ENTRY(0x1A01, 0, U8_RW, tmap_n[1]),           /* 16 */
    ENTRY(0x1A01, 1, U32_RW, tmap[1]),            /* 17 */
    ENTRY(0x2000, 0, U32_RW_RPDO, in32),          /* 18 */
    ENTRY(0x2001, 0, U16_RW_RPDO_TPDO, in16),     /* 19 */
    ENTRY(0x2100, 0, U32_RW_TPDO, out32),         /* 20 */
};

/* Power-on values (canola/od.h, co_od_tables_t.defaults): a head (bits 0-4 the entries
 * skipped since the previous record's, bits 5-7 the length), wire bytes. RPDO1 maps 0x2000
 * (32 bits), a dummy UNSIGNED8 (0x0005, 8 bits) and 0x2001 (16 bits); TPDO1 (type 1: every
 * SYNC) maps 0x2100, TPDO2 (type 254: on events) 0x2001. */
#define LEN(n) ((n) << 5)
static const uint8_t k_image[] = {
    LEN(1),     0x80,                   /* 0: 0x1005, SYNC on 0x80 */
    LEN(1),     2,                      /* 1: 0x1400 sub0 */
    LEN(2),     0x00, 0x02,             /* 2: 0x200 + node-ID */
    LEN(1),     255,                    /* 3: asynchronous */
    LEN(1),     3,                      /* 4: three entries */
    LEN(4),     0x20, 0x00, 0x00, 0x20, /* 5: 0x2000 sub0, 32 bits */
    LEN(4),     0x08, 0x00, 0x05, 0x00, /* 6: dummy UNSIGNED8 */
    LEN(4),     0x10, 0x00, 0x01, 0x20, /* 7: 0x2001 sub0, 16 bits */
    LEN(1),     2,                      /* 8: 0x1800 sub0 */
    LEN(2),     0x80, 0x01,             /* 9: 0x180 + node-ID */
    LEN(1),     1,                      /* 10: every SYNC */
    LEN(1),     2,                      /* 11: 0x1801 sub0 */
    LEN(2),     0x80, 0x02,             /* 12: 0x280 + node-ID */
    LEN(1),     254,                    /* 13: on events */
    LEN(1),     1,                      /* 14: one entry */
    LEN(4),     0x20, 0x00, 0x00, 0x21, /* 15: 0x2100 sub0, 32 bits */
    LEN(1),     1,                      /* 16: one entry */
    LEN(4),     0x10, 0x00, 0x01, 0x20, /* 17: 0x2001 sub0, 16 bits */
    LEN(4) | 2, 0x44, 0x33, 0x22, 0x11, /* 20 (18 and 19 skipped): 0x2100 = 0x11223344 */
    0,                                  /* end */
};

static const co_od_tables_t k_tables = {.defaults = k_image};

typedef struct sent {
    co_frame_t frames[8];
    unsigned count;
} sent_t;

static co_err_t tx(void *ctx, const co_frame_t *frame)
{
    sent_t *s = ctx;
    if (s->count < 8) {
        s->frames[s->count++] = *frame;
    }
    return CO_OK;
}

static void feed(co_node_t *node, uint32_t id, const uint8_t *data, uint8_t len)
{
    co_frame_t f = {.id = id, .len = len};
    if (len > 0) { /* (a SYNC has no data: no pointer either) */
        memcpy(f.data, data, len);
    }
    co_node_ingest(node, 0, &f);
}

/* A node on the dictionary, started and operational, with nothing sent yet. */
static void start(co_node_t *node, sent_t *sent)
{
    memset(&v, 0, sizeof v);
    memset(sent, 0, sizeof *sent);
    co_node_config_t cfg = {.node_id = NODE_ID,
                            .od = {.entries = entries,
                                   .count = sizeof entries / sizeof entries[0],
                                   .values = &v,
                                   .rows = k_rows,
                                   .rows_count = sizeof k_rows / sizeof k_rows[0],
                                   .tables = &k_tables},
                            .driver = {.tx = tx, .ctx = sent}};
    CHECK_EQ(co_node_init(node, &cfg), CO_OK);
    CHECK_EQ(co_node_start(node, 0), CO_OK);
    const uint8_t go[2] = {0x01, NODE_ID}; /* NMT start */
    feed(node, 0x000, go, 2);
    sent->count = 0;
}

static void test_rpdo_skips_dummy_and_triggers_tpdo(void)
{
    static co_node_t node;
    sent_t sent;
    start(&node, &sent);
    const uint8_t data[7] = {0x78, 0x56, 0x34, 0x12, 0xEE, 0xCD, 0xAB};
    feed(&node, 0x200 + NODE_ID, data, 7);
    CHECK_EQ(v.in32, 0x12345678u);
    CHECK_EQ(v.in16, 0xABCDu); /* after the dummy byte */
    /* TPDO2 maps 0x2001: the RPDO's change is its event */
    CHECK_EQ(sent.count, 1u);
    CHECK_EQ(sent.frames[0].id, 0x280u + NODE_ID);
    CHECK_EQ(sent.frames[0].len, 2u);
    CHECK_EQ(sent.frames[0].data[0], 0xCDu);
    CHECK_EQ(sent.frames[0].data[1], 0xABu);
}

static void test_tpdo_on_sync_and_event(void)
{
    static co_node_t node;
    sent_t sent;
    start(&node, &sent);
    feed(&node, 0x80, NULL, 0); /* SYNC */
    CHECK_EQ(sent.count, 1u);
    CHECK_EQ(sent.frames[0].id, 0x180u + NODE_ID);
    CHECK_EQ(sent.frames[0].len, 4u);
    CHECK_EQ(sent.frames[0].data[0], 0x44u);
    CHECK_EQ(sent.frames[0].data[3], 0x11u);
    v.in16 = 0x0102;
    CHECK_EQ(co_pdo_event(&node, 0x2001, 0), 1u); /* TPDO2 maps it, TPDO1 does not */
    CHECK_EQ(co_pdo_event(&node, 0x2000, 0), 0u);
    CHECK_EQ(sent.count, 2u);
    CHECK_EQ(sent.frames[1].id, 0x280u + NODE_ID);
    CHECK_EQ(sent.frames[1].data[0], 0x02u);
    CHECK_EQ(sent.frames[1].data[1], 0x01u);
}

int main(void)
{
    RUN(test_rpdo_skips_dummy_and_triggers_tpdo);
    RUN(test_tpdo_on_sync_and_event);
    return check_summary();
}
