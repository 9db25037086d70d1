/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_canola_node.c -- the canola-node program, natively: run over --bus against a fake
 * socketcand server in this process (loopback TCP), and with bad arguments.
 *
 * usage: test_canola_node PATH-TO-canola-node
 *
 * Checks: boot-up, an NMT start seen in the heartbeat, an SDO "save" with --store DIR
 * writing the parameter files and a restart reading them back, the NMT state changes on stderr, a
 * clean exit 0 on SIGTERM and SIGINT, exit 1 when the server goes away, one-line errors and exit 2
 * for bad arguments; the bus named by CANOLA_BUS (which --iface/--bus override: the other tests
 * run with a CANOLA_BUS it cannot open), one-line errors for the forms it cannot open.
 * Bounded: every wait has a time-out; alarm(180).
 */
#define _GNU_SOURCE

#include "check.h"
#include "tcp_loopback.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const char *prog;

/* How long a wait for the program may take (ms): a bound for a starved machine, where a
 * program under ASan may need seconds to start; the waits end when the awaited text or
 * exit comes. */
#define WAIT_MS 20000

static long now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1000L + ts.tv_nsec / 1000000L;
}

typedef struct child {
    pid_t pid;
    int err; /* read end of its stderr */
    char text[4096];
    size_t len;
} child_t;

static void spawn(child_t *c, char *const argv[])
{
    memset(c, 0, sizeof *c);
    int p[2];
    CHECK(pipe2(p, O_CLOEXEC) == 0);
    c->pid = fork();
    if (c->pid == 0) {
        dup2(p[1], 2);
        int null = open("/dev/null", O_WRONLY);
        dup2(null, 1);
        execv(argv[0], argv);
        _exit(127);
    }
    close(p[1]);
    c->err = p[0];
    fcntl(c->err, F_SETFL, O_NONBLOCK);
}

static void collect(child_t *c)
{
    ssize_t n;
    while ((n = read(c->err, c->text + c->len, sizeof c->text - 1 - c->len)) > 0) {
        c->len += (size_t)n;
    }
    c->text[c->len] = '\0';
}

/* Wait up to `ms` for the child to exit; its exit status, or -1 (then it is killed). */
static int finish(child_t *c, int ms)
{
    long end = now_ms() + ms;
    int status;
    for (;;) {
        collect(c);
        pid_t r = waitpid(c->pid, &status, WNOHANG);
        if (r == c->pid) {
            collect(c);
            close(c->err);
            return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        }
        if (now_ms() > end) {
            kill(c->pid, SIGKILL);
            waitpid(c->pid, &status, 0);
            close(c->err);
            return -1;
        }
        usleep(5000);
    }
}

/* ---- the fake server side */

typedef struct conn {
    int fd;
    char buf[16384];
    size_t len;
} conn_t;

/* Read until `text` appears after offset `from` or `ms` pass; its offset or -1. */
static long wait_text(conn_t *k, size_t from, const char *text, int ms)
{
    long end = now_ms() + ms;
    for (;;) {
        k->buf[k->len] = '\0';
        const char *hit = from <= k->len ? strstr(k->buf + from, text) : NULL;
        if (hit != NULL) {
            return hit - k->buf;
        }
        long left = end - now_ms();
        struct pollfd p = {.fd = k->fd, .events = POLLIN};
        if (left <= 0 || poll(&p, 1, (int)left) <= 0) {
            return -1;
        }
        ssize_t n = read(k->fd, k->buf + k->len, sizeof k->buf - 1 - k->len);
        if (n <= 0) {
            return -1;
        }
        k->len += (size_t)n;
    }
}

static void send_text(conn_t *k, const char *text)
{
    CHECK(write(k->fd, text, strlen(text)) == (ssize_t)strlen(text));
}

static int accept_within(int ls, int ms)
{
    struct pollfd p = {.fd = ls, .events = POLLIN};
    if (poll(&p, 1, ms) <= 0) {
        return -1;
    }
    return accept4(ls, NULL, NULL, SOCK_CLOEXEC);
}

