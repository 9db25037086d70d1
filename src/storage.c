/* SPDX-License-Identifier: Apache-2.0 */
/*
 * storage.c -- stored parameters (0x1010, 0x1011); see canola/storage.h.
 */
#include "storage_internal.h"

#include "crc16.h"

/* The storage given, or none when the feature is left out (CO_CONFIG_STORAGE 0): every
 * path below then is the "no storage" one, and the compiler drops the rest. */
static inline const co_storage_t *storage_of(const co_node_t *node)
{
    return CO_CONFIG_STORAGE ? node->cfg.storage : NULL;
}

#define RECORD_HEAD 4u /* index (2), sub-index (1), length (1) */

/* Entries a save of `group` records: in the group's range, writable from the network, with
 * storage, not a DOMAIN, and not one of the objects that are commands or logs rather than
 * parameters. */
static bool is_parameter(const co_od_t *od, const co_od_entry_t *e, co_param_group_t group)
{
    if (e->index < co_group_first(group) || e->index > co_group_last(group) ||
        !(co_od_attr(od, e) & CO_OD_WRITE) || (co_od_attr(od, e) & CO_OD_CONST) ||
        co_od_value(od, e) == NULL || co_od_type(od, e) == CO_TYPE_DOMAIN) {
        return false;
    }
    return e->index != 0x1003 && e->index != 0x1010 && e->index != 0x1011;
}

/* ---- the image's header */

#define HEADER_CRC_AT 10u         /* the CRC follows the header's other fields */
#define IMAGE_LEN_MAX 0x7FFFFFFFu /* no offset arithmetic below can wrap */
/* CO_STORE_MAGIC ("CNPS"), the header's bytes 0..3, as a little-endian word. */
#define MAGIC_WORD                                                                                 \
    ((uint32_t)'C' | ((uint32_t)'N' << 8) | ((uint32_t)'P' << 16) | ((uint32_t)'S' << 24))

/* Header bytes 4..5 of an image of `group` (format, group) as a little-endian half-word. */
static uint16_t format_and_group(co_param_group_t group)
{
    return (uint16_t)(CO_STORE_FORMAT | ((unsigned)group << 8));
}

/* Header bytes 0..9 of an image of `group` with `len` bytes of records. */
static void header_fields(uint8_t hdr[CO_STORE_HEADER_SIZE], co_param_group_t group, uint32_t len)
{
    co_put_u32(hdr, MAGIC_WORD);
    co_put_u16(&hdr[4], format_and_group(group));
    co_put_u32(&hdr[6], len);
}

/* The CRC covers the records, then header bytes 0..9: a save knows the records' CRC only
 * after its first pass, and writes the header before the records. */
static uint16_t image_crc(uint16_t records_crc, const uint8_t hdr[CO_STORE_HEADER_SIZE])
{
    return co_crc16(records_crc, hdr, HEADER_CRC_AT);
}

static void group_error_clear(co_node_t *node, co_param_group_t group)
{
    (void)co_emcy_clear(node, (uint16_t)(CO_EMCY_STORE_REJECTED + group));
}

/* ---- saving */

/* Length and CRC of the records written (or only counted). */
typedef struct image_sum {
    uint32_t len;
    uint16_t crc;
} image_sum_t;

/* One pass over the group's parameters: each record summed, and written when `write`. */
static co_err_t each_record(co_node_t *node, co_param_group_t group, bool write, image_sum_t *sum)
{
    const co_storage_t *st = storage_of(node);
    const co_od_t *od = &node->cfg.od;
    co_err_t err = CO_OK;
    for (uint32_t i = 0; i < od->count && err == CO_OK; i++) {
        const co_od_entry_t *e = &od->entries[i];
        if (!is_parameter(od, e, group)) {
            continue;
        }
        uint8_t rec[RECORD_HEAD + CO_STORE_VALUE_MAX];
        uint32_t n = 0;
        uint32_t total = 0;
        co_abort_t abort = co_od_read(od, e, 0, &rec[RECORD_HEAD], CO_STORE_VALUE_MAX, &n, &total);
        if (abort != CO_ABORT_NONE || total != n) {
            continue; /* unreadable or too long to store */
        }
        co_put_u16(rec, e->index);
        rec[2] = e->sub;
        rec[3] = (uint8_t)n;
        sum->len += RECORD_HEAD + n;
        sum->crc = co_crc16(sum->crc, rec, RECORD_HEAD + n);
        if (write) {
            err = st->write(st->ctx, rec, RECORD_HEAD + n);
        }
    }
    return sum->len <= IMAGE_LEN_MAX ? err : CO_ERR_FULL;
}

