/*
 * camera_cli.h - the camera options of `ilf view` and `ilf relight`
 * (--position, --look-at, --up, --fov, --size): one table, one parser and
 * one way of making a camera of them (relight's rl_camera, checked by
 * rl_camera_check()), so that the commands agree on what a camera is.
 *
 * Invariants: an option given replaces exactly that part of the camera it
 * starts from (the scene's, or the scene file's defaults when there is
 * none); values are range-checked when parsed and the whole camera is
 * checked once made, so a bad camera is bad usage (exit 2).
 */
#ifndef ILF_CAMERA_CLI_H
#define ILF_CAMERA_CLI_H

#include "cli.h"
#include "relight/camera.h"

/* The camera options, in their order in a command's table: a command
 * reserves CAMERA_OPT_COUNT entries from some index and fills them with
 * camera_options_fill(). */
enum camera_option_id { CAMERA_OPT_POSITION, CAMERA_OPT_LOOK_AT, CAMERA_OPT_UP, CAMERA_OPT_FOV, CAMERA_OPT_SIZE,
                        CAMERA_OPT_COUNT };

/** Camera options given on the command line. */
typedef struct camera_overrides {
    unsigned given;   /**< bit k set when option k (enum camera_option_id) was given */
    rl_camera values; /**< the given values; other fields unused */
} camera_overrides;

/**
 * Fills table[0 .. CAMERA_OPT_COUNT) with the camera options. over_scene:
 * the options change a scene's camera (`ilf relight`: each defaults to the
 * scene camera's); 0: they make the whole camera (`ilf view`: --position
 * and --look-at required).
 */
void camera_options_fill(cli_option *table, int over_scene);

/** Parses the value of camera option opt (< CAMERA_OPT_COUNT) into o. @return 1, or 0 after reporting. */
int camera_option_apply(const cli_parser *p, camera_overrides *o, int opt, const char *value);

/**
 * Makes the camera of a command: base (NULL: none) with the given options
 * in place of its parts; without a base, --position and --look-at are
 * needed and the rest take the scene file's defaults (docs/scene.md).
 * @return 1 and *out; 0 when there is no camera (no base, no option
 * given); -1 after reporting a missing option or a camera that
 * rl_camera_check() refuses (exit 2).
 */
int camera_resolve(const char *sub, const camera_overrides *o, const rl_camera *base, rl_camera *out);

#endif /* ILF_CAMERA_CLI_H */
