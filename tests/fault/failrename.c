/*
 * failrename.c - makes one chosen rename() fail, for the output-set tests of
 * tests/fault_test.sh (loaded with LD_PRELOAD): the placing of a relight's
 * outputs must undo itself when one of its renames fails.
 *
 * Environment:
 *   ILFKIT_FAIL_RENAME=PATH  the first rename() whose new name is exactly PATH
 *                            fails with EIO, once; later ones (the undo that
 *                            puts an earlier file back there) pass.
 * Every other call is forwarded to the next definition (glibc's).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

int rename(const char *from, const char *to)
{
    static atomic_int fired;
    int (*next)(const char *, const char *) = (int (*)(const char *, const char *))dlsym(RTLD_NEXT, "rename");
    const char *target = getenv("ILFKIT_FAIL_RENAME");
    if (target != NULL && strcmp(to, target) == 0 && atomic_exchange(&fired, 1) == 0) {
        errno = EIO;
        return -1;
    }
    if (next == NULL) {
        errno = ENOSYS;
        return -1;
    }
    return next(from, to);
}
