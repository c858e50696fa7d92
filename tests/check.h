/*
 * check.h - the few macros ilfkit's C tests share: CHECK counts a passed or
 * failed assertion and prints each failure with its place; check_report()
 * prints the closing "N passed, M failed" line and gives the exit status;
 * check_mapped() tells whether this process maps a library.
 */
#ifndef ILF_TEST_CHECK_H
#define ILF_TEST_CHECK_H

#include <stdio.h>
#include <string.h>

static long check_passed, check_failed;

#define CHECK(cond, ...)                                                      \
    do {                                                                      \
        if (cond) {                                                           \
            check_passed++;                                                   \
        } else {                                                              \
            if (++check_failed <= 40) { /* the first few say enough */      \
                fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
                fprintf(stderr, __VA_ARGS__);                                 \
                fputc('\n', stderr);                                          \
            }                                                                 \
        }                                                                     \
    } while (0)

/* Prints the summary line. @return the process exit status. */
static inline int check_report(void)
{
    printf("%ld passed, %ld failed\n", check_passed, check_failed);
    return check_failed ? 1 : 0;
}

/* @return 1 if a line of /proc/self/maps contains name (a library mapped by this process), 0 if none does,
 * -1 if the maps cannot be read: how the tests see that a module is loaded only when needed. */
static inline int check_mapped(const char *name)
{
    FILE *f = fopen("/proc/self/maps", "r");
    if (f == NULL)
        return -1;
    char line[4096 + 128];
    int found = 0;
    while (!found && fgets(line, sizeof line, f) != NULL)
        found = strstr(line, name) != NULL;
    fclose(f);
    return found;
}

#endif
