/*
 * capture.c - a whole capture (cap_capture_run in capture/capture.h): after
 * bounding the samples it will read (budget.c), for every plane of the
 * manifest, one slab: for every grid position, read and
 * merge its images (merge.c), box-filter them onto the slab's hemisphere
 * (resample.c), store the result (runner.c), then check energy at every
 * position and gather the plane's report into the capture's.
 *
 * Invariants: per-position results (repair counts, energies, statistics)
 * go to slots indexed by position, written only by the worker that owns
 * the position, and are read only after every worker has finished; so the
 * report, like the slab, does not depend on the thread count. On failure
 * nothing is returned but the status and message.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "probe.h"

/* What the workers share: the plane, the slab frame, and per-position result slots. */
typedef struct capture_job {
    const cap_manifest *m;
    const cap__plane *pl;
    uint32_t plane;         /* its index */
    double frame[9];        /* rows e1, e2, e3 of the slab frame */
    size_t *first_image;    /* [positions]: index of the position's first image in repairs */
    cap_repair *repairs;    /* [images of the plane] */
    double *energy;         /* [positions][3]: E_image */
    uint64_t *interpolated; /* [positions] */
    uint64_t *unmerged;     /* [positions] */
    uint32_t *subdivision;  /* [positions] */
} capture_job;

/* Rows e1 = u/|u|, e2 = v/|v|, e3 = e1 x e2 of the slab frame of d. */
static void slab_frame(const lfio_slab_desc *d, double frame[9])
{
    for (int a = 0; a < 3; a++) {
        frame[a] = d->u[a];
        frame[3 + a] = d->v[a];
    }
    cap__normalise(&frame[0]);
    cap__normalise(&frame[3]);
    a3_cross(&frame[0], &frame[3], &frame[6]);
}

/* cap__position_fn: one position, from its images to rgb. */
static cap_status capture_position(void *arg, uint32_t i, uint32_t j, float *rgb)
{
    capture_job *job = arg;
    const lfio_slab_desc *d = &job->pl->desc;
    size_t k = (size_t)j * d->nu + i;
    const cap__entry *e = &job->pl->entries[k];
    cap__hdr hdr;
    cap_status st = cap__load_position(job->m, e, i, j, &hdr, &job->repairs[job->first_image[k]],
                                       &job->unmerged[k]);
    if (st != CAP_OK)
        return st;
    cap__resample_stats stats;
    st = cap__resample(&hdr, e->projection, e->R, job->frame, d->n, rgb, &stats);
    free(hdr.rgb);
    if (st != CAP_OK)
        return cap__fail_prefix(st, "%s: %s", job->m->path, e->element);
    memcpy(&job->energy[3 * k], stats.energy, sizeof stats.energy);
    job->interpolated[k] = stats.interpolated;
    job->subdivision[k] = stats.subdivision;
    return CAP_OK;
}

static void job_free(capture_job *job)
{
    free(job->first_image);
    free(job->repairs);
    free(job->energy);
    free(job->interpolated);
    free(job->unmerged);
    free(job->subdivision);
}

static cap_status job_init(capture_job *job, const cap_manifest *m, uint32_t plane)
{
    const cap__plane *pl = &m->planes[plane];
    size_t positions = (size_t)pl->desc.nu * pl->desc.nv;
    memset(job, 0, sizeof *job);
    job->m = m;
    job->pl = pl;
    job->plane = plane;
    slab_frame(&pl->desc, job->frame);
    job->first_image = malloc(positions * sizeof *job->first_image);
    job->repairs = calloc(pl->images, sizeof *job->repairs);
    job->energy = calloc(3 * positions, sizeof *job->energy);
    job->interpolated = calloc(positions, sizeof *job->interpolated);
    job->unmerged = calloc(positions, sizeof *job->unmerged);
    job->subdivision = calloc(positions, sizeof *job->subdivision);
    if (!job->first_image || !job->repairs || !job->energy || !job->interpolated || !job->unmerged ||
        !job->subdivision) {
        job_free(job);
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory for %zu positions", m->path, positions);
    }
    size_t next = 0;
    for (size_t k = 0; k < positions; k++) {
        job->first_image[k] = next;
        next += pl->entries[k].count;
    }
    return CAP_OK;
}