/* What every test but the CANOLA_BUS ones has in its environment: a bus canola-node
 * cannot open, so that they show --iface and --bus win over it. */
#define OVERRIDDEN_BUS "virtual://overridden"

/* Start canola-node on a fresh server (named by --bus, or with `by_env` by CANOLA_BUS),
 * do the handshake; conn fd -1 on failure. */
static void start_node_with(child_t *c, conn_t *k, const char *store, int *listener, bool by_env,
                            const char *sdo_timeout_ms)
{
    unsigned port;
    int ls = listen_loopback(&port);
    char url[64];
    snprintf(url, sizeof url, "socketcand://127.0.0.1:%u/vcan0", port);
    char *argv[12];
    int n = 0;
    argv[n++] = (char *)prog;
    if (by_env) {
        setenv("CANOLA_BUS", url, 1);
    } else {
        argv[n++] = "--bus";
        argv[n++] = url;
    }
    argv[n++] = "--node-id";
    argv[n++] = "7";
    argv[n++] = "--heartbeat";
    argv[n++] = "100";
    if (store != NULL) {
        argv[n++] = "--store";
        argv[n++] = (char *)store;
    }
    if (sdo_timeout_ms != NULL) {
        argv[n++] = "--sdo-timeout";
        argv[n++] = (char *)sdo_timeout_ms;
    }
    argv[n] = NULL;
    spawn(c, argv);
    setenv("CANOLA_BUS", OVERRIDDEN_BUS, 1);
    memset(k, 0, sizeof *k);
    k->fd = accept_within(ls, WAIT_MS);
    CHECK(k->fd >= 0);
    *listener = ls;
    if (k->fd < 0) {
        return;
    }
    send_text(k, "< hi >");
    CHECK(wait_text(k, 0, "< open vcan0 >", WAIT_MS) >= 0);
    send_text(k, "< ok >");
    CHECK(wait_text(k, 0, "< rawmode >", WAIT_MS) >= 0);
    send_text(k, "< ok >");
}

static void start_node_on(child_t *c, conn_t *k, const char *store, int *listener, bool by_env)
{
    start_node_with(c, k, store, listener, by_env, NULL);
}

static void start_node(child_t *c, conn_t *k, const char *store, int *listener)
{
    start_node_on(c, k, store, listener, false);
}

/* --sdo-timeout: a segmented upload left waiting is aborted (0x05040000) after that long,
 * not after the default 1000 ms. A loaded machine notices the answer late or the abort
 * late: 2 s of the 4 s are slack for the first, the second only makes the wait longer. */
static void test_sdo_timeout_option(void)
{
    child_t c;
    conn_t k;
    int ls;
    start_node_with(&c, &k, NULL, &ls, false, "4000");
    CHECK(wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS) >= 0);
    size_t from = k.len;
    send_text(&k, "< frame 607 1.000000 4008100000000000 >"); /* upload 0x1008: segmented */
    long answer = wait_text(&k, from, "< send 587 8 41 08 10 00", WAIT_MS);
    long answered_ms = now_ms();
    CHECK(answer >= 0);
    CHECK(wait_text(&k, (size_t)answer, "< send 587 8 80 08 10 00 00 00 04 05 >", WAIT_MS) >= 0);
    long waited_ms = now_ms() - answered_ms;
    if (waited_ms < 2000) {
        printf("  aborted after %ld ms (--sdo-timeout 4000)\n", waited_ms);
    }
    CHECK(waited_ms >= 2000);
    kill(c.pid, SIGTERM);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    close(k.fd);
    close(ls);
}

