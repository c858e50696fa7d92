/*
 * test_capture.c - the capture library (capture/ headers) against closed forms,
 * synthetic images, a real light probe, a relit scene and a depth test.
 *
 * Usage: test_capture DATA_DIR   (the project's data/ folder; scratch files
 * go to $ILF_TEST_TMP/capture). What is checked:
 *   - projections: frames as documented, inverse maps, pixel solid angles
 *     summing to 4 pi; partition samples inside their solid angle;
 *   - synthetic environments in all three projections (one with a rotated
 *     orientation): the captured field against the environment's exact box
 *     mean, and energy (irradiance from the field vs from the image) within
 *     0.5%; a constant image stays constant; a too-coarse image is
 *     interpolated; bad values are repaired and counted; LDR brackets merge
 *     to the HDR truth better than one clipped exposure; the result does not
 *     depend on the thread count;
 *   - the image module (OpenImageIO) loads lazily: nothing of it is mapped
 *     before the first read, not even by a write, it is after; pinned by
 *     ILFKIT_IMAGE_MODULE to a missing file or to a module of another version
 *     (child processes, as the module loads once per process), reads fail
 *     with their status and a message naming the image and the module, while
 *     writes, which need no module, succeed;
 *   - manifest, image and proxy errors: status and a message naming the file
 *     and the element;
 *   - the bound on samples read: an image whose header claims 32768 x 16384
 *     RGB (no pixel data) named at 64 positions, or in 4 brackets of 16, is
 *     refused before any decode with the total and the limit, within a second
 *     of CPU time; named at 16 positions it is under the bound and fails only
 *     on decoding its data;
 *   - the real probe data/capture/probes/studio.exr end to end: energy
 *     within 0.5% and the count of its negative values;
 *   - closed loop: capture(render-probes(scene)) against the radiance the
 *     relit scene sends through the plane;
 *   - depth correction: a small emitter captured on a plane in front of it,
 *     reprojected onto its true plane: the energy concentrates on its
 *     footprint, and relighting with the reprojected field is closer to
 *     relighting with the true emitter than relighting with the raw capture;
 *     from a box of planes, the coverage and power the one plane misses;
 *   - several planes: manifests naming them; the quick start's lamp captured
 *     from a box of planes and merged onto its proxy covers it and relights
 *     walls and floor close to the true lamp, one plane alone does not;
 *   - mask_threshold on the real probe: the directions it rules out and the
 *     relit light it costs.
 * Measured errors are printed; the last line is "N passed, M failed".
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "capture/capture.h"
#include "capture/projection.h"
#include "capture/reproject.h"
#include "check.h"
#include "image/image.h"
#include "lfio/partition.h"
#include "relight/engine.h"
#include "relight/reference.h"

#define PI 3.14159265358979323846
#define PATH_BYTES 1024

static char tmp_dir[PATH_BYTES - 64];
static const char *data_dir;

/* ------------------------------------------------------------ helpers */

/* @return tmp_dir/name in a static rotating buffer (8 live at a time). */
static const char *tmp_path(const char *name)
{
    static char bufs[8][PATH_BYTES];
    static int next;
    char *b = bufs[next++ % 8];
    if (snprintf(b, PATH_BYTES, "%s/%s", tmp_dir, name) >= PATH_BYTES) {
        fprintf(stderr, "path too long: %s/%s\n", tmp_dir, name);
        exit(2);
    }
    return b;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(2);
    }
    fputs(text, f);
    fclose(f);
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalise3(double a[3])
{
    double l = sqrt(dot3(a, a));
    a[0] /= l;
    a[1] /= l;
    a[2] /= l;
}

/* A radiance function of the world direction one looks in. */
typedef void (*env_fn)(const double d[3], double rgb[3]);

/* A smooth sky brighter towards +z with a soft lobe of 20 around s (15 degree cone). */
static void sky_env(const double d[3], double rgb[3])
{
    static const double tint[3] = {1.0, 0.8, 0.6};
    double s[3] = {0.3, -0.2, 0.9};
    normalise3(s);
    double base = 0.5 + 0.3 * d[0] + 0.2 * d[2];
    double c15 = cos(15.0 * PI / 180.0), lobe = (dot3(d, s) - c15) / (1.0 - c15);
    lobe = lobe > 0.0 ? 20.0 * lobe : 0.0;
    for (int c = 0; c < 3; c++)
        rgb[c] = base * tint[c] + lobe;
}

/* The sky without its lobe: smooth enough for an 8x4 image. */
static void smooth_env(const double d[3], double rgb[3])
{
    double base = 0.5 + 0.3 * d[0] + 0.2 * d[2];
    rgb[0] = base;
    rgb[1] = 0.8 * base;
    rgb[2] = 0.6 * base;
}

static void constant_env(const double d[3], double rgb[3])
{
    (void)d;
    rgb[0] = 2.0;
    rgb[1] = 3.0;
    rgb[2] = 4.0;
}

/* Renders env into a width x height image of projection p, orientation R (pixel centres). */
static float *env_image(env_fn env, cap_projection p, int width, int height, const double R[9])
{
    float *px = calloc((size_t)width * height * 3, sizeof *px);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            double d[3], w[3], rgb[3];
            if (!cap_projection_direction(p, width, height, x + 0.5, y + 0.5, d))
                continue;
            for (int r = 0; r < 3; r++)
                w[r] = R[3 * r] * d[0] + R[3 * r + 1] * d[1] + R[3 * r + 2] * d[2];
            env(w, rgb);
            for (int c = 0; c < 3; c++)
                px[3 * ((size_t)y * width + x) + c] = (float)rgb[c];
        }
    return px;
}

static void write_env_image(const char *path, env_fn env, cap_projection p, int width, int height, const double R[9])
{
    float *px = env_image(env, p, width, height, R);
    char err[512];
    CHECK(img_write(path, width, height, 3, px, err, sizeof err) == IMG_OK, "%s", err);
    free(px);
}

static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

/* Loads and captures a manifest. @return the light field, or NULL after a failed check. */
static lfio_lightfield *capture_file(const char *manifest, unsigned threads, cap_report *report)
{
    cap_manifest *m = NULL;
    lfio_lightfield *lf = NULL;
    cap_status st = cap_manifest_load(manifest, &m);
    CHECK(st == CAP_OK, "%s", cap_error_message());
    if (st != CAP_OK)
        return NULL;
    cap_capture_options o = {threads, NULL, NULL};
    st = cap_capture_run(m, &o, &lf, report);
    CHECK(st == CAP_OK, "%s", cap_error_message());
    cap_manifest_destroy(m);
    return lf;
}

/* Incoming radiance along propagation direction d (arriving from -d) for a reference, in v. */
typedef void (*incoming_fn)(const void *ctx, const double d[3], double v[3]);

/* Gives in ref the mean of incoming radiance f over solid angle id of slab s: k*k (k <= 6) weighted samples. */
static void box_mean(const lfio_slab *s, uint64_t id, uint32_t k, incoming_fn f, const void *ctx, double ref[3])
{
    double dirs[6 * 6 * 3], weights[6 * 6];
    cap_partition_samples(lfio_slab_get_desc(s)->n, id, k, dirs, weights);
    ref[0] = ref[1] = ref[2] = 0.0;
    for (uint32_t q = 0; q < k * k; q++) {
        double w[3], d[3], v[3];
        lfio_slab_to_world(s, &dirs[3 * q], w);
        d[0] = -w[0], d[1] = -w[1], d[2] = -w[2];
        f(ctx, d, v);
        for (int c = 0; c < 3; c++)
            ref[c] += weights[q] * v[c];
    }
}

/* An environment as an incoming_fn. */
typedef struct env_source {
    env_fn env;
} env_source;

static void from_env(const void *ctx, const double d[3], double v[3])
{
    ((const env_source *)ctx)->env(d, v);
}

/* Relative L1 difference between the stored field at (i, j) and the box mean of env over each solid angle. */
static double field_error(const lfio_slab *s, uint32_t i, uint32_t j, env_fn env)
{
    const env_source src = {env};
    double diff = 0.0, total = 0.0;
    float *rgb = malloc(lfio_slab_dir_count(s) * 3 * sizeof *rgb);
    lfio_slab_read_position(s, i, j, rgb);
    for (uint64_t id = 0; id < lfio_slab_dir_count(s); id++) {
        double ref[3];
        box_mean(s, id, 6, from_env, &src, ref);
        for (int c = 0; c < 3; c++) {
            diff += fabs(rgb[3 * id + c] - ref[c]);
            total += ref[c];
        }
    }
    free(rgb);
    return diff / total;
}

/* ------------------------------------------------------------ projections */

static void test_projection_frames(void)
{
    double d[3];
    cap_projection_direction(CAP_PROJECTION_EQUIRECTANGULAR, 64, 32, 32, 16, d);
    CHECK(fabs(d[0] - 1) < 1e-12, "equirect centre looks +x: %g %g %g", d[0], d[1], d[2]);
    cap_projection_direction(CAP_PROJECTION_EQUIRECTANGULAR, 64, 32, 32, 0, d);
    CHECK(fabs(d[2] - 1) < 1e-12, "equirect top row looks +z");
    cap_projection_direction(CAP_PROJECTION_EQUIRECTANGULAR, 64, 32, 48, 16, d);
    CHECK(fabs(d[1] + 1) < 1e-12, "equirect: right of centre turns right (-y): %g", d[1]);
    cap_projection_direction(CAP_PROJECTION_MIRROR_BALL, 64, 64, 32, 32, d);
    CHECK(fabs(d[0] + 1) < 1e-12, "mirror ball centre shows -x (behind the camera)");
    cap_projection_direction(CAP_PROJECTION_MIRROR_BALL, 64, 64, 32, 16, d);
    CHECK(d[2] > 0.5, "mirror ball: above the centre shows up");
    cap_projection_direction(CAP_PROJECTION_MIRROR_BALL, 64, 64, 48, 32, d);
    CHECK(d[1] < -0.5, "mirror ball: right of the centre shows right");
    cap_projection_direction(CAP_PROJECTION_ANGULAR_MAP, 64, 64, 32, 32, d);
    CHECK(fabs(d[0] - 1) < 1e-12, "angular map centre shows +x");
    cap_projection_direction(CAP_PROJECTION_ANGULAR_MAP, 64, 64, 32, 16, d);
    CHECK(fabs(d[2] - 1) < 1e-12, "angular map: halfway up shows +z (90 degrees)");
    cap_projection_direction(CAP_PROJECTION_ANGULAR_MAP, 64, 64, 48, 32, d);
    CHECK(fabs(d[1] + 1) < 1e-12, "angular map: halfway right shows -y");
    CHECK(!cap_projection_direction(CAP_PROJECTION_MIRROR_BALL, 64, 64, 1, 1, d), "corner is outside the disc");
    CHECK(cap_projection_check_size(CAP_PROJECTION_MIRROR_BALL, 64, 32) != NULL, "mirror balls must be square");
    CHECK(cap_projection_check_size(CAP_PROJECTION_EQUIRECTANGULAR, 64, 32) == NULL, "any equirect size");
}

/* Sum of pixel solid angles over a whole image. */
static double image_solid_angle(cap_projection p, int width, int height)
{
    double sum = 0.0;
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            sum += cap_projection_solid_angle(p, width, height, x, y);
    return sum;
}

static void test_projection_maps(void)
{
    CHECK(fabs(image_solid_angle(CAP_PROJECTION_EQUIRECTANGULAR, 64, 32) - 4 * PI) < 1e-12, "equirect sums to 4pi");
    double mb = image_solid_angle(CAP_PROJECTION_MIRROR_BALL, 64, 64);
    double am = image_solid_angle(CAP_PROJECTION_ANGULAR_MAP, 64, 64);
    CHECK(fabs(mb / (4 * PI) - 1) < 1e-3, "mirror ball sums to 4pi: %.9g", mb);
    CHECK(fabs(am / (4 * PI) - 1) < 1e-3, "angular map sums to 4pi: %.9g", am);
    static const cap_projection all[3] = {CAP_PROJECTION_EQUIRECTANGULAR, CAP_PROJECTION_MIRROR_BALL,
                                          CAP_PROJECTION_ANGULAR_MAP};
    double worst = 0.0;
    unsigned seed = 7;
    for (int t = 0; t < 3000; t++) {
        double d[3], back[3], px, py;
        for (int a = 0; a < 3; a++)
            d[a] = (seed = seed * 1103515245u + 12345u, (seed >> 8) / 8388608.0 - 1.0);
        normalise3(d);
        cap_projection p = all[t % 3];
        if ((p == CAP_PROJECTION_MIRROR_BALL && d[0] > 0.999) || (p == CAP_PROJECTION_ANGULAR_MAP && d[0] < -0.999))
            continue; /* the rim maps one direction to a circle: ill-conditioned */
        int w = p == CAP_PROJECTION_EQUIRECTANGULAR ? 128 : 96, h = p == CAP_PROJECTION_EQUIRECTANGULAR ? 64 : 96;
        cap_projection_locate(p, w, h, d, &px, &py);
        CHECK(cap_projection_direction(p, w, h, px, py, back), "locate gives a point with a direction");
        for (int a = 0; a < 3; a++)
            worst = fmax(worst, fabs(back[a] - d[a]));
    }
    CHECK(worst < 1e-7, "direction(locate(d)) = d: worst %g", worst);
}

