/*
 * atomic_file.c - ilf/atomic_file.h: temporaries beside the destination,
 * fsync, rename, fsync of the folder.
 *
 * Invariants: the temporary is created with O_EXCL under a fresh tag, so two
 * writers (threads, processes, MPI ranks) never share one; the folder's name
 * is taken when the writer is made, so once the rename has happened nothing
 * can fail for want of memory and turn a complete write into a reported error;
 * only a regular file (or nothing) is ever replaced: a destination that is a
 * folder, a FIFO or a device node (/dev/null) is refused before the temporary
 * is made and again before the rename.
 */
#include "ilf/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ilf/hash.h"

enum { TAG_DIGITS = 12, TRIES = 64 };
static const char mark[] = ".tmp-";

struct ilf_atomic {
    char *path, *temp, *folder;
    int fd, committed;
};

/* @return a hard-to-guess tag: process, call count and clock mixed. */
static unsigned long long fresh_tag(void)
{
    static atomic_uint calls;
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    uint64_t x = ((uint64_t)getpid() << 32) ^ (uint64_t)now.tv_nsec ^ ((uint64_t)now.tv_sec << 20) ^
                 ((uint64_t)atomic_fetch_add(&calls, 1u) << 44);
    return ilf_splitmix64(x) & 0xffffffffffffull;
}

/* @return the extension of name with its dot ("" if none; a leading dot does not start one). */
static const char *extension_of(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot != NULL && dot != name ? dot : "";
}

/* @return the folder part of path ("." if none), malloc'd, or NULL without memory. */
static char *folder_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t len = slash == NULL ? 0 : slash == path ? 1 : (size_t)(slash - path);
    char *dir = malloc(len ? len + 1 : 2);
    if (dir == NULL)
        return NULL;
    if (len) {
        memcpy(dir, path, len);
        dir[len] = '\0';
    } else {
        strcpy(dir, ".");
    }
    return dir;
}

/* @return 0 if path names nothing or a regular file (following links: the rename replaces the link, but a link
 * to a device is a mistake), else EEXIST with *step saying why. */
static int replaceable(const char *path, const char **step)
{
    struct stat sb;
    if (stat(path, &sb) != 0 || S_ISREG(sb.st_mode))
        return 0;
    *step = "it exists and is not a regular file (only regular files are replaced)";
    return EEXIST;
}

