/*
 * bench_plot.c - the plots of `ilf bench` (see bench.h), drawn by gnuplot:
 * the program writes a self-contained script (data inline, or a raw float
 * file beside it) to DIR/NAME.gp and runs `gnuplot NAME.gp` in DIR, which
 * draws DIR/NAME.png with the pngcairo terminal.
 *
 * Invariants: the script is always kept, so a plot can be redrawn or
 * restyled by hand (`cd DIR && gnuplot NAME.gp`); gnuplot draws into a
 * temporary beside the PNG, renamed over it only when gnuplot succeeds, so
 * a PNG is never partial; when gnuplot is not installed the scripts are
 * still written and one warning says how to draw them; text from outside
 * (scene paths) enters scripts only single-quoted and with enhanced text
 * off, so no path can break or steer a script.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench.h"
#include "cli.h"
#include "ilf/atomic_file.h"

/* Colours of the methods, in --methods order (colour-blind safe, Okabe-Ito). */
static const char *const METHOD_COLOURS[BENCH_MAX_METHODS] = {"#0072b2", "#d55e00", "#009e73", "#cc79a7",
                                                              "#e69f00", "#56b4e9", "#f0e442", "#000000"};
/* Error images: the colour scale tops out at this percentile of the methods' error pixels. */
#define IMAGE_SCALE_PERCENTILE 0.99
/* Error images narrower than this many pixels are scaled up. */
#define IMAGE_MIN_WIDTH 640

/* ------------------------------------------------------------ running gnuplot */

/* @return 1 when an executable named gnuplot is on PATH. */
static int gnuplot_installed(void)
{
    const char *path = getenv("PATH");
    if (path == NULL)
        return 0;
    while (*path != '\0') {
        const char *end = strchr(path, ':');
        size_t len = end != NULL ? (size_t)(end - path) : strlen(path);
        char file[BENCH_PATH_MAX];
        if (len > 0 && len + 9 < sizeof file) {
            snprintf(file, sizeof file, "%.*s/gnuplot", (int)len, path);
            if (access(file, X_OK) == 0)
                return 1;
        }
        path += len + (end != NULL);
    }
    return 0;
}