static void test_partition_samples(void)
{
    const uint32_t n = 4;
    double dirs[8 * 8 * 3], w[8 * 8], worst = 0.0;
    int inside = 1;
    for (uint64_t id = 0; id < lfio_part_count(n); id++) {
        double sum = 0.0, mean_z = 0.0;
        CHECK(cap_partition_samples(n, id, 8, dirs, w), "samples of id %llu", (unsigned long long)id);
        for (int q = 0; q < 64; q++) {
            uint64_t got;
            sum += w[q];
            mean_z += w[q] * dirs[3 * q + 2];
            inside &= lfio_part_id(n, &dirs[3 * q], &got) && got == id;
        }
        CHECK(fabs(sum - 1) < 1e-12, "weights sum to 1");
        if (id < lfio_part_hemi_count(n)) {
            const double pole[3] = {0, 0, 1};
            double exact = lfio_part_projected_solid_angle(n, id, pole) / lfio_part_solid_angle(n, id);
            worst = fmax(worst, fabs(mean_z - exact));
        }
    }
    CHECK(inside, "every sample lies in its own solid angle");
    CHECK(worst < 2e-3, "weighted mean of cos = projected / solid angle: worst %g", worst);
    CHECK(!cap_partition_samples(n, lfio_part_count(n), 2, dirs, w), "bad id refused");
    CHECK(!cap_partition_samples(n, 0, 65, dirs, w), "k = 65 refused");
}

/* ------------------------------------------------------------ synthetic captures */

/* A plane facing down (e3 = -z): it stores the light coming from above. */
#define DOWN_PLANE "\"plane\": {\"origin\": [-0.5, 0.5, 0], \"u\": [1, 0, 0], \"v\": [0, -1, 0]}"

