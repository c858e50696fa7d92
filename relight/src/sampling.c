/*
 * sampling.c - sample sequences and spherical-triangle warps.
 *
 * Everything here is a pure function of its arguments, which is what makes
 * the engine's output independent of thread count and of which method
 * (culled or naive) visits a (cell, solid angle) pair: the samples are a
 * function of the pair's key alone.
 */
#include <pthread.h>

#include "sampling.h"

double rl__radical_inverse(uint32_t i, uint32_t b)
{
    double inv = 1.0 / b, f = inv, r = 0.0;
    while (i) {
        r += (i % b) * f;
        i /= b;
        f *= inv;
    }
    return r;
}

double rl__lds_table[4][RL_LDS_TABLE];

/* Fills rl__lds_table. */
static void lds_fill(void)
{
    for (int j = 0; j < 4; j++)
        for (uint32_t i = 0; i < RL_LDS_TABLE; i++)
            rl__lds_table[j][i] = rl__radical_inverse(i, rl__lds_bases[j]);
}

static pthread_once_t lds_once = PTHREAD_ONCE_INIT;

lds_key rl__lds_make(uint64_t key)
{
    pthread_once(&lds_once, lds_fill); /* every key is made here, so rl__lds_coord() may assume the table */
    lds_key k;
    rl__lds_shift_pair(&k, 0, ilf_hash_mix(key, 1));
    rl__lds_shift_pair(&k, 2, ilf_hash_mix(key, 2));
    return k;
}

double rl__spherical_triangle_area(v3 a, v3 b, v3 c)
{
    double num = fabs(v3_dot(a, v3_cross(b, c)));
    double den = 1.0 + v3_dot(a, b) + v3_dot(b, c) + v3_dot(c, a);
    return 2.0 * atan2(num, den);
}

/* @return the component of v orthogonal to unit w, normalised (or w's
 * perpendicular if v is parallel to w). */
static v3 orthonormal_part(v3 v, v3 w)
{
    v3 p = v3_madd(v, w, -v3_dot(v, w));
    double len = v3_len(p);
    if (len > 0)
        return v3_scale(p, 1.0 / len);
    v3 h = fabs(w.x) < 0.9 ? v3_make(1, 0, 0) : v3_make(0, 1, 0);
    return v3_norm(v3_cross(w, h));
}

sph_tri rl__sph_tri_make(v3 a, v3 b, v3 c, double omega)
{
    sph_tri t = {.a = a, .b = b, .c = c, .omega = omega, .planar = 1};
    if (!(omega > 1e-9))
        return t;
    /* alpha is the interior angle at a, between the planes (a, b) and (a, c) */
    v3 nab = v3_cross(a, b), nac = v3_cross(a, c);
    double lab = v3_len(nab), lac = v3_len(nac);
    if (!(lab > 0) || !(lac > 0))
        return t;
    t.cos_alpha = fmin(1.0, fmax(-1.0, v3_dot(nab, nac) / (lab * lac)));
    t.sin_alpha = sqrt(fmax(0.0, 1.0 - t.cos_alpha * t.cos_alpha));
    t.alpha = acos(t.cos_alpha);
    t.cos_ab = v3_dot(a, b);
    t.c_perp = orthonormal_part(c, a);
    t.planar = 0;
    return t;
}

v3 rl__sph_tri_sample(const sph_tri *t, double u1, double u2)
{
    if (t->planar) {
        double su = sqrt(u1);
        v3 p = v3_add(v3_add(v3_scale(t->a, 1 - su), v3_scale(t->b, su * (1 - u2))), v3_scale(t->c, su * u2));
        return v3_norm(p);
    }
    /* Arvo: the sub-triangle a, b, c' of area u1*omega, then a point on the
     * arc from b to c' with the density that makes the whole uniform */
    double s = sin(u1 * t->omega - t->alpha), c = cos(u1 * t->omega - t->alpha);
    double u = c - t->cos_alpha, v = s + t->sin_alpha * t->cos_ab;
    double den = (v * s + u * c) * t->sin_alpha;
    double q = den != 0.0 ? ((v * c - u * s) * t->cos_alpha - v) / den : 1.0;
    q = q > 1.0 ? 1.0 : q < -1.0 ? -1.0 : q;
    v3 c2 = v3_add(v3_scale(t->a, q), v3_scale(t->c_perp, sqrt(1.0 - q * q)));
    double z = 1.0 - u2 * (1.0 - v3_dot(c2, t->b));
    z = z > 1.0 ? 1.0 : z < -1.0 ? -1.0 : z;
    v3 p = v3_add(v3_scale(t->b, z), v3_scale(orthonormal_part(c2, t->b), sqrt(1.0 - z * z)));
    return v3_norm(p);
}

v3 rl__sample_spherical_triangle(v3 a, v3 b, v3 c, double omega, double u1, double u2)
{
    sph_tri t = rl__sph_tri_make(a, b, c, omega);
    return rl__sph_tri_sample(&t, u1, u2);
}

double rl__sph_fan(const v3 *p, size_t n, v3 x, v3 *dir, double *omega)
{
    double total = 0.0;
    for (size_t i = 0; i < n; i++)
        dir[i] = v3_norm(v3_sub(p[i], x));
    for (size_t i = 1; i + 1 < n; i++) {
        omega[i] = rl__spherical_triangle_area(dir[0], dir[i], dir[i + 1]);
        total += omega[i];
    }
    return total;
}

v3 rl__sph_fan_sample(const v3 *dir, const double *omega, size_t n, double total, double u1, double u2)
{
    /* pick triangle i with probability omega[i] / total, reusing u1's rest within it */
    double pick = u1 * total, acc = 0.0;
    size_t i = 1;
    for (; i + 2 < n && pick >= acc + omega[i]; i++)
        acc += omega[i];
    double r = omega[i] > 0 ? fmin(fmax((pick - acc) / omega[i], 0.0), 1.0) : 0.5;
    return rl__sample_spherical_triangle(dir[0], dir[i], dir[i + 1], omega[i], r, u2);
}
