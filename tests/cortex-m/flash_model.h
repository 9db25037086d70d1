/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/cortex-m/flash_model.h -- internal flash as an STM32 has it, for the host tests of
 * port/cortex-m's flash storage: pages that erase to 0xFF, a program unit (2..32 bytes)
 * that may be programmed once per erase and only aligned (a second program of a unit, or
 * an unaligned one, is refused and counted as misuse: the STM32 L4/G4 PROGERR/PGAERR, the
 * strictest of the families), and the power cut at a chosen operation.
 *
 * A power cut stops the operation it hits part way (flash_cut_t says how) and every later
 * one fails, as after the supply went. flash_power_on gives power back; the contents stay.
 */
#ifndef CANOLA_TEST_FLASH_MODEL_H
#define CANOLA_TEST_FLASH_MODEL_H

#include "canola/cm_flash_storage.h"

#define FLASH_NEVER UINT32_MAX

/** What the operation the power cut hits leaves behind. */
typedef enum flash_cut {
    FLASH_CUT_BEFORE,  /**< nothing: the cut came as it started */
    FLASH_CUT_HALF,    /**< the first half of its bytes done, the rest untouched */
    FLASH_CUT_SCATTER, /**< every other byte (erase) or every other bit to clear (program),
                            the first one left undone: a cell-by-cell partial state */
} flash_cut_t;

typedef struct flash_model {
    co_cm_flash_t api; /**< the driver the storage uses */
    uint8_t *mem;      /**< the flash, "mapped" here */
    uint32_t size;
    uint32_t ops;    /**< erases and programs begun */
    uint32_t cut_at; /**< the operation the power cut hits (FLASH_NEVER: none) */
    flash_cut_t cut;
    uint32_t fail_at;        /**< an operation the controller reports an error for, power kept */
    bool off;                /**< the power is gone: every operation fails */
    uint32_t misuse;         /**< programs of a unit not erased, or not aligned: storage bugs */
    uint32_t commits;        /**< programs at a slot's commit unit (offset 32 of a slot) */
    uint32_t commit_ops[16]; /**< the operation number of each */
    uintptr_t slots[2];      /**< where the slots are, to recognise commit units */
} flash_model_t;

/** A blank (erased) flash of `size` bytes at `mem`, pages of `page_size`, unit `unit`. */
void flash_model_init(flash_model_t *m, uint8_t *mem, uint32_t size, uint32_t page_size,
                      uint8_t unit);
/** Power back (the contents as the cut left them), no cut or failure pending. */
void flash_power_on(flash_model_t *m);

#endif /* CANOLA_TEST_FLASH_MODEL_H */
