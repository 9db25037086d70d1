/* SPDX-License-Identifier: Apache-2.0 */
/* slcan_uart.c -- the QEMU examples' stand-in CAN controller over the UART; see slcan_uart.h. */
#include "slcan_uart.h"

#include <string.h>

#include "board.h"
#include "canola/cm_critical.h"

#define NO_MAILBOX SLCAN_UART_MAILBOXES

/* The order frames win the bus in: the lower first (an 11-bit identifier before the 29-bit
 * ones of its base). */
static uint32_t priority(const co_frame_t *f)
{
    if (f->flags & CO_FRAME_EXT) {
        return ((f->id >> 18) & 0x7FFu) << 19 | 1u << 18 | (f->id & 0x3FFFFu);
    }
    return (f->id & 0x7FFu) << 19;
}

/* An answer to a command, sent between frame lines; dropped when the answers fill up (the
 * host asks again). */
static void reply(slcan_uart_t *s, const char *text)
{
    size_t n = strlen(text);
    if (s->reply_len + n <= sizeof s->reply) {
        memcpy(&s->reply[s->reply_len], text, n);
        s->reply_len = (uint8_t)(s->reply_len + n);
    }
}

/* The next line for the UART: the answers first, then the mailbox that wins. */
static bool next_line(slcan_uart_t *s)
{
    s->line_pos = 0;
    s->line_mailbox = NO_MAILBOX;
    if (s->reply_len > 0) {
        memcpy(s->line, s->reply, s->reply_len);
        s->line_len = s->reply_len;
        s->reply_len = 0;
        return true;
    }
    s->line_len = 0;
    if (!s->open) {
        return false;
    }
    uint8_t best = NO_MAILBOX;
    for (uint8_t i = 0; i < SLCAN_UART_MAILBOXES; i++) {
        if (s->put_order[i] == 0) {
            continue;
        }
        if (best == NO_MAILBOX || priority(&s->mailbox[i]) < priority(&s->mailbox[best]) ||
            (priority(&s->mailbox[i]) == priority(&s->mailbox[best]) &&
             (int32_t)(s->put_order[i] - s->put_order[best]) < 0)) {
            best = i;
        }
    }
    if (best == NO_MAILBOX) {
        return false;
    }
    s->line_len = slcan_format(&s->mailbox[best], s->line);
    s->line_mailbox = best;
    return true;
}

/* Hand the UART what it takes now; a mailbox whose line has left is free. The critical
 * section is held, or this is the UART's interrupt. */
static void pump(slcan_uart_t *s)
{
    for (;;) {
        if (s->line_pos == s->line_len) {
            if (s->line_mailbox != NO_MAILBOX) {
                s->put_order[s->line_mailbox] = 0;
                s->freed++;
            }
            if (!next_line(s)) {
                break;
            }
        }
        if (!board_uart_tx_ready()) {
            board_uart_tx_irq(true);
            return;
        }
        board_uart_tx((uint8_t)s->line[s->line_pos++]);
    }
    board_uart_tx_irq(false);
    if (s->freed > 0) {
        board_uart_pend(); /* its transmit-complete report comes from the interrupt */
    }
}

static bool mailbox_put(void *hw, const co_frame_t *frame)
{
    slcan_uart_t *s = hw;
    for (uint8_t i = 0; i < SLCAN_UART_MAILBOXES; i++) {
        if (s->put_order[i] == 0) {
            s->mailbox[i] = *frame;
            if (++s->puts == 0) {
                s->puts = 1; /* 0 marks a free mailbox */
            }
            s->put_order[i] = s->puts;
            pump(s);
            return true;
        }
    }
    return false;
}

static bool set_filters(void *hw, const uint32_t *ids, size_t n)
{
    (void)hw;
    (void)ids;
    (void)n;
    return false; /* none: every frame is received, the node's routes sort them */
}

static co_err_t set_bit_rate(void *hw, uint32_t bit_rate)
{
    if (bit_rate < 10000u || bit_rate > 1000000u) {
        return CO_ERR_ARG;
    }
    ((slcan_uart_t *)hw)->bit_rate = bit_rate;
    return CO_OK;
}

static void error_counters(void *hw, uint8_t *tec, uint8_t *rec)
{
    (void)hw;
    *tec = 0; /* a UART has no bus errors */
    *rec = 0;
}

const co_cm_can_ops_t slcan_uart_ops = {
    .mailbox_put = mailbox_put,
    .set_filters = set_filters,
    .set_bit_rate = set_bit_rate,
    .error_counters = error_counters,
};

/* F: the status flags; bit 1, "transmit FIFO full", while every mailbox is taken. */
static void reply_status(slcan_uart_t *s)
{
    static const char hex[] = "0123456789ABCDEF";
    bool full = true;
    for (uint8_t i = 0; i < SLCAN_UART_MAILBOXES; i++) {
        full = full && s->put_order[i] != 0;
    }
    char text[5] = {'F', '0', hex[full ? 2 : 0], '\r', '\0'};
    reply(s, text);
}

static void command(slcan_uart_t *s, slcan_cmd_t cmd, const co_frame_t *frame, uint32_t arg)
{
    switch (cmd) {
    case SLCAN_NONE:
        break;
    case SLCAN_FRAME:
        if (s->open) {
            co_cm_isr_rx(s->port, frame);
        } else {
            s->refused++;
            reply(s, "\a");
        }
        break;
    case SLCAN_OPEN:
        s->open = true;
        reply(s, "\r");
        break;
    case SLCAN_CLOSE:
        s->open = false;
        reply(s, "\r");
        break;
    case SLCAN_BIT_RATE:
        s->bit_rate = arg;
        reply(s, "\r");
        break;
    case SLCAN_VERSION:
        reply(s, "V0101\r");
        break;
    case SLCAN_VERSION_FW:
        reply(s, "v0101\r");
        break;
    case SLCAN_SERIAL:
        reply(s, "NCNLA\r");
        break;
    case SLCAN_STATUS:
        reply_status(s);
        break;
    case SLCAN_OTHER:
        reply(s, "\r");
        break;
    case SLCAN_REFUSED:
        s->refused++;
        reply(s, "\a");
        break;
    }
}

void slcan_uart_init(slcan_uart_t *s, co_cm_port_t *port)
{
    memset(s, 0, sizeof *s);
    s->port = port;
    s->open = true;
    s->line_mailbox = NO_MAILBOX;
}

void slcan_uart_isr(slcan_uart_t *s)
{
    uint8_t byte;
    co_frame_t frame;
    uint32_t arg = 0;
    while (board_uart_rx(&byte)) {
        command(s, slcan_feed(&s->parser, byte, &frame, &arg), &frame, arg);
    }
    pump(s);
    uint8_t freed = s->freed;
    s->freed = 0;
    while (freed-- > 0) {
        co_cm_isr_tx_done(s->port);
    }
}

void slcan_uart_poll(slcan_uart_t *s)
{
    co_cm_irq_t irq = co_cm_critical_enter();
    pump(s);
    co_cm_critical_leave(irq);
}
