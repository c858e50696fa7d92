/*
 * engine.c - the pass scheduler of the relighting engine: passes, tiles,
 * threads, and the exchange between the ranks of a job; the solutions it
 * makes, and rl_solution_destroy().
 *
 * A run builds the radiance maps and the ray tracer, then runs pass 0 from
 * the scene's emitters (emissive polygons and light field slabs) and
 * `bounces` further passes, each from the receivers that the previous pass
 * lit, re-emitting albedo * E / pi. Within a pass, the work is the list of
 * tiles (rows of one map's grid); a team of worker threads (ilf/pool.h)
 * takes tiles from an atomic counter while the calling thread reports
 * progress, and each tile's cells are written only by the thread that owns
 * the tile, in an order fixed by the tile alone. So the output does not
 * depend on the number of threads or on scheduling. In a job of several
 * processes (rl_cluster), the tiles are dealt to the ranks by expected
 * cost (deal_tiles), or claimed by the ranks from one count as they become
 * free (rl_cluster.next; share_owners() then tells every rank who did which),
 * and after each pass the ranks exchange their tiles'
 * values: since a tile's values do not depend on who computed them, every
 * rank then holds what one process would. The solution's accessors are in
 * solution.c, the camera view in view.c, point queries in query.c and the
 * ray benchmark in bench_rays.c.
 */
#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "emitter_tree.h"
#include "engine_internal.h"
#include "ilf/clock.h"
#include "ilf/pool.h"
#include "sampling.h"

/* Grid squares a work item holds (whole rows). Larger tiles set up fewer (emitter, tile) pairs and share
 * more of what a pair builds (shadows, tables, anchors); 8192 rather than 2048 took the light-field
 * classroom's direct pass at 1.3 M cells from 9.7 to 9.0 s (anchors on its 3-row tiles were measured
 * twice) and the paper's 'beams' from 1.24 to 1.04 s, errors unchanged (BENCHMARKS-journal.md, section 2m),
 * and still leaves hundreds of items to share out between threads. */
#define TILE_CELLS 8192u
/* Cells a pass gathering by first hits (bounce_rays) gathers in a work item: each cell casts its own rays,
 * with nothing shared within a tile, so smaller items cost nothing and leave less for the last thread
 * to finish alone. */
#define TILE_FIRST_HIT 1024u

/* How often the calling thread reports progress while a team works, seconds. */
#define PROGRESS_PERIOD 0.02

/* ------------------------------------------------------------ parallel work */

typedef struct work_item {
    uint32_t map;
    uint32_t row0, row1;
    uint32_t set; /* which of the job's map arrays (pass_job.sets) */
} work_item;

typedef struct pass_job {
    rl_transfer_ctx ctx;
    rl_map *sets[2]; /* the maps the items gather on: the pass's, and those gathered with them (or NULL) */
    const work_item *items;
    size_t nitems;
    atomic_size_t next, done;
    atomic_uint_fast64_t done_cells; /* cells of the items done: the pass's progress (tiles differ in size) */
    uint64_t total_cells;            /* cells of all the items */
    atomic_int failed;
    rl_counters *counters; /* one per worker */
    double *seconds;       /* [nitems]: each tile's CPU time, or NULL */
    /* tiles claimed from the job as this rank becomes free (rl_cluster.next), or NULL: items taken in turn */
    const rl_cluster *claim;
    const size_t *claim_order; /* [nitems]: the item the job's claim t stands for */
    uint8_t *claimed;          /* [nitems]: 1 for the items this rank claimed */
    pthread_mutex_t claim_lock; /* one claim at a time (rl_cluster.next) */
    atomic_uint working;        /* workers that have not finished */
    /* maps told ready as their last tile finishes (rl__run.reporting), or left NULL */
    const rl__run *run;
    atomic_uint *left;     /* [nmaps]: tiles of each map not finished yet, plus 1 until the map is completed
                              (rl__run.finish): 0 once it may be told of */
    size_t nmaps, ready;   /* maps [0, ready) told ready */
    pthread_mutex_t lock;  /* over ready and the calls of maps_ready, which come in order */
} pass_job;

/* Completes map m, whose tiles have all finished (rl__run.finish), and only then lets tell_ready() tell of
 * it: the completion's writes happen before the count reaches 0, which tell_ready() reads. */
static void map_complete(pass_job *job, size_t m)
{
    if (job->run->finish)
        job->run->finish(job->run->finish_user, m);
    atomic_fetch_sub(&job->left[m], 1);
}

/* Tells the run's maps_ready of the maps from job->ready on that are complete, up to the first that is
 * not: maps are told in order, as their tiles are dealt. */
static void tell_ready(pass_job *job)
{
    pthread_mutex_lock(&job->lock);
    size_t r = job->ready;
    while (r < job->nmaps && atomic_load(&job->left[r]) == 0)
        r++;
    if (r > job->ready) {
        job->ready = r;
        job->run->maps_ready(job->run->maps_ready_user, job->run->reporting, r);
    }
    pthread_mutex_unlock(&job->lock);
}

/* Readies job to tell run's maps_ready of its nmaps maps as their tiles finish (job->items set, every map
 * with one at least, empty if need be; ne: the pass's emitters, none meaning no tile runs, when the maps
 * are completed here). @return 0, or -1 without memory (nothing left allocated). */
static int tell_begin(pass_job *job, const rl__run *run, size_t nmaps, size_t ne)
{
    job->left = calloc(nmaps ? nmaps : 1, sizeof *job->left);
    if (job->left == NULL || pthread_mutex_init(&job->lock, NULL) != 0) {
        free(job->left);
        job->left = NULL;
        return -1;
    }
    job->run = run, job->nmaps = nmaps, job->ready = 0;
    for (size_t m = 0; m < nmaps; m++)
        atomic_init(&job->left[m], 1);
    for (size_t k = 0; ne > 0 && k < job->nitems; k++)
        atomic_fetch_add(&job->left[job->items[k].map], 1);
    /* a map no item runs for is completed now */
    for (size_t m = 0; m < nmaps; m++)
        if (atomic_load(&job->left[m]) == 1)
            map_complete(job, m);
    return 0;
}

/* After the pass (rc its result): tells what its tiles did not (maps without any; at least once, even of
 * no map, when it succeeded), and frees what tell_begin() made. */
static void tell_end(pass_job *job, int rc)
{
    if (rc == 0)
        tell_ready(job);
    if (rc == 0 && job->ready == 0)
        job->run->maps_ready(job->run->maps_ready_user, job->run->reporting, 0);
    pthread_mutex_destroy(&job->lock);
    free(job->left);
    job->left = NULL;
}

