/*
 * points_file.h - the points file of `ilf irradiance --points FILE`: one
 * receiver per line, "x y z nx ny nz" (position in metres, then the normal it
 * faces, any nonzero length), six finite numbers separated by blanks; blank
 * lines and lines whose first non-blank character is '#' are skipped.
 */
#ifndef ILF_POINTS_FILE_H
#define ILF_POINTS_FILE_H

#include <stddef.h>

/** Points read from a file: 6 doubles each, count of them. */
typedef struct point_list {
    double *values;
    size_t count, capacity;
} point_list;

/**
 * Reads every point of path ("-": standard input) into list (start from
 * {NULL, 0, 0}), reporting any problem on stderr as "ilf irradiance: FILE:LINE: ...".
 * @return ILF_EXIT_OK; ILF_EXIT_USAGE for a file that cannot be read or a
 * malformed line; ILF_EXIT_FAILED when memory runs out. list holds what was
 * read either way: points_free() it.
 */
int points_read(const char *path, point_list *list);

/** Frees list's points and empties it. */
void points_free(point_list *list);

#endif
