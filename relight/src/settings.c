/*
 * settings.c - the one table of sampling settings (relight.h's
 * rl_setting_info): each setting's scene key, command-line option, field,
 * type, allowed values, default and help, and the few operations every
 * reader of settings needs (rule in words, check, get, set).
 *
 * Invariants: the table's rows are in the scene file's key order and cover
 * every field of rl_sampling; rl_sampling_default() is built from the
 * defaults here, so the defaults, the loader (scene.c), the setter
 * (rl_job_check) and the command line (tools/relight_cli.c) cannot
 * disagree. Bounds are doubles, exact for every integer a bound names
 * (all at most 2^53).
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "scene_model.h"

/* The integers a JSON number (a scene file, stats.json) holds exactly: seeds are written there. */
#define JSON_EXACT_MAX 9007199254740992.0

#define FIELD(f) offsetof(rl_sampling, f)

static const rl_setting_info settings[] = {
    {"method", "method", "M", RL_SETTING_METHOD, FIELD(method), RL_METHOD_CULLED, RL_METHOD_ADAPTIVE, 0,
     RL_METHOD_CULLED, "the transfer method"},
    {"partition_n", "partition-n", "N", RL_SETTING_UINT32, FIELD(partition_n), 1, 4096, RL_SETTING_POW2, 32,
     "partition level; 4096 solid angles per hemisphere at 32"},
    {"rays_per_solid_angle", "rays", "K", RL_SETTING_UINT32, FIELD(rays_per_solid_angle), 1, 65536, 0, 4,
     "rays per (cell, solid angle)"},
    {"samples_per_cell", "samples", "N", RL_SETTING_UINT32, FIELD(samples_per_cell), 1, 1048576, 0, 128,
     "shadow rays per (cell, emitter), area and solidangle"},
    {"bounces", "bounces", "B", RL_SETTING_UINT32, FIELD(bounces), 0, 64, 0, 0,
     "diffuse passes after the direct one"},
    {"bounce_partition_n", "bounce-partition-n", "N", RL_SETTING_UINT32, FIELD(bounce_partition_n), 0, 4096,
     RL_SETTING_POW2, 0, "partition level of bounce passes under bounce-rays 0; 0 = partition-n / 4"},
    {"bounce_cell_factor", "bounce-cell-factor", "F", RL_SETTING_UINT32, FIELD(bounce_cell_factor), 0, 64, 0, 0,
     "bounces gather on cells F times larger, interpolated; 1 = every cell, 0 = 4 (2 under bounce-rays 0)"},
    {"bounce_rays", "bounce-rays", "N", RL_SETTING_UINT32, FIELD(bounce_rays), 0, 1048576, 0, 256,
     "bounce passes: rays per cell over its hemisphere, first hit; 0 = the method's transfer per lit polygon"},
    {"descend", "descend", "0|1", RL_SETTING_UINT32, FIELD(descend), 0, 1, 0, 1,
     "1: Lambert's formula times sampled light for diffuse and small emitters"},
    {"zero_culling", "zero-culling", "0|1", RL_SETTING_UINT32, FIELD(zero_culling), 0, 1, 0, 1,
     "1: cull light field directions and cells by zero radiance"},
    {"anchor_stride", "anchor-stride", "S", RL_SETTING_UINT32, FIELD(anchor_stride), 0, 64, 0, 0,
     "light fields' cells that see all of one: interpolate between points S cells apart; 0 = from distance, 1 = none"},
    {"seed", "seed", "S", RL_SETTING_UINT64, FIELD(seed), 0, JSON_EXACT_MAX, RL_SETTING_TEXT_BOUNDS, 1,
     "random seed"},
    {"target_error", "target-error", "E", RL_SETTING_REAL, FIELD(target_error), 0, 1, RL_SETTING_LO_OPEN, 0.05,
     "adaptive: refine while a cell's estimated error exceeds E of its value"},
};

#define NSETTINGS (sizeof settings / sizeof settings[0])

size_t rl_sampling_setting_count(void)
{
    return NSETTINGS;
}

