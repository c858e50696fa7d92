/*
 * cmd_synth.c - `ilf synth`: writes a light field with one slab whose
 * radiance comes from an analytic model: constant, radial (the paper's
 * 'radial' emittance) or a set of ball-shaped spot lights.
 *
 * Each stored value is the model box-filtered over its solid angle: the
 * solid-angle-weighted mean over K*K jittered strata of the partition
 * triangle (see direction_mean()). Positions are computed in parallel into a
 * batch buffer, then written serially with lfio_slab_write_position(),
 * because lfio writes need exclusive access to the slab.
 *
 * Invariants: the result depends only on the options and --seed, never on
 * the thread count (each sample's jitter is a hash of seed, position,
 * direction and stratum); every stored value is finite and >= 0 because
 * every model returns a gain in [0, number of spots] and colours are >= 0.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "ilf/hash.h"
#include "ilf/pool.h"
#include "ilf/vec.h"
#include "commands.h"
#include "lfio/lightfield.h"
#include "lfio/partition.h"
#include "cli_limits.h"
#include "ilf/limits.h"

#define SYNTH_MAX_SPOTS ILF_SYNTH_MAX_SPOTS
#define SYNTH_MAX_GRID ILF_SYNTH_MAX_GRID
#define SYNTH_MAX_SUPERSAMPLE ILF_SYNTH_MAX_SUPERSAMPLE
#define SYNTH_BATCH_BYTES ((size_t)64 << 20)

typedef enum synth_kind { SYNTH_NONE, SYNTH_CONSTANT, SYNTH_RADIAL, SYNTH_SPOT } synth_kind;

/* A ball of light at centre emitting around axis (unit) inside a cone. */
typedef struct synth_spot {
    double centre[3];
    double axis[3];
    double cos_cone;
    double falloff;
    double radius; /* <= 0 until resolved to its default */
} synth_spot;

/* Everything the models need, fixed before the parallel part starts. */
typedef struct synth_model {
    synth_kind kind;
    double colour[3];
    double radial_centre[3]; /* radial: the point p light appears to come from */
    double radial_cos_cone;
    const synth_spot *spots;
    size_t spot_count;
} synth_model;

typedef struct synth_options {
    lfio_slab_desc desc;
    synth_kind kind;
    double radiance[3];
    int depth_given, cone_given;
    double depth, cone_deg;
    synth_spot spots[SYNTH_MAX_SPOTS];
    size_t spot_count;
    uint32_t supersample;
    uint32_t seed;
    uint32_t threads;
    const char *output;
    int quiet;
} synth_options;

enum synth_option_id {
    OPT_KIND, OPT_OUTPUT, OPT_GRID, OPT_N, OPT_ORIGIN, OPT_U, OPT_V, OPT_NAME, OPT_RADIANCE,
    OPT_UNITS, OPT_MASK_THRESHOLD, OPT_SUPERSAMPLE, OPT_SEED, OPT_DEPTH, OPT_CONE, OPT_SPOT, OPT_THREADS,
    OPT_QUIET
};

/* Indexed by enum synth_option_id. */
static const cli_option synth_options_table[] = {
    {"kind", 'k', "KIND", "model: constant, radial or spot (required)"},
    {"output", 'o', "OUT.h5", "file to write (required; replaced atomically)"},
    {"grid", 0, "NUxNV", "positions along u and v (default 32x32)"},
    {"n", 0, "N", "partition level: 4*N*N directions (default 16)"},
    {"origin", 0, "X,Y,Z", "slab corner in metres (default -0.5,-0.5,0)"},
    {"u", 0, "X,Y,Z", "first slab edge in metres (default 1,0,0)"},
    {"v", 0, "X,Y,Z", "second slab edge, orthogonal to u (default 0,1,0)"},
    {"name", 0, "NAME", "slab name (default synth)"},
    {"radiance", 0, "R,G,B", "colour c the model multiplies (default 1,1,1)"},
    {"units", 0, "UNITS", "radiance (W sr^-1 m^-2, default) or relative"},
    {"mask-threshold", 0, "T", "radiance above which the mask marks a direction (default 0)"},
    {"supersample", 0, "K", "K*K strata per solid angle (default 4)"},
    {"seed", 0, "S", "seed of the jittered strata (default 1)"},
    {"depth", 0, "D", "radial: distance of p behind the slab centre (default half the diagonal)"},
    {"cone", 0, "DEG", "radial: cone half-angle a in degrees (default 20)"},
    {"spot", 0, "P:A:DEG:F[:R]", "spot: centre, axis, cone, falloff, radius (repeatable)"},
    {"threads", 0, "T", "worker threads, 0 = every processor (default: the processors, at most 64)"},
    {"quiet", 'q', NULL, "no settings line, progress bar or summary"},
};

