/*
 * engine.c - passes, threads and results of the relighting engine.
 *
 * A run builds the radiance maps and the ray tracer, then runs pass 0 from
 * the scene's emitters (emissive polygons and light field slabs) and
 * `bounces` further passes, each from the receivers that the previous pass
 * lit, re-emitting albedo * E / pi. Within a pass, the work is the list of
 * tiles (rows of one map's grid); worker threads take tiles from an atomic
 * counter, and each tile's cells are written only by the thread that owns
 * the tile, in an order fixed by the tile alone. So the output does not
 * depend on the number of threads or on scheduling. In a job of several
 * processes (rl_cluster), the tiles are dealt to the ranks by expected
 * cost (deal_tiles), and after each
 * pass the ranks exchange their tiles' values: since a tile's values do not
 * depend on who computed them, every rank then holds what one process would.
 */
#include <float.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "relight/engine.h"
#include "sampling.h"
#include "transfer.h"

#define PI 3.14159265358979323846
#define TILE_CELLS 2048u

struct rl_solution {
    const rl_scene *scene;
    rl_map *maps;
    size_t nmaps;
    int32_t *polygon_map; /* scene polygon -> map index, or -1 */
    rl_tracer *tracer;
    rl_pass_stats *passes;
    uint32_t npasses;
    int flat; /* shade each cell's own value instead of interpolating between cells */
};

/* ------------------------------------------------------------ parallel work */

typedef struct work_item {
    uint32_t map;
    uint32_t row0, row1;
} work_item;

typedef struct pass_job {
    rl_transfer_ctx ctx;
    rl_map *maps;
    const work_item *items;
    size_t nitems;
    atomic_size_t next, done;
    atomic_int failed;
    rl_counters *counters; /* one per thread */
    double *seconds;       /* [nitems]: each tile's CPU time, or NULL */
} pass_job;

typedef struct worker_arg {
    pass_job *job;
    unsigned index;
} worker_arg;

