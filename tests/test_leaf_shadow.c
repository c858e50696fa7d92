/*
 * test_leaf_shadow.c - the shadows of a solid angle's shared directions
 * (relight/src/leaf_shadow.c) against brute force: for random origins on
 * the receiver, the segment each shared direction's ray would follow is
 * intersected in double precision with every polygon of the scene.
 *
 * Scenes of random quads go through the real loader, between a receiver
 * plane below (tilted, or an upright wall through the emitter's plane) and
 * a tilted emitter plane above, two of them upright through those planes
 * and one an octagon; each leaf is a small
 * random triangle of directions with four directions drawn inside it.
 * What must hold, for every sample whose ray lands on the emitter: a
 * segment that crosses a polygon well inside lies in a shadow, and one
 * that misses every polygon by a margin lies in none. Blocked and free
 * samples must both occur, and the shadows must be known for nearly every
 * leaf that casts rays, so that neither check is vacuous; the plan of each
 * ray must match the direct computation; and shadows built from a random
 * rectangle of the tile alone (culled's, around a solid angle's region)
 * must decide every origin inside it as the whole tile's do, with fewer
 * shadows somewhere.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "method.h"
#include "transfer.h"
#include "relight_scenes.h"
#include "segment_meets.h"

#define SCENES 30
#define LEAVES_PER_SCENE 40
#define ORIGINS 200
#define SHARED 4

/* @return an orthonormal frame at o with normal n (unit). */
static rl_frame frame_at(v3 o, v3 n)
{
    v3 h = fabs(n.x) < 0.9 ? (v3){1, 0, 0} : (v3){0, 1, 0};
    v3 e1 = v3_norm(v3_cross(h, n));
    return (rl_frame){o, e1, v3_cross(n, e1), n};
}