static const cli_usage synth_usage = {
    "synth",
    "--kind constant|radial|spot -o OUT.h5 [OPTIONS]",
    "Writes a synthetic light field with one slab. Each value is the model's mean\n"
    "over its solid angle (K*K jittered strata weighted by solid angle). Models, with\n"
    "x the position, w the unit direction, e3 the slab normal, c the --radiance:\n"
    "  constant  L = c\n"
    "  radial    L = c * max(0, (w.r - cos a) / (1 - cos a)), r = unit(x - p),\n"
    "            p = slab centre - depth * e3\n"
    "  spot      L = c * sum over spots of s * b, s = clamp((w.A - cos cone) /\n"
    "            (1 - cos cone), 0, 1)^falloff, b = 1 where the line through x along w\n"
    "            passes within the radius of the spot's centre P behind x, else 0.\n"
    "            --spot P:A:DEG:F[:R] gives P=px,py,pz, A=ax,ay,az, cone DEG, falloff F\n"
    "            and radius R (default 5% of the slab diagonal).",
    "ilf synth --kind constant --radiance 2,2,2 -o constant.h5\n"
    "ilf synth --kind radial --grid 64x64 --n 32 --cone 30 -o radial.h5\n"
    "ilf synth --kind spot --spot 0,0,-1:0,0,1:25:2:0.1 --spot 0.3,0,-0.5:0,0,1:40:1 -o spots.h5",
};

/* ------------------------------------------------------------- models */

static double radial_gain(const synth_model *m, const double x[3], const double w[3])
{
    double r[3] = {x[0] - m->radial_centre[0], x[1] - m->radial_centre[1], x[2] - m->radial_centre[2]};
    double len = a3_len(r);
    double cosine = a3_dot(w, r) / len;
    double g = (cosine - m->radial_cos_cone) / (1.0 - m->radial_cos_cone);
    return g > 0.0 ? g : 0.0;
}

/* The ball test: the line through x along w meets the ball, on the side behind x. */
static int sees_ball(const synth_spot *spot, const double x[3], const double w[3])
{
    double d[3] = {x[0] - spot->centre[0], x[1] - spot->centre[1], x[2] - spot->centre[2]};
    if (a3_dot(d, w) <= 0.0)
        return 0;
    double c[3];
    a3_cross(d, w, c);
    return a3_len(c) < spot->radius;
}

static double spot_gain(const synth_model *m, const double x[3], const double w[3])
{
    double sum = 0.0;
    for (size_t k = 0; k < m->spot_count; k++) {
        const synth_spot *spot = &m->spots[k];
        if (!sees_ball(spot, x, w))
            continue;
        double t = (a3_dot(w, spot->axis) - spot->cos_cone) / (1.0 - spot->cos_cone);
        /* t <= 0 is outside the cone: dark for every falloff, so falloff 0 gives a hard edge. */
        if (t > 0.0)
            sum += pow(t < 1.0 ? t : 1.0, spot->falloff);
    }
    return sum;
}

/* The model's value at x along unit world direction w, as a multiple of c. */
static double model_gain(const synth_model *m, const double x[3], const double w[3])
{
    switch (m->kind) {
    case SYNTH_RADIAL:
        return radial_gain(m, x, w);
    case SYNTH_SPOT:
        return spot_gain(m, x, w);
    default:
        return 1.0;
    }
}

/* ----------------------------------------------------------- sampling */

/* A uniform point (u1, u2) of the unit triangle u1, u2 >= 0, u1 + u2 <= 1, as barycentrics l. */
static void jitter_in_triangle(uint64_t key, double l[3])
{
    uint64_t h = ilf_splitmix64(key);
    double a = (double)(h >> 32) * 0x1p-32, b = (double)(h & 0xFFFFFFFFu) * 0x1p-32;
    if (a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
    }
    l[0] = 1.0 - a - b;
    l[1] = a;
    l[2] = b;
}