static void test_three_projections(void)
{
    /* the angular map is taken facing +y: its orientation maps camera forward to +y */
    static const double facing_y[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    write_env_image(tmp_path("sky_equirect.exr"), sky_env, CAP_PROJECTION_EQUIRECTANGULAR, 256, 128, identity);
    write_env_image(tmp_path("sky_ball.exr"), sky_env, CAP_PROJECTION_MIRROR_BALL, 256, 256, identity);
    write_env_image(tmp_path("sky_angular.exr"), sky_env, CAP_PROJECTION_ANGULAR_MAP, 256, 256, facing_y);
    write_text(tmp_path("sky.json"),
               "{" DOWN_PLANE ", \"grid\": {\"nu\": 3, \"nv\": 1}, \"n\": 16, \"slab\": \"sky\",\n"
               " \"positions\": [\n"
               "  {\"i\": 0, \"j\": 0, \"image\": \"sky_equirect.exr\"},\n"
               "  {\"i\": 1, \"j\": 0, \"image\": \"sky_ball.exr\", \"projection\": \"mirror_ball\"},\n"
               "  {\"i\": 2, \"j\": 0, \"image\": \"sky_angular.exr\", \"projection\": \"angular_map\",\n"
               "   \"orientation\": {\"forward\": [0, 1, 0], \"up\": [0, 0, 1]}}]}\n");
    cap_report r1, r3;
    lfio_lightfield *one = capture_file(tmp_path("sky.json"), 1, &r1);
    lfio_lightfield *three = capture_file(tmp_path("sky.json"), 3, &r3);
    if (one == NULL || three == NULL)
        return;
    const lfio_slab *s = lfio_lightfield_slab(one, 0);
    static const char *names[3] = {"equirectangular", "mirror ball", "angular map"};
    for (uint32_t i = 0; i < 3; i++) {
        double err = field_error(s, i, 0, sky_env);
        printf("sky, %s: field vs exact box mean %.3f%% (relative L1)\n", names[i], 100 * err);
        CHECK(err < 0.02, "%s field error %g", names[i], err);
    }
    printf("sky: energy error %.4f%% (position %u), sub-pixels %u..%u\n", 100 * r1.energy_error, r1.energy_i,
           r1.subdivision_min, r1.subdivision_max);
    CHECK(r1.energy_error < 0.005, "energy within 0.5%%: %g", r1.energy_error);
    const lfio_slab *t = lfio_lightfield_slab(three, 0);
    CHECK(memcmp(lfio_slab_radiance(s), lfio_slab_radiance(t), lfio_slab_dir_count(s) * 3 * 3 * sizeof(float)) == 0,
          "1 and 3 threads give identical fields");
    CHECK(r1.energy_error == r3.energy_error && r1.interpolated == r3.interpolated, "identical reports");
    cap_report_free(&r1);
    cap_report_free(&r3);
    lfio_lightfield_destroy(one);
    lfio_lightfield_destroy(three);
}

static void test_constant_and_coarse(void)
{
    write_env_image(tmp_path("constant.exr"), constant_env, CAP_PROJECTION_EQUIRECTANGULAR, 64, 32, identity);
    write_env_image(tmp_path("coarse.exr"), smooth_env, CAP_PROJECTION_EQUIRECTANGULAR, 8, 4, identity);
    write_text(tmp_path("constant.json"), "{" DOWN_PLANE ", \"grid\": {\"nu\": 1, \"nv\": 1}, \"n\": 8,"
                                          " \"pattern\": \"constant.exr\"}");
    write_text(tmp_path("coarse.json"), "{" DOWN_PLANE ", \"grid\": {\"nu\": 1, \"nv\": 1}, \"n\": 16,"
                                        " \"pattern\": \"coarse.exr\"}");
    cap_report r;
    lfio_lightfield *lf = capture_file(tmp_path("constant.json"), 0, &r);
    if (lf != NULL) {
        const lfio_slab *s = lfio_lightfield_slab(lf, 0);
        const float *v = lfio_slab_radiance(s);
        double worst = 0.0;
        for (uint64_t k = 0; k < lfio_slab_dir_count(s); k++)
            for (int c = 0; c < 3; c++)
                worst = fmax(worst, fabs(v[3 * k + c] / (2.0 + c) - 1.0));
        CHECK(worst < 1e-5, "a constant image gives a constant field: worst %g", worst);
        printf("constant image: energy error %.5f%%\n", 100 * r.energy_error);
        CHECK(r.energy_error < 1e-3, "constant image energy %g", r.energy_error);
        CHECK(r.interpolated == 0, "no solid angle interpolated");
        cap_report_free(&r);
        lfio_lightfield_destroy(lf);
    }
    lf = capture_file(tmp_path("coarse.json"), 0, &r);
    if (lf != NULL) {
        const lfio_slab *s = lfio_lightfield_slab(lf, 0);
        double err = field_error(s, 0, 0, smooth_env);
        printf("coarse 8x4 image at n=16: %llu of 1024 solid angles interpolated, field error %.2f%%, energy error"
               " %.3f%%\n", (unsigned long long)r.interpolated, 100 * err, 100 * r.energy_error);
        CHECK(r.interpolated > 0, "a coarse image is interpolated");
        CHECK(err < 0.05, "interpolated field close to the environment: %g", err);
        CHECK(r.subdivision_max == 16, "the largest sub-pixel factor is used");
        cap_report_free(&r);
        lfio_lightfield_destroy(lf);
    }
}

static void test_repairs(void)
{
    const int w = 32, h = 16;
    float *px = env_image(constant_env, CAP_PROJECTION_EQUIRECTANGULAR, w, h, identity);
    px[3 * (5 * w + 5) + 0] = NAN;
    px[3 * (3 * w + 10) + 1] = INFINITY;
    px[3 * (8 * w + 20) + 2] = -7.0f;
    px[3 * (8 * w + 21) + 2] = -3.0f;
    char err[256];
    CHECK(img_write(tmp_path("bad_values.exr"), w, h, 3, px, err, sizeof err) == IMG_OK, "%s", err);
    free(px);
    write_text(tmp_path("bad_values.json"), "{" DOWN_PLANE ", \"grid\": {\"nu\": 1, \"nv\": 1}, \"n\": 4,"
                                            " \"pattern\": \"bad_values.exr\"}");
    cap_report r;
    lfio_lightfield *lf = capture_file(tmp_path("bad_values.json"), 0, &r);
    if (lf == NULL)
        return;
    CHECK(r.negative == 2 && r.nan == 1 && r.infinite == 1, "counts %llu %llu %llu", (unsigned long long)r.negative,
          (unsigned long long)r.nan, (unsigned long long)r.infinite);
    CHECK(r.repair_count == 1 && strstr(r.repairs[0].file, "bad_values.exr") != NULL, "one image named");
    CHECK(r.repair_count == 1 && r.repairs[0].lowest == -7.0f, "lowest value kept");
    const lfio_slab *s = lfio_lightfield_slab(lf, 0);
    const float *v = lfio_slab_radiance(s);
    int sane = 1;
    for (uint64_t k = 0; k < 3 * lfio_slab_dir_count(s); k++)
        sane &= isfinite(v[k]) && v[k] >= 0.0f && v[k] <= 4.0f + 1e-5f;
    CHECK(sane, "repaired values are finite, >= 0 and no larger than the neighbours'");
    cap_report_free(&r);
    lfio_lightfield_destroy(lf);
}

/* sRGB encoding, to make 8-bit brackets. */
static float srgb_encode(double v)
{
    v = v < 0 ? 0 : v > 1 ? 1 : v;
    return (float)(v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055);
}

static void test_brackets(void)
{
    const int w = 128, h = 64;
    static const double exposures[3] = {1.0, 0.125, 1.0 / 64};
    float *truth = env_image(sky_env, CAP_PROJECTION_EQUIRECTANGULAR, w, h, identity);
    float *ldr = malloc((size_t)w * h * 3 * sizeof *ldr);
    char err[256], name[64];
    CHECK(img_write(tmp_path("truth.exr"), w, h, 3, truth, err, sizeof err) == IMG_OK, "%s", err);
    for (int e = 0; e < 3; e++) {
        for (size_t k = 0; k < (size_t)w * h * 3; k++)
            ldr[k] = srgb_encode(truth[k] * exposures[e]);
        snprintf(name, sizeof name, "bracket_%d.png", e);
        CHECK(img_write(tmp_path(name), w, h, 3, ldr, err, sizeof err) == IMG_OK, "%s", err);
    }
    write_text(tmp_path("bracket.json"),
               "{" DOWN_PLANE ", \"grid\": {\"nu\": 3, \"nv\": 1}, \"n\": 16, \"positions\": [\n"
               " {\"i\": 0, \"j\": 0, \"bracket\": [{\"file\": \"bracket_0.png\", \"exposure\": 1},\n"
               "   {\"file\": \"bracket_1.png\", \"exposure\": 0.125}, {\"file\": \"bracket_2.png\", \"exposure\": "
               "0.015625}]},\n"
               " {\"i\": 1, \"j\": 0, \"image\": \"bracket_0.png\"},\n"
               " {\"i\": 2, \"j\": 0, \"image\": \"truth.exr\"}]}");
    cap_report r;
    lfio_lightfield *lf = capture_file(tmp_path("bracket.json"), 0, &r);
    free(truth);
    free(ldr);
    if (lf == NULL)
        return;
    const lfio_slab *s = lfio_lightfield_slab(lf, 0);
    double merged = field_error(s, 0, 0, sky_env), single = field_error(s, 1, 0, sky_env);
    double exact = field_error(s, 2, 0, sky_env);
    printf("brackets: merged 8-bit bracket %.2f%%, one clipped 8-bit exposure %.2f%%, float truth %.2f%%"
           " (field vs exact, relative L1); %llu pixels unmerged\n",
           100 * merged, 100 * single, 100 * exact, (unsigned long long)r.unmerged);
    CHECK(merged < 0.03, "merged bracket close to the truth: %g", merged);
    CHECK(merged < 0.5 * single, "merging beats one clipped exposure: %g vs %g", merged, single);
    CHECK(r.images == 5, "five images read");
    cap_report_free(&r);

    /* The same bracket through a pattern with {k} and "exposures": the same field, bit for bit. */
    write_text(tmp_path("bracket_pattern.json"), "{" DOWN_PLANE ", \"grid\": {\"nu\": 1, \"nv\": 1}, \"n\": 16, "
                                                 "\"pattern\": \"bracket_{k}.png\", \"exposures\": [1, 0.125, 0.015625]}");
    lfio_lightfield *pf = capture_file(tmp_path("bracket_pattern.json"), 0, &r);
    if (pf != NULL) {
        const size_t count = lfio_slab_dir_count(s) * 3;
        float *a = malloc(count * sizeof *a), *b = malloc(count * sizeof *b);
        lfio_slab_read_position(s, 0, 0, a);
        lfio_slab_read_position(lfio_lightfield_slab(pf, 0), 0, 0, b);
        CHECK(memcmp(a, b, count * sizeof *a) == 0, "a pattern bracket equals the listed bracket");
        CHECK(r.images == 3, "three images read: %llu", (unsigned long long)r.images);
        free(a);
        free(b);
        cap_report_free(&r);
        lfio_lightfield_destroy(pf);
    }
    lfio_lightfield_destroy(lf);
}

/* ------------------------------------------------------------ errors */

/* Loads a manifest (text) that must fail, with a message containing every string of want. */
static void expect_manifest_error(const char *text, const char *want1, const char *want2)
{
    const char *path = tmp_path("bad.json");
    write_text(path, text);
    cap_manifest *m = NULL;
    cap_status st = cap_manifest_load(path, &m);
    const char *msg = cap_error_message();
    CHECK(st == CAP_ERR_INPUT && m == NULL, "should fail: %s", text);
    CHECK(strstr(msg, "bad.json") != NULL && strstr(msg, want1) != NULL && (want2 == NULL || strstr(msg, want2)),
          "message '%s' should name the file, '%s' and '%s'", msg, want1, want2 ? want2 : "");
    cap_manifest_destroy(m);
}

#define GRID1 "\"grid\": {\"nu\": 1, \"nv\": 1}"

/* A manifest naming two planes: what each inherits from the top level and what it overrides. */
static void test_planes_manifest(void)
{
    const char *path = tmp_path("planes.json");
    write_text(path, "{\"n\": 8, \"mask_threshold\": 0.25, \"scale\": 2, \"planes\": [{" DOWN_PLANE ", " GRID1
                     ", \"pattern\": \"constant.exr\"}, {\"plane\": {\"origin\": [0, 0, 1], \"u\": [1, 0, 0], "
                     "\"v\": [0, 0, 1]}, \"grid\": {\"nu\": 2, \"nv\": 1}, \"n\": 4, \"slab\": \"side\", "
                     "\"scale\": 3, \"positions\": [{\"i\": 0, \"j\": 0, \"image\": \"constant.exr\"}, "
                     "{\"i\": 1, \"j\": 0, \"image\": \"constant.exr\", \"scale\": 5}]}]}");
    cap_manifest *m = NULL;
    CHECK(cap_manifest_load(path, &m) == CAP_OK, "%s", cap_error_message());
    if (m == NULL)
        return;
    const lfio_slab_desc *a = cap_manifest_get_desc(m, 0), *b = cap_manifest_get_desc(m, 1);
    cap_position_info pa, pb0, pb1;
    CHECK(cap_manifest_plane_count(m) == 2 && cap_manifest_get_desc(m, 2) == NULL && cap_manifest_image_count(m) == 3,
          "two planes, three images");
    CHECK(strcmp(a->name, "capture0") == 0 && a->n == 8 && a->mask_threshold == 0.25f && a->nu == 1,
          "plane 0 inherits n and mask_threshold: '%s' n %u threshold %g", a->name, a->n, (double)a->mask_threshold);
    CHECK(strcmp(b->name, "side") == 0 && b->n == 4 && b->mask_threshold == 0.25f && b->nu == 2,
          "plane 1 overrides n and the name: '%s' n %u", b->name, b->n);
    CHECK(cap_manifest_get_position(m, 0, 0, 0, &pa) == CAP_OK && cap_manifest_get_position(m, 1, 0, 0, &pb0) == CAP_OK
              && cap_manifest_get_position(m, 1, 1, 0, &pb1) == CAP_OK && pa.scale == 2 && pb0.scale == 3 &&
              pb1.scale == 5 && strcmp(pb1.element, "planes[1].positions[1]") == 0,
          "scales inherited and overridden: %g %g %g, element '%s'", pa.scale, pb0.scale, pb1.scale, pb1.element);
    CHECK(cap_manifest_get_position(m, 2, 0, 0, &pa) == CAP_ERR_ARG, "no plane 2");
    cap_manifest_destroy(m);
}

/* @return 1 if a and b hold the same three doubles, bit for bit in value. */
static int same3(const double a[3], const double b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/*
 * cap_manifest_write(): manifests of one plane and of two, with numbers that need 17 digits (1/3), 15
 * (0.1), an exponent (1e-7) and patterns that need escaping (a quote, a backslash), read back by
 * cap_manifest_load() as written (every value equal); bad specs are refused by name; a write into a folder
 * that does not exist, or under a regular file, fails with CAP_ERR_OUTPUT naming the path and the
 * system's reason, leaving nothing there.
 */
static void test_manifest_write(void)
{
    lfio_slab_desc a, b;
    lfio_slab_desc_init(&a);
    lfio_slab_desc_init(&b);
    snprintf(a.name, sizeof a.name, "lamp.a");
    snprintf(b.name, sizeof b.name, "lamp-b_2");
    const double ao[3] = {0.1, -1.0 / 3, 1e-7}, au[3] = {1.0 / 3, 0, 0}, av[3] = {0, -0.7, 0};
    const double bo[3] = {-2.5, 12345.678, 3}, bu[3] = {0, 0.3, 0}, bv[3] = {0, 0, -1.1};
    memcpy(a.origin, ao, sizeof ao), memcpy(a.u, au, sizeof au), memcpy(a.v, av, sizeof av);
    memcpy(b.origin, bo, sizeof bo), memcpy(b.u, bu, sizeof bu), memcpy(b.v, bv, sizeof bv);
    a.nu = 2, a.nv = 1, b.nu = 1, b.nv = 2;
    const cap_manifest_plane planes[2] = {{&a, "q\"a\\_{i}_{j}.exr"}, {&b, "b_{i}_{j}.exr"}};
    const char *files[] = {"q\"a\\_0_0.exr", "q\"a\\_1_0.exr", "b_0_0.exr", "b_0_1.exr"};
    for (size_t k = 0; k < 4; k++)
        write_text(tmp_path(files[k]), "");
    for (size_t nplanes = 1; nplanes <= 2; nplanes++) {
        const cap_manifest_spec spec = {8, nplanes == 1 ? LFIO_UNITS_RELATIVE : LFIO_UNITS_RADIANCE,
                                        CAP_PROJECTION_MIRROR_BALL, CAP_COLOUR_SRGB, nplanes, planes};
        const char *path = tmp_path(nplanes == 1 ? "written1.json" : "written2.json");
        CHECK(cap_manifest_write(path, &spec) == CAP_OK, "write %zu planes: %s", nplanes, cap_error_message());
        cap_manifest *m = NULL;
        CHECK(cap_manifest_load(path, &m) == CAP_OK, "read back %zu planes: %s", nplanes, cap_error_message());
        CHECK(cap_manifest_plane_count(m) == nplanes && cap_manifest_image_count(m) == 2 * nplanes,
              "%zu planes read back: %zu planes, %llu images", nplanes, cap_manifest_plane_count(m),
              (unsigned long long)cap_manifest_image_count(m));
        for (size_t k = 0; m != NULL && k < nplanes; k++) {
            const lfio_slab_desc *want = planes[k].desc, *got = cap_manifest_get_desc(m, k);
            CHECK(got && strcmp(got->name, want->name) == 0 && same3(got->origin, want->origin) &&
                      same3(got->u, want->u) && same3(got->v, want->v) && got->nu == want->nu &&
                      got->nv == want->nv && got->n == spec.n && got->units == spec.units,
                  "plane %zu of %zu read back as written", k, nplanes);
            cap_position_info pos;
            uint32_t i = want->nu - 1, j = want->nv - 1;
            CHECK(cap_manifest_get_position(m, k, i, j, &pos) == CAP_OK && pos.projection == spec.projection &&
                      pos.colour_space == spec.colour_space && pos.image_count == 1 && pos.scale == 1 &&
                      strcmp(pos.files[0], tmp_path(files[2 * k + 1])) == 0,
                  "plane %zu position %u,%u: file '%s'", k, i, j, pos.image_count ? pos.files[0] : "");
        }
        cap_manifest_destroy(m);
    }
    cap_manifest_spec bad = {8, LFIO_UNITS_RADIANCE, CAP_PROJECTION_EQUIRECTANGULAR, CAP_COLOUR_LINEAR, 0, planes};
    const char *never = tmp_path("never.json");
    CHECK(cap_manifest_write(never, &bad) == CAP_ERR_ARG && strstr(cap_error_message(), "1 to"), "no planes: %s",
          cap_error_message());
    bad.nplanes = 1, bad.n = 0;
    CHECK(cap_manifest_write(never, &bad) == CAP_ERR_ARG && strstr(cap_error_message(), "n 0"), "n 0: %s",
          cap_error_message());
    bad.n = 8, bad.projection = (cap_projection)7;
    CHECK(cap_manifest_write(never, &bad) == CAP_ERR_ARG, "unknown projection: %s", cap_error_message());
    CHECK(cap_manifest_write(NULL, &bad) == CAP_ERR_ARG && cap_manifest_write(never, NULL) == CAP_ERR_ARG, "NULL");
    struct stat sb;
    CHECK(stat(never, &sb) != 0 && errno == ENOENT, "refused specs wrote nothing");
    const cap_manifest_spec good = {8, LFIO_UNITS_RADIANCE, CAP_PROJECTION_EQUIRECTANGULAR, CAP_COLOUR_LINEAR, 1,
                                    planes};
    const char *nowhere = tmp_path("no_such_folder/manifest.json");
    CHECK(cap_manifest_write(nowhere, &good) == CAP_ERR_OUTPUT && strstr(cap_error_message(), nowhere) &&
              strstr(cap_error_message(), strerror(ENOENT)),
          "a folder that does not exist: %s", cap_error_message());
    const char *under_file = tmp_path("written1.json/manifest.json");
    CHECK(cap_manifest_write(under_file, &good) == CAP_ERR_OUTPUT && strstr(cap_error_message(), under_file) &&
              strstr(cap_error_message(), strerror(ENOTDIR)),
          "a folder that is a regular file: %s", cap_error_message());
}

static void test_manifest_errors(void)
{
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"bracket_{k}.png\"}", "pattern",
                          "{k} needs 'exposures'");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"bracket_0.png\", \"exposures\": [1, 2]}",
                          "pattern", "must contain {k}");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"bracket_{k}.png\", \"exposures\": [1, 0]}",
                          "exposures[1]", NULL);
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"bracket_{k}.png\", \"exposures\": []}",
                          "exposures", "0 exposures");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"bracket_{k}.png\", \"exposures\": [1, 2, 4, 8]}",
                          "pattern", "bracket_3.png");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"exposures\": [1], \"positions\": [{\"i\": 0, \"j\": 0, "
                          "\"image\": \"constant.exr\"}]}", "exposures", "goes with 'pattern'");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"constant.exr\", \"colour\": \"srgb\"}",
                          "unknown key 'colour'", NULL);
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"nothere.exr\"}", "pattern", "nothere.exr");
    expect_manifest_error("{" DOWN_PLANE ", \"grid\": {\"nu\": 2, \"nv\": 1}, \"positions\": ["
                          "{\"i\": 0, \"j\": 0, \"image\": \"constant.exr\"},"
                          "{\"i\": 0, \"j\": 0, \"image\": \"constant.exr\"}]}",
                          "positions[1]", "already given by positions[0]");
    expect_manifest_error("{" DOWN_PLANE ", \"grid\": {\"nu\": 2, \"nv\": 1}, \"positions\": ["
                          "{\"i\": 0, \"j\": 0, \"image\": \"constant.exr\"}]}",
                          "no image for position (1, 0)", NULL);
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"positions\": [{\"i\": 0, \"j\": 0, \"image\": "
                          "\"constant.exr\", \"orientation\": [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}]}",
                          "positions[0].orientation", "not a rotation");
    expect_manifest_error("{" DOWN_PLANE ",\n " GRID1 ",\n \"pattern\": \"constant.exr\",\n}\n", "bad.json:4:",
                          "not valid JSON");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"positions\": [{\"i\": 0, \"j\": 0, \"bracket\": ["
                          "{\"file\": \"constant.exr\", \"exposure\": 1}, {\"file\": \"constant.exr\", \"exposure\": 0}"
                          "]}]}",
                          "positions[0].bracket[1].exposure", "must be > 0");
    expect_manifest_error("{\"plane\": {\"origin\": [0, 0, 0], \"u\": [1, 0, 0], \"v\": [1, 1, 0]}, " GRID1
                          ", \"pattern\": \"constant.exr\"}",
                          "plane", "orthogonal");
    expect_manifest_error("{" DOWN_PLANE ", \"grid\": {\"nu\": 2, \"nv\": 1}, \"pattern\": \"constant.exr\"}",
                          "pattern", "{i}");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"projection\": \"fisheye\", \"pattern\": \"constant.exr\"}",
                          "projection", "fisheye");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"mask_threshold\": -0.5, \"pattern\": \"constant.exr\"}",
                          "mask_threshold", "must be >= 0");
    expect_manifest_error("{" DOWN_PLANE ", " GRID1 ", \"mask_threshold\": \"low\", \"pattern\": \"constant.exr\"}",
                          "mask_threshold", NULL);
    expect_manifest_error("{\"planes\": []}", "planes", "0 planes");
    expect_manifest_error("{\"planes\": [{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"constant.exr\"}], "
                          "\"pattern\": \"constant.exr\"}", "unknown key 'pattern'", NULL);
    expect_manifest_error("{\"planes\": [{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"constant.exr\"}, {" DOWN_PLANE
                          ", \"grid\": {\"nu\": 2, \"nv\": 1}, \"pattern\": \"constant.exr\"}]}",
                          "planes[1].pattern", "{i}");
    expect_manifest_error("{\"planes\": [{" DOWN_PLANE ", " GRID1 ", \"slab\": \"a\", \"pattern\": \"constant.exr\"}, {"
                          DOWN_PLANE ", " GRID1 ", \"slab\": \"a\", \"pattern\": \"constant.exr\"}]}",
                          "planes[1]", "already that of planes[0]");
    expect_manifest_error("{\"planes\": [{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"constant.exr\"}, {"
                          "\"plane\": {\"origin\": [0, 0, 0], \"u\": [1, 0, 0], \"v\": [1, 1, 0]}, " GRID1
                          ", \"pattern\": \"constant.exr\"}]}", "planes[1].plane", "orthogonal");
    test_planes_manifest();
}