const rl_setting_info *rl_sampling_setting(size_t k)
{
    return k < NSETTINGS ? &settings[k] : NULL;
}

size_t rl_sampling_setting_find(const char *key)
{
    size_t k = 0;
    while (key && k < NSETTINGS && strcmp(settings[k].key, key) != 0)
        k++;
    return key ? k : NSETTINGS;
}

const char *rl_sampling_setting_rule(size_t k, char *buf, size_t size)
{
    if (!buf || size == 0)
        return "";
    buf[0] = '\0';
    if (k >= NSETTINGS)
        return buf;
    const rl_setting_info *s = &settings[k];
    switch (s->type) {
    case RL_SETTING_METHOD: {
        size_t used = 0;
        for (int m = (int)s->lo; m <= (int)s->hi && used < size; m++) {
            const char *sep = m == (int)s->lo ? "" : m == (int)s->hi ? " or " : ", ";
            int n = snprintf(buf + used, size - used, "%s%s", sep, rl_method_name((rl_method)m));
            used += n > 0 ? (size_t)n : 0;
        }
        break;
    }
    case RL_SETTING_UINT32:
    case RL_SETTING_UINT64:
        snprintf(buf, size, "%s in %.0f..%.0f", (s->flags & RL_SETTING_POW2) ? "a power of two" : "an integer", s->lo,
                 s->hi);
        break;
    case RL_SETTING_REAL:
        snprintf(buf, size, "in %c%g, %g]", (s->flags & RL_SETTING_LO_OPEN) ? '(' : '[', s->lo, s->hi);
        break;
    }
    return buf;
}

int rl_sampling_setting_allows(size_t k, double v, int text)
{
    if (k >= NSETTINGS || !isfinite(v))
        return 0;
    const rl_setting_info *s = &settings[k];
    int bounded = text || !(s->flags & RL_SETTING_TEXT_BOUNDS);
    if (s->type == RL_SETTING_REAL)
        return ((s->flags & RL_SETTING_LO_OPEN) ? v > s->lo : v >= s->lo) && v <= s->hi;
    if (v != floor(v) || v < 0 || (bounded && (v < s->lo || v > s->hi)))
        return 0;
    if (s->flags & RL_SETTING_POW2) {
        uint64_t u = (uint64_t)v;
        return (u & (u - 1)) == 0;
    }
    return 1;
}

int rl_sampling_get(const rl_sampling *x, size_t k, double *value)
{
    if (!x || !value || k >= NSETTINGS)
        return 0;
    const char *at = (const char *)x + settings[k].offset;
    switch (settings[k].type) {
    case RL_SETTING_METHOD: *value = (double)*(const rl_method *)(const void *)at; break;
    case RL_SETTING_UINT32: *value = (double)*(const uint32_t *)(const void *)at; break;
    case RL_SETTING_UINT64: *value = (double)*(const uint64_t *)(const void *)at; break;
    case RL_SETTING_REAL: *value = *(const double *)(const void *)at; break;
    }
    return 1;
}

int rl_sampling_set(rl_sampling *x, size_t k, double value)
{
    if (!x || k >= NSETTINGS)
        return 0;
    char *at = (char *)x + settings[k].offset;
    rl_setting_type t = settings[k].type;
    if (t != RL_SETTING_REAL &&
        !(value >= 0 && value == floor(value) && value <= (t == RL_SETTING_UINT64 ? 18446744073709549568.0 : 4294967295.0)))
        return 0;
    switch (t) {
    case RL_SETTING_METHOD: *(rl_method *)(void *)at = (rl_method)(uint32_t)value; break;
    case RL_SETTING_UINT32: *(uint32_t *)(void *)at = (uint32_t)value; break;
    case RL_SETTING_UINT64: *(uint64_t *)(void *)at = (uint64_t)value; break;
    case RL_SETTING_REAL: *(double *)(void *)at = value; break;
    }
    return 1;
}

void rl_sampling_default(rl_sampling *s)
{
    memset(s, 0, sizeof *s);
    for (size_t k = 0; k < NSETTINGS; k++)
        rl_sampling_set(s, k, settings[k].default_value);
}
