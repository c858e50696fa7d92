/*
 * jsonout.c - JSON output shared by `ilf` subcommands (see jsonout.h): info
 * prints its report, relight writes stats.json.
 *
 * Invariants: json_write_file() never leaves a partial file at the target:
 * the text goes to "<path>.tmp-XXXXXX" in the same folder, is fsynced and
 * renamed over the target, and the folder is fsynced; on any failure the
 * temporary is removed and the target untouched.
 */
#include "jsonout.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"

int json_add_doubles(cJSON *obj, const char *key, const double *v, int count)
{
    cJSON *arr = cJSON_CreateDoubleArray(v, count);
    if (arr != NULL && cJSON_AddItemToObject(obj, key, arr))
        return 1;
    cJSON_Delete(arr);
    return 0;
}

int json_print(const char *sub, const cJSON *root)
{
    char *text = cJSON_Print(root);
    if (text == NULL) {
        cli_error(sub, "out of memory while formatting JSON");
        return ILF_EXIT_FAILED;
    }
    puts(text);
    cJSON_free(text);
    return ILF_EXIT_OK;
}

/* Writes size bytes to fd, resuming after partial writes and signals. @return 0 or an errno value. */
static int write_fully(int fd, const char *data, size_t size)
{
    while (size > 0) {
        ssize_t n = write(fd, data, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return n < 0 ? errno : EIO;
        data += n;
        size -= (size_t)n;
    }
    return 0;
}

/* fsyncs the folder holding path, so that a rename inside it is durable. @return 0 or an errno value. */
static int sync_parent_folder(const char *path)
{
    const char *slash = strrchr(path, '/');
    char folder[4096] = ".";
    if (slash != NULL) {
        size_t len = slash == path ? 1 : (size_t)(slash - path);
        if (len >= sizeof folder)
            return ENAMETOOLONG;
        memcpy(folder, path, len);
        folder[len] = '\0';
    }
    int fd = open(folder, O_RDONLY | O_DIRECTORY);
    if (fd < 0)
        return errno;
    int err = fsync(fd) == 0 ? 0 : errno;
    close(fd);
    return err;
}

/* Writes size bytes of data to a new temporary beside path and renames it over path.
 * @return 0, or an errno value with *step saying what failed. */
static int replace_file(const char *path, const void *data, size_t size, const char **step)
{
    static const char suffix[] = ".tmp-XXXXXX";
    char *tmp = malloc(strlen(path) + sizeof suffix);
    if (tmp == NULL) {
        *step = "out of memory";
        return ENOMEM;
    }
    strcpy(tmp, path);
    strcat(tmp, suffix);
    int fd = mkstemp(tmp), err = fd < 0 ? errno : 0;
    *step = "cannot create a temporary file beside it";
    if (fd >= 0) {
        fchmod(fd, 0644); /* mkstemp makes it private; outputs are ordinary files */
        *step = "cannot write the temporary file";
        if ((err = write_fully(fd, data, size)) == 0 && fsync(fd) != 0)
            err = errno;
        if (close(fd) != 0 && err == 0)
            err = errno;
        if (err == 0 && rename(tmp, path) != 0) {
            err = errno;
            *step = "cannot rename the temporary file over it";
        }
        if (err != 0)
            remove(tmp);
        else if ((err = sync_parent_folder(path)) != 0)
            *step = "written, but cannot flush its folder";
    }
    free(tmp);
    return err;
}

int json_write_file(const char *path, const cJSON *root, char *err, size_t errlen)
{
    char *text = cJSON_Print(root);
    if (text == NULL) {
        snprintf(err, errlen, "%s: out of memory while formatting JSON", path);
        return 0;
    }
    /* cJSON_Print ends without a newline; files end with one. */
    size_t len = strlen(text);
    char *line = malloc(len + 2);
    const char *step = "";
    int code = line == NULL ? ENOMEM : 0;
    if (line != NULL) {
        memcpy(line, text, len);
        strcpy(line + len, "\n");
        code = replace_file(path, line, len + 1, &step);
    } else {
        step = "out of memory";
    }
    cJSON_free(text);
    free(line);
    if (code != 0)
        snprintf(err, errlen, "%s: %s: %s", path, step, strerror(code));
    return code == 0;
}

int file_write_atomic(const char *path, const void *data, size_t size, char *err, size_t errlen)
{
    const char *step = "";
    int code = replace_file(path, data, size, &step);
    if (code != 0)
        snprintf(err, errlen, "%s: %s: %s", path, step, strerror(code));
    return code == 0;
}