/* @return the time of clock (monotonic wall, process or thread CPU), in seconds. */
static double now(clockid_t clock)
{
    struct timespec ts;
    clock_gettime(clock, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Takes tiles until none are left. */
static void *worker(void *p)
{
    worker_arg *a = p;
    pass_job *job = a->job;
    rl_scratch scratch = {0};
    tracer_thread_init();
    for (;;) {
        size_t k = atomic_fetch_add(&job->next, 1);
        if (k >= job->nitems || atomic_load(&job->failed))
            break;
        const work_item *w = &job->items[k];
        double t0 = job->seconds ? now(CLOCK_THREAD_CPUTIME_ID) : 0.0;
        if (transfer_tile(&job->ctx, w->map, &job->maps[w->map], w->row0, w->row1, &scratch,
                          &job->counters[a->index]) != 0)
            atomic_store(&job->failed, 1);
        if (job->seconds)
            job->seconds[k] = now(CLOCK_THREAD_CPUTIME_ID) - t0;
        atomic_fetch_add(&job->done, 1);
    }
    scratch_free(&scratch);
    return NULL;
}

/* @return the number of worker threads to use for setting t (0 = every core). */
static unsigned thread_count(uint32_t t)
{
    if (t > 0)
        return t;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (unsigned)n : 1;
}


/* Runs job on n threads, reporting progress from the calling thread.
 * base and span place this pass within the run's [0, 1] progress. @return 0 or -1. */
static int run_job(pass_job *job, unsigned n, rl_progress_fn progress, void *user, double base, double span)
{
    pthread_t *threads = malloc(n * sizeof *threads);
    worker_arg *args = malloc(n * sizeof *args);
    job->counters = calloc(n, sizeof *job->counters);
    if (!threads || !args || !job->counters) {
        free(threads);
        free(args);
        return -1;
    }
    atomic_init(&job->next, 0);
    atomic_init(&job->done, 0);
    atomic_init(&job->failed, 0);
    unsigned started = 0;
    for (; started < n; started++) {
        args[started] = (worker_arg){job, started};
        if (pthread_create(&threads[started], NULL, worker, &args[started]) != 0)
            break;
    }
    if (started == 0) {
        args[0] = (worker_arg){job, 0};
        worker(&args[0]); /* no threads to be had: do the work here */
    }
    while (progress && started > 0 && atomic_load(&job->done) < job->nitems && !atomic_load(&job->failed)) {
        progress(user, base + span * (double)atomic_load(&job->done) / (double)(job->nitems ? job->nitems : 1));
        struct timespec ts = {0, 20 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    for (unsigned k = 0; k < started; k++)
        pthread_join(threads[k], NULL);
    free(threads);
    free(args);
    return atomic_load(&job->failed) ? -1 : 0;
}

/* Sums the per-thread counters into stats. */
static void sum_counters(const rl_counters *c, unsigned n, rl_pass_stats *st)
{
    for (unsigned k = 0; k < n; k++) {
        st->samples += c[k].samples;
        st->rays_cast += c[k].rays_cast;
        st->rays_kept += c[k].rays_kept;
        st->solid_angles_considered += c[k].leaves_considered;
        st->solid_angles_culled += c[k].leaves_culled;
        st->pairs += c[k].pairs;
        st->pairs_descended += c[k].pairs_descended;
        st->refinements += c[k].refinements;
        st->estimated_rmse += c[k].variance; /* a sum of variances until run_pass divides */
        st->budget_reached |= c[k].budget_reached;
    }
}

/* Splits every map into tiles of about TILE_CELLS grid squares. @return the items (count in *n) or NULL. */
static work_item *make_tiles(const rl_map *maps, size_t nmaps, size_t *n)
{
    size_t count = 0, k = 0;
    for (size_t m = 0; m < nmaps; m++) {
        uint32_t rows = maps[m].nu >= TILE_CELLS ? 1 : TILE_CELLS / maps[m].nu;
        count += (maps[m].nv + rows - 1) / rows;
    }
    work_item *items = malloc((count ? count : 1) * sizeof *items);
    if (!items)
        return NULL;
    for (size_t m = 0; m < nmaps; m++) {
        uint32_t rows = maps[m].nu >= TILE_CELLS ? 1 : TILE_CELLS / maps[m].nu;
        for (uint32_t r = 0; r < maps[m].nv; r += rows)
            items[k++] = (work_item){(uint32_t)m, r, r + rows < maps[m].nv ? r + rows : maps[m].nv};
    }
    *n = count;
    return items;
}

/* ------------------------------------------------------------ several ranks */

/* @return the first cell of map m in grid row j or after: cells are numbered row by row. */
static uint32_t first_cell_of_row(const rl_map *m, uint32_t j)
{
    uint32_t lo = 0, hi = m->ncells;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (m->cells[mid].j < j)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* @return the number of cells of tile w. */
static uint32_t tile_cells(const rl_map *maps, const work_item *w)
{
    const rl_map *m = &maps[w->map];
    return first_cell_of_row(m, w->row1) - first_cell_of_row(m, w->row0);
}

/* The expected cost of a tile with no measurement: its cells, plus what setting up any tile costs
 * (its emitter pairs, its clipping), in cells. Fitted to the classroom's tiles (cost = a cells + b):
 * b is about 0 cells in the direct pass, 9 in a bounce pass (3,035 emitters, every tile paired with each). */
#define TILE_SETUP_CELLS 8.0

/* A tile in the deal: its expected cost and a fixed hash that orders equal costs. */
typedef struct dealt {
    double cost;
    uint64_t key;
    size_t tile;
} dealt;

/* qsort order of dealt: dearest first, then by key, then tile. */
static int dearest_first(const void *a, const void *b)
{
    const dealt *x = a, *y = b;
    if (x->cost != y->cost)
        return x->cost > y->cost ? -1 : 1;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->tile > y->tile) - (x->tile < y->tile);
}


/* Deals the n tiles of a pass to the ranks by expected cost, dearest first, each to the rank with
 * the least so far (longest processing time first): the measured CPU seconds of the same tiles in
 * the previous pass when given (bounce passes repeat their tiles), else their cells. Equal costs are
 * ordered by a fixed hash of the tile's index, so that the many tiles of the same size are mixed:
 * taken in list order, a rank would get every box's top, lit, face. Every rank computes the same
 * deal. @return owner[n] (malloc'd), or NULL when out of memory. */
static uint32_t *deal_tiles(const rl_cluster *cl, const rl_map *maps, const work_item *items, size_t n,
                            const double *measured)
{
    uint32_t *owner = malloc((n ? n : 1) * sizeof *owner);
    dealt *order = malloc((n ? n : 1) * sizeof *order);
    double *load = calloc(cl->ranks, sizeof *load);
    if (owner && order && load) {
        for (size_t k = 0; k < n; k++)
            order[k] = (dealt){measured ? measured[k] : tile_cells(maps, &items[k]) + TILE_SETUP_CELLS,
                               hash_mix(0x9e3779b97f4a7c15u, k), k};
        qsort(order, n, sizeof *order, dearest_first);
        for (size_t k = 0; k < n; k++) {
            uint32_t least = 0;
            for (uint32_t r = 1; r < cl->ranks; r++)
                least = load[r] < load[least] ? r : least;
            owner[order[k].tile] = least;
            load[least] += order[k].cost;
        }
    } else {
        free(owner);
        owner = NULL;
    }
    free(load);
    free(order);
    return owner;
}

/* Copies the pass irradiance of every tile of owners other than `rank` (skip_own) or of `rank` alone
 * (!skip_own) between the maps and buf, packed by owner then tile: to buf when pack, else from it.
 * cursor (one per rank) starts at each owner's offset. */
static void copy_tiles(const rl_cluster *cl, const uint32_t *owners, rl_map *maps, const work_item *items,
                       size_t nitems, double *buf, uint64_t *cursor, int pack)
{
    for (size_t k = 0; k < nitems; k++) {
        uint32_t owner = owners[k];
        rl_map *m = &maps[items[k].map];
        uint32_t c0 = first_cell_of_row(m, items[k].row0), c1 = first_cell_of_row(m, items[k].row1);
        size_t values = 3 * (size_t)(c1 - c0);
        /* a rank packs its own tiles and unpacks everyone else's */
        if ((owner == cl->rank) == pack && values > 0) {
            double *at = buf + cursor[owner], *cells = &m->e_pass[c0][0];
            memcpy(pack ? at : cells, pack ? cells : at, values * sizeof *buf);
        }
        cursor[owner] += values;
    }
}

/* Makes every rank's pass irradiance whole: each rank computed only its own tiles. @return 0 or -1 (failed,
 * with *why naming what). */
static int exchange_tiles(const rl_cluster *cl, const uint32_t *owners, rl_map *maps, const work_item *items,
                          size_t nitems, const char **why)
{
    uint64_t *counts = calloc(cl->ranks, sizeof *counts), *offsets = calloc(cl->ranks, sizeof *offsets),
             *cursor = calloc(cl->ranks, sizeof *cursor);
    double *buf = NULL;
    int rc = -1;
    *why = "out of memory for the exchange";
    if (counts && offsets && cursor) {
        for (size_t k = 0; k < nitems; k++)
            counts[owners[k]] += 3 * (uint64_t)tile_cells(maps, &items[k]);
        uint64_t total = 0;
        for (uint32_t r = 0; r < cl->ranks; r++)
            offsets[r] = total, total += counts[r];
        buf = malloc((total ? total : 1) * sizeof *buf);
    }
    if (buf) {
        memcpy(cursor, offsets, cl->ranks * sizeof *cursor);
        copy_tiles(cl, owners, maps, items, nitems, buf, cursor, 1);
        *why = "the exchange between ranks failed";
        if (cl->allgather(cl->user, buf, counts, offsets) == 0) {
            memcpy(cursor, offsets, cl->ranks * sizeof *cursor);
            copy_tiles(cl, owners, maps, items, nitems, buf, cursor, 0);
            rc = 0;
        }
    }
    free(buf);
    free(cursor);
    free(offsets);
    free(counts);
    return rc;
}

/* This rank's share of a pass's tiles. */
typedef struct share {
    uint32_t *owner;  /* [n]: each tile's rank */
    work_item *mine;  /* this rank's tiles, in list order */
    size_t *index;    /* [nmine]: their places in the list */
    double *seconds;  /* [nmine]: the CPU time each took */
    size_t nmine;
} share;

/* Frees a share's arrays. */
static void share_free(share *sh)
{
    free(sh->owner);
    free(sh->mine);
    free(sh->index);
    free(sh->seconds);
}

/* Deals the n tiles of items (by measured costs when given) and keeps this rank's. @return 0 or -1 (out of
 * memory). */
static int share_deal(const rl_cluster *cl, const rl_map *maps, const work_item *items, size_t n,
                      const double *measured, share *sh)
{
    memset(sh, 0, sizeof *sh);
    sh->owner = deal_tiles(cl, maps, items, n, measured);
    sh->mine = malloc((n ? n : 1) * sizeof *sh->mine);
    sh->index = malloc((n ? n : 1) * sizeof *sh->index);
    sh->seconds = calloc(n ? n : 1, sizeof *sh->seconds);
    if (!sh->owner || !sh->mine || !sh->index || !sh->seconds) {
        share_free(sh);
        return -1;
    }
    for (size_t k = 0; k < n; k++)
        if (sh->owner[k] == cl->rank) {
            sh->index[sh->nmine] = k;
            sh->mine[sh->nmine++] = items[k];
        }
    return 0;
}

/* Gathers every tile's measured CPU time onto every rank, into *measured (replaced; n values), for the
 * deal of a next pass over the same tiles. @return 0, or -1 when the exchange fails. */
static int share_measure(const rl_cluster *cl, const share *sh, size_t n, double **measured)
{
    free(*measured);
    *measured = calloc(n ? n : 1, sizeof **measured);
    if (!*measured)
        return 0; /* no measurement: the next deal goes by cells */
    for (size_t k = 0; k < sh->nmine; k++)
        (*measured)[sh->index[k]] = sh->seconds[k];
    if (cl->sum(cl->user, *measured, n) == 0)
        return 0;
    free(*measured);
    *measured = NULL;
    return -1;
}

/* Sums the pass statistics over ranks (wall time stays this rank's). @return 0 or -1. */
static int sum_stats(const rl_cluster *cl, rl_pass_stats *st)
{
    double v[] = {(double)st->samples, (double)st->rays_cast, (double)st->rays_kept,
                  (double)st->solid_angles_considered, (double)st->solid_angles_culled, (double)st->pairs,
                  (double)st->pairs_descended, (double)st->refinements, st->estimated_rmse,
                  (double)st->budget_reached, st->cpu_seconds};
    if (cl->sum(cl->user, v, sizeof v / sizeof v[0]) != 0)
        return -1;
    uint64_t *counts[] = {&st->samples, &st->rays_cast, &st->rays_kept, &st->solid_angles_considered,
                          &st->solid_angles_culled, &st->pairs, &st->pairs_descended, &st->refinements};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++)
        *counts[k] = (uint64_t)v[k];
    st->estimated_rmse = v[8];
    st->budget_reached = v[9] > 0;
    st->cpu_seconds = v[10];
    return 0;
}

/* ---------------------------------------------------------------- emitters */

/* @return 1 if any channel of v is > 0. */
static int positive3(const float v[3])
{
    return v[0] > 0 || v[1] > 0 || v[2] > 0;
}

/* Builds the emitters of the scene itself (pass 0). @return the array (count in *n) or NULL. */
static rl_emitter *primary_emitters(const rl_scene *scene, size_t extra, size_t *n)
{
    size_t count = scene->nlightfields;
    for (size_t k = 0; k < scene->npolygons; k++)
        count += positive3(scene->materials[scene->polygons[k].material].emission);
    rl_emitter *e = malloc((count + extra + 1) * sizeof *e);
    if (!e)
        return NULL;
    size_t m = 0;
    for (size_t k = 0; k < scene->npolygons; k++)
        if (positive3(scene->materials[scene->polygons[k].material].emission))
            emitter_from_polygon(scene, (uint32_t)k, NULL, &e[m++]);
    for (size_t k = 0; k < scene->nlightfields; k++)
        emitter_from_lightfield(&scene->lightfields[k], &e[m++]);
    *n = m;
    return e;
}

/* Appends to e (room assumed) one emitter per map that re-emits light. @return the new count. */
static size_t append_bounce_emitters(const rl_scene *scene, const rl_map *maps, size_t nmaps, rl_emitter *e,
                                     size_t n)
{
    for (size_t m = 0; m < nmaps; m++) {
        int lit = 0;
        for (uint32_t c = 0; c < maps[m].ncells && !lit; c++)
            lit = maps[m].e_prev[c][0] > 0 || maps[m].e_prev[c][1] > 0 || maps[m].e_prev[c][2] > 0;
        if (lit)
            emitter_from_polygon(scene, (uint32_t)maps[m].polygon, &maps[m], &e[n++]);
    }
    return n;
}

/* @return the sampling of pass p. Bounce passes use bounce_partition_n and
 * never descend: their emitters are every lit surface, which at a coarse
 * level nearly all subtend less than a solid angle, and descending for each
 * would cost more than the smooth indirect light is worth. */
static rl_sampling pass_sampling(const rl_sampling *s, uint32_t p)
{
    rl_sampling out = *s;
    if (p > 0) {
        out.partition_n = s->bounce_partition_n ? s->bounce_partition_n
                          : s->partition_n >= 4 ? s->partition_n / 4 : 1;
        out.descend = 0;
    }
    return out;
}

/* Fills the shared context of a pass; sampling must outlive it. */
static void make_ctx(const rl_scene *scene, const rl_tracer *tracer, uint32_t pass, const rl_sampling *sampling,
                     const rl_emitter *e, size_t n, rl_transfer_ctx *ctx)
{
    ctx->scene = scene;
    ctx->tracer = tracer;
    ctx->occluders = tracer_occluders(tracer);
    ctx->sampling = sampling;
    ctx->pass = pass;
    ctx->emitters = e;
    ctx->nemitters = n;
    /* about eight single-precision ulps at the scene's extent */
    ctx->centre = tracer_centre(tracer);
    ctx->eps = 1e-6 * tracer_extent(tracer);
    ctx->margin = 1e-9 * tracer_extent(tracer);
    ctx->deadline = sampling->time_budget > 0 ? now(CLOCK_MONOTONIC) + sampling->time_budget : 0.0;
}

/* Runs one pass over maps with emitters e; gather_level_pass chooses the
 * partition level (0: partition_n, else the bounce level). With several ranks,
 * *measured holds the previous pass's per-tile CPU times (NULL: none) when
 * this pass repeats its tiles, and receives this pass's. @return RL_OK or an error. */
static rl_status run_pass(const rl_scene *scene, const rl_tracer *tracer, const rl_cluster *cl, uint32_t pass,
                          uint32_t gather_level_pass, rl_map *maps, size_t nmaps, const rl_emitter *e, size_t ne,
                          rl_progress_fn progress, void *user, double base, double span, double **measured,
                          rl_pass_stats *st)
{
    double w0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
    memset(st, 0, sizeof *st);
    st->emitters = (uint32_t)ne;
    for (size_t m = 0; m < nmaps; m++)
        memset(maps[m].e_pass, 0, (maps[m].ncells ? maps[m].ncells : 1) * sizeof *maps[m].e_pass);
    pass_job job;
    memset(&job, 0, sizeof job);
    rl_sampling sampling = pass_sampling(&scene->sampling, gather_level_pass);
    make_ctx(scene, tracer, pass, &sampling, e, ne, &job.ctx);
    job.maps = maps;
    size_t nall = 0;
    work_item *all = make_tiles(maps, nmaps, &nall);
    share sh = {0};
    if (!all || (cl && share_deal(cl, maps, all, nall, *measured, &sh) != 0)) {
        free(all);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the work list");
    }
    job.items = cl ? sh.mine : all;
    job.nitems = cl ? sh.nmine : nall;
    job.seconds = cl ? sh.seconds : NULL;
    unsigned threads = thread_count(scene->sampling.threads);
    int rc = ne > 0 ? run_job(&job, threads, progress, user, base, span) : 0;
    if (job.counters)
        sum_counters(job.counters, threads, st);
    free(job.counters);
    st->cpu_seconds = now(CLOCK_PROCESS_CPUTIME_ID) - c0;
    const char *why = "out of memory";
    /* A failed rank leaves now: the others wait in the exchange until the job is ended (engine.h). */
    if (rc == 0 && cl && ne > 0 && exchange_tiles(cl, sh.owner, maps, all, nall, &why) != 0)
        rc = -2;
    if (rc == 0 && cl && ne > 0 && share_measure(cl, &sh, nall, measured) != 0)
        rc = -2, why = "the exchange of tile costs between ranks failed";
    if (rc == 0 && cl && sum_stats(cl, st) != 0)
        rc = -2, why = "the exchange of statistics between ranks failed";
    free(all);
    share_free(&sh);
    if (rc != 0)
        return rl__fail(rc == -2 ? RL_ERR_IO : RL_ERR_NOMEM, "pass %u: %s", pass, why);
    size_t cells = 0;
    for (size_t m = 0; m < nmaps; m++)
        cells += maps[m].ncells;
    st->estimated_rmse = cells ? sqrt(st->estimated_rmse / (double)cells) : 0.0;
    st->wall_seconds = now(CLOCK_MONOTONIC) - w0;
    return RL_OK;
}

/* Adds each map's pass irradiance to its total and keeps it for the next bounce. */
static void close_pass(rl_map *maps, size_t nmaps)
{
    for (size_t m = 0; m < nmaps; m++)
        for (uint32_t c = 0; c < maps[m].ncells; c++)
            for (int k = 0; k < 3; k++) {
                maps[m].e_total[c][k] += maps[m].e_pass[c][k];
                if (maps[m].e_prev != NULL)
                    maps[m].e_prev[c][k] = maps[m].e_pass[c][k];
            }
}

/* Solves the maps with `passes` passes (may be 0). */
static rl_status solve(const rl_scene *scene, const rl_cluster *cl, uint32_t passes, rl_progress_fn progress,
                       void *user, rl_solution **out)
{
    *out = NULL;
    rl_solution *s = calloc(1, sizeof *s);
    if (!s)
        return rl__fail(RL_ERR_NOMEM, "out of memory");
    s->scene = scene;
    rl_status st = maps_build(scene, &s->maps, &s->nmaps);
    if (st == RL_OK)
        st = tracer_new(scene, &s->tracer);
    s->polygon_map = malloc((scene->npolygons + 1) * sizeof *s->polygon_map);
    s->passes = calloc(passes + 1, sizeof *s->passes);
    if (st == RL_OK && (!s->polygon_map || !s->passes))
        st = rl__fail(RL_ERR_NOMEM, "out of memory");
    if (st != RL_OK) {
        rl_solution_destroy(s);
        return st;
    }
    for (size_t k = 0; k < scene->npolygons; k++)
        s->polygon_map[k] = -1;
    for (size_t m = 0; m < s->nmaps; m++)
        s->polygon_map[s->maps[m].polygon] = (int32_t)m;
    size_t ne = 0;
    rl_emitter *e = primary_emitters(scene, s->nmaps, &ne);
    if (!e) {
        rl_solution_destroy(s);
        return rl__fail(RL_ERR_NOMEM, "out of memory for emitters");
    }
    /* bounce passes gather on coarser cells when asked: indirect light is smooth */
    rl_map *coarse = NULL;
    size_t ncoarse = 0;
    uint32_t factor = scene->sampling.bounce_cell_factor ? scene->sampling.bounce_cell_factor : 2;
    if (passes > 1 && factor > 1)
        st = maps_build_sized(scene, scene->cell_size * factor, &coarse, &ncoarse);
    /* per-tile CPU times of the last pass: bounce passes after the first repeat its tiles and emitters */
    double *measured = NULL;
    for (uint32_t p = 0; p < passes && st == RL_OK; p++) {
        int gather_coarse = p > 0 && coarse;
        if (p > 0)
            ne = append_bounce_emitters(scene, s->maps, s->nmaps, e, 0);
        if (p < 2) {
            free(measured);
            measured = NULL;
        }
        st = run_pass(scene, s->tracer, cl, p, p, gather_coarse ? coarse : s->maps, gather_coarse ? ncoarse : s->nmaps, e,
                      ne, progress, user, (double)p / passes, 1.0 / passes, &measured, &s->passes[p]);
        for (size_t m = 0; gather_coarse && m < s->nmaps; m++)
            map_interpolate(&coarse[m], &s->maps[m]);
        close_pass(s->maps, s->nmaps);
        s->npasses = p + 1;
    }
    maps_free(coarse, ncoarse);
    free(measured);
    free(e);
    if (st != RL_OK) {
        rl_solution_destroy(s);
        return st;
    }
    if (progress)
        progress(user, 1.0);
    *out = s;
    return RL_OK;
}

/* @return the cluster to run with: NULL for one process. Checks it (RL_ERR_ARG in *st). */
static const rl_cluster *check_cluster(const rl_cluster *cl, rl_status *st)
{
    *st = RL_OK;
    if (cl && (cl->ranks == 0 || cl->rank >= cl->ranks || !cl->allgather || !cl->sum))
        *st = rl__fail(RL_ERR_ARG, "cluster: rank %u of %u, or a NULL callback", cl->rank, cl->ranks);
    return cl && cl->ranks > 1 ? cl : NULL;
}

rl_status rl_relight_cluster(const rl_scene *scene, const rl_cluster *cluster, rl_progress_fn progress,
                             void *user, rl_solution **out)
{
    if (!scene || !out)
        return rl__fail(RL_ERR_ARG, "rl_relight: NULL argument");
    rl_status st;
    const rl_cluster *cl = check_cluster(cluster, &st);
    return st != RL_OK ? st : solve(scene, cl, scene->sampling.bounces + 1, progress, user, out);
}

rl_status rl_relight(const rl_scene *scene, rl_progress_fn progress, void *user, rl_solution **out)
{
    return rl_relight_cluster(scene, NULL, progress, user, out);
}

void rl_solution_destroy(rl_solution *s)
{
    if (!s)
        return;
    maps_free(s->maps, s->nmaps);
    tracer_destroy(s->tracer);
    free(s->polygon_map);
    free(s->passes);
    free(s);
}

uint32_t rl_solution_pass_count(const rl_solution *s)
{
    return s->npasses;
}

rl_status rl_solution_pass_stats(const rl_solution *s, uint32_t k, rl_pass_stats *out)
{
    if (k >= s->npasses)
        return rl__fail(RL_ERR_ARG, "pass %u of %u", k, s->npasses);
    *out = s->passes[k];
    return RL_OK;
}

size_t rl_solution_map_count(const rl_solution *s)
{
    return s->nmaps;
}

rl_status rl_solution_map_info(const rl_solution *s, size_t k, rl_map_info *out)
{
    if (k >= s->nmaps)
        return rl__fail(RL_ERR_ARG, "map %zu of %zu", k, s->nmaps);
    const rl_map *m = &s->maps[k];
    out->polygon = (uint32_t)m->polygon;
    out->label = s->scene->polygons[m->polygon].label;
    v3_store(m->frame.origin, out->origin);
    v3_store(m->frame.e1, out->e1);
    v3_store(m->frame.e2, out->e2);
    v3_store(m->frame.n, out->normal);
    out->cell_size = m->cell;
    out->u0 = m->u0;
    out->v0 = m->v0;
    out->nu = m->nu;
    out->nv = m->nv;
    out->ncells = m->ncells;
    memcpy(out->albedo, m->albedo, sizeof out->albedo);
    memcpy(out->emission, m->emission, sizeof out->emission);
    const rl_polygon *pg = &s->scene->polygons[m->polygon];
    out->vertices = &s->scene->vertices[pg->first][0];
    out->nvertices = pg->count;
    return RL_OK;
}

/* @return x as a float, FLT_MAX where it is beyond float's range: a light
 * field may hold radiance near FLT_MAX, whose irradiance is pi times more,
 * and a map must never hold inf. */
static float saturate_float(double x)
{
    return x > FLT_MAX ? FLT_MAX : (float)x;
}

rl_status rl_solution_map_cells(const rl_solution *s, size_t k, uint32_t *ij, double *area, double *centre,
                                float *irradiance, float *radiosity)
{
    if (k >= s->nmaps)
        return rl__fail(RL_ERR_ARG, "map %zu of %zu", k, s->nmaps);
    const rl_map *m = &s->maps[k];
    for (uint32_t c = 0; c < m->ncells; c++) {
        const rl_cell *cell = &m->cells[c];
        if (ij) {
            ij[2 * c] = cell->i;
            ij[2 * c + 1] = cell->j;
        }
        if (area)
            area[c] = cell->area;
        if (centre) {
            v2 poly[RL_MAX_POLY_VERTS + 8];
            uint32_t n = map_cell_polygon(m, cell, poly);
            v3_store(frame_point(&m->frame, polygon_centroid(poly, n)), centre + 3 * c);
        }
        for (int ch = 0; ch < 3; ch++) {
            if (irradiance)
                irradiance[3 * c + ch] = saturate_float(m->e_total[c][ch]);
            if (radiosity)
                radiosity[3 * c + ch] = saturate_float(PI * m->emission[ch] + m->albedo[ch] * m->e_total[c][ch]);
        }
    }
    return RL_OK;
}

/* ------------------------------------------------------------------ render */

typedef struct render_job {
    const rl_solution *s;
    float *rgb;                 /* radiance per pixel, or NULL */
    int32_t *map_ids, *cell_ids; /* what each pixel sees, or NULL */
    v3 forward, right, up;
    double tan_half, aspect;
    atomic_uint next_row;
} render_job;

/* Finds the front face first hit along a ray: its polygon, map and cell
 * (map or cell -1 when the polygon does not receive). @return 1, or 0 for
 * no hit or a back face. */
static int pick(const rl_solution *s, v3 org, v3 dir, uint32_t *poly, int32_t *map, int64_t *cell, v2 *at)
{
    double t;
    *map = -1;
    *cell = -1;
    if (!tracer_hit(s->tracer, org, dir, 0.0, INFINITY, poly, &t))
        return 0;
    if (v3_dot(dir, v3_load(s->scene->polygons[*poly].normal)) >= 0)
        return 0; /* the back of a one-sided surface */
    *map = s->polygon_map[*poly];
    if (*map >= 0) {
        *at = frame_project(&s->maps[*map].frame, v3_madd(org, dir, t));
        *cell = map_cell_at(&s->maps[*map], *at);
    }
    return 1;
}

/* Shades the first surface along one camera ray: emission plus albedo * E / pi. */
static void shade(const rl_solution *s, v3 org, v3 dir, float out[3])
{
    uint32_t poly;
    int32_t map;
    int64_t cell;
    v2 at;
    out[0] = out[1] = out[2] = 0.0f;
    if (!pick(s, org, dir, &poly, &map, &cell, &at))
        return;
    const rl_material *mat = &s->scene->materials[s->scene->polygons[poly].material];
    double e[3] = {0, 0, 0};
    if (cell >= 0 && s->flat)
        memcpy(e, s->maps[map].e_total[cell], sizeof e);
    else if (cell >= 0)
        map_sample(&s->maps[map], at, (const double(*)[3])s->maps[map].e_total, e);
    for (int c = 0; c < 3; c++)
        out[c] = (float)(mat->emission[c] + (cell >= 0 ? s->maps[map].albedo[c] * e[c] / PI : 0.0));
}

rl_status rl_solution_set_smooth(rl_solution *s, int smooth)
{
    if (!s)
        return rl__fail(RL_ERR_ARG, "rl_solution_set_smooth: NULL solution");
    s->flat = !smooth;
    return RL_OK;
}

rl_status rl_solution_trace(const rl_solution *s, const double org[3], const double dir[3], float rgb[3])
{
    v3 o = v3_load(org), d = v3_load(dir);
    double len = v3_len(d);
    if (!isfinite(v3_maxabs(o)) || !isfinite(len) || !(len > 0))
        return rl__fail(RL_ERR_ARG, "rl_solution_trace: origin and direction must be finite, direction nonzero");
    shade(s, o, v3_scale(d, 1.0 / len), rgb);
    return RL_OK;
}

/* Renders rows until none are left. */
static void *render_worker(void *p)
{
    render_job *job = p;
    const rl_camera *cam = &job->s->scene->camera;
    tracer_thread_init();
    for (;;) {
        unsigned y = atomic_fetch_add(&job->next_row, 1);
        if (y >= cam->height)
            break;
        for (unsigned x = 0; x < cam->width; x++) {
            double sx = (2.0 * (x + 0.5) / cam->width - 1.0) * job->tan_half * job->aspect;
            double sy = (1.0 - 2.0 * (y + 0.5) / cam->height) * job->tan_half;
            v3 d = v3_norm(v3_add(job->forward, v3_add(v3_scale(job->right, sx), v3_scale(job->up, sy))));
            size_t px = (size_t)y * cam->width + x;
            if (job->rgb)
                shade(job->s, v3_load(cam->position), d, job->rgb + 3 * px);
            if (job->map_ids) {
                uint32_t poly;
                int32_t map;
                int64_t cell;
                v2 at;
                pick(job->s, v3_load(cam->position), d, &poly, &map, &cell, &at);
                job->map_ids[px] = cell >= 0 ? map : -1;
                job->cell_ids[px] = cell >= 0 ? (int32_t)cell : -1;
            }
        }
    }
    return NULL;
}

/* Runs a render job over the camera's rows on every worker thread. */
static rl_status render(const rl_solution *s, float *rgb, int32_t *map_ids, int32_t *cell_ids)
{
    const rl_camera *cam = &s->scene->camera;
    if (!s->scene->has_camera)
        return rl__fail(RL_ERR_ARG, "%s: the scene has no camera", s->scene->path);
    render_job job;
    job.s = s;
    job.rgb = rgb;
    job.map_ids = map_ids;
    job.cell_ids = cell_ids;
    job.forward = v3_norm(v3_sub(v3_load(cam->look_at), v3_load(cam->position)));
    job.right = v3_norm(v3_cross(job.forward, v3_load(cam->up)));
    job.up = v3_cross(job.right, job.forward);
    job.tan_half = tan(cam->fov_deg * PI / 360.0);
    job.aspect = (double)cam->width / cam->height;
    atomic_init(&job.next_row, 0);
    unsigned n = thread_count(s->scene->sampling.threads), started = 0;
    pthread_t *threads = malloc(n * sizeof *threads);
    if (threads == NULL)
        return rl__fail(RL_ERR_NOMEM, "%s: out of memory for %u render threads", s->scene->path, n);
    for (; started < n; started++)
        if (pthread_create(&threads[started], NULL, render_worker, &job) != 0)
            break;
    if (started == 0)
        render_worker(&job);
    for (unsigned k = 0; k < started; k++)
        pthread_join(threads[k], NULL);
    free(threads);
    return RL_OK;
}

rl_status rl_solution_render(const rl_solution *s, float *rgb)
{
    return render(s, rgb, NULL, NULL);
}

rl_status rl_solution_render_cells(const rl_solution *s, int32_t *map_ids, int32_t *cell_ids)
{
    return render(s, NULL, map_ids, cell_ids);
}

/* -------------------------------------------------------------- ray bench */

typedef struct ray_job {
    const rl_scene *scene;
    const rl_tracer *tracer;
    const double *cdf; /* cumulative polygon areas, npolygons entries */
    uint64_t per_thread;
    atomic_uint_fast64_t occluded;
    _Atomic double trace_cpu, trace_wall; /* summed over threads; the longest thread */
} ray_job;

/* @return a uniform double in [0, 1) from state. */
static double next_unit(uint64_t *state)
{
    *state = hash_mix(*state, 0x632be59bd9b4e019ull);
    return (*state >> 11) * (1.0 / 9007199254740992.0);
}

/* Gives a random shadow ray: from a point uniform on the scene's polygons
 * (by area) in a cosine-distributed direction about the polygon's normal. */
static void random_ray(const ray_job *job, uint64_t *state, v3 *org, v3 *dir)
{
    const rl_scene *sc = job->scene;
    double pick_a = next_unit(state) * job->cdf[sc->npolygons - 1];
    size_t lo = 0, hi = sc->npolygons - 1;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (job->cdf[mid] <= pick_a)
            lo = mid + 1;
        else
            hi = mid;
    }
    const rl_polygon *pg = &sc->polygons[lo];
    const double(*v)[3] = sc->vertices + pg->first;
    /* a point on one fan triangle, a cosine-distributed direction about the normal */
    uint32_t t = 1 + (uint32_t)(next_unit(state) * (pg->count - 2));
    double su = sqrt(next_unit(state)), b = next_unit(state);
    v3 a0 = v3_load(v[0]), a1 = v3_load(v[t]), a2 = v3_load(v[t + 1]);
    *org = v3_add(v3_add(v3_scale(a0, 1 - su), v3_scale(a1, su * (1 - b))), v3_scale(a2, su * b));
    v3 n = v3_load(pg->normal), e1 = v3_norm(v3_sub(a1, a0)), e2 = v3_cross(n, e1);
    double r1 = next_unit(state), phi = 2 * PI * next_unit(state), sr = sqrt(r1);
    *dir = v3_add(v3_scale(n, sqrt(1 - r1)), v3_add(v3_scale(e1, sr * cos(phi)), v3_scale(e2, sr * sin(phi))));
}

/* Traces this thread's share of random shadow rays: a chunk is drawn, then
 * traced in packets as the engine traces, and only the tracing is timed. */
static void *ray_worker(void *p)
{
    enum { CHUNK = 4096 };
    ray_job *job = p;
    static atomic_uint seq;
    uint64_t state = hash_mix(0x5eed, atomic_fetch_add(&seq, 1)), hits = 0;
    double reach = 4.0 * tracer_extent(job->tracer), cpu = 0.0, wall = 0.0;
    v3 *org = malloc(CHUNK * sizeof *org), *dir = malloc(CHUNK * sizeof *dir);
    double *tn = malloc(CHUNK * sizeof *tn), *tf = malloc(CHUNK * sizeof *tf);
    tracer_thread_init();
    for (uint64_t done = 0; org && dir && tn && tf && done < job->per_thread; done += CHUNK) {
        size_t n = job->per_thread - done < CHUNK ? (size_t)(job->per_thread - done) : CHUNK;
        for (size_t i = 0; i < n; i++) {
            random_ray(job, &state, &org[i], &dir[i]);
            tn[i] = 1e-6 * reach;
            tf[i] = reach;
        }
        double c0 = now(CLOCK_THREAD_CPUTIME_ID), w0 = now(CLOCK_MONOTONIC);
        for (size_t i = 0; i < n; i += RL_RAY_PACKET) {
            int occ[RL_RAY_PACKET];
            size_t m = n - i < RL_RAY_PACKET ? n - i : RL_RAY_PACKET;
            tracer_occluded_n(job->tracer, m, org + i, dir + i, tn + i, tf + i, occ);
            for (size_t k = 0; k < m; k++)
                hits += occ[k] != 0;
        }
        cpu += now(CLOCK_THREAD_CPUTIME_ID) - c0;
        wall += now(CLOCK_MONOTONIC) - w0;
    }
    free(org);
    free(dir);
    free(tn);
    free(tf);
    atomic_fetch_add(&job->occluded, hits);
    double c = atomic_load(&job->trace_cpu);
    while (!atomic_compare_exchange_weak(&job->trace_cpu, &c, c + cpu))
        ;
    double w = atomic_load(&job->trace_wall);
    while (w < wall && !atomic_compare_exchange_weak(&job->trace_wall, &w, wall))
        ;
    return NULL;
}

rl_status rl_bench_rays(const rl_scene *scene, uint64_t rays, rl_ray_bench *out)
{
    rl_tracer *tracer = NULL;
    memset(out, 0, sizeof *out);
    if (scene->npolygons == 0)
        return rl__fail(RL_ERR_ARG, "%s: the scene has no polygons to trace against", scene->path);
    rl_status st = tracer_new(scene, &tracer);
    if (st != RL_OK)
        return st;
    double *cdf = malloc(scene->npolygons * sizeof *cdf);
    unsigned n = thread_count(scene->sampling.threads), started = 0;
    pthread_t *threads = malloc(n * sizeof *threads);
    if (!cdf || !threads) {
        free(cdf);
        free(threads);
        tracer_destroy(tracer);
        return rl__fail(RL_ERR_NOMEM, "out of memory");
    }
    double acc = 0;
    for (size_t k = 0; k < scene->npolygons; k++)
        cdf[k] = acc += scene->polygons[k].area;
    ray_job job = {scene, tracer, cdf, rays / n + 1, 0, 0.0, 0.0};
    for (; started < n; started++)
        if (pthread_create(&threads[started], NULL, ray_worker, &job) != 0)
            break;
    if (started == 0) {
        ray_worker(&job);
        started = 1;
    } else {
        for (unsigned k = 0; k < started; k++)
            pthread_join(threads[k], NULL);
    }
    out->wall_seconds = atomic_load(&job.trace_wall);
    out->cpu_seconds = atomic_load(&job.trace_cpu);
    out->rays = job.per_thread * started;
    out->occluded = atomic_load(&job.occluded);
    free(cdf);
    free(threads);
    tracer_destroy(tracer);
    return RL_OK;
}

/* ------------------------------------------------------------------ points */

/* Checks the points and builds one zero-area receiver per point. @return RL_OK or an error. */
static rl_status point_maps(const double *points, size_t count, rl_map **out)
{
    rl_map *maps = calloc(count ? count : 1, sizeof *maps);
    if (!maps)
        return rl__fail(RL_ERR_NOMEM, "out of memory for %zu points", count);
    for (size_t k = 0; k < count; k++) {
        v3 p = v3_load(points + 6 * k), n = v3_load(points + 6 * k + 3);
        double len = v3_len(n);
        if (!isfinite(v3_maxabs(p)) || !isfinite(len) || !(len > 0)) {
            maps_free(maps, k);
            return rl__fail(RL_ERR_ARG, "point %zu: position and normal must be finite, normal nonzero", k + 1);
        }
        if (map_point(p, v3_scale(n, 1.0 / len), &maps[k]) != RL_OK) {
            maps_free(maps, k + 1);
            return rl__fail(RL_ERR_NOMEM, "out of memory for %zu points", count);
        }
    }
    *out = maps;
    return RL_OK;
}

rl_status rl_irradiance(const rl_scene *scene, const double *points, size_t count, double *out,
                        rl_pass_stats *stats)
{
    return rl_irradiance_cluster(scene, NULL, points, count, out, stats);
}

rl_status rl_irradiance_cluster(const rl_scene *scene, const rl_cluster *cluster, const double *points,
                                size_t count, double *out, rl_pass_stats *stats)
{
    rl_map *pts = NULL;
    rl_solution *sol = NULL;
    rl_status st;
    const rl_cluster *cl = check_cluster(cluster, &st);
    if (st != RL_OK)
        return st;
    st = point_maps(points, count, &pts);
    if (st != RL_OK)
        return st;
    /* Light reflected by the scene: solve `bounces` passes and let every lit
     * map re-emit the irradiance summed over them. */
    st = solve(scene, cl, scene->sampling.bounces, NULL, NULL, &sol);
    size_t ne = 0;
    rl_emitter *e = st == RL_OK ? primary_emitters(scene, sol->nmaps, &ne) : NULL;
    if (st == RL_OK && !e)
        st = rl__fail(RL_ERR_NOMEM, "out of memory for emitters");
    if (st == RL_OK && scene->sampling.bounces > 0) {
        for (size_t m = 0; m < sol->nmaps; m++)
            memcpy(sol->maps[m].e_prev, sol->maps[m].e_total, sol->maps[m].ncells * sizeof *sol->maps[m].e_prev);
        ne = append_bounce_emitters(scene, sol->maps, sol->nmaps, e, ne);
    }
    rl_pass_stats local;
    double *measured = NULL;
    if (st == RL_OK)
        st = run_pass(scene, sol->tracer, cl, scene->sampling.bounces, 0, pts, count, e, ne, NULL, NULL, 0, 1,
                      &measured, stats ? stats : &local);
    free(measured);
    for (size_t k = 0; st == RL_OK && k < count; k++)
        for (int c = 0; c < 3; c++)
            out[3 * k + c] = pts[k].e_pass[0][c];
    free(e);
    rl_solution_destroy(sol);
    maps_free(pts, count);
    return st;
}
