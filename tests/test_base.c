/*
 * test_base.c - the ground floor (base/): the thread pool runs every index
 * exactly once whatever the count, and the atomic writer's temporaries follow
 * the one naming rule, vanish on release and replace the destination whole;
 * inputs that are not regular files are refused without blocking, and outputs
 * that are not regular files are neither written nor replaced.
 */
#include <dirent.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ilf/atomic_file.h"
#include "ilf/file_kind.h"
#include "ilf/hash.h"
#include "ilf/limits.h"
#include "ilf/message.h"
#include "ilf/pool.h"

static int failures;
#define CHECK(cond)                                                                                                    \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond);                                   \
            failures++;                                                                                                \
        }                                                                                                              \
    } while (0)

/* ------------------------------------------------------------------ pool */

enum { ITEMS = 10000 };
typedef struct counted {
    atomic_uint runs[ILF_MAX_THREADS];
    atomic_size_t next;
    atomic_uint done[ITEMS];
} counted;

static void count_run(void *arg, unsigned k)
{
    counted *c = arg;
    atomic_fetch_add(&c->runs[k], 1);
    for (size_t i; (i = atomic_fetch_add(&c->next, 1)) < ITEMS;)
        atomic_fetch_add(&c->done[i], 1);
}

/* ilf_parallel_for()'s body: counts index k. */
static void count_index(void *arg, size_t k)
{
    counted *c = arg;
    atomic_fetch_add(&c->done[k], 1);
}

static void check_once(counted *c, unsigned n, const char *what)
{
    for (unsigned k = 0; k < ILF_MAX_THREADS; k++)
        if (atomic_load(&c->runs[k]) != (k < n ? 1u : 0u)) {
            fprintf(stderr, "%s, n = %u: index %u ran %u times\n", what, n, k, atomic_load(&c->runs[k]));
            failures++;
            return;
        }
    for (size_t i = 0; i < ITEMS; i++)
        if (atomic_load(&c->done[i]) != 1) {
            fprintf(stderr, "%s, n = %u: item %zu done %u times\n", what, n, i, atomic_load(&c->done[i]));
            failures++;
            return;
        }
}

static void test_pool(void)
{
    static counted c;
    const unsigned counts[] = {1, 2, 3, 7, 64};
    for (size_t t = 0; t < sizeof counts / sizeof counts[0]; t++) {
        memset(&c, 0, sizeof c);
        ilf_team *team = NULL;
        CHECK(ilf_team_start(counts[t], count_run, &c, &team) == 0 && team != NULL);
        CHECK(ilf_team_threads(team) <= counts[t]);
        ilf_team_join(team);
        check_once(&c, counts[t], "team");
        memset(&c, 0, sizeof c);
        ilf_parallel(counts[t], count_run, &c);
        check_once(&c, counts[t], "parallel");
    }
    /* Past the cap, a team is capped, and 0 = every core is at least one. */
    memset(&c, 0, sizeof c);
    ilf_team *capped = NULL;
    CHECK(ilf_team_start(ILF_MAX_THREADS + 5, count_run, &c, &capped) == 0);
    ilf_team_join(capped);
    check_once(&c, ILF_MAX_THREADS, "capped team");
    CHECK(ilf_thread_count(0) >= 1 && ilf_thread_count(0) <= ILF_MAX_THREADS);
    CHECK(ilf_thread_count(3) == 3);
    CHECK(ilf_thread_count(ILF_MAX_THREADS * 2) == ILF_MAX_THREADS);
    ilf_team_join(NULL);
    CHECK(ilf_team_threads(NULL) == 0);
    /* a parallel loop runs each index once, on any number of threads (0 taken as every core, more than indices),
     * over any number of indices (none at all) */
    const unsigned loop_threads[] = {0, 1, 2, 3, 7, 64};
    const size_t sizes[] = {0, 1, 5, ITEMS};
    for (size_t t = 0; t < sizeof loop_threads / sizeof loop_threads[0]; t++)
        for (size_t z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
            memset(&c, 0, sizeof c);
            ilf_parallel_for(loop_threads[t], sizes[z], count_index, &c);
            size_t wrong = 0;
            for (size_t i = 0; i < ITEMS; i++)
                wrong += atomic_load(&c.done[i]) != (i < sizes[z] ? 1u : 0u);
            CHECK(wrong == 0);
        }
}

/* ----------------------------------------------------------- atomic file */

/* @return the number of entries of dir that are temporaries under the rule. */
static int temporaries_in(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;)
        n += ilf_atomic_is_temporary(e->d_name);
    if (d)
        closedir(d);
    return n;
}

