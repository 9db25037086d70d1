/* SPDX-License-Identifier: Apache-2.0 */
/* slcan.c -- the SLCAN (Lawicel) line protocol, adapter side; see slcan.h. */
#include "slcan.h"

static const char k_hex[] = "0123456789ABCDEF";

/* The CiA 301 rates of S0..S8 (SLCAN's own table). */
static const uint32_t k_rates[] = {10000,  20000,  50000,  100000, 125000,
                                   250000, 500000, 800000, 1000000};

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    return -1;
}

/* `n` hex digits from `s`, or -1 when one is not. */
static int64_t hex_value(const char *s, unsigned n)
{
    int64_t v = 0;
    for (unsigned i = 0; i < n; i++) {
        int d = hex_digit(s[i]);
        if (d < 0) {
            return -1;
        }
        v = (v << 4) | d;
    }
    return v;
}

/* A frame line (t, T, r, R) of `len` characters without its CR. */
static bool parse_frame(const char *s, uint8_t len, co_frame_t *frame)
{
    bool ext = s[0] == 'T' || s[0] == 'R';
    bool rtr = s[0] == 'r' || s[0] == 'R';
    unsigned id_digits = ext ? 8u : 3u;
    if (len < 2u + id_digits) {
        return false;
    }
    int64_t id = hex_value(s + 1, id_digits);
    int dlc = s[1 + id_digits] - '0';
    if (id < 0 || id > (ext ? (int64_t)CO_ID_EXT_MAX : (int64_t)CO_ID_STD_MAX) || dlc < 0 ||
        dlc > (int)CO_FRAME_DATA_MAX || len != 2u + id_digits + (rtr ? 0u : 2u * (unsigned)dlc)) {
        return false;
    }
    frame->id = (uint32_t)id;
    frame->flags = (uint8_t)((ext ? CO_FRAME_EXT : 0u) | (rtr ? CO_FRAME_RTR : 0u));
    frame->len = (uint8_t)dlc;
    for (int i = 0; i < dlc && !rtr; i++) {
        int64_t b = hex_value(s + 2 + id_digits + 2 * i, 2);
        if (b < 0) {
            return false;
        }
        frame->data[i] = (uint8_t)b;
    }
    return true;
}

static slcan_cmd_t parse_line(const char *s, uint8_t len, co_frame_t *frame, uint32_t *arg)
{
    if (len == 0) {
        return SLCAN_NONE; /* hosts send a few CRs to flush the line: no answer */
    }
    switch (s[0]) {
    case 't':
    case 'T':
    case 'r':
    case 'R':
        return parse_frame(s, len, frame) ? SLCAN_FRAME : SLCAN_REFUSED;
    case 'S':
        if (len == 2 && s[1] >= '0' && s[1] <= '8') {
            *arg = k_rates[s[1] - '0'];
            return SLCAN_BIT_RATE;
        }
        return SLCAN_REFUSED;
    case 'O':
    case 'L':
        return len == 1 ? SLCAN_OPEN : SLCAN_REFUSED;
    case 'C':
        return len == 1 ? SLCAN_CLOSE : SLCAN_REFUSED;
    case 'V':
        return len == 1 ? SLCAN_VERSION : SLCAN_REFUSED;
    case 'v':
        return len == 1 ? SLCAN_VERSION_FW : SLCAN_REFUSED;
    case 'N':
        return len == 1 ? SLCAN_SERIAL : SLCAN_REFUSED;
    case 'F':
        return len == 1 ? SLCAN_STATUS : SLCAN_REFUSED;
    case 's': /* BTR0/BTR1 of an SJA1000: taken, the rate stays */
        return len == 5 && hex_value(s + 1, 4) >= 0 ? SLCAN_OTHER : SLCAN_REFUSED;
    case 'Z': /* time stamps on/off, acceptance code and mask, auto-poll: taken */
    case 'M':
    case 'm':
    case 'X':
        return SLCAN_OTHER;
    default:
        return SLCAN_REFUSED;
    }
}

slcan_cmd_t slcan_feed(slcan_parser_t *p, uint8_t byte, co_frame_t *frame, uint32_t *arg)
{
    if (byte == '\r') {
        slcan_cmd_t cmd = p->overlong ? SLCAN_REFUSED : parse_line(p->line, p->len, frame, arg);
        p->len = 0;
        p->overlong = false;
        return cmd;
    }
    if ((byte == '\n' || byte == '\0') && p->len == 0) {
        return SLCAN_NONE;
    }
    if (p->len < SLCAN_LINE_MAX) {
        p->line[p->len++] = (char)byte;
    } else {
        p->overlong = true;
    }
    return SLCAN_NONE;
}

uint8_t slcan_format(const co_frame_t *frame, char *out)
{
    bool ext = (frame->flags & CO_FRAME_EXT) != 0;
    bool rtr = (frame->flags & CO_FRAME_RTR) != 0;
    unsigned id_digits = ext ? 8u : 3u;
    uint8_t len = frame->len <= CO_FRAME_DATA_MAX ? frame->len : (uint8_t)CO_FRAME_DATA_MAX;
    uint8_t n = 0;
    out[n++] = rtr ? (ext ? 'R' : 'r') : (ext ? 'T' : 't');
    for (unsigned i = id_digits; i-- > 0;) {
        out[n++] = k_hex[(frame->id >> (4 * i)) & 0xFu];
    }
    out[n++] = (char)('0' + len);
    for (uint8_t i = 0; i < len && !rtr; i++) {
        out[n++] = k_hex[frame->data[i] >> 4];
        out[n++] = k_hex[frame->data[i] & 0xFu];
    }
    out[n++] = '\r';
    return n;
}