/* Captures a manifest (text) whose images must fail at run time, with a message containing want1 and want2. */
static void expect_capture_error(const char *text, const char *want1, const char *want2)
{
    const char *path = tmp_path("bad_run.json");
    write_text(path, text);
    cap_manifest *m = NULL;
    lfio_lightfield *lf = NULL;
    CHECK(cap_manifest_load(path, &m) == CAP_OK, "%s", cap_error_message());
    cap_status st = cap_capture_run(m, NULL, &lf, NULL);
    const char *msg = cap_error_message();
    CHECK(st == CAP_ERR_INPUT && lf == NULL, "capture should fail: %s", text);
    CHECK(strstr(msg, "bad_run.json") != NULL && strstr(msg, want1) != NULL && strstr(msg, want2) != NULL,
          "message '%s' should name the manifest, '%s' and '%s'", msg, want1, want2);
    cap_manifest_destroy(m);
}

static void test_capture_errors(void)
{
    write_text(tmp_path("not_an_image.exr"), "this is text, not an image\n");
    expect_capture_error("{" DOWN_PLANE ", " GRID1 ", \"pattern\": \"not_an_image.exr\"}", "pattern",
                         "not_an_image.exr");
    expect_capture_error("{" DOWN_PLANE ", " GRID1 ", \"positions\": [{\"i\": 0, \"j\": 0, \"bracket\": ["
                         "{\"file\": \"constant.exr\", \"exposure\": 1}, "
                         "{\"file\": \"coarse.exr\", \"exposure\": 2}]}]}",
                         "coarse.exr is 8x4 but", "constant.exr is 64x32");
    expect_capture_error("{" DOWN_PLANE ", " GRID1 ", \"projection\": \"mirror_ball\", \"pattern\": \"constant.exr\"}",
                         "64x32", "square");
}

/* A manifest of an nu x nv grid whose every position names image, as one image or a bracket of `bracket`
 * copies (0: a single image), into text (size bytes). */
static void repeated_manifest(char *text, size_t size, int nu, int nv, const char *image, int bracket)
{
    size_t len = (size_t)snprintf(text, size, "{" DOWN_PLANE ", \"grid\": {\"nu\": %d, \"nv\": %d}, \"positions\": [",
                                  nu, nv);
    for (int k = 0; k < nu * nv && len < size; k++) {
        len += (size_t)snprintf(text + len, size - len, "%s{\"i\": %d, \"j\": %d, ", k ? ", " : "", k % nu, k / nu);
        if (bracket == 0)
            len += (size_t)snprintf(text + len, size - len, "\"image\": \"%s\"}", image);
        else
            for (int b = 0; b < bracket && len < size; b++)
                len += (size_t)snprintf(text + len, size - len, "%s{\"file\": \"%s\", \"exposure\": %d}%s",
                                        b ? ", " : "\"bracket\": [", image, b + 1, b + 1 < bracket ? "" : "]}");
    }
    if (len < size)
        snprintf(text + len, size - len, "]}");
}

static void test_sample_bound(void)
{
    /* 32768 x 16384 x 3 = 1610612736 samples a read, no pixel data: a decode would fail on the data */
    write_text(tmp_path("header_only.hdr"), "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 32768\n");
    static char text[65536];
    char total[64];
    snprintf(total, sizeof total, "%llu samples", 64ull * 1610612736ull);
    char limit[64];
    snprintf(limit, sizeof limit, "limit of %llu", (unsigned long long)CAP_CAPTURE_MAX_SAMPLES);
    clock_t start = clock();
    repeated_manifest(text, sizeof text, 8, 8, "header_only.hdr", 0);
    expect_capture_error(text, total, limit);
    repeated_manifest(text, sizeof text, 2, 2, "header_only.hdr", 16);
    expect_capture_error(text, total, limit);
    double cpu = (double)(clock() - start) / CLOCKS_PER_SEC;
    CHECK(cpu < 1.0, "64 reads of one image refused from its header in %.3f s of CPU time", cpu);
    repeated_manifest(text, sizeof text, 4, 4, "header_only.hdr", 0);
    expect_capture_error(text, "positions[0]", "cannot read image data");
}

/* ------------------------------------------------------------ the image module */

/* @return whether text contains every one of the NULL-terminated list of parts. */
static int names_all(const char *text, const char *const *parts)
{
    for (; *parts != NULL; parts++)
        if (strstr(text, *parts) == NULL)
            return 0;
    return 1;
}

/* With the module pinned to module_path (which cannot serve), a read fails with its status and a
 * message naming the image, module_path and why (NULL: not checked), while a write, which needs no
 * module, succeeds; OpenImageIO is not mapped. Argument errors are reported as before. */
static void expect_unavailable(const char *module_path, const char *why)
{
    const char *image = tmp_path("unavailable.png");
    char probe[PATH_BYTES], err[1024];
    snprintf(probe, sizeof probe, "%s/capture/probes/studio.exr", data_dir);
    const float px[3] = {0.5f, 0.25f, 1.0f};
    remove(image);
    CHECK(img_write(image, 1, 1, 3, px, err, sizeof err) == IMG_OK && access(image, F_OK) == 0,
          "a write needs no module: %s", err);
    img_image img;
    CHECK(img_read(probe, &img, err, sizeof err) == IMG_ERR_INPUT, "read without a module: %s", err);
    const char *read_parts[] = {probe, module_path, "cannot read", "not available", why, NULL};
    CHECK(names_all(err, read_parts), "the message names image, module and cause: %s", err);
    CHECK(img.pixels == NULL && img.width == 0, "a failed read leaves the image zeroed");
    /* The image library keeps no message of its own: capture passes the image's message on through
     * cap_error_message(), after the manifest and element, with the image's status. */
    char manifest[PATH_BYTES];
    snprintf(manifest, sizeof manifest, "%s/capture/studio.json", data_dir);
    cap_manifest *m = NULL;
    lfio_lightfield *lf = NULL;
    cap_capture_options o = {1, NULL, NULL};
    CHECK(cap_manifest_load(manifest, &m) == CAP_OK, "%s", cap_error_message());
    CHECK(m != NULL && cap_capture_run(m, &o, &lf, NULL) == CAP_ERR_INPUT && lf == NULL,
          "a capture without a module fails as bad input: %s", cap_error_message());
    const char *capture_parts[] = {manifest, err, NULL};
    CHECK(names_all(cap_error_message(), capture_parts), "cap_error_message() names the manifest and gives the"
          " image's message (%s): %s", err, cap_error_message());
    cap_manifest_destroy(m);
    CHECK(img_write(tmp_path("unavailable.tif"), 1, 1, 3, px, err, sizeof err) == IMG_ERR_ARG,
          "a bad extension is still a bad argument: %s", err);
    CHECK(check_mapped("libOpenImageIO") == 0, "no OpenImageIO mapped after a failed load");
}

/* Runs expect_unavailable(module_path, why) in a child process whose module is pinned to
 * module_path; the module loads once per process, so this process must not have loaded it yet. */
static void in_child_without_module(const char *module_path, const char *why)
{
    fflush(stdout);
    fflush(stderr);
    long failed_before = check_failed;
    pid_t pid = fork();
    if (pid == 0) {
        setenv("ILFKIT_IMAGE_MODULE", module_path, 1);
        expect_unavailable(module_path, why);
        fflush(stdout);
        _exit(check_failed > failed_before ? 1 : 0);
    }
    int status = -1;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0,
          "the child pinned to %s passed its checks (wait status %d)", module_path, status);
}

static void test_unavailable_module(void)
{
    in_child_without_module(tmp_path("no-such-dir/libilfkit_oiio.so"), NULL);
    in_child_without_module(STALE_IMAGE_MODULE, "module version");
}

/* Must be this process's first image call. */
static void test_lazy_module(void)
{
    CHECK(check_mapped("libOpenImageIO") == 0, "OpenImageIO is not mapped before the first image call");
    CHECK(check_mapped("libilfkit_oiio") == 0, "the image module is not mapped before the first image call");
    img_image img = {1, 1, 1, NULL, 0, 8};
    img_free(&img);
    CHECK(img_guess_format("a/b.Exr") == IMG_FORMAT_EXR && img_guess_format("b.PNG") ==
          IMG_FORMAT_PNG && img_guess_format("b.exr/c") == IMG_FORMAT_UNKNOWN,
          "formats by extension");
    CHECK(check_mapped("libOpenImageIO") == 0, "guessing formats and freeing images load nothing");
    const float px[2 * 2 * 3] = {0, 0.5f, 1, 2, 3, 4, -1, 1e6f, 0.25f, 7, 8, 9};
    char err[512];
    CHECK(img_write(tmp_path("lazy.exr"), 2, 2, 3, px, err, sizeof err) == IMG_OK, "%s", err);
    CHECK(check_mapped("libilfkit_oiio") == 0 && check_mapped("libOpenImageIO") == 0, "a write loads nothing of OpenImageIO");
    CHECK(img_read(tmp_path("lazy.exr"), &img, err, sizeof err) == IMG_OK, "%s", err);
    CHECK(check_mapped("libilfkit_oiio") == 1, "the image module is mapped after the first read");
    CHECK(check_mapped("libOpenImageIO") == 1, "OpenImageIO is mapped after the first read");
    CHECK(img.width == 2 && img.height == 2 && img.channels == 3 && !img.integer && img.bits == 32 &&
              memcmp(img.pixels, px, sizeof px) == 0,
          "32-bit float EXR read back exactly");
    img_free(&img);
}

/* ------------------------------------------------------------ the real probe */

static void test_real_probe(void)
{
    char manifest[PATH_BYTES], image[PATH_BYTES];
    snprintf(manifest, sizeof manifest, "%s/capture/studio.json", data_dir);
    snprintf(image, sizeof image, "%s/capture/probes/studio.exr", data_dir);
    img_image img;
    char err[256];
    uint64_t negative = 0;
    CHECK(img_read(image, &img, err, sizeof err) == IMG_OK, "%s", err);
    for (size_t p = 0; p < (size_t)img.width * img.height; p++)
        for (int c = 0; c < 3; c++)
            negative += img.pixels[p * img.channels + c] < 0.0f;
    CHECK(!img.integer && img.bits == 16, "studio.exr is half float");
    img_free(&img);
    cap_report r;
    lfio_lightfield *lf = capture_file(manifest, 2, &r);
    if (lf == NULL)
        return;
    printf("real probe studio.exr (n=%u): energy error %.4f%% (field %.4f vs image %.4f, green), %llu negative values"
           " repaired (lowest %g)\n",
           lfio_slab_get_desc(lfio_lightfield_slab(lf, 0))->n, 100 * r.energy_error, r.energy_field[1],
           r.energy_image[1], (unsigned long long)r.negative, r.repair_count ? (double)r.repairs[0].lowest : 0.0);
    CHECK(r.energy_error < 0.005, "real probe energy within 0.5%%: %g", r.energy_error);
    CHECK(r.negative == negative && negative == 2028, "negative values %llu, counted %llu",
          (unsigned long long)r.negative, (unsigned long long)negative);
    CHECK(r.nan == 0 && r.infinite == 0 && r.repair_count == 1, "one image repaired");
    CHECK(r.repair_count == 1 && r.repairs[0].lowest < -149.0f && r.repairs[0].lowest > -150.0f, "lowest about -149");
    cap_report_free(&r);
    lfio_lightfield_destroy(lf);
}

/* ------------------------------------------------------------ closed loop */

/* cap_radiance_fn over a relit scene. */
static int trace_scene(void *user, const double org[3], const double dir[3], float rgb[3])
{
    return rl_solution_trace(user, org, dir, rgb) == RL_OK;
}

/* A relit scene seen from point x, as an incoming_fn. */
typedef struct scene_source {
    const rl_solution *sol;
    double x[3];
} scene_source;

static void from_scene(const void *ctx, const double d[3], double v[3])
{
    const scene_source *src = ctx;
    float rgb[3];
    rl_solution_trace(src->sol, src->x, d, rgb);
    for (int c = 0; c < 3; c++)
        v[c] = rgb[c];
}

/* The scene's box-mean radiance through position x of slab s, per solid angle, vs the stored field:
 * relative L1 error; irradiance of the reference and of the field in *e_ref, *e_field (green). */
static double loop_error(const rl_solution *sol, const lfio_slab *s, uint32_t i, uint32_t j, double *e_ref,
                         double *e_field)
{
    const uint32_t n = lfio_slab_get_desc(s)->n;
    const double pole[3] = {0, 0, 1};
    scene_source src = {sol, {0, 0, 0}};
    double diff = 0.0, total = 0.0;
    float *rgb = malloc(lfio_slab_dir_count(s) * 3 * sizeof *rgb);
    lfio_slab_read_position(s, i, j, rgb);
    lfio_slab_position(s, i, j, src.x);
    *e_ref = *e_field = 0.0;
    for (uint64_t id = 0; id < lfio_slab_dir_count(s); id++) {
        double ref[3], proj = lfio_part_projected_solid_angle(n, id, pole);
        box_mean(s, id, 4, from_scene, &src, ref);
        for (int c = 0; c < 3; c++) {
            diff += fabs(rgb[3 * id + c] - ref[c]);
            total += ref[c];
        }
        *e_ref += ref[1] * proj;
        *e_field += rgb[3 * id + 1] * proj;
    }
    free(rgb);
    return diff / total;
}

