/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola_node.c -- canola-node: the example device (examples/example_od.c) as a Linux
 * program, firmware-style: one node on SocketCAN or on a socketcand server/hub, run by
 * the event loop (canola/linux_loop.h).
 *
 * usage: canola-node [--iface IFACE | --bus URL] --node-id N [--store DIR] [--heartbeat MS]
 *                    [--sdo-timeout MS]
 *
 * The bus: --iface IFACE, or --bus URL (socketcand://HOST[:PORT]/CHANNEL or
 * socketcan://IFACE), else the URL in the environment variable CANOLA_BUS, which the canola
 * command line reads too (python-can's configuration, its fallback, is the Python side's
 * alone; so is its in-process virtual:// bus).
 *
 * With --store DIR it keeps stored parameters (0x1010/0x1011) and the LSS configuration
 * there: an LSS store configuration (CiA 305) writes DIR/lss.params, and its node-ID is the
 * one canola-node starts with from then on (--node-id is then only the default, and may
 * be left out); an NMT reset node brings that stored node-ID back, as a power cycle does.
 * A node-ID configured by LSS and not stored lasts until the next reset node.
 *
 * NMT state changes are logged to stderr, one line each. SIGTERM or SIGINT stop it
 * cleanly (exit 0). Bad arguments (no bus named among them): one line on stderr, exit 2. A
 * bus that fails or cannot be opened, a CANOLA_BUS it cannot use included: one line, exit 1.
 */
#include "canola/file_storage.h"
#include "canola/linux_loop.h"
#include "canola/socketcan.h"
#include "canola/socketcand.h"
#include "example_od.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROG "canola-node"
#define CONNECT_TIMEOUT_MS 5000u
#define BUS_ENV "CANOLA_BUS"
#define TOKEN_ENV "CANOLA_TOKEN"
#define SOCKETCAN_SCHEME "socketcan://"

static const char usage[] =
    "usage: " PROG " [--iface IFACE | --bus URL] --node-id N [--store DIR] [--heartbeat MS]\n"
    "                   [--sdo-timeout MS] [--token TOKEN]\n"
    "  --iface IFACE    SocketCAN interface (can0, vcan0)\n"
    "  --bus URL        socketcand://HOST[:PORT]/CHANNEL (a socketcand server or the\n"
    "                   `canola bus serve` hub) or socketcan://IFACE; without --iface and\n"
    "                   --bus, the URL in $" BUS_ENV " (as for the canola commands)\n"
    "  --node-id N      1..127 (with --store, a node-ID stored by LSS wins)\n"
    "  --store DIR      keep stored parameters (0x1010/0x1011) and the LSS configuration\n"
    "                   (store configuration) in files in DIR\n"
    "  --heartbeat MS   producer heartbeat time 0x1017 at power-on (default 1000)\n"
    "  --sdo-timeout MS SDO server time-out: a transfer the client leaves waiting that\n"
    "                   long is aborted (1..65535, default 1000)\n"
    "  --token TOKEN    the secret a hub that asks for one (canola bus serve --token)\n"
    "                   gets first; default $" TOKEN_ENV "\n";

typedef struct args {
    const char *iface; /* SocketCAN interface, or NULL */
    const char *bus;   /* socketcand URL, or NULL */
    const char *store;
    const char *token; /* for a socketcand hub that asks for one, or NULL */
    long node_id;
    long heartbeat_ms;
    long sdo_timeout_ms;
} args_t;

typedef struct app {
    example_od_t od;
    co_node_t node;
    co_loop_t loop;
    co_socketcan_t can;
    co_socketcand_t scd;
    co_file_storage_t storage;
    const char *where;
} app_t;

static app_t app; /* large (the dictionary and the node): not on the stack */

static int bad_args(const char *fmt, const char *value)
{
    fprintf(stderr, PROG ": ");
    fprintf(stderr, fmt, value);
    fprintf(stderr, " (" PROG " --help)\n");
    return 2;
}

/* A whole decimal or 0x-hex number within lo..hi, else -1. */
static long number(const char *s, long lo, long hi)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 0);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) {
        return -1;
    }
    return v;
}

/* Why `url` names no bus canola-node can open (NULL: it does; a socketcan:// URL then
 * sets a->iface, any other a->bus). */
static const char *bus_url(const char *url, args_t *a, char *why, size_t why_cap)
{
    if (strncmp(url, SOCKETCAN_SCHEME, sizeof SOCKETCAN_SCHEME - 1) == 0) {
        const char *iface = url + sizeof SOCKETCAN_SCHEME - 1;
        if (*iface == '\0' || strchr(iface, '/') != NULL) {
            return "expected socketcan://IFACE";
        }
        a->iface = iface;
        a->bus = NULL;
        return NULL;
    }
    if (strncmp(url, "virtual://", 10) == 0) {
        return "python-can's in-process virtual bus is not reachable from another program: "
               "use socketcand://HOST:PORT/CHANNEL (canola bus serve) or socketcan://IFACE";
    }
    if (strncmp(url, "socketcand://", 13) != 0) {
        return "unknown bus URL: use socketcand://HOST:PORT/CHANNEL or socketcan://IFACE";
    }
    co_socketcand_url_t u;
    if (co_socketcand_parse_url(url, &u, why, why_cap) != CO_OK) {
        return why;
    }
    a->bus = url;
    return NULL;
}

