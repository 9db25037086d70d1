/* SPDX-License-Identifier: Apache-2.0 */
/*
 * consumer.c -- a program built against canola the way its users build: against an
 * installed tree (find_package(canola) or pkg-config) or with add_subdirectory(canola).
 * tests/packaging/c-install builds it each way and runs it.
 *
 * A device (node 5, parameters stored in files in the folder given as argument) and a
 * master (node 1) on the simulated bus: the device's boot-up is seen on the bus, the master
 * reads its vendor-ID (expedited SDO) and its device name (segmented SDO). It prints
 * sizeof(co_node_t), which must be the same however the program was built.
 *
 * Built with -DCANOLA_EXPECTED_SDO_BUF_SIZE=N, it checks
 * at compile time that it sees the library's configuration (tests/packaging/config.h, a
 * MinSizeRel build), not the defaults.
 *
 * usage: consumer STORAGE_DIR    exit 0 when every step happened, 1 naming the one that did not
 */
#include <stdio.h>
#include <string.h>

#include "canola/canola.h"
#include "canola/file_storage.h"
#include "canola/sim.h"

#ifdef CANOLA_EXPECTED_SDO_BUF_SIZE
_Static_assert(CO_SDO_BUF_SIZE == CANOLA_EXPECTED_SDO_BUF_SIZE,
               "CO_SDO_BUF_SIZE is not the library's value");
#endif

#define DEVICE_ID 5
#define VENDOR_ID 0x00C0FFEEu
#define MS 1000u

/* A small dictionary: device type, error register, device name, heartbeat, vendor-ID. */
typedef struct station {
    uint32_t device_type;
    uint8_t error_register;
    char name[24];
    uint16_t heartbeat_ms;
    uint8_t identity_count;
    uint32_t vendor;
    co_od_entry_t entries[6];
    co_node_t node;
    co_sim_port_t port;
} station_t;

static const uint32_t k_device_type = 0x00000191u;
static const uint8_t k_zero_u8 = 0;
static const uint16_t k_zero_u16 = 0;
static const uint8_t k_one_u8 = 1;
static const uint32_t k_vendor = VENDOR_ID;
static const char k_name[24] = "installed canola device";

static co_od_t station_od(station_t *s)
{
    const co_od_entry_t e[6] = {
        {.index = 0x1000,
         .type = CO_TYPE_UNSIGNED32,
         .attr = CO_OD_RO,
         .size = 4,
         .value = &s->device_type,
         .dflt = &k_device_type},
        {.index = 0x1001,
         .type = CO_TYPE_UNSIGNED8,
         .attr = CO_OD_RO,
         .size = 1,
         .value = &s->error_register,
         .dflt = &k_zero_u8},
        {.index = 0x1008,
         .type = CO_TYPE_VISIBLE_STRING,
         .attr = CO_OD_CO,
         .size = 24,
         .value = s->name,
         .dflt = k_name},
        {.index = 0x1017,
         .type = CO_TYPE_UNSIGNED16,
         .attr = CO_OD_RW,
         .size = 2,
         .value = &s->heartbeat_ms,
         .dflt = &k_zero_u16},
        {.index = 0x1018,
         .type = CO_TYPE_UNSIGNED8,
         .attr = CO_OD_CO,
         .size = 1,
         .value = &s->identity_count,
         .dflt = &k_one_u8},
        {.index = 0x1018,
         .sub = 1,
         .type = CO_TYPE_UNSIGNED32,
         .attr = CO_OD_RO,
         .size = 4,
         .value = &s->vendor,
         .dflt = &k_vendor},
    };
    memcpy(s->entries, e, sizeof e);
    co_od_t od = {.entries = s->entries, .count = 6};
    co_od_reset(&od, 0x1000, 0xFFFF, 0);
    return od;
}

