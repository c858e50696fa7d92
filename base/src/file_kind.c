/*
 * file_kind.c - ilf/file_kind.h: inputs opened without blocking and kept only
 * when regular; outputs checked before any work.
 *
 * Invariants: an input descriptor is returned only after fstat said regular
 * file, so no read ever waits on a FIFO or a device; nothing here allocates,
 * so the checks can run before anything else and in any failure path.
 */
#include "ilf/file_kind.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Longest folder these checks examine; longer paths are left to the writers, which report precisely. */
enum { FOLDER_BYTES = 4096 };

const char *ilf_file_kind_name(unsigned mode)
{
    return S_ISREG(mode)    ? "a regular file"
           : S_ISDIR(mode)  ? "a folder"
           : S_ISFIFO(mode) ? "a FIFO"
           : S_ISCHR(mode)  ? "a character device"
           : S_ISBLK(mode)  ? "a block device"
           : S_ISSOCK(mode) ? "a socket"
                            : "not a regular file";
}

int ilf_input_open(const char *path, int *fd, char *why, size_t why_size)
{
    *fd = -1;
    /* O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer. */
    int f = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (f < 0) {
        int err = errno;
        snprintf(why, why_size, "cannot open: %s", strerror(err));
        return err;
    }
    struct stat sb;
    int err = 0;
    if (fstat(f, &sb) != 0) {
        err = errno;
        snprintf(why, why_size, "cannot examine: %s", strerror(err));
    } else if (S_ISDIR(sb.st_mode)) {
        err = EISDIR;
        snprintf(why, why_size, "is a directory, not a regular file");
    } else if (!S_ISREG(sb.st_mode)) {
        err = EINVAL;
        snprintf(why, why_size, "is %s, not a regular file", ilf_file_kind_name(sb.st_mode));
    } else {
        int flags = fcntl(f, F_GETFL);
        if (flags < 0 || fcntl(f, F_SETFL, flags & ~O_NONBLOCK) != 0) {
            err = errno;
            snprintf(why, why_size, "cannot read: %s", strerror(err));
        }
    }
    if (err != 0) {
        close(f);
        return err;
    }
    *fd = f;
    return 0;
}

int ilf_input_check(const char *path, char *why, size_t why_size)
{
    int fd;
    int err = ilf_input_open(path, &fd, why, why_size);
    if (err == 0)
        close(fd);
    return err;
}

/* Copies the folder part of path ("." for none, "/" for "/x") into folder. @return 0 if it does not fit. */
static int folder_of(const char *path, char folder[FOLDER_BYTES])
{
    const char *slash = strrchr(path, '/');
    size_t len = slash == NULL ? 1 : slash == path ? 1 : (size_t)(slash - path);
    if (len >= FOLDER_BYTES)
        return 0;
    memcpy(folder, slash == NULL ? "." : path, len);
    folder[len] = '\0';
    return 1;
}

/* Checks that folder is an existing folder this process may create files in. */
static ilf_output_verdict writable_folder(const char *folder, char *why, size_t why_size)
{
    struct stat sb;
    if (stat(folder, &sb) != 0) {
        int err = errno;
        snprintf(why, why_size, err == ENOENT ? "folder '%s' does not exist" : "folder '%s': %s", folder,
                 strerror(err));
        return ILF_OUTPUT_FAILED;
    }
    if (!S_ISDIR(sb.st_mode)) {
        snprintf(why, why_size, "'%s' is %s, not a folder", folder, ilf_file_kind_name(sb.st_mode));
        return ILF_OUTPUT_FAILED;
    }
    if (access(folder, W_OK | X_OK) != 0) {
        snprintf(why, why_size, "cannot write in folder '%s': %s", folder, strerror(errno));
        return ILF_OUTPUT_FAILED;
    }
    return ILF_OUTPUT_OK;
}

ilf_output_verdict ilf_output_check(const char *path, char *why, size_t why_size)
{
    size_t len = strlen(path);
    if (len == 0 || path[len - 1] == '/') {
        snprintf(why, why_size, "names a folder, not a file");
        return ILF_OUTPUT_REFUSED;
    }
    struct stat sb;
    if (stat(path, &sb) == 0) {
        if (S_ISDIR(sb.st_mode)) {
            snprintf(why, why_size, "is a folder, not a file");
            return ILF_OUTPUT_REFUSED;
        }
        if (!S_ISREG(sb.st_mode)) {
            snprintf(why, why_size, "is %s, not a regular file: only regular files are replaced",
                     ilf_file_kind_name(sb.st_mode));
            return ILF_OUTPUT_REFUSED;
        }
    } else if (errno != ENOENT) {
        snprintf(why, why_size, "%s", strerror(errno));
        return ILF_OUTPUT_FAILED;
    }
    char folder[FOLDER_BYTES];
    return folder_of(path, folder) ? writable_folder(folder, why, why_size) : ILF_OUTPUT_OK;
}

ilf_output_verdict ilf_output_folder_check(const char *path, char *why, size_t why_size)
{
    char at[FOLDER_BYTES];
    size_t len = strlen(path);
    if (len == 0) {
        snprintf(why, why_size, "an empty folder name");
        return ILF_OUTPUT_REFUSED;
    }
    if (len >= sizeof at)
        return ILF_OUTPUT_OK; /* left to mkdir and the writers, which report precisely */
    memcpy(at, path, len + 1);
    struct stat sb;
    if (stat(at, &sb) == 0 && !S_ISDIR(sb.st_mode)) {
        snprintf(why, why_size, "is %s, not a folder", ilf_file_kind_name(sb.st_mode));
        return S_ISREG(sb.st_mode) ? ILF_OUTPUT_FAILED : ILF_OUTPUT_REFUSED;
    }
    /* The nearest existing ancestor must be a folder this process may write: the rest is created in it. */
    for (;;) {
        while (len > 1 && at[len - 1] == '/')
            at[--len] = '\0';
        if (stat(at, &sb) == 0 || errno != ENOENT)
            return writable_folder(at, why, why_size);
        char *slash = strrchr(at, '/');
        if (slash == NULL) {
            strcpy(at, ".");
        } else {
            slash[slash == at ? 1 : 0] = '\0';
        }
        len = strlen(at);
    }
}