/* --iface, --bus, else CANOLA_BUS: which bus, checked (see the top of the file). */
static int choose_bus(args_t *a)
{
    char why[96];
    if (a->iface != NULL) {
        return 0;
    }
    if (a->bus != NULL) {
        const char *url = a->bus;
        const char *bad = bus_url(url, a, why, sizeof why);
        if (bad != NULL) {
            fprintf(stderr, PROG ": --bus %s: %s (" PROG " --help)\n", url, bad);
            return 2;
        }
        return 0;
    }
    const char *env = getenv(BUS_ENV);
    if (env == NULL || *env == '\0') {
        return bad_args("no bus: give --iface IFACE or --bus URL, or set " BUS_ENV "=URL%s", "");
    }
    const char *bad = bus_url(env, a, why, sizeof why);
    if (bad != NULL) {
        fprintf(stderr, PROG ": " BUS_ENV "=%s: %s\n", env, bad);
        return 1;
    }
    return 0;
}

static int parse_args(int argc, char **argv, args_t *a)
{
    memset(a, 0, sizeof *a);
    a->node_id = -1;
    a->heartbeat_ms = 1000;
    a->sdo_timeout_ms = 1000;
    for (int i = 1; i < argc; i++) {
        const char *opt = argv[i];
        if (strcmp(opt, "--help") == 0 || strcmp(opt, "-h") == 0) {
            fputs(usage, stdout);
            exit(0);
        }
        if (strncmp(opt, "--", 2) != 0) {
            return bad_args("unexpected argument '%s'", opt);
        }
        if (i + 1 >= argc) {
            return bad_args("%s needs a value", opt);
        }
        const char *val = argv[++i];
        if (strcmp(opt, "--iface") == 0) {
            a->iface = val;
        } else if (strcmp(opt, "--bus") == 0) {
            a->bus = val;
        } else if (strcmp(opt, "--store") == 0) {
            a->store = val;
        } else if (strcmp(opt, "--token") == 0) {
            a->token = val;
        } else if (strcmp(opt, "--node-id") == 0) {
            if ((a->node_id = number(val, 1, 127)) < 0) {
                return bad_args("--node-id must be 1..127, not '%s'", val);
            }
        } else if (strcmp(opt, "--heartbeat") == 0) {
            if ((a->heartbeat_ms = number(val, 0, 65535)) < 0) {
                return bad_args("--heartbeat must be 0..65535 ms, not '%s'", val);
            }
        } else if (strcmp(opt, "--sdo-timeout") == 0) {
            if ((a->sdo_timeout_ms = number(val, 1, 65535)) < 0) {
                return bad_args("--sdo-timeout must be 1..65535 ms, not '%s'", val);
            }
        } else {
            return bad_args("unknown option '%s'", opt);
        }
    }
    if (a->iface != NULL && a->bus != NULL) {
        return bad_args("give exactly one of --iface and --bus%s", "");
    }
    if (a->node_id < 0 && a->store == NULL) {
        return bad_args("--node-id is required%s", "");
    }
    if (a->token == NULL) {
        a->token = getenv(TOKEN_ENV);
    }
    return choose_bus(a);
}

/* The node-ID an LSS store configuration left in `dir` replaces `*node_id` (the
 * --node-id given, or -1), said on stderr. Nonzero (said too) when there is none at all,
 * or lss.params is damaged and no --node-id was given. */
static int stored_node_id(const char *dir, long *node_id)
{
    uint8_t id = 0;
    uint8_t timing = 0;
    co_err_t err = co_file_storage_load_lss(&app.storage, &id, &timing);
    if (err == CO_OK) {
        fprintf(stderr, PROG ": node-ID %u, stored by LSS in %s/lss.params", id, dir);
        if (*node_id >= 0 && *node_id != id) {
            fprintf(stderr, " (not --node-id %ld)", *node_id);
        }
        fputc('\n', stderr);
        *node_id = id;
        return 0;
    }
    if (err != CO_ERR_NOT_FOUND) {
        fprintf(stderr, PROG ": %s/lss.params: damaged (not a line of canola-lss 1): %s\n", dir,
                *node_id >= 0 ? "ignored, --node-id used" : "give --node-id");
    }
    if (*node_id < 0) {
        if (err == CO_ERR_NOT_FOUND) {
            fprintf(stderr, PROG ": --node-id is required (no node-ID stored by LSS in %s)\n", dir);
        }
        return 2;
    }
    return 0;
}