/* Per-sample context of one (position, direction). */
typedef struct direction_cell {
    lfio_part_strata strata; /* the partition triangle's corners (world frame, unit length), K */
    uint64_t key;            /* hash of seed, position and direction */
} direction_cell;

/*
 * The model averaged over one solid angle: the planar triangle through its
 * three corners is cut into K*K strata (lfio_part_strata_sample()), each
 * sampled once at a jittered point and weighted by its solid angle share,
 * so the mean is over solid angle.
 */
static double direction_mean(const synth_model *m, const double x[3], const direction_cell *cell)
{
    double sum = 0.0, weight = 0.0;
    uint32_t count = cell->strata.k * cell->strata.k;
    for (uint32_t s = 0; s < count; s++) {
        double l[3], w[3], ws;
        jitter_in_triangle(cell->key ^ (s * 0xD1B54A32D192ED03ull), l);
        lfio_part_strata_sample(&cell->strata, s, l, w, &ws, NULL);
        sum += ws * model_gain(m, x, w);
        weight += ws;
    }
    return sum / weight;
}

/* ---------------------------------------------------------- positions */

/* A batch of positions computed by the workers into out ([pos][dir][rgb]). */
typedef struct synth_batch {
    const synth_model *model;
    const lfio_slab *slab;
    uint32_t strata;
    uint32_t seed;
    uint64_t first;         /* first position index (j*nu + i) of the batch */
    uint64_t count;         /* positions in the batch */
    float *out;
    atomic_uint_fast64_t next; /* next position of the batch to claim */
    cli_progress *progress;
} synth_batch;

/* Fills rgb ([dir][rgb]) for position index pos. */
static void compute_position(const synth_batch *b, uint64_t pos, float *rgb)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(b->slab);
    uint64_t ndir = lfio_slab_dir_count(b->slab);
    double x[3];
    lfio_slab_position(b->slab, (uint32_t)(pos % d->nu), (uint32_t)(pos / d->nu), x);
    direction_cell cell;
    for (uint64_t dir = 0; dir < ndir; dir++) {
        double gain = 1.0;
        /* The constant model is exactly c: skip sampling, which would only add rounding. */
        if (b->model->kind != SYNTH_CONSTANT) {
            double local[3][3], world[3][3];
            lfio_part_vertices(d->n, dir, local);
            for (int k = 0; k < 3; k++)
                lfio_slab_to_world(b->slab, local[k], world[k]);
            lfio_part_strata_init(&cell.strata, (const double(*)[3])world, b->strata);
            cell.key = ilf_splitmix64(ilf_splitmix64(ilf_splitmix64(b->seed) ^ pos) ^ dir);
            gain = direction_mean(b->model, x, &cell);
        }
        for (int c = 0; c < 3; c++)
            rgb[dir * 3 + c] = (float)(b->model->colour[c] * gain);
    }
}

static void synth_worker(void *arg, unsigned index)
{
    (void)index;
    synth_batch *b = arg;
    uint64_t ndir = lfio_slab_dir_count(b->slab);
    for (;;) {
        uint64_t k = atomic_fetch_add(&b->next, 1);
        if (k >= b->count)
            break;
        compute_position(b, b->first + k, b->out + k * ndir * 3);
        cli_progress_add(b->progress, 1);
    }
}

/* Runs the workers over one batch; the calling thread works too. */
static void run_batch(synth_batch *b, unsigned threads)
{
    atomic_store(&b->next, 0);
    ilf_parallel(ilf_thread_count(threads), synth_worker, b);
}

static const char *kind_name(synth_kind kind);