/* Begin and write the image of `group`, not committed. Two passes: the first sums the
 * records for the header, the second writes header and records; a dictionary that changed
 * between them fails the save (see canola/storage.h). (Out of line in a build for size:
 * inlined, each_group's loop saves more registers.) */
static CO_SIZE_NOINLINE co_err_t write_group(co_node_t *node, co_param_group_t group)
{
    const co_storage_t *st = storage_of(node);
    image_sum_t planned = {0, 0};
    image_sum_t written = {0, 0};
    co_err_t err = each_record(node, group, false, &planned);
    if (err != CO_OK) {
        return err;
    }
    uint8_t hdr[CO_STORE_HEADER_SIZE];
    header_fields(hdr, group, planned.len);
    co_put_u16(&hdr[HEADER_CRC_AT], image_crc(planned.crc, hdr));
    err = st->begin(st->ctx, group);
    if (err == CO_OK) {
        err = st->write(st->ctx, hdr, sizeof hdr);
    }
    if (err == CO_OK) {
        err = each_record(node, group, true, &written);
    }
    if (err == CO_OK && (written.len != planned.len || written.crc != planned.crc)) {
        err = CO_ERR_STATE;
    }
    return err;
}

/* The groups that sub-index `which` of 0x1010/0x1011 names (1: both, 2: communication,
 * 3: application), in that order: each saved, or erased when `restore` (its defaults at
 * the next reset). A save of both through a storage that stages is one commit; otherwise
 * each group is committed (or erased) alone. Each group done ends the EMCY of its rejected
 * image; a save that fails is discarded whole (what was staged with it too). */
static CO_SIZE_INLINE co_err_t each_group(co_node_t *node, uint8_t which, bool restore)
{
    const co_storage_t *st = storage_of(node);
    bool one_step = which == 1 && st->stage != NULL && !restore;
    co_err_t err = CO_OK;
    for (uint8_t g = CO_PARAMS_COMMUNICATION; g <= CO_PARAMS_APPLICATION && err == CO_OK; g++) {
        co_param_group_t group = (co_param_group_t)g;
        if (which == 4u - g) {
            continue; /* the other group alone */
        }
        if (restore) {
            err = st->erase(st->ctx, group);
        } else {
            err = write_group(node, group);
            if (err == CO_OK) {
                bool stage = one_step && group == CO_PARAMS_COMMUNICATION;
                err = stage ? st->stage(st->ctx) : st->commit(st->ctx);
            }
            if (err != CO_OK && st->discard != NULL) {
                st->discard(st->ctx);
            }
        }
        if (err == CO_OK) {
            group_error_clear(node, group);
        }
    }
    return err;
}

/* A command of sub-index `which` on 0x1010 (save) or 0x1011 (`restore`): the groups done,
 * or the failure reported (EMCY, on_error) until a later command succeeds; either way
 * 0x1010/0x1011 read the storage's capability again. */
static co_err_t run_command(co_node_t *node, uint8_t which, bool restore)
{
    co_err_t err = each_group(node, which, restore);
    if (err == CO_OK) {
        (void)co_emcy_clear(node, CO_EMCY_STORE_FAILED);
    } else {
        const uint8_t mfr[5] = {which, restore ? 0x11u : 0x10u, 0, 0, 0};
        (void)co_emcy_raise(node, CO_EMCY_STORE_FAILED, mfr);
        if (node->cfg.on_error) {
            node->cfg.on_error(node->cfg.user, CO_NODE_ERR_STORE_FAILED);
        }
    }
    co_storage_reset_comm(node); /* the capability may have come or gone with it */
    return err;
}

co_err_t co_storage_save(co_node_t *node, uint8_t which)
{
    if (storage_of(node) == NULL) {
        return CO_ERR_STATE;
    }
    if (which < 1 || which > 3) {
        return CO_ERR_ARG;
    }
    return run_command(node, which, false);
}

/* ---- checking and loading */

