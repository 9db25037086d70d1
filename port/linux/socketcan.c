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
#include <time.h>
#include <unistd.h>

uint64_t co_linux_now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

co_err_t co_socketcan_open(co_socketcan_t *can, const char *ifname)
{
    if (can == NULL || ifname == NULL) {
        return CO_ERR_ARG;
    }
    memset(can, 0, sizeof *can);
    can->fd = -1;
    size_t n = strlen(ifname);
    if (n == 0 || n >= sizeof can->ifname) {
        return CO_ERR_ARG;
    }
    memcpy(can->ifname, ifname, n + 1);
    unsigned ifindex = if_nametoindex(ifname);
    if (ifindex == 0) {
        return CO_ERR_NOT_FOUND;
    }
    int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
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
        close(fd);
        errno = saved;
        return CO_ERR_STATE;
    }
    can->fd = fd;
    return CO_OK;
}

static co_err_t tx(void *ctx, const co_frame_t *frame)
{
    co_socketcan_t *can = ctx;
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
        ssize_t n = write(can->fd, &cf, sizeof cf);
        if (n == (ssize_t)sizeof cf) {
            return CO_OK;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS)) {
            return CO_ERR_BUSY;
        }
        return CO_ERR_STATE;
    }
}

/* Program the kernel filter with the node's routes: a perfect filter per COB-ID. The
 * RTR bit is left out of the mask so that remote frames (node guarding) pass too. */
static int set_filters(co_socketcan_t *can)
{
    struct can_filter filters[CO_RX_ROUTES_MAX > 0 ? CO_RX_ROUTES_MAX : 1];
    uint32_t count = co_node_route_count(can->node);
    if (count > sizeof filters / sizeof filters[0]) {
        count = sizeof filters / sizeof filters[0];
    }
    for (uint32_t i = 0; i < count; i++) {
        uint32_t key = co_node_route_id(can->node, i);
        if (key & 0x80000000u) {
            filters[i].can_id = (key & CAN_EFF_MASK) | CAN_EFF_FLAG;
            filters[i].can_mask = CAN_EFF_MASK | CAN_EFF_FLAG;
        } else {
            filters[i].can_id = key & CAN_SFF_MASK;
            filters[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG;
        }
    }
    return setsockopt(can->fd, SOL_CAN_RAW, CAN_RAW_FILTER, count ? filters : NULL,
                      (socklen_t)(count * sizeof filters[0]));
}

static void on_routes_changed(void *ctx)
{
    co_socketcan_t *can = ctx;
    if (can->node != NULL && can->fd >= 0) {
        (void)set_filters(can);
    }
}

co_driver_t co_socketcan_driver(co_socketcan_t *can)
{
    co_driver_t d = {.tx = tx, .on_routes_changed = on_routes_changed, .ctx = can};
    return d;
}

co_err_t co_socketcan_bind(co_socketcan_t *can, co_node_t *node)
{
    if (can == NULL || node == NULL || can->fd < 0) {
        return CO_ERR_ARG;
    }
    can->node = node;
    return set_filters(can) == 0 ? CO_OK : CO_ERR_STATE;
}

static void error_frame(co_socketcan_t *can, const struct can_frame *cf)
{
    can->rx_errors++;
    if (cf->can_id & CAN_ERR_CRTL) {
        uint8_t ctrl = cf->data[1];
        if (ctrl & CAN_ERR_CRTL_RX_OVERFLOW) {
            co_node_bus_event(can->node, CO_BUS_RX_OVERRUN);
        }
        if (ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
            co_node_bus_event(can->node, CO_BUS_ERROR_PASSIVE);
        }
#ifdef CAN_ERR_CRTL_ACTIVE
        if (ctrl & CAN_ERR_CRTL_ACTIVE) {
            co_node_bus_event(can->node, CO_BUS_ERROR_ACTIVE);
        }
#endif
    }
    if (cf->can_id & CAN_ERR_BUSOFF) {
        co_node_bus_event(can->node, CO_BUS_OFF);
    }
    if (cf->can_id & CAN_ERR_RESTARTED) {
        co_node_bus_event(can->node, CO_BUS_OFF_RECOVERED);
    }
}

int co_socketcan_receive(co_socketcan_t *can, uint64_t now_us)
{
    if (can == NULL || can->node == NULL || can->fd < 0) {
        return -1;
    }
    int count = 0;
    for (;;) {
        struct can_frame cf;
        ssize_t n = read(can->fd, &cf, sizeof cf);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return count;
            }
            return -1;
        }
        if (n != (ssize_t)sizeof cf) {
            continue; /* not a classic CAN frame (CAN FD is not enabled): ignore */
        }
        count++;
        if (cf.can_id & CAN_ERR_FLAG) {
            error_frame(can, &cf);
            continue;
        }
        co_frame_t f;
        memset(&f, 0, sizeof f);
        if (cf.can_id & CAN_EFF_FLAG) {
            f.id = cf.can_id & CAN_EFF_MASK;
            f.flags = CO_FRAME_EXT;
        } else {
            f.id = cf.can_id & CAN_SFF_MASK;
        }
        if (cf.can_id & CAN_RTR_FLAG) {
            f.flags |= CO_FRAME_RTR;
        }
        f.len = cf.len > 8 ? 8 : cf.len;
        if (!(f.flags & CO_FRAME_RTR)) {
            memcpy(f.data, cf.data, f.len);
        }
        co_node_ingest(can->node, now_us, &f);
    }
}

int co_socketcan_fd(const co_socketcan_t *can) { return can != NULL ? can->fd : -1; }

void co_socketcan_close(co_socketcan_t *can)
{
    if (can != NULL && can->fd >= 0) {
        close(can->fd);
        can->fd = -1;
    }
    if (can != NULL) {
        can->node = NULL;
    }
}
