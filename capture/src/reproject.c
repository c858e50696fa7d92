/*
 * reproject.c - depth correction (cap_reproject_field and cap_reproject_slab
 * in capture/reproject.h): every ray of a proxy slab is traced back, as a
 * line, to each captured slab's plane, and the captured radiance is looked
 * up there, either by asking each neighbouring probe for the direction
 * towards the proxy point (depth-corrected) or along the ray's own direction
 * (plain); the captures that cover the ray are blended, each weighted by how
 * finely it resolves the ray (resolution_weight()).
 *
 * Each stored value is a box filter over its cell and its solid angle: a
 * value sampled at the cell centre alone would, where the field has an
 * asymmetric edge inside the cell, misstate the slab's power (by 8% for a
 * 20 cm emitter on 2.5 cm cells, measured), whereas the cell mean keeps it.
 *
 * Invariants: the captured slab is only queried (lfio queries on a const
 * slab may run concurrently), the new slab is filled by the runner; each
 * stored value is a convex combination of captured values, hence finite and
 * >= 0; coverage is summed per position into its own slot and added up in
 * position order afterwards, so it does not depend on the thread count;
 * each sample's coverage byte is written by the one worker that owns its
 * position.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture/projection.h"
#include "capture/reproject.h"
#include "internal.h"
#include "lfio/partition.h"
#include "ilf/limits.h"

#define DEFAULT_STRATA 2u
#define MAX_STRATA ILF_REPROJECT_MAX_STRATA
/* Below this |t| (metres) the proxy point lies on the capture plane: the plain lookup is used. */
#define ON_PLANE 1e-9

/* One captured slab as the lookups see it. */
typedef struct capture_view {
    const lfio_slab *cap;          /* the captured slab */
    const lfio_slab_desc *cd;      /* its description */
    double cap_e3[3];              /* its normal */
    double angle;                  /* the side of its mean solid angle, sqrt(2 pi / 4n^2), radians */
} capture_view;

/* What the workers share. */
typedef struct reproject_job {
    capture_view *views;           /* [count] */
    size_t count;
    const lfio_slab_desc *td;      /* the proxy slab's description */
    cap_reproject_mode mode;
    uint32_t strata;               /* s: rays per (cell, solid angle) = s^2 */
    uint32_t samples;              /* s^2 */
    uint64_t dirs;                 /* 4n^2 of the proxy slab */
    double *ray_dir;               /* [dirs][samples][3] world directions */
    double *ray_weight;            /* [dirs][samples] weights within a solid angle (sum 1) */
    double *etendue;               /* [dirs] projected solid angle about the proxy's e3 */
    double *covered_share;         /* [positions] covered etendue */
    uint64_t *covered_rays;        /* [positions] */
    uint8_t *covered;              /* NULL, or [dirs][positions]: 1 if some ray of the sample is covered */
} reproject_job;

/* ------------------------------------------------------------ lookups */

/* Captured radiance at (s, t) in world direction w. Interpolation can round to about -1e-20 where
 * the true value is 0; such values are stored as 0, keeping every value >= 0. */
static void captured_radiance(const capture_view *cv, double s, double t, const double w[3], double out[3])
{
    float rgb[3] = {0.0f, 0.0f, 0.0f};
    lfio_slab_radiance_interp(cv->cap, s, t, w, rgb);
    for (int c = 0; c < 3; c++)
        out[c] = rgb[c] > 0.0f ? rgb[c] : 0.0;
}

/* Bilinear cell of position centres around coordinate s of a row of count positions: index and weight of the upper. */
static void cell_of(double s, uint32_t count, uint32_t *lo, double *frac)
{
    double f = s * count - 0.5;
    if (f <= 0.0 || count == 1) {
        *lo = 0;
        *frac = 0.0;
    } else if (f >= count - 1) {
        *lo = count - 1;
        *frac = 0.0;
    } else {
        *lo = (uint32_t)f;
        *frac = f - *lo;
    }
}

