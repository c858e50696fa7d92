/*
 * jsonout.c - JSON output shared by `ilf` subcommands (see jsonout.h): info
 * prints its report, relight writes stats.json.
 *
 * Invariants: json_write_file() and file_write_atomic() never leave a partial
 * file at the target: they write through the project's one atomic writer
 * (ilf/atomic_file.h: a temporary ".NAME.tmp-TAG" beside it, fsynced and
 * renamed over it, the folder fsynced); on any failure the temporary is
 * removed and the target untouched.
 */
#include "jsonout.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "ilf/atomic_file.h"

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
        code = ilf_atomic_write(path, line, len + 1, &step);
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
    int code = ilf_atomic_write(path, data, size, &step);
    if (code != 0)
        snprintf(err, errlen, "%s: %s: %s", path, step, strerror(code));
    return code == 0;
}
