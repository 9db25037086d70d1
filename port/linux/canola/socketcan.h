/*
 * canola/socketcan.h -- a CAN driver on Linux SocketCAN (port/linux).
 *
 * One raw CAN socket per node, non-blocking. Frames the node sends go out with write();
 * a full socket send queue (EAGAIN/ENOBUFS) is reported as CO_ERR_BUSY, so the node keeps
 * the frame and retries on its next poll. The kernel filter (CAN_RAW_FILTER) is set to
 * the node's receive routes and reprogrammed whenever they change, so only frames the
 * node listens to wake the process. Controller error frames (overrun, error passive,
 * bus-off, restarted) become co_node_bus_event() calls. The socket does not receive the
 * frames it sent itself (CAN_RAW_RECV_OWN_MSGS off).
 *
 * Use:
 *     co_socketcan_t can;
 *     co_socketcan_open(&can, "can0");
 *     config.driver = co_socketcan_driver(&can);
 *     co_node_init(&node, &config);
 *     co_socketcan_bind(&can, &node);       // filters follow the node's routes
 *     co_node_start(&node, co_linux_now_us());
 *     loop: poll() on co_socketcan_fd(&can) until the node's next deadline, then
 *           co_socketcan_receive(&can, now) and co_node_poll(&node, now).
 *
 * Not part of the portable core: Linux only. Not thread-safe (like the node).
 */
#ifndef CANOLA_SOCKETCAN_H
#define CANOLA_SOCKETCAN_H

#include "canola/config.h"
#include "canola/node.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CO_SOCKETCAN_IFNAME_MAX 16 /* IFNAMSIZ */

typedef struct co_socketcan {
    int fd;          /**< the raw CAN socket, or -1 */
    co_node_t *node; /**< the node frames and bus events go to (co_socketcan_bind) */
    char ifname[CO_SOCKETCAN_IFNAME_MAX];
    uint32_t rx_errors; /**< error frames received */
} co_socketcan_t;

/** Open a raw CAN socket on interface `ifname` (non-blocking, error frames on, own
 *  frames not received, no filter until bound). Returns CO_ERR_ARG for a NULL argument or
 *  a name too long, CO_ERR_NOT_FOUND when there is no such interface, CO_ERR_STATE when
 *  the socket cannot be made (errno tells why). */
co_err_t co_socketcan_open(co_socketcan_t *can, const char *ifname);

/** The driver to put into co_node_config_t.driver. */
co_driver_t co_socketcan_driver(co_socketcan_t *can);

/** Attach the node (after co_node_init) and set the kernel filter to its routes.
 *  Returns CO_ERR_STATE when the filter could not be set. */
co_err_t co_socketcan_bind(co_socketcan_t *can, co_node_t *node);

/** Read every pending frame and hand it to the bound node (error frames as bus events).
 *  Returns the number of frames read (0 when none was pending), or -1 on a socket error
 *  or when no node is bound. */
int co_socketcan_receive(co_socketcan_t *can, uint64_t now_us);

/** The socket, for poll()/epoll (readable: call co_socketcan_receive). */
int co_socketcan_fd(const co_socketcan_t *can);

/** Close the socket (safe to call twice). */
void co_socketcan_close(co_socketcan_t *can);

/** Microseconds of CLOCK_MONOTONIC: the clock to give co_node_poll/co_node_ingest. */
uint64_t co_linux_now_us(void);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_SOCKETCAN_H */