/* Renders the probes of a 2x2 grid into tmp and writes their manifest. */
static void render_loop_probes(const rl_solution *sol, const lfio_slab_desc *d)
{
    cap_probe_settings ps = {256, 128, 2, 1, 0, NULL, NULL};
    float *px = malloc((size_t)ps.width * ps.height * 3 * sizeof *px);
    char name[64], err[256];
    for (uint32_t j = 0; j < d->nv; j++)
        for (uint32_t i = 0; i < d->nu; i++) {
            double x[3];
            for (int a = 0; a < 3; a++)
                x[a] = d->origin[a] + (i + 0.5) / d->nu * d->u[a] + (j + 0.5) / d->nv * d->v[a];
            CHECK(cap_probe_render(&ps, trace_scene, (void *)sol, x, NULL, px) == CAP_OK, "%s", cap_error_message());
            snprintf(name, sizeof name, "loop_%u_%u.exr", i, j);
            CHECK(img_write(tmp_path(name), ps.width, ps.height, 3, px, err, sizeof err) == IMG_OK, "%s", err);
        }
    free(px);
    write_text(tmp_path("loop.json"), "{\"plane\": {\"origin\": [-0.5, 0.5, 1.5], \"u\": [1, 0, 0], \"v\": [0, -1, 0]},"
                                      " \"grid\": {\"nu\": 2, \"nv\": 2}, \"n\": 16, \"colour_space\": \"linear\","
                                      " \"pattern\": \"loop_{i}_{j}.exr\"}");
}

/* Loads data/capture/scene.json and relights it with its own settings; *scene and *sol stay NULL where that
 * fails (a failed check). */
static void relight_capture_scene(rl_scene **scene, rl_solution **sol)
{
    char scene_path[PATH_BYTES];
    snprintf(scene_path, sizeof scene_path, "%s/capture/scene.json", data_dir);
    CHECK(rl_scene_load(scene_path, scene) == RL_OK, "%s", rl_errmsg());
    CHECK(*scene == NULL || rl_relight(*scene, NULL, sol) == RL_OK, "%s", rl_errmsg());
}

static void test_closed_loop(void)
{
    rl_scene *scene = NULL;
    rl_solution *sol = NULL;
    relight_capture_scene(&scene, &sol);
    if (sol == NULL) {
        rl_scene_destroy(scene);
        return;
    }
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    const double origin[3] = {-0.5, 0.5, 1.5}, u[3] = {1, 0, 0}, v[3] = {0, -1, 0};
    memcpy(d.origin, origin, sizeof origin);
    memcpy(d.u, u, sizeof u);
    memcpy(d.v, v, sizeof v);
    d.nu = d.nv = 2;
    render_loop_probes(sol, &d);
    cap_report r;
    lfio_lightfield *lf = capture_file(tmp_path("loop.json"), 0, &r);
    if (lf != NULL) {
        const lfio_slab *s = lfio_lightfield_slab(lf, 0);
        double worst = 0.0, worst_e = 0.0;
        for (uint32_t j = 0; j < 2; j++)
            for (uint32_t i = 0; i < 2; i++) {
                double e_ref, e_field, err = loop_error(sol, s, i, j, &e_ref, &e_field);
                worst = fmax(worst, err);
                worst_e = fmax(worst_e, fabs(e_field / e_ref - 1));
            }
        printf("closed loop capture(render-probes(scene)) vs the scene's radiance through the plane: relative L1 "
               "%.2f%% (worst position), irradiance %.3f%%; capture energy check %.3f%%\n",
               100 * worst, 100 * worst_e, 100 * r.energy_error);
        CHECK(worst < 0.08, "closed-loop radiance error %g", worst);
        CHECK(worst_e < 0.015, "closed-loop irradiance error %g", worst_e);
        CHECK(r.energy_error < 0.005, "energy %g", r.energy_error);
        cap_report_free(&r);
        lfio_lightfield_destroy(lf);
    }
    rl_solution_destroy(sol);
    rl_scene_destroy(scene);
}

/* ------------------------------------------------------------ depth correction */

/* A 0.2 m square emitter of radiance 10 at z = 1, facing down; captured on the plane z = 0.6. */
#define EMITTER_HALF 0.1
#define EMITTER_Z 1.0
#define EMITTER_L 10.0

/* Radiance seen from x looking along d (world, unit) when only the emitter is there. */
static double emitter_seen(const double x[3], const double d[3])
{
    if (d[2] <= 0.0)
        return 0.0;
    double t = (EMITTER_Z - x[2]) / d[2];
    double qx = x[0] + t * d[0], qy = x[1] + t * d[1];
    return t > 0.0 && fabs(qx) <= EMITTER_HALF && fabs(qy) <= EMITTER_HALF ? EMITTER_L : 0.0;
}

/* The capture of the emitter made directly on the plane origin + s u + t v (nu x nv positions, n = 16): each
 * solid angle's box mean over 5x5 directions. */
static lfio_slab *emitter_capture_on(const double origin[3], const double u[3], const double v[3], uint32_t nu,
                                     uint32_t nv)
{
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    snprintf(d.name, sizeof d.name, "capture");
    memcpy(d.origin, origin, sizeof d.origin);
    memcpy(d.u, u, sizeof d.u);
    memcpy(d.v, v, sizeof d.v);
    d.nu = nu;
    d.nv = nv;
    d.n = 16;
    lfio_slab *s = NULL;
    CHECK(lfio_slab_new(&d, &s) == LFIO_OK, "%s", lfio_errmsg());
    float *rgb = malloc(lfio_slab_dir_count(s) * 3 * sizeof *rgb);
    double dirs[5 * 5 * 3], weights[25];
    for (uint32_t j = 0; j < d.nv; j++)
        for (uint32_t i = 0; i < d.nu; i++) {
            double x[3];
            lfio_slab_position(s, i, j, x);
            for (uint64_t id = 0; id < lfio_slab_dir_count(s); id++) {
                double sum = 0.0;
                cap_partition_samples(d.n, id, 5, dirs, weights);
                for (int q = 0; q < 25; q++) {
                    double w[3], look[3];
                    lfio_slab_to_world(s, &dirs[3 * q], w);
                    look[0] = -w[0], look[1] = -w[1], look[2] = -w[2];
                    sum += weights[q] * emitter_seen(x, look);
                }
                rgb[3 * id] = rgb[3 * id + 1] = rgb[3 * id + 2] = (float)sum;
            }
            lfio_slab_write_position(s, i, j, rgb);
        }
    free(rgb);
    return s;
}

/* The capture plane of the depth-correction test: 2 m square at z = 0.6, 16 x 16 positions, facing down. */
static lfio_slab *emitter_capture(void)
{
    const double origin[3] = {-1, 1, 0.6}, u[3] = {2, 0, 0}, v[3] = {0, -2, 0};
    return emitter_capture_on(origin, u, v, 16, 16);
}

/* Writes slab s (ownership taken) alone to tmp/name. */
static void write_slab(lfio_slab *s, const char *name)
{
    lfio_lightfield *lf = NULL;
    lfio_lightfield_new(&lf);
    lfio_lightfield_take_slab(lf, s);
    CHECK(lfio_lightfield_write(lf, tmp_path(name)) == LFIO_OK, "%s", lfio_errmsg());
    lfio_lightfield_destroy(lf);
}

/* Share of a proxy slab's power (radiance times projected solid angle times cell area, summed over
 * positions and over the directions within acos(cos_min) of its normal) leaving from the emitter's
 * footprint; *total: that power over the whole slab, W. */
static double cap_norm_product(const lfio_slab_desc *d)
{
    return sqrt(dot3(d->u, d->u)) * sqrt(dot3(d->v, d->v));
}

static double footprint_share(const lfio_slab *s, double cos_min, double *total)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(s);
    const double pole[3] = {0, 0, 1};
    float *rgb = malloc(lfio_slab_dir_count(s) * 3 * sizeof *rgb);
    double in = 0.0, all = 0.0, cell = cap_norm_product(d) / ((double)d->nu * d->nv);
    for (uint32_t j = 0; j < d->nv; j++)
        for (uint32_t i = 0; i < d->nu; i++) {
            double x[3], power = 0.0;
            lfio_slab_position(s, i, j, x);
            lfio_slab_read_position(s, i, j, rgb);
            for (uint64_t id = 0; id < lfio_slab_dir_count(s); id++) {
                double c[3];
                lfio_part_centroid(d->n, id, c);
                if (c[2] >= cos_min)
                    power += rgb[3 * id + 1] * lfio_part_projected_solid_angle(d->n, id, pole);
            }
            all += power;
            if (fabs(x[0]) < EMITTER_HALF && fabs(x[1]) < EMITTER_HALF)
                in += power;
        }
    free(rgb);
    *total = all * cell;
    return in / all;
}

/* Reprojects the count captured slabs onto the emitter's plane (0.6 m square, 24x24, n = 8) in mode. */
static lfio_slab *reproject_onto_emitter(const lfio_slab *const *captured, size_t count, cap_reproject_mode mode,
                                         cap_coverage *cov)
{
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    snprintf(d.name, sizeof d.name, "lamp");
    const double origin[3] = {-0.3, 0.3, EMITTER_Z}, u[3] = {0.6, 0, 0}, v[3] = {0, -0.6, 0};
    memcpy(d.origin, origin, sizeof origin);
    memcpy(d.u, u, sizeof u);
    memcpy(d.v, v, sizeof v);
    d.nu = d.nv = 24;
    d.n = 8;
    cap_reproject_options o = {mode, 2, 0, NULL, NULL, NULL};
    lfio_slab *out = NULL;
    CHECK(cap_reproject_field(captured, count, &d, &o, &out, cov) == CAP_OK, "%s", cap_error_message());
    return out;
}

#define FLOOR                                                                                                         \
    "{\"material\": \"floor\", \"vertices\": [[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]]}"
/* Relighting accurate enough (about 2% per cell) that the fields, not the sampling, make the differences. */
#define SCENE_REST                                                                                                    \
    "\"radiance_maps\": {\"cell_size\": 0.1}, \"sampling\": {\"partition_n\": 64, \"rays_per_solid_angle\": 4}"

/* Relights tmp/scene_name (written from text) and copies the irradiance (green) per cell of each polygon whose bit
 * is set in polygons, in polygon order, with the cells' centres and areas (either may be NULL). @return cells. */
static uint32_t map_irradiance(const char *scene_name, const char *text, unsigned polygons, double *out,
                               double *centres, double *areas)
{
    write_text(tmp_path(scene_name), text);
    rl_scene *scene = NULL;
    rl_solution *sol = NULL;
    uint32_t count = 0;
    CHECK(rl_scene_load(tmp_path(scene_name), &scene) == RL_OK, "%s", rl_errmsg());
    CHECK(scene == NULL || rl_relight(scene, NULL, &sol) == RL_OK, "%s", rl_errmsg());
    for (size_t k = 0; sol != NULL && k < rl_solution_map_count(sol); k++) {
        rl_map_info m;
        rl_solution_map_info(sol, k, &m);
        if (m.polygon >= 8 * sizeof polygons || !(polygons >> m.polygon & 1u))
            continue;
        float *e = malloc((size_t)m.ncells * 3 * sizeof *e);
        rl_solution_map_cells(sol, k, NULL, areas != NULL ? areas + count : NULL,
                              centres != NULL ? centres + 3 * count : NULL, e, NULL);
        for (uint32_t c = 0; c < m.ncells; c++)
            out[count + c] = e[3 * c + 1];
        count += m.ncells;
        free(e);
    }
    rl_solution_destroy(sol);
    rl_scene_destroy(scene);
    return count;
}

/* Relative RMS difference of b against a over count cells. */
static double rms_error(const double *a, const double *b, uint32_t count)
{
    double num = 0.0, den = 0.0;
    for (uint32_t c = 0; c < count; c++) {
        num += (b[c] - a[c]) * (b[c] - a[c]);
        den += a[c] * a[c];
    }
    return sqrt(num / den);
}

/*
 * The emitter's rectangle as a mesh proxy: an OBJ quad, the quad as two triangles split along its first
 * diagonal (the fan exporters and assimp write), and split along the other one. Also each sample's coverage:
 * 0 exactly where the radiance has no covered ray, kept through a file.
 */