/* Computes every position batch by batch and stores it in the slab. */
static int fill_slab(lfio_slab *slab, const synth_model *model, const synth_options *o)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(slab);
    uint64_t ndir = lfio_slab_dir_count(slab), npos = (uint64_t)d->nu * d->nv;
    size_t per_position = (size_t)ndir * 3 * sizeof(float);
    uint64_t batch_size = SYNTH_BATCH_BYTES / per_position;
    batch_size = batch_size < 1 ? 1 : batch_size > npos ? npos : batch_size;
    float *out = malloc((size_t)batch_size * per_position);
    if (out == NULL) {
        cli_error("synth", "out of memory for %llu positions", (unsigned long long)batch_size);
        return ILF_EXIT_FAILED;
    }
    /* every position costs the same (its directions times the strata): the bar counts positions */
    cli_settings("synth", "kind %s, %ux%u positions, n %u (%llu directions), %u strata per direction, %u thread%s",
                 kind_name(o->kind), (unsigned)d->nu, (unsigned)d->nv, (unsigned)d->n, (unsigned long long)ndir,
                 model->kind == SYNTH_CONSTANT ? 1u : o->supersample * o->supersample, ilf_thread_count(o->threads),
                 ilf_thread_count(o->threads) == 1 ? "" : "s");
    cli_progress progress;
    cli_progress_start(&progress, "synth", npos);
    synth_batch batch = {.model = model, .slab = slab, .strata = o->supersample, .seed = o->seed,
                         .out = out, .progress = &progress};
    int code = ILF_EXIT_OK;
    for (uint64_t first = 0; first < npos && code == ILF_EXIT_OK; first += batch_size) {
        batch.first = first;
        batch.count = npos - first < batch_size ? npos - first : batch_size;
        run_batch(&batch, o->threads);
        for (uint64_t k = 0; k < batch.count && code == ILF_EXIT_OK; k++) {
            uint64_t pos = first + k;
            lfio_status st = lfio_slab_write_position(slab, (uint32_t)(pos % d->nu), (uint32_t)(pos / d->nu),
                                                      out + k * ndir * 3);
            if (st != LFIO_OK)
                code = cli_lfio_failure("synth", st, CLI_OUTPUT, o->output);
        }
    }
    cli_progress_finish(&progress);
    free(out);
    return code;
}

/* ------------------------------------------------------------ options */

static void set_defaults(synth_options *o)
{
    memset(o, 0, sizeof *o);
    lfio_slab_desc_init(&o->desc);
    snprintf(o->desc.name, sizeof o->desc.name, "synth");
    o->desc.nu = o->desc.nv = 32;
    o->desc.n = 16;
    const double origin[3] = {-0.5, -0.5, 0}, u[3] = {1, 0, 0}, v[3] = {0, 1, 0};
    memcpy(o->desc.origin, origin, sizeof origin);
    memcpy(o->desc.u, u, sizeof u);
    memcpy(o->desc.v, v, sizeof v);
    o->desc.units = LFIO_UNITS_RADIANCE;
    o->desc.mask_threshold = 0.0f;
    o->radiance[0] = o->radiance[1] = o->radiance[2] = 1.0;
    o->cone_deg = 20.0;
    o->supersample = 4;
    o->seed = 1;
    o->threads = cli_default_threads();
}

/* Where a vector option's three numbers go, or NULL for other options. */
static double *vector_target(synth_options *o, int opt)
{
    switch (opt) {
    case OPT_ORIGIN: return o->desc.origin;
    case OPT_U: return o->desc.u;
    case OPT_V: return o->desc.v;
    case OPT_RADIANCE: return o->radiance;
    default: return NULL;
    }
}

static int cone_is_valid(double deg)
{
    return deg > 0.0 && deg <= 180.0;
}

/* Parses one spot's fields, already split at ':'. @return 1, or 0 with why. */
static int parse_spot_fields(char *fields[5], size_t count, synth_spot *spot, char *why, size_t why_size)
{
    double cone;
    if (count < 4 || count > 5) {
        snprintf(why, why_size, "expected P:A:DEG:FALLOFF[:RADIUS], got %zu fields", count);
        return 0;
    }
    if (!cli_parse_doubles(fields[0], spot->centre, 3, why, why_size) ||
        !cli_parse_doubles(fields[1], spot->axis, 3, why, why_size) ||
        !cli_parse_double(fields[2], &cone, why, why_size) ||
        !cli_parse_double(fields[3], &spot->falloff, why, why_size))
        return 0;
    spot->radius = 0.0; /* resolved to 5% of the slab diagonal once the slab exists */
    if (count == 5) {
        if (!cli_parse_double(fields[4], &spot->radius, why, why_size))
            return 0;
        if (!(spot->radius > 0.0)) {
            snprintf(why, why_size, "the radius must be > 0");
            return 0;
        }
    }
    double len = a3_len(spot->axis);
    if (!(len > 0.0) || !isfinite(len)) {
        snprintf(why, why_size, "the axis must be a nonzero direction");
        return 0;
    }
    if (!cone_is_valid(cone) || spot->falloff < 0.0) {
        snprintf(why, why_size, "the cone must be in (0, 180] degrees and the falloff >= 0");
        return 0;
    }
    for (int k = 0; k < 3; k++)
        spot->axis[k] /= len;
    spot->cos_cone = cos(cone * ILF_PI / 180.0);
    return 1;
}