static uint32_t tile_work(const rl_map *maps, const work_item *w);

/* Takes the next item of job for a worker: the next in turn, or the one claimed from the ranks' job.
 * @return 1 and *k, or 0 when none is left. */
static int take_item(pass_job *job, size_t *k)
{
    if (!job->claim) {
        *k = atomic_fetch_add(&job->next, 1);
        return *k < job->nitems;
    }
    pthread_mutex_lock(&job->claim_lock);
    uint64_t t = job->claim->next(job->claim->user, job->nitems);
    pthread_mutex_unlock(&job->claim_lock);
    if (t >= job->nitems)
        return 0;
    *k = job->claim_order[t];
    job->claimed[*k] = 1;
    return 1;
}

/* Worker `index` of a pass: takes tiles until none are left. */
static void worker(void *p, unsigned index)
{
    pass_job *job = p;
    rl_scratch scratch = {0};
    rl__tracer_thread_init();
    for (;;) {
        size_t k = 0;
        if (!take_item(job, &k) || atomic_load(&job->failed))
            break;
        const work_item *w = &job->items[k];
        uint32_t cells = tile_work(job->sets[w->set], w);
        double t0 = job->seconds ? ilf_clock_thread_cpu() : 0.0;
        if (w->row0 < w->row1 && rl__transfer_tile(&job->ctx, w->map, &job->sets[w->set][w->map], w->row0,
                                                   w->row1, &scratch, &job->counters[index]) != 0)
            atomic_store(&job->failed, 1);
        if (job->seconds)
            job->seconds[k] = ilf_clock_thread_cpu() - t0;
        /* the tile's cells are written: its map may be final (its values happen before this) */
        if (job->left && !atomic_load(&job->failed) && atomic_fetch_sub(&job->left[w->map], 1) == 2) {
            map_complete(job, w->map);
            tell_ready(job);
        }
        atomic_fetch_add(&job->done_cells, cells);
        atomic_fetch_add(&job->done, 1);
    }
    rl__scratch_free(&scratch);
    atomic_fetch_sub(&job->working, 1);
}

/* Runs job on a team of n workers, reporting progress from the calling thread while they work.
 * base and span place this pass within the run's [0, 1] progress. @return 0 or -1. */
static int run_job(pass_job *job, unsigned n, const rl__run *run, double base, double span)
{
    job->counters = calloc(n, sizeof *job->counters);
    if (!job->counters)
        return -1;
    atomic_init(&job->next, 0);
    atomic_init(&job->done, 0);
    atomic_init(&job->done_cells, 0);
    atomic_init(&job->failed, 0);
    atomic_init(&job->working, n);
    job->total_cells = 0;
    for (size_t k = 0; k < job->nitems; k++)
        job->total_cells += tile_work(job->sets[job->items[k].set], &job->items[k]);
    ilf_team *team;
    if (ilf_team_start(n, worker, job, &team) != 0) {
        free(job->counters);
        job->counters = NULL;
        return -1;
    }
    /* Without a started thread the work runs at join: nothing to wait for here. Workers whose thread
     * did not start run at join too, so the wait is for the others. A rank that claims its tiles does
     * about 1/ranks of the cells: its share stands for the job's progress. */
    unsigned unstarted = n - ilf_team_threads(team);
    double ranks = job->claim ? (double)job->claim->ranks : 1.0;
    while (run->progress && ilf_team_threads(team) > 0 && atomic_load(&job->working) > unstarted &&
           !atomic_load(&job->failed)) {
        double f = ranks * (double)atomic_load(&job->done_cells) / (double)(job->total_cells ? job->total_cells : 1);
        run->progress(run->user, base + span * (f < 1.0 ? f : 1.0));
        ilf_clock_sleep(PROGRESS_PERIOD);
    }
    ilf_team_join(team);
    return atomic_load(&job->failed) ? -1 : 0;
}

/* Sums the per-thread counters into stats. */
static void sum_counters(const rl_counters *c, unsigned n, rl_pass_stats *st)
{
    for (unsigned k = 0; k < n; k++) {
        for (unsigned b = 0; b < RL_CELL_ERROR_BINS; b++)
            st->cell_error_histogram[b] += c[k].cell_error[b];
        st->samples += c[k].samples;
        st->rays_cast += c[k].rays_cast;
        st->rays_kept += c[k].rays_kept;
        st->rays_free += c[k].rays_free;
        st->solid_angles_considered += c[k].leaves_considered;
        st->solid_angles_culled += c[k].leaves_culled;
        st->pairs += c[k].pairs;
        st->pairs_descended += c[k].pairs_descended;
        st->refinements += c[k].refinements;
        st->estimated_rmse += c[k].variance; /* a sum of variances until run_pass divides */
        st->budget_reached |= c[k].budget_reached;
    }
}