/* ------------------------------------------------------------ report */

/* Relative energy difference at one position, against the brightest channel of E_image. */
static double energy_error(const double image[3], const double field[3])
{
    double top = fmax(image[0], fmax(image[1], image[2]));
    double diff = fmax(fabs(field[0] - image[0]), fmax(fabs(field[1] - image[1]), fabs(field[2] - image[2])));
    if (diff <= 1e-30)
        return 0.0;
    return top > 0.0 ? diff / top : 1.0;
}

/* Compares E_field (lfio_slab_irradiance at each position) with E_image; keeps the worst over the planes so far. */
static void check_energy(const capture_job *job, const lfio_slab *slab, cap_report *r)
{
    const lfio_slab_desc *d = &job->pl->desc;
    for (uint32_t j = 0; j < d->nv; j++)
        for (uint32_t i = 0; i < d->nu; i++) {
            const double *image = &job->energy[3 * ((size_t)j * d->nu + i)];
            double field[3];
            lfio_slab_irradiance(slab, (i + 0.5) / d->nu, (j + 0.5) / d->nv, field);
            double err = energy_error(image, field);
            if (err > r->energy_error) {
                r->energy_error = err;
                r->energy_plane = job->plane;
                r->energy_i = i;
                r->energy_j = j;
                memcpy(r->energy_image, image, sizeof r->energy_image);
                memcpy(r->energy_field, field, sizeof r->energy_field);
            }
        }
}

/* Appends the plane's repairs that did something to the report's, in position then bracket order. */
static cap_status collect_repairs(const capture_job *job, cap_report *r)
{
    size_t count = 0;
    for (uint64_t k = 0; k < job->pl->images; k++) {
        const cap_repair *x = &job->repairs[k];
        r->negative += x->negative;
        r->nan += x->nan;
        r->infinite += x->infinite;
        count += x->negative + x->nan + x->infinite > 0;
    }
    if (count == 0)
        return CAP_OK;
    cap_repair *grown = realloc(r->repairs, (r->repair_count + count) * sizeof *grown);
    if (grown == NULL)
        return cap__fail(CAP_ERR_NOMEM, "out of memory for the capture report");
    r->repairs = grown;
    for (uint64_t k = 0; k < job->pl->images; k++) {
        const cap_repair *x = &job->repairs[k];
        if (x->negative + x->nan + x->infinite == 0)
            continue;
        char *file = malloc(strlen(x->file) + 1);
        if (file == NULL)
            return cap__fail(CAP_ERR_NOMEM, "out of memory for the capture report");
        r->repairs[r->repair_count] = *x;
        r->repairs[r->repair_count].plane = job->plane;
        r->repairs[r->repair_count++].file = strcpy(file, x->file);
    }
    return CAP_OK;
}

/* Adds the plane's figures to the report (started by report_start()). */
static cap_status add_to_report(const capture_job *job, const lfio_slab *slab, cap_report *r)
{
    const size_t positions = (size_t)job->pl->desc.nu * job->pl->desc.nv;
    r->positions += positions;
    r->images += job->pl->images;
    for (size_t k = 0; k < positions; k++) {
        r->interpolated += job->interpolated[k];
        r->unmerged += job->unmerged[k];
        r->subdivision_min = job->subdivision[k] < r->subdivision_min ? job->subdivision[k] : r->subdivision_min;
        r->subdivision_max = job->subdivision[k] > r->subdivision_max ? job->subdivision[k] : r->subdivision_max;
    }
    check_energy(job, slab, r);
    return collect_repairs(job, r);
}

/* An empty report, ready for add_to_report(). */
static void report_start(cap_report *r)
{
    memset(r, 0, sizeof *r);
    r->subdivision_min = UINT32_MAX;
    r->energy_error = -1.0;
}

