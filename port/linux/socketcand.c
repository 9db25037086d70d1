/* SPDX-License-Identifier: Apache-2.0 */
/* socketcand.c -- CAN over TCP in socketcand's ASCII protocol; see canola/socketcand.h. */
#define _GNU_SOURCE

#include "canola/socketcand.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* The CAN_ERR_* class bits of linux/can/error.h that matter here (kept local: the
 * protocol carries numbers, whatever the host's headers). */
#define ERR_CLASS_BUSOFF 0x40u
#define ERR_CLASS_RESTARTED 0x100u

/* ---- URL */

static void why_set(char *why, size_t cap, const char *text)
{
    if (why != NULL && cap > 0) {
        (void)snprintf(why, cap, "%s", text);
    }
}

co_err_t co_socketcand_parse_url(const char *url, co_socketcand_url_t *out, char *why,
                                 size_t why_cap)
{
    static const char scheme[] = "socketcand://";
    if (url == NULL || out == NULL) {
        why_set(why, why_cap, "no URL");
        return CO_ERR_ARG;
    }
    memset(out, 0, sizeof *out);
    if (strncmp(url, scheme, sizeof scheme - 1) != 0) {
        why_set(why, why_cap, "not a socketcand:// URL");
        return CO_ERR_ARG;
    }
    const char *p = url + sizeof scheme - 1;
    const char *host = p;
    size_t host_len;
    if (*p == '[') { /* [IPv6] */
        const char *end = strchr(p, ']');
        if (end == NULL) {
            why_set(why, why_cap, "unclosed [ in the host");
            return CO_ERR_ARG;
        }
        host = p + 1;
        host_len = (size_t)(end - host);
        p = end + 1;
    } else {
        host_len = strcspn(p, ":/");
        p += host_len;
    }
    if (host_len == 0 || host_len > CO_SOCKETCAND_HOST_MAX) {
        why_set(why, why_cap, host_len ? "host name too long" : "no host");
        return CO_ERR_ARG;
    }
    memcpy(out->host, host, host_len);
    out->port = (uint16_t)CO_SOCKETCAND_PORT;
    if (*p == ':') {
        p++;
        unsigned long port = 0;
        size_t digits = 0;
        while (*p >= '0' && *p <= '9' && digits < 6) {
            port = port * 10u + (unsigned long)(*p - '0');
            p++;
            digits++;
        }
        if (digits == 0 || port == 0 || port > 65535u) {
            why_set(why, why_cap, "port must be 1..65535");
            return CO_ERR_ARG;
        }
        out->port = (uint16_t)port;
    }
    if (*p != '/') {
        why_set(why, why_cap, "expected /CHANNEL after the host");
        return CO_ERR_ARG;
    }
    p++;
    size_t ch_len = strlen(p);
    if (ch_len == 0 || ch_len > CO_SOCKETCAND_CHANNEL_MAX) {
        why_set(why, why_cap, "channel must be 1..16 characters");
        return CO_ERR_ARG;
    }
    for (size_t i = 0; i < ch_len; i++) {
        unsigned char c = (unsigned char)p[i];
        if (c <= ' ' || c == '<' || c == '>' || c == '/' || c >= 0x7F) {
            why_set(why, why_cap, "channel has a character the protocol cannot carry");
            return CO_ERR_ARG;
        }
    }
    memcpy(out->channel, p, ch_len);
    return CO_OK;
}

/* ---- parsing one message */

#define TOKENS_MAX 16

typedef struct token {
    const char *s;
    size_t n;
} token_t;

