/*
 * test_slab.c - the in-memory light field model: validation, writes, frames,
 * queries, the zero-radiance mask and slab collections.
 *
 * The mask is checked against a brute-force answer computed without the
 * library's hierarchy functions: each finest direction's ancestor at a
 * coarser level is found by looking up its centroid there, and a coarse bit
 * must be set exactly when one of its finest directions carries radiance
 * above the threshold at some position. That is checked after random
 * sequences of writes that both raise and clear radiance.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "lfio/lightfield.h"
#include "lfio/partition.h"

#define PI 3.14159265358979323846

static uint64_t rng_state = 12345;
static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static double rng_unit(void) { return (rng_next() >> 11) * (1.0 / 9007199254740992.0); }

/* A slab with a rotated frame: u along (1,1,0), v along (0,0,2). */
static lfio_slab *make_slab(uint32_t nu, uint32_t nv, uint32_t n, float threshold)
{
    lfio_slab_desc d;
    lfio_slab *s = NULL;
    lfio_slab_desc_init(&d);
    strcpy(d.name, "test");
    d.origin[0] = 1; d.origin[1] = -2; d.origin[2] = 3;
    d.u[0] = 1; d.u[1] = 1; d.u[2] = 0;
    d.v[0] = 0; d.v[1] = 0; d.v[2] = 2;
    d.nu = nu; d.nv = nv; d.n = n;
    d.mask_threshold = threshold;
    lfio_status st = lfio_slab_new(&d, &s);
    CHECK(st == LFIO_OK && s, "slab_new: %s", lfio_errmsg());
    return s;
}

static void check_validation(void)
{
    lfio_slab_desc d;
    lfio_slab *s;
    int k;
    /* each mutation of a valid description must be refused with a message */
    for (k = 0; k < 10; k++) {
        lfio_slab_desc_init(&d);
        strcpy(d.name, "ok");
        switch (k) {
        case 0: d.v[0] = 0.5; break;                     /* not orthogonal */
        case 1: d.u[0] = 0; break;                       /* zero length */
        case 2: d.origin[1] = NAN; break;                /* not finite */
        case 3: d.n = 0; break;
        case 4: d.n = LFIO_SLAB_MAX_N + 1; break;
        case 5: d.nu = 0; break;
        case 6: d.nu = d.nv = 1u << 31; break;           /* absurd size */
        case 7: strcpy(d.name, "bad name!"); break;
        case 8: d.mask_threshold = -1.0f; break;
        case 9: d.u[2] = INFINITY; break;
        }
        s = (lfio_slab *)&d; /* any non-NULL value, to see it reset */
        lfio_status st = lfio_slab_new(&d, &s);
        CHECK(st == LFIO_ERR_ARG && s == NULL && strlen(lfio_errmsg()) > 0, "case %d: status %d", k, st);
        /* the public check gives the same verdict and the same message */
        char msg[256];
        snprintf(msg, sizeof msg, "%s", lfio_errmsg());
        CHECK(lfio_slab_desc_check(&d) == LFIO_ERR_ARG && strcmp(msg, lfio_errmsg()) == 0, "case %d: '%s' vs '%s'",
              k, msg, lfio_errmsg());
    }
    lfio_slab_desc_init(&d);
    CHECK(lfio_slab_desc_check(&d) == LFIO_OK, "the default description is valid (an empty name included)");
    CHECK(lfio_slab_desc_check(NULL) == LFIO_ERR_ARG, "NULL refused");
    CHECK(lfio_slab_desc_bytes(&d) == 4 * 3 * sizeof(float), "1x1 positions at n = 1: 4 directions");
    d.nu = d.nv = UINT32_MAX;
    d.n = LFIO_SLAB_MAX_N;
    CHECK(lfio_slab_desc_bytes(&d) == UINT64_MAX, "overflow saturates");
    CHECK(lfio_slab_name_valid("a.b-c_9") && !lfio_slab_name_valid("") && !lfio_slab_name_valid("a b") &&
              !lfio_slab_name_valid(NULL), "names");
    char longest[LFIO_NAME_MAX + 2];
    memset(longest, 'x', sizeof longest);
    longest[LFIO_NAME_MAX] = '\0';
    CHECK(lfio_slab_name_valid(longest), "63 characters");
    longest[LFIO_NAME_MAX] = 'x';
    longest[LFIO_NAME_MAX + 1] = '\0';
    CHECK(!lfio_slab_name_valid(longest), "64 characters");
    const double u[3] = {1, 0, 0}, v[3] = {0, 2, 0}, skew[3] = {1e-6, 1, 0}, zero[3] = {0, 0, 0},
                 huge[3] = {0, 1e200, 0}, hugeu[3] = {1e200, 0, 0}, nan[3] = {NAN, 0, 0};
    CHECK(lfio_slab_edges_check(u, v) == LFIO_EDGES_OK, "orthogonal edges");
    CHECK(lfio_slab_edges_check(u, skew) == LFIO_EDGES_ORTHOGONAL, "skew edges");
    CHECK(lfio_slab_edges_check(zero, v) == LFIO_EDGES_LENGTH, "zero edge");
    CHECK(lfio_slab_edges_check(u, nan) == LFIO_EDGES_LENGTH, "NaN edge");
    CHECK(lfio_slab_edges_check(hugeu, huge) == LFIO_EDGES_LENGTH, "|u||v| overflows");
    CHECK(lfio_slab_new(NULL, &s) == LFIO_ERR_ARG && s == NULL, "NULL desc refused");
    lfio_slab_destroy(NULL);
}

