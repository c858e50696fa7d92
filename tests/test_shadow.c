/*
 * test_shadow.c - the exact visibility of beams (relight/src/shadow.h)
 * against brute force: segments between random points of a beam's two
 * ends, intersected in double precision with every polygon of the scene.
 *
 * Scenes of random quads go through the real loader; each beam runs from a
 * random small quad or a point (a pyramid) to another small quad. What must
 * hold: a beam classified FREE has no segment meeting any polygon; one
 * classified BLOCKED has every segment meeting one; and the list of polygons
 * collected for a beam holds every polygon some segment meets (a superset is
 * what lets a block's parts be classified against its list). The search
 * for a single blocker (rl__occluders_block_any()) must find one exactly
 * for the BLOCKED beams, and, toward a box as the emitter tree asks, only
 * when every segment is met. Every outcome must occur, so that none of
 * these checks is vacuous.
 *
 * Corners (check_corners()): two walls sharing an edge, as a room's do, and
 * beams from inside their wedge to beyond both their planes, which no single
 * polygon may hide but the two together do: the search must find such
 * corners, and every segment of a beam it finds hidden must meet a polygon.
 * Beside them, two quads of one plane that share an edge and overlap (a seat
 * and the strip under its rim, in the classroom), which must not pass for a
 * corner: segments crossing the plane past their shared edge meet neither.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "check.h"
#include "relight_scenes.h"
#include "segment_meets.h"
#include "shadow.h"

#define SCENES 40
#define BEAMS_PER_SCENE 60
#define SEGMENTS 300
#define CAP 64

/* @return a point of quad v (4 vertices, a parallelogram) from two numbers in [0, 1). */
static v3 quad_point(const v3 *v, double s, double t)
{
    return v3_add(v[0], v3_add(v3_scale(v3_sub(v[1], v[0]), s), v3_scale(v3_sub(v[3], v[0]), t)));
}

/* The part of scene quad v (a parallelogram) of parameters [s0, s0 + f] x [t0, t0 + f]: a patch lying on it. */
static void quad_patch(const v3 *v, double s0, double t0, double f, v3 out[4])
{
    out[0] = quad_point(v, s0, t0);
    out[1] = quad_point(v, s0 + f, t0);
    out[2] = quad_point(v, s0 + f, t0 + f);
    out[3] = quad_point(v, s0, t0 + f);
}

/* A random quad shrunk about its centre by f, as world points. */
static void small_quad(double f, v3 out[4])
{
    tpoly q = ts_random_quad("grey");
    v3 c = {0, 0, 0};
    for (int k = 0; k < 4; k++)
        c = v3_add(c, v3_scale(v3_load(q.v[k]), 0.25));
    for (int k = 0; k < 4; k++)
        out[k] = v3_add(c, v3_scale(v3_sub(v3_load(q.v[k]), c), f));
}

/* @return 1 if segment x -> y meets polygon k of s (ts_segment_meets()). */
static int segment_meets(const rl_scene *s, size_t k, v3 x, v3 y, double margin)
{
    const rl_polygon *pg = &s->polygons[k];
    v3 v[RL_SCENE_MAX_POLY_VERTS];
    for (uint32_t i = 0; i < pg->count; i++)
        v[i] = v3_load(s->vertices[pg->first + i]);
    return ts_segment_meets(v, pg->count, v3_load(pg->normal), x, y, margin);
}

/* Checks rl__occluders_block_any() from points a (na) to the eight corners
 * of b's bounding box, a far end that is not planar (as the emitter tree
 * gives it): when it finds a blocker, every segment from a point of a's hull
 * to a point of the box must meet a polygon. Counts the found in *found. */
