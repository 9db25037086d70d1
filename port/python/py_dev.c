/* SPDX-License-Identifier: Apache-2.0 */
/* canola.Device / canola.Master: a node with every callback routed to Python, on a
 * simulated bus or on a link (see canola_py.h). */
#include "canola_py.h"

#include <string.h>

static co_err_t sim_tx(canola_py_dev_t *d, const co_frame_t *frame)
{
    co_err_t err = co_sim_send(&d->port, frame);
    if (err == CO_OK && d->raw.bus) {
        if (d->own_count == CANOLA_PY_OWN_FRAMES) { /* forget the oldest */
            d->own_head = (d->own_head + 1) % CANOLA_PY_OWN_FRAMES;
            d->own_count--;
        }
        d->own[(d->own_head + d->own_count++) % CANOLA_PY_OWN_FRAMES] = *frame;
    }
    return err;
}

/* Every frame the node sends: a quiet node's error control frames (0x700 + its node-ID:
 * boot-up, heartbeat, guarding answers) stay off the bus. */
static co_err_t dev_tx(void *ctx, const co_frame_t *frame)
{
    canola_py_dev_t *d = ctx;
    if (d->quiet && !(frame->flags & CO_FRAME_EXT) && frame->id == 0x700u + co_node_id(&d->node)) {
        return CO_OK;
    }
    co_err_t err = d->sim ? sim_tx(d, frame) : canola_py_link_tx(d, frame);
    if (err == CO_OK) {
        bool abort = frame->len == 8 && frame->data[0] == 0x80u && !(frame->flags & CO_FRAME_RTR);
        d->abort_sent_id = abort ? frame->id : CANOLA_PY_NO_ABORT;
        if (d->sent_frames) {
            canola_py_sent(d->user, frame);
        }
    }
    return err;
}

/* Every write that reaches an entry's hooks, with its origin. */
static void dev_written(void *ctx, const co_od_entry_t *entry)
{
    const canola_py_dev_t *d = ctx;
    canola_py_written(d->user, entry, d->app_writes ? CANOLA_PY_BY_APP : CANOLA_PY_BY_NETWORK);
}

/* The node's routes changed: the bus's delivery index follows (see canola/sim.h). */
static void sim_routes_changed(void *ctx)
{
    canola_py_dev_t *d = ctx;
    co_sim_port_routes_changed(&d->port);
}

static bool same_frame(const co_frame_t *a, const co_frame_t *b)
{
    return a->id == b->id && a->flags == b->flags && a->len == b->len &&
           ((a->flags & CO_FRAME_RTR) || memcmp(a->data, b->data, a->len) == 0);
}

static void sim_raw_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    canola_py_dev_t *d = ctx;
    for (uint32_t i = 0; i < d->own_count; i++) {
        co_frame_t *f = &d->own[(d->own_head + i) % CANOLA_PY_OWN_FRAMES];
        if (same_frame(f, frame)) { /* drop it and everything sent before it */
            d->own_head = (d->own_head + i + 1) % CANOLA_PY_OWN_FRAMES;
            d->own_count -= i + 1;
            return;
        }
    }
    canola_py_raw_rx(d->user, now_us, frame);
}

