/*
 * image.c - capture/image.h: argument checks, formats by extension, atomic
 * writes and input checks in plain C, with the pixels encoded and decoded by
 * the image module libilfkit_oiio.so (image_oiio.cpp, the table of
 * image_module.h), loaded on the first read or write. Programs that never
 * touch an image therefore never map OpenImageIO.
 *
 * Where the module is looked for, once per process (pthread_once), loaded
 * with dlopen(RTLD_NOW | RTLD_LOCAL) and never unloaded:
 *   1. $ILFKIT_IMAGE_MODULE, a full path, when set and not empty: then the
 *      only place tried, so that a test or a user can pin the module;
 *   2. <folder of /proc/self/exe>/../LIBDIR/ilfkit/<file>: the build tree
 *      (programs in BUILD/tools and BUILD/tests, the module in BUILD/LIBDIR/ilfkit)
 *      and a relocated install (PREFIX/bin, PREFIX/LIBDIR/ilfkit);
 *   3. the configured install location, ILFKIT_IMAGE_MODULE_INSTALLED.
 * Both paths come from CMake (ILFKIT_IMAGE_MODULE_RELATIVE and _INSTALLED).
 *
 * Invariants:
 *   - guess_format and free never load the module; argument errors are
 *     reported without loading it; a write that cannot load it creates no file.
 *   - After the once-only load, the module pointer and the load failure text
 *     are read-only, so concurrent calls need no lock.
 *   - A module whose table version differs from CAP__IMAGE_MODULE_VERSION is
 *     refused (and stays mapped, unused: it may have run initialisers).
 *   - A write either leaves a complete image at the path (renamed from a
 *     flushed temporary in the same folder, so the rename is atomic) or leaves
 *     the path as it was and no temporary behind.
 *   - Every failure message is one line naming the image file; a load
 *     failure also names each module path tried and why it failed.
 */
#include <ctype.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "capture/image.h"
#include "image_module.h"
#include "internal.h"

#ifndef ILFKIT_IMAGE_MODULE_RELATIVE
#error "ILFKIT_IMAGE_MODULE_RELATIVE (LIBDIR/ilfkit/<file>, relative to a prefix) must be defined"
#endif
#ifndef ILFKIT_IMAGE_MODULE_INSTALLED
#error "ILFKIT_IMAGE_MODULE_INSTALLED (the module's installed path) must be defined"
#endif

#define MESSAGE_BYTES 1024
#define MODULE_PATH_BYTES 4096

/* Tries for a fresh temporary name before giving up on a folder. */
#define TEMPORARY_TRIES 64

/* ------------------------------------------------------------ messages */

/* Formats a message into err (when given) and the thread's capture message. @return status. */
static cap_status fail(cap_status status, char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static cap_status fail(cap_status status, char *err, size_t errlen, const char *fmt, ...)
{
    char text[MESSAGE_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (err != NULL && errlen > 0)
        snprintf(err, errlen, "%s", text);
    return cap__fail_text(status, text);
}

/* ------------------------------------------------------------ the module */

static pthread_once_t module_once = PTHREAD_ONCE_INIT;
static const cap__image_module *module;      /* NULL until loaded, or if loading failed */
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
static const cap__image_module *open_module(const char *path)
{
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        note_failure("%s", dl_reason(path));
        return NULL;
    }
    dlerror();
    void *symbol = dlsym(handle, CAP__IMAGE_MODULE_ENTRY);
    if (symbol == NULL) {
        note_failure("%s", dl_reason(path));
        return NULL;
    }
    /* POSIX guarantees that dlsym's object pointer converts to a function pointer. */
    cap__image_module_entry_fn entry;
    _Static_assert(sizeof entry == sizeof symbol, "function and object pointers differ in size");
    memcpy(&entry, &symbol, sizeof entry);
    const cap__image_module *table = entry();
    if (table == NULL || table->version != CAP__IMAGE_MODULE_VERSION) {
        note_failure("%s: module version %u, this program needs %u", path, table != NULL ? table->version : 0u,
                     CAP__IMAGE_MODULE_VERSION);
        return NULL;
    }
    return table;
}

/* Writes <folder of this program>/../ILFKIT_IMAGE_MODULE_RELATIVE to out. @return 1, or 0 with the reason noted. */
static int beside_program(char *out, size_t outlen)
{
    char exe[MODULE_PATH_BYTES];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0 || (size_t)n >= sizeof exe - 1) {
        note_failure("/proc/self/exe: %s", n < 0 ? strerror(errno) : "path too long");
        return 0;
    }
    exe[n] = '\0';
    char *slash = strrchr(exe, '/');
    if (slash == NULL) {
        note_failure("/proc/self/exe: no folder in %s", exe);
        return 0;
    }
    *slash = '\0';
    int len = snprintf(out, outlen, "%s/../%s", exe, ILFKIT_IMAGE_MODULE_RELATIVE);
    if (len < 0 || (size_t)len >= outlen) {
        note_failure("%s: path too long", exe);
        return 0;
    }
    return 1;
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
    if (module == NULL)
        module = open_module(ILFKIT_IMAGE_MODULE_INSTALLED);
}

