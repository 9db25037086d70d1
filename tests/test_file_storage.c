/* SPDX-License-Identifier: Apache-2.0 */
/* test_file_storage.c -- parameter storage in files: saves survive a power cycle, a save
 * cut off before its commit leaves the old image, restore removes it; damaged files are
 * refused whole, a link at the temporary name is not followed, a failed save leaves no
 * temporary file, a read-only folder or a full disk reads as "cannot save"; a save of
 * both groups killed (SIGKILL) at any step of its file system calls leaves both groups
 * old or both new.
 *
 * File system failures are injected at link time (-Wl,--wrap, tests/CMakeLists.txt):
 * while `g_read_only` is set, access(W_OK), open(O_CREAT) and unlink fail with EROFS,
 * as on a read-only mount (chmod would not stop root); while `g_full` is set, statvfs
 * says no block is free. A full disk is a file size limit (RLIMIT_FSIZE: writes past it
 * fail with EFBIG). A kill: a forked child counts the file system calls of its save
 * (open, write, fsync, rename, unlink) and SIGKILLs itself before call number N. */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "canola/file_storage.h"
#include "check.h"
#include "harness.h"

static char g_dir[64];
static co_file_storage_t g_fs;
static bool g_read_only;
static bool g_full;
static int g_kill_at; /* SIGKILL before this file system call (1-based); 0: never */
static int g_calls;

int __real_access(const char *path, int mode);
int __real_open(const char *path, int flags, ...);
int __real_unlink(const char *path);
int __real_rename(const char *from, const char *to);
int __real_fsync(int fd);
ssize_t __real_write(int fd, const void *buf, size_t len);
int __real_statvfs(const char *path, struct statvfs *v);
int __wrap_access(const char *path, int mode);
int __wrap_open(const char *path, int flags, ...);
int __wrap_unlink(const char *path);
int __wrap_rename(const char *from, const char *to);
int __wrap_fsync(int fd);
ssize_t __wrap_write(int fd, const void *buf, size_t len);
int __wrap_statvfs(const char *path, struct statvfs *v);

/* One more file system call: the process dies here when it is the one to kill at. */
static void step(void)
{
    if (g_kill_at > 0 && ++g_calls == g_kill_at) {
        raise(SIGKILL);
    }
}

int __wrap_rename(const char *from, const char *to)
{
    step();
    return __real_rename(from, to);
}

int __wrap_fsync(int fd)
{
    step();
    return __real_fsync(fd);
}

ssize_t __wrap_write(int fd, const void *buf, size_t len)
{
    step();
    return __real_write(fd, buf, len);
}

int __wrap_statvfs(const char *path, struct statvfs *v)
{
    int rc = __real_statvfs(path, v);
    if (rc == 0 && g_full) {
        v->f_bavail = 0;
        v->f_bfree = 0;
    }
    return rc;
}

int __wrap_access(const char *path, int mode)
{
    if (g_read_only && (mode & W_OK)) {
        errno = EROFS;
        return -1;
    }
    return __real_access(path, mode);
}

int __wrap_open(const char *path, int flags, ...)
{
    step();
    mode_t mode = 0;
    if (flags & O_CREAT) {
        va_list ap;
        va_start(ap, flags);
        mode = (mode_t)va_arg(ap, int);
        va_end(ap);
        if (g_read_only) {
            errno = EROFS;
            return -1;
        }
    }
    return __real_open(path, flags, mode);
}

int __wrap_unlink(const char *path)
{
    step();
    if (g_read_only) {
        errno = EROFS;
        return -1;
    }
    return __real_unlink(path);
}

static void power_on(test_node_t *t)
{
    CHECK_EQ(test_node_init(t, 5, 100), CO_OK);
    t->node.cfg.storage = &g_fs.api;
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
}

static void fresh_dir(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/canola-fs-XXXXXX");
    CHECK(mkdtemp(g_dir) != NULL);
    CHECK_EQ(co_file_storage_init(&g_fs, g_dir), CO_OK);
}

static const char *in_dir(const char *name)
{
    static char path[128];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    return path;
}

static void clean_dir(void)
{
    const char *names[] = {"comm.params",    "app.params",    "comm.params.tmp",
                           "app.params.tmp", "params.commit", "lss.params"};
    for (unsigned i = 0; i < 6; i++) {
        unlink(in_dir(names[i]));
    }
    CHECK_EQ(rmdir(g_dir), 0); /* nothing else was left behind */
}