static void check_frames(void)
{
    lfio_slab *s = make_slab(5, 3, 2, 0);
    double x[3], a, b, h, w[3] = {0.3, -0.7, 0.2}, l[3], back[3];
    lfio_slab_position(s, 4, 2, x);
    lfio_slab_locate(s, x, &a, &b, &h);
    CHECK(fabs(a - 0.9) < 1e-12 && fabs(b - 2.5 / 3) < 1e-12 && fabs(h) < 1e-12, "locate %g %g %g", a, b, h);
    lfio_slab_to_local(s, w, l);
    lfio_slab_to_world(s, l, back);
    CHECK(fabs(back[0] - w[0]) + fabs(back[1] - w[1]) + fabs(back[2] - w[2]) < 1e-14, "frame round trip");
    /* e3 = e1 x e2 with e1 = (1,1,0)/sqrt2, e2 = (0,0,1): e3 = (1,-1,0)/sqrt2 */
    double e3w[3] = {1, -1, 0}, e3l[3];
    lfio_slab_to_local(s, e3w, e3l);
    CHECK(fabs(e3l[2] - sqrt(2.0)) < 1e-12, "normal is u x v (right-handed): %g", e3l[2]);
    CHECK(lfio_slab_position(s, 5, 0, x) == LFIO_ERR_ARG, "position out of range");
    lfio_slab_destroy(s);
}