static void box_blocks(const rl_scene *s, const rl_occluders *occ, const v3 *a, size_t na, const v3 *b, long *found,
                       long *segments)
{
    v3 lo = b[0], hi = b[0], corner[8];
    for (int k = 1; k < 4; k++) {
        lo = (v3){fmin(lo.x, b[k].x), fmin(lo.y, b[k].y), fmin(lo.z, b[k].z)};
        hi = (v3){fmax(hi.x, b[k].x), fmax(hi.y, b[k].y), fmax(hi.z, b[k].z)};
    }
    for (int c = 0; c < 8; c++)
        corner[c] = (v3){c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z};
    if (!rl__occluders_block_any(occ, a, na, corner, 8, 1e-6, 1e-9, NULL))
        return;
    (*found)++;
    int all_met = 1;
    for (int sg = 0; sg < SEGMENTS; sg++, (*segments)++) {
        v3 x = na == 1 ? a[0] : sg < 32 ? a[sg % 4] : quad_point(a, ts_rnd(), ts_rnd());
        v3 y = sg < 32 ? corner[(sg / 4) % 8] : (v3){lo.x + ts_rnd() * (hi.x - lo.x), lo.y + ts_rnd() * (hi.y - lo.y),
                                                      lo.z + ts_rnd() * (hi.z - lo.z)};
        int met = 0;
        for (size_t k = 0; k < s->npolygons && !met; k++)
            met = segment_meets(s, k, x, y, -1e-7);
        all_met &= met;
    }
    CHECK(all_met, "a blocker found from a patch to a box, but a segment between them passes");
}

/* Writes the n grey quads p as the scene at path and loads it into *s. @return its occluder index, or NULL
 * (reported). */
static rl_occluders *grey_scene(const char *path, const tpoly *p, int n, rl_scene **s)
{
    ts_write_scene(path, "{\"grey\": {\"albedo\": [0.5, 0.5, 0.5]}}", p, n, NULL);
    *s = ts_load(path);
    rl_occluders *occ = NULL;
    CHECK(*s && rl__occluders_new(*s, &occ) == RL_OK, "%s and its occluder index", path);
    return occ;
}

/* A patch of side f about point c, in the plane spanned by unit vectors u and w. */
static void patch_at(v3 c, v3 u, v3 w, double f, v3 out[4])
{
    const double corner[4][2] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
    for (int k = 0; k < 4; k++)
        out[k] = v3_add(c, v3_add(v3_scale(u, f * corner[k][0]), v3_scale(w, f * corner[k][1])));
}

/* Stores the four points v as a quad of the scene. */
static tpoly quad_of(const v3 v[4])
{
    tpoly q = {"grey", 4, {{0}}};
    for (int k = 0; k < 4; k++)
        v3_store(v[k], q.v[k]);
    return q;
}

/* The corners of the file's comment: scenes of a corner's two walls (a frame turned at random: walls along u
 * and w from o, height h), a pair of overlapping quads of one plane sharing an edge, and 8 random quads;
 * beams from a patch in the walls' wedge to a patch beyond both their planes (above the walls at times),
 * and from below the pair's plane to above it, across their shared edge. Every segment of a beam found
 * hidden must meet a polygon. Counts in found[0] the beams found hidden by a corner alone (not BLOCKED by
 * one polygon), and in found[1] the beams across the pair with a segment that meets nothing. */
