/*
 * bench_util.c - small helpers of `ilf bench` (see bench.h): growing text
 * buffers for the CSV, markdown and gnuplot files, reading a whole file,
 * paths, creating one folder, writing a text file atomically, clocks and
 * luminance.
 *
 * Invariants: a bench_text that failed to grow stays failed and is never
 * written; paths longer than BENCH_PATH_MAX are refused, never truncated;
 * every file goes through file_write_atomic() (jsonout.h), the one atomic
 * writer of `ilf`.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "bench.h"
#include "cli.h"
#include "ilf/file_kind.h"
#include "jsonout.h"

void bench_printf(bench_text *t, const char *fmt, ...)
{
    if (t->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = t->cap - t->len;
        int n = vsnprintf(t->cap > 0 ? t->data + t->len : NULL, room, fmt, ap);
        va_end(ap);
        if (n < 0) {
            t->failed = 1;
            return;
        }
        if ((size_t)n < room) {
            t->len += (size_t)n;
            return;
        }
        size_t cap = 2 * t->cap + (size_t)n + 256;
        char *data = realloc(t->data, cap);
        if (data == NULL) {
            t->failed = 1;
            return;
        }
        t->data = data;
        t->cap = cap;
    }
}

void bench_text_free(bench_text *t)
{
    free(t->data);
    memset(t, 0, sizeof *t);
}

char *bench_read_text(const char *path)
{
    /* opened without blocking, a regular file only: a FIFO never hangs the benchmark (ilf/file_kind.h) */
    char why[160];
    int fd;
    if (ilf_input_open(path, &fd, why, sizeof why) != 0)
        return NULL;
    FILE *f = fdopen(fd, "rb");
    if (f == NULL) {
        close(fd);
        return NULL;
    }
    bench_text t = {0};
    char buf[65536];
    size_t n;
    int bad = 0;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) {
        bad = bad || memchr(buf, '\0', n) != NULL; /* text stops at a NUL: refuse rather than truncate */
        bench_printf(&t, "%.*s", (int)n, buf);
    }
    bad = bad || ferror(f) || t.failed;
    fclose(f);
    if (bad || t.data == NULL) {
        bench_text_free(&t);
        return bad ? NULL : calloc(1, 1);
    }
    return t.data;
}

int bench_resolve_beside(char *out, const char *scene, const char *name)
{
    if (name[0] == '/')
        return snprintf(out, BENCH_PATH_MAX, "%s", name) < BENCH_PATH_MAX;
    const char *slash = strrchr(scene, '/');
    int folder = slash != NULL ? (int)(slash - scene) : 1;
    int n = snprintf(out, BENCH_PATH_MAX, "%.*s/%s", folder, slash != NULL ? scene : ".", name);
    return n >= 0 && n < BENCH_PATH_MAX;
}

int bench_path(char *out, const char *dir, const char *name)
{
    size_t len = strlen(dir);
    const char *sep = len > 0 && dir[len - 1] == '/' ? "" : "/";
    int n = snprintf(out, BENCH_PATH_MAX, "%s%s%s", dir, sep, name);
    if (n < 0 || n >= BENCH_PATH_MAX) {
        cli_error(BENCH_SUB, "path too long: %s/%s", dir, name);
        return 0;
    }
    return 1;
}

int bench_make_folder(const char *path)
{
    struct stat st;
    if (mkdir(path, 0777) != 0 && errno != EEXIST) {
        cli_error(BENCH_SUB, "cannot create folder '%s': %s", path, strerror(errno));
        return 0;
    }
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        cli_error(BENCH_SUB, "cannot use '%s' as a folder: it is not one", path);
        return 0;
    }
    return 1;
}

int bench_write_text(const char *path, const bench_text *t, const char *what, int quiet)
{
    char err[BENCH_PATH_MAX + 256];
    if (t->failed) {
        cli_error(BENCH_SUB, "out of memory while building %s", path);
        return 0;
    }
    if (!file_write_atomic(path, t->data != NULL ? t->data : "", t->len, err, sizeof err)) {
        cli_error(BENCH_SUB, "%s", err);
        return 0;
    }
    if (!quiet)
        printf("wrote %s: %s\n", path, what);
    return 1;
}

double bench_luminance(const float rgb[3])
{
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}
