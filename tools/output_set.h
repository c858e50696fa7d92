/*
 * output_set.h - places a command's staged outputs into their folder as one
 * step that a failure undoes: every output of a run lands, and every file of
 * an earlier run that this one does not write goes, or nothing changes.
 *
 * A command stages its outputs in a staging folder inside the destination
 * folder (cli_staging_make(): the same file system, so renames are atomic),
 * each under its final name. Placing then moves every file that the set's
 * names already name in the folder aside into the staging folder, renames
 * each staged output into place, and flushes the folder; on any failure it
 * renames the new files back and the old ones back, so the folder is as it
 * was. Interruptions are held off meanwhile (cli_interrupts_hold()). The
 * files moved aside are removed with the staging folder.
 */
#ifndef ILF_OUTPUT_SET_H
#define ILF_OUTPUT_SET_H

#include <stddef.h>

/* Longest path of a slot. */
#define OUTPUT_SET_PATH 4096

/* One name of a set: its staged file, its place, where an earlier file of that name is kept meanwhile. */
typedef struct output_slot {
    char staged[OUTPUT_SET_PATH]; /* in the staging folder */
    char placed[OUTPUT_SET_PATH]; /* in the destination folder */
    char aside[OUTPUT_SET_PATH];  /* in the staging folder, under another name than any staged file */
    int written;                  /* this run staged it; otherwise an earlier file of that name is removed */
} output_slot;

/* Fills *slot with the paths of name k of a set (user: the caller's). @return 1, or 0 if a path does not fit. */
typedef int (*output_slot_fn)(void *user, size_t k, output_slot *slot);

/* Places the count names of a set, slot(user, k, ...) giving name k's paths, into folder dir as above, reporting
 * a failure as "ilf SUB: ...". Allocates (two bytes a name) before it moves anything, nothing after.
 * @return ILF_EXIT_OK, or ILF_EXIT_FAILED with dir as it was (unless only the final flush failed). */
int output_set_place(const char *sub, const char *dir, size_t count, output_slot_fn slot, void *user);

#endif /* ILF_OUTPUT_SET_H */