/* @return the first cell of map m in grid row j or after: cells are numbered row by row. */
static uint32_t first_cell_of_row(const rl_map *m, uint32_t j)
{
    uint32_t lo = 0, hi = m->ncells;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (rl__map_cell(m, mid).j < j)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* @return the number of cells of tile w (a run of consecutive cells). */
static uint32_t tile_cells(const rl_map *maps, const work_item *w)
{
    const rl_map *m = &maps[w->map];
    return first_cell_of_row(m, w->row1) - first_cell_of_row(m, w->row0);
}

/* @return the number of cells of map m in grid rows [row0, row1) that a pass gathers: those of
 * rl_map.subset when it is set. */
static uint32_t rows_work(const rl_map *m, uint32_t row0, uint32_t row1)
{
    uint32_t c0 = first_cell_of_row(m, row0), c1 = first_cell_of_row(m, row1), n = 0;
    if (!m->subset)
        return c1 - c0;
    for (uint32_t c = c0; c < c1; c++)
        n += m->subset[c] != 0;
    return n;
}

/* @return the number of cells of tile w that a pass gathers (rows_work()). */
static uint32_t tile_work(const rl_map *maps, const work_item *w)
{
    return rows_work(&maps[w->map], w->row0, w->row1);
}

/* @return what row j of map m adds to a tile: its grid squares, or with by_work the cells of it a pass
 * gathers (rows_work()). */
static uint32_t row_units(const rl_map *m, uint32_t j, int by_work)
{
    return by_work ? rows_work(m, j, j + 1) : m->nu;
}

/* Splits every map of each of the nsets arrays of nmaps maps into tiles of whole rows, each row added
 * while the tile stays within per_tile units (row_units()) or is empty, leaving out those with no cell
 * to gather; map m's tiles of every set lie together, the sets in order, then map m + 1's. With empty,
 * a map left without any has one empty item (rows 0 to 0), in its place. items NULL counts them only.
 * @return the number of items. */
static size_t split_tiles(rl_map *const *sets, size_t nsets, size_t nmaps, uint32_t per_tile, int by_work, int empty,
                          work_item *items)
{
    size_t k = 0;
    for (size_t m = 0; m < nmaps; m++) {
        size_t first = k;
        for (uint32_t set = 0; set < nsets; set++) {
            const rl_map *maps = sets[set], *mp = &maps[m];
            for (uint32_t r0 = 0, r1; r0 < mp->nv; r0 = r1) {
                uint64_t units = 0;
                for (r1 = r0; r1 < mp->nv; r1++) {
                    uint32_t u = row_units(mp, r1, by_work);
                    if (r1 > r0 && units + u > per_tile)
                        break;
                    units += u;
                }
                work_item w = {(uint32_t)m, r0, r1, set};
                /* by work, the units counted are the cells the tile gathers */
                if (by_work ? units == 0 : tile_work(maps, &w) == 0)
                    continue;
                if (items)
                    items[k] = w;
                k++;
            }
        }
        if (empty && k == first) {
            if (items)
                items[k] = (work_item){(uint32_t)m, 0, 0, 0};
            k++;
        }
    }
    return k;
}

/* Splits every map of the sets into items (split_tiles()). @return the items (count in *n) or NULL. */
static work_item *make_tiles(rl_map *const *sets, size_t nsets, size_t nmaps, uint32_t per_tile, int by_work,
                             int empty, size_t *n)
{
    size_t count = split_tiles(sets, nsets, nmaps, per_tile, by_work, empty, NULL);
    work_item *items = malloc((count ? count : 1) * sizeof *items);
    if (items)
        *n = split_tiles(sets, nsets, nmaps, per_tile, by_work, empty, items);
    return items;
}

/* ------------------------------------------------------------ several ranks */

/* The expected cost of a tile with no measurement: its cells, plus what setting up any tile costs
 * (its emitter pairs, its clipping), in cells. Fitted to the classroom's tiles (cost = a cells + b):
 * b is about 0 cells in the direct pass, 9 in a bounce pass by the method (3,035 emitters, every tile paired
 * with each); a first-hit bounce pass costs its cells alone. */
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


/* Orders the n tiles of a pass by expected cost, dearest first: the measured CPU seconds of the same
 * tiles in the previous pass when given (bounce passes repeat their tiles), else their cells. Equal
 * costs are ordered by a fixed hash of the tile's index, so that the many tiles of the same size are
 * mixed: taken in list order, a rank would get every box's top, lit, face. Every rank computes the same
 * order. @return the order (malloc'd), or NULL when out of memory. */
static dealt *dearest_order(const rl_map *maps, const work_item *items, size_t n, const double *measured)
{
    dealt *order = malloc((n ? n : 1) * sizeof *order);
    if (order) {
        for (size_t k = 0; k < n; k++)
            order[k] = (dealt){measured ? measured[k] : tile_work(maps, &items[k]) + TILE_SETUP_CELLS,
                               ilf_hash_mix(0x9e3779b97f4a7c15u, k), k};
        qsort(order, n, sizeof *order, dearest_first);
    }
    return order;
}

/* Deals the n tiles of a pass to the ranks up front in dearest_order(), each to the rank with the
 * least so far (longest processing time first). Every rank computes the same deal.
 * @return owner[n] (malloc'd), or NULL when out of memory. */
static uint32_t *deal_tiles(const rl_cluster *cl, const rl_map *maps, const work_item *items, size_t n,
                            const double *measured)
{
    uint32_t *owner = malloc((n ? n : 1) * sizeof *owner);
    dealt *order = dearest_order(maps, items, n, measured);
    double *load = calloc(cl->ranks, sizeof *load);
    if (owner && order && load) {
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

/* This rank's share of a pass's tiles: dealt up front (mine, index), or claimed as the rank becomes
 * free (rl_cluster.next: order, claimed; every tile is then "mine" until the pass tells whose it was). */
typedef struct share {
    uint32_t *owner;  /* [n]: each tile's rank (claimed tiles: once the pass is over) */
    work_item *mine;  /* this rank's tiles, in list order */
    size_t *index;    /* [nmine]: their places in the list */
    double *seconds;  /* [nmine]: the CPU time each took */
    size_t nmine;
    size_t *order;    /* claimed: [n], the tile the job's claim t stands for */
    uint8_t *claimed; /* claimed: [n], 1 for the tiles this rank claimed */
} share;

/* Frees a share's arrays. */
static void share_free(share *sh)
{
    free(sh->owner);
    free(sh->mine);
    free(sh->index);
    free(sh->seconds);
    free(sh->order);
    free(sh->claimed);
}

/* Readies the n tiles of items to be claimed as the rank becomes free, dearest first (by measured costs
 * when given), all the ranks claiming from one count (rl_cluster.next). @return 0 or -1 (out of memory). */
static int share_claims(const rl_map *maps, const work_item *items, size_t n, const double *measured, share *sh)
{
    dealt *order = dearest_order(maps, items, n, measured);
    sh->owner = malloc((n ? n : 1) * sizeof *sh->owner);
    sh->mine = malloc((n ? n : 1) * sizeof *sh->mine);
    sh->index = malloc((n ? n : 1) * sizeof *sh->index);
    sh->seconds = calloc(n ? n : 1, sizeof *sh->seconds);
    sh->order = malloc((n ? n : 1) * sizeof *sh->order);
    sh->claimed = calloc(n ? n : 1, sizeof *sh->claimed);
    int ok = order && sh->owner && sh->mine && sh->index && sh->seconds && sh->order && sh->claimed;
    for (size_t k = 0; ok && k < n; k++)
        sh->order[k] = order[k].tile, sh->index[k] = k, sh->mine[k] = items[k];
    sh->nmine = n;
    free(order);
    if (!ok)
        share_free(sh);
    return ok ? 0 : -1;
}

/* After a pass of claimed tiles: tells every rank whose each tile was, by a sum over the ranks of, per
 * tile, the claims (1 or 0) and the claimer's rank + 1 (or 0): small integers, so the sums are exact
 * whatever their order, and a tile claimed by no rank or by two is caught. @return 0, -1 (out of
 * memory) or -2 (the exchange failed, or the claims did not share the tiles out). */
static int share_owners(const rl_cluster *cl, share *sh, size_t n)
{
    double *v = malloc((n ? 2 * n : 1) * sizeof *v);
    if (!v)
        return -1;
    for (size_t k = 0; k < n; k++)
        v[2 * k] = sh->claimed[k], v[2 * k + 1] = sh->claimed[k] ? cl->rank + 1.0 : 0.0;
    int rc = cl->sum(cl->user, v, 2 * n) == 0 ? 0 : -2;
    for (size_t k = 0; rc == 0 && k < n; k++) {
        if (v[2 * k] != 1.0 || !(v[2 * k + 1] >= 1.0 && v[2 * k + 1] <= cl->ranks))
            rc = -2;
        else
            sh->owner[k] = (uint32_t)v[2 * k + 1] - 1;
    }
    free(v);
    return rc;
}

/* Deals the n tiles of items (by measured costs when given) and keeps this rank's: up front, or to be
 * claimed when the cluster claims. @return 0 or -1 (out of memory). */
static int share_deal(const rl_cluster *cl, const rl_map *maps, const work_item *items, size_t n,
                      const double *measured, share *sh)
{
    memset(sh, 0, sizeof *sh);
    if (cl->next)
        return share_claims(maps, items, n, measured, sh);
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

/* Sets st's summary of the cells' relative standard errors from their histogram (rl__cell_error_bin()). */
static void summarise_cell_errors(rl_pass_stats *st)
{
    const uint64_t *hist = st->cell_error_histogram;
    uint64_t total = 0, below = 0;
    for (unsigned b = 0; b < RL_CELL_ERROR_BINS; b++)
        total += hist[b];
    st->cell_error_cells = total;
    st->cell_error_median = st->cell_error_p95 = st->cell_error_max = 0.0;
    for (unsigned b = 0; b < RL_CELL_ERROR_BINS && total > 0; b++) {
        if (hist[b] == 0)
            continue;
        double v = b == 0 ? 0.0 : rl__cell_error_of_bin(b); /* the first bin holds the cells of no error */
        if (below < 0.5 * (double)total && (double)(below + hist[b]) >= 0.5 * (double)total)
            st->cell_error_median = v;
        if (below < 0.95 * (double)total && (double)(below + hist[b]) >= 0.95 * (double)total)
            st->cell_error_p95 = v;
        st->cell_error_max = v;
        below += hist[b];
    }
}

/* Sums the pass statistics over ranks (wall time stays this rank's). @return 0 or -1. */
static int sum_stats(const rl_cluster *cl, rl_pass_stats *st)
{
    double hist[RL_CELL_ERROR_BINS];
    for (unsigned b = 0; b < RL_CELL_ERROR_BINS; b++)
        hist[b] = (double)st->cell_error_histogram[b];
    if (cl->sum(cl->user, hist, RL_CELL_ERROR_BINS) != 0)
        return -1;
    for (unsigned b = 0; b < RL_CELL_ERROR_BINS; b++)
        st->cell_error_histogram[b] = (uint64_t)hist[b];
    double v[] = {(double)st->samples, (double)st->rays_cast, (double)st->rays_kept,
                  (double)st->solid_angles_considered, (double)st->solid_angles_culled, (double)st->pairs,
                  (double)st->pairs_descended, (double)st->refinements, (double)st->rays_free,
                  st->estimated_rmse, (double)st->budget_reached, st->cpu_seconds};
    if (cl->sum(cl->user, v, sizeof v / sizeof v[0]) != 0)
        return -1;
    uint64_t *counts[] = {&st->samples, &st->rays_cast, &st->rays_kept, &st->solid_angles_considered,
                          &st->solid_angles_culled, &st->pairs, &st->pairs_descended, &st->refinements,
                          &st->rays_free};
    size_t nc = sizeof counts / sizeof counts[0];
    for (size_t k = 0; k < nc; k++)
        *counts[k] = (uint64_t)v[k];
    st->estimated_rmse = v[nc];
    st->budget_reached = v[nc + 1] > 0;
    st->cpu_seconds = v[nc + 2];
    return 0;
}

/* ---------------------------------------------------------------- emitters */

/* @return 1 if any channel of v is > 0. */
static int positive3(const float v[3])
{
    return v[0] > 0 || v[1] > 0 || v[2] > 0;
}

/* Builds the emitters of the scene itself (pass 0). @return the array (count in *n) or NULL. */
rl_emitter *rl__primary_emitters(const rl_scene *scene, const rl_slab_tables *tables, size_t extra, size_t *n)
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
            rl__emitter_from_polygon(scene, (uint32_t)k, NULL, &e[m++]);
    for (size_t k = 0; k < scene->nlightfields; k++)
        rl__emitter_from_lightfield(&scene->lightfields[k], &tables[k], &e[m++]);
    *n = m;
    return e;
}

/* Appends to e (room assumed) one emitter per map that re-emits light. @return the new count. */
size_t rl__append_bounce_emitters(const rl_scene *scene, const rl_map *maps, size_t nmaps, rl_emitter *e, size_t n)
{
    for (size_t m = 0; m < nmaps; m++) {
        int lit = 0;
        for (uint32_t c = 0; c < maps[m].ncells && !lit; c++)
            lit = maps[m].e_prev[c][0] > 0 || maps[m].e_prev[c][1] > 0 || maps[m].e_prev[c][2] > 0;
        if (lit)
            rl__emitter_from_polygon(scene, (uint32_t)maps[m].polygon, &maps[m], &e[n++]);
    }
    return n;
}

/* @return the sampling of pass p. Bounce passes by the method (bounce_rays 0) use bounce_partition_n
 * and never descend: their emitters are every lit surface, which at a coarse
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

/* ------------------------------------------------------------ progress weights */

/* A run's progress is shared out between its passes by their expected work, counted in rays, so that a
 * cheap pass does not take as much of the bar as a costly one (a direct pass of 4096 shadow rays per cell
 * and emitter against a first-hit bounce of 256 rays per larger cell). The counts are estimates made
 * before the pass runs: a culled or adaptive pass is taken to test a quarter of an emitter's 4n^2 solid
 * angles; cells are the receivers' area over the cell's (the maps are not built yet). */

double rl__pass_work(const rl_sampling *job, uint32_t pass, double cells, double emitters)
{
    rl_sampling s = pass_sampling(job, pass);
    if (pass > 0 && s.bounce_rays > 0)
        return cells * s.bounce_rays; /* first hits: the emitters are read where the rays land */
    double per_pair = s.method == RL_METHOD_AREA || s.method == RL_METHOD_SOLIDANGLE
                          ? (double)s.samples_per_cell
                          : (double)s.rays_per_solid_angle * s.partition_n * s.partition_n;
    return cells * emitters * per_pair;
}

/* @return the expected cells of the scene's receivers at cells of side `side` (m), and their count in
 * *receivers. */
static double receiver_cells(const rl_scene *scene, double side, size_t *receivers)
{
    double cells = 0.0;
    *receivers = 0;
    for (size_t k = 0; k < scene->npolygons; k++) {
        const float *al = scene->materials[scene->polygons[k].material].albedo;
        if (al[0] > 0 || al[1] > 0 || al[2] > 0) {
            cells += 1.0 + scene->polygons[k].area / (side * side);
            ++*receivers;
        }
    }
    return cells;
}

/* @return the factor by which bounce passes enlarge the cells they gather on (rl__solve()). */
static uint32_t bounce_factor(const rl_sampling *s)
{
    return s->bounce_cell_factor ? s->bounce_cell_factor : s->bounce_rays > 0 ? 4 : 2;
}

double rl__solve_work(const rl_scene *scene, const rl__run *run, uint32_t passes, double *per_pass)
{
    size_t receivers = 0, ne = 0;
    for (size_t k = 0; k < scene->npolygons; k++)
        ne += positive3(scene->materials[scene->polygons[k].material].emission);
    ne += scene->nlightfields;
    double total = 0.0, fine = receiver_cells(scene, run->cell_size, &receivers);
    double coarse =
        passes > 1 ? receiver_cells(scene, run->cell_size * bounce_factor(&run->sampling), &receivers) : fine;
    for (uint32_t p = 0; p < passes; p++) {
        /* a bounce pass's emitters are the lit receivers: at most all of them */
        double w = p == 0 ? rl__pass_work(&run->sampling, 0, fine, (double)ne)
                          : rl__pass_work(&run->sampling, p, coarse, (double)receivers);
        if (per_pass)
            per_pass[p] = w;
        total += w;
    }
    return total;
}

/* Fills the shared context of a pass; sampling must outlive it. */
static void make_ctx(const rl_scene *scene, const rl_tracer *tracer, const rl__run *run, uint32_t pass,
                     const rl_sampling *sampling, const rl_emitter *e, size_t n, rl_transfer_ctx *ctx)
{
    ctx->scene = scene;
    ctx->tracer = tracer;
    ctx->occluders = rl__tracer_occluders(tracer);
    ctx->sampling = sampling;
    ctx->pass = pass;
    ctx->emitters = e;
    ctx->nemitters = n;
    /* about eight single-precision ulps at the scene's extent */
    ctx->centre = rl__tracer_centre(tracer);
    ctx->eps = 1e-6 * rl__tracer_extent(tracer);
    ctx->margin = 1e-9 * rl__tracer_extent(tracer);
    /* ilf_clock_wall() is the monotonic clock the transfer compares the deadline with */
    ctx->deadline = run->time_budget > 0 ? ilf_clock_wall() + run->time_budget : 0.0;
}

rl_status rl__run_pass(const rl__pass *in, double **measured, rl_pass_stats *st)
{
    const rl_scene *scene = in->scene;
    const rl_cluster *cl = in->cl;
    const rl__run *run = in->run;
    rl_map *maps = in->maps;
    size_t nmaps = in->nmaps, ne = in->ne;
    assert(!(in->with && cl)); /* the ranks exchange the tiles of one set of maps */
    double w0 = ilf_clock_wall(), c0 = ilf_clock_process_cpu();
    memset(st, 0, sizeof *st);
    st->emitters = (uint32_t)ne;
    pass_job job;
    memset(&job, 0, sizeof job);
    job.sets[0] = maps, job.sets[1] = in->with;
    size_t nsets = in->with ? 2 : 1;
    for (size_t set = 0; set < nsets; set++)
        for (size_t m = 0; m < nmaps; m++)
            memset(job.sets[set][m].e_pass, 0,
                   (job.sets[set][m].ncells ? job.sets[set][m].ncells : 1) * sizeof *job.sets[set][m].e_pass);
    rl_sampling sampling = pass_sampling(&run->sampling, in->gather_level_pass);
    make_ctx(scene, in->tracer, run, in->pass, &sampling, in->e, ne, &job.ctx);
    /* a bounce pass of rl__solve() with bounce_rays gathers by first hits, which read each polygon's glow */
    rl_glow *glow = NULL;
    if (in->gather_level_pass > 0 && sampling.bounce_rays > 0) {
        if (rl__glow_new(scene, in->e, ne, run->threads, &glow) != RL_OK)
            return rl__fail(RL_ERR_NOMEM, "out of memory for the bounce pass");
        job.ctx.glow = glow;
    }
    /* the other passes gather each tile from the emitters that may reach it, listed by a tree built once */
    rl_emitter_tree *reach = NULL;
    if (!glow && ne > 0 && job.ctx.occluders) {
        if (rl__emitter_tree_new(in->e, ne, in->tracer, job.ctx.centre, job.ctx.eps, &reach) != RL_OK)
            return RL_ERR_NOMEM;
        job.ctx.reach = reach;
    }
    size_t nall = 0;
    /* a first-hit gather costs its cells alone: small tiles share its cells out evenly between threads, and
     * let a last pass tell of its maps as they finish */
    int first_hit = glow != NULL;
    /* one process's pass whose maps are final as they finish: tell the caller map by map, a map with
     * nothing to gather being completed by a worker, in its place, as one with an empty item */
    int telling = run->maps_ready && run->reporting && !cl;
    work_item *all = make_tiles(job.sets, nsets, nmaps, first_hit ? TILE_FIRST_HIT : TILE_CELLS, first_hit, telling,
                                &nall);
    share sh = {0};
    if (!all || (cl && share_deal(cl, maps, all, nall, *measured, &sh) != 0)) {
        free(all);
        rl__glow_free(glow, scene->npolygons);
        rl__emitter_tree_destroy(reach);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the work list");
    }
    job.items = cl ? sh.mine : all;
    job.nitems = cl ? sh.nmine : nall;
    job.seconds = cl ? sh.seconds : NULL;
    if (cl && cl->next)
        job.claim = cl, job.claim_order = sh.order, job.claimed = sh.claimed;
    if ((telling && tell_begin(&job, run, nmaps, ne) != 0) ||
        (job.claim && pthread_mutex_init(&job.claim_lock, NULL) != 0)) {
        share_free(&sh);
        free(all);
        rl__glow_free(glow, scene->npolygons);
        rl__emitter_tree_destroy(reach);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the work list");
    }
    int rc = ne > 0 ? run_job(&job, run->threads, run, in->base, in->span) : 0;
    if (telling)
        tell_end(&job, rc);
    if (job.claim)
        pthread_mutex_destroy(&job.claim_lock);
    if (job.counters)
        sum_counters(job.counters, run->threads, st);
    free(job.counters);
    st->cpu_seconds = ilf_clock_process_cpu() - c0;
    const char *why = "out of memory";
    /* A failed rank leaves now: the others wait in the exchange until the job is ended (engine.h). */
    if (rc == 0 && cl && cl->next && ne > 0 && (rc = share_owners(cl, &sh, nall)) == -2)
        why = "the exchange of claimed tiles between ranks failed";
    if (rc == 0 && cl && ne > 0 && exchange_tiles(cl, sh.owner, maps, all, nall, &why) != 0)
        rc = -2;
    if (rc == 0 && cl && ne > 0 && share_measure(cl, &sh, nall, measured) != 0)
        rc = -2, why = "the exchange of tile costs between ranks failed";
    if (rc == 0 && cl && sum_stats(cl, st) != 0)
        rc = -2, why = "the exchange of statistics between ranks failed";
    free(all);
    rl__glow_free(glow, scene->npolygons);
    rl__emitter_tree_destroy(reach);
    share_free(&sh);
    if (rc != 0)
        return rl__fail(rc == -2 ? RL_ERR_IO : RL_ERR_NOMEM, "pass %u: %s", in->pass, why);
    size_t cells = 0;
    for (size_t m = 0; m < nmaps; m++)
        cells += maps[m].ncells;
    st->estimated_rmse = cells ? sqrt(st->estimated_rmse / (double)cells) : 0.0;
    summarise_cell_errors(st);
    st->wall_seconds = ilf_clock_wall() - w0;
    return RL_OK;
}

/* What completing a pass's maps takes (complete_map()). */
typedef struct pass_end {
    rl_map *maps;            /* the scene's */
    const rl_map *coarse;    /* the larger cells the pass gathered on, one map per scene map, or NULL */
    const uint8_t *gathered; /* with coarse: the larger cells whose area is gathered on its own, or NULL */
    const size_t *at;        /* with coarse: map m's first larger cell among all the maps' */
    int last;                /* the solve's last pass: the total is all that is kept */
    uint8_t *done;           /* [nmaps]: map m completed */
} pass_end;

/* Completes map m after a pass has gathered its cells: sets the cells the pass left to the larger cells
 * from those (rl__map_interpolate()), adds the pass's irradiance to the total and, but after the last pass,
 * keeps it for the next bounce (a map whose total is its pass array already holds it). It writes map m
 * alone and reads its larger map, so maps may be completed by any thread while the pass still gathers
 * others; what other maps' gathers read of it, e_prev, it changes only between passes. */
static void complete_map(void *user, size_t m)
{
    pass_end *pe = user;
    rl_map *f = &pe->maps[m];
    if (pe->coarse)
        rl__map_interpolate(&pe->coarse[m], pe->gathered ? pe->gathered + pe->at[m] : NULL, f);
    if (f->e_total != f->e_pass)
        for (uint32_t c = 0; c < f->ncells; c++)
            for (int k = 0; k < 3; k++) {
                f->e_total[c][k] += f->e_pass[c][k];
                if (f->e_prev != NULL && !pe->last)
                    f->e_prev[c][k] = f->e_pass[c][k];
            }
    pe->done[m] = 1;
}

/* Completes map m unless the pass did (ilf_parallel_for()'s fn over a pass_end). */
static void complete_rest(void *user, size_t m)
{
    pass_end *pe = user;
    if (!pe->done[m])
        complete_map(pe, m);
}

/* Cells that bounce passes on larger cells gather themselves. The first pass's gather on the larger
 * cells flags those near an occluder (rl_map.near); the cells of the scene's maps that lie in a
 * flagged larger cell or in one of its eight neighbours are then gathered on their own
 * (rl_map.subset), and the others interpolated from the larger cells around them but those
 * (rl__map_mark_direct()), in this and every later bounce pass: the flags are geometry, the same in
 * every pass. */
typedef struct refine {
    uint8_t *near;     /* one flag per larger cell, all maps in order */
    uint8_t *gathered; /* one mark per larger cell whose area is gathered on its own cells, in order */
    uint8_t *subset;   /* one mark per cell of the scene's maps, in order */
    size_t nnear;
    uint64_t marked; /* cells marked in subset */
    int ready;       /* subset filled (after the first bounce pass's larger gather) */
    double *measured;
    rl_map *coarse;
    size_t ncoarse;
} refine;

/* Allocates rf's flags and points each larger map's near at its share. @return 0 or -1 (memory). */
static int refine_new(rl_map *coarse, size_t ncoarse, const rl_map *maps, refine *rf)
{
    size_t nc = 0, nf = 0;
    for (size_t m = 0; m < ncoarse; m++)
        nc += coarse[m].ncells, nf += maps[m].ncells;
    rf->near = calloc(nc ? nc : 1, 1);
    rf->gathered = calloc(nc ? nc : 1, 1);
    rf->subset = calloc(nf ? nf : 1, 1);
    if (!rf->near || !rf->gathered || !rf->subset)
        return -1;
    rf->nnear = nc;
    rf->coarse = coarse;
    rf->ncoarse = ncoarse;
    for (size_t m = 0, at = 0; m < ncoarse; at += coarse[m++].ncells)
        coarse[m].near = rf->near + at;
    return 0;
}

static void refine_free(refine *rf, rl_map *maps, size_t nmaps)
{
    for (size_t m = 0; m < nmaps; m++)
        maps[m].subset = NULL;
    for (size_t m = 0; m < rf->ncoarse; m++)
        rf->coarse[m].near = NULL;
    free(rf->near);
    free(rf->gathered);
    free(rf->subset);
    free(rf->measured);
}

/* The marking of one map's cells (ilf_parallel_for()'s fn): map m's cells lie from at[m] among all the maps', its
 * larger cells from cat[m]; it marks marked[m] of them. */
typedef struct mark_job {
    rl_map *maps;
    refine *rf;
    size_t *at, *cat;
    uint32_t *marked;
} mark_job;

/* Marks the cells of map m that gather themselves, their count in marked[m] (ilf_parallel_for()'s fn). */
static void mark_map(void *user, size_t m)
{
    mark_job *j = user;
    j->marked[m] = rl__map_mark_direct(&j->rf->coarse[m], &j->maps[m], j->rf->gathered + j->cat[m],
                                       j->rf->subset + j->at[m]);
}

/* Marks the cells that gather themselves from the larger maps' flags (summed over ranks first: each rank
 * gathered its own tiles), a map at a time on up to threads threads. @return 0, -1 (out of memory) or
 * -2 (the exchange failed). */
static int refine_mark(const rl_cluster *cl, unsigned threads, rl_map *maps, size_t nmaps, refine *rf)
{
    if (cl) {
        double *v = malloc((rf->nnear ? rf->nnear : 1) * sizeof *v);
        if (!v)
            return -1;
        for (size_t k = 0; k < rf->nnear; k++)
            v[k] = rf->near[k];
        int rc = cl->sum(cl->user, v, rf->nnear);
        for (size_t k = 0; k < rf->nnear; k++)
            rf->near[k] = v[k] > 0;
        free(v);
        if (rc != 0)
            return -2;
    }
    size_t n = nmaps ? nmaps : 1;
    mark_job j = {maps, rf, malloc(n * sizeof *j.at), malloc(n * sizeof *j.cat), malloc(n * sizeof *j.marked)};
    if (!j.at || !j.cat || !j.marked) {
        free(j.at);
        free(j.cat);
        free(j.marked);
        return -1;
    }
    for (size_t m = 0, at = 0, cat = 0; m < nmaps; at += maps[m].ncells, cat += rf->coarse[m++].ncells)
        j.at[m] = at, j.cat[m] = cat;
    ilf_parallel_for(threads, nmaps, mark_map, &j);
    for (size_t m = 0; m < nmaps; m++) {
        rf->marked += j.marked[m];
        maps[m].subset = rf->subset + j.at[m];
    }
    for (size_t m = 0; m < rf->ncoarse; m++)
        rf->coarse[m].near = NULL; /* flagged once: later passes only read the marks */
    rf->ready = 1;
    free(j.at);
    free(j.cat);
    free(j.marked);
    return 0;
}

/* Gathers pass p on the marked cells of the scene's maps (marking them first if need be), its statistics in
 * *more (zero when no cell is marked; add_refined() adds them to the pass's). @return RL_OK or the failure. */
static rl_status refine_pass(const rl_scene *scene, rl_solution *s, const rl_cluster *cl, const rl__run *run,
                             uint32_t p, const rl_emitter *e, size_t ne, double base, double span, refine *rf,
                             rl_pass_stats *more)
{
    memset(more, 0, sizeof *more);
    int rc = rf->ready ? 0 : refine_mark(cl, run->threads, s->maps, s->nmaps, rf);
    if (rc == -1)
        return rl__fail(RL_ERR_NOMEM, "pass %u: out of memory marking the bounce cells", p);
    if (rc == -2)
        return rl__fail(RL_ERR_IO, "pass %u: the exchange of bounce cell flags between ranks failed", p);
    if (rf->marked == 0)
        return RL_OK;
    rl__pass in = {.scene = scene, .tracer = s->tracer, .cl = cl, .run = run, .pass = p, .gather_level_pass = p,
                   .maps = s->maps, .nmaps = s->nmaps, .e = e, .ne = ne, .base = base, .span = span};
    return rl__run_pass(&in, &rf->measured, more);
}

/* Adds the statistics of a pass's refinement (refine_pass()) to the pass's, to. */
static void add_refined(rl_pass_stats *to, const rl_pass_stats *more, const refine *rf)
{
    to->wall_seconds += more->wall_seconds;
    to->cpu_seconds += more->cpu_seconds;
    to->samples += more->samples;
    to->rays_cast += more->rays_cast;
    to->rays_kept += more->rays_kept;
    for (unsigned b = 0; b < RL_CELL_ERROR_BINS; b++)
        to->cell_error_histogram[b] += more->cell_error_histogram[b];
    summarise_cell_errors(to);
    if (rf->marked > 0)
        to->cells_direct = rf->marked;
}

/* @return the bytes of the irradiance arrays of n maps not yet settled: one array a map, or three for a map
 * that re-emits (rl__map_settle() makes them one). */
static uint64_t accumulator_bytes(const rl_map *maps, size_t n)
{
    uint64_t bytes = 0;
    for (size_t m = 0; m < n; m++)
        bytes += (uint64_t)maps[m].ncells * sizeof *maps[m].e_pass * (maps[m].e_prev ? 3u : 1u);
    return bytes;
}

void rl_solution_destroy(rl_solution *s)
{
    if (!s)
        return;
    rl__maps_free(s->maps, s->nmaps);
    rl__tracer_destroy(s->tracer);
    rl__slab_tables_destroy(s->slab_tables, s->scene->nlightfields);
    free(s->polygon_map);
    free(s->passes);
    free(s);
}

rl_status rl__solve(const rl_scene *scene, const rl_cluster *cl, const rl__run *run, uint32_t passes, double span,
                    rl_solution **out)
{
    *out = NULL;
    rl_solution *s = calloc(1, sizeof *s);
    if (!s)
        return rl__fail(RL_ERR_NOMEM, "out of memory");
    s->scene = scene;
    rl_status st = rl__maps_build(scene, run->cell_size, run->sampling.bounces > 0, run->threads, &s->maps, &s->nmaps);
    if (st == RL_OK)
        st = rl__tracer_new(scene, run->threads, &s->tracer);
    if (st == RL_OK && (s->slab_tables = rl__slab_tables_new(scene)) == NULL)
        st = rl__fail(RL_ERR_NOMEM, "out of memory for the light fields' tables");
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
    /* room for one bounce emitter per map only when bounce passes follow (an emitter is about 5 KB:
     * 14.5 MB for the classroom's 3,031 maps) */
    rl_emitter *e = rl__primary_emitters(scene, s->slab_tables, passes > 1 ? s->nmaps : 0, &ne);
    if (!e) {
        rl_solution_destroy(s);
        return rl__fail(RL_ERR_NOMEM, "out of memory for emitters");
    }
    /* bounce passes gather on coarser cells when asked: indirect light is smooth */
    rl_map *coarse = NULL;
    size_t ncoarse = 0;
    /* by default 4 for the first-hit gather, which gathers the cells near occluders on their own; 2 for
     * the methods' own, which interpolates everywhere (as before the first-hit gather's flags) */
    uint32_t factor = bounce_factor(&run->sampling);
    if (passes > 1 && factor > 1)
        st = rl__maps_build_sized(scene, run->cell_size * factor, run->threads, &coarse, &ncoarse);
    assert(!coarse || ncoarse == s->nmaps); /* one map per receiving polygon, in order, at any cell size */
    s->accumulator_bytes = accumulator_bytes(s->maps, s->nmaps) + accumulator_bytes(coarse, ncoarse);
    refine rf = {0};
    if (st == RL_OK && coarse && run->sampling.bounce_rays > 0 && refine_new(coarse, ncoarse, s->maps, &rf) != 0)
        st = rl__fail(RL_ERR_NOMEM, "out of memory for the bounce cells");
    /* per-tile CPU times of the last pass: bounce passes after the first repeat its tiles and emitters */
    double *measured = NULL;
    uint8_t *done = st == RL_OK ? malloc(s->nmaps ? s->nmaps : 1) : NULL;
    size_t *coarse_at = st == RL_OK && coarse ? malloc((ncoarse ? ncoarse : 1) * sizeof *coarse_at) : NULL;
    if (st == RL_OK && (!done || (coarse && !coarse_at)))
        st = rl__fail(RL_ERR_NOMEM, "out of memory for the maps' passes");
    for (size_t m = 0, at = 0; coarse_at && m < ncoarse; at += coarse[m++].ncells)
        coarse_at[m] = at;
    /* each pass's share of [0, span) of the progress, by its expected work */
    double *work = st == RL_OK ? calloc(passes + 1, sizeof *work) : NULL;
    if (st == RL_OK && !work)
        st = rl__fail(RL_ERR_NOMEM, "out of memory for the maps' passes");
    double all_work = work ? rl__solve_work(scene, run, passes, work) : 0.0, work_before = 0.0;
    int told = 0, telling = 0; /* the caller was told of every map; of some, maybe */
    for (uint32_t p = 0; p < passes && st == RL_OK; p++) {
        /* Cells near occluders are gathered on their own besides the larger cells once marked, unless the
         * marking found none: in the first bounce pass, which marks them, after the larger cells; later,
         * for one process, in the same job, each map's larger cells and its own together, so that the maps
         * finish one after another through the whole job (several ranks run the two jobs one after the
         * other, as they exchange the tiles of one set of maps at a time). */
        int gather_coarse = p > 0 && coarse, refining = gather_coarse && rf.near && !(rf.ready && rf.marked == 0);
        int together = refining && rf.ready && !cl, apart = refining && !together;
        double base = all_work > 0 ? span * work_before / all_work : span * p / passes;
        double part = all_work > 0 ? span * work[p] / all_work : span / passes;
        work_before += work[p];
        if (p > 0)
            ne = rl__append_bounce_emitters(scene, s->maps, s->nmaps, e, 0);
        if (p < 2) {
            free(measured);
            measured = NULL;
        }
        if (apart)
            part *= 0.75; /* the rest for the cells gathered themselves */
        pass_end pe = {s->maps, gather_coarse ? coarse : NULL, gather_coarse && rf.near ? rf.gathered : NULL,
                       coarse_at, p + 1 == passes, done};
        memset(done, 0, s->nmaps);
        /* The last pass of one process completes each map once the last of its own gathers has finished,
         * and tells the caller of it then, so that the caller may write it while the engine goes on; the
         * other passes complete every map at their end. */
        rl__run gather_run = *run, refine_run = *run;
        rl__run *last_run = apart ? &refine_run : &gather_run;
        if (pe.last && run->maps_ready && !cl) {
            last_run->reporting = s;
            last_run->finish = complete_map;
            last_run->finish_user = &pe;
            telling = 1;
        }
        rl__pass in = {.scene = scene, .tracer = s->tracer, .cl = cl, .run = &gather_run, .pass = p,
                       .gather_level_pass = p, .maps = gather_coarse ? coarse : s->maps,
                       .nmaps = gather_coarse ? ncoarse : s->nmaps, .with = together ? s->maps : NULL, .e = e,
                       .ne = ne, .base = base, .span = part};
        st = rl__run_pass(&in, &measured, &s->passes[p]);
        if (st == RL_OK && together)
            s->passes[p].cells_direct = rf.marked;
        if (st == RL_OK && apart) {
            rl_pass_stats refined;
            st = refine_pass(scene, s, cl, &refine_run, p, e, ne, base + part, part / 3, &rf, &refined);
            add_refined(&s->passes[p], &refined, &rf);
        }
        /* the last run told of every map if it ran (a refinement with no cell to gather runs none) */
        told = st == RL_OK && last_run->reporting != NULL && (last_run == &gather_run || rf.marked > 0);
        if (st == RL_OK)
            ilf_parallel_for(run->threads, s->nmaps, complete_rest, &pe);
        s->npasses = p + 1;
    }
    refine_free(&rf, s->maps, s->nmaps);
    rl__maps_free(coarse, ncoarse);
    free(measured);
    free(work);
    free(e);
    free(done);
    free(coarse_at);
    if (st != RL_OK) {
        if (telling) /* maps may have been told: withdrawn before they are freed */
            run->maps_ready(run->maps_ready_user, NULL, 0);
        rl_solution_destroy(s);
        return st;
    }
    for (size_t m = 0; m < s->nmaps; m++)
        rl__map_settle(&s->maps[m]);
    if (run->maps_ready && !told)
        run->maps_ready(run->maps_ready_user, s, s->nmaps);
    *out = s;
    return RL_OK;
}

const rl_cluster *rl__check_cluster(const rl_cluster *cl, rl_status *st)
{
    *st = RL_OK;
    if (cl && (cl->ranks == 0 || cl->rank >= cl->ranks || !cl->allgather || !cl->sum))
        *st = rl__fail(RL_ERR_ARG, "cluster: rank %u of %u, or a NULL callback", cl->rank, cl->ranks);
    return cl && cl->ranks > 1 ? cl : NULL;
}

rl_status rl_relight_cluster(const rl_scene *scene, const rl_cluster *cluster, const rl_job *job, rl_solution **out)
{
    if (!scene || !out)
        return rl__fail(RL_ERR_ARG, "rl_relight: NULL argument");
    *out = NULL;
    rl__run run;
    rl_status st = rl__job_resolve(scene, job, &run);
    const rl_cluster *cl = st == RL_OK ? rl__check_cluster(cluster, &st) : NULL;
    if (st == RL_OK)
        st = rl__solve(scene, cl, &run, run.sampling.bounces + 1, 1.0, out);
    if (st == RL_OK && run.progress)
        run.progress(run.user, 1.0);
    return st;
}

rl_status rl_relight(const rl_scene *scene, const rl_job *job, rl_solution **out)
{
    return rl_relight_cluster(scene, NULL, job, out);
}
