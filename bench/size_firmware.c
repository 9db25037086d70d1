/* SPDX-License-Identifier: Apache-2.0 */
/*
 * size_firmware.c -- the smallest firmware of a device on canola, for the size rows of
 * bench/run: the core, the dictionary canola.odgen generated (ds301.h, from the size rows'
 * EDS) and a blank CAN driver, linked for Cortex-M with --gc-sections from `firmware`.
 *
 * What it calls is what a device's main loop calls (initialise, start, hand over received
 * frames, poll, raise an EMCY), so the image holds exactly the code a device in that
 * configuration can reach, and its .data + .bss are the RAM a device needs: the node, the
 * dictionary's values, and the driver's one receive frame. Not run: bench/run only
 * measures the image.
 */
#include "canola/canola.h"
#include "ds301.h"

#define NODE_ID 1u

/* The blank driver: a receive register the CAN interrupt would fill (and flag), a
 * free-running microsecond timer, a transmit that always succeeds. */
static volatile co_frame_t rx_frame;
static volatile bool rx_pending;
static volatile uint32_t timer_us;

static co_err_t can_tx(void *ctx, const co_frame_t *frame)
{
    (void)ctx;
    (void)frame;
    return CO_OK;
}

static co_node_t node;

/* Zeroes with a byte loop that GCC keeps (it turns a plain one into a memset call): the core
 * links nothing of the C library, and neither should the firmware around it. */
static void zero(void *p, size_t n)
{
    volatile uint8_t *b = p;
    while (n-- > 0) {
        *b++ = 0;
    }
}

void firmware(void);

void firmware(void)
{
    co_node_config_t config; /* on the stack: co_node_init copies it */
    zero(&config, sizeof config);
    config.node_id = NODE_ID;
    config.od = ds301_od;
    config.driver.tx = can_tx;
    co_od_reset(&ds301_od, 0x0000, 0xFFFF, NODE_ID);
    if (co_node_init(&node, &config) != CO_OK || co_node_start(&node, timer_us) != CO_OK) {
        (void)co_emcy_raise(&node, 0x6100, NULL); /* internal software error */
    }
    for (;;) {
        if (rx_pending) {
            co_frame_t frame;
            frame.id = rx_frame.id;
            frame.flags = rx_frame.flags;
            frame.len = rx_frame.len;
            for (uint8_t i = 0; i < 8; i++) {
                frame.data[i] = rx_frame.data[i];
            }
            rx_pending = false;
            co_node_ingest(&node, timer_us, &frame);
        }
        (void)co_node_poll(&node, timer_us);
    }
}