/* Parses --spot P:A:DEG:FALLOFF[:RADIUS] into the next free spot. */
static int add_spot(const cli_parser *p, synth_options *o, const char *text)
{
    if (o->spot_count == SYNTH_MAX_SPOTS) {
        cli_bad_value(p, text, "too many spots (at most 64)");
        return 0;
    }
    char copy[512], why[160];
    if (strlen(text) >= sizeof copy) {
        cli_bad_value(p, text, "too long");
        return 0;
    }
    strcpy(copy, text);
    char *fields[5];
    size_t count = 0;
    for (char *f = copy; f != NULL && count <= 5; count++) {
        char *colon = strchr(f, ':');
        if (colon != NULL)
            *colon = '\0';
        if (count < 5)
            fields[count] = f;
        f = colon != NULL ? colon + 1 : NULL;
    }
    if (!parse_spot_fields(fields, count, &o->spots[o->spot_count], why, sizeof why)) {
        cli_bad_value(p, text, why);
        return 0;
    }
    o->spot_count++;
    return 1;
}

static int parse_kind(const cli_parser *p, const char *text, synth_kind *kind)
{
    static const char *const names[] = {"constant", "radial", "spot"};
    static const synth_kind kinds[] = {SYNTH_CONSTANT, SYNTH_RADIAL, SYNTH_SPOT};
    for (size_t k = 0; k < 3; k++) {
        if (strcmp(text, names[k]) == 0) {
            *kind = kinds[k];
            return 1;
        }
    }
    cli_bad_value(p, text, "expected constant, radial or spot");
    return 0;
}

static int parse_units(const cli_parser *p, const char *text, lfio_units *units)
{
    if (strcmp(text, "radiance") == 0)
        *units = LFIO_UNITS_RADIANCE;
    else if (strcmp(text, "relative") == 0)
        *units = LFIO_UNITS_RELATIVE;
    else
        return cli_bad_value(p, text, "expected radiance or relative"), 0;
    return 1;
}

static int parse_name(const cli_parser *p, const char *text, char name[LFIO_NAME_MAX + 1])
{
    if (strlen(text) > LFIO_NAME_MAX) {
        cli_bad_value(p, text, "longer than 63 bytes");
        return 0;
    }
    strcpy(name, text);
    return 1;
}

