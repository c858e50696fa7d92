/*
 * jsonout.h - JSON output for `ilf` subcommands (cJSON): number arrays,
 * printing a document to stdout, and writing one (or any bytes) to a file
 * atomically.
 *
 * Invariants: documents are printed formatted and end with a newline; a
 * file is either replaced whole (a flushed temporary renamed over it) or
 * left as it was, with no temporary behind; nothing here exits.
 */
#ifndef ILF_JSONOUT_H
#define ILF_JSONOUT_H

#include <stddef.h>

#include <cjson/cJSON.h>

/** Adds key = [v0, v1, ...] (count doubles) to obj. @return 1, or 0 when memory runs out. */
int json_add_doubles(cJSON *obj, const char *key, const double *v, int count);

/** Prints root to stdout; sub names the subcommand in an error. @return an exit code (cli.h). */
int json_print(const char *sub, const cJSON *root);

/**
 * Writes root to path atomically (temporary beside it, fsync, rename, folder fsync).
 * @return 1; 0 with a one-line message naming path in err (errlen bytes).
 */
int json_write_file(const char *path, const cJSON *root, char *err, size_t errlen);

/**
 * Writes size bytes of data (any file: CSV, text, raw arrays) to path atomically, as json_write_file().
 * @return 1; 0 with a one-line message naming path in err (errlen bytes).
 */
int file_write_atomic(const char *path, const void *data, size_t size, char *err, size_t errlen);

#endif /* ILF_JSONOUT_H */
