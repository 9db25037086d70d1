/*
 * canola/storage.h -- stored parameters: 0x1010 store parameters and 0x1011 restore
 * default parameters, through a storage interface that a port implements (files on
 * Linux, flash on a microcontroller, RAM on the simulated bus).
 *
 * Two groups are stored, each as one image: communication parameters (0x1000..0x1FFF)
 * and application parameters (0x2000..0x9FFF). An image holds every entry of its range
 * that the network may write and that has storage: record by record, index (u16),
 * sub-index (u8), length (u8), the value's wire bytes. Not stored: DOMAINs, values
 * longer than CO_STORE_VALUE_MAX bytes, 0x1003 (error history), 0x1010 and 0x1011.
 *
 * 0x1010 sub1 saves both groups, sub2 the communication group, sub3 the application
 * group, when written the signature "save" (0x65766173); 0x1011 sub1..3 forgets the
 * same groups with the signature "load" (0x64616F6C), effective at the next reset.
 * Another value aborts with 0x08000020, as does any sub-index above 3 and a node
 * without storage; a storage failure aborts with 0x06060000. Read, 0x1010/0x1011 subN
 * give 1 when the node has storage (parameters are saved on command) and 0 otherwise.
 * A core built without storage (CO_CONFIG_STORAGE 0) refuses every command the same way
 * and leaves 0x1010/0x1011 as the dictionary gives them (its dictionary says 0 there).
 *
 * Power-on values: reset application and reset communication first copy the defaults
 * of their range, then the stored image over them, so what is stored is exactly what a
 * reset restores. Records of entries the dictionary no longer has, or whose length
 * changed, are skipped.
 *
 * Cost: saving is O(entries in the range) calls of write; loading O(records x log n).
 */
#ifndef CANOLA_STORAGE_H
#define CANOLA_STORAGE_H

#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** The stored groups. */
typedef enum co_param_group {
    CO_PARAMS_COMMUNICATION = 1, /**< 0x1000..0x1FFF */
    CO_PARAMS_APPLICATION = 2,   /**< 0x2000..0x9FFF */
} co_param_group_t;

/** What a port implements. A save is begin, write..., commit: the implementation must make
 *  it atomic (the old image stays valid until commit returns CO_OK). */
typedef struct co_storage {
    co_err_t (*begin)(void *ctx, co_param_group_t group);
    co_err_t (*write)(void *ctx, const uint8_t *data, uint32_t len);
    co_err_t (*commit)(void *ctx);
    /** Copy up to `cap` bytes of the stored image of `group` from `offset`; `*n` = bytes
     *  copied (0 past the end). CO_ERR_NOT_FOUND when nothing is stored. */
    co_err_t (*read)(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf, uint32_t cap,
                     uint32_t *n);
    /** Forget the stored image of `group` (no image: defaults at the next reset). */
    co_err_t (*erase)(void *ctx, co_param_group_t group);
    void *ctx;
} co_storage_t;

#define CO_STORE_SIGNATURE 0x65766173u   /**< "save" */
#define CO_RESTORE_SIGNATURE 0x64616F6Cu /**< "load" */

/** Save groups now, as a write of "save" to 0x1010 would (`which`: 1 all, 2 communication,
 *  3 application). Returns CO_ERR_STATE without storage, CO_ERR_ARG for another `which`,
 *  or the storage's error. */
co_err_t co_storage_save(co_node_t *node, uint8_t which);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_STORAGE_H */