static void test_triangulated_proxy(const lfio_slab *captured)
{
    static const char *const files[3][2] = {
        {"lamp_quad.obj", "f 1 2 3 4\n"}, {"lamp_fan.obj", "f 1 2 3\nf 1 3 4\n"}, {"lamp_diag.obj", "f 1 2 4\nf 2 3 4\n"}};
    const cap_proxy_defaults def = {24, 24, 8};
    const size_t samples = 4 * 8 * 8 * 24 * 24;
    lfio_slab *out[3] = {NULL, NULL, NULL};
    uint8_t *covered[3];
    cap_coverage cov[3];
    double power[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        char text[256];
        snprintf(text, sizeof text, "v -0.3 0.3 %g\nv 0.3 0.3 %g\nv 0.3 -0.3 %g\nv -0.3 -0.3 %g\n%s", EMITTER_Z,
                 EMITTER_Z, EMITTER_Z, EMITTER_Z, files[k][1]);
        write_text(tmp_path(files[k][0]), text);
        cap_proxy *p = NULL;
        CHECK(cap_proxy_load(tmp_path(files[k][0]), &def, &p) == CAP_OK && cap_proxy_count(p) == 1, "%s: %s",
              files[k][0], cap_error_message());
        covered[k] = malloc(samples);
        memset(covered[k], 7, samples);
        cap_reproject_options o = {CAP_REPROJECT_DEPTH, 2, 0, NULL, NULL, covered[k]};
        if (p != NULL)
            CHECK(cap_reproject_slab(captured, cap_proxy_get_desc(p, 0), &o, &out[k], &cov[k]) == CAP_OK, "%s: %s",
                  files[k][0], cap_error_message());
        cap_proxy_destroy(p);
        if (out[k] != NULL)
            footprint_share(out[k], cos(PI / 4), &power[k]);
    }
    if (out[0] != NULL && out[1] != NULL && out[2] != NULL) {
        const size_t bytes = samples * 3 * sizeof(float);
        CHECK(memcmp(lfio_slab_radiance(out[0]), lfio_slab_radiance(out[1]), bytes) == 0 &&
                  memcmp(covered[0], covered[1], samples) == 0 && cov[0].covered == cov[1].covered,
              "a quad triangulated along its first diagonal reprojects bit for bit as the quad");
        printf("triangulated proxy: other diagonal: coverage %.3f%% vs %.3f%%, power within 45 degrees %.5f W vs "
               "%.5f W (quad)\n", 100 * cov[2].fraction, 100 * cov[0].fraction, power[2], power[0]);
        CHECK(fabs(cov[2].fraction - cov[0].fraction) < 0.002, "other diagonal: coverage %g vs %g", cov[2].fraction,
              cov[0].fraction);
        CHECK(fabs(power[2] / power[0] - 1) < 0.01, "other diagonal: power %g vs %g", power[2], power[0]);

        /* Each sample's coverage: 0 or 1, 0 only where the radiance is exactly 0, and its etendue-weighted share
         * at least the exact share of covered rays (a sample counts once any of its rays is covered). */
        const float *rad = lfio_slab_radiance(out[0]);
        const double pole[3] = {0, 0, 1};
        size_t bad = 0, ones = 0;
        double share = 0.0;
        for (size_t e = 0; e < samples; e++) {
            bad += covered[0][e] > 1 || (covered[0][e] == 0 && (rad[3 * e] != 0 || rad[3 * e + 1] != 0 ||
                                                                 rad[3 * e + 2] != 0));
            ones += covered[0][e];
            share += covered[0][e] * lfio_part_projected_solid_angle(8, e / (24 * 24), pole);
        }
        share /= PI * 24 * 24;
        printf("sample coverage: %zu of %zu samples, %.2f%% of the etendue (rays: %.2f%%)\n", ones, samples,
               100 * share, 100 * cov[0].fraction);
        CHECK(bad == 0, "%zu samples not 0/1 or uncovered with radiance", bad);
        CHECK(ones > 0 && ones < samples, "some samples covered, some not: %zu", ones);
        CHECK(share >= cov[0].fraction && share < cov[0].fraction + 0.05, "sample share %g vs ray share %g", share,
              cov[0].fraction);

        /* Through a file: the coverage dataset comes back as written. */
        lfio_lightfield *lf = NULL, *back = NULL;
        lfio_lightfield_new(&lf);
        lfio_lightfield_take_slab(lf, out[0]);
        out[0] = NULL;
        CHECK(lfio_lightfield_set_coverage(lf, 0, covered[0]) == LFIO_OK, "%s", lfio_errmsg());
        CHECK(lfio_lightfield_write(lf, tmp_path("lamp_coverage.h5")) == LFIO_OK, "%s", lfio_errmsg());
        CHECK(lfio_lightfield_read(tmp_path("lamp_coverage.h5"), &back) == LFIO_OK, "%s", lfio_errmsg());
        CHECK(back != NULL && lfio_lightfield_coverage(back, 0) != NULL &&
                  memcmp(lfio_lightfield_coverage(back, 0), covered[0], samples) == 0,
              "coverage read back");
        CHECK(back != NULL && isnan(lfio_lightfield_coverage_fraction(back, 0)),
              "a file written without a covered share reads back without one");
        lfio_lightfield_destroy(back);
        lfio_lightfield_destroy(lf);
    }
    for (int k = 0; k < 3; k++) {
        lfio_slab_destroy(out[k]);
        free(covered[k]);
    }
}

/*
 * The depth-correction test with several planes: the capture plane under the emitter plus four sides of the box
 * it closes (x, y = +-1, from z = 0.6 up to the emitter's plane, facing out, 16 x 4 positions each), merged onto
 * the proxy. The sides cover the grazing rays the plane under it misses: coverage rises to about 1, and with it
 * the power the field carries in all directions (true: L pi A). below: the power from the plane under it alone.
 */
static void test_depth_planes(lfio_slab *under, double below)
{
    const double z = 0.6, h = EMITTER_Z - z;
    const double sides[4][3][3] = {{{1, -1, z}, {0, 2, 0}, {0, 0, h}}, {{-1, 1, z}, {0, -2, 0}, {0, 0, h}},
                                   {{1, 1, z}, {-2, 0, 0}, {0, 0, h}}, {{-1, -1, z}, {2, 0, 0}, {0, 0, h}}};
    lfio_slab *slabs[5] = {under, NULL, NULL, NULL, NULL};
    for (int k = 0; k < 4; k++)
        slabs[k + 1] = emitter_capture_on(sides[k][0], sides[k][1], sides[k][2], 16, 4);
    cap_coverage cov;
    lfio_slab *box = reproject_onto_emitter((const lfio_slab *const *)slabs, 5, CAP_REPROJECT_DEPTH, &cov);
    double power = 0.0, near_power = 0.0, truth = EMITTER_L * PI * 0.04;
    if (box != NULL) {
        double share = footprint_share(box, 0.0, &power), near = footprint_share(box, cos(PI / 4), &near_power);
        printf("depth correction from 5 planes: coverage %.2f%%, power %.4f W (true %.4f; plane under it alone "
               "%.4f), within 45 degrees %.4f W, share from the footprint %.1f%% (within 45 degrees %.1f%%)\n",
               100 * cov.fraction, power, truth, below, near_power, 100 * share, 100 * near);
        CHECK(cov.fraction > 0.99, "coverage from 5 planes %g", cov.fraction);
        CHECK(fabs(power / truth - 1) < fabs(below / truth - 1) && fabs(power / truth - 1) < 0.05,
              "power from 5 planes %g W, from one %g W, true %g W", power, below, truth);
        CHECK(fabs(near_power / (EMITTER_L * PI * 0.5 * 0.04) - 1) < 0.03, "within 45 degrees %g W", near_power);
    }
    lfio_slab_destroy(box);
    for (int k = 1; k < 5; k++)
        lfio_slab_destroy(slabs[k]);
}

static void test_depth_correction(void)
{
    lfio_slab *captured = emitter_capture();
    cap_coverage cov_depth, cov_plain;
    lfio_slab *depth = reproject_onto_emitter((const lfio_slab *const *)&captured, 1, CAP_REPROJECT_DEPTH, &cov_depth);
    lfio_slab *plain = reproject_onto_emitter((const lfio_slab *const *)&captured, 1, CAP_REPROJECT_PLAIN, &cov_plain);
    if (depth == NULL || plain == NULL)
        return;
    double all_depth, all_plain, near_power, unused;
    double share_depth = footprint_share(depth, 0.0, &all_depth), share_plain = footprint_share(plain, 0.0, &all_plain);
    double near_depth = footprint_share(depth, cos(PI / 4), &near_power);
    double near_plain = footprint_share(plain, cos(PI / 4), &unused);
    /* a Lambertian square of side 0.2 m and radiance L sends L * pi * sin^2(45 deg) * area within 45 degrees */
    double near_true = EMITTER_L * PI * 0.5 * 0.04;
    printf("depth correction: share of the reprojected field's power leaving the emitter's footprint (11%% of the "
           "proxy): all directions %.1f%% depth-corrected, %.1f%% plain; within 45 degrees of the normal %.1f%% and "
           "%.1f%%; power within 45 degrees %.4f W (true %.4f); coverage %.1f%%\n",
           100 * share_depth, 100 * share_plain, 100 * near_depth, 100 * near_plain, near_power, near_true,
           100 * cov_depth.fraction);
    CHECK(near_depth > 0.8, "depth-corrected field concentrates on the footprint: %g", near_depth);
    CHECK(share_depth > share_plain + 0.1 && near_depth > near_plain + 0.1, "depth correction concentrates more");
    CHECK(fabs(near_power / near_true - 1) < 0.03, "power within 45 degrees kept: %g W", near_power);
    CHECK(cov_depth.fraction > 0.5 && cov_depth.fraction < 1.0 && cov_depth.covered < cov_depth.rays,
          "coverage %g", cov_depth.fraction);
    test_triangulated_proxy(captured);
    test_depth_planes(captured, all_depth);
    write_slab(captured, "depth_capture.h5");
    write_slab(depth, "depth_depth.h5");
    write_slab(plain, "depth_plain.h5");

    static double e_a[256], e_b[256], e_c[256], e_p[256], centres[3 * 256];
    const char *mats = "{\"materials\": {\"floor\": {\"albedo\": [0.5, 0.5, 0.5]}, \"lamp\": {\"albedo\": [0, 0, 0],"
                       " \"emission\": [10, 10, 10]}},\n";
    char text[2048];
    snprintf(text, sizeof text, "%s\"polygons\": [" FLOOR ", {\"material\": \"lamp\", \"vertices\": [[-0.1, -0.1, 1],"
             " [-0.1, 0.1, 1], [0.1, 0.1, 1], [0.1, -0.1, 1]]}],\n" SCENE_REST "}", mats);
    uint32_t cells = map_irradiance("depth_a.json", text, 1u, e_a, centres, NULL);
    const char *fields[3] = {"depth_capture.h5", "depth_depth.h5", "depth_plain.h5"};
    double *outs[3] = {e_b, e_c, e_p};
    for (int k = 0; k < 3; k++) {
        char name[32];
        snprintf(text, sizeof text,
                 "%s\"polygons\": [" FLOOR "], \"lightfields\": [{\"file\": \"%s\"}],\n" SCENE_REST "}", mats,
                 fields[k]);
        snprintf(name, sizeof name, "depth_%d.json", k);
        CHECK(map_irradiance(name, text, 1u, outs[k], centres, NULL) == cells, "same floor cells");
    }
    /* Lambert's formula averaged over each 0.1 m cell (4 x 4 points): the truth all three are measured against */
    double exact[256] = {0};
    const double lamp[12] = {-0.1, -0.1, 1, -0.1, 0.1, 1, 0.1, 0.1, 1, 0.1, -0.1, 1}, up[3] = {0, 0, 1};
    for (uint32_t c = 0; c < cells; c++)
        for (int q = 0; q < 16; q++) {
            double x[3] = {centres[3 * c] + 0.1 * ((q % 4 + 0.5) / 4 - 0.5),
                           centres[3 * c + 1] + 0.1 * ((q / 4 + 0.5) / 4 - 0.5), 0.0};
            exact[c] += rl_reference_polygon_irradiance(lamp, 4, x, up, EMITTER_L) / 16;
        }
    double err_b = rms_error(e_a, e_b, cells), err_c = rms_error(e_a, e_c, cells), err_p = rms_error(e_a, e_p, cells);
    printf("depth correction, floor irradiance (relative RMS over %u cells) vs relighting with the true emitter: raw "
           "capture plane %.2f%%, reprojected %.2f%% (plain lookup %.2f%%); vs Lambert cell means: true emitter "
           "%.2f%%, raw %.2f%%, reprojected %.2f%%\n",
           cells, 100 * err_b, 100 * err_c, 100 * err_p, 100 * rms_error(exact, e_a, cells),
           100 * rms_error(exact, e_b, cells), 100 * rms_error(exact, e_c, cells));
    CHECK(cells == 100, "the floor has 100 cells: %u", cells);
    CHECK(err_c < err_b, "reprojected field closer to the true emitter than the raw capture: %g vs %g", err_c, err_b);
    CHECK(err_c < 0.04, "reprojected field within 4%% of the true emitter's: %g", err_c);
    CHECK(rms_error(exact, e_c, cells) < rms_error(exact, e_b, cells), "also against Lambert");
}


/* ------------------------------------------------------------ a lamp captured from several planes */

/* The quick start's scene (data/capture/scene.json): a 0.4 m lamp of radiance 10 at z = 2 facing down over a
 * floor, a red wall at x = 1 and a green wall at x = -1. The capture box around the lamp: a plane under it at
 * z = LAMP_BOX_Z and four sides up to the lamp's plane, every one facing out (e3 away from the lamp). */
#define LAMP_BOX_HALF 0.6
#define LAMP_BOX_Z 1.4
#define LAMP_PLANES 5
#define LAMP_PROBE_W 128
#define LAMP_PROBE_H 64
static const struct {
    double origin[3], u[3], v[3];
    uint32_t nu, nv;
} lamp_box[LAMP_PLANES] = {
    {{-LAMP_BOX_HALF, LAMP_BOX_HALF, LAMP_BOX_Z}, {2 * LAMP_BOX_HALF, 0, 0}, {0, -2 * LAMP_BOX_HALF, 0}, 2, 2},
    {{LAMP_BOX_HALF, -LAMP_BOX_HALF, LAMP_BOX_Z}, {0, 2 * LAMP_BOX_HALF, 0}, {0, 0, 2 - LAMP_BOX_Z}, 2, 1},
    {{-LAMP_BOX_HALF, LAMP_BOX_HALF, LAMP_BOX_Z}, {0, -2 * LAMP_BOX_HALF, 0}, {0, 0, 2 - LAMP_BOX_Z}, 2, 1},
    {{LAMP_BOX_HALF, LAMP_BOX_HALF, LAMP_BOX_Z}, {-2 * LAMP_BOX_HALF, 0, 0}, {0, 0, 2 - LAMP_BOX_Z}, 2, 1},
    {{-LAMP_BOX_HALF, -LAMP_BOX_HALF, LAMP_BOX_Z}, {2 * LAMP_BOX_HALF, 0, 0}, {0, 0, 2 - LAMP_BOX_Z}, 2, 1},
};