static void check_writes_and_queries(void)
{
    lfio_slab *s = make_slab(4, 3, 4, 0);
    uint64_t nd = lfio_slab_dir_count(s);
    CHECK(nd == 64, "4n^2 directions: %llu", (unsigned long long)nd);
    float *img = malloc(4 * 3 * 3 * sizeof(float)), *pos = malloc(nd * 3 * sizeof(float));
    for (int k = 0; k < 36; k++)
        img[k] = (float)k;
    CHECK(lfio_slab_write_direction(s, 7, img) == LFIO_OK, "write_direction");
    float rgb[3] = {1, 2, 3}, got[3];
    CHECK(lfio_slab_write(s, 9, 1, 2, rgb) == LFIO_OK, "write");
    float bad[3] = {1, -1, 0}, nan3[3] = {NAN, 0, 0}, inf3[3] = {0, INFINITY, 0};
    CHECK(lfio_slab_write(s, 9, 1, 2, bad) == LFIO_ERR_ARG, "negative refused");
    CHECK(lfio_slab_write(s, 9, 1, 2, nan3) == LFIO_ERR_ARG, "NaN refused");
    CHECK(lfio_slab_write(s, 9, 1, 2, inf3) == LFIO_ERR_ARG, "Inf refused");
    CHECK(lfio_slab_write(s, 64, 0, 0, rgb) == LFIO_ERR_ARG, "dir out of range");
    /* a rejected bulk write changes nothing */
    img[35] = NAN;
    CHECK(lfio_slab_write_direction(s, 3, img) == LFIO_ERR_ARG, "bulk with NaN refused");
    CHECK(lfio_slab_mask_count(s, 4) == 2, "only dirs 7 and 9 set: %llu",
          (unsigned long long)lfio_slab_mask_count(s, 4));
    lfio_slab_read_position(s, 1, 2, pos);
    CHECK(pos[9 * 3] == 1 && pos[9 * 3 + 2] == 3 && pos[7 * 3] == (float)((2 * 4 + 1) * 3), "read_position");
    lfio_slab_read_direction(s, 7, img);
    CHECK(img[34] == 34.0f, "read_direction");
    /* nearest query at the centroid of dir 9 and the centre of (1, 2) */
    double c[3], w[3];
    lfio_part_centroid(4, 9, c);
    lfio_slab_to_world(s, c, w);
    lfio_slab_radiance_nearest(s, 1.5 / 4, 2.5 / 3, w, got);
    CHECK(got[0] == 1 && got[1] == 2 && got[2] == 3, "nearest %g %g %g", got[0], got[1], got[2]);
    lfio_slab_radiance_interp(s, 1.5 / 4, 2.5 / 3, w, got);
    CHECK(fabs(got[1] - 2) < 1e-5, "interp exact at centroid and centre: %g", got[1]);
    /* mix with the weights interp finds gives what interp gives */
    for (int k = 0; k < 200; k++) {
        double d[3] = {rng_unit() - 0.5, rng_unit() - 0.5, rng_unit() + 0.01}, wd[4], dw[3];
        double a = rng_unit() * 1.2 - 0.1, b = rng_unit();
        uint64_t ids[4];
        float gi[3], gm[3];
        lfio_part_interp(4, d, ids, wd);
        lfio_slab_to_world(s, d, dw);
        lfio_slab_radiance_interp(s, a, b, dw, gi);
        CHECK(lfio_slab_radiance_mix(s, a, b, ids, wd, gm) == LFIO_OK, "mix");
        CHECK(gi[0] == gm[0] && gi[1] == gm[1] && gi[2] == gm[2], "mix == interp: %g %g", gi[1], gm[1]);
    }
    {
        uint64_t ids[4] = {64, 0, 0, 0};
        double wd[4] = {1, 0, 0, 0};
        CHECK(lfio_slab_radiance_mix(s, 0.5, 0.5, ids, wd, got) == LFIO_ERR_ARG, "mix: unstored direction refused");
        ids[0] = 9;
        CHECK(lfio_slab_radiance_mix(s, INFINITY, 0.5, ids, wd, got) == LFIO_ERR_ARG, "mix: infinite s refused");
    }
    double behind[3] = {-w[0], -w[1], -w[2]}, lb[3];
    lfio_slab_to_local(s, behind, lb);
    if (lb[2] < 0) {
        lfio_slab_radiance_nearest(s, 0.5, 0.5, behind, got);
        CHECK(got[0] == 0 && got[1] == 0 && got[2] == 0, "behind the slab is dark");
    }
    double zero[3] = {0, 0, 0};
    CHECK(lfio_slab_radiance_interp(s, 0.5, 0.5, zero, got) == LFIO_ERR_ARG, "zero direction refused");
    CHECK(lfio_slab_radiance_interp(s, NAN, 0.5, w, got) == LFIO_ERR_ARG, "NaN position refused");
    free(img);
    free(pos);
    lfio_slab_destroy(s);
}

