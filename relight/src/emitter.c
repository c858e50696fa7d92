/*
 * emitter.c - setting up emitters and reading the radiance they send.
 *
 * A constant polygon takes a frame on its first edge; a bounce emitter takes
 * the receiving map's own frame, so that frame coordinates index its cells;
 * a light field takes the slab's (u, v) edges, normalised, so that frame
 * coordinates divided by the edge lengths are the slab's positions. The
 * radiance read here is the general path: a light field interpolated in
 * direction through the slab's own rotation. Leaves that nest in the slab's
 * partition read it faster through rl__leaf_radiance_mix() (leaf.c).
 */
#include <string.h>

#include <lfio/partition.h>

#include "method.h"

/* Fills the 2D polygon, its edge half-planes and area of e from its world vertices and frame. */
static void emitter_finish(rl_emitter *e)
{
    for (uint32_t i = 0; i < e->nverts; i++)
        e->poly2[i] = frame_project(&e->frame, e->verts[i]);
    for (uint32_t i = 0, j = e->nverts - 1; i < e->nverts; j = i++)
        e->edge[i] = edge_halfplane(e->poly2[j], e->poly2[i]);
    e->area = rl__polygon_area2(e->poly2, e->nverts);
}

void rl__emitter_from_polygon(const rl_scene *scene, uint32_t k, const rl_map *map, rl_emitter *e)
{
    const rl_polygon *pg = &scene->polygons[k];
    memset(e, 0, sizeof *e);
    e->kind = map ? EM_MAP : EM_CONST;
    e->polygon = (int32_t)k;
    e->map = map;
    e->nverts = pg->count;
    for (uint32_t i = 0; i < pg->count; i++)
        e->verts[i] = v3_load(scene->vertices[pg->first + i]);
    if (map) {
        e->frame = map->frame; /* so that frame coordinates index the map's cells */
    } else {
        e->frame.origin = e->verts[0];
        e->frame.n = v3_load(pg->normal);
        e->frame.e1 = v3_norm(v3_sub(e->verts[1], e->verts[0]));
        e->frame.e2 = v3_cross(e->frame.n, e->frame.e1);
    }
    memcpy(e->emission, scene->materials[pg->material].emission, sizeof e->emission);
    emitter_finish(e);
}

void rl__emitter_from_lightfield(const rl_lightfield *lf, rl_emitter *e)
{
    memset(e, 0, sizeof *e);
    e->kind = EM_SLAB;
    e->polygon = -1;
    e->lf = lf;
    v3 o = v3_load(lf->origin), u = v3_load(lf->u), v = v3_load(lf->v);
    e->len_u = v3_len(u);
    e->len_v = v3_len(v);
    e->frame.origin = o;
    e->frame.e1 = v3_scale(u, 1.0 / e->len_u);
    e->frame.e2 = v3_scale(v, 1.0 / e->len_v);
    e->frame.n = v3_cross(e->frame.e1, e->frame.e2);
    e->nverts = 4;
    e->verts[0] = o;
    e->verts[1] = v3_add(o, u);
    e->verts[2] = v3_add(v3_add(o, u), v);
    e->verts[3] = v3_add(o, v);
    emitter_finish(e);
}

void rl__emitter_radiance_at(const rl_emitter *e, v2 q, v3 d, double out[3])
{
    switch (e->kind) {
    case EM_CONST:
        for (int c = 0; c < 3; c++)
            out[c] = e->emission[c];
        return;
    case EM_MAP:
        rl__map_radiance(e->map, rl__map_cell_at(e->map, q), out);
        return;
    case EM_SLAB: {
        float rgb[3] = {0, 0, 0};
        /* back to the slab's own frame: the transform's rotation, transposed */
        const double (*r)[3] = e->lf->rot;
        double ds[3] = {r[0][0] * d.x + r[1][0] * d.y + r[2][0] * d.z, r[0][1] * d.x + r[1][1] * d.y + r[2][1] * d.z,
                        r[0][2] * d.x + r[1][2] * d.y + r[2][2] * d.z};
        lfio_slab_radiance_interp(e->lf->slab, q.x / e->len_u, q.y / e->len_v, ds, rgb);
        for (int c = 0; c < 3; c++)
            out[c] = rgb[c];
        return;
    }
    }
}

int rl__emitter_node_dark(const rl_emitter *e, uint32_t lv, uint64_t id)
{
    const lfio_slab *s = e->lf->slab;
    uint32_t n = lfio_slab_get_desc(s)->n;
    while (lv > n) { /* finer than the slab: its ancestor at the slab's level */
        if (lv % 2 || !lfio_part_parent(lv, id, &id))
            return 0;
        lv /= 2;
    }
    if (lfio_slab_mask_test(s, lv, id))
        return 0;
    uint64_t nb[3];
    if (!lfio_part_neighbours(lv, id, nb))
        return 0;
    for (int k = 0; k < 3; k++)
        if (nb[k] < lfio_part_hemi_count(lv) && lfio_slab_mask_test(s, lv, nb[k]))
            return 0;
    return 1;
}