static bool exists(const char *name)
{
    struct stat st;
    return lstat(in_dir(name), &st) == 0;
}

/* The whole of file `name` into `buf`; its length. */
static size_t slurp(const char *name, uint8_t *buf, size_t cap)
{
    FILE *f = fopen(in_dir(name), "rb");
    CHECK(f != NULL);
    size_t n = f ? fread(buf, 1, cap, f) : 0;
    if (f) {
        fclose(f);
    }
    return n;
}

static void spill(const char *name, const uint8_t *buf, size_t len)
{
    FILE *f = fopen(in_dir(name), "wb");
    CHECK(f != NULL);
    if (f) {
        CHECK_EQ(fwrite(buf, 1, len, f), len);
        fclose(f);
    }
}

static void test_save_survives_a_power_cycle(void)
{
    static test_node_t t;
    fresh_dir();
    power_on(&t);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    co_node_set_uint(&t.node, 0x1017, 0, 250);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0xCAFE);
    CHECK_EQ(t.od.hb_period_ms, 250);
    clean_dir();
}

static void test_save_cut_before_commit_keeps_the_old_image(void)
{
    static test_node_t t;
    fresh_dir();
    power_on(&t);
    co_node_set_uint(&t.node, 0x2000, 0, 0x1111);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    /* A new save starts and writes, then the power goes before the commit. */
    CHECK_EQ(g_fs.api.begin(g_fs.api.ctx, CO_PARAMS_APPLICATION), CO_OK);
    const uint8_t junk[] = {0x00, 0x20, 0x00, 4, 0x22, 0x22, 0, 0};
    CHECK_EQ(g_fs.api.write(g_fs.api.ctx, junk, sizeof junk), CO_OK);
    CHECK_EQ(co_file_storage_init(&g_fs, g_dir), CO_OK); /* the process restarts */
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0x1111);
    /* The next save replaces the stray temporary file. */
    co_node_set_uint(&t.node, 0x2000, 0, 0x3333);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0x3333);
    clean_dir();
}

static void test_restore_removes_the_image(void)
{
    static test_node_t t;
    fresh_dir();
    power_on(&t);
    co_node_set_uint(&t.node, 0x2000, 0, 0xCAFE);
    write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE);
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_NONE);
    power_on(&t);
    CHECK_EQ(t.od.app_u32, 0x12345678);
    uint32_t n = 9;
    uint8_t b[4];
    CHECK_EQ(g_fs.api.read(g_fs.api.ctx, CO_PARAMS_APPLICATION, 0, b, 4, &n), CO_ERR_NOT_FOUND);
    clean_dir();
}

static void test_bad_folder_refused(void)
{
    co_file_storage_t fs;
    CHECK_EQ(co_file_storage_init(&fs, "/nonexistent/canola"), CO_ERR_ARG);
    CHECK_EQ(co_file_storage_init(&fs, ""), CO_ERR_ARG);
}

/* ---- damaged files, hostile folders, failing saves */