/* Depth-corrected radiance: each probe around p is asked for the direction from y (= p - t*w) to itself. */
static void depth_corrected(const capture_view *cv, double s, double t_st, const double p[3], double t,
                            const double w[3], double out[3])
{
    uint32_t i0, j0;
    double fs, ft, total = 0.0;
    cell_of(s, cv->cd->nu, &i0, &fs);
    cell_of(t_st, cv->cd->nv, &j0, &ft);
    out[0] = out[1] = out[2] = 0.0;
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++) {
            double weight = (a ? fs : 1.0 - fs) * (b ? ft : 1.0 - ft);
            if (weight <= 0.0)
                continue;
            uint32_t i = i0 + (uint32_t)a, j = j0 + (uint32_t)b;
            double x[3], wk[3], value[3];
            lfio_slab_position(cv->cap, i, j, x);
            for (int c = 0; c < 3; c++)
                wk[c] = w[c] + (x[c] - p[c]) / t;
            if (!cap__normalise(wk) || a3_dot(wk, cv->cap_e3) <= 0.0)
                continue;
            captured_radiance(cv, (i + 0.5) / cv->cd->nu, (j + 0.5) / cv->cd->nv, wk, value);
            for (int c = 0; c < 3; c++)
                out[c] += weight * value[c];
            total += weight;
        }
    if (total > 0.0)
        for (int c = 0; c < 3; c++)
            out[c] /= total;
}

/*
 * How finely capture cv resolves a ray that crosses its plane at cosine `cosine` after running |t| metres
 * from the proxy: one of its solid angles spans about |t| * angle metres across the ray at the proxy, so
 * the weight is the inverse of that patch's area, times the cosine (the share of the plane's probes the
 * ray's neighbourhood meets). A ray on the plane itself (|t| below ON_PLANE) is resolved exactly.
 */
static double resolution_weight(const capture_view *cv, double t, double cosine)
{
    double blur = fmax(fabs(t), ON_PLANE) * cv->angle;
    return cosine / (blur * blur);
}

/* Radiance of the line through y along w, from capture cv. @return 1 and *weight (resolution_weight()) if
 * the capture covers it, else 0 (out = 0). */
static int trace_back(const reproject_job *job, const capture_view *cv, const double y[3], const double w[3],
                      double out[3], double *weight)
{
    out[0] = out[1] = out[2] = 0.0;
    double denom = a3_dot(w, cv->cap_e3);
    if (!(denom > 1e-12))
        return 0;
    double to_plane[3] = {cv->cd->origin[0] - y[0], cv->cd->origin[1] - y[1], cv->cd->origin[2] - y[2]};
    double t = a3_dot(to_plane, cv->cap_e3) / denom;
    double p[3] = {y[0] + t * w[0], y[1] + t * w[1], y[2] + t * w[2]};
    double s, t_st;
    lfio_slab_locate(cv->cap, p, &s, &t_st, NULL);
    if (!(s >= 0.0 && s <= 1.0 && t_st >= 0.0 && t_st <= 1.0))
        return 0;
    if (job->mode == CAP_REPROJECT_PLAIN || fabs(t) < ON_PLANE) {
        captured_radiance(cv, s, t_st, w, out);
    } else {
        depth_corrected(cv, s, t_st, p, t, w, out);
    }
    *weight = resolution_weight(cv, t, denom);
    return 1;
}

/* Radiance of the line through y along w: the blend of every capture that covers it, by resolution_weight().
 * @return 1 if some capture covers it, else 0 (out = 0). */
static int trace_all(const reproject_job *job, const double y[3], const double w[3], double out[3])
{
    double total = 0.0;
    out[0] = out[1] = out[2] = 0.0;
    for (size_t k = 0; k < job->count; k++) {
        double value[3], weight = 0.0;
        if (!trace_back(job, &job->views[k], y, w, value, &weight))
            continue;
        for (int c = 0; c < 3; c++)
            out[c] += weight * value[c];
        total += weight;
    }
    if (!(total > 0.0))
        return 0;
    for (int c = 0; c < 3; c++)
        out[c] /= total;
    return 1;
}

/* ------------------------------------------------------------ positions */

/* Start of ray k in cell (i, j): the centre of sub-cell k of a strata x strata split of the cell. */
static void ray_origin(const reproject_job *job, uint32_t i, uint32_t j, uint32_t k, double y[3])
{
    const lfio_slab_desc *td = job->td;
    double s = (i + (k % job->strata + 0.5) / job->strata) / td->nu;
    double t = (j + (k / job->strata + 0.5) / job->strata) / td->nv;
    for (int c = 0; c < 3; c++)
        y[c] = td->origin[c] + s * td->u[c] + t * td->v[c];
}

/* cap__position_fn: for each solid angle, the mean over its rays, ray k leaving sub-cell k of cell
 * (i, j) along sub-direction k: a box filter over the cell and the solid angle together. */
