/*
 * module.c - ilf/module.h: finding, opening and checking an optional module
 * (the image module, the mesh module) in the four places the header lists.
 *
 * Invariants: a module's fields tried, table and failure are written only
 * under the one lock, once; every failure is appended to failure, so that a
 * load that finds nothing names each path tried. dladdr1() (GNU) tells which
 * loaded file holds this code: the way from a shared library to the module.
 */
#define _GNU_SOURCE
#include "ilf/module.h"

#include <dlfcn.h>
#include <errno.h>
#include <link.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Longest path built or read here (a Linux PATH_MAX). */
#define MODULE_PATH_BYTES 4096

/* One lock for every module: loads are rare, and a second caller must wait for the first's result. */
static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;

/* Appends "; " (unless first) and the formatted text to m->failure, truncating. */
static void note_failure(ilf_module *m, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void note_failure(ilf_module *m, const char *fmt, ...)
{
    size_t used = strlen(m->failure);
    if (used > 0 && used + 2 < sizeof m->failure) {
        memcpy(m->failure + used, "; ", 3);
        used += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(m->failure + used, sizeof m->failure - used, fmt, ap);
    va_end(ap);
}

/* @return dlerror()'s text, or fallback when it has none. */
static const char *dl_reason(const char *fallback)
{
    const char *reason = dlerror();
    return reason != NULL ? reason : fallback;
}

/* Opens path and checks its table's version. @return the table, or NULL with the reason noted. */
static const void *open_module(ilf_module *m, const char *path)
{
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        note_failure(m, "%s", dl_reason(path));
        return NULL;
    }
    dlerror();
    void *symbol = dlsym(handle, m->entry);
    if (symbol == NULL) {
        note_failure(m, "%s", dl_reason(path));
        return NULL;
    }
    /* POSIX guarantees that dlsym's object pointer converts to a function pointer. */
    const void *(*entry)(void);
    _Static_assert(sizeof entry == sizeof symbol, "function and object pointers differ in size");
    memcpy(&entry, &symbol, sizeof entry);
    const void *table = entry();
    unsigned version = 0;
    if (table != NULL)
        memcpy(&version, table, sizeof version); /* every table's first member */
    if (table == NULL || version != m->version) {
        note_failure(m, "%s: module version %u, this program needs %u", path, version, m->version);
        return NULL;
    }
    return table;
}

/* Writes <folder of file>/../<m->relative> to out. @return 1, or 0 with the reason noted. */
static int beside(ilf_module *m, const char *file, char *out, size_t outlen)
{
    const char *slash = strrchr(file, '/');
    if (slash == NULL) {
        note_failure(m, "no folder in %s", file);
        return 0;
    }
    int len = snprintf(out, outlen, "%.*s/../%s", (int)(slash - file), file, m->relative);
    if (len < 0 || (size_t)len >= outlen) {
        note_failure(m, "%s: path too long", file);
        return 0;
    }
    return 1;
}

/* Writes the module's path beside this program to out. @return 1, or 0 with the reason noted. */
static int beside_program(ilf_module *m, char *out, size_t outlen)
{
    char exe[MODULE_PATH_BYTES];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0 || (size_t)n >= sizeof exe - 1) {
        note_failure(m, "/proc/self/exe: %s", n < 0 ? strerror(errno) : "path too long");
        return 0;
    }
    exe[n] = '\0';
    return beside(m, exe, out, outlen);
}

/* Writes the module's path beside the shared library holding this code to out.
 * @return 1, or 0 when this code is part of the program itself (already tried) or the library's path is unknown. */
static int beside_library(ilf_module *m, char *out, size_t outlen)
{
    Dl_info info;
    struct link_map *map = NULL;
    if (dladdr1(&load_lock, &info, (void **)&map, RTLD_DL_LINKMAP) == 0 || map == NULL || map->l_name == NULL ||
        map->l_name[0] == '\0')
        return 0; /* the main program's link map has no name */
    return beside(m, map->l_name, out, outlen);
}

/* Looks for m in the header's four places. @return the first table of the right version, or NULL. */
static const void *load(ilf_module *m)
{
    const char *pinned = getenv(m->env);
    if (pinned != NULL && pinned[0] != '\0')
        return open_module(m, pinned);
    char path[MODULE_PATH_BYTES];
    const void *table = NULL;
    if (beside_program(m, path, sizeof path))
        table = open_module(m, path);
    if (table == NULL && beside_library(m, path, sizeof path))
        table = open_module(m, path);
    if (table == NULL)
        table = open_module(m, m->installed);
    return table;
}

const void *ilf_module_get(ilf_module *m)
{
    pthread_mutex_lock(&load_lock);
    if (!m->tried) {
        m->failure[0] = '\0';
        m->table = load(m);
        m->tried = 1;
    }
    const void *table = m->table;
    pthread_mutex_unlock(&load_lock);
    return table;
}

const char *ilf_module_failure(const ilf_module *m)
{
    return m->table == NULL ? m->failure : "";
}