static void test_runs_on_a_socketcand_bus(void)
{
    child_t c;
    conn_t k;
    int ls;
    char dir[] = "/tmp/canola-node-test-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    start_node(&c, &k, dir, &ls);
    long boot = wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS);
    CHECK(boot >= 0);
    long hb = wait_text(&k, (size_t)(boot + 1), "< send 707 1 7F >", WAIT_MS);
    CHECK(hb >= 0);
    /* NMT start node 7. */
    send_text(&k, "< frame 000 1.000000 0107 >");
    CHECK(wait_text(&k, (size_t)hb, "< send 707 1 05 >", WAIT_MS) >= 0);
    /* 0x1017 = 250 ms, then 0x1010 sub1 = "save": the parameters land in --store. */
    size_t from = k.len;
    send_text(&k, "< frame 607 2.000000 2B171000FA000000 >");
    CHECK(wait_text(&k, from, "< send 587 8 60 17 10 00 00 00 00 00 >", WAIT_MS) >= 0);
    from = k.len;
    send_text(&k, "< frame 607 2.100000 2310100173617665 >");
    CHECK(wait_text(&k, from, "< send 587 8 60 10 10 01 00 00 00 00 >", WAIT_MS) >= 0);
    char path[128];
    struct stat st;
    snprintf(path, sizeof path, "%s/comm.params", dir);
    CHECK(stat(path, &st) == 0 && st.st_size > 0);
    kill(c.pid, SIGTERM);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    CHECK(strstr(c.text, "node 7 on socketcand://") != NULL);
    CHECK(strstr(c.text, ": pre-operational\n") != NULL);
    CHECK(strstr(c.text, ": operational\n") != NULL);
    CHECK(strstr(c.text, "stopped by SIGTERM") != NULL);
    printf("  its stderr:\n%s", c.text);
    close(k.fd);
    close(ls);

    /* Power cycle: the stored 250 ms beats --heartbeat 100. */
    start_node(&c, &k, dir, &ls);
    CHECK(wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS) >= 0);
    from = k.len;
    send_text(&k, "< frame 607 3.000000 4017100000000000 >");
    CHECK(wait_text(&k, from, "< send 587 8 4B 17 10 00 FA 00 00 00 >", WAIT_MS) >= 0);
    kill(c.pid, SIGTERM);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    close(k.fd);
    close(ls);
    unlink(path);
    snprintf(path, sizeof path, "%s/app.params", dir);
    unlink(path);
    CHECK(rmdir(dir) == 0);
}

/* LSS (CiA 305) with --store: a configured node-ID that is stored (store configuration)
 * survives a reset node and a restart, whatever --node-id says; one configured and not
 * stored is gone after the reset node. (Before: store configuration answered 1, "not
 * supported", and reset node brought back the node-ID of --node-id.) */
static void test_lss_node_id_stored(void)
{
    child_t c;
    conn_t k;
    int ls;
    char dir[] = "/tmp/canola-node-lss-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    start_node(&c, &k, dir, &ls);
    CHECK(wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS) >= 0);
    size_t from = k.len;
    send_text(&k, "< frame 7E5 1.000000 0401000000000000 >"); /* configuration state */
    send_text(&k, "< frame 7E5 1.000000 1109000000000000 >"); /* configure node-ID 9 */
    CHECK(wait_text(&k, from, "< send 7E4 8 11 00 00 00 00 00 00 00 >", WAIT_MS) >= 0);
    from = k.len;
    send_text(&k, "< frame 7E5 1.000000 1700000000000000 >"); /* store configuration */
    CHECK(wait_text(&k, from, "< send 7E4 8 17 00 00 00 00 00 00 00 >", WAIT_MS) >= 0);
    send_text(&k, "< frame 7E5 1.000000 0400000000000000 >"); /* waiting */
    from = k.len;
    send_text(&k, "< frame 000 1.000000 8107 >"); /* NMT reset node 7 */
    CHECK(wait_text(&k, from, "< send 709 1 00 >", WAIT_MS) >= 0);
    kill(c.pid, SIGTERM);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    close(k.fd);
    close(ls);
    char path[128];
    snprintf(path, sizeof path, "%s/lss.params", dir);
    char line[64] = {0};
    FILE *f = fopen(path, "r");
    CHECK(f != NULL);
    if (f != NULL) {
        CHECK(fgets(line, sizeof line, f) != NULL);
        fclose(f);
    }
    CHECK_STR(line, "canola-lss 1 node-id 9 bit-timing 255\n");

    /* A restart with --node-id 7: node 9, and it says why. */
    start_node(&c, &k, dir, &ls);
    CHECK(wait_text(&k, 0, "< send 709 1 00 >", WAIT_MS) >= 0);
    /* configured to 11 but not stored: the reset node brings 9 back */
    from = k.len;
    send_text(&k, "< frame 7E5 1.000000 0401000000000000 >");
    send_text(&k, "< frame 7E5 1.000000 110B000000000000 >");
    CHECK(wait_text(&k, from, "< send 7E4 8 11 00 00 00 00 00 00 00 >", WAIT_MS) >= 0);
    send_text(&k, "< frame 7E5 1.000000 0400000000000000 >");
    from = k.len;
    send_text(&k, "< frame 000 1.000000 8109 >");
    CHECK(wait_text(&k, from, "< send 709 1 00 >", WAIT_MS) >= 0);
    kill(c.pid, SIGTERM);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    char said[160];
    snprintf(said, sizeof said, "node-ID 9, stored by LSS in %s/lss.params (not --node-id 7)", dir);
    CHECK(strstr(c.text, said) != NULL);
    close(k.fd);
    close(ls);
    CHECK(unlink(path) == 0);
    CHECK(rmdir(dir) == 0);
}