static cap_status reproject_position(void *arg, uint32_t i, uint32_t j, float *rgb)
{
    reproject_job *job = arg;
    double origins[MAX_STRATA * MAX_STRATA][3];
    for (uint32_t k = 0; k < job->samples; k++)
        ray_origin(job, i, j, k, origins[k]);
    double share = 0.0;
    uint64_t rays = 0;
    const size_t slot = (size_t)j * job->td->nu + i, positions = (size_t)job->td->nu * job->td->nv;
    for (uint64_t id = 0; id < job->dirs; id++) {
        double sum[3] = {0.0, 0.0, 0.0};
        uint8_t any = 0;
        for (uint32_t k = 0; k < job->samples; k++) {
            double value[3], weight = job->ray_weight[id * job->samples + k];
            if (!trace_all(job, origins[k], &job->ray_dir[3 * (id * job->samples + k)], value))
                continue;
            for (int c = 0; c < 3; c++)
                sum[c] += weight * value[c];
            share += weight * job->etendue[id];
            rays++;
            any = 1;
        }
        for (int c = 0; c < 3; c++)
            rgb[3 * id + c] = (float)sum[c];
        if (job->covered != NULL)
            job->covered[id * positions + slot] = any;
    }
    job->covered_share[slot] = share;
    job->covered_rays[slot] = rays;
    return CAP_OK;
}

/* ------------------------------------------------------------ set-up */

/* Fills the world directions and weights of every solid angle's rays, and its etendue. */
static void fill_rays(reproject_job *job, const lfio_slab *target, uint32_t strata)
{
    const uint32_t n = job->td->n;
    const double pole[3] = {0.0, 0.0, 1.0};
    for (uint64_t id = 0; id < job->dirs; id++) {
        double *dirs = &job->ray_dir[3 * id * job->samples];
        cap_partition_samples(n, id, strata, dirs, &job->ray_weight[id * job->samples]);
        for (uint32_t k = 0; k < job->samples; k++) {
            double local[3] = {dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]};
            lfio_slab_to_world(target, local, &dirs[3 * k]);
            cap__normalise(&dirs[3 * k]);
        }
        job->etendue[id] = lfio_part_projected_solid_angle(n, id, pole);
    }
}

static void job_free(reproject_job *job)
{
    free(job->views);
    free(job->ray_dir);
    free(job->ray_weight);
    free(job->etendue);
    free(job->covered_share);
    free(job->covered_rays);
    memset(job, 0, sizeof *job);
}

/* Fills cv for captured slab cap. */
static void view_init(capture_view *cv, const lfio_slab *cap)
{
    const double pole[3] = {0.0, 0.0, 1.0};
    cv->cap = cap;
    cv->cd = lfio_slab_get_desc(cap);
    lfio_slab_to_world(cap, pole, cv->cap_e3);
    cap__normalise(cv->cap_e3);
    cv->angle = sqrt(2.0 * ILF_PI / (4.0 * (double)cv->cd->n * cv->cd->n));
}

static cap_status job_init(reproject_job *job, const lfio_slab *const *captured, size_t count,
                           const lfio_slab *target, const cap_reproject_options *o)
{
    uint32_t strata = o->strata == 0 ? DEFAULT_STRATA : o->strata;
    memset(job, 0, sizeof *job);
    job->td = lfio_slab_get_desc(target);
    job->mode = o->mode;
    job->covered = o->covered;
    job->strata = strata;
    job->samples = strata * strata;
    job->dirs = lfio_slab_dir_count(target);
    job->views = calloc(count, sizeof *job->views);
    job->count = count;
    for (size_t k = 0; job->views != NULL && k < count; k++)
        view_init(&job->views[k], captured[k]);
    size_t positions = (size_t)job->td->nu * job->td->nv;
    job->ray_dir = malloc(job->dirs * job->samples * 3 * sizeof(double));
    job->ray_weight = malloc(job->dirs * job->samples * sizeof(double));
    job->etendue = malloc(job->dirs * sizeof(double));
    job->covered_share = calloc(positions, sizeof(double));
    job->covered_rays = calloc(positions, sizeof(uint64_t));
    if (!job->views || !job->ray_dir || !job->ray_weight || !job->etendue || !job->covered_share ||
        !job->covered_rays) {
        /* the message first: job_free() releases what names the slab */
        cap_status st = cap__fail(CAP_ERR_NOMEM, "out of memory for reprojecting onto '%s'", job->td->name);
        job_free(job);
        return st;
    }
    fill_rays(job, target, strata);
    return CAP_OK;
}

