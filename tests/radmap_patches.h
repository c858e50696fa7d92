/*
 * radmap_patches.h - the radiance-map patches of the lfio tests
 * (test_radmap.c, test_radmap_mpi.c): square polygons with deterministic
 * cell values, and a field-by-field, bit-for-bit comparison. Include after
 * check.h.
 */
#ifndef ILF_TEST_RADMAP_PATCHES_H
#define ILF_TEST_RADMAP_PATCHES_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "lfio/radmap.h"

/* A patch and the arrays it borrows. */
struct test_patch {
    lfio_radmap_patch p;
    double vertices[4][3];
    uint32_t *ij;
    double *area, *centre;
    float *irradiance, *radiosity;
};

/*
 * Builds a square polygon of side `side` in the plane z = height facing +z,
 * gridded at cell_size, keeping only cells whose index sum is not divisible by
 * skip (skip 0: keep all; a huge grid with few cells also works). Values
 * are deterministic functions of the cell.
 */
static void make_patch(struct test_patch *t, const char *label, uint32_t polygon, double side, double height,
                       double cell_size, uint32_t skip)
{
    memset(t, 0, sizeof *t);
    lfio_radmap_patch *p = &t->p;
    const double corners[4][2] = {{0, 0}, {side, 0}, {side, side}, {0, side}};
    for (int v = 0; v < 4; v++) {
        t->vertices[v][0] = corners[v][0];
        t->vertices[v][1] = corners[v][1];
        t->vertices[v][2] = height;
    }
    p->label = label;
    p->polygon = polygon;
    p->nverts = 4;
    p->vertices = &t->vertices[0][0];
    p->origin[2] = height;
    p->e1[0] = 1, p->e2[1] = 1, p->normal[2] = 1;
    p->cell_size = cell_size;
    p->u0 = p->v0 = 0;
    p->nu = p->nv = (uint32_t)lround(side / cell_size);
    uint32_t total = p->nu * p->nv;
    t->ij = malloc(2 * (size_t)total * sizeof *t->ij);
    t->area = malloc((size_t)total * sizeof *t->area);
    t->centre = malloc(3 * (size_t)total * sizeof *t->centre);
    t->irradiance = malloc(3 * (size_t)total * sizeof *t->irradiance);
    t->radiosity = malloc(3 * (size_t)total * sizeof *t->radiosity);
    for (uint32_t j = 0; j < p->nv; j++)
        for (uint32_t i = 0; i < p->nu; i++) {
            if (skip && (i + j) % skip == 0)
                continue;
            uint32_t c = p->ncells++;
            t->ij[2 * c] = i, t->ij[2 * c + 1] = j;
            t->area[c] = cell_size * cell_size * (1.0 - 0.25 * ((i * 7 + j) % 3) / 2.0);
            t->centre[3 * c] = (i + 0.5) * cell_size, t->centre[3 * c + 1] = (j + 0.5) * cell_size;
            t->centre[3 * c + 2] = height;
            for (int k = 0; k < 3; k++) {
                t->irradiance[3 * c + k] = (float)(1.0 + 0.001 * c + 0.5 * k);
                t->radiosity[3 * c + k] = 0.5f * t->irradiance[3 * c + k];
            }
        }
    p->cell_ij = t->ij, p->cell_area = t->area, p->cell_centre = t->centre;
    p->irradiance = t->irradiance, p->radiosity = t->radiosity;
    p->albedo[0] = 0.5f, p->albedo[1] = 0.4f, p->albedo[2] = 0.3f;
    p->emission[0] = polygon == 0 ? 2.0f : 0.0f;
}

/* Releases the arrays of t. */
static void free_patch(struct test_patch *t)
{
    free(t->ij);
    free(t->area);
    free(t->centre);
    free(t->irradiance);
    free(t->radiosity);
}

/* Checks that two patches are equal field by field, arrays bit for bit. */
static void check_patch_equal(const lfio_radmap_patch *a, const lfio_radmap_patch *b, const char *what)
{
    CHECK(strcmp(a->label, b->label) == 0, "%s: label '%s' vs '%s'", what, a->label, b->label);
    CHECK(a->polygon == b->polygon && a->nverts == b->nverts && a->nu == b->nu && a->nv == b->nv
              && a->ncells == b->ncells, "%s: counts", what);
    CHECK(memcmp(a->origin, b->origin, sizeof a->origin) == 0 && memcmp(a->e1, b->e1, sizeof a->e1) == 0
              && memcmp(a->e2, b->e2, sizeof a->e2) == 0 && memcmp(a->normal, b->normal, sizeof a->normal) == 0,
          "%s: frame", what);
    CHECK(a->cell_size == b->cell_size && a->u0 == b->u0 && a->v0 == b->v0, "%s: grid", what);
    CHECK(memcmp(a->albedo, b->albedo, sizeof a->albedo) == 0 && memcmp(a->emission, b->emission, sizeof a->emission) == 0,
          "%s: material", what);
    CHECK(memcmp(a->vertices, b->vertices, 3 * sizeof(double) * a->nverts) == 0, "%s: vertices", what);
    if (a->ncells != b->ncells || a->ncells == 0)
        return;
    const size_t n = a->ncells;
    CHECK(memcmp(a->cell_ij, b->cell_ij, 2 * n * sizeof(uint32_t)) == 0, "%s: cell_ij", what);
    CHECK(memcmp(a->cell_area, b->cell_area, n * sizeof(double)) == 0, "%s: cell_area", what);
    CHECK(memcmp(a->cell_centre, b->cell_centre, 3 * n * sizeof(double)) == 0, "%s: cell_centre", what);
    CHECK(memcmp(a->irradiance, b->irradiance, 3 * n * sizeof(float)) == 0, "%s: irradiance", what);
    CHECK(memcmp(a->radiosity, b->radiosity, 3 * n * sizeof(float)) == 0, "%s: radiosity", what);
}

#endif /* ILF_TEST_RADMAP_PATCHES_H */