/* Runs `gnuplot -e "outfile='OUT'" SCRIPT` in folder dir, its stdout discarded. @return 1 when it exits with 0. */
static int run_gnuplot(const char *dir, const char *script, const char *out)
{
    char setting[BENCH_PATH_MAX + 32];
    snprintf(setting, sizeof setting, "outfile='%s'", out);
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0)
        return 0;
    if (pid == 0) {
        if (chdir(dir) == 0 && freopen("/dev/null", "w", stdout) != NULL)
            execlp("gnuplot", "gnuplot", "-e", setting, script, (char *)NULL);
        _exit(127);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

int bench_plot(const char *dir, const char *name, const bench_text *script, int quiet)
{
    static int warned;
    char script_name[256], png_name[256];
    char gp[BENCH_PATH_MAX], png[BENCH_PATH_MAX];
    snprintf(script_name, sizeof script_name, "%s.gp", name);
    snprintf(png_name, sizeof png_name, "%s.png", name);
    if (!bench_path(gp, dir, script_name) || !bench_path(png, dir, png_name) ||
        !bench_write_text(gp, script, "gnuplot script", 1))
        return 0;
    if (!gnuplot_installed()) {
        if (!warned)
            cli_error(BENCH_SUB, "warning: gnuplot is not installed: wrote the plots' scripts only; draw them with "
                                 "'cd %s && gnuplot NAME.gp' (Debian: apt-get install gnuplot-nox)",
                      dir);
        warned = 1;
        return 1;
    }
    /* gnuplot draws into the one writer's temporary (ilf/atomic_file.h), named relative to dir */
    ilf_atomic *a = NULL;
    const char *step = NULL;
    int drawn = ilf_atomic_new(png, &a, &step) == 0;
    if (drawn) {
        const char *temp = ilf_atomic_temp_path(a), *slash = strrchr(temp, '/');
        drawn = run_gnuplot(dir, script_name, slash != NULL ? slash + 1 : temp) && ilf_atomic_commit(a, &step) == 0;
    }
    ilf_atomic_release(a);
    if (!drawn) {
        cli_error(BENCH_SUB, "gnuplot could not draw %s (its script: %s)", png, gp);
        return 0;
    }
    if (!quiet)
        printf("wrote %s: drawn by gnuplot from %s\n", png, script_name);
    return 1;
}

/* ------------------------------------------------------------ script pieces */

/* Appends text as a gnuplot single-quoted string (a quote is doubled). */
static void gp_string(bench_text *t, const char *text)
{
    bench_printf(t, "'");
    for (const char *c = text; *c != '\0'; c++)
        bench_printf(t, *c == '\'' ? "''" : "%c", *c);
    bench_printf(t, "'");
}

/* Appends the opening every script shares: where it came from, the PNG terminal and the output. */
static void gp_open(bench_text *t, const char *name, int width, int height)
{
    bench_printf(t, "# %s.gp - written by %s; redraw with: gnuplot %s.gp\n", name, BENCH_CREATOR, name);
    bench_printf(t, "if (!exists('outfile')) outfile = '%s.png'\n", name);
    bench_printf(t, "set terminal pngcairo size %d,%d enhanced font 'sans,11'\nset output outfile\n", width, height);
}

/* ------------------------------------------------------------ error against time */

/* Appends datablock $NAME with one "time error mottling 'label'" line per usable run of method m (front only if
 * asked). */
static void gp_method_block(bench_text *t, const bench_sweep *s, rl_method m, int front_only, const char *suffix)
{
    /* Front points in time order: insertion order is by cost, so sort by time here. */
    size_t order[256], n = 0;
    for (size_t i = 0; i < s->count && n < 256; i++) {
        const bench_entry *e = &s->entries[i];
        if (e->setting.method != m || !e->ran || !e->result.ok || !(e->result.rmse > 0) || (front_only && !e->on_front))
            continue;
        size_t k = n++;
        while (k > 0 && s->entries[order[k - 1]].result.wall_seconds > e->result.wall_seconds) {
            order[k] = order[k - 1];
            k--;
        }
        order[k] = i;
    }
    bench_printf(t, "$%s%s << EOD\n", rl_method_name(m), suffix);
    for (size_t k = 0; k < n; k++) {
        const bench_entry *e = &s->entries[order[k]];
        char label[64];
        bench_setting_label(&e->setting, label, sizeof label);
        const char *knobs = strchr(label, ' ');
        bench_printf(t, "%.6g %.6g %.6g \"%s\"\n", e->result.wall_seconds, e->result.rmse, e->result.mottling,
                     knobs != NULL ? knobs + 1 : "");
    }
    bench_printf(t, "EOD\n");
}

/* Plots every method's runs, column `column` of gp_method_block()'s lines against time, into NAME.png, with
 * the reference's error as a dashed line when ref_line. @return 1, or 0 (said on stderr). */
static int plot_vs_time(const bench_sweep *s, const char *name, const char *ylabel, int column, int ref_line)
{
    bench_text t = {0};
    const bench_config *cfg = s->cfg;
    gp_open(&t, name, 1100, 750);
    bench_printf(&t, "set title ");
    gp_string(&t, cfg->scene);
    bench_printf(&t, " noenhanced\nset logscale xy\nset xlabel 'wall time (s)'\nset ylabel '%s'\n"
                     "set grid xtics ytics mxtics mytics lc rgb '#e0e0e0'\nset key outside right top\n", ylabel);
    for (size_t m = 0; m < cfg->nmethods; m++) {
        gp_method_block(&t, s, cfg->methods[m], 0, "");
        gp_method_block(&t, s, cfg->methods[m], 1, "_front");
    }
    if (ref_line && s->ref->error > 0)
        bench_printf(&t, "set arrow from graph 0, first %.6g to graph 1, first %.6g nohead dt 2 lc rgb '#808080'\n",
                     s->ref->error, s->ref->error);
    bench_printf(&t, "plot ");
    for (size_t m = 0; m < cfg->nmethods; m++) {
        const char *method = rl_method_name(cfg->methods[m]), *colour = METHOD_COLOURS[m];
        bench_printf(&t, "%s$%s using 1:%d with points pt 7 ps 1.4 lc rgb '%s' title '%s', \\\n", m ? ", " : "",
                     method, column, colour, method);
        bench_printf(&t, "  $%s_front using 1:%d with lines lw 2 lc rgb '%s' notitle, \\\n", method, column, colour);
        bench_printf(&t, "  $%s using 1:%d:4 with labels offset 0.6,0.7 font ',8' tc rgb '%s' noenhanced notitle",
                     method, column, colour);
    }
    if (ref_line && s->ref->error > 0) /* a line across the whole graph, and its entry in the key */
        bench_printf(&t, ", \\\n  NaN with lines dt 2 lc rgb '#808080' title 'reference error estimate'");
    bench_printf(&t, "\n");
    int ok = bench_plot(cfg->output, name, &t, cfg->quiet);
    bench_text_free(&t);
    return ok;
}

int bench_plot_error_vs_time(const bench_sweep *s)
{
    return plot_vs_time(s, "error_vs_time", "RMSE of irradiance luminance Y (W m^{-2})", 2, 1) &&
           plot_vs_time(s, "mottling_vs_time", "mottling: median |Y - mean of 2 neighbours| / Y", 3, 0);
}

/* ------------------------------------------------------------ error images */

/* qsort order of floats, ascending. */
static int float_order(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* @return the IMAGE_SCALE_PERCENTILE of the finite pixels of raw float file path (count pixels), or 0. */
static double image_percentile(const char *path, size_t count)
{
    float *px = malloc((count ? count : 1) * sizeof *px);
    FILE *f = px != NULL ? fopen(path, "rb") : NULL;
    size_t got = f != NULL ? fread(px, sizeof *px, count, f) : 0, n = 0;
    if (f != NULL)
        fclose(f);
    for (size_t k = 0; k < got; k++)
        if (isfinite(px[k]))
            px[n++] = px[k];
    double v = 0.0;
    if (n > 0) {
        qsort(px, n, sizeof *px, float_order);
        v = px[(size_t)(IMAGE_SCALE_PERCENTILE * (double)(n - 1))];
    }
    free(px);
    return v;
}

/* Writes and draws error_<method>.gp for method slot m, colour scale [0, top]. @return 1 or 0. */
static int plot_error_image(const bench_sweep *s, size_t m, double top)
{
    const bench_entry *e = &s->entries[s->best[m]];
    const char *method = rl_method_name(s->cfg->methods[m]);
    int w = (int)s->camera_width, h = (int)s->camera_height;
    /* Small cameras are drawn larger, so that the title and the scale stay legible. */
    double zoom = w < IMAGE_MIN_WIDTH ? (double)IMAGE_MIN_WIDTH / w : 1.0;
    char name[64], label[64];
    snprintf(name, sizeof name, "error_%s", method);
    bench_text t = {0};
    gp_open(&t, name, (int)(zoom * w) + 230, (int)(zoom * h) + 110);
    bench_printf(&t, "set title \"%s, RMSE %.4g W m^{-2}\\n|Y - Y_{ref}| / peak Y_{ref}, Y = luminance of irradiance\"\n",
                 bench_setting_label(&e->setting, label, sizeof label), e->result.rmse);
    bench_printf(&t, "unset key\nunset xtics\nunset ytics\nset border 0\nset size ratio -1\n"
                     "set xrange [-0.5:%d.5]\nset yrange [-0.5:%d.5]\nset cbrange [0:%.6g]\n",
                 w - 1, h - 1, top);
    bench_printf(&t, "set palette defined (0 '#000004', 0.25 '#51127c', 0.5 '#b73779', 0.75 '#fc8961', 1 '#fcfdbf')\n"
                     "set colorbox vertical\nset cblabel 'relative error (clipped at the top)'\n"
                     "set object 1 rectangle from graph 0,0 to graph 1,1 behind fillcolor rgb '#9a9a9a' "
                     "fillstyle solid noborder\n");
    bench_printf(&t, "plot '%s.bin' binary array=(%d,%d) format='%%float' flipy with image\n", name, w, h);
    int ok = bench_plot(s->cfg->output, name, &t, s->cfg->quiet);
    bench_text_free(&t);
    return ok;
}

int bench_plot_error_images(const bench_sweep *s)
{
    size_t count = (size_t)s->camera_width * s->camera_height;
    double top = 0.0;
    for (size_t m = 0; m < s->cfg->nmethods; m++) {
        char name[64], path[BENCH_PATH_MAX];
        snprintf(name, sizeof name, "error_%s.bin", rl_method_name(s->cfg->methods[m]));
        if (s->best[m] >= 0 && bench_path(path, s->cfg->output, name))
            top = fmax(top, image_percentile(path, count));
    }
    if (!(top > 0.0))
        top = 1e-6;
    int ok = 1;
    for (size_t m = 0; m < s->cfg->nmethods; m++)
        if (s->best[m] >= 0)
            ok = plot_error_image(s, m, top) && ok;
    return ok;
}

/* ------------------------------------------------------------ scaling */

int bench_plot_scaling(const char *dir, const bench_scaling_series *s, int quiet)
{
    bench_text t = {0};
    gp_open(&t, s->name, 1000, 700);
    bench_printf(&t, "set logscale xy\nset logscale y2\nset xlabel '%s'\nset ylabel 'wall time (s)'\n"
                     "set y2label 'peak memory (MiB)'\nset ytics nomirror\nset y2tics\n"
                     "set grid xtics ytics lc rgb '#e0e0e0'\nset key top left\n",
                 s->xlabel);
    bench_printf(&t, "$runs << EOD\n");
    for (size_t k = 0; k < s->n; k++)
        bench_printf(&t, "%.9g %.6g %.6g\n", s->x[k], s->time[k], s->mib[k]);
    bench_printf(&t, "EOD\n");
    if (s->fitted)
        bench_printf(&t, "ft(x) = exp(%.9g) * x**(%.9g)\nfm(x) = exp(%.9g) * x**(%.9g)\n", s->time_a, s->time_b,
                     s->mib_a, s->mib_b);
    bench_printf(&t, "plot $runs using 1:2 with points pt 7 ps 1.5 lc rgb '%s' title 'wall time', \\\n"
                     "  $runs using 1:3 axes x1y2 with points pt 5 ps 1.3 lc rgb '%s' title 'peak memory'",
                 METHOD_COLOURS[0], METHOD_COLOURS[1]);
    if (s->fitted)
        bench_printf(&t, ", \\\n  ft(x) with lines lw 2 lc rgb '%s' title sprintf('time fit: x^{%%.2f}', %.9g), "
                         "\\\n  fm(x) axes x1y2 with lines lw 2 dt 2 lc rgb '%s' title sprintf('memory fit: x^{%%.2f}', %.9g)",
                     METHOD_COLOURS[0], s->time_b, METHOD_COLOURS[1], s->mib_b);
    bench_printf(&t, "\n");
    int ok = bench_plot(dir, s->name, &t, quiet);
    bench_text_free(&t);
    return ok;
}
