/*
 * cli.c - the pieces every `ilf` subcommand shares (see cli.h): error
 * reporting and exit codes, the option parser and help printer, strict
 * number parsing, slab selection, the progress bar, and the removal of
 * in-flight temporaries when the command is interrupted.
 *
 * Invariants: parsers never accept part of a value; nothing here exits the
 * process (subcommands return exit codes up to main), except the
 * interruption watcher, which ends it by the signal that interrupted it;
 * stdout carries only help text, stderr carries errors and the progress bar.
 */
#include "cli.h"
#include "ilf/atomic_file.h"
#include "tonemap.h"
#include "ilf/file_kind.h"
#include "ilf/limits.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#ifdef __SANITIZE_ADDRESS__
#include <sanitizer/lsan_interface.h>
#endif

/* --------------------------------------------------------------- errors */

/* Who the messages come from: "ilf", or "ilf-mpi" and a rank (cli_set_identity()). */
static const char *message_program = "ilf";
static char message_suffix[64];

void cli_set_identity(const char *program, const char *suffix)
{
    message_program = program;
    snprintf(message_suffix, sizeof message_suffix, "%s", suffix ? suffix : "");
}

/* Set by the interruption watcher once it cleans up: the main thread's errors about outputs vanishing under
 * it are not news, and the watcher's own line says what happened. */
static atomic_int interrupting;

/* Prints "PROGRAM SUB[SUFFIX]: " and the formatted text as one line on stderr. */
static void message_line(const char *sub, const char *fmt, va_list ap)
{
    fprintf(stderr, "%s %s%s: ", message_program, sub, message_suffix);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
}

void cli_error(const char *sub, const char *fmt, ...)
{
    if (atomic_load(&interrupting))
        return;
    va_list ap;
    va_start(ap, fmt);
    message_line(sub, fmt, ap);
    va_end(ap);
}

/* -------------------------------------------------------------- warnings */

/* Warnings kept for stats.json; a fixed store, so warning never fails. */
#define MAX_WARNINGS 32
#define WARNING_BYTES 640 /* a diagnostic's line (rl_diagnostic.text) and a prefix */
static char warnings[MAX_WARNINGS][WARNING_BYTES];
static size_t warning_count;
static int quiet_mode;

void cli_set_quiet(int quiet)
{
    quiet_mode = quiet != 0;
}

