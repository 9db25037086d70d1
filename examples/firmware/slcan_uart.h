/* SPDX-License-Identifier: Apache-2.0 */
/*
 * slcan_uart.h -- the QEMU examples' CAN controller: a stand-in that carries frames over the
 * board's UART in the SLCAN protocol (slcan.h), driven as a register-level CAN driver is
 * (canola/cm_can.h's co_cm_can_ops_t and interrupt calls), so that the port above it runs as
 * on a real controller.
 *
 * Three transmit mailboxes. A frame put into one waits for the UART; the UART sends the
 * lines one at a time, the highest priority first (lowest identifier, then the order put),
 * and a mailbox is free again once its line has left: the UART interrupt then reports it
 * (co_cm_isr_tx_done), as a transmit-complete interrupt would. Received lines become frames
 * for co_cm_isr_rx. The channel is open from reset ("on the bus"); C closes it (frames wait
 * in the mailboxes, none are received), O opens it. No acceptance filters (set_filters
 * answers false: the node's routes filter); bit rates are taken and reported by F's flags.
 *
 * Threading: ops with the port's critical section held (cm_can.h); slcan_uart_isr from the
 * UART's interrupt; slcan_uart_poll from the main loop.
 */
#ifndef CANOLA_EXAMPLE_SLCAN_UART_H
#define CANOLA_EXAMPLE_SLCAN_UART_H

#include "canola/cm_port.h"
#include "slcan.h"

#define SLCAN_UART_MAILBOXES 3u
#define SLCAN_UART_REPLY_MAX 24u

typedef struct slcan_uart {
    co_cm_port_t *port;
    slcan_parser_t parser;
    co_frame_t mailbox[SLCAN_UART_MAILBOXES];
    uint32_t put_order[SLCAN_UART_MAILBOXES]; /* 0: free */
    uint32_t puts;                            /* mailbox puts so far: the next order */
    char line[SLCAN_LINE_MAX];                /* on the UART now */
    uint8_t line_len;
    uint8_t line_pos;
    uint8_t line_mailbox;             /* whose line (SLCAN_UART_MAILBOXES: a reply) */
    uint8_t freed;                    /* mailboxes emptied, their interrupt calls not made yet */
    char reply[SLCAN_UART_REPLY_MAX]; /* answers to commands, sent between lines */
    uint8_t reply_len;
    bool open;
    uint32_t bit_rate;
    uint32_t refused; /* lines answered BEL */
} slcan_uart_t;

/** The driver's operations (hw = the slcan_uart_t). */
extern const co_cm_can_ops_t slcan_uart_ops;

/** Ready, channel open, for `port` (whose interrupt calls it makes). */
void slcan_uart_init(slcan_uart_t *s, co_cm_port_t *port);

/** The UART's interrupt: received bytes, the next bytes out, freed mailboxes reported. */
void slcan_uart_isr(slcan_uart_t *s);

/** The main loop's check: a transmission that waits for an interrupt the UART did not raise
 *  goes on. */
void slcan_uart_poll(slcan_uart_t *s);

#endif /* CANOLA_EXAMPLE_SLCAN_UART_H */
