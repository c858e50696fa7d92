/*
 * camera.h - a pinhole camera, as a value: where it is, what it looks at,
 * which way is up, its vertical field of view and its image size. A scene
 * file may carry one (docs/scene.md, "camera"); a caller may make its own
 * and render a solution through it (engine.h) without changing the scene.
 * Conventions as in relight/relight.h.
 *
 * The image: row 0 at the top; the pixel (x, y) sees along the ray through
 * its centre; up is made orthogonal to the view direction; the field of
 * view is vertical, the horizontal one follows from width / height.
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_CAMERA_H
#define RELIGHT_CAMERA_H

#include <stdint.h>
#include "ilf/limits.h"
#include "relight/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A camera; rl_camera_check() says whether one is valid. */
typedef struct rl_camera {
    double position[3];     /**< the eye, world metres */
    double look_at[3];      /**< a point it looks at, distinct from position */
    double up[3];           /**< up, not zero nor parallel to the view direction (the scene file's default: 0,0,1) */
    double fov_deg;         /**< vertical field of view, degrees, strictly between 0 and 180 (default 45) */
    uint32_t width, height; /**< image size, pixels, 1 .. ILF_CAMERA_MAX_SIDE (default 640 x 480) */
} rl_camera;

/**
 * Checks a camera: every number finite, position and look_at distinct, up
 * neither zero nor parallel to the view direction, the field of view and
 * the size in range.
 * @return RL_OK; RL_ERR_ARG with a message naming the problem ("camera: ...").
 */
rl_status rl_camera_check(const rl_camera *c);

/**
 * Gives in dir the unit direction of the ray of camera c (valid: rl_camera_check())
 * through the image point (fx, fy): fx from 0 at the left edge to 1 at the right,
 * fy from 0 at the top to 1 at the bottom; pixel (x, y)'s centre is
 * ((x + 0.5) / width, (y + 0.5) / height). The ray starts at c->position.
 */
void rl_camera_ray(const rl_camera *c, double fx, double fy, double dir[3]);

/** Copies the scene's camera into *out. @return 1, or 0 (*out untouched) if the scene has none or s is NULL. */
int rl_scene_camera(const rl_scene *s, rl_camera *out);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_CAMERA_H */
