/*
 * camera_cli.c - the camera options shared by `ilf view` and `ilf relight`
 * (camera_cli.h).
 *
 * Invariants: the defaults without a scene camera are the scene file's
 * (docs/scene.md, "camera"), so a camera given on the command line and the
 * same camera in a scene file render the same view.
 */
#include "camera_cli.h"

#include <stdio.h>

#include "commands.h"

/* The scene file's camera defaults (docs/scene.md). */
static const rl_camera camera_defaults = {.up = {0, 0, 1}, .fov_deg = 45, .width = 640, .height = 480};

void camera_options_fill(cli_option *table, int over_scene)
{
    static const char *const help[2][CAMERA_OPT_COUNT] = {
        {"camera position, metres (required)", "point the camera looks at (required)",
         "up direction (default 0,0,1)", "vertical field of view, degrees, between 0 and 180 (default 45)",
         "image size in pixels (default 640x480)"},
        {"camera position, metres (default: the scene camera's; with --look-at, a view of a scene without one)",
         "point the camera looks at (default: the scene camera's)",
         "up direction (default: the scene camera's, else 0,0,1)",
         "vertical field of view, degrees, between 0 and 180 (default: the scene camera's, else 45)",
         "view size in pixels (default: the scene camera's, else 640x480)"},
    };
    static const char *const names[CAMERA_OPT_COUNT] = {"position", "look-at", "up", "fov", "size"};
    static const char *const metas[CAMERA_OPT_COUNT] = {"X,Y,Z", "X,Y,Z", "X,Y,Z", "DEG", "WxH"};
    for (int k = 0; k < CAMERA_OPT_COUNT; k++)
        table[k] = (cli_option){names[k], 0, metas[k], help[over_scene != 0][k]};
}

int camera_option_apply(const cli_parser *p, camera_overrides *o, int opt, const char *value)
{
    rl_camera *c = &o->values;
    o->given |= 1u << opt;
    switch (opt) {
    case CAMERA_OPT_POSITION: return cli_value_doubles(p, value, c->position, 3);
    case CAMERA_OPT_LOOK_AT: return cli_value_doubles(p, value, c->look_at, 3);
    case CAMERA_OPT_UP: return cli_value_doubles(p, value, c->up, 3);
    case CAMERA_OPT_FOV:
        if (!cli_value_double(p, value, &c->fov_deg))
            return 0;
        if (!(c->fov_deg > 0.0 && c->fov_deg < 180.0))
            return cli_bad_value(p, value, "must lie strictly between 0 and 180 degrees"), 0;
        return 1;
    default: {
        uint32_t size[2];
        if (!cli_value_u32_pair(p, value, 'x', 1, ILF_CAMERA_MAX_SIDE, size))
            return 0;
        c->width = size[0];
        c->height = size[1];
        return 1;
    }
    }
}

int camera_resolve(const char *sub, const camera_overrides *o, const rl_camera *base, rl_camera *out)
{
    const unsigned both = 1u << CAMERA_OPT_POSITION | 1u << CAMERA_OPT_LOOK_AT;
    if (base == NULL && o->given == 0)
        return 0;
    if (base == NULL && (o->given & both) != both) {
        cli_error(sub, "%s is required%s", o->given & 1u << CAMERA_OPT_POSITION ? "--look-at X,Y,Z" : "--position X,Y,Z",
                  o->given & ~both ? " (the camera options make a camera; there is no other to change)" : "");
        return -1;
    }
    rl_camera c = base ? *base : camera_defaults;
    const rl_camera *v = &o->values;
    if (o->given & 1u << CAMERA_OPT_POSITION)
        for (int i = 0; i < 3; i++)
            c.position[i] = v->position[i];
    if (o->given & 1u << CAMERA_OPT_LOOK_AT)
        for (int i = 0; i < 3; i++)
            c.look_at[i] = v->look_at[i];
    if (o->given & 1u << CAMERA_OPT_UP)
        for (int i = 0; i < 3; i++)
            c.up[i] = v->up[i];
    if (o->given & 1u << CAMERA_OPT_FOV)
        c.fov_deg = v->fov_deg;
    if (o->given & 1u << CAMERA_OPT_SIZE) {
        c.width = v->width;
        c.height = v->height;
    }
    if (rl_camera_check(&c) != RL_OK) {
        cli_error(sub, "%s (from %s)", rl_errmsg(), base ? "the scene's camera and the camera options" : "the camera options");
        return -1;
    }
    *out = c;
    return 1;
}
