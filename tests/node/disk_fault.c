/* keel_disk_fault: an LD_PRELOAD shim for tests that makes a node's disk fail (docs/
 * fault-model.md, "Durable state"). Test code only; no flight binary links it.
 *
 *   LD_PRELOAD=libkeel_disk_fault.so
 *   KEEL_DISK_FAULT_MATCH=ST1.checkpoints.sqlite   which files fail (a substring of the path)
 *   KEEL_DISK_FAULT_TRIGGER=/run/dir/disk-full     they fail while this file exists
 *
 * While armed, every write to a matching file (write, pwrite, pwrite64, SQLite's main file,
 * its WAL and journal alike) fails with ENOSPC, as on a full disk, and fsync/fdatasync
 * fail with EIO. Everything else, and every file that does not match, is untouched. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

static int armed_for(int fd) {
    const char* trigger = getenv("KEEL_DISK_FAULT_TRIGGER");
    const char* match = getenv("KEEL_DISK_FAULT_MATCH");
    if (trigger == NULL || match == NULL || access(trigger, F_OK) != 0) return 0;
    char link[64];
    char path[PATH_MAX];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    const ssize_t n = readlink(link, path, sizeof path - 1);
    if (n <= 0) return 0;
    path[n] = '\0';
    return strstr(path, match) != NULL;
}

typedef ssize_t (*write_fn)(int, const void*, size_t);
typedef ssize_t (*pwrite_fn)(int, const void*, size_t, off_t);
typedef ssize_t (*pwrite64_fn)(int, const void*, size_t, off64_t);
typedef int (*sync_fn)(int);

#define REAL(name, type) \
    static type real = NULL; \
    if (real == NULL) real = (type)dlsym(RTLD_NEXT, name)

ssize_t write(int fd, const void* buffer, size_t count) {
    REAL("write", write_fn);
    if (armed_for(fd)) {
        errno = ENOSPC;
        return -1;
    }
    return real(fd, buffer, count);
}

ssize_t pwrite(int fd, const void* buffer, size_t count, off_t offset) {
    REAL("pwrite", pwrite_fn);
    if (armed_for(fd)) {
        errno = ENOSPC;
        return -1;
    }
    return real(fd, buffer, count, offset);
}

ssize_t pwrite64(int fd, const void* buffer, size_t count, off64_t offset) {
    REAL("pwrite64", pwrite64_fn);
    if (armed_for(fd)) {
        errno = ENOSPC;
        return -1;
    }
    return real(fd, buffer, count, offset);
}

int fsync(int fd) {
    REAL("fsync", sync_fn);
    if (armed_for(fd)) {
        errno = EIO;
        return -1;
    }
    return real(fd);
}

int fdatasync(int fd) {
    REAL("fdatasync", sync_fn);
    if (armed_for(fd)) {
        errno = EIO;
        return -1;
    }
    return real(fd);
}