/* Sums the per-position coverage into *coverage. */
static void sum_coverage(const reproject_job *job, cap_coverage *coverage)
{
    size_t positions = (size_t)job->td->nu * job->td->nv;
    double total = 0.0, share = 0.0;
    for (uint64_t id = 0; id < job->dirs; id++)
        total += job->etendue[id];
    coverage->covered = 0;
    for (size_t k = 0; k < positions; k++) {
        share += job->covered_share[k];
        coverage->covered += job->covered_rays[k];
    }
    coverage->rays = (uint64_t)positions * job->dirs * job->samples;
    coverage->fraction = total > 0.0 ? share / (total * (double)positions) : 0.0;
}

static cap_status check_options(const lfio_slab *const *captured, size_t count, const lfio_slab_desc *target,
                                const cap_reproject_options *o, lfio_slab **out)
{
    if (captured == NULL || target == NULL || out == NULL)
        return cap__fail(CAP_ERR_ARG, "cap_reproject_field: a required argument is NULL");
    if (count == 0 || count > CAP_CAPTURED_MAX)
        return cap__fail(CAP_ERR_ARG, "cap_reproject_field: %zu captured slabs; 1 to %u are accepted", count,
                         CAP_CAPTURED_MAX);
    for (size_t k = 0; k < count; k++) {
        if (captured[k] == NULL)
            return cap__fail(CAP_ERR_ARG, "cap_reproject_field: captured slab %zu is NULL", k);
        if (lfio_slab_get_desc(captured[k])->units != lfio_slab_get_desc(captured[0])->units)
            return cap__fail(CAP_ERR_ARG, "cap_reproject_field: captured slabs '%s' and '%s' have different units",
                             lfio_slab_get_desc(captured[0])->name, lfio_slab_get_desc(captured[k])->name);
    }
    if (o->mode != CAP_REPROJECT_DEPTH && o->mode != CAP_REPROJECT_PLAIN)
        return cap__fail(CAP_ERR_ARG, "cap_reproject_field: unknown mode %d", (int)o->mode);
    if (o->strata > MAX_STRATA)
        return cap__fail(CAP_ERR_ARG, "cap_reproject_field: %u strata per axis; at most %u", o->strata, MAX_STRATA);
    return CAP_OK;
}

cap_status cap_reproject_field(const lfio_slab *const *captured, size_t count, const lfio_slab_desc *target,
                               const cap_reproject_options *o, lfio_slab **out, cap_coverage *coverage)
{
    static const cap_reproject_options defaults = {CAP_REPROJECT_DEPTH, 0, 0, NULL, NULL, NULL};
    if (out != NULL)
        *out = NULL;
    if (o == NULL)
        o = &defaults;
    cap_status st = check_options(captured, count, target, o, out);
    if (st != CAP_OK)
        return st;
    lfio_slab_desc d = *target;
    d.units = lfio_slab_get_desc(captured[0])->units;
    /* the smallest threshold: the mask then rules out no direction that one of the captures keeps */
    d.mask_threshold = lfio_slab_get_desc(captured[0])->mask_threshold;
    for (size_t k = 1; k < count; k++)
        d.mask_threshold = fminf(d.mask_threshold, lfio_slab_get_desc(captured[k])->mask_threshold);
    lfio_slab *slab = NULL;
    lfio_status ls = lfio_slab_new(&d, &slab);
    if (ls != LFIO_OK)
        return cap__fail(ls == LFIO_ERR_NOMEM ? CAP_ERR_NOMEM : CAP_ERR_ARG, "proxy '%s': %s", d.name, lfio_errmsg());
    reproject_job job;
    memset(&job, 0, sizeof job);
    st = job_init(&job, captured, count, slab, o);
    if (st == CAP_OK)
        st = cap__run_positions(slab, o->threads, reproject_position, &job, o->progress, o->progress_user);
    if (st == CAP_OK && coverage != NULL)
        sum_coverage(&job, coverage);
    if (st != CAP_OK) {
        lfio_slab_destroy(slab);
        slab = NULL;
    }
    job_free(&job);
    *out = slab;
    return st;
}

cap_status cap_reproject_slab(const lfio_slab *captured, const lfio_slab_desc *target,
                              const cap_reproject_options *o, lfio_slab **out, cap_coverage *coverage)
{
    return cap_reproject_field(&captured, 1, target, o, out, coverage);
}
