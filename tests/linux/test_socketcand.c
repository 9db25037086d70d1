/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_socketcand.c -- the socketcand client transport, natively (no CAN, no server).
 *
 * The parser and formatter on their own; the URL; the handshake and raw mode against a
 * scripted fake server on the other end of a stream socketpair (what it says is written
 * before the client reads, what the client says is read back and compared); a real TCP
 * connection to a forked fake server on loopback; and everything a broken server can
 * do: garbage, an over-long message, a malformed frame, silence, an error, closing.
 * Waits are for events (tests/linux/loop_wait.h), bounded in seconds, so a busy machine
 * only makes the test slower. Bounded: alarm(120), and every wait in the code under test
 * has a time-out.
 */
#define _GNU_SOURCE

#include "canola/linux_loop.h"
#include "canola/socketcan.h"
#include "canola/socketcand.h"
#include "check.h"
#include "example_od.h"
#include "loop_wait.h"
#include "tcp_loopback.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#define MS 1000u

static co_socketcand_msg_t parse(const char *msg, co_frame_t *f, uint32_t *ev)
{
    return co_socketcand_parse(msg, strlen(msg), f, ev);
}

static void test_parse_frames(void)
{
    co_frame_t f;
    uint32_t ev = 0;
    CHECK_EQ(parse("< frame 123 23.424242 11223344 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.id, 0x123);
    CHECK_EQ(f.flags, 0);
    CHECK_EQ(f.len, 4);
    CHECK_EQ(f.data[0], 0x11);
    CHECK_EQ(f.data[3], 0x44);
    /* Bytes one per token, as the protocol document writes them. */
    CHECK_EQ(parse("< frame 705 1.5 05 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.len, 1);
    CHECK_EQ(f.data[0], 0x05);
    CHECK_EQ(parse("< frame 000 1.000000 01 7f >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.len, 2);
    CHECK_EQ(f.data[1], 0x7F);
    /* No data: socketcand writes two spaces. */
    CHECK_EQ(parse("< frame 080 0.000001  >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.id, 0x80);
    CHECK_EQ(f.len, 0);
    /* 29-bit: 8 digits (and anything longer than 3). */
    CHECK_EQ(parse("< frame 1AAAAAAA 5.0 01F1 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.id, 0x1AAAAAAA);
    CHECK_EQ(f.flags, CO_FRAME_EXT);
    CHECK_EQ(f.len, 2);
    CHECK_EQ(parse("< frame 00000123 5 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.id, 0x123);
    CHECK_EQ(f.flags, CO_FRAME_EXT);
    CHECK_EQ(parse("< frame 1FFFFFFF 5 0102030405060708 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.len, 8);
    CHECK_EQ(f.data[7], 0x08);
    /* Remote frames. */
    CHECK_EQ(parse("< rtr 705 23.424242 1 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.id, 0x705);
    CHECK_EQ(f.flags, CO_FRAME_RTR);
    CHECK_EQ(f.len, 1);
    CHECK_EQ(parse("< rtr 1AAAAAAA 1.0 2 >", &f, &ev), CO_SCD_FRAME);
    CHECK_EQ(f.flags, CO_FRAME_RTR | CO_FRAME_EXT);
}

static void test_parse_rejects(void)
{
    co_frame_t f;
    uint32_t ev;
    const char *bad[] = {
        "< frame 800 1.0 00 >",                 /* 3 digits: 11-bit, but > 0x7FF */
        "< frame 20000000 1.0 >",               /* > 29 bits */
        "< frame 123456789 1.0 >",              /* 9 digits */
        "< frame 12G 1.0 >",                    /* not hex */
        "< frame 123 >",                        /* no time */
        "< frame 123 x1.0 01 >",                /* not a time */
        "< frame 123 1.0.0 01 >",               /* two dots */
        "< frame 123 1.0 012 >",                /* odd digits */
        "< frame 123 1.0 010203040506070809 >", /* 9 bytes */
        "< frame 123 1.0 01 02 03 04 05 06 07 08 09 >",
        "< frame 123 1.0 0Z >",
        "< rtr 123 1.0 9 >", /* dlc > 8 */
        "< rtr 123 1.0 >",
        "<>",
        "<   >",
        "< fr\x01me >", /* control character */
        "< frame < 1.0 >",
        "frame 123 1.0 >",
        "< frame 123 1.0",
        "< a b c d e f g h i j k l m n o p q >", /* 17 tokens */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        co_socketcand_msg_t m = parse(bad[i], &f, &ev);
        if (m != CO_SCD_BAD) {
            printf("  accepted: %s\n", bad[i]);
        }
        CHECK_EQ(m, CO_SCD_BAD);
    }
}

static void test_parse_other_messages(void)
{
    co_frame_t f;
    uint32_t ev = 0xFFFF;
    CHECK_EQ(parse("< hi >", &f, &ev), CO_SCD_HI);
    CHECK_EQ(parse("<ok>", &f, &ev), CO_SCD_OK);
    CHECK_EQ(parse("< echo >", &f, &ev), CO_SCD_OTHER);
    CHECK_EQ(parse("< stat 1 2 3 4 >", &f, &ev), CO_SCD_OTHER);
    CHECK_EQ(parse("< error unknown command >", &f, &ev), CO_SCD_ERROR);
    /* Error frames: the class bits (bus-off 0x40, restarted 0x100). */
    CHECK_EQ(parse("< error 040 12.000001 >", &f, &ev), CO_SCD_EVENTS);
    CHECK_EQ(ev, 1u << CO_BUS_OFF);
    CHECK_EQ(parse("< error 100 12.5 >", &f, &ev), CO_SCD_EVENTS);
    CHECK_EQ(ev, 1u << CO_BUS_OFF_RECOVERED);
    CHECK_EQ(parse("< error 004 12.5 >", &f, &ev), CO_SCD_EVENTS); /* controller: no detail */
    CHECK_EQ(ev, 0);
}

static void test_format(void)
{
    char buf[64];
    co_frame_t f = {.id = 0x123, .len = 0};
    CHECK_EQ(co_socketcand_format(&f, buf, sizeof buf), strlen("< send 123 0 >"));
    CHECK_STR(buf, "< send 123 0 >");
    f = (co_frame_t){.id = 0x705, .len = 1, .data = {0x7F}};
    co_socketcand_format(&f, buf, sizeof buf);
    CHECK_STR(buf, "< send 705 1 7F >");
    f = (co_frame_t){.id = 0x1AAAAAAA, .flags = CO_FRAME_EXT, .len = 2, .data = {0x01, 0xF1}};
    co_socketcand_format(&f, buf, sizeof buf);
    CHECK_STR(buf, "< send 1AAAAAAA 2 01 F1 >");
    f = (co_frame_t){.id = 0x5, .flags = CO_FRAME_EXT, .len = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
    co_socketcand_format(&f, buf, sizeof buf);
    CHECK_STR(buf, "< send 00000005 8 01 02 03 04 05 06 07 08 >");
    f = (co_frame_t){.id = 0x705, .flags = CO_FRAME_RTR, .len = 1};
    co_socketcand_format(&f, buf, sizeof buf);
    CHECK_STR(buf, "< sendrtr 705 1 >");
    /* What it writes, it reads back (as a frame the server would echo). */
    f = (co_frame_t){.id = 0x1ABCDEF0, .flags = CO_FRAME_EXT, .len = 3, .data = {9, 8, 7}};
    co_socketcand_format(&f, buf, sizeof buf);
    char echo[160];
    /* buf is "< send 1ABCDEF0 3 09 08 07 >": the id at 7, the bytes (and " >") at 18 */
    snprintf(echo, sizeof echo, "< frame %.8s 1.0 %s", buf + 7, buf + 18);
    co_frame_t g;
    uint32_t ev;
    CHECK_EQ(parse(echo, &g, &ev), CO_SCD_FRAME);
    CHECK_EQ(g.id, f.id);
    CHECK_EQ(g.flags, f.flags);
    CHECK_EQ(g.len, 3);
    CHECK_EQ(g.data[2], 7);
    /* Invalid frames and small buffers write nothing. */
    f = (co_frame_t){.id = 0x800, .len = 0};
    CHECK_EQ(co_socketcand_format(&f, buf, sizeof buf), 0);
    f = (co_frame_t){.id = 0x1, .len = 9};
    CHECK_EQ(co_socketcand_format(&f, buf, sizeof buf), 0);
    f = (co_frame_t){.id = 0x123, .len = 8};
    CHECK_EQ(co_socketcand_format(&f, buf, 20), 0);
}

static void test_url(void)
{
    co_socketcand_url_t u;
    char why[96];
    CHECK_EQ(co_socketcand_parse_url("socketcand://127.0.0.1:29536/vcan0", &u, why, sizeof why),
             CO_OK);
    CHECK_STR(u.host, "127.0.0.1");
    CHECK_EQ(u.port, 29536);
    CHECK_STR(u.channel, "vcan0");
    CHECK_EQ(co_socketcand_parse_url("socketcand://hub.local/can1", &u, why, sizeof why), CO_OK);
    CHECK_STR(u.host, "hub.local");
    CHECK_EQ(u.port, CO_SOCKETCAND_PORT);
    CHECK_EQ(co_socketcand_parse_url("socketcand://[::1]:4000/bus", &u, why, sizeof why), CO_OK);
    CHECK_STR(u.host, "::1");
    CHECK_EQ(u.port, 4000);
    const char *bad[] = {"tcp://h:1/c",
                         "socketcand://",
                         "socketcand://h:1",
                         "socketcand://h:1/",
                         "socketcand://:1/c",
                         "socketcand://h:0/c",
                         "socketcand://h:65536/c",
                         "socketcand://h:x/c",
                         "socketcand://h:1/abcdefghijklmnopq",
                         "socketcand://h:1/a b",
                         "socketcand://h:1/a/b",
                         "socketcand://[::1/c"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        why[0] = '\0';
        CHECK_EQ(co_socketcand_parse_url(bad[i], &u, why, sizeof why), CO_ERR_ARG);
        CHECK(why[0] != '\0');
    }
    CHECK_EQ(co_socketcand_parse_url(NULL, &u, NULL, 0), CO_ERR_ARG);
}

/* ---- against a scripted server on a socketpair */

typedef struct rig {
    co_loop_t loop;
    example_od_t od;
    co_node_t node;
    co_node_config_t cfg;
    co_socketcand_t sc;
    int server;
    char heard[8192]; /* everything the client wrote */
    size_t heard_len;
} rig_t;

static rig_t R;

static void say(rig_t *r, const char *text)
{
    CHECK(write(r->server, text, strlen(text)) == (ssize_t)strlen(text));
}

static void hear(rig_t *r)
{
    for (;;) {
        ssize_t n = read(r->server, r->heard + r->heard_len, sizeof r->heard - 1 - r->heard_len);
        if (n <= 0) {
            break;
        }
        r->heard_len += (size_t)n;
    }
    r->heard[r->heard_len] = '\0';
}

/* Handshake with `greeting` already written by the server, proving `token` (NULL: none)
 * first; returns open_fd_auth's result. */
static co_err_t rig_connect_auth(rig_t *r, const char *greeting, const char *token,
                                 unsigned timeout_ms)
{
    memset(r, 0, sizeof *r);
    int sv[2];
    CHECK(socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) == 0);
    r->server = sv[1];
    CHECK(fcntl(r->server, F_SETFL, O_NONBLOCK) == 0);
    say(r, greeting);
    return co_socketcand_open_fd_auth(&r->sc, sv[0], "vcan0", token, timeout_ms);
}

/* The same without a token, as co_socketcand_open_fd runs it. */
static co_err_t rig_connect(rig_t *r, const char *greeting, unsigned timeout_ms)
{
    return rig_connect_auth(r, greeting, NULL, timeout_ms);
}

static void rig_node(rig_t *r, uint16_t hb_ms)
{
    CHECK_EQ(co_loop_init(&r->loop), CO_OK);
    r->cfg.node_id = 5;
    r->cfg.od = example_od_init(&r->od, hb_ms);
    CHECK_EQ(co_loop_add_node(&r->loop, &r->node, &r->cfg, &r->sc.transport), CO_OK);
    CHECK_EQ(co_node_start(&r->node, co_linux_now_us()), CO_OK);
}

static co_loop_reason_t run_ms(rig_t *r, unsigned ms)
{
    co_loop_reason_t why = co_loop_run_until(&r->loop, co_linux_now_us() + ms * MS);
    hear(r);
    return why;
}

/* What run_until waits for: the node's state (if not CO_NMT_INITIALISING, i.e. any), and
 * `text` among what the server heard (if not NULL). */
typedef struct awaited {
    rig_t *r;
    co_nmt_state_t state;
    const char *text;
} awaited_t;

static bool has_happened(void *ctx)
{
    awaited_t *a = ctx;
    hear(a->r);
    return (a->state == CO_NMT_INITIALISING || co_nmt_state(&a->r->node) == a->state) &&
           (a->text == NULL || strstr(a->r->heard, a->text) != NULL);
}

/* Run the loop until the node is in `state` and the server heard `text` (either may be
 * left out: CO_NMT_INITIALISING, NULL): whether both came within the bound. */
static bool run_until(rig_t *r, co_nmt_state_t state, const char *text)
{
    awaited_t a = {r, state, text};
    bool ok = loop_wait(&r->loop, has_happened, &a, NULL);
    if (!ok) {
        printf("  waited for state %d and '%s'; heard: %s\n", (int)state, text ? text : "",
               r->heard);
    }
    return ok;
}

static void rig_close(rig_t *r)
{
    co_loop_close(&r->loop);
    co_socketcand_close(&r->sc);
    co_socketcand_close(&r->sc); /* twice is fine */
    close(r->server);
}

static void test_handshake_and_raw_mode(void)
{
    rig_t *r = &R;
    /* The NMT start right behind the last ok (same segment) must not be lost. */
    CHECK_EQ(rig_connect(r, "< hi >< ok >\n< ok >< frame 000 1.000000 0105 >", 1000), CO_OK);
    hear(r);
    CHECK_STR(r->heard, "< open vcan0 >< rawmode >");
    r->heard_len = 0;
    rig_node(r, 100);
    CHECK(run_until(r, CO_NMT_OPERATIONAL, "< send 705 1 00 >"));
    CHECK(strstr(r->heard, "< send 705 1 00 >") == r->heard);     /* boot-up first */
    CHECK(run_until(r, CO_NMT_OPERATIONAL, "< send 705 1 05 >")); /* heartbeat: operational */
    /* A frame the protocol cannot carry is dropped by the node; the connection stays. */
    co_frame_t bad = {.id = 0x800, .len = 0};
    (void)co_node_send(&r->node, &bad);
    CHECK_EQ(co_node_stats(&r->node)->tx_dropped, 1);
    CHECK_EQ(run_ms(r, 20), CO_LOOP_DEADLINE);
    rig_close(r);
}

static void test_partial_and_batched_messages(void)
{
    rig_t *r = &R;
    CHECK_EQ(rig_connect(r, "< hi >< ok >< ok >", 1000), CO_OK);
    rig_node(r, 0);
    CHECK_EQ(run_ms(r, 10), CO_LOOP_DEADLINE);
    /* A message cut in three reads. */
    say(r, "< fra");
    CHECK_EQ(run_ms(r, 20), CO_LOOP_DEADLINE);
    say(r, "me 000 1.000000 01");
    CHECK_EQ(run_ms(r, 20), CO_LOOP_DEADLINE);
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_PRE_OPERATIONAL);
    say(r, "05 >");
    CHECK(run_until(r, CO_NMT_OPERATIONAL, NULL));
    /* Many in one read, with white space and messages to ignore between them. */
    uint32_t rx0 = co_node_stats(&r->node)->rx_frames;
    say(r, "< echo >\r\n< frame 000 2.0 02 05 >  < error unknown command >\n"
           "< frame 1AAAAAAA 2.1 01F1 >< rtr 705 2.2 1 >< stat 1 2 3 4 >< frame 000 2.3 8005 >");
    r->heard_len = 0;
    /* The guarding answer comes from the fourth frame of the batch: all of it was read. */
    CHECK(run_until(r, CO_NMT_PRE_OPERATIONAL, "< send 705 1 04 >"));
    CHECK_EQ(co_node_stats(&r->node)->rx_frames, rx0 + 4);
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_PRE_OPERATIONAL); /* stop, then pre-operational */
    CHECK_EQ(r->sc.server_errors, 1);
    CHECK_EQ(r->sc.rx_other, 2);
    /* The RTR on 0x705 is node guarding: the node, stopped at that moment, answers
     * (toggle 0, state 0x04). */
    if (strstr(r->heard, "< send 705 1 04 >") == NULL) {
        printf("  heard: %s\n", r->heard);
    }
    CHECK(strstr(r->heard, "< send 705 1 04 >") != NULL);
    rig_close(r);
}

static void test_error_frames_become_bus_events(void)
{
    rig_t *r = &R;
    CHECK_EQ(rig_connect(r, "< hi >< ok >< ok >< frame 000 1.0 0105 >", 1000), CO_OK);
    rig_node(r, 0);
    CHECK(run_until(r, CO_NMT_OPERATIONAL, NULL));
    r->heard_len = 0;
    /* Bus-off: error behaviour 0 (the example's default) -> pre-operational. Restarted:
     * EMCY 0x8140 (error register 0x11: generic + communication). */
    say(r, "< error 040 3.0 >");
    CHECK(run_until(r, CO_NMT_PRE_OPERATIONAL, NULL));
    say(r, "< error 100 3.1 >");
    CHECK(run_until(r, CO_NMT_INITIALISING, "< send 085 8 40 81 11 00 00 00 00 00 >"));
    CHECK(co_emcy_active(&r->node, 0x8140));
    rig_close(r);
}

static void expect_failure(const char *what, const char *server_says, const char *error_part)
{
    rig_t *r = &R;
    CHECK_EQ(rig_connect(r, "< hi >< ok >< ok >", 1000), CO_OK);
    rig_node(r, 100);
    CHECK_EQ(run_ms(r, 10), CO_LOOP_DEADLINE);
    if (server_says != NULL) {
        say(r, server_says);
    } else {
        shutdown(r->server, SHUT_WR);
    }
    co_loop_reason_t why = run_ms(r, LOOP_WAIT_BOUND_MS); /* ends at the failure */
    if (why != CO_LOOP_TRANSPORT_FAILED || strstr(r->sc.transport.error, error_part) == NULL) {
        printf("  %s: %s, '%s'\n", what, co_loop_reason_name(why), r->sc.transport.error);
    }
    CHECK_EQ(why, CO_LOOP_TRANSPORT_FAILED);
    CHECK(co_loop_failed(&r->loop) == &r->sc.transport);
    CHECK(strstr(r->sc.transport.error, error_part) != NULL);
    rig_close(r);
}

static void test_broken_servers(void)
{
    expect_failure("garbage", "hello\n", "garbage");
    expect_failure("garbage after a message", "< ok > junk", "garbage");
    char longmsg[CO_SOCKETCAND_RX_BUF + 200];
    memset(longmsg, 'a', sizeof longmsg - 1);
    longmsg[0] = '<';
    longmsg[sizeof longmsg - 1] = '\0';
    expect_failure("no end", longmsg, "longer than");
    char justover[CO_SOCKETCAND_MSG_MAX + 2];
    memset(justover, 'b', sizeof justover - 1);
    justover[0] = '<';
    justover[1] = ' ';
    justover[sizeof justover - 2] = '>';
    justover[sizeof justover - 1] = '\0';
    expect_failure("one byte too long", justover, "longer than");
    expect_failure("malformed frame", "< frame 12345678901 1.0 >", "malformed");
    expect_failure("server closed", NULL, "closed");
}

static void test_handshake_failures(void)
{
    rig_t *r = &R;
    CHECK_EQ(rig_connect(r, "< hi >< error no such bus >", 1000), CO_ERR_STATE);
    CHECK(strstr(r->sc.transport.error, "no such bus") != NULL);
    CHECK_EQ(r->sc.transport.fd, -1);
    close(r->server);

    uint64_t t0 = co_linux_now_us();
    CHECK_EQ(rig_connect(r, "", 200), CO_ERR_STATE);         /* a server that never greets */
    CHECK(co_linux_now_us() - t0 < LOOP_WAIT_BOUND_MS * MS); /* ended by its time-out */
    CHECK(strstr(r->sc.transport.error, "timed out waiting for < hi >") != NULL);
    close(r->server);

    CHECK_EQ(rig_connect(r, "SSH-2.0-OpenSSH\r\n", 1000), CO_ERR_STATE);
    CHECK(strstr(r->sc.transport.error, "garbage") != NULL);
    close(r->server);

    /* Out of order (found by fuzz_socketcand_client): the failure says why. */
    CHECK_EQ(rig_connect(r, "< hi > < hi >< ok >< ok >", 1000), CO_ERR_STATE);
    CHECK_STR(r->sc.transport.error,
              "socketcand: expected < ok > to open, the server said '< hi >'");
    close(r->server);
    CHECK_EQ(rig_connect(r, "< ok >< ok >< ok >", 1000), CO_ERR_STATE);
    CHECK_STR(r->sc.transport.error, "socketcand: expected < hi >, the server said '< ok >'");
    close(r->server);

    CHECK_EQ(rig_connect(r, "< hi >< ok >< ok >", 1000), CO_OK);
    co_socketcand_close(&r->sc);
    close(r->server);
    CHECK_EQ(co_socketcand_open_fd(&r->sc, -1, "vcan0", 100), CO_ERR_ARG);
}

/* A hub that asks for a token (canola bus serve --token): it goes first, a refusal says
 * the server's words, and a token that is not one never leaves. */
static void test_token(void)
{
    rig_t *r = &R;
    const char *token = "Zm9vYmFyLXRva2VuLTIwMjQ";
    CHECK_EQ(rig_connect_auth(r, "< hi >< ok >< ok >< ok >", token, 1000), CO_OK);
    hear(r);
    CHECK_STR(r->heard, "< auth Zm9vYmFyLXRva2VuLTIwMjQ >< open vcan0 >< rawmode >");
    co_socketcand_close(&r->sc);
    close(r->server);

    CHECK_EQ(rig_connect_auth(r, "< hi >< error wrong token >", token, 1000), CO_ERR_STATE);
    CHECK_STR(r->sc.transport.error,
              "socketcand: expected < ok > to auth, the server said '< error wrong token >'");
    close(r->server);

    /* without one, a hub that asks says so */
    CHECK_EQ(rig_connect_auth(r, "< hi >< error authentication required >", "", 1000),
             CO_ERR_STATE);
    CHECK(strstr(r->sc.transport.error, "authentication required") != NULL);
    hear(r);
    CHECK_STR(r->heard, "< open vcan0 >");
    close(r->server);

    const char *bad[] = {"short", "has space in it 0123", "0123456789abcdef<>",
                         "0123456789012345678901234567890123456789012345678901234567890123X"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_EQ(rig_connect_auth(r, "< hi >", bad[i], 1000), CO_ERR_ARG);
        CHECK(strstr(r->sc.transport.error, "16..64") != NULL);
        hear(r);
        CHECK_EQ(r->heard_len, 0u); /* nothing was sent */
        close(r->server);
    }
}

static void test_output_buffer_fills_and_drains(void)
{
    rig_t *r = &R;
    CHECK_EQ(rig_connect(r, "< hi >< ok >< ok >", 1000), CO_OK);
    hear(r);
    int small = 4096;
    CHECK(setsockopt(r->sc.transport.fd, SOL_SOCKET, SO_SNDBUF, &small, sizeof small) == 0);
    co_transport_t *t = &r->sc.transport;
    co_frame_t f = {.id = 0x181, .len = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
    int sent = 0;
    co_err_t rc = CO_OK;
    while (sent < 100000 && (rc = t->ops->send(t, &f)) == CO_OK) {
        sent++;
    }
    CHECK_EQ(rc, CO_ERR_BUSY); /* the server does not read: the buffer fills, no overflow */
    CHECK(t->ops->pending(t));
    CHECK(sent > 10);
    /* The server reads everything; flushing then empties the buffer. */
    size_t total = 0;
    for (int i = 0; i < 1000 && t->ops->pending(t); i++) {
        r->heard_len = 0;
        hear(r);
        total += r->heard_len;
        (void)t->ops->flush(t);
    }
    r->heard_len = 0;
    hear(r);
    total += r->heard_len;
    CHECK(!t->ops->pending(t));
    CHECK_EQ(total, (size_t)sent * strlen("< send 181 8 01 02 03 04 05 06 07 08 >"));
    CHECK_EQ(t->ops->send(t, &f), CO_OK);
    co_frame_t invalid = {.id = 0x800};
    CHECK_EQ(t->ops->send(t, &invalid), CO_ERR_ARG);
    co_socketcand_close(&r->sc);
    close(r->server);
}

static void server_reads(void *ctx, int fd, uint32_t events)
{
    (void)fd;
    (void)events;
    hear(ctx);
}

static bool all_flushed(void *ctx)
{
    rig_t *r = ctx;
    return strstr(r->heard, "< send 203 1 03 >") != NULL &&
           !r->sc.transport.ops->pending(&r->sc.transport);
}

static void test_loop_flushes_when_writable(void)
{
    /* The transport's buffer is full and the server reads nothing: the node's frames wait
     * in its queue (busy). Once the server reads (an application fd of the same loop),
     * the loop sees the socket writable, flushes, polls the node, and every frame goes
     * out in order. */
    rig_t *r = &R;
    CHECK_EQ(rig_connect(r, "< hi >< ok >< ok >", 1000), CO_OK);
    hear(r);
    r->heard_len = 0;
    int small = 4096;
    CHECK(setsockopt(r->sc.transport.fd, SOL_SOCKET, SO_SNDBUF, &small, sizeof small) == 0);
    rig_node(r, 0);
    CHECK_EQ(run_ms(r, 10), CO_LOOP_DEADLINE); /* boot-up out, heard */
    r->heard_len = 0;
    co_transport_t *t = &r->sc.transport;
    co_frame_t f = {.id = 0x181, .len = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
    int filler = 0;
    while (filler < 100000 && t->ops->send(t, &f) == CO_OK) {
        filler++;
    }
    for (uint8_t i = 0; i < 4; i++) {
        co_frame_t g = {.id = 0x200u + i, .len = 1, .data = {i}};
        CHECK_EQ(co_node_send(&r->node, &g), CO_OK);
    }
    /* At least one had to wait (the socket may take a little more now and then). */
    CHECK(co_node_stats(&r->node)->tx_queued >= 1);
    CHECK(co_loop_stats(&r->loop)->busy >= 1);
    printf("  %d filler frames, %u of 4 queued in the node\n", filler,
           (unsigned)co_node_stats(&r->node)->tx_queued);
    CHECK_EQ(co_loop_add_fd(&r->loop, r->server, EPOLLIN, server_reads, r), CO_OK);
    unsigned slices = 0;
    CHECK(loop_wait(&r->loop, all_flushed, r, &slices));
    const char *a = strstr(r->heard, "< send 200 1 00 >");
    const char *d = strstr(r->heard, "< send 203 1 03 >");
    CHECK(a != NULL && d != NULL && a < d);
    CHECK(!t->ops->pending(t));
    size_t fillers = 0;
    for (const char *p = r->heard; (p = strstr(p, "< send 181 8")) != NULL; p++) {
        fillers++;
    }
    CHECK_EQ(fillers, (size_t)filler);
    /* woken by the socket (and once per slice of the wait), not spinning */
    CHECK(co_loop_stats(&r->loop)->wakeups < 200 + slices);
    rig_close(r);
}

/* ---- a real TCP connection (URL, resolve, connect) to a forked server on loopback */

static int serve_one(int lsock)
{
    alarm(60);
    int c = accept(lsock, NULL, NULL);
    if (c < 0) {
        return 10;
    }
    const char *hi = "< hi >";
    if (write(c, hi, strlen(hi)) < 0) {
        return 11;
    }
    char buf[512];
    size_t len = 0;
    /* Answer open and rawmode, then send an NMT start and wait for the heartbeat. */
    int oks = 0;
    while (len < sizeof buf - 1) {
        ssize_t n = read(c, buf + len, sizeof buf - 1 - len);
        if (n <= 0) {
            return 12;
        }
        len += (size_t)n;
        buf[len] = '\0';
        if (oks == 0 && strstr(buf, "< open vcan0 >")) {
            oks = 1;
            if (write(c, "< ok >", 6) != 6) {
                return 13;
            }
        }
        if (oks == 1 && strstr(buf, "< rawmode >")) {
            oks = 2;
            const char *go = "< ok >< frame 000 1.0 0105 >";
            if (write(c, go, strlen(go)) < 0) {
                return 14;
            }
        }
        if (strstr(buf, "< send 705 1 05 >")) {
            close(c);
            return 0;
        }
    }
    return 15;
}

static void test_tcp_loopback(void)
{
    unsigned port = 0;
    int ls = listen_loopback(&port);
    pid_t child = fork();
    if (child == 0) {
        _exit(serve_one(ls));
    }
    close(ls);
    char url[80];
    snprintf(url, sizeof url, "socketcand://127.0.0.1:%u/vcan0", port);
    rig_t *r = &R;
    memset(r, 0, sizeof *r);
    r->server = -1;
    CHECK_EQ(co_socketcand_open(&r->sc, url, 10000), CO_OK);
    rig_node(r, 50);
    co_loop_reason_t why = run_ms(r, LOOP_WAIT_BOUND_MS); /* ends when the server hangs up */
    /* The server hangs up once it heard the heartbeat: the loop reports it. */
    CHECK_EQ(why, CO_LOOP_TRANSPORT_FAILED);
    CHECK_EQ(co_nmt_state(&r->node), CO_NMT_OPERATIONAL);
    int status = -1;
    CHECK_EQ(waitpid(child, &status, 0), child);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    co_loop_close(&r->loop);
    co_socketcand_close(&r->sc);

    /* Nobody listens there any more. */
    co_socketcand_t sc;
    CHECK_EQ(co_socketcand_open(&sc, url, 1000), CO_ERR_STATE);
    CHECK(strstr(sc.transport.error, "connect") != NULL);
    CHECK(strstr(sc.transport.error, url) == NULL || strlen(sc.transport.error) > 0);
    CHECK_EQ(co_socketcand_open(&sc, "socketcand://127.0.0.1/", 1000), CO_ERR_ARG);
    CHECK(strstr(sc.transport.error, "channel") != NULL);
}

int main(void)
{
    alarm(120);
    setvbuf(stdout, NULL, _IOLBF, 0);
    RUN(test_parse_frames);
    RUN(test_parse_rejects);
    RUN(test_parse_other_messages);
    RUN(test_format);
    RUN(test_url);
    RUN(test_handshake_and_raw_mode);
    RUN(test_partial_and_batched_messages);
    RUN(test_error_frames_become_bus_events);
    RUN(test_broken_servers);
    RUN(test_handshake_failures);
    RUN(test_token);
    RUN(test_output_buffer_fills_and_drains);
    RUN(test_loop_flushes_when_writable);
    RUN(test_tcp_loopback);
    return check_summary();
}
