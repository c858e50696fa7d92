/*
 * image.c - image/image.h: argument checks, formats by extension, atomic
 * writes (base's ilf/atomic_file.h) and input checks in plain C. Writes are
 * encoded by writers.c (OpenEXR's core library and libpng); reads are decoded
 * by the image module libilfkit_oiio.so (oiio_module.cpp, the table of
 * module.h), loaded on the first read or header read. Programs that never read an image
 * therefore never map OpenImageIO.
 *
 * Where the module is looked for, once per process (pthread_once), loaded
 * with dlopen(RTLD_NOW | RTLD_LOCAL) and never unloaded:
 *   1. $ILFKIT_IMAGE_MODULE, a full path, when set and not empty: then the
 *      only place tried, so that a test or a user can pin the module;
 *   2. <folder of /proc/self/exe>/../LIBDIR/ilfkit/<file>: the build tree
 *      (programs in BUILD/tools and BUILD/tests, the module in BUILD/LIBDIR/ilfkit)
 *      and a relocated install (PREFIX/bin, PREFIX/LIBDIR/ilfkit);
 *   3. when this code runs inside a shared library (the installed libcapture.so,
 *      PREFIX/LIBDIR), <folder of that library>/../LIBDIR/ilfkit/<file>: a user's
 *      program, wherever it lives, finds the module of the install it links;
 *   4. the configured install location, ILFKIT_IMAGE_MODULE_INSTALLED.
 * Both paths come from CMake (ILFKIT_IMAGE_MODULE_RELATIVE and _INSTALLED).
 *
 * Invariants:
 *   - guess_format, free and write never load the module; argument errors
 *     are reported without loading it.
 *   - After the once-only load, the module pointer and the load failure text
 *     are read-only, so concurrent calls need no lock.
 *   - A module whose table version differs from IMG__MODULE_VERSION is
 *     refused (and stays mapped, unused: it may have run initialisers).
 *   - A write either leaves a complete image at the path (renamed from a
 *     flushed temporary in the same folder, so the rename is atomic) or leaves
 *     the path as it was and no temporary behind. The temporary keeps the
 *     path's extension (base's rule), so any reader of a leftover sees the
 *     right type (writers.c is told the format anyway).
 *   - The library holds no message state: every report goes to the caller's
 *     err buffer, so it needs no per-thread storage.
 *   - Every failure message is one line naming the image file; a load
 *     failure also names each module path tried and why it failed.
 */
/* dladdr1() (GNU) tells which loaded file holds this code: the way from a shared library to the module. */
#define _GNU_SOURCE
#include "image/image.h"

#include <ctype.h>
#include <dlfcn.h>
#include <link.h>
#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ilf/atomic_file.h"
#include "ilf/file_kind.h"
#include "ilf/limits.h"
#include "module.h"
#include "writers.h"

#ifndef ILFKIT_IMAGE_MODULE_RELATIVE
#error "ILFKIT_IMAGE_MODULE_RELATIVE (LIBDIR/ilfkit/<file>, relative to a prefix) must be defined"
#endif
#ifndef ILFKIT_IMAGE_MODULE_INSTALLED
#error "ILFKIT_IMAGE_MODULE_INSTALLED (the module's installed path) must be defined"
#endif

#define MESSAGE_BYTES ILF_MESSAGE_BYTES
#define MODULE_PATH_BYTES 4096

/* ------------------------------------------------------------ messages */