#define LAMP_MATERIALS                                                                                                \
    "{\"materials\": {\"white\": {\"albedo\": [0.7, 0.7, 0.7]}, \"red\": {\"albedo\": [0.7, 0.15, 0.1]},"         \
    " \"green\": {\"albedo\": [0.15, 0.6, 0.15]}, \"lamp\": {\"albedo\": [0, 0, 0], \"emission\": [10, 10, 10]}},\n"
#define LAMP_ROOM                                                                                                     \
    "{\"material\": \"white\", \"vertices\": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]},"                   \
    " {\"material\": \"red\", \"vertices\": [[1, -1, 0], [1, -1, 2.5], [1, 1, 2.5], [1, 1, 0]]},"                  \
    " {\"material\": \"green\", \"vertices\": [[-1, -1, 0], [-1, 1, 0], [-1, 1, 2.5], [-1, -1, 2.5]]}"
/* Direct light only, at partition level 32: at the scene's own 16, sampling the light field emitter alone
 * differs from the true lamp's exact formula by about 8% RMS on the floor (measured), which would hide the
 * capture's own error. */
#define LAMP_REST                                                                                                     \
    "\"radiance_maps\": {\"cell_size\": 0.1}, \"sampling\": {\"partition_n\": 32, \"rays_per_solid_angle\": 2,"   \
    " \"bounces\": 0}}"

/* Renders the probes of the capture box from the relit scene and writes their manifest, tmp/lamp_box.json. */
static void render_lamp_box(const rl_solution *sol)
{
    cap_probe_settings ps = {LAMP_PROBE_W, LAMP_PROBE_H, 2, 1, 0, NULL, NULL};
    float *px = malloc((size_t)ps.width * ps.height * 3 * sizeof *px);
    char name[64], err[256], text[4096];
    size_t len = (size_t)snprintf(text, sizeof text, "{\"n\": 16, \"colour_space\": \"linear\", \"planes\": [");
    for (int k = 0; k < LAMP_PLANES; k++) {
        const double *o = lamp_box[k].origin, *u = lamp_box[k].u, *v = lamp_box[k].v;
        for (uint32_t j = 0; j < lamp_box[k].nv; j++)
            for (uint32_t i = 0; i < lamp_box[k].nu; i++) {
                double x[3];
                for (int a = 0; a < 3; a++)
                    x[a] = o[a] + (i + 0.5) / lamp_box[k].nu * u[a] + (j + 0.5) / lamp_box[k].nv * v[a];
                CHECK(cap_probe_render(&ps, trace_scene, (void *)sol, x, NULL, px) == CAP_OK, "%s",
                      cap_error_message());
                snprintf(name, sizeof name, "lamp_%d_%u_%u.exr", k, i, j);
                CHECK(img_write(tmp_path(name), ps.width, ps.height, 3, px, err, sizeof err) == IMG_OK, "%s", err);
            }
        len += (size_t)snprintf(text + len, sizeof text - len,
                                "%s{\"plane\": {\"origin\": [%g, %g, %g], \"u\": [%g, %g, %g], \"v\": [%g, %g, %g]},"
                                " \"grid\": {\"nu\": %u, \"nv\": %u}, \"slab\": \"side%d\","
                                " \"pattern\": \"lamp_%d_{i}_{j}.exr\"}",
                                k ? ", " : "", o[0], o[1], o[2], u[0], u[1], u[2], v[0], v[1], v[2], lamp_box[k].nu,
                                lamp_box[k].nv, k, k);
    }
    snprintf(text + len, sizeof text - len, "]}");
    write_text(tmp_path("lamp_box.json"), text);
    free(px);
}

/* Reprojects the first count slabs of lf onto the quick start's proxy (data/capture/proxy.json) and writes the
 * result, with its coverage share, to tmp/name. @return the covered share of the etendue, -1 on failure. */
static double reproject_lamp(const lfio_lightfield *lf, size_t count, const char *name)
{
    char path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/capture/proxy.json", data_dir);
    const cap_proxy_defaults def = {16, 16, 16};
    cap_proxy *proxy = NULL;
    CHECK(cap_proxy_load(path, &def, &proxy) == CAP_OK, "%s", cap_error_message());
    const lfio_slab *captured[LAMP_PLANES];
    for (size_t k = 0; k < count; k++)
        captured[k] = lfio_lightfield_slab(lf, k);
    lfio_slab *out = NULL;
    cap_coverage cov = {-1.0, 0, 0};
    if (proxy != NULL)
        CHECK(cap_reproject_field(captured, count, cap_proxy_get_desc(proxy, 0), NULL, &out, &cov) == CAP_OK, "%s",
              cap_error_message());
    cap_proxy_destroy(proxy);
    if (out == NULL)
        return -1.0;
    lfio_lightfield *field = NULL, *back = NULL;
    lfio_lightfield_new(&field);
    lfio_lightfield_take_slab(field, out);
    CHECK(lfio_lightfield_set_coverage_fraction(field, 0, 1.5) == LFIO_ERR_ARG &&
              lfio_lightfield_set_coverage_fraction(field, 0, -0.25) == LFIO_ERR_ARG &&
              lfio_lightfield_set_coverage_fraction(field, 1, 0.5) == LFIO_ERR_ARG &&
              isnan(lfio_lightfield_coverage_fraction(field, 0)),
          "a share outside [0, 1] or of no slab is refused; none is NaN");
    CHECK(lfio_lightfield_set_coverage_fraction(field, 0, cov.fraction) == LFIO_OK, "%s", lfio_errmsg());
    CHECK(lfio_lightfield_write(field, tmp_path(name)) == LFIO_OK, "%s", lfio_errmsg());
    lfio_lightfield_destroy(field);
    /* the share comes back from the file as the slab's coverage_fraction attribute */
    CHECK(lfio_lightfield_read(tmp_path(name), &back) == LFIO_OK && lfio_lightfield_coverage_fraction(back, 0) ==
                                                                        cov.fraction,
          "%s: coverage_fraction read back", name);
    lfio_lightfield_destroy(back);
    return cov.fraction;
}

/* Relights the room of tmp/name (written from text): irradiance per cell of the floor, then of the walls, into
 * e and their areas into areas (may be NULL). @return the floor's cells (they come first), *walls the walls'. */
static uint32_t relight_room(const char *name, const char *text, double *e, double *areas, uint32_t *walls)
{
    static double centres[3 * 1500];
    uint32_t count = map_irradiance(name, text, 7u, e, centres, areas), floor = 0;
    while (floor < count && centres[3 * floor + 2] == 0.0)
        floor++;
    *walls = count - floor;
    return floor;
}

/* Relative power difference of b against a over count cells of the given areas. */
static double power_error(const double *a, const double *b, const double *areas, uint32_t count)
{
    double pa = 0.0, pb = 0.0;
    for (uint32_t c = 0; c < count; c++) {
        pa += a[c] * areas[c];
        pb += b[c] * areas[c];
    }
    return pb / pa - 1.0;
}

/*
 * The quick start's lamp captured from a box of planes around it (a plane under it and four sides), merged
 * onto its rectangle: coverage near 1, and the room relit with the reprojected field (bounces 0) close to the
 * room relit with the true lamp, walls and floor; from the plane under it alone, coverage about half.
 */
static void test_lamp_planes(void)
{
    rl_scene *scene = NULL;
    rl_solution *sol = NULL;
    relight_capture_scene(&scene, &sol);
    if (sol != NULL)
        render_lamp_box(sol);
    rl_solution_destroy(sol);
    rl_scene_destroy(scene);
    lfio_lightfield *lf = sol != NULL ? capture_file(tmp_path("lamp_box.json"), 0, NULL) : NULL;
    if (lf == NULL)
        return;
    CHECK(lfio_lightfield_slab_count(lf) == LAMP_PLANES && lfio_lightfield_find(lf, "side3") != NULL,
          "one slab per plane, named by the manifest: %zu", lfio_lightfield_slab_count(lf));
    double all = reproject_lamp(lf, LAMP_PLANES, "lamp_box.h5"), one = reproject_lamp(lf, 1, "lamp_under.h5");
    lfio_lightfield_destroy(lf);

    static double e_true[1500], e_box[1500], e_one[1500], areas[1500];
    char text[4096];
    snprintf(text, sizeof text, LAMP_MATERIALS "\"polygons\": [" LAMP_ROOM ", {\"material\": \"lamp\", \"vertices\":"
             " [[-0.2, -0.2, 2], [-0.2, 0.2, 2], [0.2, 0.2, 2], [0.2, -0.2, 2]]}],\n" LAMP_REST);
    uint32_t walls = 0, walls_k = 0, floor = relight_room("lamp_true.json", text, e_true, areas, &walls);
    const char *fields[2] = {"lamp_box.h5", "lamp_under.h5"};
    double *outs[2] = {e_box, e_one};
    for (int k = 0; k < 2; k++) {
        snprintf(text, sizeof text, LAMP_MATERIALS "\"polygons\": [" LAMP_ROOM "], \"lightfields\": [{\"file\":"
                 " \"%s\"}],\n" LAMP_REST, fields[k]);
        CHECK(relight_room("lamp_field.json", text, outs[k], NULL, &walls_k) == floor && walls_k == walls,
              "same cells");
    }
    double floor_box = rms_error(e_true, e_box, floor), walls_box = rms_error(e_true + floor, e_box + floor, walls);
    double floor_one = rms_error(e_true, e_one, floor), walls_one = rms_error(e_true + floor, e_one + floor, walls);
    printf("lamp from %d planes: coverage %.2f%%, relit vs the true lamp (bounces 0, relative RMS over cells): floor "
           "%.2f%% (power %+.2f%%), walls %.2f%% (power %+.2f%%); from the plane under it alone: coverage %.2f%%, "
           "floor %.2f%% (power %+.2f%%), walls %.2f%% (power %+.2f%%)\n",
           LAMP_PLANES, 100 * all, 100 * floor_box, 100 * power_error(e_true, e_box, areas, floor), 100 * walls_box,
           100 * power_error(e_true + floor, e_box + floor, areas + floor, walls), 100 * one, 100 * floor_one,
           100 * power_error(e_true, e_one, areas, floor), 100 * walls_one,
           100 * power_error(e_true + floor, e_one + floor, areas + floor, walls));
    CHECK(floor == 400 && walls == 1000, "cells: floor %u, walls %u", floor, walls);
    CHECK(all >= 0.95, "coverage from the box of planes %g", all);
    CHECK(one >= 0 && one < 0.7, "coverage from one plane %g", one);
    CHECK(floor_box < 0.05, "floor within 5%%: %g", floor_box);
    CHECK(walls_box < 0.10, "walls within 10%%: %g", walls_box);
    CHECK(walls_one > 0.3, "one plane misses the walls' light: %g", walls_one);
}


/* ------------------------------------------------------------ the mask threshold on a real probe */

/* Thresholds measured on studio.exr (relative units; its field's mean radiance is about 3.7 in green). */
static const double mask_thresholds[] = {0.0, 0.01, 0.1, 1.0};
#define MASK_RUNS (sizeof mask_thresholds / sizeof mask_thresholds[0])

/* Captures studio.exr with mask threshold t into tmp/name. @return the slab's directions whose mask bit is 0 at
 * its level, and in *share the part of the field's irradiance (green) they carry; UINT64_MAX on failure. */
static uint64_t capture_studio_masked(double t, const char *name, double *share)
{
    char text[3 * PATH_BYTES], data[2 * PATH_BYTES + 2], cwd[PATH_BYTES] = "";
    /* the manifest lives in tmp: the image's path must not be relative to another folder */
    if (data_dir[0] != '/' && getcwd(cwd, sizeof cwd) == NULL)
        cwd[0] = '\0';
    snprintf(data, sizeof data, "%s%s%s", cwd, cwd[0] ? "/" : "", data_dir);
    snprintf(text, sizeof text, "{\"plane\": {\"origin\": [-0.5, 0.5, 0.0], \"u\": [1, 0, 0], \"v\": [0, -1, 0]},"
             " \"grid\": {\"nu\": 1, \"nv\": 1}, \"n\": 32, \"slab\": \"studio\", \"units\": \"relative\","
             " \"colour_space\": \"linear\", \"mask_threshold\": %.17g, \"pattern\": \"%s/capture/probes/studio.exr\"}",
             t, data);
    write_text(tmp_path("studio_masked.json"), text);
    lfio_lightfield *lf = capture_file(tmp_path("studio_masked.json"), 0, NULL);
    if (lf == NULL)
        return UINT64_MAX;
    const lfio_slab *s = lfio_lightfield_slab(lf, 0);
    const uint32_t n = lfio_slab_get_desc(s)->n;
    const float *rad = lfio_slab_radiance(s);
    const double pole[3] = {0, 0, 1};
    double dark = 0.0, all = 0.0;
    uint64_t zeroed = 0, wrong = 0;
    for (uint64_t id = 0; id < lfio_slab_dir_count(s); id++) {
        double e = rad[3 * id + 1] * lfio_part_projected_solid_angle(n, id, pole);
        float top = fmaxf(rad[3 * id], fmaxf(rad[3 * id + 1], rad[3 * id + 2]));
        int off = !lfio_slab_mask_test(s, n, id);
        zeroed += off;
        dark += off ? e : 0.0;
        all += e;
        wrong += off != (top <= (float)t);
    }
    CHECK(lfio_slab_get_desc(s)->mask_threshold == (float)t && wrong == 0,
          "threshold %g: the mask rules out exactly the directions at or below it (%llu differ)", t,
          (unsigned long long)wrong);
    CHECK(lfio_lightfield_write(lf, tmp_path(name)) == LFIO_OK, "%s", lfio_errmsg());
    lfio_lightfield_destroy(lf);
    *share = dark / all;
    return zeroed;
}