/* Saved: 0x1017 = 777 and 0x2000 = 0xCAFE, both groups; then a fresh start. */
static void save_777(test_node_t *t)
{
    fresh_dir();
    power_on(t);
    co_node_set_uint(&t->node, 0x1017, 0, 777);
    co_node_set_uint(&t->node, 0x2000, 0, 0xCAFE);
    CHECK_EQ(write_u32(t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    power_on(t);
    CHECK_EQ(t->od.hb_period_ms, 777);
    CHECK_EQ(t->error_count, 0);
}

/* The communication parameters were refused: defaults, EMCY 0xFF11, on_error. */
static void check_comm_refused(test_node_t *t)
{
    CHECK_EQ(t->od.hb_period_ms, 100);
    CHECK(co_emcy_active(&t->node, 0xFF11));
    bool told = false;
    for (uint32_t i = 0; i < t->error_count; i++) {
        told |= t->errors[i] == CO_NODE_ERR_STORED_COMM;
    }
    CHECK(told);
}

static void test_flipped_bit_in_the_file_is_refused(void)
{
    static test_node_t t;
    save_777(&t);
    uint8_t buf[4096];
    size_t len = slurp("comm.params", buf, sizeof buf);
    const uint8_t value[] = {0x17, 0x10, 0x00, 2, 0x09, 0x03}; /* 0x1017 = 777 */
    size_t at = 0;
    while (at + sizeof value <= len && memcmp(&buf[at], value, sizeof value) != 0) {
        at++;
    }
    CHECK(at + sizeof value <= len);
    buf[at + 5] ^= 0x01; /* 777 -> 521 */
    spill("comm.params", buf, len);
    power_on(&t);
    check_comm_refused(&t);
    CHECK_EQ(t.od.app_u32, 0xCAFE); /* the other file is intact */
    clean_dir();
}

static void test_truncated_file_is_refused(void)
{
    static test_node_t t;
    save_777(&t);
    uint8_t buf[4096];
    size_t len = slurp("comm.params", buf, sizeof buf);
    for (size_t cut = 1; cut < 8 && cut <= len; cut++) {
        spill("comm.params", buf, len - cut);
        power_on(&t);
        check_comm_refused(&t);
    }
    clean_dir();
}

static void test_random_files_are_refused(void)
{
    static test_node_t t;
    fresh_dir();
    uint8_t junk[300];
    uint32_t x = 777;
    for (int round = 0; round < 20; round++) {
        size_t len = (size_t)round * 15u;
        for (size_t i = 0; i < len; i++) {
            x = x * 1103515245u + 12345u;
            junk[i] = (uint8_t)(x >> 16);
        }
        spill("comm.params", junk, len);
        spill("app.params", junk, len);
        power_on(&t);
        check_comm_refused(&t);
        CHECK_EQ(t.od.app_u32, 0x12345678);
        CHECK(co_emcy_active(&t.node, 0xFF12));
    }
    clean_dir();
}

/* A FIFO where a stored file belongs: refused at once, not waited on. */
static void test_fifo_in_place_of_the_file_does_not_hang(void)
{
    static test_node_t t;
    fresh_dir();
    CHECK_EQ(mkfifo(in_dir("comm.params"), 0600), 0);
    power_on(&t);
    check_comm_refused(&t);
    clean_dir();
}

static void test_link_at_the_temporary_name_is_not_followed(void)
{
    static test_node_t t;
    save_777(&t);
    char victim[64];
    snprintf(victim, sizeof victim, "/tmp/canola-victim-XXXXXX");
    int fd = mkstemp(victim);
    CHECK(fd >= 0);
    CHECK_EQ(write(fd, "precious", 8), 8);
    close(fd);
    CHECK_EQ(symlink(victim, in_dir("comm.params.tmp")), 0);
    co_node_set_uint(&t.node, 0x1017, 0, 888);
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    char got[16] = {0};
    FILE *f = fopen(victim, "rb");
    CHECK(f != NULL);
    if (f) {
        CHECK_EQ(fread(got, 1, sizeof got, f), 8);
        fclose(f);
    }
    CHECK_STR(got, "precious");
    struct stat st;
    CHECK_EQ(lstat(in_dir("comm.params"), &st), 0);
    CHECK(S_ISREG(st.st_mode));
    CHECK(!exists("comm.params.tmp"));
    power_on(&t);
    CHECK_EQ(t.od.hb_period_ms, 888);
    unlink(victim);
    clean_dir();
}

/* A full disk: the save fails with 0x06060000, leaves no temporary file, and the old
 * image stays. */
static void test_failed_save_leaves_no_temporary_file(void)
{
    static test_node_t t;
    save_777(&t);
    co_node_set_uint(&t.node, 0x1017, 0, 999);
    co_node_set_uint(&t.node, 0x2000, 0, 0xBEEF);
    struct rlimit old;
    CHECK_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
    struct rlimit small = {8, old.rlim_max};
    signal(SIGXFSZ, SIG_IGN); /* the write fails with EFBIG instead of killing us */
    CHECK_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    /* the failure is told: 0x1010 reads "does not save" now, EMCY 0x5530 */
    CHECK_EQ(t.od.store[0], 0);
    CHECK_EQ(t.od.restore[1], 0);
    CHECK(co_emcy_active(&t.node, CO_EMCY_STORE_FAILED));
    CHECK_EQ(setrlimit(RLIMIT_FSIZE, &old), 0);
    signal(SIGXFSZ, SIG_DFL);
    CHECK(!exists("comm.params.tmp"));
    CHECK(!exists("app.params.tmp"));
    /* room again: a save is tried, works, and 0x1010 reads 1 again */
    CHECK_EQ(write_u32(&t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(t.od.store[0], 1);
    CHECK(!co_emcy_active(&t.node, CO_EMCY_STORE_FAILED));
    power_on(&t);
    CHECK_EQ(t.od.hb_period_ms, 777);
    CHECK_EQ(t.od.app_u32, 0xBEEF);
    CHECK_EQ(t.error_count, 0);
    clean_dir();
}

/* A full file system (no free block): 0x1010/0x1011 read 0 from the start; a save tried
 * all the same fails only if the disk really is full (here it is not: it works). */
static void test_full_disk_reads_as_cannot_save(void)
{
    static test_node_t t;
    save_777(&t);
    g_full = true;
    power_on(&t);
    CHECK_EQ(t.od.store[0], 0);
    CHECK_EQ(t.od.store[2], 0);
    CHECK_EQ(t.od.restore[0], 0);
    g_full = false;
    CHECK_EQ(write_u32(&t, 0x1010, 2, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(t.od.store[0], 1);
    clean_dir();
}

/* ---- the LSS configuration (lss.params) */

/* Stored, read back; anything but the exact line is refused whole (nothing set). */
static void test_lss_configuration_round_trip_and_damage(void)
{
    fresh_dir();
    uint8_t id = 0x55;
    uint8_t timing = 0x55;
    CHECK_EQ(co_file_storage_load_lss(&g_fs, &id, &timing), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_file_storage_store_lss(&g_fs, 9, 0xFF), CO_OK);
    CHECK_EQ(co_file_storage_load_lss(&g_fs, &id, &timing), CO_OK);
    CHECK_EQ(id, 9);
    CHECK_EQ(timing, 0xFF);
    CHECK(!exists("lss.params.tmp"));
    CHECK_EQ(co_file_storage_store_lss(&g_fs, CO_NODE_ID_UNCONFIGURED, 2), CO_OK);
    CHECK_EQ(co_file_storage_load_lss(&g_fs, &id, &timing), CO_OK);
    CHECK_EQ(id, 0xFF);
    CHECK_EQ(timing, 2);
    const char *damaged[] = {
        "",
        "canola-lss 1 node-id 9 bit-timing 255",      /* no end of line */
        "canola-lss 1 node-id 0 bit-timing 255\n",    /* 0 is no node-ID */
        "canola-lss 1 node-id 128 bit-timing 255\n",  /* nor 128 */
        "canola-lss 1 node-id 9 bit-timing 256\n",    /* not an index */
        "canola-lss 2 node-id 9 bit-timing 255\n",    /* another format */
        "canola-lss 1 node-id 09 bit-timing 255\n",   /* not as written */
        "canola-lss 1 node-id 9 bit-timing 255\nx\n", /* more */
        "node-id 9\n",
    };
    for (unsigned i = 0; i < sizeof damaged / sizeof damaged[0]; i++) {
        spill("lss.params", (const uint8_t *)damaged[i], strlen(damaged[i]));
        id = 0x55;
        CHECK_EQ(co_file_storage_load_lss(&g_fs, &id, &timing), CO_ERR_STATE);
        CHECK_EQ(id, 0x55);
    }
    unlink(in_dir("lss.params"));
    CHECK_EQ(mkfifo(in_dir("lss.params"), 0600), 0); /* refused, not waited on */
    CHECK_EQ(co_file_storage_load_lss(&g_fs, &id, &timing), CO_ERR_STATE);
    unlink(in_dir("lss.params"));
    g_read_only = true;
    CHECK_EQ(co_file_storage_store_lss(&g_fs, 9, 0xFF), CO_ERR_STATE);
    g_read_only = false;
    clean_dir();
}

/* ---- a save of both groups killed at every step */

/* Saved (777, 0xCAFE); a child sets (888, 0xBEEF) and saves both groups, killed before
 * file system call `kill_at`. Whether the child finished its save (not killed). */
static bool save_killed_at(int kill_at)
{
    static test_node_t t;
    fflush(stdout);
    pid_t pid = fork();
    CHECK(pid >= 0);
    if (pid == 0) {
        power_on(&t);
        co_node_set_uint(&t.node, 0x1017, 0, 888);
        co_node_set_uint(&t.node, 0x2000, 0, 0xBEEF);
        g_calls = 0;
        g_kill_at = kill_at;
        co_abort_t abort = write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE);
        _exit(abort == CO_ABORT_NONE ? 0 : 1);
    }
    int status = 0;
    struct timespec nap = {0, 2000000};
    for (int waited = 0; waitpid(pid, &status, WNOHANG) == 0; waited++) {
        if (waited > 10000) { /* 20 s: a child that hangs fails the test, never hangs it */
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            CHECK(!"the saving child did not end within 20 s");
            return true;
        }
        nanosleep(&nap, NULL);
    }
    if (WIFEXITED(status)) {
        CHECK_EQ(WEXITSTATUS(status), 0);
        return true;
    }
    CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    return false;
}

static void test_save_of_both_groups_killed_at_every_step(void)
{
    static test_node_t t;
    int old = 0;
    int new = 0;
    bool done = false;
    for (int at = 1; at < 2000 && !done; at++) {
        save_777(&t);
        done = save_killed_at(at);
        CHECK_EQ(co_file_storage_init(&g_fs, g_dir), CO_OK); /* the process restarts */
        power_on(&t);
        bool was_old = t.od.hb_period_ms == 777 && t.od.app_u32 == 0xCAFE;
        bool is_new = t.od.hb_period_ms == 888 && t.od.app_u32 == 0xBEEF;
        if (!was_old && !is_new) {
            printf("  killed before call %d: 0x1017 = %u, 0x2000 = 0x%X (a mix)\n", at,
                   (unsigned)t.od.hb_period_ms, (unsigned)t.od.app_u32);
        }
        CHECK(was_old || is_new);
        CHECK_EQ(t.error_count, 0); /* nothing refused: each file whole */
        old += was_old;
        new += is_new;
        CHECK(!exists("params.commit")); /* finished by the restart */
        clean_dir();
    }
    CHECK(done);
    CHECK(old > 3 && new >= 1); /* the kills landed before and after the commit point */
}

/* A read-only folder: 0x1010/0x1011 read 0 ("does not save"), a save is refused with
 * 0x06060000 and leaves nothing; once writable again they read 1 and saves work. */
static void test_read_only_folder_reads_as_cannot_save(void)
{
    static test_node_t t;
    save_777(&t);
    g_read_only = true;
    power_on(&t);
    CHECK_EQ(t.od.hb_period_ms, 777); /* what is stored still loads */
    CHECK_EQ(t.od.store[0], 0);
    CHECK_EQ(t.od.store[1], 0);
    CHECK_EQ(t.od.restore[0], 0);
    co_node_set_uint(&t.node, 0x1017, 0, 555);
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(write_u32(&t, 0x1011, 1, CO_RESTORE_SIGNATURE), CO_ABORT_HARDWARE);
    CHECK_EQ(t.od.store[0], 0);
    g_read_only = false;
    CHECK(!exists("comm.params.tmp"));
    CHECK_EQ(write_u32(&t, 0x1010, 1, CO_STORE_SIGNATURE), CO_ABORT_NONE);
    CHECK_EQ(t.od.store[0], 1);
    CHECK_EQ(t.od.restore[2], 1);
    power_on(&t);
    CHECK_EQ(t.od.hb_period_ms, 555);
    clean_dir();
}

int main(void)
{
    RUN(test_save_survives_a_power_cycle);
    RUN(test_save_cut_before_commit_keeps_the_old_image);
    RUN(test_restore_removes_the_image);
    RUN(test_bad_folder_refused);
    RUN(test_flipped_bit_in_the_file_is_refused);
    RUN(test_truncated_file_is_refused);
    RUN(test_random_files_are_refused);
    RUN(test_fifo_in_place_of_the_file_does_not_hang);
    RUN(test_link_at_the_temporary_name_is_not_followed);
    RUN(test_failed_save_leaves_no_temporary_file);
    RUN(test_read_only_folder_reads_as_cannot_save);
    RUN(test_full_disk_reads_as_cannot_save);
    RUN(test_lss_configuration_round_trip_and_damage);
    RUN(test_save_of_both_groups_killed_at_every_step);
    return check_summary();
}