/* Formats a message into err (when given). @return status. */
static img_status fail(img_status status, char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static img_status fail(img_status status, char *err, size_t errlen, const char *fmt, ...)
{
    if (err != NULL && errlen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return status;
}

const char *img_status_name(img_status s)
{
    switch (s) {
    case IMG_OK:
        return "ok";
    case IMG_ERR_ARG:
        return "bad argument";
    case IMG_ERR_INPUT:
        return "bad input";
    case IMG_ERR_OUTPUT:
        return "cannot write";
    case IMG_ERR_NOMEM:
        return "out of memory";
    }
    return "unknown status";
}

/* ------------------------------------------------------------ the module */

static pthread_once_t module_once = PTHREAD_ONCE_INIT;
static const img__module *module;      /* NULL until loaded, or if loading failed */
static char load_failure[2 * MESSAGE_BYTES]; /* "path: reason; path: reason" when module is NULL */

/* Appends "; " (unless first) and the formatted text to load_failure, truncating. */
static void note_failure(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

static void note_failure(const char *fmt, ...)
{
    size_t used = strlen(load_failure);
    if (used > 0 && used + 2 < sizeof load_failure) {
        memcpy(load_failure + used, "; ", 3);
        used += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(load_failure + used, sizeof load_failure - used, fmt, ap);
    va_end(ap);
}

/* @return dlerror()'s text, or fallback when it has none. */
static const char *dl_reason(const char *fallback)
{
    const char *reason = dlerror();
    return reason != NULL ? reason : fallback;
}

/* Opens path and checks its table. @return the table, or NULL with the reason noted. */
static const img__module *open_module(const char *path)
{
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        note_failure("%s", dl_reason(path));
        return NULL;
    }
    dlerror();
    void *symbol = dlsym(handle, IMG__MODULE_ENTRY);
    if (symbol == NULL) {
        note_failure("%s", dl_reason(path));
        return NULL;
    }
    /* POSIX guarantees that dlsym's object pointer converts to a function pointer. */
    img__module_entry_fn entry;
    _Static_assert(sizeof entry == sizeof symbol, "function and object pointers differ in size");
    memcpy(&entry, &symbol, sizeof entry);
    const img__module *table = entry();
    if (table == NULL || table->version != IMG__MODULE_VERSION) {
        note_failure("%s: module version %u, this program needs %u", path, table != NULL ? table->version : 0u,
                     IMG__MODULE_VERSION);
        return NULL;
    }
    return table;
}

/* Writes <folder of file>/../ILFKIT_IMAGE_MODULE_RELATIVE to out. @return 1, or 0 with the reason noted. */
static int beside(const char *file, char *out, size_t outlen)
{
    const char *slash = strrchr(file, '/');
    if (slash == NULL) {
        note_failure("no folder in %s", file);
        return 0;
    }
    int len = snprintf(out, outlen, "%.*s/../%s", (int)(slash - file), file, ILFKIT_IMAGE_MODULE_RELATIVE);
    if (len < 0 || (size_t)len >= outlen) {
        note_failure("%s: path too long", file);
        return 0;
    }
    return 1;
}

/* Writes the module's path beside this program to out. @return 1, or 0 with the reason noted. */
static int beside_program(char *out, size_t outlen)
{
    char exe[MODULE_PATH_BYTES];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0 || (size_t)n >= sizeof exe - 1) {
        note_failure("/proc/self/exe: %s", n < 0 ? strerror(errno) : "path too long");
        return 0;
    }
    exe[n] = '\0';
    return beside(exe, out, outlen);
}

/* Writes the module's path beside the shared library holding this code to out.
 * @return 1, or 0 when this code is part of the program itself (already tried) or the library's path is unknown. */
static int beside_library(char *out, size_t outlen)
{
    Dl_info info;
    struct link_map *map = NULL;
    if (dladdr1(&module_once, &info, (void **)&map, RTLD_DL_LINKMAP) == 0 || map == NULL || map->l_name == NULL ||
        map->l_name[0] == '\0')
        return 0; /* the main program's link map has no name */
    return beside(map->l_name, out, outlen);
}
/* pthread_once routine: sets module from the first place that gives a valid table. */
static void load_module(void)
{
    const char *pinned = getenv("ILFKIT_IMAGE_MODULE");
    if (pinned != NULL && pinned[0] != '\0') {
        module = open_module(pinned);
        return;
    }
    char path[MODULE_PATH_BYTES];
    if (beside_program(path, sizeof path))
        module = open_module(path);
    if (module == NULL && beside_library(path, sizeof path))
        module = open_module(path);
    if (module == NULL)
        module = open_module(ILFKIT_IMAGE_MODULE_INSTALLED);
}

/* @return the loaded module, or NULL (and a message naming path, to be read) if it cannot be loaded. */
static const img__module *need_module(const char *path, char *err, size_t errlen)
{
    pthread_once(&module_once, load_module);
    if (module == NULL)
        fail(IMG_ERR_INPUT, err, errlen, "%s: cannot read: image support is not available (%s)", path, load_failure);
    return module;
}

/* ------------------------------------------------------------ names and formats */

/* @return the extension of path's last component without its dot, "" if none. */
static const char *extension_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    return dot != NULL && (slash == NULL || dot > slash) ? dot + 1 : "";
}

/* @return whether a and b are equal, ignoring ASCII case. */
static int equals_ignoring_case(const char *a, const char *b)
{
    for (; *a != '\0' && *b != '\0'; a++, b++)
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b))
            return 0;
    return *a == *b;
}

img_format img_guess_format(const char *path)
{
    if (path == NULL)
        return IMG_FORMAT_UNKNOWN;
    const char *ext = extension_of(path);
    if (equals_ignoring_case(ext, "exr"))
        return IMG_FORMAT_EXR;
    if (equals_ignoring_case(ext, "png"))
        return IMG_FORMAT_PNG;
    if (equals_ignoring_case(ext, "hdr"))
        return IMG_FORMAT_HDR;
    return IMG_FORMAT_UNKNOWN;
}

/* ------------------------------------------------------------ writing */

