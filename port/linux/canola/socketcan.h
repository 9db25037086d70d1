/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/socketcan.h -- a CAN driver on Linux SocketCAN (port/linux).
 *
 * One raw CAN socket per node, non-blocking. Frames the node sends go out with write();
 * a full socket send queue (EAGAIN/ENOBUFS) is reported as CO_ERR_BUSY, so the node keeps
 * the frame and retries on its next poll. The kernel filter (CAN_RAW_FILTER) is set to
 * the node's receive routes and reprogrammed whenever they change, so only frames the
 * node listens to wake the process. Controller error frames (overrun, error passive,
 * back to error active, bus-off, restarted) become co_node_bus_event() calls
 * (co_socketcan_error_events is that mapping). The socket does not receive the frames it
 * sent itself (CAN_RAW_RECV_OWN_MSGS off); other sockets on the interface do.
 *
 * It is also a co_transport_t (canola/transport.h) for the event loop
 * (canola/linux_loop.h), which is the easy way to run it:
 *     co_socketcan_t can;
 *     co_socketcan_open(&can, "can0");
 *     co_loop_add_node(&loop, &node, &config, &can.transport);
 *
 * Or by hand:
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
#include "canola/transport.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CO_SOCKETCAN_IFNAME_MAX 16 /* IFNAMSIZ */

typedef struct co_socketcan {
    co_transport_t transport; /**< first: the event loop's view (fd inside) */
    co_node_t *node;          /**< the node frames and bus events go to (co_socketcan_bind) */
    char ifname[CO_SOCKETCAN_IFNAME_MAX];
    bool is_can;        /**< a CAN socket (filters apply); false for co_socketcan_open_fd */
    uint32_t rx_errors; /**< error frames received */
} co_socketcan_t;

/** Open a raw CAN socket on interface `ifname` (non-blocking, error frames on, own
 *  frames not received, no filter until bound). Returns CO_ERR_ARG for a NULL argument or
 *  a name too long, CO_ERR_NOT_FOUND when there is no such interface, CO_ERR_STATE when
 *  the socket cannot be made (errno tells why, and so does can->transport.error). */
co_err_t co_socketcan_open(co_socketcan_t *can, const char *ifname);

/** Use an fd that already carries frames in SocketCAN's `struct can_frame` layout, one
 *  per packet (for example one end of a SOCK_SEQPACKET socketpair: a two-station bus in
 *  a test without CAN). Made non-blocking; no kernel filter. Takes ownership of `fd`.
 *  Returns CO_ERR_ARG for a NULL `can` or a negative fd. */
co_err_t co_socketcan_open_fd(co_socketcan_t *can, int fd);

/** The driver to put into co_node_config_t.driver (not needed with the event loop). */
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

/** The bus events an error frame reports (its can_id with CAN_ERR_FLAG, its 8 data
 *  bytes), as bits (1u << co_bus_event_t): CAN_ERR_CRTL with RX/TX overflow ->
 *  CO_BUS_RX_OVERRUN, RX/TX passive -> CO_BUS_ERROR_PASSIVE, CAN_ERR_CRTL_ACTIVE ->
 *  CO_BUS_ERROR_ACTIVE; CAN_ERR_BUSOFF -> CO_BUS_OFF; CAN_ERR_RESTARTED ->
 *  CO_BUS_OFF_RECOVERED. 0 for a frame that is not an error frame or reports nothing
 *  the node cares about (warnings, protocol errors). Pure function. */
uint32_t co_socketcan_error_events(uint32_t can_id, const uint8_t data[8]);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_SOCKETCAN_H */