/* Applies one option (or a stray positional argument) to the synth_options
 * ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    synth_options *o = ctx;
    if (opt == CLI_POSITIONAL) {
        cli_error("synth", "unexpected argument '%s' (the output is given with -o)", value);
        return 0;
    }
    double *vector = vector_target(o, opt);
    if (vector != NULL)
        return cli_value_doubles(p, value, vector, 3);
    uint32_t grid[2];
    double x;
    switch (opt) {
    case OPT_KIND: return parse_kind(p, value, &o->kind);
    case OPT_OUTPUT: o->output = value; return 1;
    case OPT_GRID:
        if (!cli_value_u32_pair(p, value, 'x', 1, SYNTH_MAX_GRID, grid))
            return 0;
        o->desc.nu = grid[0];
        o->desc.nv = grid[1];
        return 1;
    case OPT_N: return cli_value_u32(p, value, 1, LFIO_SLAB_MAX_N, &o->desc.n);
    case OPT_NAME: return parse_name(p, value, o->desc.name);
    case OPT_UNITS: return parse_units(p, value, &o->desc.units);
    case OPT_MASK_THRESHOLD:
        if (!cli_value_double(p, value, &x))
            return 0;
        if (x < 0.0 || x > 3.4e38)
            return cli_bad_value(p, value, "must be >= 0 and fit a float"), 0;
        o->desc.mask_threshold = (float)x;
        return 1;
    case OPT_SUPERSAMPLE: return cli_value_u32(p, value, 1, SYNTH_MAX_SUPERSAMPLE, &o->supersample);
    case OPT_SEED: return cli_value_u32(p, value, 0, UINT32_MAX, &o->seed);
    case OPT_THREADS: return cli_value_threads(p, value, &o->threads);
    case OPT_QUIET: o->quiet = 1; cli_set_quiet(1); return 1;
    case OPT_DEPTH:
        o->depth_given = 1;
        if (!cli_value_double(p, value, &o->depth))
            return 0;
        return o->depth > 0.0 || (cli_bad_value(p, value, "must be > 0"), 0);
    case OPT_CONE:
        o->cone_given = 1;
        if (!cli_value_double(p, value, &o->cone_deg))
            return 0;
        return cone_is_valid(o->cone_deg) || (cli_bad_value(p, value, "must be in (0, 180] degrees"), 0);
    case OPT_SPOT: return add_spot(p, o, value);
    default: return 0;
    }
}

/* Reads argv into o. @return -1 to go on, or an exit code (help, bad usage). */
static int parse_arguments(synth_options *o, int argc, char **argv)
{
    return cli_parse(&synth_usage, synth_options_table, sizeof synth_options_table / sizeof synth_options_table[0],
                     argc, argv, NULL, apply_option, o);
}

/* Checks what single options cannot: required options and combinations. */
static int check_combination(const synth_options *o)
{
    const char *problem = NULL;
    if (o->kind == SYNTH_NONE)
        problem = "--kind is required (constant, radial or spot)";
    else if (o->output == NULL)
        problem = "-o OUT.h5 is required";
    else if (o->kind == SYNTH_SPOT && o->spot_count == 0)
        problem = "--kind spot needs at least one --spot";
    else if (o->kind != SYNTH_SPOT && o->spot_count > 0)
        problem = "--spot applies to --kind spot only";
    else if (o->kind != SYNTH_RADIAL && (o->depth_given || o->cone_given))
        problem = "--depth and --cone apply to --kind radial only";
    else if (o->radiance[0] < 0.0 || o->radiance[1] < 0.0 || o->radiance[2] < 0.0 ||
             o->radiance[0] > 1e30 || o->radiance[1] > 1e30 || o->radiance[2] > 1e30)
        problem = "--radiance values must be from 0 to 1e30";
    if (problem != NULL) {
        cli_error("synth", "%s", problem);
        return 0;
    }
    return 1;
}

/* Checks the radiance array stays within lfio's limit before asking for it. */
static int check_size(const lfio_slab_desc *d)
{
    uint64_t bytes = lfio_slab_desc_bytes(d);
    if (bytes > LFIO_SLAB_MAX_BYTES) {
        char size[32], limit[32];
        cli_error("synth", "%ux%u positions with n=%u need %s of radiance, more than the limit of %s",
                  (unsigned)d->nu, (unsigned)d->nv, (unsigned)d->n,
                  cli_format_bytes((long long)bytes, size, sizeof size),
                  cli_format_bytes((long long)LFIO_SLAB_MAX_BYTES, limit, sizeof limit));
        return 0;
    }
    return 1;
}

/* Checks that the evaluations o asks for (each radiance value, supersample^2 times each spot) are within
 * ILF_SYNTH_MAX_EVALUATIONS, before any work. @return 1, or 0 after reporting. */
static int check_work(const synth_options *o)
{
    const lfio_slab_desc *d = &o->desc;
    /* each factor is bounded by its option's limit and lfio's slab size, so the product fits in a double */
    double values = (double)d->nu * d->nv * (double)lfio_part_hemi_count(d->n);
    double work = values * o->supersample * o->supersample * (o->spot_count > 0 ? (double)o->spot_count : 1.0);
    if (work > (double)ILF_SYNTH_MAX_EVALUATIONS) {
        cli_error("synth", "%ux%u positions, n=%u, supersample %u and %zu spot%s need %.3g evaluations, more than "
                  "the limit of %.3g (tools/cli_limits.h)", (unsigned)d->nu, (unsigned)d->nv, (unsigned)d->n,
                  (unsigned)o->supersample, o->spot_count, o->spot_count == 1 ? "" : "s", work,
                  (double)ILF_SYNTH_MAX_EVALUATIONS);
        return 0;
    }
    return 1;
}