static int start(co_sim_bus_t *bus, station_t *s, uint8_t id, const co_storage_t *storage)
{
    co_node_config_t cfg = {.node_id = id, .od = station_od(s), .storage = storage};
    if (co_sim_port_attach(bus, &s->port) != CO_OK) {
        return -1;
    }
    cfg.driver = co_sim_port_driver(&s->port);
    if (co_node_init(&s->node, &cfg) != CO_OK) {
        return -1;
    }
    co_sim_port_bind(&s->port, &s->node);
    return co_node_start(&s->node, bus->now_us) == CO_OK ? 0 : -1;
}

typedef struct results {
    bool bootup;      /* 0x705 with 00 seen on the bus */
    bool vendor_done; /* the vendor-ID read finished */
    co_abort_t vendor_abort;
    uint64_t vendor;
    bool name_done; /* the device name read finished */
    co_abort_t name_abort;
    uint32_t name_len;
    uint8_t name[32];
} results_t;

static void watch(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    (void)now_us;
    results_t *r = ctx;
    if (frame->id == 0x700u + DEVICE_ID && frame->len == 1 && frame->data[0] == 0) {
        r->bootup = true;
    }
}

static void vendor_read(void *ctx, uint8_t channel, co_abort_t abort, uint64_t value, uint32_t len)
{
    (void)channel;
    (void)len;
    results_t *r = ctx;
    r->vendor_done = true;
    r->vendor_abort = abort;
    r->vendor = value;
}

static void name_read(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    results_t *r = ctx;
    r->name_done = true;
    r->name_abort = abort;
    r->name_len = len;
}

static int fail(const char *what)
{
    fprintf(stderr, "consumer: %s\n", what);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        return fail("usage: consumer STORAGE_DIR");
    }
    static co_sim_bus_t bus;
    static co_sim_port_t watcher;
    static station_t master, device;
    static co_file_storage_t storage;
    static results_t r;
    if (co_file_storage_init(&storage, argv[1]) != CO_OK) {
        return fail("the storage folder is refused (co_file_storage_init)");
    }
    if (co_sim_bus_init(&bus, 125000) != CO_OK ||
        co_sim_port_attach_raw(&bus, &watcher, watch, &r) != CO_OK ||
        start(&bus, &device, DEVICE_ID, &storage.api) != 0 || start(&bus, &master, 1, NULL) != 0) {
        return fail("setting up the bus and the nodes failed");
    }
    co_sim_run_until(&bus, 50 * MS);
    if (!r.bootup) {
        return fail("no boot-up of node 5 on the bus");
    }
    if (co_sdo_client_setup(&master.node, 0, DEVICE_ID) != CO_OK ||
        co_sdo_read_value(&master.node, 0, 0x1018, 1, vendor_read, &r) != CO_OK) {
        return fail("the vendor-ID read could not start");
    }
    co_sim_run_until(&bus, 100 * MS);
    if (!r.vendor_done || r.vendor_abort != CO_ABORT_NONE || r.vendor != VENDOR_ID) {
        return fail("the vendor-ID read did not give 0x00C0FFEE");
    }
    if (co_sdo_upload(&master.node, 0, 0x1008, 0, CO_SDO_SEGMENTED, r.name, sizeof r.name,
                      name_read, &r) != CO_OK) {
        return fail("the device name read could not start");
    }
    co_sim_run_until(&bus, 200 * MS);
    if (!r.name_done || r.name_abort != CO_ABORT_NONE || r.name_len != strlen(k_name) ||
        memcmp(r.name, k_name, r.name_len) != 0) {
        return fail("the device name read did not give the device's name");
    }
    printf("consumer: boot-up seen, vendor-ID 0x%08X, device name \"%.*s\"; "
           "CO_SDO_BUF_SIZE %d, sizeof(co_node_t) %u\n",
           (unsigned)r.vendor, (int)r.name_len, (const char *)r.name, CO_SDO_BUF_SIZE,
           (unsigned)sizeof(co_node_t));
    return 0;
}