static char *read_all(const char *path)
{
    static char buf[256];
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

static void test_atomic(const char *tmp)
{
    char dir[4096], path[4200];
    snprintf(dir, sizeof dir, "%s/test_base.%ld", tmp, (long)getpid());
    CHECK(mkdir(dir, 0755) == 0);
    snprintf(path, sizeof path, "%s/out.v2.png", dir);
    const char *step = NULL;

    /* Released without commit: nothing remains. */
    ilf_atomic *a = NULL;
    CHECK(ilf_atomic_new(path, &a, &step) == 0 && a != NULL);
    const char *t = strrchr(ilf_atomic_temp_path(a), '/') + 1;
    CHECK(ilf_atomic_is_temporary_of(t, "out.v2.png"));
    CHECK(!ilf_atomic_is_temporary_of(t, "out.v2"));
    CHECK(ilf_atomic_is_temporary(t));
    CHECK(strcmp(t + strlen(t) - 4, ".png") == 0); /* the extension is kept */
    CHECK(temporaries_in(dir) == 1);
    ilf_atomic_release(a);
    CHECK(temporaries_in(dir) == 0);
    CHECK(access(path, F_OK) != 0);

    /* Written and committed: the destination holds it whole, and no temporary is left. */
    CHECK(ilf_atomic_write(path, "first", 5, &step) == 0);
    CHECK(read_all(path) && strcmp(read_all(path), "first") == 0);
    chmod(path, 0640);
    CHECK(ilf_atomic_write(path, "second", 6, &step) == 0);
    CHECK(read_all(path) && strcmp(read_all(path), "second") == 0);
    struct stat st;
    CHECK(stat(path, &st) == 0 && (st.st_mode & 0777) == 0640); /* a replaced file keeps its mode */
    CHECK(temporaries_in(dir) == 0);

    /* Two writers at once get two temporaries. */
    ilf_atomic *b = NULL, *c = NULL;
    CHECK(ilf_atomic_new(path, &b, &step) == 0 && ilf_atomic_new(path, &c, &step) == 0);
    CHECK(b && c && strcmp(ilf_atomic_temp_path(b), ilf_atomic_temp_path(c)) != 0);
    CHECK(temporaries_in(dir) == 2);
    ilf_atomic_release(b);
    ilf_atomic_release(c);
    ilf_atomic_release(NULL);

    /* A missing folder fails with errno and a step, creating nothing. */
    char missing[4300];
    snprintf(missing, sizeof missing, "%s/no/such/file.h5", dir);
    a = NULL;
    CHECK(ilf_atomic_new(missing, &a, &step) == ENOENT && a == NULL && step != NULL);

    /* The naming rule, both ways. */
    CHECK(ilf_atomic_is_temporary_of(".radiance.h5.tmp-0123456789ab.h5", "radiance.h5"));
    CHECK(ilf_atomic_is_temporary_of(".stage.tmp-0123456789ab", "stage"));
    CHECK(!ilf_atomic_is_temporary_of(".radiance.h5.tmp-0123456789ab.png", "radiance.h5"));
    CHECK(!ilf_atomic_is_temporary_of(".radiance.h5.tmp-0123456789a.h5", "radiance.h5"));
    CHECK(!ilf_atomic_is_temporary_of("radiance.h5.tmp-0123456789ab.h5", "radiance.h5"));
    CHECK(!ilf_atomic_is_temporary("radiance.h5"));
    CHECK(!ilf_atomic_is_temporary(".tmp-0123456789ab"));
    unlink(path);
    CHECK(rmdir(dir) == 0);
}

/* ----------------------------------------------------------- file kinds */

/* A FIFO with no writer is refused at once (a blocking open would hang this test), as input and as output; a
 * regular file is opened in blocking mode; a folder, /dev/null and a missing folder get their verdicts, and the
 * atomic writer refuses to replace a FIFO. */
static void test_file_kind(const char *tmp)
{
    char dir[4096], fifo[4200], file[4200], missing[4200], why[256];
    snprintf(dir, sizeof dir, "%s/test_base_kind_%ld", tmp, (long)getpid());
    CHECK(mkdir(dir, 0700) == 0);
    snprintf(fifo, sizeof fifo, "%s/fifo", dir);
    snprintf(file, sizeof file, "%s/file", dir);
    snprintf(missing, sizeof missing, "%s/no/file", dir);
    CHECK(mkfifo(fifo, 0600) == 0);
    const char *step = NULL;
    CHECK(ilf_atomic_write(file, "x", 1, &step) == 0);
    int fd = -1;
    CHECK(ilf_input_open(fifo, &fd, why, sizeof why) == EINVAL && fd == -1 && strstr(why, "is a FIFO") != NULL);
    CHECK(ilf_input_open(dir, &fd, why, sizeof why) == EISDIR && fd == -1);
    CHECK(ilf_input_open(missing, &fd, why, sizeof why) == ENOENT && fd == -1);
    CHECK(ilf_input_open(file, &fd, why, sizeof why) == 0 && fd >= 0);
    if (fd >= 0) {
        char c = 0;
        CHECK(read(fd, &c, 1) == 1 && c == 'x');
        close(fd);
    }
    CHECK(ilf_input_check("/dev/null", why, sizeof why) == EINVAL && strstr(why, "character device") != NULL);
    CHECK(ilf_output_check(file, why, sizeof why) == ILF_OUTPUT_OK);
    CHECK(ilf_output_check(fifo, why, sizeof why) == ILF_OUTPUT_REFUSED && strstr(why, "is a FIFO") != NULL);
    CHECK(ilf_output_check("/dev/null", why, sizeof why) == ILF_OUTPUT_REFUSED);
    CHECK(ilf_output_check(dir, why, sizeof why) == ILF_OUTPUT_REFUSED);
    CHECK(ilf_output_check(missing, why, sizeof why) == ILF_OUTPUT_FAILED && strstr(why, "does not exist") != NULL);
    CHECK(ilf_output_folder_check(dir, why, sizeof why) == ILF_OUTPUT_OK);
    CHECK(ilf_output_folder_check(missing, why, sizeof why) == ILF_OUTPUT_OK); /* can be created */
    CHECK(ilf_output_folder_check(fifo, why, sizeof why) == ILF_OUTPUT_REFUSED);
    CHECK(ilf_output_folder_check(file, why, sizeof why) == ILF_OUTPUT_FAILED);
    CHECK(ilf_atomic_write(fifo, "y", 1, &step) == EEXIST && step != NULL);
    struct stat st;
    CHECK(lstat(fifo, &st) == 0 && S_ISFIFO(st.st_mode));
    DIR *d = opendir(dir);
    int entries = 0;
    for (struct dirent *e; d != NULL && (e = readdir(d)) != NULL;)
        entries += e->d_name[0] != '.';
    if (d != NULL)
        closedir(d);
    CHECK(entries == 2); /* fifo and file: no temporary left */
    unlink(fifo);
    unlink(file);
    CHECK(rmdir(dir) == 0);
}

/* The message rule: formatted, cut at a whole UTF-8 character, safe when an argument is the buffer. */
static void test_message(void)
{
    static char buf[ILF_MESSAGE_BYTES];
    CHECK(ilf_message_format(buf, "%s: %d", "a", 7) == 4 && strcmp(buf, "a: 7") == 0);
    CHECK(ilf_message_format(buf, "ctx: %s", buf) == 9 && strcmp(buf, "ctx: a: 7") == 0);
    char big[2 * ILF_MESSAGE_BYTES];
    memset(big, 'x', sizeof big);
    big[sizeof big - 1] = '\0';
    CHECK(ilf_message_format(buf, "%s", big) == ILF_MESSAGE_BYTES - 1 && strlen(buf) == ILF_MESSAGE_BYTES - 1);
    /* a 3-byte character straddling the cut is dropped whole; one that fits exactly is kept */
    for (size_t at = ILF_MESSAGE_BYTES - 4; at <= ILF_MESSAGE_BYTES - 2; at++) {
        memset(big, 'x', sizeof big);
        big[sizeof big - 1] = '\0';
        memcpy(big + at, "\xe2\x82\xac", 3);
        size_t len = ilf_message_format(buf, "%s", big);
        CHECK(len == (at + 3 <= ILF_MESSAGE_BYTES - 1 ? ILF_MESSAGE_BYTES - 1 : at));
        CHECK(strlen(buf) == len);
    }
}

int main(void)
{
    test_message();
    const char *tmp = getenv("ILF_TEST_TMP");
    test_pool();
    test_atomic(tmp && *tmp ? tmp : "/tmp");
    test_file_kind(tmp && *tmp ? tmp : "/tmp");
    /* splitmix64 of 0 is the published first output of the generator seeded with 0. */
    CHECK(ilf_splitmix64(0) == 0xe220a8397b1dcdafull);
    if (failures)
        fprintf(stderr, "test_base: %d failures\n", failures);
    else
        printf("test_base: ok\n");
    return failures ? 1 : 0;
}