static void check_corners(const char *tmp, rl_beam *beam, long found[2], long *segments)
{
    for (int sc = 0; sc < SCENES / 2; sc++) {
        v3 u = v3_norm((v3){ts_rnd() - 0.5, ts_rnd() - 0.5, ts_rnd() - 0.5});
        v3 h = v3_norm(v3_cross(u, (v3){ts_rnd() - 0.5, ts_rnd() - 0.5, ts_rnd() - 0.5}));
        v3 w = v3_cross(h, u), o = {ts_rnd() - 0.5, ts_rnd() - 0.5, ts_rnd() - 0.5};
        double len = 2.0, tall = 1.5;
        v3 wall1[4] = {o, v3_add(o, v3_scale(u, len)), v3_add(v3_add(o, v3_scale(u, len)), v3_scale(h, tall)),
                       v3_add(o, v3_scale(h, tall))};
        v3 wall2[4] = {o, v3_add(o, v3_scale(h, tall)), v3_add(v3_add(o, v3_scale(w, len)), v3_scale(h, tall)),
                       v3_add(o, v3_scale(w, len))};
        /* the pair: a quad of the plane through p0 spanned by u and w, and the strip along its edge at +u
         * inside it, the same plane facing the other way */
        v3 p0 = v3_add(o, v3_scale(h, 4.0)), e0 = v3_add(p0, v3_scale(u, 1.0)), e1 = v3_add(e0, v3_scale(w, 1.0));
        v3 seat[4] = {p0, e0, e1, v3_add(p0, v3_scale(w, 1.0))};
        v3 rim[4] = {v3_sub(e0, v3_scale(u, 0.1)), v3_sub(e1, v3_scale(u, 0.1)), e1, e0};
        tpoly p[12];
        p[0] = quad_of(wall1), p[1] = quad_of(wall2), p[2] = quad_of(seat), p[3] = quad_of(rim);
        for (int k = 4; k < 12; k++) {
            p[k] = ts_random_quad("grey"); /* moved far off, so that they seldom stand in the way */
            for (int i = 0; i < 4; i++)
                p[k].v[i][0] += 9.0;
        }
        char path[1100];
        snprintf(path, sizeof path, "%s/shadow_corner_%d.json", tmp, sc);
        rl_scene *s = NULL;
        rl_occluders *occ = grey_scene(path, p, 12, &s);
        for (int bi = 0; occ && bi < BEAMS_PER_SCENE; bi++) {
            v3 a[4], b[4];
            int across = bi % 3 == 2;
            if (!across) {
                v3 ca = v3_add(o, v3_add(v3_scale(u, 0.2 + 0.8 * ts_rnd()),
                                          v3_add(v3_scale(w, 0.2 + 0.8 * ts_rnd()), v3_scale(h, 0.2 + ts_rnd()))));
                v3 cb = v3_sub(o, v3_add(v3_scale(u, 0.2 + 0.8 * ts_rnd()),
                                          v3_sub(v3_scale(w, 0.2 + 0.8 * ts_rnd()), v3_scale(h, 0.3 + 1.4 * ts_rnd()))));
                patch_at(ca, u, w, 0.1, a);
                patch_at(cb, u, w, 0.1, b);
            } else { /* below the pair, near its shared edge, to above it past the edge */
                v3 ca = v3_add(e0, v3_add(v3_scale(u, -0.3 * ts_rnd()), v3_sub(v3_scale(w, 0.5), v3_scale(h, 0.5))));
                v3 cb = v3_add(e0, v3_add(v3_scale(u, 0.3 * ts_rnd()), v3_add(v3_scale(w, 0.5), v3_scale(h, 0.5))));
                patch_at(ca, u, w, 0.1, a);
                patch_at(cb, u, w, 0.1, b);
            }
            uint32_t blocker = UINT32_MAX;
            int any = rl__occluders_block_any(occ, a, 4, b, 4, 1e-9, 1e-9, &blocker);
            rl_visibility vis = VIS_PARTIAL;
            uint32_t list[CAP], mine[CAP];
            size_t n = 0, nmine = 0;
            if (rl__beam_make(a, 4, b, 4, 1e-9, beam) && (n = rl__occluders_collect(occ, beam, -1, list, CAP)) != SIZE_MAX)
                vis = rl__occluders_classify(occ, beam, list, n, mine, &nmine);
            found[0] += any && vis != VIS_BLOCKED;
            int all_met = 1, passed = 0;
            for (int sg = 0; sg < SEGMENTS; sg++, (*segments)++) {
                v3 x = sg < 16 ? a[sg % 4] : quad_point(a, ts_rnd(), ts_rnd());
                v3 y = sg < 16 ? b[(sg / 4) % 4] : quad_point(b, ts_rnd(), ts_rnd());
                int met = 0;
                for (size_t k = 0; k < s->npolygons && !met; k++)
                    met = segment_meets(s, k, x, y, -1e-7);
                all_met &= met;
                passed |= !met;
            }
            found[1] += across && passed;
            CHECK(!any || all_met, "corner scene %d beam %d: found hidden (by polygon %u), but a segment passes", sc,
                  bi, blocker);
        }
        rl__occluders_destroy(occ);
        rl_scene_destroy(s);
    }
}

