/*
 * resample.c - box-filtering one probe image onto a slab's front
 * hemisphere (cap__resample in probe.h), as capture/capture.h specifies:
 * sub-pixels with exact solid angles are binned into the partition's solid
 * angles; solid angles that contain no pixel centre are interpolated.
 *
 * The sub-pixel factor S is chosen from the ratio of the largest pixel to
 * an average solid angle so that an average solid angle receives about
 * SUBDIVISION_TARGET^2 sub-pixels: the error of binning by sub-pixel
 * centres (a sub-pixel straddling an edge counts wholly on one side) then
 * stays well below the 0.5% energy budget.
 *
 * Invariants: the stored value of a binned solid angle is a convex
 * combination of pixel values, so it is finite and >= 0 like them; the sum
 * of the sub-pixel weights of a pixel equals its solid angle (exactly for
 * equirectangular images); nothing here depends on other positions.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "lfio/partition.h"
#include "probe.h"

#define SUBDIVISION_TARGET 24.0
#define SUBDIVISION_MAX 16
/* Directions per solid angle when interpolating: k*k with k = 2 (cap_partition_samples). */
#define FALLBACK_K 2u

typedef struct resampler {
    const cap__hdr *img;
    cap_projection p;
    int width, height, S;
    uint32_t n;
    uint64_t dirs;
    double M[9];       /* frame * R: slab-frame propagation direction w = -M d for camera direction d */
    double *acc;       /* [dirs][4]: weighted r, g, b and the weight */
    uint32_t *centres; /* [dirs]: pixel centres falling in each solid angle */
    /* equirectangular tables: S sub-rows per row, S sub-columns per column */
    double *row_cos, *row_sin, *row_weight; /* [height*S] */
    double *col_cos, *col_sin;              /* [width*S] */
} resampler;

/* ------------------------------------------------------------ set-up */

/* @return S for an image whose largest pixel has solid angle pixel_sr, at partition level n. */
static int choose_subdivision(double pixel_sr, uint32_t n)
{
    double average = sqrt(0.5 * ILF_PI) / n; /* side of an average solid angle, sqrt(2 pi / 4n^2) */
    double s = ceil(SUBDIVISION_TARGET * sqrt(pixel_sr) / average);
    return s < 1.0 ? 1 : s > SUBDIVISION_MAX ? SUBDIVISION_MAX : (int)s;
}

/* @return the largest pixel solid angle of the image's projection. */
static double largest_pixel(cap_projection p, int width, int height)
{
    double area = 1.0 / ((double)width * height);
    if (p == CAP_PROJECTION_EQUIRECTANGULAR)
        return 2.0 * ILF_PI * ILF_PI * area;
    return (p == CAP_PROJECTION_MIRROR_BALL ? 16.0 : 4.0 * ILF_PI * ILF_PI) * area;
}

/* Fills the equirectangular sub-row and sub-column tables. */
static void fill_tables(resampler *rs)
{
    const int S = rs->S;
    const double dphi = 2.0 * ILF_PI / ((double)rs->width * S);
    for (int r = 0; r < rs->height * S; r++) {
        double t0 = ILF_PI * r / ((double)rs->height * S), t1 = ILF_PI * (r + 1) / ((double)rs->height * S);
        double tm = 0.5 * (t0 + t1);
        rs->row_cos[r] = cos(tm);
        rs->row_sin[r] = sin(tm);
        rs->row_weight[r] = dphi * (cos(t0) - cos(t1));
    }
    for (int c = 0; c < rs->width * S; c++) {
        double phi = ILF_PI * (1.0 - 2.0 * (c + 0.5) / ((double)rs->width * S));
        rs->col_cos[c] = cos(phi);
        rs->col_sin[c] = sin(phi);
    }
}

static void resampler_free(resampler *rs)
{
    free(rs->acc);
    free(rs->centres);
    free(rs->row_cos);
    free(rs->row_sin);
    free(rs->row_weight);
    free(rs->col_cos);
    free(rs->col_sin);
}