void cap_report_free(cap_report *report)
{
    if (report == NULL)
        return;
    for (size_t k = 0; k < report->repair_count; k++)
        free((char *)report->repairs[k].file);
    free(report->repairs);
    memset(report, 0, sizeof *report);
}

/* ------------------------------------------------------------ the run */

/* The caller's progress, counted over every plane: positions of the planes before this one, plus this one's. */
typedef struct plane_progress {
    cap_progress_fn fn;
    void *user;
    uint64_t offset, total;
} plane_progress;

/* cap_progress_fn: one plane's count, shown after the earlier planes'. */
static void on_plane_progress(void *user, uint64_t done, uint64_t total)
{
    (void)total;
    const plane_progress *pp = user;
    pp->fn(pp->user, pp->offset + done, pp->total);
}

/* Captures plane q of m into a new slab *out, adding its figures to r. */
static cap_status capture_plane(const cap_manifest *m, uint32_t q, const cap_capture_options *o, plane_progress *pp,
                                lfio_slab **out, cap_report *r)
{
    const cap__plane *pl = &m->planes[q];
    capture_job job;
    cap_status st = job_init(&job, m, q);
    if (st != CAP_OK)
        return st;
    lfio_status ls = lfio_slab_new(&pl->desc, out);
    if (ls != LFIO_OK)
        st = cap__fail(ls == LFIO_ERR_NOMEM ? CAP_ERR_NOMEM : CAP_ERR_INPUT, "%s: %s", m->path, lfio_errmsg());
    if (st == CAP_OK)
        st = cap__run_positions(*out, o->threads, capture_position, &job, pp->fn ? on_plane_progress : NULL, pp);
    if (st == CAP_OK)
        st = add_to_report(&job, *out, r);
    pp->offset += (uint64_t)pl->desc.nu * pl->desc.nv;
    job_free(&job);
    if (st != CAP_OK) {
        lfio_slab_destroy(*out);
        *out = NULL;
    }
    return st;
}

cap_status cap_capture_run(const cap_manifest *m, const cap_capture_options *o, lfio_lightfield **out,
                           cap_report *report)
{
    if (out != NULL)
        *out = NULL;
    if (report != NULL)
        memset(report, 0, sizeof *report);
    if (m == NULL || out == NULL)
        return cap__fail(CAP_ERR_ARG, "cap_capture_run: manifest or output is NULL");
    static const cap_capture_options defaults = {0, NULL, NULL};
    if (o == NULL)
        o = &defaults;
    cap_report local;
    cap_report *r = report != NULL ? report : &local;
    report_start(r);
    plane_progress pp = {o->progress, o->progress_user, 0, 0};
    for (size_t q = 0; q < m->nplanes; q++)
        pp.total += (uint64_t)m->planes[q].desc.nu * m->planes[q].desc.nv;
    lfio_lightfield *lf = NULL;
    cap_status st = cap__check_samples(m);
    if (st == CAP_OK && lfio_lightfield_new(&lf) != LFIO_OK)
        st = cap__fail(CAP_ERR_NOMEM, "%s: out of memory", m->path);
    for (uint32_t q = 0; st == CAP_OK && q < m->nplanes; q++) {
        lfio_slab *slab = NULL;
        st = capture_plane(m, q, o, &pp, &slab, r);
        /* slab names were checked distinct when the manifest was loaded */
        lfio_status taken = st == CAP_OK ? lfio_lightfield_take_slab(lf, slab) : LFIO_OK;
        if (taken != LFIO_OK)
            st = cap__fail(taken == LFIO_ERR_NOMEM ? CAP_ERR_NOMEM : CAP_ERR_INPUT, "%s: %s", m->path, lfio_errmsg());
    }
    if (report == NULL || st != CAP_OK)
        cap_report_free(r);
    if (st != CAP_OK) {
        lfio_lightfield_destroy(lf);
        return st;
    }
    *out = lf;
    return CAP_OK;
}