/*
 * mask_threshold on the real probe: how many of its directions each threshold rules out, the share of its
 * irradiance they carry, and what relighting a floor under it (4 m square, 1 m below, bounces 0, culled
 * with zero culling, the defaults) loses against threshold 0.
 */
static void test_mask_threshold(void)
{
    static double e[MASK_RUNS][400], areas[400];
    uint32_t cells[MASK_RUNS] = {0};
    for (size_t r = 0; r < MASK_RUNS; r++) {
        char name[32], text[1024];
        double share = 0.0;
        snprintf(name, sizeof name, "studio_mask%zu.h5", r);
        uint64_t zeroed = capture_studio_masked(mask_thresholds[r], name, &share);
        if (zeroed == UINT64_MAX)
            return;
        snprintf(text, sizeof text, "{\"materials\": {\"floor\": {\"albedo\": [0.5, 0.5, 0.5]}}, \"polygons\": ["
                 "{\"material\": \"floor\", \"vertices\": [[-2, -2, -1], [2, -2, -1], [2, 2, -1], [-2, 2, -1]]}],"
                 " \"lightfields\": [{\"file\": \"%s\"}], \"radiance_maps\": {\"cell_size\": 0.2},"
                 " \"sampling\": {\"partition_n\": 32, \"rays_per_solid_angle\": 2, \"bounces\": 0}}", name);
        cells[r] = map_irradiance("studio_mask.json", text, 1u, e[r], NULL, areas);
        double rms = rms_error(e[0], e[r], cells[r]), power = power_error(e[0], e[r], areas, cells[r]);
        printf("mask_threshold %g on studio.exr (n = 32): %llu of 4096 directions ruled out (%.1f%%) carrying %.4f%% "
               "of its irradiance; floor relit vs threshold 0: %.4f%% RMS, power %+.4f%%\n",
               mask_thresholds[r], (unsigned long long)zeroed, 100.0 * zeroed / 4096, 100 * share, 100 * rms,
               100 * power);
        CHECK(cells[r] == 400 && cells[r] == cells[0], "floor cells %u", cells[r]);
        CHECK((r == 0) == (zeroed == 0), "threshold %g rules out %llu directions", mask_thresholds[r],
              (unsigned long long)zeroed);
        /* what the relit floor loses is light from those directions: at most about their share */
        CHECK(rms <= fmax(2 * share, 1e-6), "threshold %g: relit error %g for a share of %g", mask_thresholds[r], rms,
              share);
    }
}

/* ------------------------------------------------------------ proxies and rendering */

static void expect_proxy_error(const char *name, const char *text, const char *want1, const char *want2)
{
    cap_proxy_defaults def = {8, 8, 4};
    cap_proxy *p = NULL;
    write_text(tmp_path(name), text);
    cap_status st = cap_proxy_load(tmp_path(name), &def, &p);
    const char *msg = cap_error_message();
    CHECK(st == CAP_ERR_INPUT && p == NULL, "proxy %s should fail", name);
    CHECK(strstr(msg, name) != NULL && strstr(msg, want1) != NULL && strstr(msg, want2) != NULL,
          "message '%s' should name %s, '%s' and '%s'", msg, name, want1, want2);
}

static void test_proxies(void)
{
    cap_proxy_defaults def = {8, 6, 4};
    cap_proxy *p = NULL;
    write_text(tmp_path("quads.obj"), "v 0 0 1\nv 1 0 1\nv 1 2 1\nv 0 2 1\nv 0 0 0\nv 0 1 0\nv 0 1 1\nv 0 0 1\n"
                                      "f 1 2 3 4\nf 5 6 7 8\n");
    CHECK(cap_proxy_load(tmp_path("quads.obj"), &def, &p) == CAP_OK, "%s", cap_error_message());
    CHECK(cap_proxy_count(p) == 2, "two quads");
    const lfio_slab_desc *d = cap_proxy_get_desc(p, 0);
    CHECK(d != NULL && strcmp(d->name, "face0") == 0 && d->u[0] == 1 && d->v[1] == 2 && d->origin[2] == 1 &&
              d->nu == 8 && d->nv == 6 && d->n == 4,
          "first quad as a slab");
    CHECK(cap_proxy_get_desc(p, 2) == NULL, "no third quad");
    cap_proxy_destroy(p);
    write_text(tmp_path("quads.json"), "[{\"name\": \"lamp\", \"origin\": [0, 0, 1], \"u\": [1, 0, 0], "
                                       "\"v\": [0, -1, 0], \"grid\": {\"nu\": 3, \"nv\": 2}, \"n\": 2}, "
                                       "{\"origin\": [0, 0, 0], \"u\": [0, 1, 0], \"v\": [0, 0, 1]}]");
    CHECK(cap_proxy_load(tmp_path("quads.json"), &def, &p) == CAP_OK, "%s", cap_error_message());
    CHECK(cap_proxy_count(p) == 2 && strcmp(cap_proxy_get_desc(p, 0)->name, "lamp") == 0 &&
              cap_proxy_get_desc(p, 0)->nu == 3 && cap_proxy_get_desc(p, 1)->nu == 8 &&
              strcmp(cap_proxy_get_desc(p, 1)->name, "proxy1") == 0,
          "JSON quads with and without their own grid");
    cap_proxy_destroy(p);
    /* The same two quads, triangulated as a fan from their first corner: the same rectangles, bit for bit,
     * named after their first triangle. */
    write_text(tmp_path("quads_tri.obj"), "v 0 0 1\nv 1 0 1\nv 1 2 1\nv 0 2 1\nv 0 0 0\nv 0 1 0\nv 0 1 1\nv 0 0 1\n"
                                          "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n");
    cap_proxy *q = NULL;
    CHECK(cap_proxy_load(tmp_path("quads.obj"), &def, &p) == CAP_OK, "%s", cap_error_message());
    CHECK(cap_proxy_load(tmp_path("quads_tri.obj"), &def, &q) == CAP_OK, "%s", cap_error_message());
    CHECK(cap_proxy_count(q) == 2, "two triangle pairs make two rectangles: %zu", cap_proxy_count(q));
    for (size_t k = 0; k < 2 && cap_proxy_count(q) == 2; k++) {
        const lfio_slab_desc *a = cap_proxy_get_desc(p, k), *b = cap_proxy_get_desc(q, k);
        CHECK(memcmp(a->origin, b->origin, sizeof a->origin) == 0 && memcmp(a->u, b->u, sizeof a->u) == 0 &&
                  memcmp(a->v, b->v, sizeof a->v) == 0 && a->nu == b->nu && a->n == b->n,
              "triangulated quad %zu is the quad's rectangle", k);
    }
    CHECK(cap_proxy_count(q) == 2 && strcmp(cap_proxy_get_desc(q, 1)->name, "face2") == 0,
          "a merged pair is named after its first face");
    cap_proxy_destroy(p);
    cap_proxy_destroy(q);
    /* Triangulated along the other diagonal, in the other order: the same rectangle from another corner. */
    write_text(tmp_path("diag.obj"), "v 0 0 1\nv 1 0 1\nv 1 2 1\nv 0 2 1\nf 2 3 4\nf 1 2 4\n");
    CHECK(cap_proxy_load(tmp_path("diag.obj"), &def, &q) == CAP_OK, "%s", cap_error_message());
    d = cap_proxy_get_desc(q, 0);
    CHECK(cap_proxy_count(q) == 1 && d->origin[0] == 1 && d->origin[1] == 0 && d->u[0] == 0 && d->u[1] == 2 &&
              d->v[0] == -1 && d->v[1] == 0,
          "other diagonal: origin %g %g, u %g %g, v %g %g", d->origin[0], d->origin[1], d->u[0], d->u[1], d->v[0],
          d->v[1]);
    cap_proxy_destroy(q);
    expect_proxy_error("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\nf 1 2 3\n", "face 1",
                       "3 vertices: is a triangle without a later triangle sharing its longest edge");
    expect_proxy_error("twisted.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n", "face 0",
                       "without a later triangle"); /* wound the other way: not one surface's front */
    expect_proxy_error("rhomb.obj", "v 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0.5 1 0\nf 1 2 3\nf 1 3 4\n", "face 0",
                       "does not form a rectangle");
    expect_proxy_error("penta.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\nf 1 2 3 4 5\n", "face 0",
                       "neither a quad nor a triangle");
    expect_proxy_error("skew.obj", "v 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0 1 0\nf 1 2 3 4\n", "face 0", "not a rectangle");
    expect_proxy_error("bad.json", "[{\"origin\": [0, 0, 0], \"u\": [1, 0, 0], \"v\": [0, 1, 0], \"size\": 2}]",
                       "[0]", "unknown key 'size'");
    expect_proxy_error("twice.json", "[{\"name\": \"a\", \"origin\": [0, 0, 0], \"u\": [1, 0, 0], \"v\": [0, 1, 0]},"
                                     " {\"name\": \"a\", \"origin\": [0, 0, 1], \"u\": [1, 0, 0], \"v\": [0, 1, 0]}]",
                       "[1]", "used twice");
}

/* cap_radiance_fn: the sky environment, ignoring the origin. */
static int sky_radiance(void *user, const double org[3], const double dir[3], float rgb[3])
{
    double v[3];
    (void)user;
    (void)org;
    sky_env(dir, v);
    for (int c = 0; c < 3; c++)
        rgb[c] = (float)v[c];
    return 1;
}

/* cap_radiance_fn: radiance 1.5 everywhere. */
static int one_and_a_half(void *user, const double org[3], const double dir[3], float rgb[3])
{
    (void)user, (void)org, (void)dir;
    rgb[0] = rgb[1] = rgb[2] = 1.5f;
    return 1;
}

/* @return the relative L1 difference of two images of count floats. */
static double image_difference(const float *a, const float *b, size_t count)
{
    double diff = 0.0, total = 0.0;
    for (size_t k = 0; k < count; k++) {
        diff += fabs(a[k] - b[k]);
        total += fabs(b[k]);
    }
    return diff / total;
}

static void test_render(void)
{
    const double org[3] = {0, 0, 0};
    const size_t count = 64 * 32 * 3;
    cap_probe_settings one = {64, 32, 3, 5, 1, NULL, NULL}, two = {64, 32, 3, 5, 2, NULL, NULL};
    cap_probe_settings fine = {64, 32, 12, 9, 0, NULL, NULL};
    float *a = malloc(count * sizeof *a), *b = malloc(count * sizeof *b), *c = malloc(count * sizeof *c);
    CHECK(cap_probe_render(&one, sky_radiance, NULL, org, NULL, a) == CAP_OK, "%s", cap_error_message());
    CHECK(cap_probe_render(&two, sky_radiance, NULL, org, NULL, b) == CAP_OK, "%s", cap_error_message());
    CHECK(memcmp(a, b, count * sizeof *a) == 0, "rendering does not depend on the thread count");
    CHECK(cap_probe_render(&fine, sky_radiance, NULL, org, NULL, c) == CAP_OK, "%s", cap_error_message());
    double err = image_difference(a, c, count);
    printf("render: 3x3 jittered directions per pixel vs 12x12: %.3f%% (relative L1)\n", 100 * err);
    CHECK(err < 0.01, "pixels estimate their mean radiance: %g", err);
    CHECK(cap_probe_render(&one, one_and_a_half, NULL, org, NULL, a) == CAP_OK, "%s", cap_error_message());
    int exact = 1;
    for (size_t k = 0; k < count; k++)
        exact &= a[k] == 1.5f;
    CHECK(exact, "a constant radiance renders exactly");
    cap_probe_settings bad = {0, 32, 3, 5, 1, NULL, NULL};
    CHECK(cap_probe_render(&bad, sky_radiance, NULL, org, NULL, a) == CAP_ERR_ARG, "zero width refused");
    free(a);
    free(b);
    free(c);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_capture DATA_DIR\n");
        return 2;
    }
    data_dir = argv[1];
    const char *base = getenv("ILF_TEST_TMP");
    snprintf(tmp_dir, sizeof tmp_dir, "%s/capture", base != NULL ? base : "/tmp");
    mkdir(base != NULL ? base : "/tmp", 0777);
    mkdir(tmp_dir, 0777);
    /* The image module loads once per process: the children that pin it elsewhere are forked
     * before this process's first image call, which is test_lazy_module's. */
    test_unavailable_module();
    test_lazy_module();
    test_projection_frames();
    test_projection_maps();
    test_partition_samples();
    test_three_projections();
    test_constant_and_coarse();
    test_repairs();
    test_brackets();
    test_manifest_errors();
    test_manifest_write();
    test_capture_errors();
    test_sample_bound();
    test_real_probe();
    test_render();
    test_proxies();
    test_closed_loop();
    test_depth_correction();
    test_lamp_planes();
    test_mask_threshold();
    return check_report();
}