static int hexval(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

static bool parse_hex(token_t t, size_t max_digits, uint32_t *out)
{
    if (t.n == 0 || t.n > max_digits) {
        return false;
    }
    uint32_t v = 0;
    for (size_t i = 0; i < t.n; i++) {
        int h = hexval(t.s[i]);
        if (h < 0) {
            return false;
        }
        v = (v << 4) | (uint32_t)h;
    }
    *out = v;
    return true;
}

static bool tok_is(token_t t, const char *word)
{
    return t.n == strlen(word) && memcmp(t.s, word, t.n) == 0;
}

/* SECS.USECS (digits, at most one dot). */
static bool is_time(token_t t)
{
    int dots = 0;
    size_t digits = 0;
    for (size_t i = 0; i < t.n; i++) {
        if (t.s[i] == '.') {
            dots++;
        } else if (t.s[i] >= '0' && t.s[i] <= '9') {
            digits++;
        } else {
            return false;
        }
    }
    return digits > 0 && dots <= 1;
}

/* 1..3 hex digits: 11-bit; 4..8: 29-bit (socketcand pads to 3 and 8). */
static bool parse_id(token_t t, co_frame_t *f)
{
    uint32_t id;
    if (!parse_hex(t, 8, &id)) {
        return false;
    }
    if (t.n <= 3) {
        if (id > CO_ID_STD_MAX) {
            return false;
        }
        f->flags = 0;
    } else {
        if (id > CO_ID_EXT_MAX) {
            return false;
        }
        f->flags = CO_FRAME_EXT;
    }
    f->id = id;
    return true;
}

static co_socketcand_msg_t parse_frame(const token_t *tok, int n, co_frame_t *f)
{
    memset(f, 0, sizeof *f);
    if (n < 3 || !parse_id(tok[1], f) || !is_time(tok[2])) {
        return CO_SCD_BAD;
    }
    size_t len = 0;
    for (int i = 3; i < n; i++) {
        size_t bytes = tok[i].n == 1 ? 1 : tok[i].n / 2;
        if (tok[i].n == 0 || (tok[i].n > 1 && tok[i].n % 2 != 0) || len + bytes > 8) {
            return CO_SCD_BAD;
        }
        for (size_t b = 0; b < bytes; b++) {
            uint32_t v;
            token_t two = {tok[i].s + (tok[i].n == 1 ? 0 : 2 * b), tok[i].n == 1 ? 1 : 2};
            if (!parse_hex(two, 2, &v)) {
                return CO_SCD_BAD;
            }
            f->data[len++] = (uint8_t)v;
        }
    }
    f->len = (uint8_t)len;
    return CO_SCD_FRAME;
}

co_socketcand_msg_t co_socketcand_parse(const char *msg, size_t len, co_frame_t *frame,
                                        uint32_t *events)
{
    if (len < 2 || msg[0] != '<' || msg[len - 1] != '>') {
        return CO_SCD_BAD;
    }
    token_t tok[TOKENS_MAX];
    int n = 0;
    for (size_t i = 1; i + 1 < len;) {
        char c = msg[i];
        if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
            i++;
            continue;
        }
        if ((unsigned char)c < 0x20 || (unsigned char)c >= 0x7F || c == '<') {
            return CO_SCD_BAD;
        }
        if (n == TOKENS_MAX) {
            return CO_SCD_BAD;
        }
        size_t start = i;
        while (i + 1 < len && msg[i] != ' ' && msg[i] != '\t' && msg[i] != '\r' && msg[i] != '\n') {
            if ((unsigned char)msg[i] < 0x20 || (unsigned char)msg[i] >= 0x7F || msg[i] == '<') {
                return CO_SCD_BAD;
            }
            i++;
        }
        tok[n++] = (token_t){msg + start, i - start};
    }
    if (n == 0) {
        return CO_SCD_BAD;
    }
    if (tok_is(tok[0], "frame")) {
        return parse_frame(tok, n, frame);
    }
    if (tok_is(tok[0], "rtr")) {
        uint32_t dlc;
        memset(frame, 0, sizeof *frame);
        if (n != 4 || !parse_id(tok[1], frame) || !is_time(tok[2]) || !parse_hex(tok[3], 1, &dlc) ||
            dlc > 8) {
            return CO_SCD_BAD;
        }
        frame->flags |= CO_FRAME_RTR;
        frame->len = (uint8_t)dlc;
        return CO_SCD_FRAME;
    }
    if (tok_is(tok[0], "error")) {
        uint32_t cls;
        if (n == 3 && parse_hex(tok[1], 8, &cls) && is_time(tok[2])) {
            uint32_t ev = 0;
            if (cls & ERR_CLASS_BUSOFF) {
                ev |= 1u << CO_BUS_OFF;
            }
            if (cls & ERR_CLASS_RESTARTED) {
                ev |= 1u << CO_BUS_OFF_RECOVERED;
            }
            *events = ev;
            return CO_SCD_EVENTS;
        }
        return CO_SCD_ERROR;
    }
    if (n == 1 && tok_is(tok[0], "hi")) {
        return CO_SCD_HI;
    }
    if (n == 1 && tok_is(tok[0], "ok")) {
        return CO_SCD_OK;
    }
    return CO_SCD_OTHER;
}

