/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/harness.h -- a fake driver that records frames, and frame helpers.
 */
#ifndef CANOLA_TEST_HARNESS_H
#define CANOLA_TEST_HARNESS_H

#include "canola/canola.h"
#include "example_od.h"

#define FAKE_MAX_FRAMES 512

typedef struct fake_bus {
    co_frame_t frames[FAKE_MAX_FRAMES];
    uint32_t count;
    bool busy; /* tx answers CO_ERR_BUSY while set */
    uint32_t tx_calls;
    uint32_t routes_changed;
} fake_bus_t;

/** A driver whose tx records into `bus`. */
co_driver_t fake_driver(fake_bus_t *bus);
void fake_clear(fake_bus_t *bus);
/** Number of recorded frames with this COB-ID. */
uint32_t fake_count_id(const fake_bus_t *bus, uint32_t id);
/** The recorded frames as candump lines ("701#05 000#0105 ..."), space-separated. */
const char *fake_dump(const fake_bus_t *bus, char *buf, size_t cap);

/** Frame from an ID and hex bytes, e.g. frm(0x000, "01 05"); "R2" makes an RTR of len 2. */
co_frame_t frm(uint32_t id, const char *hex);
/** One frame as "ID#HEX" (candump style), into a static-free caller buffer. */
const char *frame_str(const co_frame_t *f, char *buf, size_t cap);

/** A node on the fake driver with the example OD, recording every callback. */
typedef struct test_node {
    example_od_t od;
    fake_bus_t bus;
    co_node_t node;
    co_node_config_t cfg;
    co_ec_event_t events[64];
    uint32_t event_count;
    co_nmt_state_t states[32];
    uint32_t state_count;
    co_reset_t resets[16];
    uint32_t reset_count;
    co_node_error_t errors[16];
    uint32_t error_count;
} test_node_t;

/** Fill `t` and co_node_init it (not started). Returns co_node_init's result. */
co_err_t test_node_init(test_node_t *t, uint8_t node_id, uint16_t hb_ms);
/** Index of the first recorded event of `kind` for `node_id`, or -1. */
int test_find_event(const test_node_t *t, co_ec_event_kind_t kind, uint8_t node_id);
/** Feed frm(id, hex) to the node at `now`. */
void ingest(test_node_t *t, uint64_t now, uint32_t id, const char *hex);
/** Write a little-endian value as the network would (co_node_write_net); the abort code. */
co_abort_t write_u8(test_node_t *t, uint16_t idx, uint8_t sub, uint8_t v);
co_abort_t write_u16(test_node_t *t, uint16_t idx, uint8_t sub, uint16_t v);
co_abort_t write_u32(test_node_t *t, uint16_t idx, uint8_t sub, uint32_t v);

/** What an SDO client transfer reported: the context of sdo_result_done (co_sdo_done_fn)
 *  and sdo_result_value (co_sdo_value_fn), which count the calls and keep the last one's
 *  arguments (`value` only sdo_result_value). */
typedef struct sdo_result {
    int calls;
    uint8_t channel;
    co_abort_t abort;
    uint32_t len;
    uint64_t value;
} sdo_result_t;

void sdo_result_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len);
void sdo_result_value(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value, uint32_t len);

/** 0x1016 value for consuming `node_id` with `time_ms`. */
static inline uint32_t hb_consumer_value(uint8_t node_id, uint16_t time_ms)
{
    return ((uint32_t)node_id << 16) | time_ms;
}

#endif /* CANOLA_TEST_HARNESS_H */
