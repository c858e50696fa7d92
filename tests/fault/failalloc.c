/*
 * failalloc.c - makes one chosen allocation of ilfkit's own code fail, for
 * the out-of-memory walk of tests/alloc_fault_test.sh (loaded with LD_PRELOAD).
 *
 * It stands in for malloc, calloc, realloc, reallocarray, strdup, strndup,
 * posix_memalign and aligned_alloc. A call counts when it comes straight from
 * ilfkit's code: the executable itself (lfio, relight and capture are linked
 * into it, or into a test program) or liblfio. Calls from libraries (libc,
 * HDF5, Embree, assimp, the C++ runtime) pass through uncounted: their own
 * out-of-memory behaviour is theirs, and ours is what a test can hold to a
 * contract. A realloc that does not grow its block (a trim, whose failure
 * the caller answers by keeping the block) passes through uncounted too: it
 * has no out-of-memory path to test. Every call is forwarded to the next definition (glibc's, or
 * AddressSanitizer's when the program is built with it), so free() needs no
 * stand-in.
 *
 * Environment:
 *   ILFKIT_FAIL_ALLOC=N      the N-th counted call (from 1) returns NULL, once;
 *                            0 or unset counts only.
 *   ILFKIT_FAIL_ALLOC_LOG=F  at exit, F receives "COUNT FIRED": the number of
 *                            counted calls and whether the failure was taken.
 *   ILFKIT_FAIL_ALLOC_TRACE=1  the failing call prints its stack on stderr
 *                            (addresses: addr2line -f -e ilf turns them into lines).
 * Counting is atomic, but only a single-threaded run numbers its calls the same
 * way every time: the walk runs ilf with --threads 1.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <execinfo.h>
#include <errno.h>
#include <fcntl.h>
#include <link.h>
#include <malloc.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_RANGES 64

typedef struct {
    uintptr_t lo, hi;
} code_range;

static code_range ranges[MAX_RANGES];
static int range_count;
static long fail_at;
static atomic_long counted;
static atomic_int fired;
static const char *log_path;
static int trace;

static void *(*next_malloc)(size_t);
static void *(*next_calloc)(size_t, size_t);
static void *(*next_realloc)(void *, size_t);
static int (*next_posix_memalign)(void **, size_t, size_t);
static void *(*next_aligned_alloc)(size_t, size_t);

/* dlsym may allocate while the stand-ins are being resolved: such early
 * requests are served from this arena and never freed (free() of them would
 * be a bug, but none has been seen: glibc's dlsym allocates only on error). */
static unsigned char arena[4096] __attribute__((aligned(16)));
static size_t arena_used;
static int resolving;

static void *arena_take(size_t size)
{
    size = (size + 15) & ~(size_t)15;
    if (arena_used + size > sizeof arena)
        return NULL;
    void *p = arena + arena_used;
    arena_used += size;
    return p;
}

static void resolve(void)
{
    if (next_malloc != NULL || resolving)
        return;
    resolving = 1;
    next_calloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "calloc");
    next_realloc = (void *(*)(void *, size_t))dlsym(RTLD_NEXT, "realloc");
    next_posix_memalign = (int (*)(void **, size_t, size_t))dlsym(RTLD_NEXT, "posix_memalign");
    next_aligned_alloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "aligned_alloc");
    next_malloc = (void *(*)(size_t))dlsym(RTLD_NEXT, "malloc");
    resolving = 0;
}

/* Records the executable segments of the program and of liblfio. */
static int note_object(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    (void)data;
    const char *name = info->dlpi_name;
    const char *base = name != NULL ? strrchr(name, '/') : NULL;
    base = base != NULL ? base + 1 : name;
    int ours = name == NULL || name[0] == '\0' || strncmp(base, "liblfio.so", 10) == 0;
    for (int k = 0; ours && k < info->dlpi_phnum && range_count < MAX_RANGES; k++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[k];
        if (ph->p_type == PT_LOAD && (ph->p_flags & PF_X)) {
            ranges[range_count].lo = info->dlpi_addr + ph->p_vaddr;
            ranges[range_count].hi = info->dlpi_addr + ph->p_vaddr + ph->p_memsz;
            range_count++;
        }
    }
    return 0;
}

