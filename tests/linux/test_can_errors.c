/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_can_errors.c -- SocketCAN error frames to the core's bus events and EMCYs,
 * natively: the decoder on crafted frames, then whole error frames through the SocketCAN
 * transport (a socketpair carries struct can_frame as a CAN socket would) into a node in
 * the event loop, whose EMCYs the test reads on the other end. The SocketCAN tier repeats
 * the delivery on vcan0 (test_socketcan). Bounded: alarm(120) (a starved machine is slow, not
 * wrong).
 */
#define _GNU_SOURCE

#include "canola/linux_loop.h"
#include "canola/socketcan.h"
#include "check.h"
#include "example_od.h"
#include "loop_wait.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#define EV(e) (1u << (e))

static void test_decode_crafted_frames(void)
{
    uint8_t d[8] = {0};
    CHECK_EQ(co_socketcan_error_events(0x123, d), 0); /* not an error frame */
    d[1] = CAN_ERR_CRTL_RX_PASSIVE;
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_CRTL, d), EV(CO_BUS_ERROR_PASSIVE));
    d[1] = CAN_ERR_CRTL_TX_PASSIVE;
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_CRTL, d), EV(CO_BUS_ERROR_PASSIVE));
    d[1] = CAN_ERR_CRTL_RX_OVERFLOW;
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_CRTL, d), EV(CO_BUS_RX_OVERRUN));
    d[1] = CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING; /* warnings: nothing for CiA 301 */
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_CRTL, d), 0);
#ifdef CAN_ERR_CRTL_ACTIVE
    d[1] = CAN_ERR_CRTL_ACTIVE;
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_CRTL, d), EV(CO_BUS_ERROR_ACTIVE));
#endif
    d[1] = 0;
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_BUSOFF, d), EV(CO_BUS_OFF));
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_RESTARTED, d),
             EV(CO_BUS_OFF_RECOVERED));
    /* The control byte means nothing without the CRTL class bit. */
    d[1] = CAN_ERR_CRTL_RX_PASSIVE;
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_PROT, d), 0);
    /* Several in one frame. */
    CHECK_EQ(co_socketcan_error_events(CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_BUSOFF, d),
             EV(CO_BUS_ERROR_PASSIVE) | EV(CO_BUS_OFF));
}

/* ---- through the transport into a node */

static co_loop_t loop;
static example_od_t od;
static co_node_t node;
static co_socketcan_t can;
static int peer;

static void put(uint32_t can_id, uint8_t ctrl)
{
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = can_id;
    cf.len = CAN_ERR_DLC;
    cf.data[1] = ctrl;
    CHECK(write(peer, &cf, sizeof cf) == (ssize_t)sizeof cf);
}

/* The EMCY codes the peer received since the last call (-1 terminated). */
static int emcys(uint16_t *codes, int cap)
{
    int n = 0;
    struct can_frame cf;
    while (read(peer, &cf, sizeof cf) == (ssize_t)sizeof cf) {
        if (cf.can_id == 0x80u + 5 && n < cap) {
            codes[n++] = (uint16_t)(cf.data[0] | cf.data[1] << 8);
        }
    }
    return n;
}

static void run_ms(unsigned ms)
{
    CHECK_EQ(co_loop_run_until(&loop, co_linux_now_us() + ms * 1000u), CO_LOOP_DEADLINE);
}

static uint32_t errors_wanted;

static bool errors_read(void *ctx)
{
    (void)ctx;
    return can.rx_errors >= errors_wanted;
}

/* Put an error frame and run the loop until the transport has read it (and the node has
 * handled it: the same wake-up), however busy the machine is. */
static void put_and_run(uint32_t can_id, uint8_t ctrl)
{
    put(can_id, ctrl);
    errors_wanted = can.rx_errors + 1;
    CHECK(loop_wait(&loop, errors_read, NULL, NULL));
}

static void test_error_frames_through_the_transport(void)
{
    int sv[2];
    CHECK(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv) == 0);
    peer = sv[1];
    CHECK_EQ(co_loop_init(&loop), CO_OK);
    CHECK_EQ(co_socketcan_open_fd(&can, sv[0]), CO_OK);
    co_node_config_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = 5;
    cfg.od = example_od_init(&od, 0);
    CHECK_EQ(co_loop_add_node(&loop, &node, &cfg, &can.transport), CO_OK);
    CHECK_EQ(co_node_start(&node, co_linux_now_us()), CO_OK);
    CHECK_EQ(co_nmt_apply(&node, CO_NMT_CMD_START), CO_OK);
    run_ms(10);
    uint16_t c[8];
    (void)emcys(c, 8);

    put_and_run(CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE); /* error passive */
    CHECK_EQ(emcys(c, 8), 1);
    CHECK_EQ(c[0], 0x8120);
    CHECK(co_emcy_active(&node, 0x8120));
    put_and_run(CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE); /* still passive: once */
    CHECK_EQ(emcys(c, 8), 0);

    put_and_run(CAN_ERR_FLAG | CAN_ERR_BUSOFF, 0); /* bus-off: error behaviour 0 -> pre-op */
    CHECK_EQ(co_nmt_state(&node), CO_NMT_PRE_OPERATIONAL);

    put_and_run(CAN_ERR_FLAG | CAN_ERR_RESTARTED, 0); /* recovered: 0x8140, passive ends */
    int n = emcys(c, 8);
    CHECK_EQ(n, 1);
    CHECK_EQ(c[0], 0x8140);
    CHECK(co_emcy_active(&node, 0x8140));
    CHECK(!co_emcy_active(&node, 0x8120));

    put_and_run(CAN_ERR_FLAG | CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW); /* overrun: 0x8110 */
    CHECK_EQ(emcys(c, 8), 1);
    CHECK_EQ(c[0], 0x8110);
    CHECK_EQ(can.rx_errors, 5);
    CHECK_EQ(co_loop_stats(&loop)->frames_in, 0); /* error frames are not frames */

    co_loop_close(&loop);
    co_socketcan_close(&can);
    close(peer);
}

int main(void)
{
    alarm(120);
    setvbuf(stdout, NULL, _IOLBF, 0);
    RUN(test_decode_crafted_frames);
    RUN(test_error_frames_through_the_transport);
    return check_summary();
}