/* @return IMG_OK if img_write's arguments are usable, else IMG_ERR_ARG with a message; loads nothing. */
static img_status check_write_args(const char *path, int width, int height, int channels, const float *pixels,
                                   char *err, size_t errlen)
{
    if (path == NULL || pixels == NULL)
        return fail(IMG_ERR_ARG, err, errlen, "image path or pixels missing");
    if (img_guess_format(path) == IMG_FORMAT_UNKNOWN)
        return fail(IMG_ERR_ARG, err, errlen, "%s: unsupported image type (use .exr or .png)", path);
    if (width < 1 || height < 1 || width > IMG_MAX_SIDE || height > IMG_MAX_SIDE)
        return fail(IMG_ERR_ARG, err, errlen, "%s: image size %dx%d out of range", path, width, height);
    if (channels < 1 || channels > 4)
        return fail(IMG_ERR_ARG, err, errlen, "%s: %d channels (1 to 4 supported)", path, channels);
    return IMG_OK;
}

/* Encodes into a's temporary and commits it over path. @return a status, with a message on failure. */
static img_status encode_and_commit(ilf_atomic *a, const char *path, int width, int height, int channels,
                                    const float *pixels, char *err, size_t errlen)
{
    char msg[MESSAGE_BYTES] = "";
    img_status status = img__write_pixels(ilf_atomic_temp_path(a), path, img_guess_format(path), width, height,
                                          channels, pixels, msg, sizeof msg);
    if (status != IMG_OK)
        return fail(status, err, errlen, "%s", msg);
    const char *step = NULL;
    int code = ilf_atomic_commit(a, &step);
    if (code != 0)
        return fail(IMG_ERR_OUTPUT, err, errlen, "%s: %s: %s", path, step, strerror(code));
    return IMG_OK;
}

img_status img_write(const char *path, int width, int height, int channels, const float *pixels, char *err,
                     size_t errlen)
{
    img_status status = check_write_args(path, width, height, channels, pixels, err, errlen);
    if (status != IMG_OK)
        return status;
    ilf_atomic *a = NULL;
    const char *step = NULL;
    int code = ilf_atomic_new(path, &a, &step);
    if (code != 0)
        return fail(code == ENOMEM ? IMG_ERR_NOMEM : IMG_ERR_OUTPUT, err, errlen, "%s: cannot create a file there: %s",
                    path, strerror(code));
    status = encode_and_commit(a, path, width, height, channels, pixels, err, errlen);
    ilf_atomic_release(a); /* removes the temporary unless it was committed */
    return status;
}

/* ------------------------------------------------------------ reading */

/* @return IMG_OK if path is a regular file (opened without blocking: a FIFO is refused, never waited on), else
 * IMG_ERR_INPUT with a message naming it. */
static img_status check_readable(const char *path, char *err, size_t errlen)
{
    char why[160];
    int code = ilf_input_check(path, why, sizeof why);
    if (code == EISDIR)
        return fail(IMG_ERR_INPUT, err, errlen, "%s: is a folder, not an image", path);
    if (code != 0)
        return fail(IMG_ERR_INPUT, err, errlen, "%s: %s", path, why);
    return IMG_OK;
}

/* Checks path as a readable regular file and loads the module. @return the module, or NULL with err set. */
static const img__module *reader_for(const char *path, char *err, size_t errlen)
{
    if (check_readable(path, err, errlen) != IMG_OK)
        return NULL;
    return need_module(path, err, errlen);
}

img_status img_read(const char *path, img_image *img, char *err, size_t errlen)
{
    if (img != NULL)
        memset(img, 0, sizeof *img);
    if (path == NULL || img == NULL)
        return fail(IMG_ERR_ARG, err, errlen, "image path or output missing");
    const img__module *m = reader_for(path, err, errlen);
    if (m == NULL)
        return IMG_ERR_INPUT;
    char msg[MESSAGE_BYTES] = "";
    img_status status = m->read(path, img, msg, sizeof msg);
    if (status != IMG_OK) {
        memset(img, 0, sizeof *img);
        return fail(status, err, errlen, "%s", msg);
    }
    return IMG_OK;
}

img_status img_header_read(const char *path, img_header *hdr, char *err, size_t errlen)
{
    if (hdr != NULL)
        memset(hdr, 0, sizeof *hdr);
    if (path == NULL || hdr == NULL)
        return fail(IMG_ERR_ARG, err, errlen, "image path or output missing");
    const img__module *m = reader_for(path, err, errlen);
    if (m == NULL)
        return IMG_ERR_INPUT;
    char msg[MESSAGE_BYTES] = "";
    img_status status = m->header(path, hdr, msg, sizeof msg);
    if (status != IMG_OK) {
        memset(hdr, 0, sizeof *hdr);
        return fail(status, err, errlen, "%s", msg);
    }
    return IMG_OK;
}

void img_free(img_image *img)
{
    if (img == NULL)
        return;
    free(img->pixels);
    memset(img, 0, sizeof *img);
}