static void write_log(void)
{
    if (log_path == NULL)
        return;
    int fd = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0)
        return;
    char line[64];
    int n = snprintf(line, sizeof line, "%ld %d\n", atomic_load(&counted), atomic_load(&fired));
    if (n > 0 && write(fd, line, (size_t)n) != n)
        n = -1;
    close(fd);
}

__attribute__((constructor)) static void failalloc_init(void)
{
    resolve();
    const char *at = getenv("ILFKIT_FAIL_ALLOC");
    fail_at = at != NULL ? strtol(at, NULL, 10) : 0;
    log_path = getenv("ILFKIT_FAIL_ALLOC_LOG");
    trace = getenv("ILFKIT_FAIL_ALLOC_TRACE") != NULL;
    if (trace) {
        void *warm[2];
        backtrace(warm, 2); /* loads the unwinder now, not inside a failing call */
    }
    dl_iterate_phdr(note_object, NULL);
    if (log_path != NULL)
        atexit(write_log);
}

/* @return 1 if this call, made from code address caller, is the one to fail. */
static int should_fail(const void *caller)
{
    uintptr_t a = (uintptr_t)caller;
    int ours = 0;
    for (int k = 0; k < range_count && !ours; k++)
        ours = a >= ranges[k].lo && a < ranges[k].hi;
    if (!ours)
        return 0;
    long n = atomic_fetch_add(&counted, 1) + 1;
    if (n != fail_at)
        return 0;
    atomic_store(&fired, 1);
    if (trace) {
        void *frames[32];
        int depth = backtrace(frames, 32);
        Dl_info where;
        for (int k = 1; k < depth; k++)
            if (dladdr(frames[k], &where) && where.dli_fname != NULL)
                fprintf(stderr, "failalloc: #%d %s+0x%lx\n", k, where.dli_fname,
                        (unsigned long)((uintptr_t)frames[k] - (uintptr_t)where.dli_fbase));
    }
    return 1;
}

#define CALLER __builtin_extract_return_addr(__builtin_return_address(0))

void *malloc(size_t size)
{
    if (next_malloc == NULL) {
        resolve();
        if (next_malloc == NULL)
            return arena_take(size);
    }
    if (should_fail(CALLER)) {
        errno = ENOMEM;
        return NULL;
    }
    return next_malloc(size);
}

void *calloc(size_t count, size_t size)
{
    if (next_calloc == NULL) {
        resolve();
        if (next_calloc == NULL) {
            void *p = count != 0 && size > SIZE_MAX / count ? NULL : arena_take(count * size);
            return p; /* the arena is static, so already zero */
        }
    }
    if (should_fail(CALLER)) {
        errno = ENOMEM;
        return NULL;
    }
    return next_calloc(count, size);
}

void *realloc(void *old, size_t size)
{
    resolve();
    if (old != NULL && size > 0 && size <= malloc_usable_size(old))
        return next_realloc(old, size);
    if (should_fail(CALLER)) {
        errno = ENOMEM;
        return NULL;
    }
    return next_realloc(old, size);
}

void *reallocarray(void *old, size_t count, size_t size)
{
    resolve();
    if (should_fail(CALLER) || (count != 0 && size > SIZE_MAX / count)) {
        errno = ENOMEM;
        return NULL;
    }
    return next_realloc(old, count * size);
}

int posix_memalign(void **out, size_t alignment, size_t size)
{
    resolve();
    if (should_fail(CALLER))
        return ENOMEM;
    return next_posix_memalign(out, alignment, size);
}

void *aligned_alloc(size_t alignment, size_t size)
{
    resolve();
    if (should_fail(CALLER)) {
        errno = ENOMEM;
        return NULL;
    }
    return next_aligned_alloc(alignment, size);
}

char *strndup(const char *s, size_t limit)
{
    resolve();
    if (should_fail(CALLER)) {
        errno = ENOMEM;
        return NULL;
    }
    size_t n = strnlen(s, limit);
    char *p = next_malloc(n + 1);
    if (p != NULL) {
        memcpy(p, s, n);
        p[n] = '\0';
    }
    return p;
}

char *strdup(const char *s)
{
    resolve();
    if (should_fail(CALLER)) {
        errno = ENOMEM;
        return NULL;
    }
    size_t n = strlen(s) + 1;
    char *p = next_malloc(n);
    if (p != NULL)
        memcpy(p, s, n);
    return p;
}
