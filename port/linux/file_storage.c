/* SPDX-License-Identifier: Apache-2.0 */
/* file_storage.c -- parameter storage in files, written atomically; see
 * canola/file_storage.h. */
#define _POSIX_C_SOURCE 200809L

#include "canola/file_storage.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

/* The save in progress will not be committed: close and remove its temporary file. */
static void discard(void *ctx)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    if (fs->fd < 0) {
        return;
    }
    close(fs->fd);
    fs->fd = -1;
    if (path_of(fs, fs->group, true, tmp, sizeof tmp) == 0) {
        (void)unlink(tmp);
    }
}

/* The temporary file is made anew, never opened through whatever stands at its name: a
 * leftover (an interrupted save, or a link planted there) is removed first, and the
 * creation is exclusive and follows no link, so a link that reappears fails the save. */
static co_err_t begin(void *ctx, co_param_group_t group)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    discard(fs); /* an earlier save that never committed */
    fs->group = group;
    if (path_of(fs, group, true, tmp, sizeof tmp) != 0 || (unlink(tmp) != 0 && errno != ENOENT)) {
        return CO_ERR_STATE;
    }
    fs->fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    return fs->fd >= 0 ? CO_OK : CO_ERR_STATE;
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
            discard(fs); /* a full disk leaves no temporary file behind */
            return CO_ERR_STATE;
        }
        data += n;
        len -= (uint32_t)n;
    }
    return fs->fd >= 0 ? CO_OK : CO_ERR_STATE;
}

static co_err_t commit(void *ctx)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    if (fs->fd < 0) {
        return CO_ERR_STATE;
    }
    int rc = fsync(fs->fd);
    rc |= close(fs->fd);
    fs->fd = -1;
    rc |= path_of(fs, fs->group, true, tmp, sizeof tmp);
    rc |= path_of(fs, fs->group, false, final, sizeof final);
    if (rc != 0 || rename(tmp, final) != 0) {
        (void)unlink(tmp);
        return CO_ERR_STATE;
    }
    return sync_dir(fs) == 0 ? CO_OK : CO_ERR_STATE;
}

/* Only a regular file is read: a FIFO or device put in its place is opened without
 * waiting (O_NONBLOCK) and refused (a read error: the core then starts with defaults). */
static co_err_t read_at(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf,
                        uint32_t cap, uint32_t *n)
{
    const co_file_storage_t *fs = ctx;
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    *n = 0;
    if (path_of(fs, group, false, final, sizeof final) != 0) {
        return CO_ERR_STATE;
    }
    int fd = open(final, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
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
    if (path_of(fs, group, false, final, sizeof final) != 0) {
        return CO_ERR_STATE;
    }
    if (unlink(final) != 0 && errno != ENOENT) {
        return CO_ERR_STATE;
    }
    return sync_dir(fs) == 0 ? CO_OK : CO_ERR_STATE;
}

/* A save needs to create and rename files in the folder. */
static bool can_save(void *ctx)
{
    const co_file_storage_t *fs = ctx;
    return access(fs->dir, W_OK | X_OK) == 0;
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
    fs->api = (co_storage_t){.begin = begin,
                             .write = write_all,
                             .commit = commit,
                             .read = read_at,
                             .erase = erase,
                             .ctx = fs,
                             .can_save = can_save,
                             .discard = discard};
    return CO_OK;
}
