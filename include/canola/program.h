/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/program.h -- program download (CiA 302-3): the device side of 0x1F50, 0x1F51,
 * 0x1F56, 0x1F57, and a master that downloads a program and checks what runs after.
 *
 * Device. The objects live in the application's dictionary (sub-index 1 = program 1);
 * their hooks are the ones below, so the core stores nothing of them:
 *   0x1F50 sub1 program data, DOMAIN, write-only: the image arrives in pieces (SDO
 *        segmented or block transfer) and goes to the application's `write` callback
 *        (offset, bytes, announced total, last piece). Refused with 0x08000022 while the
 *        program runs.
 *   0x1F51 sub1 program control, UNSIGNED8: write 0 stop, 1 start, 2 reset (stop, then
 *        start), 3 clear (only while stopped, else 0x08000022); another value 0x06090030.
 *        The application's `control` callback may refuse with an abort code. Read: 0
 *        stopped, 1 running.
 *   0x1F56 sub1 program software identification, UNSIGNED32, read-only: the value the
 *        application sets with co_program_set_ident() (for example the image's CRC).
 *   0x1F57 sub1 flash status, UNSIGNED32, read-only: bit 0 set while a download runs;
 *        bits 1..7 a status code: 0 ok, 1 no valid program (after clear), 5 flash write
 *        error (the `write` callback refused a piece).
 * With co_od_t.hook_ctx pointing to the co_program_t, put co_program_data_hooks,
 * co_program_control_hooks, co_program_ident_hooks and co_program_status_hooks in the
 * entries (value NULL). An application whose hook_ctx is its own calls
 * co_program_data_write() and friends from its own hooks instead.
 *
 * Master. co_flash_start() runs, over one SDO client channel: write 0x1F51 = 0 (stop);
 * with `clear`, 0x1F51 = 3; the image to 0x1F50 by SDO block transfer (progress reported
 * as the bytes the server acknowledged); 0x1F51 = 1 (start); read 0x1F56 and compare it
 * with the expected identification. Asynchronous: the node's ingest/poll drive it and
 * `done` runs once with the stage reached and the SDO abort code, if any. Built with
 * CO_CONFIG_MANAGER; the co_flash_t belongs to the caller and must stay put until `done`.
 */
#ifndef CANOLA_PROGRAM_H
#define CANOLA_PROGRAM_H

#include "canola/config.h"
#include "canola/od.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/* 0x1F51 commands and states. */
#define CO_PROGRAM_STOP 0u
#define CO_PROGRAM_START 1u
#define CO_PROGRAM_RESET 2u
#define CO_PROGRAM_CLEAR 3u

/* 0x1F57 status codes (bits 1..7). */
#define CO_FLASH_STATUS_BUSY 0x01u
#define CO_FLASH_STATUS_NO_PROGRAM 1u
#define CO_FLASH_STATUS_WRITE_ERROR 5u

/* ---- device */

/** What the application does with the program. */
typedef struct co_program_app {
    /** Take a piece of the image (0x1F50): `offset` of this piece, `total` the announced
     *  size (CO_OD_SIZE_UNKNOWN if none), `last` on the final piece. Return
     *  CO_ABORT_NONE or an abort code (the download stops; 0x1F57 says write error). */
    co_abort_t (*write)(void *ctx, uint32_t offset, const uint8_t *data, uint32_t n, uint32_t total,
                        bool last);
    /** Carry out a 0x1F51 command (CO_PROGRAM_*); return CO_ABORT_NONE or an abort code. */
    co_abort_t (*control)(void *ctx, uint8_t command);
    void *ctx;
} co_program_app_t;

/** Device-side state (caller-owned; fields are internal). */
typedef struct co_program {
    co_program_app_t app;
    uint32_t ident;  /**< 0x1F56 */
    uint32_t status; /**< 0x1F57 */
    uint8_t state;   /**< 0x1F51 as read: CO_PROGRAM_STOP or CO_PROGRAM_START */
} co_program_t;

/** Fill `p`: the program runs (`running`) with identification `ident`. */
void co_program_init(co_program_t *p, const co_program_app_t *app, bool running, uint32_t ident);

/** Set 0x1F56 (after a download the application has checked, for example). */
void co_program_set_ident(co_program_t *p, uint32_t ident);

/** Hooks for the entries, with co_od_t.hook_ctx = the co_program_t. */
extern const co_od_hooks_t co_program_data_hooks;    /**< 0x1F50 subN */
extern const co_od_hooks_t co_program_control_hooks; /**< 0x1F51 subN */
extern const co_od_hooks_t co_program_ident_hooks;   /**< 0x1F56 subN */
extern const co_od_hooks_t co_program_status_hooks;  /**< 0x1F57 subN */

/** What those hooks do, for applications that call them from hooks of their own. */
co_abort_t co_program_data_write(co_program_t *p, uint32_t offset, const uint8_t *data, uint32_t n,
                                 uint32_t total, bool last);
co_abort_t co_program_control_write(co_program_t *p, uint8_t command);

/* ---- master */

/** Where a download ended. */
typedef enum co_flash_stage {
    CO_FLASH_STAGE_STOP = 1, /**< writing 0x1F51 = 0 */
    CO_FLASH_STAGE_CLEAR,    /**< writing 0x1F51 = 3 */
    CO_FLASH_STAGE_DATA,     /**< block download of 0x1F50 */
    CO_FLASH_STAGE_START,    /**< writing 0x1F51 = 1 */
    CO_FLASH_STAGE_VERIFY,   /**< reading 0x1F56 */
    CO_FLASH_STAGE_DONE,     /**< all went well */
} co_flash_stage_t;

typedef struct co_flash_result {
    uint8_t stage;    /**< co_flash_stage_t: DONE on success, else where it failed */
    bool ident_ok;    /**< 0x1F56 matched (or no check asked) */
    co_abort_t abort; /**< the SDO abort code of the failed stage, CO_ABORT_NONE if none */
    uint32_t ident;   /**< 0x1F56 as read */
    uint32_t bytes;   /**< image bytes acknowledged */
} co_flash_result_t;

typedef struct co_flash_request {
    uint8_t channel;  /**< SDO client channel (set up by co_flash_start) */
    uint8_t server;   /**< the device's node-ID */
    uint8_t program;  /**< sub-index of 0x1F50/0x1F51/0x1F56 (0 = 1) */
    bool clear;       /**< clear the program before the download */
    bool check_ident; /**< compare 0x1F56 with `ident` after the start */
    uint32_t ident;
    const uint8_t *data; /**< the image (valid until done) */
    uint32_t len;
    void (*progress)(void *ctx, uint32_t done, uint32_t total);
    void (*done)(void *ctx, const co_flash_result_t *result);
    void *ctx;
} co_flash_request_t;

/** A download in progress (caller-owned; fields are internal). */
typedef struct co_flash {
    co_flash_request_t req;
    co_node_t *node;
    co_flash_result_t result;
    uint32_t reported; /**< progress last reported */
    uint8_t stage;
    uint8_t value[1];
} co_flash_t;

/** Start downloading. Returns CO_ERR_ARG for NULL or empty data or a bad node-ID,
 *  CO_ERR_BUSY when the channel or another download is busy, CO_ERR_STATE when the
 *  master side is not built in, else co_sdo_client_setup's error or CO_OK. */
co_err_t co_flash_start(co_flash_t *flash, co_node_t *node, const co_flash_request_t *request);

/** Name of a stage ("stop", "data", ...). */
const char *co_flash_stage_name(uint8_t stage);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_PROGRAM_H */
