/* SPDX-License-Identifier: Apache-2.0 */
/* cm_flash_storage.c -- stored parameters in two flash slots written in turn; see
 * canola/cm_flash_storage.h for the layout and why a power cut leaves one slot valid. */
#include "canola/cm_flash_storage.h"

#include <string.h>

#define SLOT_MAGIC 0x53464E43u /* "CNFS" */
#define COMMIT_BYTE 0xC5u
#define NO_SLOT 2u
#define NO_IMAGE 0xFFFFFFFFu
#define HEADER_LEN 32u
#define HEADER_CRC_AT 28u
#define COMMIT_AT 32u

/* Where a group's image lies in a slot. */
typedef struct image_at {
    uint32_t off;
    uint32_t len;
} image_at_t;

static const uint8_t *mapped(uintptr_t addr) { return (const uint8_t *)addr; }

static unsigned group_index(co_param_group_t group)
{
    return group == CO_PARAMS_COMMUNICATION ? 0u : 1u;
}

/* CRC-32 (IEEE 802.3, reflected), bit by bit: the header is 28 bytes, read twice a boot. */
static uint32_t crc32(const uint8_t *p, uint32_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    while (n-- > 0) {
        crc ^= *p++;
        for (unsigned bit = 0; bit < 8; bit++) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

/* True when slot `s` is committed and its header intact (sequence and images in *seq and
 * images[]). The commit unit is checked first: it is the last thing a save programs. */
static bool slot_valid(const co_cm_flash_storage_t *st, unsigned s, uint32_t *seq,
                       image_at_t images[2])
{
    const uint8_t *p = mapped(st->slot[s]);
    for (unsigned i = 0; i < st->flash->unit; i++) {
        if (p[COMMIT_AT + i] != COMMIT_BYTE) {
            return false;
        }
    }
    if (co_get_u32(p) != SLOT_MAGIC || co_get_u32(p + HEADER_CRC_AT) != crc32(p, HEADER_CRC_AT)) {
        return false;
    }
    *seq = co_get_u32(p + 4);
    for (unsigned g = 0; g < 2; g++) {
        images[g].off = co_get_u32(p + 8 + 8 * g);
        images[g].len = co_get_u32(p + 12 + 8 * g);
        if (images[g].len != NO_IMAGE &&
            (images[g].off < CO_CM_FLASH_SLOT_HEAD || images[g].off > st->slot_size ||
             images[g].len > st->slot_size - images[g].off)) {
            return false;
        }
    }
    return true;
}

/* The image of `group` in the slot in use, if it holds one. */
static bool stored_image(const co_cm_flash_storage_t *st, co_param_group_t group, image_at_t *out)
{
    uint32_t seq;
    image_at_t images[2];
    if (st->current == NO_SLOT || !slot_valid(st, st->current, &seq, images)) {
        return false;
    }
    *out = images[group_index(group)];
    return out->len != NO_IMAGE;
}

static unsigned next_slot(const co_cm_flash_storage_t *st) { return st->current == 0 ? 1u : 0u; }

static uint32_t round_up(uint32_t n, uint32_t unit) { return (n + unit - 1) & ~(unit - 1); }

/* Program one unit at `offset` of the next slot and read it back. */
static co_err_t put_unit(const co_cm_flash_storage_t *st, uint32_t offset, const uint8_t *data)
{
    const co_cm_flash_t *f = st->flash;
    uintptr_t addr = st->slot[next_slot(st)] + offset;
    co_err_t err = f->program(f->hw, addr, data);
    if (err != CO_OK) {
        return err;
    }
    return memcmp(mapped(addr), data, f->unit) == 0 ? CO_OK : CO_ERR_STATE;
}

/* Program `len` bytes from `src` at `offset` of the next slot, the last unit padded with
 * erased bytes. */
static co_err_t put_bytes(co_cm_flash_storage_t *st, uint32_t offset, const uint8_t *src,
                          uint32_t len)
{
    uint8_t unit = st->flash->unit;
    for (uint32_t done = 0; done < len; done += unit) {
        uint32_t n = len - done < unit ? len - done : unit;
        memcpy(st->partial, src + done, n);
        memset(st->partial + n, 0xFF, unit - n);
        co_err_t err = put_unit(st, offset + done, st->partial);
        if (err != CO_OK) {
            return err;
        }
    }
    return CO_OK;
}

static co_err_t erase_next_slot(const co_cm_flash_storage_t *st)
{
    const co_cm_flash_t *f = st->flash;
    uintptr_t start = st->slot[next_slot(st)];
    for (uintptr_t page = start; page < start + st->slot_size; page += f->page_size) {
        co_err_t err = f->erase_page(f->hw, page);
        if (err != CO_OK) {
            return err;
        }
    }
    return CO_OK;
}

/* Bytes the image being saved may take: the slot less its head and the other group's image. */
static uint32_t room(const co_cm_flash_storage_t *st)
{
    image_at_t other;
    co_param_group_t other_group =
        st->group == CO_PARAMS_COMMUNICATION ? CO_PARAMS_APPLICATION : CO_PARAMS_COMMUNICATION;
    uint32_t taken =
        stored_image(st, other_group, &other) ? round_up(other.len, st->flash->unit) : 0u;
    return st->slot_size - CO_CM_FLASH_SLOT_HEAD - taken;
}

/* Finish the next slot and make it the one in use: the image of st->group (st->written
 * bytes, programmed from st->base on; NO_IMAGE: none), the other group's image (staged in
 * this slot, or copied from the slot in use), the header, and last the commit unit. */
static co_err_t switch_slots(co_cm_flash_storage_t *st, uint32_t new_len)
{
    image_at_t images[2];
    unsigned mine = group_index((co_param_group_t)st->group);
    images[mine].off = st->base;
    images[mine].len = new_len;
    image_at_t from;
    image_at_t *other = &images[1u - mine];
    other->len = NO_IMAGE;
    if (st->staged) {
        other->off = CO_CM_FLASH_SLOT_HEAD;
        other->len = st->staged_len;
    } else if (stored_image(st, mine == 0 ? CO_PARAMS_APPLICATION : CO_PARAMS_COMMUNICATION,
                            &from)) {
        other->off =
            CO_CM_FLASH_SLOT_HEAD + (new_len == NO_IMAGE ? 0u : round_up(new_len, st->flash->unit));
        other->len = from.len;
        co_err_t err =
            put_bytes(st, other->off, mapped(st->slot[st->current] + from.off), from.len);
        if (err != CO_OK) {
            return err;
        }
    }
    st->staged = false;

    uint8_t header[HEADER_LEN];
    co_put_u32(header, SLOT_MAGIC);
    co_put_u32(header + 4, st->seq + 1u);
    for (unsigned g = 0; g < 2; g++) {
        co_put_u32(header + 8 + 8 * g, images[g].len == NO_IMAGE ? NO_IMAGE : images[g].off);
        co_put_u32(header + 12 + 8 * g, images[g].len);
    }
    co_put_u32(header + HEADER_CRC_AT, crc32(header, HEADER_CRC_AT));
    co_err_t err = put_bytes(st, 0, header, HEADER_LEN);
    if (err != CO_OK) {
        return err;
    }
    memset(st->partial, COMMIT_BYTE, st->flash->unit);
    err = put_unit(st, COMMIT_AT, st->partial);
    if (err != CO_OK) {
        return err;
    }
    st->current = (uint8_t)next_slot(st);
    st->seq++;
    return CO_OK;
}

/* The end of the save in progress: nothing more programmed, nothing staged. */
static void end_save(co_cm_flash_storage_t *st)
{
    st->saving = false;
    st->staged = false;
}

/* A new image for `group`: the next slot erased; or, after stage, the second image of a save
 * of both groups, in the same slot after the first. */
static co_err_t begin(void *ctx, co_param_group_t group)
{
    co_cm_flash_storage_t *st = ctx;
    st->saving = false;
    st->written = 0;
    if (st->staged) {
        if (group == (co_param_group_t)st->group) {
            end_save(st);
            return CO_ERR_STATE; /* one image a group */
        }
        st->group = (uint8_t)group;
        st->base = CO_CM_FLASH_SLOT_HEAD + round_up(st->staged_len, st->flash->unit);
        st->room = st->slot_size - st->base;
        st->saving = true;
        return CO_OK;
    }
    st->group = (uint8_t)group;
    st->base = CO_CM_FLASH_SLOT_HEAD;
    st->room = room(st);
    co_err_t err = erase_next_slot(st);
    st->saving = err == CO_OK;
    return err;
}

static co_err_t write(void *ctx, const uint8_t *data, uint32_t len)
{
    co_cm_flash_storage_t *st = ctx;
    uint8_t unit = st->flash->unit;
    if (!st->saving) {
        return CO_ERR_STATE;
    }
    if (len > st->room - st->written) {
        end_save(st);
        return CO_ERR_FULL;
    }
    for (uint32_t i = 0; i < len; i++) {
        st->partial[st->written % unit] = data[i];
        st->written++;
        if (st->written % unit == 0) {
            co_err_t err = put_unit(st, st->base + st->written - unit, st->partial);
            if (err != CO_OK) {
                end_save(st);
                return err;
            }
        }
    }
    return CO_OK;
}

/* The image's last bytes, its unit padded with erased bytes. */
static co_err_t finish_image(co_cm_flash_storage_t *st)
{
    uint8_t unit = st->flash->unit;
    uint32_t rest = st->written % unit;
    if (rest == 0) {
        return CO_OK;
    }
    memset(st->partial + rest, 0xFF, unit - rest);
    return put_unit(st, st->base + st->written - rest, st->partial);
}

/* The image written since begin is kept for the commit; the next begin writes the other
 * group's beside it, and the commit switches to both at once. */
static co_err_t stage(void *ctx)
{
    co_cm_flash_storage_t *st = ctx;
    if (!st->saving || st->staged) {
        end_save(st);
        return CO_ERR_STATE;
    }
    st->saving = false;
    co_err_t err = finish_image(st);
    if (err != CO_OK) {
        return err;
    }
    st->staged = true;
    st->staged_len = st->written;
    return CO_OK;
}

static co_err_t commit(void *ctx)
{
    co_cm_flash_storage_t *st = ctx;
    if (!st->saving) {
        end_save(st);
        return CO_ERR_STATE;
    }
    st->saving = false;
    co_err_t err = finish_image(st);
    if (err == CO_OK) {
        err = switch_slots(st, st->written);
    }
    st->staged = false;
    return err;
}

static void discard(void *ctx) { end_save(ctx); }

static co_err_t read(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf, uint32_t cap,
                     uint32_t *n)
{
    const co_cm_flash_storage_t *st = ctx;
    image_at_t image;
    *n = 0;
    if (!stored_image(st, group, &image)) {
        return CO_ERR_NOT_FOUND;
    }
    if (offset < image.len) {
        *n = image.len - offset < cap ? image.len - offset : cap;
        memcpy(buf, mapped(st->slot[st->current] + image.off + offset), *n);
    }
    return CO_OK;
}

/* Forgetting a group is a new slot without its image (nothing to do when none is stored). */
static co_err_t erase(void *ctx, co_param_group_t group)
{
    co_cm_flash_storage_t *st = ctx;
    image_at_t image;
    end_save(st);
    if (!stored_image(st, group, &image)) {
        return CO_OK;
    }
    st->group = (uint8_t)group;
    st->base = CO_CM_FLASH_SLOT_HEAD;
    co_err_t err = erase_next_slot(st);
    return err == CO_OK ? switch_slots(st, NO_IMAGE) : err;
}

co_err_t co_cm_flash_storage_init(co_cm_flash_storage_t *st, const co_cm_flash_t *flash,
                                  uintptr_t slot0, uintptr_t slot1, uint32_t slot_size)
{
    if (st == NULL || flash == NULL || flash->erase_page == NULL || flash->program == NULL) {
        return CO_ERR_ARG;
    }
    uint32_t unit = flash->unit;
    if (unit == 0 || unit > CO_CM_FLASH_UNIT_MAX || (unit & (unit - 1)) != 0 ||
        flash->page_size == 0 || flash->page_size % unit != 0 ||
        slot_size % flash->page_size != 0 || slot_size <= CO_CM_FLASH_SLOT_HEAD ||
        slot0 % flash->page_size != 0 || slot1 % flash->page_size != 0 ||
        (slot0 < slot1 + slot_size && slot1 < slot0 + slot_size)) {
        return CO_ERR_ARG;
    }
    memset(st, 0, sizeof *st);
    st->api = (co_storage_t){.begin = begin,
                             .write = write,
                             .commit = commit,
                             .read = read,
                             .erase = erase,
                             .discard = discard,
                             .stage = stage,
                             .ctx = st};
    st->flash = flash;
    st->slot[0] = slot0;
    st->slot[1] = slot1;
    st->slot_size = slot_size;
    st->current = NO_SLOT;
    uint32_t seq[2];
    image_at_t images[2];
    bool valid[2] = {slot_valid(st, 0, &seq[0], images), slot_valid(st, 1, &seq[1], images)};
    if (valid[0] || valid[1]) {
        /* Both valid: the later one (serial number arithmetic: a sequence may wrap). */
        st->current =
            (uint8_t)(valid[0] && (!valid[1] || (int32_t)(seq[0] - seq[1]) > 0) ? 0u : 1u);
        st->seq = seq[st->current];
    }
    return CO_OK;
}