int main(void)
{
    const char *tmp = getenv("ILF_TEST_TMP") ? getenv("ILF_TEST_TMP") : "/tmp";
    long blocked = 0, arrived = 0, known = 0, leaves = 0, wrong_free = 0, wrong_blocked = 0, plan_bad = 0, dead = 0;
    long part_compared = 0, part_differ = 0, part_fewer = 0;
    long casting = 0, unknown_casting = 0;
    rl_map *map = calloc(1, sizeof *map);
    rl_emitter *e = calloc(1, sizeof *e);
    rl_pair *p = calloc(1, sizeof *p);
    rl_tile *t = calloc(1, sizeof *t);
    rl_leaf *L = calloc(1, sizeof *L);
    if (!map || !e || !p || !t || !L)
        return 1;
    for (int sc = 0; sc < SCENES; sc++) {
        char path[1100];
        snprintf(path, sizeof path, "%s/leaf_shadow_%d.json", tmp, sc);
        tpoly q[12];
        for (int k = 0; k < 12; k++)
            q[k] = ts_random_quad("grey");
        /* two upright quads through the emitter's plane and the receiver's: only the part of each
         * between the two planes can stop a ray */
        for (int k = 10; k < 12; k++) {
            double x0 = 4 * ts_rnd() - 2, y0 = 4 * ts_rnd() - 2, z0 = k == 10 ? 2.0 : -4.0, a = 6.28 * ts_rnd();
            double dx = cos(a), dy = sin(a);
            const double at[4][2] = {{0, 0}, {1.5, 0}, {1.5, 2}, {0, 2}};
            for (int v = 0; v < 4; v++) {
                q[k].v[v][0] = x0 + at[v][0] * dx;
                q[k].v[v][1] = y0 + at[v][0] * dy;
                q[k].v[v][2] = z0 + at[v][1];
            }
        }
        /* and one quad replaced by a tilted octagon */
        double oc[3] = {2 * ts_rnd() - 1, 2 * ts_rnd() - 1, 2 * ts_rnd() - 1};
        q[9].n = 8;
        for (int v = 0; v < 8; v++) {
            double a = 6.283185307179586 * v / 8, r = 0.8;
            q[9].v[v][0] = oc[0] + r * cos(a);
            q[9].v[v][1] = oc[1] + r * sin(a);
            q[9].v[v][2] = oc[2] + 0.3 * r * cos(a);
        }
        ts_write_scene(path, "{\"grey\": {\"albedo\": [0.5, 0.5, 0.5]}}", q, 12, NULL);
        rl_scene *s = ts_load(path);
        rl_occluders *occ = NULL;
        CHECK(s && rl__occluders_new(s, &occ) == RL_OK, "scene %d and its occluder index", sc);
        if (!occ) {
            rl_scene_destroy(s);
            continue;
        }
        /* the receiver: the square [-3, 3]^2 of a plane facing up at z = -3, tilted by up to 30
         * degrees; every third scene an upright wall at x = -3 instead, reaching past the emitter's
         * plane (its top is cut off) and seeing some of each leaf's directions from behind */
        v3 rn = sc % 3 == 2 ? (v3){1, 0, 0.05 * ts_rnd()} : (v3){ts_rnd() - 0.5, ts_rnd() - 0.5, 2};
        map->frame = frame_at(sc % 3 == 2 ? (v3){-3, 0, 1} : (v3){0, 0, -3}, v3_norm(rn));
        map->polygon = -1;
        t->m = map;
        t->npoly = 4;
        const v2 sq[4] = {{-3, -3}, {3, -3}, {3, 3}, {-3, 3}};
        memcpy(t->poly, sq, sizeof sq);
        /* the emitter: a 6 m square 3 m up, tilted, facing down */
        v3 en = v3_norm((v3){0.4 * ts_rnd() - 0.2, 0.4 * ts_rnd() - 0.2, -1});
        e->kind = EM_SLAB;
        e->polygon = -1;
        e->frame = frame_at((v3){0, 0, 3}, en);
        p->e = e;
        p->ns = 4;
        for (int k = 0; k < 4; k++)
            p->sclip[k] = frame_point(&e->frame, (v2){sq[k].x, sq[k].y});
        p->eps = 1e-6;
        rl_transfer_ctx ctx;
        memset(&ctx, 0, sizeof ctx);
        ctx.occluders = occ;
        rl_scratch scratch, part;
        memset(&scratch, 0, sizeof scratch);
        memset(&part, 0, sizeof part);
        uint32_t npolys = (uint32_t)rl_scene_polygon_count(s);
        for (int lf = 0; lf < LEAVES_PER_SCENE; lf++) {
            /* a triangle of directions about 0.1 rad across, leaving the emitter's front */
            double c[3] = {0.6 * ts_rnd() - 0.3, 0.6 * ts_rnd() - 0.3, 1}, corner[3][3];
            memset(L, 0, sizeof *L);
            L->reach = 1;
            for (int k = 0; k < 3; k++) {
                for (int a = 0; a < 2; a++)
                    corner[k][a] = c[a] + 0.1 * (ts_rnd() - 0.5);
                corner[k][2] = 1;
                L->land[k] = (v2){corner[k][0], corner[k][1]};
                L->p[k] = frame_vector(&e->frame, corner[k]);
            }
            L->nshared = SHARED;
            for (int i = 0; i < SHARED; i++) {
                double w0 = ts_rnd(), w1 = ts_rnd() * (1 - w0), w[3] = {w0, w1, 1 - w0 - w1}, d[3] = {0, 0, 0};
                for (int k = 0; k < 3; k++)
                    for (int a = 0; a < 3; a++)
                        d[a] += w[k] * corner[k][a];
                L->sd[i] = v3_norm(frame_vector(&e->frame, d));
                L->sw[i] = 1.0;
            }
            rl__leaf_plan(L, e, &map->frame, p->eps);
            leaves++;
            CHECK(rl__shadows_build(&ctx, p, t, L, NULL, &scratch) == 0, "scene %d leaf %d: shadows built", sc, lf);
            const rl_shadows *sh = scratch.shadows;
            int is_known = sh && sh->known, casts = 0;
            known += is_known;
            for (int o = 0; o < ORIGINS; o++) {
                v2 uv = {6 * ts_rnd() - 3, 6 * ts_rnd() - 3};
                v3 x = frame_point(&map->frame, uv);
                if (is_known)
                    rl__shadows_row(scratch.shadows, uv.x, uv.x, uv.y, uv.y);
                for (uint32_t i = 0; i < SHARED; i++) {
                    const rl_shared_plan *pl = &L->plan[i];
                    double tt = pl->t[0] + pl->t[1] * uv.x + pl->t[2] * uv.y;
                    v2 land = {pl->qx[0] + pl->qx[1] * uv.x + pl->qx[2] * uv.y,
                               pl->qy[0] + pl->qy[1] * uv.x + pl->qy[2] * uv.y};
                    /* the plan against the direct computation rl__shoot_back() makes */
                    v3 d = L->sd[i];
                    double cos_r = -v3_dot(d, map->frame.n), dn = v3_dot(d, e->frame.n);
                    double hx = v3_dot(v3_sub(x, e->frame.origin), e->frame.n), td = hx / dn;
                    v2 qd = frame_project(&e->frame, v3_madd(x, d, -td));
                    dead += !pl->live;
                    if (pl->live != (cos_r > 0 && dn > 0))
                        plan_bad++;
                    double tol = 1e-9 * (1 + fabs(td));
                    if (pl->live &&
                        (fabs(tt - td) > tol || fabs(land.x - qd.x) > tol || fabs(land.y - qd.y) > tol))
                        plan_bad++;
                    if (!pl->live || !(tt > 0) || fabs(land.x) > 3 || fabs(land.y) > 3)
                        continue; /* the ray would not be cast */
                    casts = 1;
                    if (!is_known)
                        continue;
                    v3 from = v3_madd(x, pl->back, pl->tnear), to = v3_madd(x, pl->back, tt - pl->tshort);
                    int surely = 0, maybe = 0;
                    for (uint32_t k = 0; k < npolys; k++) {
                        const v3 *v;
                        size_t n = rl__occluders_polygon(occ, k, &v);
                        v3 nrm = v3_norm(v3_cross(v3_sub(v[1], v[0]), v3_sub(v[2], v[0])));
                        surely |= ts_segment_meets(v, n, nrm, from, to, 1e-7);
                        maybe |= ts_segment_meets(v, n, nrm, from, to, -1e-7);
                    }
                    int shadowed = rl__shadowed(sh, i, uv);
                    blocked += shadowed;
                    arrived += !shadowed;
                    wrong_free += surely && !shadowed;
                    wrong_blocked += !maybe && shadowed;
                }
            }
            casting += casts;
            unknown_casting += casts && !is_known;
            /* shadows from a part of the tile alone (culled's rectangle around a
             * solid angle's region) decide every origin in that part alike */
            double within[4] = {6 * ts_rnd() - 3, 0, 6 * ts_rnd() - 3, 0};
            within[1] = within[0] + (3 - within[0]) * ts_rnd();
            within[3] = within[2] + (3 - within[2]) * ts_rnd();
            CHECK(rl__shadows_build(&ctx, p, t, L, within, &part) == 0, "scene %d leaf %d: part's shadows", sc, lf);
            if (is_known && part.shadows->known) {
                for (int o = 0; o < ORIGINS / 4; o++) {
                    v2 uv = {within[0] + (within[1] - within[0]) * ts_rnd(),
                             within[2] + (within[3] - within[2]) * ts_rnd()};
                    rl__shadows_row(scratch.shadows, uv.x, uv.x, uv.y, uv.y);
                    rl__shadows_row(part.shadows, uv.x, uv.x, uv.y, uv.y);
                    for (uint32_t i = 0; i < SHARED; i++) {
                        if (!L->plan[i].live)
                            continue;
                        part_compared++;
                        part_differ += rl__shadowed(scratch.shadows, i, uv) != rl__shadowed(part.shadows, i, uv);
                    }
                }
                part_fewer += part.shadows->npolys < scratch.shadows->npolys;
            }
        }
        rl__scratch_free(&scratch);
        rl__scratch_free(&part);
        rl__occluders_destroy(occ);
        rl_scene_destroy(s);
    }
    printf("leaves: %ld of %ld with known shadows, %ld of %ld casting rays unknown; "
           "samples: %ld blocked, %ld arrive, %ld facing away\n",
           known, leaves, unknown_casting, casting, blocked, arrived, dead);
    printf("shadows from a part of the tile: %ld verdicts compared, %ld leaves with fewer shadows\n", part_compared,
           part_fewer);
    CHECK(part_compared > 1000 && part_differ == 0, "%ld of %ld verdicts in a part of the tile differ from the whole's",
          part_differ, part_compared);
    CHECK(part_fewer > 0, "a part of the tile casts fewer shadows somewhere");
    CHECK(plan_bad == 0, "%ld samples whose planned ray differs from the direct computation", plan_bad);
    CHECK(dead > 0, "some shared directions miss the receiver's front (%ld)", dead);
    CHECK(wrong_free == 0, "%ld samples whose segment crosses a polygon lie in no shadow", wrong_free);
    CHECK(wrong_blocked == 0, "%ld samples whose segment misses every polygon lie in a shadow", wrong_blocked);
    CHECK(unknown_casting <= 0.05 * casting, "shadows unknown for %ld of the %ld leaves that cast rays",
          unknown_casting, casting);
    CHECK(blocked > 1000 && arrived > 1000, "both outcomes occur: %ld blocked, %ld arrive", blocked, arrived);
    free(map);
    free(e);
    free(p);
    free(t);
    free(L);
    return check_report();
}
