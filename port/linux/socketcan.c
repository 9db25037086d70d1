/* SPDX-License-Identifier: Apache-2.0 */
/* socketcan.c -- CAN driver on Linux SocketCAN raw sockets; see canola/socketcan.h. */
#define _GNU_SOURCE

#include "canola/socketcan.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

static co_rx_t sc_recv(co_transport_t *t, co_frame_t *frame, uint32_t *events);
static co_err_t sc_send(co_transport_t *t, const co_frame_t *frame);
static void sc_set_filter(co_transport_t *t, const co_node_t *node);
static void sc_close(co_transport_t *t);

static const co_transport_ops_t sc_ops = {
    .recv = sc_recv, .send = sc_send, .set_filter = sc_set_filter, .close = sc_close};

static void sc_reset(co_socketcan_t *can)
{
    memset(can, 0, sizeof *can);
    can->transport.ops = &sc_ops;
    can->transport.fd = -1;
}

co_err_t co_socketcan_open(co_socketcan_t *can, const char *ifname)
{
    if (can == NULL || ifname == NULL) {
        return CO_ERR_ARG;
    }
    sc_reset(can);
    size_t n = strlen(ifname);
    if (n == 0 || n >= sizeof can->ifname) {
        co_transport_fail(&can->transport, "bad interface name '%s'", ifname);
        return CO_ERR_ARG;
    }
    memcpy(can->ifname, ifname, n + 1);
    unsigned ifindex = if_nametoindex(ifname);
    if (ifindex == 0) {
        co_transport_fail(&can->transport, "%s: no such CAN interface", ifname);
        return CO_ERR_NOT_FOUND;
    }
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        co_transport_fail(&can->transport, "%s: CAN socket: %s", ifname, strerror(errno));
        return CO_ERR_STATE;
    }
    /* Nothing passes until co_socketcan_bind sets the node's routes. */
    int off = 0;
    can_err_mask_t err_mask = CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)ifindex;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, NULL, 0) != 0 ||
        setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0 ||
        setsockopt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, sizeof off) != 0 ||
        bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        int saved = errno;
        co_transport_fail(&can->transport, "%s: %s", ifname, strerror(saved));
        close(fd);
        errno = saved;
        return CO_ERR_STATE;
    }
    can->transport.fd = fd;
    can->is_can = true;
    return CO_OK;
}

co_err_t co_socketcan_open_fd(co_socketcan_t *can, int fd)
{
    if (can == NULL || fd < 0) {
        return CO_ERR_ARG;
    }
    sc_reset(can);
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) != 0) {
        co_transport_fail(&can->transport, "fd %d: %s", fd, strerror(errno));
        return CO_ERR_STATE;
    }
    can->transport.fd = fd;
    memcpy(can->ifname, "fd", 3);
    return CO_OK;
}

static co_err_t sc_send(co_transport_t *t, const co_frame_t *frame)
{
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    if (frame->flags & CO_FRAME_EXT) {
        cf.can_id = (frame->id & CAN_EFF_MASK) | CAN_EFF_FLAG;
    } else {
        cf.can_id = frame->id & CAN_SFF_MASK;
    }
    if (frame->flags & CO_FRAME_RTR) {
        cf.can_id |= CAN_RTR_FLAG;
    }
    cf.len = frame->len > 8 ? 8 : frame->len;
    if (!(frame->flags & CO_FRAME_RTR)) {
        memcpy(cf.data, frame->data, cf.len);
    }
    for (;;) {
        ssize_t n = write(t->fd, &cf, sizeof cf);
        if (n == (ssize_t)sizeof cf) {
            return CO_OK;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) {
            return CO_ERR_BUSY;
        }
        co_transport_fail(t, "write: %s", n < 0 ? strerror(errno) : "short write");
        return CO_ERR_STATE;
    }
}

static co_err_t tx(void *ctx, const co_frame_t *frame)
{
    co_socketcan_t *can = ctx;
    return sc_send(&can->transport, frame);
}

/* Program the kernel filter with the node's routes: a perfect filter per COB-ID. The
 * RTR bit is left out of the mask so that remote frames (node guarding) pass too. */