size_t co_socketcand_format(const co_frame_t *frame, char *buf, size_t cap)
{
    bool ext = (frame->flags & CO_FRAME_EXT) != 0;
    if (frame->len > 8 || frame->id > (ext ? CO_ID_EXT_MAX : CO_ID_STD_MAX) || cap == 0) {
        return 0;
    }
    int n;
    if (frame->flags & CO_FRAME_RTR) {
        n = snprintf(buf, cap, ext ? "< sendrtr %08X %u >" : "< sendrtr %03X %u >",
                     (unsigned)frame->id, (unsigned)frame->len);
    } else {
        /* " XX" a byte, written by hand: snprintf here is a -Wformat-truncation false
         * positive of gcc -O3 (it loses the len <= 8 check above), an error with -Werror. */
        static const char hex[] = "0123456789ABCDEF";
        char data[8 * 3 + 1];
        size_t k = 0;
        for (unsigned i = 0; i < frame->len; i++) {
            data[k++] = ' ';
            data[k++] = hex[frame->data[i] >> 4];
            data[k++] = hex[frame->data[i] & 0x0Fu];
        }
        data[k] = '\0';
        n = snprintf(buf, cap, ext ? "< send %08X %u%s >" : "< send %03X %u%s >",
                     (unsigned)frame->id, (unsigned)frame->len, data);
    }
    if (n < 0 || (size_t)n >= cap) {
        buf[0] = '\0';
        return 0;
    }
    return (size_t)n;
}

/* ---- the receive buffer */

typedef enum take {
    TAKE_NONE,  /* no whole message buffered */
    TAKE_MSG,   /* one message: at 0, *len bytes */
    TAKE_ERROR, /* garbage or over-long: transport.error says which */
} take_t;

/* Find the first whole message in the buffer. */
static take_t take_message(co_socketcand_t *sc, size_t *start, size_t *len)
{
    size_t i = 0;
    while (i < sc->rx_len &&
           (sc->rx[i] == ' ' || sc->rx[i] == '\t' || sc->rx[i] == '\r' || sc->rx[i] == '\n')) {
        i++;
    }
    if (i > 0) { /* drop the white space between messages */
        memmove(sc->rx, sc->rx + i, sc->rx_len - i);
        sc->rx_len -= i;
    }
    if (sc->rx_len == 0) {
        return TAKE_NONE;
    }
    if (sc->rx[0] != '<') {
        unsigned char c = (unsigned char)sc->rx[0];
        co_transport_fail(&sc->transport, "socketcand: garbage from the server (byte 0x%02X)", c);
        return TAKE_ERROR;
    }
    const char *end = memchr(sc->rx, '>', sc->rx_len);
    size_t have = end != NULL ? (size_t)(end - sc->rx) + 1 : sc->rx_len;
    if (have > CO_SOCKETCAND_MSG_MAX) {
        co_transport_fail(&sc->transport, "socketcand: message longer than %d bytes",
                          CO_SOCKETCAND_MSG_MAX);
        return TAKE_ERROR;
    }
    if (end == NULL) {
        return TAKE_NONE; /* partial: wait for the rest */
    }
    *start = 0;
    *len = have;
    return TAKE_MSG;
}

static void consume(co_socketcand_t *sc, size_t len)
{
    memmove(sc->rx, sc->rx + len, sc->rx_len - len);
    sc->rx_len -= len;
}

/* Read what the socket has into the buffer: 1 read something, 0 nothing now, -1 failed. */
static int fill(co_socketcand_t *sc)
{
    size_t room = sizeof sc->rx - sc->rx_len;
    if (room == 0) {
        return 0; /* take_message reports the over-long message first */
    }
    for (;;) {
        ssize_t n = read(sc->transport.fd, sc->rx + sc->rx_len, room);
        if (n > 0) {
            sc->rx_len += (size_t)n;
            return 1;
        }
        if (n == 0) {
            co_transport_fail(&sc->transport, "socketcand: the server closed the connection");
            return -1;
        }
        if (errno == EINTR) {
            continue;
        }
        if (errno == EAGAIN || errno == EWOULDBLOCK) {
            return 0;
        }
        co_transport_fail(&sc->transport, "socketcand: read: %s", strerror(errno));
        return -1;
    }
}

