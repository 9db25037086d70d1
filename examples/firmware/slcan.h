/* SPDX-License-Identifier: Apache-2.0 */
/*
 * slcan.h -- the SLCAN (Lawicel) ASCII protocol, adapter side: what the QEMU examples'
 * stand-in CAN driver speaks over the board's UART, so that python-can's `slcan` interface
 * (and canola's `slcan://` buses, `canola bus bridge`) reach the firmware.
 *
 * The host sends commands, one a line ended by CR: `tIIIL<data>` / `TIIIIIIIIL<data>` a
 * frame onto the bus (11- / 29-bit identifier in hex, length digit 0..8, two hex digits a
 * byte), `rIIIL` / `RIIIIIIIIL` a remote frame, `O` (and `L`, listen only) open the channel,
 * `C` close it, `Sn` a bit rate (0..8: 10 k..1 M), `V` / `v` / `N` / `F` version, serial
 * number, status flags; a few more are taken and ignored (`sXXYY`, `Z`, `M`, `m`, `X`).
 * The adapter answers CR (done) or BEL (refused: an unknown command, a bad frame, a line too
 * long), and sends each frame from the bus as a line of the same form.
 *
 * Pure functions on a caller-owned parser: no hardware, no globals (host-tested).
 */
#ifndef CANOLA_EXAMPLE_SLCAN_H
#define CANOLA_EXAMPLE_SLCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/types.h"

/** The longest line either way: "T" + 8 + 1 + 16 + CR. */
#define SLCAN_LINE_MAX 27u

typedef enum slcan_cmd {
    SLCAN_NONE = 0,   /**< no complete line yet */
    SLCAN_FRAME,      /**< a frame to put on the bus: in *frame */
    SLCAN_OPEN,       /**< O or L */
    SLCAN_CLOSE,      /**< C */
    SLCAN_BIT_RATE,   /**< Sn: the rate in bit/s in *arg */
    SLCAN_VERSION,    /**< V: answer "V" + 4 digits */
    SLCAN_VERSION_FW, /**< v: answer "v" + 4 digits */
    SLCAN_SERIAL,     /**< N: answer "N" + 4 characters */
    SLCAN_STATUS,     /**< F: answer "F" + 2 hex digits of status flags */
    SLCAN_OTHER,      /**< a command taken and ignored: answer CR */
    SLCAN_REFUSED,    /**< answer BEL */
} slcan_cmd_t;

typedef struct slcan_parser {
    char line[SLCAN_LINE_MAX];
    uint8_t len;
    bool overlong; /**< the line outgrew `line`: refused at its CR */
} slcan_parser_t;

/** Take one byte from the host. At a CR, the line's command (SLCAN_NONE before); a frame
 *  goes to *frame, a bit rate to *arg. LF and NUL between lines are skipped. O(1). */
slcan_cmd_t slcan_feed(slcan_parser_t *p, uint8_t byte, co_frame_t *frame, uint32_t *arg);

/** `frame` as a line with its CR into `out` (SLCAN_LINE_MAX bytes); its length. */
uint8_t slcan_format(const co_frame_t *frame, char *out);

#endif /* CANOLA_EXAMPLE_SLCAN_H */
