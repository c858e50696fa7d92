/*
 * point_gather.h - culled transfer to a point receiver from the point's own view
 * of each emitter (point_gather.c), and Lambert's closed form for an unoccluded
 * polygon that it and Lambert's gather (lambert.c) share.
 */
#ifndef RELIGHT_POINT_GATHER_H
#define RELIGHT_POINT_GATHER_H

#include "pass.h"

/* Adds to out the irradiance at point x (unit normal nx) from emitter ei,
 * by culled transfer from the point's own view (point_gather.c): exact where a
 * part of the emitter is wholly seen or wholly hidden, `rays` samples in
 * each solid angle a shadow boundary crosses. receiver keys the samples.
 * @return 0, or -1 if scratch memory ran out. */
int rl__point_gather(const rl_transfer_ctx *ctx, uint32_t ei, uint64_t receiver, v3 x, v3 nx, uint32_t rays,
                 double out[3], rl_scratch *s, rl_counters *cnt);

/* @return (1/2) sum over edges of theta_i (n . g_i): the irradiance at x (unit normal n) from the
 * convex polygon q (nq vertices, all in front of x's plane) of unit radiance, unoccluded. */
double rl__polygon_lambert(v3 x, v3 n, const v3 *q, size_t nq);

#endif /* RELIGHT_POINT_GATHER_H */