static co_rx_t sd_recv(co_transport_t *t, co_frame_t *frame, uint32_t *events)
{
    co_socketcand_t *sc = (co_socketcand_t *)t;
    for (;;) {
        size_t start, len;
        take_t k = take_message(sc, &start, &len);
        if (k == TAKE_ERROR) {
            return CO_RX_ERROR;
        }
        if (k == TAKE_NONE) {
            int r = fill(sc);
            if (r < 0) {
                return CO_RX_ERROR;
            }
            if (r == 0) {
                return CO_RX_AGAIN;
            }
            continue;
        }
        co_socketcand_msg_t m = co_socketcand_parse(sc->rx + start, len, frame, events);
        if (m == CO_SCD_BAD) {
            co_transport_fail(t, "socketcand: malformed message '%.*s'", (int)(len > 80 ? 80 : len),
                              sc->rx + start);
            return CO_RX_ERROR;
        }
        consume(sc, len);
        switch (m) {
        case CO_SCD_FRAME:
            sc->rx_frames++;
            return CO_RX_FRAME;
        case CO_SCD_EVENTS:
            if (*events != 0) {
                return CO_RX_EVENTS;
            }
            break;
        case CO_SCD_ERROR:
            sc->server_errors++;
            break;
        default:
            sc->rx_other++;
            break;
        }
    }
}

static bool sd_buffered(const co_transport_t *t)
{
    const co_socketcand_t *sc = (const co_socketcand_t *)t;
    return memchr(sc->rx, '>', sc->rx_len) != NULL ||
           (sc->rx_len > 0 && sc->rx[0] != '<' && sc->rx[0] != ' ' && sc->rx[0] != '\n');
}

static co_err_t sd_flush(co_transport_t *t)
{
    co_socketcand_t *sc = (co_socketcand_t *)t;
    size_t off = 0;
    while (off < sc->tx_len) {
        ssize_t n = send(t->fd, sc->tx + off, sc->tx_len - off, MSG_NOSIGNAL);
        if (n > 0) {
            off += (size_t)n;
            continue;
        }
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            break;
        }
        co_transport_fail(t, "socketcand: write: %s", n < 0 ? strerror(errno) : "nothing written");
        return CO_ERR_STATE;
    }
    memmove(sc->tx, sc->tx + off, sc->tx_len - off);
    sc->tx_len -= off;
    return sc->tx_len == 0 ? CO_OK : CO_ERR_BUSY;
}

static bool sd_pending(const co_transport_t *t) { return ((const co_socketcand_t *)t)->tx_len > 0; }

static co_err_t sd_send(co_transport_t *t, const co_frame_t *frame)
{
    co_socketcand_t *sc = (co_socketcand_t *)t;
    char line[64];
    size_t n = co_socketcand_format(frame, line, sizeof line);
    if (n == 0) {
        return CO_ERR_ARG; /* not a frame the protocol can carry: dropped by the node */
    }
    if (sc->tx_len + n > sizeof sc->tx) {
        if (sd_flush(t) == CO_ERR_STATE) {
            return CO_ERR_STATE;
        }
        if (sc->tx_len + n > sizeof sc->tx) {
            return CO_ERR_BUSY;
        }
    }
    memcpy(sc->tx + sc->tx_len, line, n);
    sc->tx_len += n;
    return sd_flush(t) == CO_ERR_STATE ? CO_ERR_STATE : CO_OK; /* buffered counts as taken */
}

static void sd_close(co_transport_t *t)
{
    if (t->fd >= 0) {
        close(t->fd);
        t->fd = -1;
    }
}

static const co_transport_ops_t sd_ops = {.recv = sd_recv,
                                          .send = sd_send,
                                          .pending = sd_pending,
                                          .buffered = sd_buffered,
                                          .flush = sd_flush,
                                          .close = sd_close};

void co_socketcand_close(co_socketcand_t *sc)
{
    if (sc != NULL) {
        sd_close(&sc->transport);
    }
}

/* ---- handshake */

static uint64_t now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