void cli_warn(const char *fmt, ...)
{
    char text[WARNING_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (warning_count < MAX_WARNINGS)
        memcpy(warnings[warning_count++], text, sizeof text);
    if (!quiet_mode)
        fprintf(stderr, "%s%s: warning: %s\n", message_program, message_suffix, text);
}

size_t cli_warning_count(void)
{
    return warning_count;
}

const char *cli_warning(size_t k)
{
    return k < warning_count ? warnings[k] : "";
}

void cli_settings(const char *sub, const char *fmt, ...)
{
    if (quiet_mode)
        return;
    va_list ap;
    va_start(ap, fmt);
    message_line(sub, fmt, ap);
    va_end(ap);
}

const char *cli_one_line(const char *text, char *buf, size_t size)
{
    size_t k = 0;
    for (; text[k] != '\0' && k + 1 < size; k++)
        buf[k] = text[k] == '\n' || text[k] == '\r' ? ' ' : text[k];
    buf[k] = '\0';
    return buf;
}

int cli_lfio_failure(const char *sub, lfio_status status, cli_role role, const char *path)
{
    return cli_lfio_failure_msg(sub, status, role, path, lfio_errmsg());
}

int cli_lfio_failure_msg(const char *sub, lfio_status status, cli_role role, const char *path, const char *text)
{
    char line[1024];
    const char *msg = cli_one_line(text, line, sizeof line);
    if (msg[0] == '\0')
        msg = lfio_status_name(status);
    /* lfio's messages usually name the file already; add it only when they do not. */
    if (path != NULL && strstr(msg, path) == NULL)
        cli_error(sub, "%s: %s", path, msg);
    else
        cli_error(sub, "%s", msg);
    if (status == LFIO_ERR_NOMEM)
        return ILF_EXIT_FAILED;
    return role == CLI_INPUT ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
}

/* -------------------------------------------------------------- options */

void cli_parser_init(cli_parser *p, const cli_usage *usage, const cli_option *options,
                     size_t option_count, int argc, char **argv)
{
    p->usage = usage;
    p->options = options;
    p->option_count = option_count;
    p->argc = argc;
    p->argv = argv;
    p->next = 1;
    p->options_ended = 0;
    p->current = "";
}

static int is_help_flag(const char *arg)
{
    return strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0;
}

/* Finds a long option by the name between "--" and an optional '='. */
static int find_long_option(const cli_parser *p, const char *name, size_t len)
{
    for (size_t k = 0; k < p->option_count; k++)
        if (strlen(p->options[k].name) == len && strncmp(p->options[k].name, name, len) == 0)
            return (int)k;
    return -1;
}

static int find_short_option(const cli_parser *p, char c)
{
    for (size_t k = 0; k < p->option_count; k++)
        if (p->options[k].short_name != 0 && p->options[k].short_name == c)
            return (int)k;
    return -1;
}

/* Locates the option named by arg; *inline_value gets the text after '=' if any. */
static int identify_option(const cli_parser *p, const char *arg, const char **inline_value)
{
    *inline_value = NULL;
    if (arg[1] == '-') {
        const char *name = arg + 2;
        const char *eq = strchr(name, '=');
        size_t len = eq != NULL ? (size_t)(eq - name) : strlen(name);
        if (eq != NULL)
            *inline_value = eq + 1;
        return find_long_option(p, name, len);
    }
    if (arg[2] != '\0')
        return -1; /* bundled short options are not supported: "-ox" is an error */
    return find_short_option(p, arg[1]);
}

/* Takes the option's value from "=VALUE" or the following argument. */
static int take_value(cli_parser *p, int index, const char *inline_value, const char **value)
{
    const cli_option *opt = &p->options[index];
    if (opt->value_name == NULL) {
        if (inline_value != NULL) {
            cli_error(p->usage->sub, "option --%s takes no value", opt->name);
            return CLI_BAD;
        }
        *value = NULL;
        return index;
    }
    if (inline_value != NULL) {
        *value = inline_value;
        return index;
    }
    if (p->next >= p->argc) {
        cli_error(p->usage->sub, "option --%s needs a value (%s)", opt->name, opt->value_name);
        return CLI_BAD;
    }
    *value = p->argv[p->next++];
    return index;
}

int cli_next(cli_parser *p, const char **value)
{
    *value = NULL;
    if (p->next >= p->argc)
        return CLI_DONE;
    const char *arg = p->argv[p->next++];
    /* "-" alone is a positional argument by convention (standard input/output). */
    if (p->options_ended || arg[0] != '-' || arg[1] == '\0') {
        *value = arg;
        return CLI_POSITIONAL;
    }
    if (strcmp(arg, "--") == 0) {
        p->options_ended = 1;
        return cli_next(p, value);
    }
    if (is_help_flag(arg)) {
        cli_print_help(stdout, p->usage, p->options, p->option_count);
        return CLI_HELP;
    }
    const char *inline_value;
    int index = identify_option(p, arg, &inline_value);
    if (index < 0) {
        cli_error(p->usage->sub, "unknown option '%s' (see 'ilf %s --help')", arg, p->usage->sub);
        return CLI_BAD;
    }
    p->current = p->options[index].name;
    return take_value(p, index, inline_value, value);
}

/* One row of the option table; a long left column pushes the help to its own line. */
static void print_option_line(FILE *out, const char *left, const char *help)
{
    enum { COLUMN = 28 };
    if (strlen(left) < COLUMN)
        fprintf(out, "  %-*s %s\n", COLUMN, left, help);
    else
        fprintf(out, "  %s\n  %-*s %s\n", left, COLUMN, "", help);
}

void cli_print_help(FILE *out, const cli_usage *usage, const cli_option *options, size_t option_count)
{
    fprintf(out, "Usage: ilf %s %s\n\n%s\n\nOptions:\n", usage->sub, usage->synopsis, usage->summary);
    for (size_t k = 0; k < option_count; k++) {
        const cli_option *o = &options[k];
        char shortcut[8] = "    "; /* keeps long names aligned whether or not a letter exists */
        char left[64];
        if (o->short_name != 0)
            snprintf(shortcut, sizeof shortcut, "-%c, ", o->short_name);
        snprintf(left, sizeof left, "%s--%s%s%s", shortcut, o->name, o->value_name ? " " : "",
                 o->value_name ? o->value_name : "");
        print_option_line(out, left, o->help);
    }
    print_option_line(out, "-h, --help", "show this help and exit");
    fprintf(out, "\n%s:\n", strchr(usage->example, '\n') != NULL ? "Examples" : "Example");
    /* Indent each line of the examples. */
    const char *line = usage->example;
    while (*line != '\0') {
        const char *end = strchr(line, '\n');
        size_t len = end != NULL ? (size_t)(end - line) : strlen(line);
        fprintf(out, "  %.*s\n", (int)len, line);
        line += len + (end != NULL);
    }
}

int cli_parse(const cli_usage *usage, const cli_option *options, size_t option_count, int argc, char **argv,
              const char **path, cli_apply_fn apply, void *ctx)
{
    cli_parser p;
    cli_parser_init(&p, usage, options, option_count, argc, argv);
    const char *value;
    for (int opt; (opt = cli_next(&p, &value)) != CLI_DONE;) {
        if (opt == CLI_HELP)
            return ILF_EXIT_OK;
        if (opt == CLI_BAD)
            return ILF_EXIT_USAGE;
        int ok = opt == CLI_POSITIONAL && path != NULL ? cli_single_path(usage->sub, path, value)
                                                       : apply(&p, opt, value, ctx);
        if (!ok)
            return ILF_EXIT_USAGE;
    }
    return -1;
}

int cli_single_path(const char *sub, const char **path, const char *value)
{
    if (*path != NULL) {
        cli_error(sub, "one file at a time (got '%s' and '%s')", *path, value);
        return 0;
    }
    *path = value;
    return 1;
}

int cli_bad_value(const cli_parser *p, const char *value, const char *why)
{
    cli_error(p->usage->sub, "--%s '%s': %s", p->current, value, why);
    return ILF_EXIT_USAGE;
}

/* -------------------------------------------------------------- numbers */

int cli_parse_double(const char *text, double *out, char *why, size_t why_size)
{
    /* strtod skips leading blanks and accepts "inf" and "nan"; neither is a valid value here. */
    if (text[0] == '\0' || isspace((unsigned char)text[0])) {
        snprintf(why, why_size, "expected a number");
        return 0;
    }
    char *end;
    double x = strtod(text, &end);
    if (end == text || *end != '\0') {
        snprintf(why, why_size, "'%s' is not a number", text);
        return 0;
    }
    /* Overflow gives infinity; underflow to a tiny or zero value is harmless and accepted. */
    if (!isfinite(x)) {
        snprintf(why, why_size, "'%s' is not a finite number", text);
        return 0;
    }
    *out = x;
    return 1;
}

int cli_parse_doubles(const char *text, double *out, size_t count, char *why, size_t why_size)
{
    double values[16];
    size_t found = 0;
    const char *field = text;
    if (count > sizeof values / sizeof values[0]) {
        snprintf(why, why_size, "too many values requested");
        return 0;
    }
    for (;;) {
        const char *comma = strchr(field, ',');
        size_t len = comma != NULL ? (size_t)(comma - field) : strlen(field);
        char buf[128];
        if (found == count) {
            found++; /* count the surplus fields for the message */
        } else {
            if (len >= sizeof buf) {
                snprintf(why, why_size, "value %zu is too long", found + 1);
                return 0;
            }
            memcpy(buf, field, len);
            buf[len] = '\0';
            if (!cli_parse_double(buf, &values[found], why, why_size))
                return 0;
            found++;
        }
        if (comma == NULL)
            break;
        field = comma + 1;
    }
    if (found != count) {
        snprintf(why, why_size, "expected %zu comma-separated numbers, got %s%zu", count,
                 found > count ? "more than " : "", found > count ? count : found);
        return 0;
    }
    memcpy(out, values, count * sizeof *out);
    return 1;
}

int cli_parse_u32(const char *text, uint32_t lo, uint32_t hi, uint32_t *out, char *why, size_t why_size)
{
    /* Digits only: strtoull would accept "-1" (as a huge number), blanks and "+". */
    size_t len = strlen(text);
    int digits_only = len > 0;
    for (size_t k = 0; k < len; k++)
        digits_only = digits_only && isdigit((unsigned char)text[k]);
    if (!digits_only) {
        snprintf(why, why_size, "expected a whole number from %u to %u", (unsigned)lo, (unsigned)hi);
        return 0;
    }
    errno = 0;
    unsigned long long x = strtoull(text, NULL, 10);
    if (errno == ERANGE || x < lo || x > hi) {
        snprintf(why, why_size, "must be from %u to %u", (unsigned)lo, (unsigned)hi);
        return 0;
    }
    *out = (uint32_t)x;
    return 1;
}

int cli_parse_u32_pair(const char *text, char sep, uint32_t lo, uint32_t hi, uint32_t out[2],
                       char *why, size_t why_size)
{
    const char *mid = strchr(text, sep);
    char first[32];
    size_t len = mid != NULL ? (size_t)(mid - text) : 0;
    if (mid == NULL || len >= sizeof first || strchr(mid + 1, sep) != NULL) {
        snprintf(why, why_size, "expected two whole numbers written A%cB", sep);
        return 0;
    }
    memcpy(first, text, len);
    first[len] = '\0';
    uint32_t a, b;
    if (!cli_parse_u32(first, lo, hi, &a, why, why_size) || !cli_parse_u32(mid + 1, lo, hi, &b, why, why_size))
        return 0;
    out[0] = a;
    out[1] = b;
    return 1;
}

int cli_value_double(const cli_parser *p, const char *text, double *out)
{
    char why[160];
    return cli_parse_double(text, out, why, sizeof why) || (cli_bad_value(p, text, why), 0);
}

int cli_value_doubles(const cli_parser *p, const char *text, double *out, size_t count)
{
    char why[160];
    return cli_parse_doubles(text, out, count, why, sizeof why) || (cli_bad_value(p, text, why), 0);
}

int cli_value_u32(const cli_parser *p, const char *text, uint32_t lo, uint32_t hi, uint32_t *out)
{
    char why[160];
    return cli_parse_u32(text, lo, hi, out, why, sizeof why) || (cli_bad_value(p, text, why), 0);
}

int cli_value_threads(const cli_parser *p, const char *text, uint32_t *out)
{
    return cli_value_u32(p, text, 0, ILF_MAX_THREADS, out);
}

int cli_value_u32_pair(const cli_parser *p, const char *text, char sep, uint32_t lo, uint32_t hi,
                       uint32_t out[2])
{
    char why[160];
    return cli_parse_u32_pair(text, sep, lo, hi, out, why, sizeof why) || (cli_bad_value(p, text, why), 0);
}

int cli_value_tone(const cli_parser *p, const char *text, int exposure, tone_fixed *f)
{
    double v = 0.0;
    if (!cli_value_double(p, text, &v))
        return 0;
    if (f->kind != TONE_AUTO && (f->kind == TONE_EXPOSURE) != (exposure != 0))
        return cli_bad_value(p, text, "give only one of --exposure and --scale"), 0;
    if (exposure && !(fabs(v) <= 100.0))
        return cli_bad_value(p, text, "must be from -100 to 100"), 0;
    if (!exposure && !(v > 0.0))
        return cli_bad_value(p, text, "must be a radiance > 0 (the value shown as white)"), 0;
    f->kind = exposure ? TONE_EXPOSURE : TONE_WHITE;
    f->value = v;
    return 1;
}

/* ---------------------------------------------------------------- slabs */

int cli_select_slab(const char *sub, const char *path, const lfio_reader *r, const char *which,
                    size_t *index)
{
    size_t count = lfio_reader_slab_count(r);
    if (which == NULL) {
        *index = 0;
        return 1;
    }
    uint32_t k;
    char why[160];
    if (cli_parse_u32(which, 0, UINT32_MAX, &k, why, sizeof why)) {
        if (k < count) {
            *index = k;
            return 1;
        }
        cli_error(sub, "%s: no slab %u (the file has %zu)", path, (unsigned)k, count);
        return 0;
    }
    for (size_t s = 0; s < count; s++) {
        if (strcmp(lfio_reader_slab_desc(r, s)->name, which) == 0) {
            *index = s;
            return 1;
        }
    }
    cli_error(sub, "%s: no slab named '%s'", path, which);
    return 0;
}

/* @return the exit code for verdict v on path, reported with why. */
static int output_verdict(const char *sub, const char *path, ilf_output_verdict v, const char *why)
{
    if (v == ILF_OUTPUT_OK)
        return ILF_EXIT_OK;
    cli_error(sub, "cannot write %s: %s", path, why);
    return v == ILF_OUTPUT_REFUSED ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
}

int cli_output_check(const char *sub, const char *path)
{
    char why[512];
    return output_verdict(sub, path, ilf_output_check(path, why, sizeof why), why);
}

int cli_output_folder_check(const char *sub, const char *dir, const char *const *names, size_t count)
{
    char why[512], path[4096];
    int code = output_verdict(sub, dir, ilf_output_folder_check(dir, why, sizeof why), why);
    size_t len = strlen(dir);
    struct stat st;
    /* a folder still to be created holds nothing yet */
    int exists = stat(dir, &st) == 0;
    for (size_t k = 0; code == ILF_EXIT_OK && exists && k < count; k++) {
        int n = snprintf(path, sizeof path, "%s%s%s", dir, len > 0 && dir[len - 1] == '/' ? "" : "/", names[k]);
        if (n > 0 && (size_t)n < sizeof path)
            code = output_verdict(sub, path, ilf_output_check(path, why, sizeof why), why);
    }
    return code;
}

int cli_stdout_finish(const char *sub, int code)
{
    errno = 0;
    if (fflush(stdout) == 0 && !ferror(stdout))
        return code;
    cli_error(sub, "cannot write the standard output: %s", errno != 0 ? strerror(errno) : "write error");
    return code == ILF_EXIT_OK ? ILF_EXIT_FAILED : code;
}

int cli_program_run(const char *sub, int (*run)(int argc, char **argv), int argc, char **argv)
{
    cli_interrupts_install(); /* an interrupted command says so, and what it kept */
    /* results on stdout are outputs too: one that cannot be written (a full disk, /dev/full) fails the run */
    int code = cli_stdout_finish(sub, run(argc, argv));
#ifdef __SANITIZE_ADDRESS__
    /* Sanitizer builds look for leaks here, while the libraries' thread pools
     * are idle: at exit their static destructors stop those threads while
     * LeakSanitizer walks them, which crashed its tracer in CI. */
    __lsan_do_leak_check();
#endif
    return code;
}

long long cli_file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long long)st.st_size : -1;
}

