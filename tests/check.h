/*
 * check.h - the few macros ilfkit's C tests share: CHECK counts a passed or
 * failed assertion and prints each failure with its place; check_report()
 * prints the closing "N passed, M failed" line and gives the exit status.
 */
#ifndef ILF_TEST_CHECK_H
#define ILF_TEST_CHECK_H

#include <stdio.h>

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

#endif