/* Wait for `events` on the fd until `end_ms`: 1 ready, 0 timed out, -1 failed. */
static int wait_fd(int fd, short events, uint64_t end_ms)
{
    for (;;) {
        uint64_t now = now_ms();
        if (now >= end_ms) {
            return 0;
        }
        struct pollfd p = {.fd = fd, .events = events};
        int r = poll(&p, 1, (int)(end_ms - now));
        if (r < 0 && errno == EINTR) {
            continue;
        }
        return r < 0 ? -1 : r > 0 ? 1 : 0;
    }
}

/* The next message of the handshake, which must be `want` (< hi > or < ok >): frames,
 * echo and stat before it are dropped; anything else fails the handshake, saying why. */
static co_socketcand_msg_t expect(co_socketcand_t *sc, co_socketcand_msg_t want, const char *what,
                                  uint64_t end_ms)
{
    for (;;) {
        size_t start, len;
        take_t k = take_message(sc, &start, &len);
        if (k == TAKE_ERROR) {
            return CO_SCD_BAD;
        }
        if (k == TAKE_MSG) {
            co_frame_t f;
            uint32_t ev = 0;
            co_socketcand_msg_t m = co_socketcand_parse(sc->rx + start, len, &f, &ev);
            if (m == CO_SCD_BAD || m == CO_SCD_ERROR ||
                ((m == CO_SCD_HI || m == CO_SCD_OK) && m != want)) {
                co_transport_fail(&sc->transport, "socketcand: expected %s, the server said '%.*s'",
                                  what, (int)(len > 80 ? 80 : len), sc->rx + start);
                return CO_SCD_BAD;
            }
            consume(sc, len);
            if (m == want) {
                return m;
            }
            continue; /* frames, echo, stat: not the answer yet */
        }
        int w = wait_fd(sc->transport.fd, POLLIN, end_ms);
        if (w == 0) {
            co_transport_fail(&sc->transport, "socketcand: timed out waiting for %s", what);
            return CO_SCD_BAD;
        }
        if (w < 0 || fill(sc) < 0) {
            if (w < 0) {
                co_transport_fail(&sc->transport, "socketcand: %s", strerror(errno));
            }
            return CO_SCD_BAD;
        }
    }
}

static bool say(co_socketcand_t *sc, const char *text, uint64_t end_ms)
{
    size_t n = strlen(text);
    memcpy(sc->tx, text, n);
    sc->tx_len = n;
    for (;;) {
        co_err_t rc = sd_flush(&sc->transport);
        if (rc == CO_OK) {
            return true;
        }
        if (rc == CO_ERR_STATE || wait_fd(sc->transport.fd, POLLOUT, end_ms) <= 0) {
            if (rc != CO_ERR_STATE) {
                co_transport_fail(&sc->transport, "socketcand: timed out sending '%s'", text);
            }
            return false;
        }
    }
}

static void sd_init(co_socketcand_t *sc)
{
    memset(sc, 0, sizeof *sc);
    sc->transport.ops = &sd_ops;
    sc->transport.fd = -1;
}

/* Whether `token` is one a hub takes (none is NULL or ""). */
static bool token_ok(const char *token)
{
    size_t n = strlen(token);
    if (n < CO_SOCKETCAND_TOKEN_MIN || n > CO_SOCKETCAND_TOKEN_MAX) {
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        char c = token[i];
        if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
              strchr("._~+/=-", c) != NULL)) {
            return false;
        }
    }
    return true;
}

co_err_t co_socketcand_open_fd(co_socketcand_t *sc, int fd, const char *channel,
                               unsigned timeout_ms)
{
    return co_socketcand_open_fd_auth(sc, fd, channel, NULL, timeout_ms);
}