/* Constant fields stay constant under interpolation; irradiance is pi*L. */
static void check_constant_field(uint32_t n)
{
    lfio_slab *s = make_slab(3, 2, n, 0);
    uint64_t nd = lfio_slab_dir_count(s);
    float *pos = malloc(nd * 3 * sizeof(float));
    for (uint64_t d = 0; d < nd; d++) {
        pos[3 * d] = 2.0f;
        pos[3 * d + 1] = 0.5f;
        pos[3 * d + 2] = 1e-20f;
    }
    for (uint32_t j = 0; j < 2; j++)
        for (uint32_t i = 0; i < 3; i++)
            lfio_slab_write_position(s, i, j, pos);
    long bad = 0;
    for (int k = 0; k < 2000; k++) {
        double l[3] = {rng_unit() - 0.5, rng_unit() - 0.5, rng_unit() + 1e-3}, w[3];
        float got[3];
        lfio_slab_to_world(s, l, w);
        lfio_slab_radiance_interp(s, rng_unit() * 1.2 - 0.1, rng_unit(), w, got);
        bad += fabs(got[0] - 2.0) > 1e-5 || fabs(got[1] - 0.5) > 1e-6;
    }
    CHECK(bad == 0, "n=%u: %ld interpolated values of a constant field differ", n, bad);
    double e[3];
    lfio_slab_irradiance(s, 0.3, 0.7, e);
    CHECK(fabs(e[0] - 2 * PI) < 1e-12 * 2 * PI && fabs(e[1] - 0.5 * PI) < 1e-12, "n=%u: E = %.15g, want 2pi",
          n, e[0]);
    CHECK(fabs(e[2] - 1e-20 * PI) < 1e-6 * 1e-20 * PI, "tiny radiance keeps its precision: %g", e[2]);
    free(pos);
    lfio_slab_destroy(s);
}

/* Radiance linear in s: bilinear interpolation reproduces it between centres. */
static void check_bilinear(void)
{
    lfio_slab *s = make_slab(8, 1, 1, 0);
    for (uint32_t i = 0; i < 8; i++) {
        float rgb[3] = {(float)i, 0, 0};
        for (uint64_t d = 0; d < lfio_slab_dir_count(s); d++)
            lfio_slab_write(s, d, i, 0, rgb);
    }
    double w[3] = {0, 0, 0}, l[3] = {0.1, 0.2, 1};
    float got[3];
    lfio_slab_to_world(s, l, w);
    long bad = 0;
    for (int k = 0; k <= 100; k++) {
        double a = 0.0625 + (0.875 * k) / 100; /* centre of 0 .. centre of 7 */
        lfio_slab_radiance_interp(s, a, 0.5, w, got);
        bad += fabs(got[0] - (a * 8 - 0.5)) > 1e-5;
    }
    lfio_slab_radiance_interp(s, 0.0, 0.5, w, got);
    CHECK(got[0] == 0.0f, "clamped at the border: %g", got[0]);
    CHECK(bad == 0, "%ld bilinear values off", bad);
    lfio_slab_destroy(s);
}

/* Irradiance from one direction is L times its projected solid angle. */
static void check_irradiance_single(void)
{
    lfio_slab *s = make_slab(1, 1, 8, 0);
    float rgb[3] = {3, 3, 3};
    const double pole[3] = {0, 0, 1};
    lfio_slab_write(s, 100, 0, 0, rgb);
    double e[3];
    lfio_slab_irradiance(s, 0.5, 0.5, e);
    double want = 3 * lfio_part_projected_solid_angle(8, 100, pole);
    CHECK(fabs(e[0] - want) < 1e-12 * want, "E = %g, want %g", e[0], want);
    lfio_slab_destroy(s);
}

/* Brute-force mask: bit (m, id) set iff a level-n direction inside it is bright somewhere. */
static void check_mask_against_brute_force(const lfio_slab *s, const char *when)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(s);
    const float *rad = lfio_slab_radiance(s);
    uint64_t nd = lfio_slab_dir_count(s), npos = (uint64_t)d->nu * d->nv;
    long bad = 0;
    for (uint32_t k = 0; k < lfio_slab_mask_levels(s); k++) {
        uint32_t m = lfio_slab_mask_n(s, k);
        uint64_t cm = lfio_part_hemi_count(m), set = 0;
        unsigned char *expect = calloc(cm, 1);
        for (uint64_t dir = 0; dir < nd; dir++) {
            int bright = 0;
            for (uint64_t q = 0; q < npos && !bright; q++) {
                const float *p = rad + (dir * npos + q) * 3;
                bright = p[0] > d->mask_threshold || p[1] > d->mask_threshold || p[2] > d->mask_threshold;
            }
            double c[3];
            uint64_t anc;
            lfio_part_centroid(d->n, dir, c);
            lfio_part_id(m, c, &anc);
            if (bright)
                expect[anc] = 1;
        }
        for (uint64_t id = 0; id < cm; id++) {
            bad += lfio_slab_mask_test(s, m, id) != expect[id];
            set += expect[id];
        }
        bad += lfio_slab_mask_count(s, m) != set;
        free(expect);
    }
    CHECK(bad == 0, "n=%u %s: %ld mask bits disagree with the radiance", d->n, when, bad);
}