static void on_state(void *user, co_nmt_state_t state)
{
    app_t *a = user;
    fprintf(stderr, PROG ": node %u on %s: %s\n", co_node_id(&a->node), a->where,
            co_nmt_state_name((uint8_t)state));
}

static const char *error_text(co_node_error_t error)
{
    switch (error) {
    case CO_NODE_ERR_TX_OVERFLOW:
        return "transmit queue overflow, a frame was lost";
    case CO_NODE_ERR_TX_DRIVER:
        return "the bus refused a frame";
    case CO_NODE_ERR_STORED_COMM:
        return "stored communication parameters (comm.params) failed their checks: ignored, "
               "defaults in use (EMCY 0xFF11)";
    case CO_NODE_ERR_STORED_APP:
        return "stored application parameters (app.params) failed their checks: ignored, "
               "defaults in use (EMCY 0xFF12)";
    case CO_NODE_ERR_STORE_FAILED:
        return "storing parameters failed (full disk, read-only or broken storage): the "
               "files stored before stay, EMCY 0x5530";
    case CO_NODE_ERR_SDO_COB_FIXED:
        return "the dictionary gives 0x1200 sub1/sub2 other COB-IDs than CiA 301 fixes: "
               "the default SDO server serves on 0x600/0x580 + node-ID regardless";
    }
    return "unknown error";
}

static void on_error(void *user, co_node_error_t error)
{
    app_t *a = user;
    fprintf(stderr, PROG ": node %u on %s: %s\n", co_node_id(&a->node), a->where,
            error_text(error));
}

int main(int argc, char **argv)
{
    args_t args;
    int rc = parse_args(argc, argv, &args);
    if (rc != 0) {
        return rc;
    }
    co_node_config_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.od = example_od_init(&app.od, (uint16_t)args.heartbeat_ms);
    cfg.sdo_timeout_ms = (uint16_t)args.sdo_timeout_ms;
    cfg.user = &app;
    cfg.on_state = on_state;
    cfg.on_error = on_error;
    if (args.store != NULL) {
        if (co_file_storage_init(&app.storage, args.store) != CO_OK) {
            fprintf(stderr, PROG ": --store %s: not a folder (or the path is too long)\n",
                    args.store);
            return 2;
        }
        cfg.storage = &app.storage.api;
        if (stored_node_id(args.store, &args.node_id) != 0) {
            return 2;
        }
    }
    cfg.node_id = (uint8_t)args.node_id;

    /* Signals first: a SIGTERM during the connection must not kill us half-way. */
    if (co_loop_init(&app.loop) != CO_OK || co_loop_handle_signals(&app.loop) != CO_OK) {
        fprintf(stderr, PROG ": event loop: %s\n", strerror(errno));
        return 1;
    }
    co_transport_t *t;
    if (args.iface != NULL) {
        app.where = args.iface;
        if (co_socketcan_open(&app.can, args.iface) != CO_OK) {
            fprintf(stderr, PROG ": %s\n", app.can.transport.error);
            return 1;
        }
        t = &app.can.transport;
    } else {
        app.where = args.bus;
        if (co_socketcand_open_auth(&app.scd, args.bus, args.token, CONNECT_TIMEOUT_MS) != CO_OK) {
            fprintf(stderr, PROG ": %s\n", app.scd.transport.error);
            return 1;
        }
        t = &app.scd.transport;
    }
    if (co_loop_add_node(&app.loop, &app.node, &cfg, t) != CO_OK) {
        fprintf(stderr, PROG ": cannot set up node %ld\n", args.node_id);
        return 1;
    }
    if (args.store != NULL) { /* LSS store configuration: into the folder */
        const co_lss_slave_config_t lss = {.store = co_file_storage_store_lss, .ctx = &app.storage};
        (void)co_lss_slave_setup(&app.node, &lss);
    }
    fprintf(stderr, PROG ": node %u on %s, heartbeat %ld ms%s%s\n", cfg.node_id, app.where,
            args.heartbeat_ms, args.store ? ", parameters in " : "", args.store ? args.store : "");
    (void)co_node_start(&app.node, co_linux_now_us());

    co_loop_reason_t why = co_loop_run(&app.loop);
    int status = 0;
    if (why == CO_LOOP_SIGNAL) {
        fprintf(stderr, PROG ": stopped by %s\n",
                co_loop_signal(&app.loop) == SIGINT ? "SIGINT" : "SIGTERM");
    } else if (why == CO_LOOP_TRANSPORT_FAILED) {
        fprintf(stderr, PROG ": %s\n", co_loop_failed(&app.loop)->error);
        status = 1;
    } else {
        fprintf(stderr, PROG ": event loop: %s\n", co_loop_reason_name(why));
        status = 1;
    }
    co_transport_close(t);
    co_loop_close(&app.loop);
    return status;
}
