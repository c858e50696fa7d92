/*
 * common.c - the engine's per-thread error message, method names and the
 * default sampling settings.
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "ilf/message.h"
#include "scene_internal.h"

static _Thread_local char errbuf[ILF_MESSAGE_BYTES];

const char *rl_errmsg(void)
{
    return errbuf;
}

rl_status rl__fail(rl_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ilf_message_vformat(errbuf, fmt, ap);
    va_end(ap);
    return status;
}

static const char *const method_names[] = {"culled", "naive", "area", "solidangle", "adaptive"};

const char *rl_method_name(rl_method m)
{
    return (unsigned)m < sizeof method_names / sizeof method_names[0] ? method_names[m] : "unknown";
}

int rl_method_parse(const char *name, rl_method *m)
{
    for (unsigned k = 0; name && k < sizeof method_names / sizeof method_names[0]; k++)
        if (strcmp(name, method_names[k]) == 0) {
            *m = (rl_method)k;
            return 1;
        }
    return 0;
}

void rl_sampling_default(rl_sampling *s)
{
    memset(s, 0, sizeof *s);
    s->method = RL_METHOD_CULLED;
    s->partition_n = 32;
    s->rays_per_solid_angle = 4;
    s->samples_per_cell = 128;
    s->bounces = 0;
    s->bounce_partition_n = 0;
    s->bounce_cell_factor = 0;
    s->seed = 1;
    s->descend = 1;
    s->zero_culling = 1;
    s->threads = 0;
    s->target_error = 0.05;
    s->time_budget = 0.0;
}
