/*
 * falsecolor.c - false-colour images with a legend (see falsecolor.h): a
 * colour ramp, a round top for the scale, and a 5x7 bitmap font for the
 * legend's numbers, so that no font library is needed.
 *
 * Invariants: the image keeps the camera's pixels one for one (the legend is
 * added to the right, and rows of background below when the legend needs
 * more height than the view has); every value written is in [0, 1].
 */
#include "falsecolor.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


/* ------------------------------------------------------------ colours */

/* The ramp's stops (sRGB): dark blue, blue, cyan, green, yellow, orange, red, evenly spaced over [0, 1],
 * hues apart enough to read a level off at a glance. */
static const float ramp[][3] = {{0.00f, 0.00f, 0.35f}, {0.00f, 0.25f, 1.00f}, {0.00f, 0.80f, 0.90f},
                                {0.10f, 0.80f, 0.10f}, {0.95f, 0.95f, 0.00f}, {1.00f, 0.50f, 0.00f},
                                {0.90f, 0.00f, 0.00f}};
#define RAMP_STOPS (sizeof ramp / sizeof ramp[0])
static const float over[3] = {1.0f, 0.0f, 1.0f};       /* above the top */
static const float no_value[3] = {0.15f, 0.15f, 0.15f}; /* no receiving surface */
static const float background[3] = {0.0f, 0.0f, 0.0f};  /* the legend's ground */
static const float ink[3] = {1.0f, 1.0f, 1.0f};         /* its text and ticks */

void falsecolor_colour(double v, double top, float rgb[3])
{
    const float *c = no_value;
    float mixed[3];
    if (v >= 0 && v > top) {
        c = over;
    } else if (v >= 0) {
        double x = top > 0 ? v / top * (double)(RAMP_STOPS - 1) : 0.0;
        size_t k = x >= (double)(RAMP_STOPS - 1) ? RAMP_STOPS - 2 : (size_t)x;
        float f = (float)(x - (double)k);
        for (int i = 0; i < 3; i++)
            mixed[i] = ramp[k][i] + f * (ramp[k + 1][i] - ramp[k][i]);
        c = mixed;
    }
    memcpy(rgb, c, 3 * sizeof *rgb);
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

double falsecolor_auto_top(const float *v, size_t count)
{
    float *lit = malloc((count ? count : 1) * sizeof *lit);
    size_t n = 0;
    if (lit == NULL)
        return -1.0;
    for (size_t k = 0; k < count; k++)
        if (v[k] > 0)
            lit[n++] = v[k];
    double p = 0.0;
    if (n > 0) {
        qsort(lit, n, sizeof *lit, compare_floats);
        size_t rank = (size_t)ceil(0.99 * (double)n);
        p = lit[(rank > 0 ? rank : 1) - 1];
    }
    free(lit);
    if (!(p > 0))
        return 1.0;
    /* the smallest of 1, 2, 5 times 10^k at or above p */
    double decade = pow(10.0, floor(log10(p)));
    static const double steps[] = {1.0, 2.0, 5.0, 10.0};
    for (size_t k = 0; k < sizeof steps / sizeof steps[0]; k++)
        if (steps[k] * decade >= p * (1.0 - 1e-12))
            return steps[k] * decade;
    return 10.0 * decade;
}

/* ------------------------------------------------------------ font */

/* 5x7 glyphs, one byte a row from the top, bit 4 the leftmost column. */
typedef struct glyph {
    char c;
    unsigned char rows[7];
} glyph;

static const glyph font[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}}, {'l', {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'u', {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D}}, {'x', {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}},
    {'^', {0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00}}, {'/', {0x01, 0x02, 0x02, 0x04, 0x08, 0x08, 0x10}},
};

#define GLYPH_W 5
#define GLYPH_H 7
#define ADVANCE 6 /* a glyph and a column of space */
#define LABEL_CHARS 7

/* @return the glyph of c, or NULL (drawn blank). */
static const glyph *glyph_of(char c)
{
    for (size_t k = 0; k < sizeof font / sizeof font[0]; k++)
        if (font[k].c == c)
            return &font[k];
    return NULL;
}

/* An image being drawn: [height][width][3]. */
typedef struct canvas {
    float *px;
    int width, height;
} canvas;