/* Fixes the model's geometry once the slab (and so its frame) exists. */
static void build_model(synth_options *o, const lfio_slab *slab, synth_model *m)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(slab);
    double diagonal = sqrt(a3_dot(d->u, d->u) + a3_dot(d->v, d->v)); /* u and v are orthogonal */
    double e3_local[3] = {0, 0, 1}, e3[3];
    lfio_slab_to_world(slab, e3_local, e3);
    double depth = o->depth_given ? o->depth : 0.5 * diagonal;
    m->kind = o->kind;
    memcpy(m->colour, o->radiance, sizeof m->colour);
    for (int k = 0; k < 3; k++)
        m->radial_centre[k] = d->origin[k] + 0.5 * d->u[k] + 0.5 * d->v[k] - depth * e3[k];
    m->radial_cos_cone = cos(o->cone_deg * ILF_PI / 180.0);
    for (size_t s = 0; s < o->spot_count; s++)
        if (o->spots[s].radius <= 0.0)
            o->spots[s].radius = 0.05 * diagonal;
    m->spots = o->spots;
    m->spot_count = o->spot_count;
}

static const char *kind_name(synth_kind kind)
{
    return kind == SYNTH_CONSTANT ? "constant" : kind == SYNTH_RADIAL ? "radial" : "spot";
}

/* Wraps the filled slab in a light field and writes it; takes ownership of slab. */
static int write_file(lfio_slab *slab, const synth_options *o)
{
    lfio_lightfield *lf = NULL;
    lfio_status st = lfio_lightfield_new(&lf);
    if (st != LFIO_OK) {
        lfio_slab_destroy(slab);
        return cli_lfio_failure("synth", st, CLI_OUTPUT, o->output);
    }
    char creator[128];
    snprintf(creator, sizeof creator, "ilf synth --kind %s (ilfkit %s)", kind_name(o->kind), ILFKIT_VERSION);
    int code = ILF_EXIT_OK;
    /* take_slab owns the slab from here on, even when it fails; it rejects only a bad --name. */
    if ((st = lfio_lightfield_take_slab(lf, slab)) != LFIO_OK)
        code = cli_lfio_failure("synth", st, CLI_INPUT, NULL);
    else if ((st = lfio_lightfield_set_creator(lf, creator)) != LFIO_OK ||
             (st = lfio_lightfield_write(lf, o->output)) != LFIO_OK)
        code = cli_lfio_failure("synth", st, CLI_OUTPUT, o->output);
    lfio_lightfield_destroy(lf);
    return code;
}

static void print_summary(const synth_options *o)
{
    if (o->quiet)
        return;
    const lfio_slab_desc *d = &o->desc;
    char size[32];
    printf("wrote %s: %s slab '%s', %ux%u positions, n=%u (%llu directions), %s\n", o->output,
           kind_name(o->kind), d->name, (unsigned)d->nu, (unsigned)d->nv, (unsigned)d->n,
           (unsigned long long)lfio_part_hemi_count(d->n),
           cli_format_bytes(cli_file_size(o->output), size, sizeof size));
}

int ilf_cmd_synth(int argc, char **argv)
{
    synth_options o;
    set_defaults(&o);
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    if (!check_combination(&o) || !check_size(&o.desc) || !check_work(&o))
        return ILF_EXIT_USAGE;
    if ((code = cli_output_check("synth", o.output)) != ILF_EXIT_OK)
        return code;
    cli_output_watch(o.output);
    lfio_slab *slab = NULL;
    lfio_status st = lfio_slab_new(&o.desc, &slab);
    if (st != LFIO_OK) /* the description came from the options: bad input unless memory ran out */
        return cli_lfio_failure("synth", st, CLI_INPUT, NULL);
    synth_model model;
    build_model(&o, slab, &model);
    code = fill_slab(slab, &model, &o);
    if (code != ILF_EXIT_OK) {
        lfio_slab_destroy(slab);
        return code;
    }
    code = write_file(slab, &o);
    if (code == ILF_EXIT_OK)
        print_summary(&o);
    return code;
}
