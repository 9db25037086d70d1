/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/file_storage.h -- parameter storage in files, for Linux (port/linux).
 *
 * Each group is one file in a folder: comm.params (0x1000..0x1FFF) and app.params
 * (0x2000..0x9FFF), each an image in the format of canola/storage.h (header and CRC: a
 * damaged file is refused whole). A save writes a temporary file beside it
 * (comm.params.tmp, app.params.tmp), fsyncs it, renames it over the old one and fsyncs
 * the folder: whenever the power goes, the folder holds the old image or the new one,
 * never a mix. A save of both groups (0x1010 sub1) is one step: both temporary files are
 * written and fsynced, then an empty commit record params.commit is created and the folder
 * fsynced (the commit point), then both are renamed and the record removed. While the
 * record exists the temporary files are the images (reads take them); the next save,
 * restore or co_file_storage_init finishes the renames. So a crash or SIGKILL at any step
 * leaves both groups old or both new. A restore erases each group's file alone.
 *
 * The temporary file is created exclusively and without following links (O_CREAT |
 * O_EXCL | O_NOFOLLOW, after removing whatever had its name: a file left by an
 * interrupted save, or a planted link, whose target stays untouched); a save that fails
 * (full disk, read-only folder) removes it and leaves the old images. Only regular files
 * are read (a FIFO in a file's place is a read error, not a wait).
 *
 * can_save (what 0x1010/0x1011 read): the folder is writable (access(W_OK)), its file
 * system has a free block and inode (statvfs; the reserved blocks count for root), and no
 * save failed since the last one that succeeded. So 0x1010 reads 0 on a read-only folder
 * or mount, on a full disk, and after a save that failed (a file size limit, an I/O
 * error); a command is still tried, and one that succeeds makes it read 1 again.
 *
 * The same folder keeps the LSS configuration (co_file_storage_store_lss): lss.params, the
 * node-ID a CiA 305 store configuration saved, which the program uses at its next start.
 *
 * Not part of the portable core: uses POSIX file calls. One save at a time per object.
 */
#ifndef CANOLA_FILE_STORAGE_H
#define CANOLA_FILE_STORAGE_H

#include "canola/storage.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CO_FILE_STORAGE_PATH_MAX 256

typedef struct co_file_storage {
    co_storage_t api; /**< give &api to co_node_config_t.storage */
    char dir[CO_FILE_STORAGE_PATH_MAX];
    int fd; /**< the temporary file of a save in progress, or -1 */
    co_param_group_t group;
    unsigned staged; /**< bit (1 << group) per temporary file of the save in progress */
    bool failed;     /**< a save failed since the last one that succeeded */
} co_file_storage_t;

/** LSS store configuration (CiA 305, cs 0x17; give it as co_lss_slave_config_t.store with
 *  ctx = the co_file_storage_t): the node-ID and bit timing index (0xFF: none) into
 *  lss.params in the folder, one line of text ("canola-lss 1 node-id 7 bit-timing 255"),
 *  written atomically like the images (a temporary file, fsync, rename, folder fsync).
 *  Returns CO_ERR_STATE when the folder refused. */
co_err_t co_file_storage_store_lss(void *fs, uint8_t node_id, uint8_t bit_timing);

/** What store configuration kept: the node-ID (1..127, or 0xFF: unconfigured) and the
 *  bit timing index (0xFF: none). CO_ERR_NOT_FOUND when nothing was stored, CO_ERR_STATE
 *  when lss.params is not exactly such a line (or not a regular file); nothing is set then. */
co_err_t co_file_storage_load_lss(const co_file_storage_t *fs, uint8_t *node_id,
                                  uint8_t *bit_timing);

/** Storage in folder `dir` (which must exist); finishes a save of both groups that a
 *  crash interrupted after its commit point. Returns CO_ERR_ARG when the path is too
 *  long or not a folder. */
co_err_t co_file_storage_init(co_file_storage_t *fs, const char *dir);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_FILE_STORAGE_H */