static void check_mask(uint32_t n, float threshold)
{
    lfio_slab *s = make_slab(3, 2, n, threshold);
    uint64_t nd = lfio_slab_dir_count(s);
    CHECK(lfio_slab_mask_count(s, n) == 0, "empty slab has an empty mask");
    uint32_t levels = lfio_slab_mask_levels(s), expect_levels = 1;
    for (uint32_t m = n; !(m & 1u); m /= 2)
        expect_levels++;
    CHECK(levels == expect_levels, "n=%u: %u levels", n, levels);
    CHECK(lfio_slab_mask_n(s, levels - 1) == n, "finest level is n");
    for (int round = 0; round < 6; round++) {
        /* sparse bright writes, then some of them cleared again */
        for (int k = 0; k < 40; k++) {
            float v = (float)(rng_unit() < 0.5 ? threshold * 2 + 1 : threshold * 0.5);
            float rgb[3] = {0, v, 0};
            lfio_slab_write(s, rng_next() % nd, rng_next() % 3, rng_next() % 2, rgb);
        }
        check_mask_against_brute_force(s, "after writes");
        for (int k = 0; k < 60; k++) {
            float zero[3] = {0, 0, 0};
            lfio_slab_write(s, rng_next() % nd, rng_next() % 3, rng_next() % 2, zero);
        }
        check_mask_against_brute_force(s, "after clears");
    }
    /* a conservative answer for questions the mask cannot answer */
    CHECK(lfio_slab_mask_test(s, n + 1, 0) == 1, "non-level is conservative");
    CHECK(lfio_slab_mask_test(s, n, nd) == 1, "out-of-range id is conservative");
    lfio_slab_destroy(s);
}

/* Culling by the mask never removes a direction that carries radiance. */
static void check_mask_never_culls_radiance(void)
{
    lfio_slab *s = make_slab(2, 2, 16, 0);
    for (int k = 0; k < 30; k++) {
        float rgb[3] = {1e-30f, 0, 0};
        lfio_slab_write(s, rng_next() % lfio_slab_dir_count(s), rng_next() % 2, rng_next() % 2, rgb);
    }
    long bad = 0;
    for (int k = 0; k < 20000; k++) {
        double l[3] = {rng_unit() - 0.5, rng_unit() - 0.5, rng_unit()}, w[3];
        float got[3];
        lfio_slab_to_world(s, l, w);
        for (uint32_t i = 0; i < 2; i++)
            for (uint32_t j = 0; j < 2; j++) {
                lfio_slab_radiance_nearest(s, (i + 0.5) / 2, (j + 0.5) / 2, w, got);
                if (got[0] == 0)
                    continue;
                for (uint32_t m = 1; m <= 16; m *= 2) {
                    uint64_t id;
                    lfio_part_id(m, l, &id);
                    bad += !lfio_slab_mask_test(s, m, id);
                }
            }
    }
    CHECK(bad == 0, "%ld bright directions culled by the mask", bad);
    lfio_slab_destroy(s);
}

static void check_collection(void)
{
    lfio_lightfield *lf = NULL;
    CHECK(lfio_lightfield_new(&lf) == LFIO_OK, "new");
    lfio_slab *a = make_slab(1, 1, 1, 0), *b = make_slab(1, 1, 1, 0), *c = NULL;
    CHECK(lfio_lightfield_take_slab(lf, a) == LFIO_OK, "take a");
    CHECK(lfio_lightfield_take_slab(lf, b) == LFIO_ERR_ARG, "duplicate name refused (b destroyed)");
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    lfio_slab_new(&d, &c);
    CHECK(lfio_lightfield_take_slab(lf, c) == LFIO_ERR_ARG, "unnamed slab refused (c destroyed)");
    CHECK(lfio_lightfield_slab_count(lf) == 1 && lfio_lightfield_find(lf, "test") == a, "find");
    CHECK(lfio_lightfield_slab(lf, 1) == NULL && lfio_lightfield_find(lf, "nope") == NULL, "absent");
    CHECK(strncmp(lfio_lightfield_creator(lf), "lfio ", 5) == 0, "default creator");
    lfio_lightfield_destroy(lf);
    lfio_lightfield_destroy(NULL);
}

