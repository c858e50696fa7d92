/*
 * bench_pathtrace.h - the independent reference of `ilf bench --reference
 * pathtrace` and of tests/test_pathtrace.c: plain Monte Carlo path tracing
 * of a diffuse scene lit by diffuse polygons and light field slabs
 * (bench_pathtrace.c says how, and why it shares nothing with the engine's
 * estimators).
 *
 * Invariants: a tracer only reads the scene, which must outlive it; one
 * tracer may answer from several threads; every estimate is a function of
 * its seed alone, so answers repeat bit for bit.
 */
#ifndef ILF_BENCH_PATHTRACE_H
#define ILF_BENCH_PATHTRACE_H

#include <stddef.h>
#include <stdint.h>

#include "relight/engine.h"
#include "relight/scene.h"

/** The scene made ready for path tracing. Opaque. */
typedef struct bench_pt bench_pt;

/** An estimate of irradiance: the mean over its paths and the standard error of that mean. */
typedef struct bench_pt_estimate {
    double rgb[3]; /**< W m^-2 */
    double y;      /**< luminance of rgb */
    double y_se;   /**< standard error of y */
} bench_pt_estimate;

/** Prepares scene for path tracing. @return the tracer, or NULL with the reason in why (size bytes). */
bench_pt *bench_pt_new(const rl_scene *scene, char *why, size_t size);

/** Releases a tracer. NULL is a no-op. */
void bench_pt_destroy(bench_pt *pt);

/**
 * Irradiance at point x of a surface with unit normal n (light from n's side),
 * from paths of `bounces` diffuse reflections at most, `paths` of them, drawn
 * from seed.
 */
void bench_pt_point(const bench_pt *pt, const double x[3], const double n[3], uint32_t bounces, uint32_t paths,
                    uint64_t seed, bench_pt_estimate *out);

/**
 * Mean irradiance over cell (i, j) of a radiance map (info as the engine describes it): each path starts
 * at its own point drawn uniformly over the cell clipped to the map's polygon (centre where no draw
 * lands inside: a sliver), so the standard error covers the cell's spread too.
 */
void bench_pt_cell(const bench_pt *pt, const rl_map_info *info, uint32_t i, uint32_t j, const double centre[3],
                   uint32_t bounces, uint32_t paths, uint64_t seed, bench_pt_estimate *out);

#endif /* ILF_BENCH_PATHTRACE_H */
