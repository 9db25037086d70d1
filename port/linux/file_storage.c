/* SPDX-License-Identifier: Apache-2.0 */
/* file_storage.c -- parameter storage in files, written atomically; see
 * canola/file_storage.h. */
#define _POSIX_C_SOURCE 200809L

#include "canola/file_storage.h"

#include "canola/node.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#define COMMIT_RECORD "params.commit"

static const char *file_name(co_param_group_t group)
{
    return group == CO_PARAMS_COMMUNICATION ? "comm.params" : "app.params";
}

static int path_of(const co_file_storage_t *fs, co_param_group_t group, bool tmp, char *out,
                   size_t cap)
{
    int n = snprintf(out, cap, "%s/%s%s", fs->dir, file_name(group), tmp ? ".tmp" : "");
    return n > 0 && (size_t)n < cap ? 0 : -1;
}

static unsigned group_bit(co_param_group_t group) { return 1u << group; }

/* Make a rename durable: fsync the folder that holds the entry. */
static int sync_dir(const co_file_storage_t *fs)
{
    int dfd = open(fs->dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd < 0) {
        return -1;
    }
    int rc = fsync(dfd);
    close(dfd);
    return rc;
}

/* ---- the commit record of a save of both groups */

static int record_path(const co_file_storage_t *fs, char *out, size_t cap)
{
    int n = snprintf(out, cap, "%s/" COMMIT_RECORD, fs->dir);
    return n > 0 && (size_t)n < cap ? 0 : -1;
}

/* While the record exists, the temporary files present are committed images. */
static bool record_exists(const co_file_storage_t *fs)
{
    char path[CO_FILE_STORAGE_PATH_MAX + 32];
    struct stat st;
    return record_path(fs, path, sizeof path) == 0 && lstat(path, &st) == 0;
}

/* Finish a save of both groups that stopped after its record was made: the temporary files
 * renamed over the images (a rename done already is not done again), then the record
 * removed. Nothing to do without a record. */
static co_err_t roll_forward(const co_file_storage_t *fs)
{
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    if (!record_exists(fs)) {
        return CO_OK;
    }
    for (int g = CO_PARAMS_COMMUNICATION; g <= CO_PARAMS_APPLICATION; g++) {
        if (path_of(fs, (co_param_group_t)g, true, tmp, sizeof tmp) != 0 ||
            path_of(fs, (co_param_group_t)g, false, final, sizeof final) != 0 ||
            (rename(tmp, final) != 0 && errno != ENOENT)) {
            return CO_ERR_STATE;
        }
    }
    if (sync_dir(fs) != 0 || record_path(fs, tmp, sizeof tmp) != 0 || unlink(tmp) != 0) {
        return CO_ERR_STATE;
    }
    return sync_dir(fs) == 0 ? CO_OK : CO_ERR_STATE;
}

/* The commit point of a save of both groups: the record, made durable before any rename
 * (so that no rename can reach the disk without it). 0: made; -1: not there (never made,
 * or removed again when it could not be made durable). */
static int make_record(const co_file_storage_t *fs)
{
    char path[CO_FILE_STORAGE_PATH_MAX + 32];
    if (record_path(fs, path, sizeof path) != 0) {
        return -1;
    }
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
        return -1;
    }
    (void)close(fd); /* empty: its name is all it says */
    if (sync_dir(fs) == 0 || unlink(path) != 0) {
        return 0; /* durable, or impossible to take back: committed either way */
    }
    return -1;
}

/* ---- saving */

/* The save in progress will not be committed: close and remove its temporary files (the
 * one being written and those staged). */
static void discard(void *ctx)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    if (fs->fd >= 0) {
        close(fs->fd);
        fs->fd = -1;
        fs->staged |= group_bit(fs->group);
    }
    for (int g = CO_PARAMS_COMMUNICATION; g <= CO_PARAMS_APPLICATION; g++) {
        if ((fs->staged & group_bit((co_param_group_t)g)) &&
            path_of(fs, (co_param_group_t)g, true, tmp, sizeof tmp) == 0) {
            (void)unlink(tmp);
        }
    }
    fs->staged = 0;
}

/* A save failed on the storage's side: 0x1010 reads "cannot save" until one succeeds. */
static co_err_t failed(co_file_storage_t *fs)
{
    discard(fs);
    fs->failed = true;
    return CO_ERR_STATE;
}

/* A temporary file made anew, never opened through whatever stands at its name: a
 * leftover (an interrupted save, or a link planted there) is removed first, and the
 * creation is exclusive and follows no link, so a link that reappears fails the save.
 * Its fd, or -1. */