canola_py_dev_t *canola_py_dev_new(co_sim_bus_t *bus, canola_py_link_t *link,
                                   co_od_entry_t *entries, uint32_t count, uint8_t node_id,
                                   uint16_t sdo_timeout_ms, const char *store_dir, bool raw_port,
                                   void *user, co_err_t *err)
{
    canola_py_dev_t *d = canola_py_alloc(sizeof *d);
    if (!d) {
        *err = CO_ERR_FULL;
        return NULL;
    }
    co_node_config_t cfg = {0};
    cfg.node_id = node_id;
    cfg.od.entries = entries;
    cfg.od.count = count;
    cfg.od.hook_ctx = d;
    cfg.sdo_timeout_ms = sdo_timeout_ms;
    cfg.user = user;
    cfg.on_state = canola_py_on_state;
    cfg.on_reset = canola_py_on_reset;
    cfg.on_errctl = canola_py_on_errctl;
    cfg.on_error = canola_py_on_error;
    cfg.on_emcy = canola_py_on_emcy;
    cfg.on_sync = canola_py_on_sync;
    cfg.on_time = canola_py_on_time;
    cfg.on_rpdo = canola_py_on_rpdo;
    d->hooks.written = dev_written;
    d->user = user;
    d->abort_sent_id = CANOLA_PY_NO_ABORT;
    for (uint32_t i = 0; i < count; i++) {
        if (entries[i].hooks == NULL) {
            entries[i].hooks = &d->hooks;
        }
    }
    if (store_dir) {
        *err = co_file_storage_init(&d->fs, store_dir);
        if (*err != CO_OK) {
            canola_py_release(d);
            return NULL;
        }
        cfg.storage = &d->fs.api;
    }
    if (link) {
        *err = canola_py_link_attach(link, d);
        if (*err != CO_OK) { /* the link is full: nothing of d is kept anywhere */
            canola_py_release(d);
            return NULL;
        }
    }
    if (bus) {
        *err = co_sim_port_attach(bus, &d->port);
        if (*err == CO_OK && raw_port) {
            *err = co_sim_port_attach_raw(bus, &d->raw, sim_raw_rx, d);
        }
        if (*err != CO_OK) {
            return d; /* attached ports stay with the bus: the caller keeps d with it */
        }
        d->sim = true;
        cfg.driver.on_routes_changed = sim_routes_changed;
    }
    cfg.driver.tx = dev_tx;
    cfg.driver.ctx = d;
    *err = co_node_init(&d->node, &cfg);
    if (*err != CO_OK) {
        d->port.bus_off = true;
        return d;
    }
    if (store_dir) { /* LSS store configuration: into the folder, as the parameters */
        const co_lss_slave_config_t lss = {.store = co_file_storage_store_lss, .ctx = &d->fs};
        (void)co_lss_slave_setup(&d->node, &lss);
    }
    if (bus) {
        co_sim_port_bind(&d->port, &d->node);
    }
    return d;
}

void canola_py_dev_free(canola_py_dev_t *dev)
{
    if (dev->link) {
        canola_py_link_detach(dev->link, dev);
    }
    canola_py_release(dev);
}

co_node_t *canola_py_dev_node(canola_py_dev_t *dev) { return &dev->node; }

co_err_t canola_py_stored_node_id(const char *store_dir, uint8_t *node_id)
{
    co_file_storage_t fs;
    uint8_t bit_timing = 0;
    co_err_t err = co_file_storage_init(&fs, store_dir);
    return err == CO_OK ? co_file_storage_load_lss(&fs, node_id, &bit_timing) : err;
}

void canola_py_dev_touch(canola_py_dev_t *dev) { dev->port.node_due_us = 0; }

void canola_py_dev_set_quiet(canola_py_dev_t *dev, bool quiet) { dev->quiet = quiet; }

void canola_py_dev_set_sent(canola_py_dev_t *dev, bool sent) { dev->sent_frames = sent; }

bool canola_py_dev_sent_abort(const canola_py_dev_t *dev, uint32_t cob_id)
{
    return dev->abort_sent_id == cob_id;
}

co_abort_t canola_py_dev_write(canola_py_dev_t *dev, uint16_t index, uint8_t sub,
                               const uint8_t *data, uint32_t len)
{
    dev->app_writes++;
    co_abort_t abort = co_node_write_app(&dev->node, index, sub, data, len);
    dev->app_writes--;
    return abort;
}

co_abort_t canola_py_app_read(co_node_t *node, uint16_t index, uint8_t sub, uint8_t *buf,
                              uint32_t cap, uint32_t *len, uint8_t *type)
{
    co_abort_t abort;
    const co_od_entry_t *e = co_od_find(&node->cfg.od, index, sub, &abort);
    if (!e) {
        return abort;
    }
    *type = e->type;
    uint32_t total = 0;
    abort = co_od_read(&node->cfg.od, e, 0, buf, cap, len, &total);
    if (abort == CO_ABORT_NONE && total != CO_OD_SIZE_UNKNOWN && total > *len) {
        return CO_ABORT_LEN_HIGH;
    }
    return abort;
}

int canola_py_sdo_client_server(const co_node_t *node, uint8_t channel)
{
    uint64_t cobs[2];
    for (uint8_t sub = 1; sub <= 2; sub++) {
        if (co_node_get_uint(node, (uint16_t)(0x1280u + channel), sub, &cobs[sub - 1]) != CO_OK) {
            return 0;
        }
    }
    if ((cobs[0] | cobs[1]) >> 31) {
        return 0;
    }
    uint64_t n = cobs[0] - 0x600u;
    return n >= 1 && n <= 127 && cobs[1] == 0x580u + n ? (int)n : -1;
}