/* Error messages belong to the thread that failed. */
static void *fail_in_thread(void *arg)
{
    lfio_slab *s = NULL;
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    d.n = 0;
    lfio_slab_new(&d, &s);
    *(int *)arg = strstr(lfio_errmsg(), "n must") != NULL;
    return NULL;
}

static void check_thread_messages(void)
{
    lfio_slab *s = make_slab(1, 1, 1, 0);
    float bad[3] = {-1, 0, 0};
    lfio_slab_write(s, 0, 0, 0, bad);
    char mine[256];
    snprintf(mine, sizeof mine, "%s", lfio_errmsg());
    pthread_t t;
    int other_ok = 0;
    pthread_create(&t, NULL, fail_in_thread, &other_ok);
    pthread_join(t, NULL);
    CHECK(other_ok, "the other thread saw its own message");
    CHECK(strcmp(mine, lfio_errmsg()) == 0, "this thread's message unchanged: %s", lfio_errmsg());
    CHECK(strcmp(lfio_status_name(LFIO_ERR_CHECKSUM), "checksum mismatch") == 0, "status names");
    lfio_slab_destroy(s);
}

/* The support boxes against a brute-force scan, with a threshold that hides some values from the mask. */
static void check_support(float threshold)
{
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    d.nu = 7, d.nv = 5, d.n = 3, d.mask_threshold = threshold;
    lfio_slab *s = NULL;
    CHECK(lfio_slab_new(&d, &s) == LFIO_OK, "slab: %s", lfio_errmsg());
    uint64_t ndir = lfio_slab_dir_count(s);
    float rgb[4 * 3 * 3 * 3];
    CHECK(ndir * 3 <= sizeof rgb / sizeof rgb[0], "room");
    for (uint32_t j = 0; j < d.nv; j++)
        for (uint32_t i = 0; i < d.nu; i++) {
            for (uint64_t k = 0; k < ndir * 3; k++) /* sparse, some below the threshold, one channel at a time */
                rgb[k] = (k / 3 % 4 != 1 && (k * 7 + i * 3 + j * 5) % 11 == 0) ? (float)((i + j + k) % 3) * 0.25f : 0.0f;
            CHECK(lfio_slab_write_position(s, i, j, rgb) == LFIO_OK, "write: %s", lfio_errmsg());
        }
    uint32_t(*box)[4] = malloc(ndir * sizeof *box);
    CHECK(box && lfio_slab_support(s, box) == LFIO_OK, "support: %s", lfio_errmsg());
    const float *rad = lfio_slab_radiance(s);
    long bad = 0, empty = 0;
    for (uint64_t k = 0; k < ndir && box; k++) {
        uint32_t b[4] = {1, 0, 1, 0};
        int any = 0;
        for (uint32_t j = 0; j < d.nv; j++)
            for (uint32_t i = 0; i < d.nu; i++) {
                const float *p = rad + ((k * d.nv + j) * d.nu + i) * 3;
                if (p[0] != 0 || p[1] != 0 || p[2] != 0) {
                    if (!any)
                        b[0] = b[1] = i, b[2] = b[3] = j, any = 1;
                    b[0] = i < b[0] ? i : b[0], b[1] = i > b[1] ? i : b[1];
                    b[2] = j < b[2] ? j : b[2], b[3] = j > b[3] ? j : b[3];
                }
            }
        empty += !any;
        if (any ? memcmp(b, box[k], sizeof b) != 0 : !(box[k][0] > box[k][1]))
            bad++;
    }
    CHECK(bad == 0, "threshold %g: %ld of %llu boxes wrong", threshold, bad, (unsigned long long)ndir);
    CHECK(empty > 0 && empty < (long)ndir, "the test has dark and lit directions (%ld dark)", empty);
    CHECK(lfio_slab_support(NULL, box) == LFIO_ERR_ARG && lfio_slab_support(s, NULL) == LFIO_ERR_ARG, "NULL refused");
    free(box);
    lfio_slab_destroy(s);
}

/* A blend over the support of its directions reads what the mix reads, to
 * float rounding, at points all over the slab and past its edges; a box
 * cut short reads 0 outside it and the mix inside; bad boxes are refused. */
