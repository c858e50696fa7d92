/* consumer_irradiance.c - a program against an installed relight: it writes a tiny scene (one square
 * lamp, nothing else) to the file it is given, loads it, computes irradiance at points with
 * rl_irradiance() and holds each value against the closed form of an unoccluded polygon
 * (rl_reference_polygon_irradiance()). Exit 0 only if every value is finite, positive where the lamp
 * is in view, zero where it is not, and within 1% of the closed form. */
#include <math.h>
#include <stdio.h>

#include <relight/engine.h>
#include <relight/reference.h>
#include <relight/scene.h>

#define LAMP_RADIANCE 10.0
/* a 1 m square at height 1, counter-clockwise seen from below: it emits downwards */
static const double lamp[4][3] = {{-0.5, -0.5, 1}, {-0.5, 0.5, 1}, {0.5, 0.5, 1}, {0.5, -0.5, 1}};
/* x y z nx ny nz: under the lamp facing up, off-centre, tilted, and one facing away (unlit) */
static const double points[][6] = {{0, 0, 0, 0, 0, 1}, {0.3, -0.2, 0, 0, 0, 1}, {1, 1, 0.2, -1, -1, 1},
                                   {0, 0, 0, 0, 0, -1}};
#define POINTS (sizeof points / sizeof points[0])

static int write_scene(const char *path)
{
    FILE *f = fopen(path, "w");
    if (f == NULL)
        return 0;
    fprintf(f, "{\"materials\": {\"lamp\": {\"albedo\": [0, 0, 0], \"emission\": [%g, %g, %g]}},\n"
               " \"polygons\": [{\"material\": \"lamp\", \"vertices\": [",
            LAMP_RADIANCE, LAMP_RADIANCE, LAMP_RADIANCE);
    for (int k = 0; k < 4; k++)
        fprintf(f, "%s[%g, %g, %g]", k ? ", " : "", lamp[k][0], lamp[k][1], lamp[k][2]);
    fprintf(f, "]}],\n \"sampling\": {\"partition_n\": 8}}\n");
    return fclose(f) == 0;
}

int main(int argc, char **argv)
{
    rl_scene *scene = NULL;
    double e[POINTS * 3];
    if (argc != 2 || !write_scene(argv[1])) {
        fprintf(stderr, "usage: consumer_irradiance SCENE.json (written, then loaded)\n");
        return 2;
    }
    if (rl_scene_load(argv[1], &scene) != RL_OK || rl_irradiance(scene, NULL, &points[0][0], POINTS, e, NULL) != RL_OK) {
        fprintf(stderr, "consumer_irradiance: %s\n", rl_errmsg());
        rl_scene_destroy(scene);
        return 1;
    }
    int ok = 1;
    for (size_t i = 0; i < POINTS; i++) {
        const double *p = points[i];
        double len = sqrt(p[3] * p[3] + p[4] * p[4] + p[5] * p[5]), n[3] = {p[3] / len, p[4] / len, p[5] / len};
        double want = rl_reference_polygon_irradiance(&lamp[0][0], 4, p, n, LAMP_RADIANCE);
        int good = 1;
        for (int c = 0; c < 3; c++) {
            double got = e[3 * i + c];
            good &= isfinite(got) && (want > 0 ? got > 0 && fabs(got - want) <= 0.01 * want : got == 0);
        }
        printf("point %zu: %g %g %g W m^-2 (closed form %g) %s\n", i, e[3 * i], e[3 * i + 1], e[3 * i + 2], want,
               good ? "ok" : "WRONG");
        ok &= good;
    }
    rl_scene_destroy(scene);
    return ok ? 0 : 1;
}