static void test_sigint_and_server_gone(void)
{
    child_t c;
    conn_t k;
    int ls;
    start_node(&c, &k, NULL, &ls);
    CHECK(wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS) >= 0);
    kill(c.pid, SIGINT);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    CHECK(strstr(c.text, "stopped by SIGINT") != NULL);
    close(k.fd);
    close(ls);

    start_node(&c, &k, NULL, &ls);
    CHECK(wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS) >= 0);
    close(k.fd); /* the server goes away */
    CHECK_EQ(finish(&c, WAIT_MS), 1);
    CHECK(strstr(c.text, "closed the connection") != NULL);
    close(ls);
}

/* One line on stderr and exit status `want`. */
static void expect_error(int want, const char *part, char *const argv[])
{
    child_t c;
    spawn(&c, argv);
    int rc = finish(&c, WAIT_MS);
    int lines = 0;
    for (const char *p = c.text; *p; p++) {
        lines += *p == '\n';
    }
    if (rc != want || lines != 1 || strstr(c.text, part) == NULL) {
        printf("  %s ...: exit %d, stderr '%s'\n", argv[1] ? argv[1] : "", rc, c.text);
    }
    CHECK_EQ(rc, want);
    CHECK_EQ(lines, 1);
    CHECK(strstr(c.text, part) != NULL);
}

static void test_bad_arguments(void)
{
    char *p = (char *)prog;
    expect_error(
        2, "exactly one of --iface and --bus",
        (char *[]){p, "--iface", "vcan0", "--bus", "socketcan://vcan0", "--node-id", "5", NULL});
    expect_error(2, "--node-id must be 1..127",
                 (char *[]){p, "--iface", "vcan0", "--node-id", "0", NULL});
    expect_error(2, "--node-id must be 1..127",
                 (char *[]){p, "--iface", "vcan0", "--node-id", "5x", NULL});
    expect_error(2, "--node-id is required", (char *[]){p, "--iface", "vcan0", NULL});
    expect_error(2, "unknown option", (char *[]){p, "--frobnicate", "1", NULL});
    expect_error(2, "needs a value", (char *[]){p, "--iface", NULL});
    expect_error(
        2, "exactly one",
        (char *[]){p, "--iface", "vcan0", "--bus", "socketcand://h/c", "--node-id", "5", NULL});
    expect_error(2, "--bus tcp://h:1/c: unknown bus URL",
                 (char *[]){p, "--bus", "tcp://h:1/c", "--node-id", "5", NULL});
    expect_error(2, "--heartbeat must be",
                 (char *[]){p, "--iface", "vcan0", "--node-id", "5", "--heartbeat", "-1", NULL});
    expect_error(2, "--sdo-timeout must be 1..65535 ms",
                 (char *[]){p, "--iface", "vcan0", "--node-id", "5", "--sdo-timeout", "0", NULL});
    expect_error(
        2, "--sdo-timeout must be 1..65535 ms",
        (char *[]){p, "--iface", "vcan0", "--node-id", "5", "--sdo-timeout", "65536", NULL});
    expect_error(2, "not a folder",
                 (char *[]){p, "--bus", "socketcand://127.0.0.1:1/c", "--node-id", "5", "--store",
                            "/nonexistent/dir", NULL});
    expect_error(1, "no such CAN interface",
                 (char *[]){p, "--iface", "nosuchcan9", "--node-id", "5", NULL});
    expect_error(1, "Connection refused",
                 (char *[]){p, "--bus", "socketcand://127.0.0.1:1/vcan0", "--node-id", "5", NULL});
}

