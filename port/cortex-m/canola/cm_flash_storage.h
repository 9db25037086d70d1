/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/cm_flash_storage.h -- stored parameters (0x1010/0x1011) on a microcontroller's
 * internal flash, safe against power lost at any point of a write (port/cortex-m).
 *
 * Two slots, each one or more erasable pages (sectors), hold the parameters in turn. A slot
 * holds both groups' images (canola/storage.h's format, which carries its own CRC): a save
 * of one group erases the slot not in use, writes the new image into it, copies the other
 * group's image over from the slot in use, then the slot's header and, last, its commit
 * unit. Only a slot whose commit unit and header (with its own CRC-32) are intact counts,
 * and of two the one with the higher sequence number. So until the commit unit is
 * programmed the old slot is the valid one, whatever state the power cut left the other
 * in (half erased, half programmed, a unit partly programmed); once it is, the new one.
 * A save of both groups (0x1010 sub1) writes both images into the one new slot (the
 * storage's `stage`): both old or both new, never one of each. 0x1011 (forget a group) is
 * a slot with the other group's image alone, as atomic.
 *
 *   slot:  0  header: magic "CNFS", sequence, offset and length of each group's image
 *              (length 0xFFFFFFFF: none), CRC-32 of the 28 bytes before it  (32 bytes)
 *         32  commit unit: one program unit of 0xC5 bytes                   (32 bytes kept)
 *         64  the images, each from a program-unit boundary, erased bytes after them
 *
 * Each program unit is programmed once after its page's erase and read back (a mismatch is
 * a hardware error). Flash is read where it is mapped (a plain memory read).
 *
 * The flash driver (co_cm_flash_t) erases a page and programs one unit; the unit is the
 * controller's programming width: 2 bytes (STM32 F0/F1/F3), 4 (F4 at x32, nRF51/52), 8
 * (L4/G0/G4/L5/U5: a double word), 16 (U5 quad word), 32 (H7: a 256-bit flash word).
 *
 * Threading: main loop only (the node calls it from co_node_ingest/poll). Erasing a page
 * stalls the CPU on single-bank STM32 parts (tens of ms for a 16 KB sector): saves are
 * rare and on command. Memory: this object (108 bytes on a Cortex-M); no image buffer.
 * Cost: a save programs (image + other image + 64) / unit units after erasing the slot's
 * pages; a read is a copy.
 */
#ifndef CANOLA_CM_FLASH_STORAGE_H
#define CANOLA_CM_FLASH_STORAGE_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/storage.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The widest program unit supported (bytes): STM32H7's flash word. */
#define CO_CM_FLASH_UNIT_MAX 32u
/** Bytes at the start of a slot before the first image: header and commit unit. */
#define CO_CM_FLASH_SLOT_HEAD 64u

/** A flash controller as the storage sees it. Addresses are where the flash is mapped. */
typedef struct co_cm_flash {
    /** Erase the page that starts at `addr`: every byte reads 0xFF after it. Returns CO_OK,
     *  or an error (CO_ERR_STATE) when the controller reports one. */
    co_err_t (*erase_page)(void *hw, uintptr_t addr);
    /** Program `unit` bytes of `data` at `addr` (aligned to the unit, erased since). Returns
     *  CO_OK, or an error when the controller reports one. */
    co_err_t (*program)(void *hw, uintptr_t addr, const uint8_t *data);
    void *hw;
    uint32_t page_size; /**< bytes of one erasable page or sector */
    uint8_t unit;       /**< bytes programmed at once: a power of two, 1..CO_CM_FLASH_UNIT_MAX */
} co_cm_flash_t;

typedef struct co_cm_flash_storage {
    co_storage_t api; /**< give &api to co_node_config_t.storage */
    const co_cm_flash_t *flash;
    uintptr_t slot[2];
    uint32_t slot_size;
    uint32_t seq;        /**< the sequence number of the slot in use */
    uint32_t written;    /**< bytes of the image being saved */
    uint32_t base;       /**< where in the slot it starts */
    uint32_t room;       /**< bytes it may take (the slot less the other group's image) */
    uint32_t staged_len; /**< bytes of the image staged before it (a save of both groups) */
    uint8_t current;     /**< the slot in use: 0, 1, or 2 (none: nothing stored) */
    uint8_t group;       /**< the group being saved (co_param_group_t) */
    bool saving;         /**< a save has begun and neither committed nor failed */
    bool staged;         /**< the other group's new image waits in the slot for the commit */
    uint8_t partial[CO_CM_FLASH_UNIT_MAX]; /**< the image's bytes not yet programmed */
} co_cm_flash_storage_t;

/** Storage in the two slots at `slot0` and `slot1`, `slot_size` bytes each (whole pages,
 *  page-aligned, not overlapping), on `flash` (which must outlive it). Finds the slot in
 *  use. Returns CO_ERR_ARG for a geometry that does not hold: a unit that is not a power of
 *  two up to CO_CM_FLASH_UNIT_MAX, a page that is not a multiple of it, a slot that is not
 *  whole pages or not larger than CO_CM_FLASH_SLOT_HEAD. O(1): reads two headers. */
co_err_t co_cm_flash_storage_init(co_cm_flash_storage_t *st, const co_cm_flash_t *flash,
                                  uintptr_t slot0, uintptr_t slot1, uint32_t slot_size);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_CM_FLASH_STORAGE_H */
