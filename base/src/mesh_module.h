/*
 * mesh_module.h - the entry table between base/src/mesh_import.c, which
 * implements ilf/mesh.h's import with its pre-checks, and the mesh module
 * libilfkit_assimp.so (base/src/assimp_module.c), which mesh_import.c loads
 * through base's module loader (ilf/module.h) on the first import, so that
 * programs that never import a mesh (ilf info, a scene without "meshes") do
 * not map assimp and its dependencies.
 *
 * The module exports one C function, ILF__MESH_MODULE_ENTRY, returning a
 * static table whose first field is ILF__MESH_MODULE_VERSION. Any change to
 * this header or to ilf/mesh.h's ilf_mesh that changes the table, the soup's
 * layout or the functions' meaning must raise the version, so that a module
 * from another build is refused, not called.
 *
 * Division of work: mesh_import.c checks the file (kind, size, format, PLY
 * counts, glTF accessors and emissive strengths) without assimp; the module
 * only reads the checked file with assimp and copies what it read into a
 * soup. The module links base (for ilf/file_kind.h and ilf_mesh_destroy), a
 * private copy with hidden symbols, and assimp; it holds no state.
 */
#ifndef ILF_MESH_MODULE_H
#define ILF_MESH_MODULE_H

#include <stddef.h>

#include "ilf/mesh.h"

/* The table layout and meaning this build expects; raise on any change. */
#define ILF__MESH_MODULE_VERSION 1u

/* Name of the exported entry function (an ilf__mesh_module_entry_fn). */
#define ILF__MESH_MODULE_ENTRY "ilfkit_mesh_module"

/* What the module offers. */
typedef struct ilf__mesh_module {
    unsigned version; /* ILF__MESH_MODULE_VERSION of the module's build; first, in every version */

    /*
     * Reads path (a regular, non-empty file of an accepted format that
     * passed mesh_import.c's pre-checks) with assimp into a new soup, the
     * emissive colour of material k multiplied by strength[k] for k <
     * nstrength (a glTF file's KHR_materials_emissive_strength).
     * @return as ilf_mesh_import() after its checks: ILF_MESH_OK and *out; else *out untouched and why
     * (why_size > 0 bytes) naming path.
     */
    ilf_mesh_status (*import)(const char *path, const double *strength, size_t nstrength, ilf_mesh **out, char *why,
                              size_t why_size);
} ilf__mesh_module;

/* @return the module's static table (never NULL). */
typedef const ilf__mesh_module *(*ilf__mesh_module_entry_fn)(void);

#endif /* ILF_MESH_MODULE_H */
