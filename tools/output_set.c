/*
 * output_set.c - output_set.h: an output set moved into place whole, or not
 * at all.
 *
 * Invariants: nothing is allocated once the first file has moved (a failure
 * of memory cannot strand a half-placed set); a step that fails is undone in reverse order;
 * an interruption waits until the set is placed or restored.
 */
#include "output_set.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"

/* What placing did so far, to undo it: for each name, its earlier file moved aside, its new file placed. */
typedef struct set_state {
    size_t count;
    output_slot_fn slot;
    void *user;
    unsigned char *moved, *placed;
    output_slot at; /* the name being handled (16 KiB: kept off the stack) */
} set_state;

/* Puts back what placing did, in reverse: new files back to the staging folder, old ones back in place. */
static void undo(set_state *s)
{
    for (size_t k = s->count; k-- > 0;)
        if ((s->placed[k] || s->moved[k]) && s->slot(s->user, k, &s->at)) {
            if (s->placed[k])
                rename(s->at.placed, s->at.staged);
            if (s->moved[k])
                rename(s->at.aside, s->at.placed);
        }
}

/* @return 0 once dir's entries are on disk, or an errno value (none where folders cannot be flushed). */
static int flush_folder(const char *dir)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return errno;
    int err = fsync(fd) == 0 ? 0 : errno;
    close(fd);
    return err == EINVAL || err == EROFS ? 0 : err;
}

/* Moves every earlier file aside (pass 0), then every new one into place (pass 1), stopping at the first
 * failure. @return 0, or an errno value with *step and the failing path in s->at.placed. */
static int move_all(set_state *s, const char **step)
{
    for (int pass = 0; pass < 2; pass++) {
        for (size_t k = 0; k < s->count; k++) {
            if (!s->slot(s->user, k, &s->at)) {
                *step = "path too long";
                return ENAMETOOLONG;
            }
            struct stat st;
            if (pass == 0 && lstat(s->at.placed, &st) == 0) {
                if (rename(s->at.placed, s->at.aside) != 0) {
                    *step = "cannot move the earlier file aside";
                    return errno;
                }
                s->moved[k] = 1;
            } else if (pass == 1 && s->at.written) {
                if (rename(s->at.staged, s->at.placed) != 0) {
                    *step = "cannot move it into place";
                    return errno;
                }
                s->placed[k] = 1;
            }
        }
    }
    return 0;
}

int output_set_place(const char *sub, const char *dir, size_t count, output_slot_fn slot, void *user)
{
    set_state *s = calloc(1, sizeof *s);
    unsigned char *flags = calloc(count ? 2 * count : 1, 1);
    if (s == NULL || flags == NULL) {
        free(s);
        free(flags);
        cli_error(sub, "%s: out of memory while placing %zu outputs; nothing was moved", dir, count);
        return ILF_EXIT_FAILED;
    }
    *s = (set_state){count, slot, user, flags, flags + count, {{0}, {0}, {0}, 0}};
    const char *step = NULL;
    cli_interrupts_hold();
    /* Old files aside first: a name this run does not write is then gone, and one it writes is free. */
    int err = move_all(s, &step);
    char failed[OUTPUT_SET_PATH];
    memcpy(failed, s->at.placed, sizeof failed);
    if (err != 0)
        undo(s);
    /* Either way the folder's entries changed (and perhaps changed back): durable once it is flushed. */
    int flushed = flush_folder(dir);
    cli_interrupts_release();
    free(flags);
    free(s);
    if (err != 0) {
        cli_error(sub, "%s: %s: %s; %s is as it was", failed, step, strerror(err), dir);
        return ILF_EXIT_FAILED;
    }
    if (flushed != 0) {
        cli_error(sub, "%s: written, but cannot flush the folder: %s", dir, strerror(flushed));
        return ILF_EXIT_FAILED;
    }
    return ILF_EXIT_OK;
}