static void check_blend(void)
{
    lfio_slab *s = make_slab(6, 5, 4, 0);
    uint64_t ndir = lfio_slab_dir_count(s);
    float img[6 * 5 * 3];
    for (uint64_t k = 0; k < ndir; k++) {
        /* each direction lit on a rectangle of its own, so supports differ */
        uint32_t i0 = k % 3, j0 = k % 2, i1 = i0 + 2 + k % 2, j1 = j0 + 1 + k % 3;
        for (uint32_t j = 0; j < 5; j++)
            for (uint32_t i = 0; i < 6; i++)
                for (int c = 0; c < 3; c++)
                    img[(j * 6 + i) * 3 + c] =
                        (i >= i0 && i <= i1 && j >= j0 && j <= j1) ? (float)(1 + (k * 5 + i * 3 + j * 7 + c) % 13) : 0.0f;
        CHECK(lfio_slab_write_direction(s, k, img) == LFIO_OK, "write: %s", lfio_errmsg());
    }
    uint32_t(*sup)[4] = malloc(ndir * sizeof *sup);
    CHECK(sup && lfio_slab_support(s, sup) == LFIO_OK, "support");
    float table[6 * 5 * 3], cut[6 * 5 * 3];
    long worst_ppm = 0, outside_bad = 0, inside_bad = 0, rect_bad = 0, grid_bad = 0, beyond = 0;
    for (int trial = 0; trial < 200 && sup; trial++) {
        double d[3] = {rng_unit() - 0.5, rng_unit() - 0.5, rng_unit() + 0.05}, wd[4];
        uint64_t ids[4];
        lfio_part_interp(4, d, ids, wd);
        uint32_t box[4] = {UINT32_MAX, 0, UINT32_MAX, 0};
        for (int k = 0; k < 4; k++) {
            const uint32_t *b = sup[ids[k] < ndir ? ids[k] : ids[0]];
            box[0] = b[0] < box[0] ? b[0] : box[0], box[1] = b[1] > box[1] ? b[1] : box[1];
            box[2] = b[2] < box[2] ? b[2] : box[2], box[3] = b[3] > box[3] ? b[3] : box[3];
        }
        CHECK(lfio_slab_blend(s, ids, wd, box, table) == LFIO_OK, "blend: %s", lfio_errmsg());
        uint32_t small[4] = {box[0] + 1, box[1], box[2], box[3] - 1};
        int has_small = small[0] <= small[1] && small[2] <= small[3];
        if (has_small)
            CHECK(lfio_slab_blend(s, ids, wd, small, cut) == LFIO_OK, "blend a part: %s", lfio_errmsg());
        /* the inline lookup at grid coordinates where taps switch: position
         * centres, half-way, the box's edges and the rows past them, past the
         * slab's edges (the rectangle's ends, inclusive) */
        lfio_blend_grid grid;
        lfio_slab_blend_grid(s, box, &grid);
        const double us[] = {-1.5, -0.5, 0.0, box[0] - 1.0, box[0] - 0.5, box[0], box[0] + 0.5,
                             box[1], box[1] + 0.5, box[1] + 1.0, 5.0, 5.5, 6.2};
        const double vs[] = {-0.7, 0.0, box[2] - 1.0, box[2], box[3], box[3] + 0.25, box[3] + 1.0, 4.0, 4.9};
        for (size_t iu = 0; iu < sizeof us / sizeof *us; iu++)
            for (size_t iv = 0; iv < sizeof vs / sizeof *vs; iv++) {
                double gu = us[iu], gv = vs[iv];
                if (!(gu >= grid.rect[0] && gu <= grid.rect[1] && gv >= grid.rect[2] && gv <= grid.rect[3]))
                    continue;
                float at[3], mix[3];
                lfio_blend_at(&grid, table, gu, gv, at);
                lfio_slab_radiance_mix(s, (gu + 0.5) / 6, (gv + 0.5) / 5, ids, wd, mix);
                for (int c = 0; c < 3; c++)
                    grid_bad += fabs(at[c] - mix[c]) > 2e-6 * (fabs(mix[c]) + 1e-3);
            }
        for (int q = 0; q < 50; q++) {
            double a = rng_unit() * 1.4 - 0.2, b = rng_unit() * 1.4 - 0.2;
            float mix[3], got[3], part[3];
            lfio_slab_radiance_mix(s, a, b, ids, wd, mix);
            lfio_slab_blend_radiance(s, box, table, a, b, got);
            /* outside the grid's rectangle every tap lies outside the box */
            lfio_blend_grid g;
            lfio_slab_blend_grid(s, box, &g);
            double ga = a * 6 - 0.5, gb = b * 5 - 0.5;
            if (!(ga >= g.rect[0] && ga <= g.rect[1] && gb >= g.rect[2] && gb <= g.rect[3])) {
                beyond++;
                rect_bad += mix[0] != 0 || mix[1] != 0 || mix[2] != 0 || got[0] != 0 || got[1] != 0 || got[2] != 0;
            }
            for (int c = 0; c < 3; c++) {
                long ppm = (long)(1e6 * fabs(got[c] - mix[c]) / (fabs(mix[c]) + 1e-3));
                worst_ppm = ppm > worst_ppm ? ppm : worst_ppm;
            }
            if (!has_small)
                continue;
            /* a point whose four taps all lie outside the part reads 0; all inside, the mix */
            lfio_slab_blend_radiance(s, small, cut, a, b, part);
            double gu = fmin(fmax(a * 6 - 0.5, 0), 5), gv = fmin(fmax(b * 5 - 0.5, 0), 4);
            uint32_t i0 = (uint32_t)gu, j0 = (uint32_t)gv, i1 = i0 + 1 < 6 ? i0 + 1 : i0, j1 = j0 + 1 < 5 ? j0 + 1 : j0;
            int all_out = i1 < small[0] || i0 > small[1] || j1 < small[2] || j0 > small[3];
            int all_in = i0 >= small[0] && i1 <= small[1] && j0 >= small[2] && j1 <= small[3];
            if (all_out && (part[0] != 0 || part[1] != 0 || part[2] != 0))
                outside_bad++;
            if (all_in && fabs(part[1] - mix[1]) > 1e-5 * (fabs(mix[1]) + 1))
                inside_bad++;
        }
    }
    CHECK(worst_ppm <= 2, "blend reads the mix to float rounding: worst %ld ppm", worst_ppm);
    CHECK(grid_bad == 0, "lfio_blend_at() differs from the mix at %ld grid points on position centres, box "
                         "edges and past the slab", grid_bad);
    CHECK(beyond > 100 && rect_bad == 0, "%ld of %ld points outside the grid's rectangle read light", rect_bad, beyond);
    CHECK(outside_bad == 0 && inside_bad == 0, "a part of the box: %ld wrong outside, %ld inside", outside_bad,
          inside_bad);
    uint64_t ids[4] = {1, 2, 3, 4};
    double wd[4] = {0.25, 0.25, 0.25, 0.25};
    uint32_t outside[4] = {0, 6, 0, 1}, empty[4] = {2, 1, 0, 1}, ok[4] = {0, 5, 0, 4};
    CHECK(lfio_slab_blend(s, ids, wd, outside, table) == LFIO_ERR_ARG, "a box past the slab refused");
    CHECK(lfio_slab_blend(s, ids, wd, empty, table) == LFIO_ERR_ARG, "an empty box refused");
    ids[0] = ndir;
    CHECK(lfio_slab_blend(s, ids, wd, ok, table) == LFIO_ERR_ARG, "an unstored direction refused");
    free(sup);
    lfio_slab_destroy(s);
}

int main(void)
{
    check_support(0.0f);
    check_support(0.3f);
    check_validation();
    check_frames();
    check_writes_and_queries();
    check_blend();
    for (uint32_t n = 1; n <= 32; n *= 2)
        check_constant_field(n);
    check_constant_field(5);
    check_bilinear();
    check_irradiance_single();
    const uint32_t levels[] = {1, 2, 3, 4, 6, 8, 12, 16};
    for (size_t k = 0; k < sizeof levels / sizeof levels[0]; k++) {
        check_mask(levels[k], 0.0f);
        check_mask(levels[k], 0.25f);
    }
    check_mask_never_culls_radiance();
    check_collection();
    check_thread_messages();
    return check_report();
}
