/*
 * ilf/file_kind.h - what a path may name where ilfkit expects a file: inputs
 * and outputs are regular files, and nothing else is opened or replaced.
 *
 * An input (a scene, a manifest, a proxy, a points file, a mesh and the files
 * it names, an image) is opened with O_NONBLOCK and examined with fstat before
 * anything is read, so that a FIFO, a device or a socket where a file belongs
 * is refused at once instead of blocking the command forever or streaming
 * endless bytes; the descriptor is kept only for a regular file, in blocking
 * mode again.
 *
 * An output is placed by renaming a temporary over it (ilf/atomic_file.h), so
 * whatever the path named is replaced: ilf_output_check refuses a path that
 * names anything but a regular file or nothing (a folder, a FIFO, a device
 * node such as /dev/null), and says when its folder is missing or cannot be
 * written, before any work is done.
 *
 * Messages ("why") are phrases without the path, for the caller to prefix.
 * Functions are thread-safe and allocate nothing.
 */
#ifndef ILF_FILE_KIND_H
#define ILF_FILE_KIND_H

#include <stddef.h>

/* Opens path for reading without blocking and keeps it only if it is a regular file.
 * @return 0 and *fd (blocking, close-on-exec), or an errno value with why: EISDIR for a folder,
 * EINVAL for any other kind of file that is not regular (FIFO, device, socket). */
int ilf_input_open(const char *path, int *fd, char *why, size_t why_size);

/* ilf_input_open() and close: for files a library opens by name afterwards. @return as ilf_input_open(). */
int ilf_input_check(const char *path, char *why, size_t why_size);

/* @return "a FIFO", "a character device", "a block device", "a socket", "a folder", "a regular file",
 * or "not a regular file", for stat's st_mode. */
const char *ilf_file_kind_name(unsigned mode);

/* Verdicts of the output checks. */
typedef enum ilf_output_verdict {
    ILF_OUTPUT_OK = 0,  /* the path may be written */
    ILF_OUTPUT_REFUSED, /* it names something that must not be replaced (a folder, a special file): bad usage */
    ILF_OUTPUT_FAILED   /* its folder is missing or cannot be written: the system's reason */
} ilf_output_verdict;

/* Checks that path may be written as a file: it names a regular file or nothing, in an existing folder this
 * process may write. @return a verdict, with why unless ILF_OUTPUT_OK. */
ilf_output_verdict ilf_output_check(const char *path, char *why, size_t why_size);

/* Checks that folder path may hold outputs: it is a folder this process may write, or it does not exist and
 * its nearest existing ancestor is one (it can be created). @return a verdict, with why unless ILF_OUTPUT_OK. */
ilf_output_verdict ilf_output_folder_check(const char *path, char *why, size_t why_size);

#endif /* ILF_FILE_KIND_H */
