/* SPDX-License-Identifier: Apache-2.0 */
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
 * Image format (version 1), little-endian, a 12-byte header before the records:
 *   0..3  magic "CNPS"           4  format version (1)       5  group (1 or 2)
 *   6..9  length of the records  10..11  CRC-16-CCITT (crc16.c) of the records, then of
 *                                        bytes 0..9
 * A save computes length and CRC in a first pass over the dictionary and writes header
 * and records in a second; a value that changed between the passes fails the save
 * (CO_ERR_STATE, abort 0x06060000) rather than store an image that would not load.
 *
 * An image that fails any check (header, length, CRC, records that do not end exactly at
 * the length, a read error) is ignored as a whole: the group keeps its defaults (a read
 * error while applying a verified image restores them again), the node
 * raises EMCY CO_EMCY_STORE_REJECTED + group (0xFF11 communication, 0xFF12 application;
 * manufacturer byte 0 = the co_store_fault_t) and calls on_error with
 * CO_NODE_ERR_STORED_COMM / CO_NODE_ERR_STORED_APP, once reset communication is done (so
 * the error history 0x1003, which that reset clears, keeps it). The EMCY leaves after
 * boot-up; the error stays active until a save or restore of that group succeeds (or the
 * application clears it). co_storage_verify says what is wrong with an image.
 *
 * 0x1010 sub1 saves both groups, sub2 the communication group, sub3 the application
 * group, when written the signature "save" (0x65766173); 0x1011 sub1..3 forgets the
 * same groups with the signature "load" (0x64616F6C), effective at the next reset.
 * Another value aborts with 0x08000020, as does any sub-index above 3 and a node
 * without storage (CiA 301 7.5.2.13: a wrong signature). Read, 0x1010/0x1011 subN give 1
 * when the node has storage that can save now (bit 0, "saves parameters on command") and
 * 0 otherwise ("does not save parameters"): the storage's can_save says which, at every
 * reset communication and after every command (a read-only folder or a full disk reads
 * 0; a command is still tried).
 *
 * A save of both groups (sub1) is one step when the storage has `stage`: after a failure
 * or a crash at any point the storage holds both old images or both new ones, never
 * communication new and application old. Without `stage` each group is saved alone
 * (whole per group, the communication group first). A restore of both groups erases them
 * one after the other (each erase whole).
 *
 * A save or restore that fails (the storage refused: full, read-only, broken) aborts with
 * 0x06060000 (CiA 301 7.5.2.13: storing failed, "hardware error"), leaves the stored
 * images as they were, and raises EMCY CO_EMCY_STORE_FAILED (0x5530, non-volatile data
 * memory: the 0x5000 "device hardware" class of CiA 301, the code the device profiles,
 * CiA 402 among them, give data storage; manufacturer byte 0 = the sub-index of the
 * failed command, byte 1 = 0x10 for 0x1010 or 0x11 for 0x1011) and calls on_error with
 * CO_NODE_ERR_STORE_FAILED. The error stays active until a save or restore succeeds.
 * A core built without storage (CO_CONFIG_STORAGE 0) refuses every command the same way
 * and leaves 0x1010/0x1011 as the dictionary gives them (its dictionary says 0 there).
 *
 * Power-on values: reset application and reset communication first copy the defaults
 * of their range, then the stored image over them, so what is stored is exactly what a
 * reset restores. Records of entries the dictionary no longer has, or whose length
 * changed, are skipped.
 *
 * Cost: saving is O(entries in the range) calls of write, two reads of each value;
 * loading reads the image three times (CRC, record structure, apply): O(records x log n).
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

/** What a port implements. A save is begin, write..., commit (or discard): the
 *  implementation must make it atomic (the old image stays valid until commit returns
 *  CO_OK). A save of both groups with `stage`: begin, write..., stage, begin, write...,
 *  commit: commit makes both images the stored ones in one step. The port stores bytes;
 *  the core writes and checks the image format below. */
typedef struct co_storage {
    co_err_t (*begin)(void *ctx, co_param_group_t group);
    co_err_t (*write)(void *ctx, const uint8_t *data, uint32_t len);
    /** The images written since the last commit (staged, and the one begun last) become
     *  the stored ones, all together: after a crash, all old or all new. */
    co_err_t (*commit)(void *ctx);
    /** Copy up to `cap` bytes of the stored image of `group` from `offset`; `*n` = bytes
     *  copied (0 past the end). CO_ERR_NOT_FOUND when nothing is stored. */
    co_err_t (*read)(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf, uint32_t cap,
                     uint32_t *n);
    /** Forget the stored image of `group` (no image: defaults at the next reset). */
    co_err_t (*erase)(void *ctx, co_param_group_t group);
    void *ctx;
    /* Optional members (NULL: the port has none). */
    /** Whether a save could succeed now (e.g. the folder is writable); NULL: always. */
    bool (*can_save)(void *ctx);
    /** A save begun will not be committed (a write failed, or the dictionary changed
     *  under it): drop what it wrote, staged images included. NULL: the next begin
     *  starts afresh anyway. */
    void (*discard)(void *ctx);
    /** Keep the image written since begin for the coming commit; the next begin starts
     *  another group's image. NULL: the port commits one group at a time. */
    co_err_t (*stage)(void *ctx);
} co_storage_t;

/** What is wrong with a stored image (co_storage_verify; EMCY manufacturer byte 0). */
typedef enum co_store_fault {
    CO_STORE_INTACT = 0,  /**< the image passes every check */
    CO_STORE_NONE,        /**< nothing is stored (not a fault: defaults) */
    CO_STORE_BAD_HEADER,  /**< shorter than a header, or magic, version or group wrong */
    CO_STORE_BAD_LENGTH,  /**< fewer or more bytes than the header's length */
    CO_STORE_BAD_CRC,     /**< the CRC does not match */
    CO_STORE_BAD_RECORDS, /**< the records do not end exactly at the length */
    CO_STORE_READ_ERROR,  /**< the storage failed to read */
} co_store_fault_t;

#define CO_STORE_MAGIC "CNPS"          /**< the image header's first 4 bytes */
#define CO_STORE_FORMAT 1u             /**< the image format version */
#define CO_STORE_HEADER_SIZE 12u       /**< magic, version, group, length, CRC */
#define CO_EMCY_STORE_REJECTED 0xFF10u /**< + group: the EMCY code of a rejected image */
#define CO_EMCY_STORE_FAILED 0x5530u   /**< a save or restore failed (non-volatile memory) */

#define CO_STORE_SIGNATURE 0x65766173u   /**< "save" */
#define CO_RESTORE_SIGNATURE 0x64616F6Cu /**< "load" */

/** Save groups now, as a write of "save" to 0x1010 would (`which`: 1 all, 2 communication,
 *  3 application), EMCY on failure included. Returns CO_ERR_STATE without storage,
 *  CO_ERR_ARG for another `which`, or the storage's error. */
co_err_t co_storage_save(co_node_t *node, uint8_t which);

/** Check the stored image of `group` without applying it: CO_STORE_INTACT, CO_STORE_NONE,
 *  or the first check it fails. CO_STORE_NONE for a node without storage. O(image). */
co_store_fault_t co_storage_verify(const co_node_t *node, co_param_group_t group);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_STORAGE_H */