static cap_status resampler_init(resampler *rs, const cap__hdr *img, cap_projection p, const double R[9],
                                 const double frame[9], uint32_t n)
{
    memset(rs, 0, sizeof *rs);
    rs->img = img;
    rs->p = p;
    rs->width = img->width;
    rs->height = img->height;
    rs->n = n;
    rs->dirs = lfio_part_hemi_count(n);
    rs->S = choose_subdivision(largest_pixel(p, img->width, img->height), n);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++)
            rs->M[3 * r + c] = frame[3 * r] * R[c] + frame[3 * r + 1] * R[3 + c] + frame[3 * r + 2] * R[6 + c];
    rs->acc = calloc(rs->dirs * 4, sizeof *rs->acc);
    rs->centres = calloc(rs->dirs, sizeof *rs->centres);
    int ok = rs->acc != NULL && rs->centres != NULL;
    if (ok && p == CAP_PROJECTION_EQUIRECTANGULAR) {
        size_t rows = (size_t)rs->height * rs->S, cols = (size_t)rs->width * rs->S;
        rs->row_cos = malloc(rows * sizeof(double));
        rs->row_sin = malloc(rows * sizeof(double));
        rs->row_weight = malloc(rows * sizeof(double));
        rs->col_cos = malloc(cols * sizeof(double));
        rs->col_sin = malloc(cols * sizeof(double));
        ok = rs->row_cos && rs->row_sin && rs->row_weight && rs->col_cos && rs->col_sin;
        if (ok)
            fill_tables(rs);
    }
    if (!ok) {
        resampler_free(rs);
        return cap__fail(CAP_ERR_NOMEM, "out of memory for resampling a %dx%d image", img->width, img->height);
    }
    return CAP_OK;
}

/* ------------------------------------------------------------ binning */

/* Slab-frame propagation direction of camera direction d: w = -M d. */
static void to_local(const resampler *rs, const double d[3], double w[3])
{
    cap__mat_apply(rs->M, d, w);
    w[0] = -w[0];
    w[1] = -w[1];
    w[2] = -w[2];
}

/* Finds the front solid angle of camera direction d. @return 1 and *id, *cosine; 0 if d is behind. */
static int front_id(const resampler *rs, const double d[3], uint64_t *id, double *cosine)
{
    double w[3];
    to_local(rs, d, w);
    if (w[2] < 0.0 || !lfio_part_id(rs->n, w, id))
        return 0;
    *cosine = w[2];
    return 1;
}

/* Adds weight * pixel (x, y) to the solid angle of camera direction d. */
static void bin(resampler *rs, const double d[3], double weight, const float *rgb)
{
    uint64_t id;
    double cosine;
    if (!front_id(rs, d, &id, &cosine))
        return;
    double *a = &rs->acc[4 * id];
    a[0] += weight * rgb[0];
    a[1] += weight * rgb[1];
    a[2] += weight * rgb[2];
    a[3] += weight;
}

/* @return 1 if no direction of equirectangular pixel (x, y) can be in front (a margin around its centre). */
static int equirect_pixel_behind(const resampler *rs, int x, int y)
{
    double margin = 1.5 * (ILF_PI / rs->height + ILF_PI / rs->width);
    if (margin >= 0.5 * ILF_PI)
        return 0;
    double d[3], w[3];
    cap_projection_direction(rs->p, rs->width, rs->height, x + 0.5, y + 0.5, d);
    to_local(rs, d, w);
    return w[2] < -sin(margin);
}

