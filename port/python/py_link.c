/* SPDX-License-Identifier: Apache-2.0 */
/* A python-can bus object and the canola devs on it (see canola_py.h): what one dev sends
 * the others receive at once, in C, as they would on a real bus; Python hands the same
 * frames to python-can for everybody else. */
#include "canola_py.h"

/* Rounds of delivery and polling in one run: a bound against two devs that would keep
 * answering each other for ever. */
#define CANOLA_PY_LINK_ROUNDS 1024

canola_py_link_t *canola_py_link_new(void)
{
    canola_py_link_t *link = canola_py_alloc(sizeof *link);
    if (link) {
        link->due_us = CO_TIME_NEVER;
    }
    return link;
}

void canola_py_link_free(canola_py_link_t *link) { canola_py_release(link); }

co_err_t canola_py_link_attach(canola_py_link_t *link, canola_py_dev_t *dev)
{
    if (link->dev_count == CANOLA_PY_LINK_DEVS) {
        return CO_ERR_FULL;
    }
    link->devs[link->dev_count++] = dev;
    dev->link = link;
    return CO_OK;
}

void canola_py_link_detach(canola_py_link_t *link, canola_py_dev_t *dev)
{
    for (uint32_t i = 0; i < link->dev_count; i++) {
        if (link->devs[i] == dev) {
            link->devs[i] = link->devs[--link->dev_count];
            break;
        }
    }
    for (uint32_t i = 0; i < link->count; i++) { /* its queued frames stay, sender-less */
        if (link->senders[i] == dev) {
            link->senders[i] = NULL;
        }
    }
    dev->link = NULL;
}

void canola_py_dev_set_active(canola_py_dev_t *dev, bool active) { dev->active = active; }

void canola_py_dev_set_raw(canola_py_dev_t *dev, bool raw) { dev->raw_frames = raw; }

co_err_t canola_py_link_tx(canola_py_dev_t *dev, const co_frame_t *frame)
{
    canola_py_link_t *link = dev->link;
    if (!link || link->count == CANOLA_PY_LINK_FRAMES) {
        if (link) {
            link->refused = true;
        }
        return CO_ERR_BUSY;
    }
    link->frames[link->count] = *frame;
    link->senders[link->count++] = dev;
    return CO_OK;
}

void canola_py_link_ingest(canola_py_link_t *link, uint64_t now_us, const co_frame_t *frame)
{
    for (uint32_t i = 0; i < link->dev_count; i++) {
        canola_py_dev_t *d = link->devs[i];
        if (d->active) {
            co_node_ingest(&d->node, now_us, frame);
        }
    }
    canola_py_link_run(link, now_us);
}

static uint64_t poll_all(canola_py_link_t *link, uint64_t now_us)
{
    uint64_t due = CO_TIME_NEVER;
    for (uint32_t i = 0; i < link->dev_count; i++) {
        canola_py_dev_t *d = link->devs[i];
        if (d->active) {
            uint64_t t = co_node_poll(&d->node, now_us);
            due = t < due ? t : due;
        }
    }
    link->due_us = due;
    return due;
}

uint64_t canola_py_link_poll(canola_py_link_t *link, uint64_t now_us)
{
    poll_all(link, now_us);
    canola_py_link_run(link, now_us);
    return link->due_us;
}

static void deliver(canola_py_link_t *link, uint64_t now_us, uint32_t n)
{
    const co_frame_t *frame = &link->frames[n];
    const canola_py_dev_t *sender = link->senders[n];
    for (uint32_t i = 0; i < link->dev_count; i++) {
        canola_py_dev_t *d = link->devs[i];
        if (d == sender || !d->active) {
            continue;
        }
        co_node_ingest(&d->node, now_us, frame);
        if (d->raw_frames) {
            canola_py_raw_rx(d->user, now_us, frame);
        }
    }
}

uint32_t canola_py_link_run(canola_py_link_t *link, uint64_t now_us)
{
    for (uint32_t round = 0; round < CANOLA_PY_LINK_ROUNDS && link->delivered < link->count;
         round++) {
        while (link->delivered < link->count) {
            deliver(link, now_us, link->delivered++);
        }
        poll_all(link, now_us); /* what the frames started may be due now */
    }
    return link->count;
}

bool canola_py_link_clear(canola_py_link_t *link)
{
    bool refused = link->refused;
    link->count = link->delivered = 0;
    link->refused = false;
    return refused;
}
