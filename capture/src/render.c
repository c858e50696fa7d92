/*
 * render.c - rendering the equirectangular probe image seen from a point
 * (cap_probe_render in capture/projection.h), the synthetic half of a
 * closed-loop capture test.
 *
 * Each pixel is the mean of the radiance function over s*s directions,
 * stratified in (phi, cos theta) so that each stratum holds an equal share
 * of the pixel's solid angle, one jittered direction per stratum.
 *
 * Invariants: the jitter of a sample is a hash of (seed, pixel, stratum),
 * so the image does not depend on the thread count or scheduling; rows are
 * claimed under a mutex, finished rows are counted under it and progress
 * is reported under it, so the callback is never concurrent; the first
 * failing pixel's message (lowest row, then column) is the one returned.
 */
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/projection.h"
#include "ilf/hash.h"
#include "ilf/pool.h"
#include "internal.h"
#include "ilf/limits.h"

#define MAX_SIDE ILF_PROBE_MAX_SIDE
#define MAX_STRATA ILF_PROBE_MAX_STRATA

typedef struct render_job {
    const cap_probe_settings *s;
    cap_radiance_fn fn;
    void *user;
    double org[3];
    double R[9];
    float *rgb;
    pthread_mutex_t lock;
    int next_row, rows_done;
    long failed_at; /* y * width + x of the first failure, or LONG_MAX */
    char message[128];
} render_job;

/* Two uniform numbers in [0, 1) for stratum (a, b) of pixel (x, y). */
static void jitter(uint64_t seed, int x, int y, uint32_t a, uint32_t b, double *u1, double *u2)
{
    uint64_t h = ilf_splitmix64(seed ^ ilf_splitmix64(((uint64_t)(uint32_t)y << 32) | (uint32_t)x));
    h = ilf_splitmix64(h ^ (((uint64_t)a << 32) | b));
    *u1 = (double)(h >> 40) / (double)(1u << 24);
    *u2 = (double)(h & 0xffffffu) / (double)(1u << 24);
}

/* World direction of stratum (a, b) of pixel (x, y), jittered. */
static void sample_direction(const render_job *job, int x, int y, uint32_t a, uint32_t b, double d[3])
{
    const cap_probe_settings *s = job->s;
    double u1, u2;
    jitter(s->seed, x, y, a, b, &u1, &u2);
    double px = x + (a + u1) / s->strata;
    double c0 = cos(ILF_PI * y / s->height), c1 = cos(ILF_PI * (y + 1) / s->height);
    double cos_theta = c0 + (c1 - c0) * (b + u2) / s->strata;
    double sin_theta = sqrt(fmax(0.0, 1.0 - cos_theta * cos_theta));
    double phi = ILF_PI * (1.0 - 2.0 * px / s->width);
    double cam[3] = {sin_theta * cos(phi), sin_theta * sin(phi), cos_theta};
    cap__mat_apply(job->R, cam, d);
}

/* Mean radiance over pixel (x, y) into out. @return 1, or 0 if the radiance function failed. */
static int render_pixel(const render_job *job, int x, int y, float out[3])
{
    uint32_t s = job->s->strata;
    double sum[3] = {0.0, 0.0, 0.0};
    for (uint32_t b = 0; b < s; b++)
        for (uint32_t a = 0; a < s; a++) {
            double d[3];
            float rgb[3];
            sample_direction(job, x, y, a, b, d);
            if (!job->fn(job->user, job->org, d, rgb))
                return 0;
            for (int c = 0; c < 3; c++)
                sum[c] += rgb[c];
        }
    for (int c = 0; c < 3; c++)
        out[c] = (float)(sum[c] / ((double)s * s));
    return 1;
}

/* Renders row y. @return -1, or the column where the radiance function failed. */
static int render_row(const render_job *job, int y)
{
    float *row = job->rgb + (size_t)y * job->s->width * 3;
    for (int x = 0; x < job->s->width; x++)
        if (!render_pixel(job, x, y, &row[3 * x]))
            return x;
    return -1;
}

/* Claims the next row under the lock. @return the row, or -1 when done or stopped by a failure. */
static int claim_row(render_job *job)
{
    pthread_mutex_lock(&job->lock);
    int y = job->next_row < job->s->height && job->failed_at == LONG_MAX ? job->next_row++ : -1;
    pthread_mutex_unlock(&job->lock);
    return y;
}

/* Counts a finished row, or records a failure at (x_failed, y), under the lock. */
static void finish_row(render_job *job, int y, int x_failed)
{
    pthread_mutex_lock(&job->lock);
    if (x_failed >= 0) {
        long at = (long)y * job->s->width + x_failed;
        if (at < job->failed_at) {
            job->failed_at = at;
            snprintf(job->message, sizeof job->message, "the radiance function failed at pixel (%d, %d)", x_failed,
                     y);
        }
    } else {
        job->rows_done++;
        if (job->s->progress != NULL)
            job->s->progress(job->s->progress_user, (uint64_t)job->rows_done, (uint64_t)job->s->height);
    }
    pthread_mutex_unlock(&job->lock);
}

static void render_worker(void *arg, unsigned index)
{
    (void)index;
    render_job *job = arg;
    for (int y; (y = claim_row(job)) >= 0;)
        finish_row(job, y, render_row(job, y));
}

static cap_status check_settings(const cap_probe_settings *s, cap_radiance_fn fn, const double org[3],
                                 const double R[9], const float *rgb)
{
    if (s == NULL || fn == NULL || org == NULL || rgb == NULL)
        return cap__fail(CAP_ERR_ARG, "cap_probe_render: a required argument is NULL");
    if (s->width < 1 || s->height < 1 || s->width > MAX_SIDE || s->height > MAX_SIDE)
        return cap__fail(CAP_ERR_ARG, "probe size %dx%d outside 1..%d", s->width, s->height, MAX_SIDE);
    if (s->strata < 1 || s->strata > MAX_STRATA)
        return cap__fail(CAP_ERR_ARG, "%u strata per axis outside 1..%u", s->strata, MAX_STRATA);
    if (!isfinite(org[0]) || !isfinite(org[1]) || !isfinite(org[2]))
        return cap__fail(CAP_ERR_ARG, "the probe position is not finite");
    if (R != NULL && !cap_rotation_check(R))
        return cap__fail(CAP_ERR_ARG, "the probe orientation is not a rotation");
    return CAP_OK;
}

cap_status cap_probe_render(const cap_probe_settings *s, cap_radiance_fn fn, void *user, const double org[3],
                            const double R[9], float *rgb)
{
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    cap_status st = check_settings(s, fn, org, R, rgb);
    if (st != CAP_OK)
        return st;
    render_job job;
    memset(&job, 0, sizeof job);
    job.s = s;
    job.fn = fn;
    job.user = user;
    memcpy(job.org, org, sizeof job.org);
    memcpy(job.R, R != NULL ? R : identity, sizeof job.R);
    job.rgb = rgb;
    job.failed_at = LONG_MAX;
    if (pthread_mutex_init(&job.lock, NULL) != 0)
        return cap__fail(CAP_ERR_NOMEM, "cannot create a mutex");
    unsigned count = ilf_thread_count(s->threads);
    if (count > (unsigned)s->height)
        count = (unsigned)s->height;
    ilf_parallel(count, render_worker, &job);
    pthread_mutex_destroy(&job.lock);
    if (job.failed_at != LONG_MAX)
        return cap__fail(CAP_ERR_INPUT, "%s", job.message);
    return CAP_OK;
}