static void test_bus_from_the_environment(void)
{
    child_t c;
    conn_t k;
    int ls;
    start_node_on(&c, &k, NULL, &ls, true);
    CHECK(wait_text(&k, 0, "< send 707 1 00 >", WAIT_MS) >= 0);
    kill(c.pid, SIGTERM);
    CHECK_EQ(finish(&c, WAIT_MS), 0);
    CHECK(strstr(c.text, "node 7 on socketcand://127.0.0.1:") != NULL);
    close(k.fd);
    close(ls);

    char *p = (char *)prog;
    char *node[] = {p, "--node-id", "5", NULL};
    struct {
        const char *env; /* NULL: unset */
        int want;
        const char *part;
    } cases[] = {
        {"socketcan://nosuchcan9", 1, "no such CAN interface"},
        {"virtual://x", 1, "CANOLA_BUS=virtual://x: python-can's in-process virtual bus"},
        {"tcp://h:1/c", 1, "CANOLA_BUS=tcp://h:1/c: unknown bus URL"},
        {"socketcand://h", 1, "CANOLA_BUS=socketcand://h: expected /CHANNEL"},
        {"socketcan://", 1, "expected socketcan://IFACE"},
        {"socketcand://127.0.0.1:1/vcan0", 1, "Connection refused"},
        {"", 2, "no bus: give --iface IFACE or --bus URL, or set CANOLA_BUS=URL"},
        {NULL, 2, "no bus: give --iface IFACE or --bus URL, or set CANOLA_BUS=URL"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        if (cases[i].env != NULL) {
            setenv("CANOLA_BUS", cases[i].env, 1);
        } else {
            unsetenv("CANOLA_BUS");
        }
        expect_error(cases[i].want, cases[i].part, node);
    }
    setenv("CANOLA_BUS", OVERRIDDEN_BUS, 1);
    /* --bus takes the same URLs */
    expect_error(1, "no such CAN interface",
                 (char *[]){p, "--bus", "socketcan://nosuchcan9", "--node-id", "5", NULL});
    expect_error(2, "--bus virtual://x: python-can's in-process virtual bus",
                 (char *[]){p, "--bus", "virtual://x", "--node-id", "5", NULL});
}

int main(int argc, char **argv)
{
    alarm(180);
    setvbuf(stdout, NULL, _IOLBF, 0);
    signal(SIGPIPE, SIG_IGN);
    if (argc != 2) {
        printf("usage: test_canola_node PATH-TO-canola-node\n");
        return 2;
    }
    prog = argv[1];
    setenv("CANOLA_BUS", OVERRIDDEN_BUS, 1);
    RUN(test_runs_on_a_socketcand_bus);
    RUN(test_lss_node_id_stored);
    RUN(test_sigint_and_server_gone);
    RUN(test_sdo_timeout_option);
    RUN(test_bad_arguments);
    RUN(test_bus_from_the_environment);
    return check_summary();
}