static void put(const canvas *cv, int x, int y, const float rgb[3])
{
    if (x >= 0 && y >= 0 && x < cv->width && y < cv->height)
        memcpy(cv->px + 3 * ((size_t)y * (size_t)cv->width + (size_t)x), rgb, 3 * sizeof *rgb);
}

/* Draws text with its top-left corner at (x, y), each font pixel as a zoom x zoom square. */
static void draw_text(const canvas *cv, int x, int y, const char *text, int zoom)
{
    for (size_t k = 0; text[k] != '\0' && k < LABEL_CHARS; k++) {
        const glyph *g = glyph_of(text[k]);
        for (int r = 0; g != NULL && r < GLYPH_H * zoom; r++)
            for (int c = 0; c < GLYPH_W * zoom; c++)
                if (g->rows[r / zoom] & (0x10 >> (c / zoom)))
                    put(cv, x + (int)k * ADVANCE * zoom + c, y + r, ink);
    }
}

/* ------------------------------------------------------------ legend */

/* The legend's layout, in font pixels times zoom: a margin, the bar, a tick, a gap, the labels, a margin. */
#define MARGIN 6
#define BAR_W 14
#define TICK_W 3
#define GAP 3

/* @return the legend's width at zoom. */
static int legend_width(int zoom)
{
    return (MARGIN + BAR_W + TICK_W + GAP + LABEL_CHARS * ADVANCE + MARGIN) * zoom;
}

/* @return the height the legend needs at zoom: the unit, then a label's height and a gap per tick. */
static int legend_height(int zoom)
{
    return (MARGIN + GLYPH_H + MARGIN + (FALSECOLOR_STEPS + 1) * (GLYPH_H + 4) + MARGIN) * zoom;
}

/* Draws the legend into cv from column x0: the unit at the top, the bar from top (up) to 0 (down), a tick and
 * a label at each step. */
static void draw_legend(const canvas *cv, int x0, double top, const char *unit, int zoom)
{
    int bar_x = x0 + MARGIN * zoom, y0 = (MARGIN + GLYPH_H + MARGIN) * zoom + GLYPH_H * zoom / 2;
    int y1 = cv->height - MARGIN * zoom - GLYPH_H * zoom / 2 - 1;
    draw_text(cv, bar_x, MARGIN * zoom, unit, zoom);
    for (int y = y0; y <= y1; y++) {
        float rgb[3];
        falsecolor_colour(top * (double)(y1 - y) / (double)(y1 > y0 ? y1 - y0 : 1), top, rgb);
        for (int x = 0; x < BAR_W * zoom; x++)
            put(cv, bar_x + x, y, rgb);
    }
    for (int k = 0; k <= FALSECOLOR_STEPS; k++) {
        int y = y1 - (int)lround((double)(y1 - y0) * k / FALSECOLOR_STEPS);
        for (int x = 0; x < TICK_W * zoom; x++)
            for (int t = 0; t < zoom; t++)
                put(cv, bar_x + BAR_W * zoom + x, y + t, ink);
        char label[32];
        snprintf(label, sizeof label, "%.4g", top * k / FALSECOLOR_STEPS);
        draw_text(cv, bar_x + (BAR_W + TICK_W + GAP) * zoom, y - GLYPH_H * zoom / 2, label, zoom);
    }
}

float *falsecolor_image(const float *values, int width, int height, double top, const char *unit, int *out_width,
                        int *out_height)
{
    /* the font doubles on views large enough for it to stay a small part of the image */
    int zoom = height >= 4 * legend_height(1) ? 2 : 1;
    int w = width + legend_width(zoom), h = height > legend_height(zoom) ? height : legend_height(zoom);
    float *px = malloc((size_t)w * (size_t)h * 3 * sizeof *px);
    if (px == NULL)
        return NULL;
    canvas cv = {px, w, h};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float rgb[3];
            if (x < width && y < height)
                falsecolor_colour(values[(size_t)y * (size_t)width + (size_t)x], top, rgb);
            put(&cv, x, y, x < width && y < height ? rgb : background);
        }
    draw_legend(&cv, width, top, unit, zoom);
    *out_width = w;
    *out_height = h;
    return px;
}