/* @return 0 once the folder's entries are on disk, or an errno value. */
static int flush_folder(const char *folder)
{
    int fd = open(folder, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return errno;
    int err = fsync(fd) == 0 ? 0 : errno;
    close(fd);
    /* Some file systems cannot fsync a folder; the rename itself has happened. */
    return err == EINVAL || err == EROFS ? 0 : err;
}

void ilf_atomic_release(ilf_atomic *a)
{
    if (a == NULL)
        return;
    if (a->fd >= 0)
        close(a->fd);
    if (!a->committed && a->temp != NULL)
        unlink(a->temp);
    free(a->path);
    free(a->temp);
    free(a->folder);
    free(a);
}

int ilf_atomic_new(const char *path, ilf_atomic **out, const char **step)
{
    *out = NULL;
    *step = "out of memory";
    ilf_atomic *a = calloc(1, sizeof *a);
    if (a == NULL)
        return ENOMEM;
    a->fd = -1;
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash != NULL ? (size_t)(slash - path) + 1 : 0;
    const char *name = path + dirlen, *ext = extension_of(name);
    size_t cap = strlen(path) + sizeof mark + TAG_DIGITS + strlen(ext) + 2;
    a->path = strdup(path);
    a->temp = malloc(cap);
    a->folder = folder_of(path);
    if (a->path == NULL || a->temp == NULL || a->folder == NULL) {
        ilf_atomic_release(a);
        return ENOMEM;
    }
    int err = replaceable(path, step);
    if (err != 0) {
        free(a->temp);
        a->temp = NULL;
        ilf_atomic_release(a);
        return err;
    }
    *step = "cannot create a temporary file beside it";
    err = EEXIST;
    for (int attempt = 0; attempt < TRIES && err == EEXIST; attempt++) {
        snprintf(a->temp, cap, "%.*s.%s%s%0*llx%s", (int)dirlen, path, name, mark, TAG_DIGITS, fresh_tag(), ext);
        a->fd = open(a->temp, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        err = a->fd < 0 ? errno : 0;
    }
    if (err == 0) {
        struct stat old;
        if (stat(path, &old) == 0 && S_ISREG(old.st_mode) && fchmod(a->fd, old.st_mode & 07777) != 0)
            err = errno;
    }
    if (err != 0) {
        if (a->fd < 0) {
            free(a->temp);
            a->temp = NULL; /* nothing of ours to remove */
        }
        ilf_atomic_release(a);
        return err;
    }
    *out = a;
    *step = NULL;
    return 0;
}

const char *ilf_atomic_temp_path(const ilf_atomic *a) { return a->temp; }

int ilf_atomic_fd(const ilf_atomic *a) { return a->fd; }

int ilf_atomic_commit(ilf_atomic *a, const char **step)
{
    *step = "cannot write the temporary file";
    /* Flush through a fresh descriptor: the content may have been written by name (HDF5, an image library). */
    int fd = open(a->temp, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return errno;
    int err = fsync(fd) == 0 ? 0 : errno;
    close(fd);
    if (err == 0 && a->fd >= 0 && close(a->fd) != 0)
        err = errno;
    a->fd = -1;
    if (err != 0)
        return err;
    if ((err = replaceable(a->path, step)) != 0)
        return err;
    *step = "cannot rename the temporary file over it";
    if (rename(a->temp, a->path) != 0)
        return errno;
    a->committed = 1;
    *step = "written, but cannot flush its folder";
    if ((err = flush_folder(a->folder)) != 0)
        return err;
    *step = NULL;
    return 0;
}

int ilf_write_all(int fd, const void *data, size_t size)
{
    const char *p = data;
    while (size > 0) {
        ssize_t n = write(fd, p, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return n < 0 ? errno : EIO;
        p += n;
        size -= (size_t)n;
    }
    return 0;
}

int ilf_atomic_write(const char *path, const void *data, size_t size, const char **step)
{
    ilf_atomic *a = NULL;
    int err = ilf_atomic_new(path, &a, step);
    if (err != 0)
        return err;
    if ((err = ilf_write_all(a->fd, data, size)) != 0)
        *step = "cannot write the temporary file";
    else
        err = ilf_atomic_commit(a, step);
    ilf_atomic_release(a);
    return err;
}

/* @return 1 if s, after its leading ".NAME", is ".tmp-" TAG and then nothing or an extension. */
static int is_tag_and_extension(const char *s)
{
    if (strncmp(s, mark, sizeof mark - 1) != 0)
        return 0;
    s += sizeof mark - 1;
    for (int k = 0; k < TAG_DIGITS; k++, s++)
        if (!((*s >= '0' && *s <= '9') || (*s >= 'a' && *s <= 'f')))
            return 0;
    return *s == '\0' || (*s == '.' && strchr(s + 1, '/') == NULL);
}

int ilf_atomic_is_temporary_of(const char *entry, const char *name)
{
    size_t len = strlen(name);
    if (entry[0] != '.' || strncmp(entry + 1, name, len) != 0)
        return 0;
    const char *rest = entry + 1 + len, *ext = extension_of(name);
    if (!is_tag_and_extension(rest))
        return 0;
    rest += sizeof mark - 1 + TAG_DIGITS;
    return strcmp(rest, ext) == 0;
}

int ilf_atomic_is_temporary(const char *entry)
{
    if (entry[0] != '.')
        return 0;
    for (const char *p = strstr(entry, mark); p != NULL; p = strstr(p + 1, mark))
        if (p > entry + 1 && is_tag_and_extension(p))
            return 1;
    return 0;
}