static int create_fresh(const char *tmp)
{
    if (unlink(tmp) != 0 && errno != ENOENT) {
        return -1;
    }
    return open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
}

/* A save of both groups begins its second image after staging the first; any other begin
 * starts a new save (finishing first a committed one a crash interrupted). */
static co_err_t begin(void *ctx, co_param_group_t group)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    if (fs->fd >= 0 || (fs->staged & group_bit(group))) {
        discard(fs); /* an earlier save that never committed */
    }
    if (fs->staged == 0 && roll_forward(fs) != CO_OK) {
        return failed(fs);
    }
    fs->group = group;
    fs->fd = path_of(fs, group, true, tmp, sizeof tmp) == 0 ? create_fresh(tmp) : -1;
    return fs->fd >= 0 ? CO_OK : failed(fs);
}

static co_err_t write_all(void *ctx, const uint8_t *data, uint32_t len)
{
    co_file_storage_t *fs = ctx;
    while (len > 0 && fs->fd >= 0) {
        ssize_t n = write(fs->fd, data, len);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            return failed(fs); /* a full disk leaves no temporary file behind */
        }
        data += n;
        len -= (uint32_t)n;
    }
    return fs->fd >= 0 ? CO_OK : CO_ERR_STATE;
}

/* The image being written, complete on disk (fsync) and closed. */
static int finish_file(co_file_storage_t *fs)
{
    int rc = fsync(fs->fd);
    rc |= close(fs->fd);
    fs->fd = -1;
    return rc;
}

static co_err_t stage(void *ctx)
{
    co_file_storage_t *fs = ctx;
    if (fs->fd < 0) {
        return CO_ERR_STATE;
    }
    fs->staged |= group_bit(fs->group);
    return finish_file(fs) == 0 ? CO_OK : failed(fs);
}

/* One image: renamed over the old one. Several: the record first (the commit point), then
 * the renames. */
static co_err_t commit(void *ctx)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    if (fs->fd < 0) {
        return CO_ERR_STATE;
    }
    bool several = fs->staged != 0;
    fs->staged |= group_bit(fs->group);
    int rc = finish_file(fs);
    if (several) {
        if (rc != 0 || make_record(fs) != 0) {
            return failed(fs);
        }
        /* Committed: the new images are the stored ones (reads honour the record) even if
         * a rename below fails; the next start or begin finishes them. */
        fs->staged = 0;
        fs->failed = false;
        (void)roll_forward(fs);
        return CO_OK;
    }
    rc |= path_of(fs, fs->group, true, tmp, sizeof tmp);
    rc |= path_of(fs, fs->group, false, final, sizeof final);
    if (rc != 0 || rename(tmp, final) != 0) {
        return failed(fs);
    }
    fs->staged = 0;
    fs->failed = false;
    return sync_dir(fs) == 0 ? CO_OK : CO_ERR_STATE;
}

/* ---- the LSS configuration (CiA 305 store configuration): lss.params, one line of text */

#define LSS_FILE "lss.params"
#define LSS_FORMAT "canola-lss 1 node-id %u bit-timing %u\n"

static int lss_path(const co_file_storage_t *fs, bool tmp, char *out, size_t cap)
{
    int n = snprintf(out, cap, "%s/" LSS_FILE "%s", fs->dir, tmp ? ".tmp" : "");
    return n > 0 && (size_t)n < cap ? 0 : -1;
}

co_err_t co_file_storage_store_lss(void *ctx, uint8_t node_id, uint8_t bit_timing)
{
    const co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    char line[64];
    int len = snprintf(line, sizeof line, LSS_FORMAT, node_id, bit_timing);
    if (lss_path(fs, true, tmp, sizeof tmp) != 0 || lss_path(fs, false, final, sizeof final) != 0) {
        return CO_ERR_STATE;
    }
    int fd = create_fresh(tmp);
    if (fd < 0) {
        return CO_ERR_STATE;
    }
    int rc = write(fd, line, (size_t)len) == len ? 0 : -1;
    rc |= fsync(fd);
    rc |= close(fd);
    if (rc != 0 || rename(tmp, final) != 0) {
        (void)unlink(tmp);
        return CO_ERR_STATE;
    }
    return sync_dir(fs) == 0 ? CO_OK : CO_ERR_STATE;
}