/* Read exactly `len` bytes at `offset`: CO_STORE_INTACT, or why not. */
static co_store_fault_t read_exact(const co_storage_t *st, co_param_group_t group, uint32_t offset,
                                   uint8_t *buf, uint32_t len)
{
    uint32_t n = 0;
    if (st->read(st->ctx, group, offset, buf, len, &n) != CO_OK) {
        return CO_STORE_READ_ERROR;
    }
    return n == len ? CO_STORE_INTACT : CO_STORE_BAD_LENGTH;
}

/* The records of `len` bytes: their CRC (continued from `crc`), and whether they end
 * exactly at `len` (each record's length byte read as the bytes stream past). */
static co_store_fault_t check_records(const co_storage_t *st, co_param_group_t group, uint32_t len,
                                      uint16_t *crc)
{
    uint8_t chunk[64];
    uint32_t next = 0; /* offset of the next record's head */
    for (uint32_t at = 0; at < len;) {
        uint32_t want = len - at < sizeof chunk ? len - at : (uint32_t)sizeof chunk;
        co_store_fault_t fault = read_exact(st, group, CO_STORE_HEADER_SIZE + at, chunk, want);
        if (fault != CO_STORE_INTACT) {
            return fault;
        }
        *crc = co_crc16(*crc, chunk, want);
        for (; next + 3u < at + want; next += RECORD_HEAD + chunk[next + 3u - at]) {
        }
        at += want;
    }
    /* Nothing may follow the records: a byte read there is one too many. */
    co_store_fault_t after = read_exact(st, group, CO_STORE_HEADER_SIZE + len, chunk, 1);
    if (after != CO_STORE_BAD_LENGTH) {
        return after == CO_STORE_INTACT ? CO_STORE_BAD_LENGTH : after;
    }
    return next == len ? CO_STORE_INTACT : CO_STORE_BAD_RECORDS;
}

co_store_fault_t co_storage_verify(const co_node_t *node, co_param_group_t group)
{
    const co_storage_t *st = storage_of(node);
    if (st == NULL) {
        return CO_STORE_NONE;
    }
    uint8_t hdr[CO_STORE_HEADER_SIZE];
    uint32_t n = 0;
    co_err_t err = st->read(st->ctx, group, 0, hdr, sizeof hdr, &n);
    if (err != CO_OK) {
        return err == CO_ERR_NOT_FOUND ? CO_STORE_NONE : CO_STORE_READ_ERROR;
    }
    if (n != sizeof hdr || co_get_u32(hdr) != MAGIC_WORD ||
        co_get_u16(&hdr[4]) != format_and_group(group)) {
        return CO_STORE_BAD_HEADER;
    }
    uint32_t len = co_get_u32(&hdr[6]);
    if (len > IMAGE_LEN_MAX) {
        return CO_STORE_BAD_LENGTH;
    }
    uint16_t crc = 0;
    co_store_fault_t records = check_records(st, group, len, &crc);
    if (records == CO_STORE_READ_ERROR || records == CO_STORE_BAD_LENGTH) {
        return records;
    }
    if (image_crc(crc, hdr) != co_get_u16(&hdr[HEADER_CRC_AT])) {
        return CO_STORE_BAD_CRC;
    }
    return records;
}

#if CO_CONFIG_STORAGE

/* Apply the records of a verified image. False when the storage no longer reads what was
 * verified (the caller then restores the defaults). */
static CO_SIZE_INLINE bool apply_records(co_node_t *node, co_param_group_t group)
{
    const co_storage_t *st = storage_of(node);
    const co_od_t *od = &node->cfg.od;
    uint8_t hdr[CO_STORE_HEADER_SIZE];
    if (read_exact(st, group, 0, hdr, sizeof hdr) != CO_STORE_INTACT) {
        return false;
    }
    uint32_t end = CO_STORE_HEADER_SIZE + co_get_u32(&hdr[6]);
    for (uint32_t offset = CO_STORE_HEADER_SIZE; offset < end;) {
        uint8_t rec[RECORD_HEAD + 255];
        if (read_exact(st, group, offset, rec, RECORD_HEAD) != CO_STORE_INTACT) {
            return false;
        }
        uint32_t len = rec[3];
        if (read_exact(st, group, offset + RECORD_HEAD, &rec[RECORD_HEAD], len) !=
            CO_STORE_INTACT) {
            return false;
        }
        offset += RECORD_HEAD + len;
        const co_od_entry_t *e = co_od_find(od, co_get_u16(rec), rec[2], NULL);
        if (e != NULL && is_parameter(od, e, group) &&
            co_od_check(od, e, &rec[RECORD_HEAD], len) == CO_ABORT_NONE) {
            (void)co_od_store(od, e, &rec[RECORD_HEAD], len);
        }
    }
    return true;
}

