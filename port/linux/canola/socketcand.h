/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/socketcand.h -- a CAN transport over TCP to a socketcand server or hub
 * (port/linux).
 *
 * socketcand (github.com/linux-can/socketcand) serves Linux CAN interfaces over TCP in
 * an ASCII protocol; `canola bus serve` (the Python package) speaks the same protocol as
 * a hub without any CAN hardware. Both are named by one URL:
 *
 *     socketcand://HOST:PORT/CHANNEL        e.g. socketcand://127.0.0.1:29536/vcan0
 *
 * (HOST may be a name, an IPv4 address or [an IPv6 address]; PORT defaults to 29536;
 * CHANNEL is the bus name, 1..16 characters.)
 *
 * The client side, as co_socketcand_open runs it (with a time-out):
 *     server: < hi >          client: < open CHANNEL >
 *     server: < ok >          client: < rawmode >
 *     server: < ok >
 * (co_socketcand_open_auth first proves a token, as `canola bus serve --token` asks:
 *     server: < hi >          client: < auth TOKEN >
 *     server: < ok >          client: < open CHANNEL > ...)
 * then, in raw mode, every frame on the bus arrives as
 *     < frame ID SECS.USECS DATA >     ID in hex: 3 digits = 11-bit, 4..8 digits = 29-bit
 *                                       (socketcand writes %03X / %08X); DATA is the bytes
 *                                       in hex, together ("0105") or one per token ("01 05")
 *     < rtr ID SECS.USECS DLC >        a remote frame (the protocol text; socketcand
 *                                       itself does not forward remote frames in raw mode)
 *     < error CLASS SECS.USECS >       an error frame: CLASS is the CAN_ERR_* class bits;
 *                                       bus-off and restarted become bus events
 * and frames are sent as
 *     < send ID LEN B0 B1 ... >        ID as %03X (11-bit) or %08X (29-bit), bytes %02X
 *     < sendrtr ID LEN >               a remote frame (socketcand answers it in raw mode
 *                                       with < error unknown command >: node guarding
 *                                       needs a hub that carries remote frames)
 * Other well-formed messages (< echo >, < stat ... >, < ok >) are counted and ignored; a
 * server error message (< error unknown command >) is counted in server_errors.
 *
 * Robustness: received bytes go through a bounded buffer. Bytes outside < > (other than
 * white space), a message longer than CO_SOCKETCAND_MSG_MAX, or a malformed frame message
 * make the transport fail (CO_RX_ERROR, reason in transport.error): a server that speaks
 * something else is an error, never an overflow. Partial messages wait for the rest.
 * Frames to send go into a bounded output buffer; when it is full, send answers
 * CO_ERR_BUSY and the event loop flushes when the socket is writable.
 *
 * Not part of the portable core: POSIX sockets. Not thread-safe.
 */
#ifndef CANOLA_SOCKETCAND_H
#define CANOLA_SOCKETCAND_H

#include "canola/transport.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CO_SOCKETCAND_PORT 29536u
#define CO_SOCKETCAND_CHANNEL_MAX 16
#define CO_SOCKETCAND_HOST_MAX 255
#define CO_SOCKETCAND_MSG_MAX 256 /**< longest message accepted from the server */
#define CO_SOCKETCAND_RX_BUF 1024
#define CO_SOCKETCAND_TX_BUF 2048
#define CO_SOCKETCAND_TOKEN_MIN 16 /**< a token's length: 16..64 characters of */
#define CO_SOCKETCAND_TOKEN_MAX 64 /**< A-Z a-z 0-9 . _ ~ + / = - */

/** A parsed socketcand://HOST:PORT/CHANNEL. */
typedef struct co_socketcand_url {
    char host[CO_SOCKETCAND_HOST_MAX + 1];
    uint16_t port;
    char channel[CO_SOCKETCAND_CHANNEL_MAX + 1];
} co_socketcand_url_t;

/** What one server message is (co_socketcand_parse). */
typedef enum co_socketcand_msg {
    CO_SCD_BAD = -1,  /**< not a message of the protocol, or a malformed frame */
    CO_SCD_FRAME = 0, /**< < frame ... > or < rtr ... >: *frame filled */
    CO_SCD_EVENTS,    /**< < error CLASS TIME >: *events filled (may be 0) */
    CO_SCD_HI,        /**< < hi > */
    CO_SCD_OK,        /**< < ok > */
    CO_SCD_ERROR,     /**< < error TEXT >: the server refused something */
    CO_SCD_OTHER,     /**< any other well-formed message */
} co_socketcand_msg_t;

typedef struct co_socketcand {
    co_transport_t transport; /**< first: the event loop's view (fd inside) */
    char rx[CO_SOCKETCAND_RX_BUF];
    size_t rx_len;
    char tx[CO_SOCKETCAND_TX_BUF];
    size_t tx_len;
    uint32_t rx_frames;     /**< frames received */
    uint32_t rx_other;      /**< well-formed messages ignored */
    uint32_t server_errors; /**< < error TEXT > messages */
} co_socketcand_t;

/** Parse `url`. Returns CO_ERR_ARG (and a one-line reason in `why`, when not NULL, of
 *  `why_cap` bytes) for anything that is not socketcand://HOST[:PORT]/CHANNEL. */
co_err_t co_socketcand_parse_url(const char *url, co_socketcand_url_t *out, char *why,
                                 size_t why_cap);

/** Connect to the server of `url`, open its channel and switch to raw mode, waiting at
 *  most `timeout_ms` for each step. Returns CO_ERR_ARG for a bad URL, CO_ERR_NOT_FOUND
 *  when the host name does not resolve, CO_ERR_STATE when the connection or the
 *  handshake failed; sc->transport.error says why in every case. */
co_err_t co_socketcand_open(co_socketcand_t *sc, const char *url, unsigned timeout_ms);

/** As co_socketcand_open, proving `token` (NULL or "": none) to the server before the
 *  channel is opened. Returns CO_ERR_ARG for a token that is not one (see
 *  CO_SOCKETCAND_TOKEN_MIN), CO_ERR_STATE when the server refuses it (transport.error
 *  holds the server's words). */
co_err_t co_socketcand_open_auth(co_socketcand_t *sc, const char *url, const char *token,
                                 unsigned timeout_ms);

/** The handshake on an already connected stream socket (takes ownership of `fd`). */
co_err_t co_socketcand_open_fd(co_socketcand_t *sc, int fd, const char *channel,
                               unsigned timeout_ms);

/** The same, proving `token` first (as co_socketcand_open_auth). */
co_err_t co_socketcand_open_fd_auth(co_socketcand_t *sc, int fd, const char *channel,
                                    const char *token, unsigned timeout_ms);

/** Close the connection (safe to call twice). */
void co_socketcand_close(co_socketcand_t *sc);

/** Classify one message `msg` of `len` bytes (from '<' to '>' inclusive) and decode a
 *  frame or error frame. Pure function: the protocol's whole parser. */
co_socketcand_msg_t co_socketcand_parse(const char *msg, size_t len, co_frame_t *frame,
                                        uint32_t *events);

/** Write the send command for `frame` into `buf` (NUL-terminated). Returns its length,
 *  or 0 when `cap` is too small or the frame is not valid (id out of range, len > 8). */
size_t co_socketcand_format(const co_frame_t *frame, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_SOCKETCAND_H */