static void bin_equirect(resampler *rs)
{
    const int S = rs->S;
    for (int y = 0; y < rs->height; y++)
        for (int x = 0; x < rs->width; x++) {
            if (equirect_pixel_behind(rs, x, y))
                continue;
            const float *rgb = &rs->img->rgb[3 * ((size_t)y * rs->width + x)];
            for (int sy = 0; sy < S; sy++) {
                int r = y * S + sy;
                for (int sx = 0; sx < S; sx++) {
                    int c = x * S + sx;
                    double d[3] = {rs->row_sin[r] * rs->col_cos[c], rs->row_sin[r] * rs->col_sin[c], rs->row_cos[r]};
                    bin(rs, d, rs->row_weight[r], rgb);
                }
            }
        }
}

static void bin_disc(resampler *rs)
{
    const int S = rs->S;
    const double sub_area = 1.0 / ((double)S * S);
    for (int y = 0; y < rs->height; y++)
        for (int x = 0; x < rs->width; x++) {
            const float *rgb = &rs->img->rgb[3 * ((size_t)y * rs->width + x)];
            for (int sy = 0; sy < S; sy++)
                for (int sx = 0; sx < S; sx++) {
                    double px = x + (sx + 0.5) / S, py = y + (sy + 0.5) / S, d[3];
                    if (cap_projection_direction(rs->p, rs->width, rs->height, px, py, d))
                        bin(rs, d, cap__disc_density(rs->p, rs->width, rs->height, px, py) * sub_area, rgb);
                }
        }
}

/* The integral of w.e3 over pixel (x, y): exact for an equirectangular pixel (the integral of the
 * direction over a latitude-longitude rectangle has a closed form), the centre's cosine times the
 * pixel's solid angle otherwise. */
static double pixel_cosine_integral(const resampler *rs, int x, int y, double cosine)
{
    if (rs->p != CAP_PROJECTION_EQUIRECTANGULAR)
        return cosine * cap_projection_solid_angle(rs->p, rs->width, rs->height, x, y);
    double t0 = ILF_PI * y / rs->height, t1 = ILF_PI * (y + 1) / rs->height;
    double left = ILF_PI * (1.0 - 2.0 * x / rs->width), right = ILF_PI * (1.0 - 2.0 * (x + 1) / rs->width);
    double sin2 = 0.5 * (t1 - t0) - 0.25 * (sin(2.0 * t1) - sin(2.0 * t0)); /* integral of sin^2 */
    double sincos = 0.5 * (sin(t1) * sin(t1) - sin(t0) * sin(t0));         /* integral of sin cos */
    double v[3] = {sin2 * (sin(left) - sin(right)), sin2 * (cos(right) - cos(left)), sincos * (left - right)};
    /* w.e3 = -(M d).z for the camera direction d */
    double c = -(rs->M[6] * v[0] + rs->M[7] * v[1] + rs->M[8] * v[2]);
    return c > 0.0 ? c : 0.0;
}

/* Counts pixel centres per solid angle and sums E_image = L * (integral of w.e3 over the pixel) over
 * the pixels whose centre is in front. */
static void scan_centres(resampler *rs, double energy[3])
{
    energy[0] = energy[1] = energy[2] = 0.0;
    for (int y = 0; y < rs->height; y++)
        for (int x = 0; x < rs->width; x++) {
            double d[3], cosine;
            uint64_t id;
            if (!cap_projection_direction(rs->p, rs->width, rs->height, x + 0.5, y + 0.5, d) ||
                !front_id(rs, d, &id, &cosine))
                continue;
            rs->centres[id]++;
            double projected = pixel_cosine_integral(rs, x, y, cosine);
            const float *rgb = &rs->img->rgb[3 * ((size_t)y * rs->width + x)];
            for (int c = 0; c < 3; c++)
                energy[c] += rgb[c] * projected;
        }
}

/* ------------------------------------------------------------ interpolation */