_Static_assert(CO_NODE_ERR_STORED_APP - CO_NODE_ERR_STORED_COMM ==
                   CO_PARAMS_APPLICATION - CO_PARAMS_COMMUNICATION,
               "on_error's codes follow the groups");

/* A rejected image (the group holds its defaults): an EMCY and on_error. Called once reset
 * communication is done: the reset of the communication group clears the error history
 * (0x1003), which must keep the EMCY, and the EMCY goes out on the COB-ID just loaded. */
void co_storage_report(co_node_t *node, co_param_group_t group, co_store_fault_t fault)
{
    if (fault == CO_STORE_INTACT || fault == CO_STORE_NONE) {
        return;
    }
    const uint8_t mfr[5] = {(uint8_t)fault, 0, 0, 0, 0};
    (void)co_emcy_raise(node, (uint16_t)(CO_EMCY_STORE_REJECTED + group), mfr);
    if (node->cfg.on_error) {
        /* (STORED_COMM and STORED_APP follow each other as the groups do) */
        node->cfg.on_error(node->cfg.user, (co_node_error_t)(CO_NODE_ERR_STORED_COMM + group -
                                                             CO_PARAMS_COMMUNICATION));
    }
}
#endif

#if CO_CONFIG_STORAGE
/* The group's power-on values, then the values stored for it; an image that cannot be
 * applied whole leaves the power-on values. */
co_store_fault_t co_storage_reset_group(co_node_t *node, co_param_group_t group)
{
    co_group_defaults(node, group);
    co_store_fault_t fault = co_storage_verify(node, group);
    if (fault == CO_STORE_INTACT && !apply_records(node, group)) {
        co_group_defaults(node, group); /* no half image */
        fault = CO_STORE_READ_ERROR;
    }
    return fault;
}
#endif

/* ---- 0x1010 and 0x1011 */

co_abort_t co_storage_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                  uint32_t len)
{
    if (entry->sub == 0 || len != 4) {
        return CO_ABORT_NONE; /* sub0 is read-only in any sane dictionary; length is checked */
    }
    bool store = entry->index == 0x1010;
    uint32_t want = store ? CO_STORE_SIGNATURE : CO_RESTORE_SIGNATURE;
    if (storage_of(node) == NULL || entry->sub > 3 || co_get_u32(data) != want) {
        return CO_ABORT_DATA_STORE;
    }
    return run_command(node, entry->sub, !store) == CO_OK ? CO_ABORT_NONE : CO_ABORT_HARDWARE;
}

#if CO_CONFIG_STORAGE
/* What 0x1010/0x1011 subN read: 1 while the storage can save now. */
static uint64_t capability(const co_node_t *node)
{
    const co_storage_t *st = storage_of(node);
    return st != NULL && (st->can_save == NULL || st->can_save(st->ctx)) ? 1u : 0u;
}

/* Every sub-index of 0x1010 and 0x1011 reads the capability: at reset communication, and
 * after each command (which may have shown the storage can, or cannot, save now). Those
 * the dictionary lacks, or serves through hooks, are left alone (co_od_set_uint refuses). */
void co_storage_reset_comm(co_node_t *node)
{
    uint64_t value = capability(node);
    /* one loop (the compiler unrolls two nested ones), and no division (Cortex-M0 has none:
     * i / 3 would link libgcc's, 278 bytes) */
    for (unsigned i = 0; i < 6; i++) {
        unsigned second = i >= 3 ? 1u : 0u; /* 0x1011 */
        (void)co_od_set_uint(&node->cfg.od, (uint16_t)(0x1010 + second),
                             (uint8_t)(1 + i - 3 * second), value);
    }
}

/* After the command: the entries read as the capability again, not as the signature. */
void co_storage_show_capability(co_node_t *node, const co_od_entry_t *entry)
{
    (void)entry;
    co_storage_reset_comm(node);
}
#endif
