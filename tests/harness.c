/* SPDX-License-Identifier: Apache-2.0 */
/* tests/harness.c -- see harness.h. */
#include "harness.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static co_err_t fake_tx(void *ctx, const co_frame_t *frame)
{
    fake_bus_t *bus = ctx;
    bus->tx_calls++;
    if (bus->busy) {
        return CO_ERR_BUSY;
    }
    if (bus->count < FAKE_MAX_FRAMES) {
        bus->frames[bus->count++] = *frame;
    }
    return CO_OK;
}

static void fake_routes_changed(void *ctx)
{
    fake_bus_t *bus = ctx;
    bus->routes_changed++;
}

co_driver_t fake_driver(fake_bus_t *bus)
{
    co_driver_t d = {.tx = fake_tx, .on_routes_changed = fake_routes_changed, .ctx = bus};
    return d;
}

void fake_clear(fake_bus_t *bus) { bus->count = 0; }

uint32_t fake_count_id(const fake_bus_t *bus, uint32_t id)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < bus->count; i++) {
        n += bus->frames[i].id == id;
    }
    return n;
}

const char *frame_str(const co_frame_t *f, char *buf, size_t cap)
{
    size_t o = 0;
    o += (size_t)snprintf(buf + o, cap - o, (f->flags & CO_FRAME_EXT) ? "%08X#" : "%03X#",
                          (unsigned)f->id);
    if (f->flags & CO_FRAME_RTR) {
        snprintf(buf + o, cap - o, "R%u", (unsigned)f->len);
        return buf;
    }
    for (unsigned i = 0; i < f->len && o + 3 < cap; i++) {
        o += (size_t)snprintf(buf + o, cap - o, "%02X", f->data[i]);
    }
    return buf;
}

const char *fake_dump(const fake_bus_t *bus, char *buf, size_t cap)
{
    size_t o = 0;
    buf[0] = '\0';
    for (uint32_t i = 0; i < bus->count && o + 32 < cap; i++) {
        char one[40];
        o += (size_t)snprintf(buf + o, cap - o, "%s%s", i ? " " : "",
                              frame_str(&bus->frames[i], one, sizeof one));
    }
    return buf;
}

co_frame_t frm(uint32_t id, const char *hex)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    if (id > 0x7FF) {
        f.flags |= CO_FRAME_EXT;
    }
    if (hex[0] == 'R') {
        f.flags |= CO_FRAME_RTR;
        f.len = (uint8_t)atoi(hex + 1);
        return f;
    }
    const char *p = hex;
    while (*p && f.len < 8) {
        while (*p == ' ') {
            p++;
        }
        if (!*p) {
            break;
        }
        char byte[3] = {p[0], p[1], 0};
        f.data[f.len++] = (uint8_t)strtoul(byte, NULL, 16);
        p += 2;
    }
    return f;
}

static void rec_state(void *user, co_nmt_state_t state)
{
    test_node_t *t = user;
    if (t->state_count < 32) {
        t->states[t->state_count++] = state;
    }
}

static void rec_reset(void *user, co_reset_t what)
{
    test_node_t *t = user;
    if (t->reset_count < 16) {
        t->resets[t->reset_count++] = what;
    }
}

static void rec_errctl(void *user, const co_ec_event_t *ev)
{
    test_node_t *t = user;
    if (t->event_count < 64) {
        t->events[t->event_count++] = *ev;
    }
}

static void rec_error(void *user, co_node_error_t error)
{
    test_node_t *t = user;
    if (t->error_count < 16) {
        t->errors[t->error_count++] = error;
    }
}

co_err_t test_node_init(test_node_t *t, uint8_t node_id, uint16_t hb_ms)
{
    memset(t, 0, sizeof *t);
    t->cfg.node_id = node_id;
    t->cfg.od = example_od_init(&t->od, hb_ms);
    t->cfg.driver = fake_driver(&t->bus);
    t->cfg.user = t;
    t->cfg.on_state = rec_state;
    t->cfg.on_reset = rec_reset;
    t->cfg.on_errctl = rec_errctl;
    t->cfg.on_error = rec_error;
    return co_node_init(&t->node, &t->cfg);
}

int test_find_event(const test_node_t *t, co_ec_event_kind_t kind, uint8_t node_id)
{
    for (uint32_t i = 0; i < t->event_count; i++) {
        if (t->events[i].kind == kind && t->events[i].node_id == node_id) {
            return (int)i;
        }
    }
    return -1;
}

void ingest(test_node_t *t, uint64_t now, uint32_t id, const char *hex)
{
    co_frame_t f = frm(id, hex);
    co_node_ingest(&t->node, now, &f);
}

co_abort_t write_u8(test_node_t *t, uint16_t idx, uint8_t sub, uint8_t v)
{
    return co_node_write_net(&t->node, idx, sub, &v, 1);
}

co_abort_t write_u16(test_node_t *t, uint16_t idx, uint8_t sub, uint16_t v)
{
    uint8_t b[2];
    co_put_u16(b, v);
    return co_node_write_net(&t->node, idx, sub, b, 2);
}

co_abort_t write_u32(test_node_t *t, uint16_t idx, uint8_t sub, uint32_t v)
{
    uint8_t b[4];
    co_put_u32(b, v);
    return co_node_write_net(&t->node, idx, sub, b, 4);
}

void sdo_result_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    sdo_result_t *r = ctx;
    r->calls++;
    r->channel = channel;
    r->abort = abort;
    r->len = len;
}

void sdo_result_value(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value, uint32_t len)
{
    sdo_result_done(ctx, channel, abort, len);
    ((sdo_result_t *)ctx)->value = value;
}