const char *cli_format_bytes(long long bytes, char *buf, size_t size)
{
    static const char *const units[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
    double x = (double)bytes;
    size_t u = 0;
    while (x >= 1024.0 && u + 1 < sizeof units / sizeof units[0]) {
        x /= 1024.0;
        u++;
    }
    if (u == 0)
        snprintf(buf, size, "%lld bytes", bytes);
    else
        snprintf(buf, size, "%.1f %s", x, units[u]);
    return buf;
}

unsigned cli_default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    /* Beyond a few dozen threads the serial lfio writes dominate anyway. */
    return n < 1 ? 1u : n > 64 ? 64u : (unsigned)n;
}

/* ------------------------------------------------------------- progress */

double cli_clock_seconds(int clock_id)
{
    struct timespec ts;
    clock_gettime((clockid_t)clock_id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int64_t monotonic_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

const char *cli_format_duration(double seconds, char *buf, size_t size)
{
    if (!(seconds >= 0.0))
        seconds = 0.0;
    if (seconds < 60.0)
        snprintf(buf, size, "%.1f s", seconds);
    else if (seconds < 3600.0)
        snprintf(buf, size, "%d min %02d s", (int)(seconds / 60.0), (int)fmod(seconds, 60.0));
    else if (seconds < 1e7)
        snprintf(buf, size, "%d h %02d min", (int)(seconds / 3600.0), (int)fmod(seconds / 60.0, 60.0));
    else
        snprintf(buf, size, "%.3g s", seconds);
    return buf;
}

/* The share of the work done before the time left is shown: the first steps often set up, not work. */
#define ETA_AFTER_FRACTION 0.02
#define ETA_AFTER_SECONDS 1.0

static void progress_draw(const cli_progress *p, uint64_t done, int final)
{
    enum { WIDTH = 30 };
    double fraction = p->total > 0 ? (double)done / (double)p->total : 1.0;
    if (fraction > 1.0)
        fraction = 1.0;
    int filled = (int)(fraction * WIDTH);
    char bar[WIDTH + 1], taken[32], left[32] = "";
    memset(bar, '#', (size_t)filled);
    memset(bar + filled, '.', (size_t)(WIDTH - filled));
    bar[WIDTH] = '\0';
    double elapsed = (double)(monotonic_ms() - p->start_ms) / 1000.0;
    cli_format_duration(elapsed, taken, sizeof taken);
    if (!final && fraction >= ETA_AFTER_FRACTION && elapsed >= ETA_AFTER_SECONDS && fraction < 1.0) {
        char eta[24];
        snprintf(left, sizeof left, ", ETA %s", cli_format_duration(elapsed * (1.0 - fraction) / fraction, eta,
                                                                      sizeof eta));
    }
    /* \r redraws in place; \033[K clears what a longer earlier line left behind. */
    fprintf(stderr, "\r%s [%s] %5.1f%% %s%s\033[K", p->label, bar, 100.0 * fraction, taken, left);
    fflush(stderr);
}

void cli_progress_start(cli_progress *p, const char *label, uint64_t total)
{
    p->label = label;
    p->total = total;
    atomic_init(&p->done, 0);
    atomic_flag_clear(&p->drawing);
    atomic_init(&p->last_draw_ms, 0);
    p->start_ms = monotonic_ms();
    p->enabled = !quiet_mode && isatty(STDERR_FILENO);
    if (p->enabled)
        progress_draw(p, 0, 0);
}

void cli_progress_add(cli_progress *p, uint64_t count)
{
    uint64_t done = atomic_fetch_add(&p->done, count) + count;
    if (!p->enabled)
        return;
    int64_t now = monotonic_ms();
    if (now - atomic_load(&p->last_draw_ms) < 100)
        return;
    /* One thread draws; the others carry on instead of waiting for the terminal. */
    if (atomic_flag_test_and_set(&p->drawing))
        return;
    atomic_store(&p->last_draw_ms, now);
    progress_draw(p, done, 0);
    atomic_flag_clear(&p->drawing);
}

void cli_progress_reach(cli_progress *p, uint64_t done)
{
    uint64_t shown = atomic_load(&p->done);
    if (done > shown)
        cli_progress_add(p, done - shown);
}

void cli_progress_fraction(void *bar, double done)
{
    cli_progress_reach(bar, done <= 0.0   ? 0
                            : done >= 1.0 ? CLI_PROGRESS_STEPS
                                          : (uint64_t)(done * CLI_PROGRESS_STEPS));
}

void cli_progress_clear(cli_progress *p)
{
    if (!p->enabled)
        return;
    fputs("\r\033[K", stderr);
    fflush(stderr);
    atomic_store(&p->last_draw_ms, 0); /* redraw at the next step */
}

void cli_progress_finish(cli_progress *p)
{
    if (!p->enabled)
        return;
    progress_draw(p, atomic_load(&p->done), 1);
    fputc('\n', stderr);
}

/* --------------------------------------------------------- interruption */

/*
 * The writers (lfio, jsonout.c, the image writer) build each output under a
 * temporary name beside it, by the one rule of ilf/atomic_file.h
 * (".<name>.tmp-<tag>[.<ext>]"). A handler for SIGINT, SIGTERM and SIGHUP only writes the signal
 * number to a pipe, which is all a handler may safely do; a watcher thread
 * reading the pipe then removes the temporaries of every registered output,
 * every staging folder and every folder the command created, says in one line
 * which registered outputs it had already placed ("kept ..." or "nothing
 * written"), and ends the process by the same signal, its default action
 * restored (so the shell sees 128 + the signal: 130 for SIGINT). While the
 * main thread holds the watcher off (cli_interrupts_hold(), placing an output
 * set), an interruption waits for it to finish.
 */

#define MAX_WATCHED 16
#define MAX_WATCHED_PATH 4096

/* What a registered path is: an output file (its temporaries are removed), a staging folder (removed whole)
 * or a folder the command created (removed, with its created parents, if empty). */
enum watch_kind { WATCH_FILE, WATCH_STAGING, WATCH_CREATED };

/* Which file a path named when it was registered, to tell at an interruption whether the command replaced it. */
typedef struct file_identity {
    int exists;
    dev_t dev;
    ino_t ino;
    struct timespec mtime;
} file_identity;

static const int watched_signals[] = {SIGINT, SIGTERM, SIGHUP};
static pthread_mutex_t watched_lock = PTHREAD_MUTEX_INITIALIZER;
/* Fixed storage: registering an output cannot run out of memory. */
static char watched[MAX_WATCHED][MAX_WATCHED_PATH];
static enum watch_kind watched_kind[MAX_WATCHED];
static size_t watched_created_from[MAX_WATCHED]; /* WATCH_CREATED: length of the first folder created */
static file_identity watched_before[MAX_WATCHED]; /* WATCH_FILE: what the path named when registered */
static size_t watched_count;
static int signal_pipe[2] = {-1, -1};
/* Set while the main thread holds watched_lock (cli_interrupts_hold()); only that thread reads or writes it. */
static int held;

/* The process that installed the handlers: a child forked after (bench's sweeps) ends by the signal itself
 * instead of waking its parent's watcher through the inherited pipe. */
static pid_t watcher_owner;

/* Signal handler: hands the signal to the watcher thread. */
static void on_interrupt(int sig)
{
    if (getpid() != watcher_owner) {
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    unsigned char byte = (unsigned char)sig;
    int saved = errno;
    if (write(signal_pipe[1], &byte, 1) < 0) {
        /* the pipe is full: a signal is already on its way to the watcher */
    }
    errno = saved;
}

/* @return what path names now. */
static file_identity identity_of(const char *path)
{
    struct stat st;
    file_identity id = {0};
    if (stat(path, &st) == 0)
        id = (file_identity){1, st.st_dev, st.st_ino, st.st_mtim};
    return id;
}

/* @return 1 if path names a file now that it did not name at registration (before). */
static int was_replaced(const char *path, const file_identity *before)
{
    file_identity now = identity_of(path);
    return now.exists && (!before->exists || now.dev != before->dev || now.ino != before->ino ||
                          now.mtime.tv_sec != before->mtime.tv_sec || now.mtime.tv_nsec != before->mtime.tv_nsec);
}

/* Removes the temporaries of output path from its folder. */
static void remove_temporaries(const char *path)
{
    const char *slash = strrchr(path, '/');
    char folder[4096];
    size_t len = slash == NULL ? 1 : slash == path ? 1 : (size_t)(slash - path);
    if (len >= sizeof folder)
        return;
    memcpy(folder, slash == NULL ? "." : path, len);
    folder[len] = '\0';
    const char *name = slash == NULL ? path : slash + 1;
    DIR *dir = opendir(folder);
    if (dir == NULL)
        return;
    for (struct dirent *e; (e = readdir(dir)) != NULL;) {
        char victim[8192];
        if (ilf_atomic_is_temporary_of(e->d_name, name)
            && snprintf(victim, sizeof victim, "%s/%s", folder, e->d_name) < (int)sizeof victim)
            unlink(victim);
    }
    closedir(dir);
}

/* Removes staging folder path and every file in it (it holds no folders). The command's own
 * threads go on writing while this runs, so a file may appear after the folder was read: the
 * folder is emptied again until rmdir succeeds, after which nothing can be created in it. */
static void remove_folder(const char *path)
{
    for (int attempt = 0; attempt < 1000; attempt++) {
        DIR *dir = opendir(path);
        if (dir == NULL)
            return;
        for (struct dirent *e; (e = readdir(dir)) != NULL;) {
            char victim[8192];
            if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0
                && snprintf(victim, sizeof victim, "%s/%s", path, e->d_name) < (int)sizeof victim)
                unlink(victim);
        }
        closedir(dir);
        if (rmdir(path) == 0 || errno != ENOTEMPTY)
            return;
    }
}

/* Removes folder path and its parents, deepest first, down to the first of them the command created (the
 * prefix of created_from bytes), each only if empty. Allocates nothing. */
static void remove_created(const char *path, size_t created_from)
{
    char folder[MAX_WATCHED_PATH];
    size_t len = strlen(path);
    if (created_from == 0 || len >= sizeof folder)
        return;
    memcpy(folder, path, len + 1);
    while (len > 1 && folder[len - 1] == '/')
        folder[--len] = '\0';
    while (len >= created_from && rmdir(folder) == 0) {
        char *slash = strrchr(folder, '/');
        if (slash == NULL || len == created_from)
            break;
        while (slash > folder && slash[-1] == '/')
            slash--;
        *slash = '\0';
        len = (size_t)(slash - folder);
    }
}

/* Says on stderr, in one line, which registered outputs the command had placed before the interruption
 * ("interrupted" alone for a command that writes no files). */
static void say_what_was_kept(void)
{
    int kept = 0;
    fprintf(stderr, "%s%s%s: interrupted%s", isatty(STDERR_FILENO) ? "\n" : "", message_program, message_suffix,
            watched_count > 0 ? "; " : "");
    for (size_t k = 0; k < watched_count; k++)
        if (watched_kind[k] == WATCH_FILE && watched[k][0] != '\0' && was_replaced(watched[k], &watched_before[k]))
            fprintf(stderr, "%s%s", kept++ ? ", " : "kept (complete) ", watched[k]);
    fprintf(stderr, "%s\n", kept || watched_count == 0 ? "" : "nothing written");
}

/* Watcher thread: waits for a signal, removes every registered output's temporaries, the staging folders and
 * the folders the command created, says what was kept, ends the process. */
static void *watch_interrupts(void *unused)
{
    (void)unused;
    unsigned char sig = 0;
    while (read(signal_pipe[0], &sig, 1) != 1) {
        if (errno != EINTR)
            return NULL;
    }
    atomic_store(&interrupting, 1);
    pthread_mutex_lock(&watched_lock);
    for (size_t k = 0; k < watched_count; k++) {
        if (watched_kind[k] == WATCH_STAGING)
            remove_folder(watched[k]);
        else if (watched_kind[k] == WATCH_FILE)
            remove_temporaries(watched[k]);
    }
    /* created folders last, once the staging folders in them are gone; the latest registered first */
    for (size_t k = watched_count; k-- > 0;)
        if (watched_kind[k] == WATCH_CREATED)
            remove_created(watched[k], watched_created_from[k]);
    say_what_was_kept();
    signal(sig, SIG_DFL);
    kill(getpid(), sig);
    pause(); /* the signal ends the process; the lock stays held so no output is registered meanwhile */
    return NULL;
}

/* Installs the handlers and starts the watcher, once. @return 1 when they run. */
static int start_watcher(void)
{
    static int started;
    if (started)
        return started > 0;
    pthread_t thread;
    started = -1;
    watcher_owner = getpid();
    if (pipe(signal_pipe) != 0)
        return 0;
    if (pthread_create(&thread, NULL, watch_interrupts, NULL) != 0)
        return 0;
    pthread_detach(thread);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sa.sa_flags = SA_RESTART;
    sigemptyset(&sa.sa_mask);
    /* A signal ignored on entry (nohup, a background job of a script) stays ignored. */
    for (size_t k = 0; k < sizeof watched_signals / sizeof watched_signals[0]; k++) {
        struct sigaction old;
        if (sigaction(watched_signals[k], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(watched_signals[k], &sa, NULL);
    }
    started = 1;
    return 1;
}

/* Registers path as kind (created_from: WATCH_CREATED's prefix); called with watched_lock held. */
static void watch_locked(const char *path, enum watch_kind kind, size_t created_from)
{
    size_t length = strlen(path);
    if (watched_count < MAX_WATCHED && length < MAX_WATCHED_PATH && start_watcher()) {
        watched_kind[watched_count] = kind;
        watched_created_from[watched_count] = created_from;
        watched_before[watched_count] = kind == WATCH_FILE ? identity_of(path) : (file_identity){0};
        memcpy(watched[watched_count++], path, length + 1);
    }
}

/* Takes watched_lock unless this thread holds it already (cli_interrupts_hold()). */
static void lock_watched(void)
{
    if (!held)
        pthread_mutex_lock(&watched_lock);
}

static void unlock_watched(void)
{
    if (!held)
        pthread_mutex_unlock(&watched_lock);
}

void cli_interrupts_install(void)
{
    lock_watched();
    start_watcher();
    unlock_watched();
}

void cli_interrupts_hold(void)
{
    pthread_mutex_lock(&watched_lock);
    start_watcher();
    held = 1;
}

void cli_interrupts_release(void)
{
    held = 0;
    pthread_mutex_unlock(&watched_lock);
}

char *cli_staging_make(char *template)
{
    /* Created and registered under the lock the watcher takes before it cleans up: a signal that
     * arrives in between waits for the registration, so it never leaves the folder behind. The
     * handlers go in first: a signal between mkdtemp and their installation would end the process
     * with the folder in place (starting the watcher's thread is slow under AddressSanitizer). */
    lock_watched();
    start_watcher();
    char *made = mkdtemp(template);
    int saved = errno;
    if (made != NULL)
        watch_locked(made, WATCH_STAGING, 0);
    unlock_watched();
    errno = saved;
    return made;
}

int cli_folder_make(const char *sub, const char *path, size_t *created_from)
{
    *created_from = 0;
    char copy[MAX_WATCHED_PATH];
    size_t len = strlen(path);
    if (len == 0 || len >= sizeof copy) {
        cli_error(sub, "cannot create folder '%s': %s", path, strerror(len ? ENAMETOOLONG : ENOENT));
        return 0;
    }
    memcpy(copy, path, len + 1);
    /* Under the watcher's lock, and registered before it is released: an interruption removes what was made. */
    lock_watched();
    start_watcher();
    int ok = 1;
    /* Each '/' after the first character ends a parent; the whole path ends the folder itself. */
    for (char *at = copy + 1; ok; at++) {
        int last = *at == '\0';
        if (*at != '/' && !last)
            continue;
        *at = '\0';
        struct stat st;
        int made = mkdir(copy, 0777) == 0;
        if (made && *created_from == 0)
            *created_from = (size_t)(at - copy);
        if (!made && errno != EEXIST) {
            cli_error(sub, "cannot create folder '%s': %s", copy, strerror(errno));
            ok = 0;
        } else if (stat(copy, &st) != 0 || !S_ISDIR(st.st_mode)) {
            cli_error(sub, "cannot use '%s' as a folder: it is not one", copy);
            ok = 0;
        }
        if (last)
            break;
        *at = '/';
    }
    if (*created_from > 0)
        watch_locked(path, WATCH_CREATED, *created_from);
    unlock_watched();
    return ok;
}

void cli_folder_unmake(const char *path, size_t created_from)
{
    remove_created(path, created_from);
}

void cli_output_watch(const char *path)
{
    lock_watched();
    watch_locked(path, WATCH_FILE, 0);
    unlock_watched();
}

void cli_staging_forget(const char *path)
{
    lock_watched();
    for (size_t k = 0; k < watched_count; k++)
        if (watched_kind[k] == WATCH_STAGING && strcmp(watched[k], path) == 0)
            watched[k][0] = '\0'; /* opendir("") and rmdir("") fail harmlessly */
    unlock_watched();
}
