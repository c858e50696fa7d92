/*
 * points_file.c - reads the points file of `ilf irradiance --points FILE`
 * (format in points_file.h), line by line with getline.
 *
 * Invariants: memory grows with the file only (a line's buffer, then 48
 * bytes per point from lines of at least 12 bytes); every malformed line is
 * bad input, reported as FILE:LINE: problem; nothing is kept from a file
 * that fails; a line holding a NUL byte is refused (what follows the NUL
 * would otherwise be silently dropped); a named file is opened without
 * blocking and only if it is a regular file (ilf/file_kind.h), while "-"
 * reads standard input, whatever it is. Fuzzed by tests/fuzz/fuzz_points.c.
 */
#include "points_file.h"

#include <errno.h>
#include <unistd.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "ilf/file_kind.h"

/* @return 1 if line holds only blanks, or a comment starting with '#' after them. */
static int skippable(const char *line)
{
    line += strspn(line, " \t\r\n\v\f");
    return *line == '\0' || *line == '#';
}

/*
 * Parses one point line into out[6]: exactly six finite numbers separated
 * by blanks, with a nonzero normal. @return 1, or 0 with a reason in why.
 */
static int parse_point(char *line, double out[6], char *why, size_t why_size)
{
    static const char blanks[] = " \t\r\n\v\f";
    char *save = NULL;
    int found = 0;
    for (char *field = strtok_r(line, blanks, &save); field != NULL; field = strtok_r(NULL, blanks, &save)) {
        if (found == 6) {
            snprintf(why, why_size, "more than 6 numbers (expected x y z nx ny nz)");
            return 0;
        }
        char inner[160];
        if (!cli_parse_double(field, &out[found], inner, sizeof inner)) {
            snprintf(why, why_size, "value %d: %s", found + 1, inner);
            return 0;
        }
        found++;
    }
    if (found < 6) {
        snprintf(why, why_size, "%d number%s, expected 6 (x y z nx ny nz)", found, found == 1 ? "" : "s");
        return 0;
    }
    if (out[3] == 0.0 && out[4] == 0.0 && out[5] == 0.0) {
        snprintf(why, why_size, "the normal (nx ny nz) is zero");
        return 0;
    }
    return 1;
}

/* Appends one point to list. @return 1, or 0 when memory runs out. */
static int append_point(point_list *list, const double p[6])
{
    if (list->count == list->capacity) {
        size_t grown = list->capacity ? 2 * list->capacity : 256;
        double *more = realloc(list->values, grown * 6 * sizeof *more);
        if (more == NULL)
            return 0;
        list->values = more;
        list->capacity = grown;
    }
    memcpy(list->values + 6 * list->count++, p, 6 * sizeof *p);
    return 1;
}

int points_read(const char *path, point_list *list)
{
    int from_stdin = strcmp(path, "-") == 0;
    const char *shown = from_stdin ? "<stdin>" : path;
    FILE *f = stdin;
    if (!from_stdin) {
        char why[160];
        int fd;
        if (ilf_input_open(path, &fd, why, sizeof why) != 0) {
            cli_error("irradiance", "%s: %s", path, why);
            return ILF_EXIT_USAGE;
        }
        if ((f = fdopen(fd, "r")) == NULL) {
            close(fd);
            cli_error("irradiance", "%s: cannot open: %s", path, strerror(errno));
            return ILF_EXIT_FAILED;
        }
    }
    char *line = NULL;
    size_t cap = 0;
    unsigned long number = 0;
    int code = ILF_EXIT_OK;
    ssize_t length;
    while (code == ILF_EXIT_OK && (length = getline(&line, &cap, f)) >= 0) {
        number++;
        double p[6];
        char why[256];
        if (strlen(line) != (size_t)length) {
            cli_error("irradiance", "%s:%lu: a NUL byte inside the line (byte %zu)", shown, number,
                      strlen(line) + 1);
            code = ILF_EXIT_USAGE;
        } else if (skippable(line)) {
            continue;
        } else if (!parse_point(line, p, why, sizeof why)) {
            cli_error("irradiance", "%s:%lu: %s", shown, number, why);
            code = ILF_EXIT_USAGE;
        } else if (!append_point(list, p)) {
            cli_error("irradiance", "out of memory after %zu points", list->count);
            code = ILF_EXIT_FAILED;
        }
    }
    if (code == ILF_EXIT_OK && ferror(f)) {
        cli_error("irradiance", "%s: cannot read: %s", shown, strerror(errno));
        code = ILF_EXIT_USAGE;
    }
    free(line);
    if (!from_stdin)
        fclose(f);
    return code;
}

void points_free(point_list *list)
{
    free(list->values);
    list->values = NULL;
    list->count = list->capacity = 0;
}