static int set_filters(co_socketcan_t *can, const co_node_t *node)
{
    if (!can->is_can) {
        return 0; /* a plain packet fd has no filter: the node ignores what it does not route */
    }
    struct can_filter filters[CO_RX_ROUTES_MAX > 0 ? CO_RX_ROUTES_MAX : 1];
    uint32_t count = co_node_route_count(node);
    if (count > sizeof filters / sizeof filters[0]) {
        count = sizeof filters / sizeof filters[0];
    }
    for (uint32_t i = 0; i < count; i++) {
        uint32_t key = co_node_route_id(node, i);
        if (key & 0x80000000u) {
            filters[i].can_id = (key & CAN_EFF_MASK) | CAN_EFF_FLAG;
            filters[i].can_mask = CAN_EFF_MASK | CAN_EFF_FLAG;
        } else {
            filters[i].can_id = key & CAN_SFF_MASK;
            filters[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG;
        }
    }
    return setsockopt(can->transport.fd, SOL_CAN_RAW, CAN_RAW_FILTER, count ? filters : NULL,
                      (socklen_t)(count * sizeof filters[0]));
}

static void sc_set_filter(co_transport_t *t, const co_node_t *node)
{
    co_socketcan_t *can = (co_socketcan_t *)t;
    if (node != NULL && t->fd >= 0) {
        (void)set_filters(can, node);
    }
}

static void on_routes_changed(void *ctx)
{
    co_socketcan_t *can = ctx;
    if (can->node != NULL) {
        sc_set_filter(&can->transport, can->node);
    }
}

co_driver_t co_socketcan_driver(co_socketcan_t *can)
{
    co_driver_t d = {.tx = tx, .on_routes_changed = on_routes_changed, .ctx = can};
    return d;
}

co_err_t co_socketcan_bind(co_socketcan_t *can, co_node_t *node)
{
    if (can == NULL || node == NULL || can->transport.fd < 0) {
        return CO_ERR_ARG;
    }
    can->node = node;
    return set_filters(can, node) == 0 ? CO_OK : CO_ERR_STATE;
}

uint32_t co_socketcan_error_events(uint32_t can_id, const uint8_t data[8])
{
    if (!(can_id & CAN_ERR_FLAG)) {
        return 0;
    }
    uint32_t ev = 0;
    if (can_id & CAN_ERR_CRTL) {
        uint8_t ctrl = data[1];
        if (ctrl & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) {
            ev |= 1u << CO_BUS_RX_OVERRUN;
        }
        if (ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
            ev |= 1u << CO_BUS_ERROR_PASSIVE;
        }
#ifdef CAN_ERR_CRTL_ACTIVE
        if (ctrl & CAN_ERR_CRTL_ACTIVE) {
            ev |= 1u << CO_BUS_ERROR_ACTIVE;
        }
#endif
    }
    if (can_id & CAN_ERR_BUSOFF) {
        ev |= 1u << CO_BUS_OFF;
    }
    if (can_id & CAN_ERR_RESTARTED) {
        ev |= 1u << CO_BUS_OFF_RECOVERED;
    }
    return ev;
}

static co_rx_t sc_recv(co_transport_t *t, co_frame_t *frame, uint32_t *events)
{
    co_socketcan_t *can = (co_socketcan_t *)t;
    for (;;) {
        struct can_frame cf;
        ssize_t n = read(t->fd, &cf, sizeof cf);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return CO_RX_AGAIN;
            }
            co_transport_fail(t, "%s: read: %s", can->ifname, strerror(errno));
            return CO_RX_ERROR;
        }
        if (n == 0 && !can->is_can) {
            co_transport_fail(t, "%s: the peer closed", can->ifname);
            return CO_RX_ERROR;
        }
        if (n != (ssize_t)sizeof cf) {
            continue; /* not a classic CAN frame (CAN FD is not enabled): ignore */
        }
        if (cf.can_id & CAN_ERR_FLAG) {
            can->rx_errors++;
            uint32_t ev = co_socketcan_error_events(cf.can_id, cf.data);
            if (ev == 0) {
                continue;
            }
            *events = ev;
            return CO_RX_EVENTS;
        }
        memset(frame, 0, sizeof *frame);
        if (cf.can_id & CAN_EFF_FLAG) {
            frame->id = cf.can_id & CAN_EFF_MASK;
            frame->flags = CO_FRAME_EXT;
        } else {
            frame->id = cf.can_id & CAN_SFF_MASK;
        }
        if (cf.can_id & CAN_RTR_FLAG) {
            frame->flags |= CO_FRAME_RTR;
        }
        frame->len = cf.len > 8 ? 8 : cf.len;
        if (!(frame->flags & CO_FRAME_RTR)) {
            memcpy(frame->data, cf.data, frame->len);
        }
        return CO_RX_FRAME;
    }
}

int co_socketcan_receive(co_socketcan_t *can, uint64_t now_us)
{
    if (can == NULL || can->node == NULL || can->transport.fd < 0) {
        return -1;
    }
    int count = 0;
    for (;;) {
        co_frame_t f;
        uint32_t ev = 0;
        switch (sc_recv(&can->transport, &f, &ev)) {
        case CO_RX_AGAIN:
            return count;
        case CO_RX_ERROR:
            return -1;
        case CO_RX_EVENTS:
            count++;
            for (int e = CO_BUS_RX_OVERRUN; e <= CO_BUS_OFF_RECOVERED; e++) {
                if (ev & (1u << e)) {
                    co_node_bus_event(can->node, (co_bus_event_t)e);
                }
            }
            break;
        case CO_RX_FRAME:
            count++;
            co_node_ingest(can->node, now_us, &f);
            break;
        }
    }
}

int co_socketcan_fd(const co_socketcan_t *can) { return can != NULL ? can->transport.fd : -1; }

static void sc_close(co_transport_t *t)
{
    if (t->fd >= 0) {
        close(t->fd);
        t->fd = -1;
    }
}

void co_socketcan_close(co_socketcan_t *can)
{
    if (can != NULL) {
        sc_close(&can->transport);
        can->node = NULL;
    }
}
