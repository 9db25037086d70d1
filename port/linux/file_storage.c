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
    int dfd = open(fs->dir, O_RDONLY | O_DIRECTORY);
    if (dfd < 0) {
        return -1;
    }
    int rc = fsync(dfd);
    close(dfd);
    return rc;
}

static co_err_t begin(void *ctx, co_param_group_t group)
{
    co_file_storage_t *fs = ctx;
    char tmp[CO_FILE_STORAGE_PATH_MAX + 32];
    if (fs->fd >= 0) {
        close(fs->fd); /* an earlier save that never committed */
    }
    fs->group = group;
    fs->fd = path_of(fs, group, true, tmp, sizeof tmp) == 0
                 ? open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)
                 : -1;
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
    if (rc != 0 || rename(tmp, final) != 0 || sync_dir(fs) != 0) {
        return CO_ERR_STATE;
    }
    return CO_OK;
}

static co_err_t read_at(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf,
                        uint32_t cap, uint32_t *n)
{
    const co_file_storage_t *fs = ctx;
    char final[CO_FILE_STORAGE_PATH_MAX + 32];
    *n = 0;
    if (path_of(fs, group, false, final, sizeof final) != 0) {
        return CO_ERR_STATE;
    }
    int fd = open(final, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        return errno == ENOENT ? CO_ERR_NOT_FOUND : CO_ERR_STATE;
    }
    ssize_t got = pread(fd, buf, cap, (off_t)offset);
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
                             .ctx = fs};
    return CO_OK;
}