/* Maps pixel (*x, *y) into the image (wrapping equirectangular columns). @return 0 if it has no direction. */
static int usable_pixel(const resampler *rs, long *x, long *y)
{
    if (rs->p == CAP_PROJECTION_EQUIRECTANGULAR)
        *x = ((*x % rs->width) + rs->width) % rs->width;
    else
        *x = *x < 0 ? 0 : *x >= rs->width ? rs->width - 1 : *x;
    *y = *y < 0 ? 0 : *y >= rs->height ? rs->height - 1 : *y;
    return rs->p == CAP_PROJECTION_EQUIRECTANGULAR ||
           cap__disc_density(rs->p, rs->width, rs->height, *x + 0.5, *y + 0.5) > 0.0;
}

/* The image interpolated bilinearly between pixel centres at (px, py), into out. */
static void bilinear(const resampler *rs, double px, double py, double out[3])
{
    double fx = px - 0.5, fy = py - 0.5, sum[3] = {0.0, 0.0, 0.0}, total = 0.0;
    long x0 = (long)floor(fx), y0 = (long)floor(fy);
    double tx = fx - x0, ty = fy - y0;
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++) {
            long x = x0 + a, y = y0 + b;
            double w = (a ? tx : 1.0 - tx) * (b ? ty : 1.0 - ty);
            if (w <= 0.0 || !usable_pixel(rs, &x, &y))
                continue;
            const float *rgb = &rs->img->rgb[3 * ((size_t)y * rs->width + x)];
            for (int c = 0; c < 3; c++)
                sum[c] += w * rgb[c];
            total += w;
        }
    if (total <= 0.0) {
        /* no neighbour inside the disc: the pixel under the point, whatever it holds */
        long x = (long)px, y = (long)py;
        usable_pixel(rs, &x, &y);
        const float *rgb = &rs->img->rgb[3 * ((size_t)y * rs->width + x)];
        for (int c = 0; c < 3; c++)
            sum[c] = rgb[c];
        total = 1.0;
    }
    for (int c = 0; c < 3; c++)
        out[c] = sum[c] / total;
}

/* Solid angle id's radiance from the image interpolated at FALLBACK_K^2 directions inside it. */
static void interpolate(const resampler *rs, uint64_t id, float out[3])
{
    double dirs[FALLBACK_K * FALLBACK_K * 3], weights[FALLBACK_K * FALLBACK_K], sum[3] = {0.0, 0.0, 0.0};
    cap_partition_samples(rs->n, id, FALLBACK_K, dirs, weights);
    for (uint32_t k = 0; k < FALLBACK_K * FALLBACK_K; k++) {
        double d[3], px = 0.0, py = 0.0, value[3];
        /* camera direction d = -M^T w */
        cap__mat_apply_transposed(rs->M, &dirs[3 * k], d);
        d[0] = -d[0];
        d[1] = -d[1];
        d[2] = -d[2];
        cap_projection_locate(rs->p, rs->width, rs->height, d, &px, &py);
        bilinear(rs, px, py, value);
        for (int c = 0; c < 3; c++)
            sum[c] += weights[k] * value[c];
    }
    for (int c = 0; c < 3; c++)
        out[c] = (float)sum[c];
}

cap_status cap__resample(const cap__hdr *img, cap_projection p, const double R[9], const double frame[9],
                         uint32_t n, float *rgb, cap__resample_stats *stats)
{
    resampler rs;
    cap_status st = resampler_init(&rs, img, p, R, frame, n);
    if (st != CAP_OK)
        return st;
    if (p == CAP_PROJECTION_EQUIRECTANGULAR)
        bin_equirect(&rs);
    else
        bin_disc(&rs);
    scan_centres(&rs, stats->energy);
    stats->interpolated = 0;
    stats->subdivision = (uint32_t)rs.S;
    for (uint64_t id = 0; id < rs.dirs; id++) {
        const double *a = &rs.acc[4 * id];
        if (rs.centres[id] > 0 && a[3] > 0.0) {
            for (int c = 0; c < 3; c++)
                rgb[3 * id + c] = (float)(a[c] / a[3]);
        } else {
            interpolate(&rs, id, &rgb[3 * id]);
            stats->interpolated++;
        }
    }
    resampler_free(&rs);
    return CAP_OK;
}
