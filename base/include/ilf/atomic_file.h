/*
 * ilf/atomic_file.h - the project's one atomic file writer.
 *
 * An output is written under a temporary name in its destination's folder and
 * renamed over the destination only when it is complete and on disk, so a
 * reader sees the old file or the new one, never half of one. The one rule for
 * temporary names, which ilf_atomic_is_temporary_of recognises:
 *
 *     FOLDER/.NAME.tmp-TAG[.EXT]
 *
 * NAME is the destination's file name, TAG twelve hexadecimal digits, and EXT
 * the destination's extension (kept so that format-guessing writers such as
 * image libraries see the right one). The temporary gets the mode of the file
 * it replaces, else 0666 less the umask.
 *
 * Errors are errno values, and a short phrase naming the step that failed.
 * Functions are thread-safe; one ilf_atomic belongs to one thread at a time.
 */
#ifndef ILF_ATOMIC_FILE_H
#define ILF_ATOMIC_FILE_H

#include <stddef.h>

typedef struct ilf_atomic ilf_atomic;

/* Creates an empty temporary for path, open for writing. @return 0 and *out, or an errno value (*step set). */
int ilf_atomic_new(const char *path, ilf_atomic **out, const char **step);

/* @return the temporary's path, valid until ilf_atomic_release. */
const char *ilf_atomic_temp_path(const ilf_atomic *a);

/* @return the temporary's open descriptor, or -1 once committed; owned by a. */
int ilf_atomic_fd(const ilf_atomic *a);

/* Flushes the temporary (whoever wrote it, by descriptor or by name), renames it over the destination
 * and flushes the folder. @return 0, or an errno value with *step naming the step that failed. */
int ilf_atomic_commit(ilf_atomic *a, const char **step);

/* Removes the temporary unless it was committed, and frees a. NULL is a no-op. */
void ilf_atomic_release(ilf_atomic *a);

/* Writes size bytes to path atomically. @return 0, or an errno value with *step set. */
int ilf_atomic_write(const char *path, const void *data, size_t size, const char **step);

/* Writes all size bytes to descriptor fd, resuming after signals and short writes. @return 0, or an errno value. */
int ilf_write_all(int fd, const void *data, size_t size);

/* @return 1 if entry (a file name, no folder) is a temporary of the destination named name under the rule above. */
int ilf_atomic_is_temporary_of(const char *entry, const char *name);

/* @return 1 if entry is a temporary of any destination under the rule above. */
int ilf_atomic_is_temporary(const char *entry);

#endif /* ILF_ATOMIC_FILE_H */