/* @return the loaded module, or NULL (and a message naming path and what it was for) if it cannot be loaded. */
static const cap__image_module *need_module(const char *path, const char *doing, cap_status status, char *err,
                                            size_t errlen)
{
    pthread_once(&module_once, load_module);
    if (module == NULL)
        fail(status, err, errlen, "%s: cannot %s: image support is not available (%s)", path, doing, load_failure);
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

cap_image_format cap_image_guess_format(const char *path)
{
    if (path == NULL)
        return CAP_IMAGE_FORMAT_UNKNOWN;
    const char *ext = extension_of(path);
    if (equals_ignoring_case(ext, "exr"))
        return CAP_IMAGE_FORMAT_EXR;
    if (equals_ignoring_case(ext, "png"))
        return CAP_IMAGE_FORMAT_PNG;
    return CAP_IMAGE_FORMAT_UNKNOWN;
}

/* ------------------------------------------------------------ atomic writes */

/* @return a hard-to-guess tag for a temporary name: process, call count and clock mixed (splitmix64). */
static unsigned long long temporary_tag(void)
{
    static atomic_uint calls;
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    unsigned long long x = ((unsigned long long)getpid() << 32) ^ (unsigned long long)now.tv_nsec ^
                           ((unsigned long long)atomic_fetch_add(&calls, 1u) << 40);
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/*
 * Creates "<folder>/.<name>.tmp-<tag>.<ext>" next to path, exclusively, with
 * the mode of the file it will replace, or else the mode the umask gives new
 * files. Keeps the extension so that nothing downstream mistakes its format.
 * @return 1 with the name in out, or 0 with errno set.
 */
static int make_temporary(const char *path, char *out, size_t outlen)
{
    const char *slash = strrchr(path, '/');
    int dirlen = slash != NULL ? (int)(slash - path) + 1 : 0;
    const char *base = path + dirlen;
    for (int attempt = 0; attempt < TEMPORARY_TRIES; attempt++) {
        int len = snprintf(out, outlen, "%.*s.%s.tmp-%012llx.%s", dirlen, path, base,
                           temporary_tag() & 0xffffffffffffull, extension_of(path));
        if (len < 0 || (size_t)len >= outlen) {
            errno = ENAMETOOLONG;
            return 0;
        }
        int fd = open(out, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0 && errno == EEXIST)
            continue;
        if (fd < 0)
            return 0;
        struct stat old;
        int ok = stat(path, &old) != 0 || !S_ISREG(old.st_mode) || fchmod(fd, old.st_mode & 07777) == 0;
        int saved = errno;
        if (close(fd) != 0 && ok) {
            ok = 0;
            saved = errno;
        }
        if (!ok) {
            unlink(out);
            errno = saved;
        }
        return ok;
    }
    errno = EEXIST;
    return 0;
}

/* @return 1 once name's data is on disk, or 0 with errno set. */
static int flush_to_disk(const char *name)
{
    int fd = open(name, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return 0;
    int ok = fsync(fd) == 0;
    int saved = errno;
    if (close(fd) != 0 && ok) {
        ok = 0;
        saved = errno;
    }
    errno = saved;
    return ok;
}

static cap_status check_write_args(const char *path, int width, int height, int channels, const float *pixels,
                                   char *err, size_t errlen)
{
    if (path == NULL || pixels == NULL)
        return fail(CAP_ERR_ARG, err, errlen, "image path or pixels missing");
    if (cap_image_guess_format(path) == CAP_IMAGE_FORMAT_UNKNOWN)
        return fail(CAP_ERR_ARG, err, errlen, "%s: unsupported image type (use .exr or .png)", path);
    if (width < 1 || height < 1 || width > CAP_IMAGE_MAX_SIDE || height > CAP_IMAGE_MAX_SIDE)
        return fail(CAP_ERR_ARG, err, errlen, "%s: image size %dx%d out of range", path, width, height);
    if (channels < 1 || channels > 4)
        return fail(CAP_ERR_ARG, err, errlen, "%s: %d channels (1 to 4 supported)", path, channels);
    return CAP_OK;
}

/* Encodes into the fresh temporary name, flushes it and renames it over path. */
static cap_status write_and_rename(const cap__image_module *m, const char *name, const char *path, int width,
                                   int height, int channels, const float *pixels, char *err, size_t errlen)
{
    char msg[MESSAGE_BYTES] = "";
    cap_status status =
        m->write(name, path, cap_image_guess_format(path), width, height, channels, pixels, msg, sizeof msg);
    if (status != CAP_OK)
        return fail(status, err, errlen, "%s", msg);
    if (!flush_to_disk(name))
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot flush image: %s", path, strerror(errno));
    if (rename(name, path) != 0)
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot rename the finished image into place: %s", path,
                    strerror(errno));
    return CAP_OK;
}

cap_status cap_image_write(const char *path, int width, int height, int channels, const float *pixels, char *err,
                           size_t errlen)
{
    cap_status status = check_write_args(path, width, height, channels, pixels, err, errlen);
    if (status != CAP_OK)
        return status;
    const cap__image_module *m = need_module(path, "write", CAP_ERR_OUTPUT, err, errlen);
    if (m == NULL)
        return CAP_ERR_OUTPUT;
    char name[PATH_MAX + 64];
    if (!make_temporary(path, name, sizeof name))
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot create a file there: %s", path, strerror(errno));
    status = write_and_rename(m, name, path, width, height, channels, pixels, err, errlen);
    if (status != CAP_OK)
        unlink(name);
    return status;
}

/* ------------------------------------------------------------ reading */

static cap_status check_readable(const char *path, char *err, size_t errlen)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return fail(CAP_ERR_INPUT, err, errlen, "%s: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return fail(CAP_ERR_INPUT, err, errlen, "%s: is a folder, not an image", path);
    return CAP_OK;
}

cap_status cap_image_read(const char *path, cap_image *img, char *err, size_t errlen)
{
    if (img != NULL)
        memset(img, 0, sizeof *img);
    if (path == NULL || img == NULL)
        return fail(CAP_ERR_ARG, err, errlen, "image path or output missing");
    cap_status status = check_readable(path, err, errlen);
    if (status != CAP_OK)
        return status;
    const cap__image_module *m = need_module(path, "read", CAP_ERR_INPUT, err, errlen);
    if (m == NULL)
        return CAP_ERR_INPUT;
    char msg[MESSAGE_BYTES] = "";
    status = m->read(path, img, msg, sizeof msg);
    if (status != CAP_OK) {
        memset(img, 0, sizeof *img);
        return fail(status, err, errlen, "%s", msg);
    }
    return CAP_OK;
}

void cap_image_free(cap_image *img)
{
    if (img == NULL)
        return;
    free(img->pixels);
    memset(img, 0, sizeof *img);
}
