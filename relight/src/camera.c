/*
 * camera.c - rl_camera (relight/camera.h): its checks, shared by the scene
 * loader and by callers that bring their own camera; its rays, shared by
 * every render (relight's and `ilf view`'s); the scene's camera as a value.
 *
 * Invariants: a camera that passes rl__camera_problem() has a well-defined
 * frame (forward, right and up unit and orthogonal), so a render through it
 * casts finite rays only.
 */
#include <math.h>
#include <stdio.h>

#include "common.h"
#include "scene_model.h"
#include "ilf/vec.h"

int rl__camera_problem(const rl_camera *c, char *why, size_t size)
{
    v3 view = v3_sub(v3_load(c->look_at), v3_load(c->position)), up = v3_load(c->up);
    double lv = v3_len(view), ls = v3_len(v3_cross(view, up));
    const char *problem = NULL;
    if (!isfinite(v3_maxabs(v3_load(c->position))) || !isfinite(v3_maxabs(v3_load(c->look_at))) ||
        !isfinite(v3_maxabs(up)))
        problem = "position, look_at and up must be finite";
    else if (!(lv > 0 && isfinite(lv)))
        problem = "position and look_at must be distinct points";
    else if (!(ls > 1e-9 * lv * v3_len(up)) || !isfinite(ls))
        problem = "up must not be zero or parallel to the view direction";
    else if (!(c->fov_deg > 0 && c->fov_deg < 180))
        problem = "fov_deg must lie strictly between 0 and 180 degrees";
    else if (c->width < 1 || c->height < 1 || c->width > ILF_CAMERA_MAX_SIDE || c->height > ILF_CAMERA_MAX_SIDE) {
        snprintf(why, size, "width and height must be 1 to %u pixels, got %u x %u", ILF_CAMERA_MAX_SIDE,
                 (unsigned)c->width, (unsigned)c->height);
        return 1;
    }
    if (problem != NULL)
        snprintf(why, size, "%s", problem);
    return problem != NULL;
}

rl_status rl_camera_check(const rl_camera *c)
{
    if (c == NULL)
        return rl__fail(RL_ERR_ARG, "rl_camera_check: NULL camera");
    char why[160];
    return rl__camera_problem(c, why, sizeof why) ? rl__fail(RL_ERR_ARG, "camera: %s", why) : RL_OK;
}

void rl_camera_ray(const rl_camera *c, double fx, double fy, double dir[3])
{
    v3 forward = v3_norm(v3_sub(v3_load(c->look_at), v3_load(c->position)));
    v3 right = v3_norm(v3_cross(forward, v3_load(c->up)));
    v3 up = v3_cross(right, forward);
    double tan_half = tan(c->fov_deg * ILF_PI / 360.0), aspect = (double)c->width / c->height;
    double sx = (2.0 * fx - 1.0) * tan_half * aspect, sy = (1.0 - 2.0 * fy) * tan_half;
    v3 d = v3_norm(v3_add(forward, v3_add(v3_scale(right, sx), v3_scale(up, sy))));
    dir[0] = d.x;
    dir[1] = d.y;
    dir[2] = d.z;
}

int rl_scene_camera(const rl_scene *s, rl_camera *out)
{
    if (s == NULL || !s->has_camera || out == NULL)
        return 0;
    *out = s->camera;
    return 1;
}