co_err_t co_file_storage_load_lss(const co_file_storage_t *fs, uint8_t *node_id,
                                  uint8_t *bit_timing)
{
    char path[CO_FILE_STORAGE_PATH_MAX + 32];
    char text[64];
    if (lss_path(fs, false, path, sizeof path) != 0) {
        return CO_ERR_STATE;
    }
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        return errno == ENOENT ? CO_ERR_NOT_FOUND : CO_ERR_STATE;
    }
    struct stat st;
    ssize_t got = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) ? read(fd, text, sizeof text - 1) : -1;
    close(fd);
    unsigned id = 0;
    unsigned timing = 0;
    char again[64];
    if (got <= 0) {
        return CO_ERR_STATE;
    }
    text[got] = '\0';
    /* exactly the line store_lss writes: read back, printed again, the same text */
    if (sscanf(text, "canola-lss 1 node-id %3u bit-timing %3u", &id, &timing) != 2 ||
        !((id >= 1 && id <= 127) || id == CO_NODE_ID_UNCONFIGURED) || timing > 0xFF ||
        snprintf(again, sizeof again, LSS_FORMAT, id, timing) != (int)got ||
        strcmp(again, text) != 0) {
        return CO_ERR_STATE;
    }
    *node_id = (uint8_t)id;
    *bit_timing = (uint8_t)timing;
    return CO_OK;
}

/* ---- reading and erasing */

/* Only a regular file is read: a FIFO or device put in its place is opened without
 * waiting (O_NONBLOCK) and refused (a read error: the core then starts with defaults).
 * While a commit record exists, a group's temporary file is its image. */
static co_err_t read_at(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf,
                        uint32_t cap, uint32_t *n)
{
    const co_file_storage_t *fs = ctx;
    char path[CO_FILE_STORAGE_PATH_MAX + 32];
    *n = 0;
    int fd = -1;
    if (record_exists(fs) && path_of(fs, group, true, path, sizeof path) == 0) {
        fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    }
    if (fd < 0) {
        if (path_of(fs, group, false, path, sizeof path) != 0) {
            return CO_ERR_STATE;
        }
        fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    }
    if (fd < 0) {
        return errno == ENOENT ? CO_ERR_NOT_FOUND : CO_ERR_STATE;
    }
    struct stat st;
    ssize_t got =
        fstat(fd, &st) == 0 && S_ISREG(st.st_mode) ? pread(fd, buf, cap, (off_t)offset) : -1;
    close(fd);
    if (got < 0) {
        return CO_ERR_STATE;
    }
    *n = (uint32_t)got;
    return CO_OK;
}

static co_err_t erase(void *ctx, co_param_group_t group)
{
    co_file_storage_t *fs = ctx;
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    if (roll_forward(fs) != CO_OK || path_of(fs, group, false, final, sizeof final) != 0) {
        return CO_ERR_STATE;
    }
    if (unlink(final) != 0 && errno != ENOENT) {
        return CO_ERR_STATE;
    }
    return sync_dir(fs) == 0 ? CO_OK : CO_ERR_STATE;
}

/* Whether the folder's file system has a block and an inode left (for root, the reserved
 * blocks count; a file system that keeps no inode count has no inode limit). */
static bool has_room(const co_file_storage_t *fs)
{
    struct statvfs v;
    if (statvfs(fs->dir, &v) != 0) {
        return false;
    }
    fsblkcnt_t blocks = geteuid() == 0 ? v.f_bfree : v.f_bavail;
    return blocks > 0 && (v.f_files == 0 || v.f_favail > 0);
}

/* A save needs to create and rename files in the folder, room on its file system, and
 * no save has failed since the last that succeeded. */
static bool can_save(void *ctx)
{
    const co_file_storage_t *fs = ctx;
    return !fs->failed && access(fs->dir, W_OK | X_OK) == 0 && has_room(fs);
}

co_err_t co_file_storage_init(co_file_storage_t *fs, const char *dir)
{
    struct stat st;
    size_t len = strlen(dir);
    if (len == 0 || len >= sizeof fs->dir || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        return CO_ERR_ARG;
    }
    memset(fs, 0, sizeof *fs);
    memcpy(fs->dir, dir, len + 1);
    fs->fd = -1;
    (void)roll_forward(fs); /* reads find the images either way (read_at) */
    fs->api = (co_storage_t){.begin = begin,
                             .write = write_all,
                             .commit = commit,
                             .read = read_at,
                             .erase = erase,
                             .ctx = fs,
                             .can_save = can_save,
                             .discard = discard,
                             .stage = stage};
    return CO_OK;
}