int main(void)
{
    const char *tmp = getenv("ILF_TEST_TMP") ? getenv("ILF_TEST_TMP") : "/tmp";
    long outcomes[3] = {0, 0, 0}, overflowed = 0, segments = 0, tried[2] = {0, 0}, made[2] = {0, 0}, box_found = 0;
    rl_beam *beam = malloc(sizeof *beam);
    if (!beam)
        return 1;
    for (int sc = 0; sc < SCENES; sc++) {
        char path[1100];
        snprintf(path, sizeof path, "%s/shadow_%d.json", tmp, sc);
        tpoly p[12];
        for (int k = 0; k < 12; k++)
            p[k] = ts_random_quad("grey");
        if (sc % 2) {
            /* quad 1 hinged on quad 0's first edge, leaning over it by 60 degrees: its plane holds
             * part of a near end on quad 0 touching that edge, which must not make it unreachable */
            v3 v0 = v3_load(p[0].v[0]), v1 = v3_load(p[0].v[1]), w = v3_sub(v3_load(p[0].v[3]), v0);
            v3 axis = v3_norm(v3_sub(v1, v0));
            double c = 0.5, sn = sqrt(0.75);
            v3 r = v3_add(v3_add(v3_scale(w, c), v3_scale(v3_cross(axis, w), sn)),
                          v3_scale(axis, v3_dot(axis, w) * (1 - c)));
            v3 hinge[4] = {v1, v0, v3_add(v0, r), v3_add(v1, r)};
            for (int k = 0; k < 4; k++)
                v3_store(hinge[k], p[1].v[k]);
        }
        rl_scene *s = NULL;
        rl_occluders *occ = grey_scene(path, p, 12, &s);
        for (int bi = 0; occ && bi < BEAMS_PER_SCENE; bi++) {
            v3 a[4], b[4];
            size_t na = bi % 2 ? 4 : 1; /* every other beam a pyramid */
            int32_t skip = -1;
            small_quad(0.3, a);
            small_quad(0.3, b);
            if (bi % 4 == 3) {
                /* as the engine makes them: from a patch of one scene quad to a patch of another, which
                 * is skipped; both lie in the ends' planes, which the rule for such planes must pass */
                int k1 = sc % 2 ? 0 : (int)(ts_rnd() * 12), k2 = (k1 + 2 + (int)(ts_rnd() * 10)) % 12;
                v3 q1[4], q2[4];
                for (int k = 0; k < 4; k++) {
                    q1[k] = v3_load(p[k1].v[k]);
                    q2[k] = v3_load(p[k2].v[k]);
                }
                /* on the hinge's edge (t = 0) in scenes that have one */
                quad_patch(q1, 0.6 * ts_rnd(), sc % 2 ? 0.0 : 0.6 * ts_rnd(), 0.4, a);
                quad_patch(q2, 0.6 * ts_rnd(), 0.6 * ts_rnd(), 0.4, b);
                skip = k2;
            }
            if (na == 1)
                a[0] = quad_point(a, 0.5, 0.5);
            tried[na > 1]++;
            if (!rl__beam_make(a, na, b, 4, 1e-9, beam))
                continue; /* b's plane holds a, or nearly: possible, but rare */
            made[na > 1]++;
            uint32_t list[CAP], mine[CAP];
            size_t n = rl__occluders_collect(occ, beam, skip, list, CAP), nmine = 0;
            if (n == SIZE_MAX) {
                overflowed++;
                continue;
            }
            rl_visibility vis = rl__occluders_classify(occ, beam, list, n, mine, &nmine);
            outcomes[vis]++;
            /* the early-exit search finds a blocker whenever the classification does: its pruning by the
             * segment that every blocker crosses never loses one (it may find a corner besides: checked by
             * the segments below) */
            uint32_t blocker = UINT32_MAX;
            int any = rl__occluders_block_any(occ, a, na, b, 4, 1e-9, 1e-9, &blocker);
            CHECK(!any || rl__occluders_blocks(occ, blocker, a, na, b, 4, 1e-9, 1e-9),
                  "scene %d beam %d: the blocker found does not block", sc, bi);
            CHECK(any || vis != VIS_BLOCKED, "scene %d beam %d: BLOCKED, but no blocker found", sc, bi);
            box_blocks(s, occ, a, na, b, &box_found, &segments);
            int in_list[12] = {0};
            for (size_t i = 0; i < n; i++)
                in_list[list[i]] = 1;
            int free_ok = 1, blocked_ok = 1, list_ok = 1;
            for (int sg = 0; sg < SEGMENTS; sg++, segments++) {
                /* the first segments join vertices, where the classification is tightest */
                v3 x = na == 1 ? a[0] : sg < 16 ? a[sg % 4] : quad_point(a, ts_rnd(), ts_rnd());
                v3 y = sg < 16 ? b[(sg / 4) % 4] : quad_point(b, ts_rnd(), ts_rnd());
                int met_any = 0;
                for (size_t k = 0; k < s->npolygons; k++) {
                    if ((int32_t)k == skip)
                        continue;
                    if (segment_meets(s, k, x, y, 1e-7)) {
                        met_any = 1;
                        list_ok &= in_list[k];
                    }
                    if (vis == VIS_BLOCKED || any)
                        met_any |= segment_meets(s, k, x, y, -1e-7);
                }
                if (vis == VIS_FREE && met_any)
                    free_ok = 0;
                if ((vis == VIS_BLOCKED || any) && !met_any)
                    blocked_ok = 0;
            }
            CHECK(free_ok, "scene %d beam %d: FREE, but a segment meets a polygon", sc, bi);
            CHECK(blocked_ok, "scene %d beam %d: BLOCKED or a blocker found, but a segment passes", sc, bi);
            CHECK(list_ok, "scene %d beam %d: a polygon a segment meets is missing from the collected list", sc, bi);
            CHECK(vis != VIS_PARTIAL || nmine > 0, "scene %d beam %d: PARTIAL names no polygon", sc, bi);
        }
        rl__occluders_destroy(occ);
        rl_scene_destroy(s);
    }
    printf("beams: %ld free, %ld partial, %ld blocked, %ld over the list's capacity; %ld segments\n", outcomes[0],
           outcomes[1], outcomes[2], overflowed, segments);
    CHECK(made[0] >= 0.95 * tried[0] && made[1] >= 0.95 * tried[1], "beams made: %ld of %ld pyramids, %ld of %ld",
          made[0], tried[0], made[1], tried[1]);
    CHECK(outcomes[VIS_FREE] > 0 && outcomes[VIS_PARTIAL] > 0 && outcomes[VIS_BLOCKED] > 0,
          "every outcome occurs: %ld free, %ld partial, %ld blocked", outcomes[0], outcomes[1], outcomes[2]);
    printf("blockers found from a patch to a box: %ld\n", box_found);
    CHECK(box_found > 0, "some patch is wholly hidden from some box");
    long corners[2] = {0, 0};
    check_corners(tmp, beam, corners, &segments);
    printf("corners: %ld beams hidden by a corner alone; %ld beams across a pair of one plane that a segment passes\n",
           corners[0], corners[1]);
    CHECK(corners[0] > 0 && corners[1] > 0, "corners hide some beams (%ld) and beams pass a pair of one plane (%ld)",
          corners[0], corners[1]);
    free(beam);
    return check_report();
}