co_err_t co_socketcand_open_fd_auth(co_socketcand_t *sc, int fd, const char *channel,
                                    const char *token, unsigned timeout_ms)
{
    if (sc == NULL || fd < 0 || channel == NULL) {
        return CO_ERR_ARG;
    }
    sd_init(sc);
    size_t ch_len = strlen(channel);
    if (ch_len == 0 || ch_len > CO_SOCKETCAND_CHANNEL_MAX) {
        co_transport_fail(&sc->transport, "socketcand: channel must be 1..16 characters");
        close(fd);
        return CO_ERR_ARG;
    }
    bool auth = token != NULL && *token != '\0';
    if (auth && !token_ok(token)) {
        co_transport_fail(&sc->transport, "socketcand: a token is 16..64 characters of "
                                          "A-Z a-z 0-9 . _ ~ + / = -");
        close(fd);
        return CO_ERR_ARG;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) != 0) {
        co_transport_fail(&sc->transport, "socketcand: %s", strerror(errno));
        close(fd);
        return CO_ERR_STATE;
    }
    sc->transport.fd = fd;
    char open_cmd[CO_SOCKETCAND_CHANNEL_MAX + 16];
    (void)snprintf(open_cmd, sizeof open_cmd, "< open %s >", channel);
    uint64_t end = now_ms() + timeout_ms;
    bool greeted = expect(sc, CO_SCD_HI, "< hi >", end) == CO_SCD_HI;
    if (greeted && auth) {
        char auth_cmd[CO_SOCKETCAND_TOKEN_MAX + 16];
        (void)snprintf(auth_cmd, sizeof auth_cmd, "< auth %s >", token);
        greeted =
            say(sc, auth_cmd, end) && expect(sc, CO_SCD_OK, "< ok > to auth", end) == CO_SCD_OK;
    }
    if (!greeted || !say(sc, open_cmd, end) ||
        expect(sc, CO_SCD_OK, "< ok > to open", end) != CO_SCD_OK || !say(sc, "< rawmode >", end) ||
        expect(sc, CO_SCD_OK, "< ok > to rawmode", end) != CO_SCD_OK) {
        sd_close(&sc->transport);
        return CO_ERR_STATE;
    }
    return CO_OK;
}

static int connect_to(const co_socketcand_url_t *u, unsigned timeout_ms, co_transport_t *err)
{
    char port[8];
    (void)snprintf(port, sizeof port, "%u", (unsigned)u->port);
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    int gai = getaddrinfo(u->host, port, &hints, &res);
    if (gai != 0) {
        co_transport_fail(err, "socketcand: %s: %s", u->host, gai_strerror(gai));
        return -2;
    }
    int fd = -1;
    uint64_t end = now_ms() + timeout_ms;
    for (struct addrinfo *a = res; a != NULL && fd < 0; a = a->ai_next) {
        fd = socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
        if (fd < 0) {
            co_transport_fail(err, "socketcand: socket: %s", strerror(errno));
            continue;
        }
        int rc = connect(fd, a->ai_addr, a->ai_addrlen);
        if (rc != 0 && errno == EINPROGRESS) {
            int w = wait_fd(fd, POLLOUT, end);
            int so = 0;
            socklen_t sl = sizeof so;
            if (w <= 0) {
                so = w == 0 ? ETIMEDOUT : errno;
            } else if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &so, &sl) != 0) {
                so = errno;
            }
            rc = so == 0 ? 0 : -1;
            errno = so;
        }
        if (rc != 0) {
            co_transport_fail(err, "socketcand: connect to %s:%s: %s", u->host, port,
                              strerror(errno));
            close(fd);
            fd = -1;
        }
    }
    freeaddrinfo(res);
    if (fd >= 0) {
        int one = 1; /* frames are small and latency matters */
        (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    }
    return fd;
}

co_err_t co_socketcand_open(co_socketcand_t *sc, const char *url, unsigned timeout_ms)
{
    return co_socketcand_open_auth(sc, url, NULL, timeout_ms);
}

co_err_t co_socketcand_open_auth(co_socketcand_t *sc, const char *url, const char *token,
                                 unsigned timeout_ms)
{
    if (sc == NULL) {
        return CO_ERR_ARG;
    }
    sd_init(sc);
    co_socketcand_url_t u;
    char why[96];
    if (co_socketcand_parse_url(url, &u, why, sizeof why) != CO_OK) {
        co_transport_fail(&sc->transport, "%s: %s", url != NULL ? url : "(null)", why);
        return CO_ERR_ARG;
    }
    int fd = connect_to(&u, timeout_ms, &sc->transport);
    if (fd < 0) {
        return fd == -2 ? CO_ERR_NOT_FOUND : CO_ERR_STATE;
    }
    char saved[CO_TRANSPORT_ERROR_MAX];
    co_err_t rc = co_socketcand_open_fd_auth(sc, fd, u.channel, token, timeout_ms);
    if (rc != CO_OK) {
        memcpy(saved, sc->transport.error, sizeof saved);
        co_transport_fail(&sc->transport, "%s: %s", url, saved);
    }
    return rc;
}
