/*
 * check.h - the few macros ilfkit's C tests share: CHECK counts a passed or
 * failed assertion and prints each failure with its place; check_report()
 * prints the closing "N passed, M failed" line and gives the exit status;
 * check_mapped() tells whether this process maps a library;
 * check_stderr_begin() and check_stderr_end() catch what a call prints.
 */
#ifndef ILF_TEST_CHECK_H
#define ILF_TEST_CHECK_H

#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

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

/* The saved stderr and the scratch file while stderr is caught (one catch at a time). */
static inline int *check__stderr_fds(void)
{
    static int fds[2] = {-1, -1};
    return fds;
}

/* Sends stderr to the scratch file path (truncated) until check_stderr_end(): how a test proves that a
 * library call prints nothing. */
static inline void check_stderr_begin(const char *path)
{
    int *fds = check__stderr_fds();
    fflush(stderr);
    fds[0] = dup(2);
    fds[1] = open(path, O_CREAT | O_TRUNC | O_RDWR, 0644);
    dup2(fds[1], 2);
}

/* Restores stderr. @return the number of bytes written to it since check_stderr_begin(). */
static inline long check_stderr_end(void)
{
    int *fds = check__stderr_fds();
    fflush(stderr);
    long bytes = (long)lseek(fds[1], 0, SEEK_END);
    dup2(fds[0], 2);
    close(fds[0]);
    close(fds[1]);
    return bytes;
}

#endif
