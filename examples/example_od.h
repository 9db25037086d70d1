/* SPDX-License-Identifier: Apache-2.0 */
/*
 * example_od.h -- a hand-written object dictionary for the examples and tests.
 *
 * A small device: the mandatory communication objects, error control
 * (0x100C, 0x100D, 0x1016 with 4 consumer entries, 0x1017, 0x1029), EMCY (0x1003,
 * 0x1014, 0x1015, 0x1028), SYNC (0x1005..0x1007, 0x1019), TIME (0x1012), stored
 * parameters (0x1010, 0x1011), 4 RPDOs and 4 TPDOs, identity,
 * and a few application objects of assorted types. Each node in a process needs
 * its own values, so the table lives in RAM next to them: example_od_init()
 * fills an example_od_t and returns the co_od_t to give the node.
 * (Generated dictionaries for firmware are const tables in flash instead.)
 */
#ifndef CANOLA_EXAMPLE_OD_H
#define CANOLA_EXAMPLE_OD_H

#include "canola/od.h"

#define EXAMPLE_HB_CONSUMERS 4
#define EXAMPLE_OD_MAX_ENTRIES 200
#define EXAMPLE_OD_HASH_SLOTS 512 /* 2^co_od_hash_bits(EXAMPLE_OD_MAX_ENTRIES) */
#define EXAMPLE_PDOS 4            /* RPDO1..4 and TPDO1..4 */
#define EXAMPLE_PDO_ENTRIES 8
#define EXAMPLE_EMCY_HISTORY 8
#define EXAMPLE_EMCY_CONSUMERS 4
#define EXAMPLE_DOMAIN_CAP 64

typedef struct example_od {
    /* communication profile */
    uint32_t device_type;                         /* 0x1000 */
    uint8_t error_register;                       /* 0x1001 */
    uint8_t error_count;                          /* 0x1003 sub0 */
    uint32_t error_history[EXAMPLE_EMCY_HISTORY]; /* 0x1003 sub1..8, newest first */
    uint32_t sync_cob_id;                         /* 0x1005 */
    /* PDO communication and mapping: RPDO n at 0x1400+n / 0x1600+n, TPDO at 0x1800+n /
     * 0x1A00+n. RPDO1 maps 0x6200 sub1..4, TPDO1 maps 0x2000; the others map nothing. */
    struct example_pdo {
        uint8_t comm_count; /* sub0 */
        uint32_t cob_id;    /* sub1 */
        uint8_t type;       /* sub2 */
        uint16_t inhibit;   /* sub3 (TPDO) */
        uint16_t event_ms;  /* sub5 */
        uint8_t sync_start; /* sub6 (TPDO) */
        uint8_t map_count;  /* mapping sub0 */
        uint32_t map[EXAMPLE_PDO_ENTRIES];
    } rpdo[EXAMPLE_PDOS], tpdo[EXAMPLE_PDOS];
    uint8_t store_count;         /* 0x1010 sub0 */
    uint32_t store[3];           /* 0x1010 sub1..3: save all / communication / application */
    uint8_t restore_count;       /* 0x1011 sub0 */
    uint32_t restore[3];         /* 0x1011 sub1..3 */
    uint32_t sync_period_us;     /* 0x1006 */
    uint32_t sync_window_us;     /* 0x1007 */
    uint32_t time_cob_id;        /* 0x1012 */
    uint16_t emcy_inhibit;       /* 0x1015, 100 us units */
    uint8_t sync_overflow;       /* 0x1019 */
    uint8_t emcy_consumer_count; /* 0x1028 sub0 */
    uint32_t emcy_consumer[EXAMPLE_EMCY_CONSUMERS]; /* 0x1028 sub1..4 */
    char device_name[16];                           /* 0x1008 */
    uint16_t guard_time_ms;                         /* 0x100C */
    uint32_t emcy_cob_id;                           /* 0x1014: 0x80 + $NODEID */
    uint8_t life_factor;                            /* 0x100D */
    uint8_t hb_consumer_count;                      /* 0x1016 sub0 */
    uint32_t hb_consumer[EXAMPLE_HB_CONSUMERS];     /* 0x1016 sub1..4 */
    uint16_t hb_period_ms;                          /* 0x1017 */
    uint16_t hb_period_default; /* power-on value of 0x1017 (set by example_od_init) */
    uint8_t identity_count;     /* 0x1018 sub0 */
    uint32_t identity[4];       /* 0x1018 sub1..4: vendor, product, revision, serial */
    uint8_t eb_count;           /* 0x1029 sub0 */
    uint8_t eb_comm;            /* 0x1029 sub1: communication error behaviour */
    /* manufacturer area */
    uint32_t app_u32;    /* 0x2000: rw, default 0x12345678 */
    int16_t app_i16;     /* 0x2001: rw, limits -100..100 */
    char app_string[16]; /* 0x2002: rw VISIBLE_STRING, capacity 16 */
    uint8_t domain_buf[EXAMPLE_DOMAIN_CAP];
    co_od_domain_t app_domain; /* 0x2003: rw DOMAIN in RAM */
    uint8_t app_wo;            /* 0x2004: write-only u8 */
    int64_t app_i64;           /* 0x2005: rw INTEGER64 */
    float app_real;            /* 0x2006: rw REAL32 */
    uint32_t app_u32b;         /* 0x2007: rw, PDO-mappable both ways, default 0 */
    /* device profile area */
    uint8_t outputs_count; /* 0x6200 sub0 */
    uint8_t outputs[4];    /* 0x6200 sub1..4, rww, PDO-mappable */
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES];
    uint32_t keys[EXAMPLE_OD_MAX_ENTRIES]; /* co_od_t.keys, as the generator emits them */
    uint16_t hash[EXAMPLE_OD_HASH_SLOTS];  /* co_od_t.hash, likewise */
} example_od_t;

/** Fill `x` (values at their power-on defaults) and return its dictionary. The
 *  heartbeat producer default is `hb_period_ms`; consumer entries default to 0. */
co_od_t example_od_init(example_od_t *x, uint16_t hb_period_ms);

/** `od` (from example_od_init, entries final) with its dense key array (co_od_t.keys)
 *  and its hash (co_od_t.hash) filled, as generated dictionaries have them. A table
 *  edited afterwards needs them again. */
co_od_t example_od_keyed(example_od_t *x, co_od_t od);

#endif /* CANOLA_EXAMPLE_OD_H */
