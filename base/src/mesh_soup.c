/*
 * mesh_soup.c - ilf/mesh.h's ilf_mesh_destroy: freeing a soup. Apart from
 * the importer (mesh_import.c) so that the mesh module, which builds soups
 * and frees them on failure, and ilfread, whose callers free them, share it
 * through base without the module linking the importer.
 *
 * Invariant: every array of a soup is its own malloc() block.
 */
#include <stdlib.h>

#include "ilf/mesh.h"

void ilf_mesh_destroy(ilf_mesh *m)
{
    if (!m)
        return;
    free(m->vertices);
    free(m->faces);
    free(m->indices);
    free(m->materials);
    free(m);
}
