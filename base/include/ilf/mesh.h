/*
 * ilf/mesh.h - the one mesh importer of ilfkit: scene meshes (relight) and
 * capture's proxies read mesh files through it, with the same formats and the
 * same pre-checks. It is the only code that reads with assimp (a wall test
 * checks it); what it returns is a plain polygon soup that each caller turns
 * into its own objects (scene polygons, proxy rectangles).
 *
 * assimp is loaded lazily: the pre-checks run without it, and the first
 * import that passes them loads the mesh module libilfkit_assimp.so (the
 * only file of ilfkit that includes assimp) through base's module loader
 * (ilf/module.h: $ILFKIT_MESH_MODULE, a full path, pins it; otherwise beside
 * the program, beside the shared library holding this code, the install
 * location), once, thread-safely; programs that import no mesh never map
 * assimp. If the module cannot be loaded, every import past the pre-checks
 * fails with ILF_MESH_ERR_INPUT naming the mesh and every module path tried.
 *
 * Formats: OBJ, PLY, glTF, GLB, STL, FBX and 3DS, chosen by the file's
 * extension (any case). Each is in the hostile-input corpus, and each reader
 * either checks its counts against the file or is checked first: PLY files
 * by plycheck.c (declared counts against the bytes there), glTF and GLB files
 * by their header, chunk lengths and accessor types. Others of assimp's
 * readers (OFF, Collada, DirectX among them) allocate whatever a header's
 * count claims, gigabytes for a few bytes, so they are refused.
 *
 * Invariants of an imported mesh: vertices are finite as assimp read them
 * (the caller checks finiteness with its own message); every index is below
 * nvertices; faces keep assimp's order and numbering, points and lines
 * included (count 1 or 2), so messages can name a face as the file's own
 * readers count it; a face's material is an index into materials or
 * ILF_MESH_NO_MATERIAL.
 *
 * Emission: a material's emissive is the file's emissive colour times the
 * format's own strength, in the file's units (the caller takes them as
 * W sr^-1 m^-2): OBJ's Ke as written; glTF's emissiveFactor times
 * KHR_materials_emissive_strength (read here from the JSON, as assimp 5.2
 * drops that extension); FBX's EmissiveColor times EmissiveFactor (assimp's
 * product); 3DS's emissive colour as assimp reports it. PLY and STL carry no
 * material.
 *
 * Lengths: vertices are in the file's units, taken as metres, except an FBX
 * file's, scaled to metres by its UnitScaleFactor (centimetres per unit).
 *
 * Axes: vertices are as the file stores them. assimp turns a 3DS file's
 * Z-up frame into Y-up; that turn is undone here. up records which axis the
 * file itself declares up (glTF: always +Y; FBX: its GlobalSettings UpAxis
 * when it is +Y or +Z; 3DS: +Z), or ILF_MESH_UP_UNKNOWN.
 */
#ifndef ILF_MESH_H
#define ILF_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "ilf/limits.h"

/* A face whose mesh names no material of the file. */
#define ILF_MESH_NO_MATERIAL UINT32_MAX

/* Bytes of a material name, its terminator included (assimp's own limit). */
#define ILF_MESH_NAME_BYTES 1024

/* The up axis a mesh file declares. */
typedef enum ilf_mesh_up { ILF_MESH_UP_UNKNOWN = 0, ILF_MESH_UP_Y, ILF_MESH_UP_Z } ilf_mesh_up;

typedef enum ilf_mesh_status {
    ILF_MESH_OK = 0,
    ILF_MESH_ERR_INPUT, /* the file is missing, unreadable, of a refused format, or broken */
    ILF_MESH_ERR_NOMEM  /* memory ran out */
} ilf_mesh_status;

typedef struct ilf_mesh_material {
    char name[ILF_MESH_NAME_BYTES]; /* "" when the file gives none (or only assimp's stand-in) */
    int has_diffuse, has_emissive;  /* whether the file gives these colours */
    double diffuse[3], emissive[3]; /* RGB, as the file gives them; emissive times the format's strength */
} ilf_mesh_material;

typedef struct ilf_mesh_face {
    uint32_t mesh;     /* which of the file's meshes (assimp's numbering) */
    uint32_t face;     /* its number within that mesh */
    uint32_t material; /* index into materials, or ILF_MESH_NO_MATERIAL */
    uint32_t count;    /* vertices: 1 a point, 2 a line, 3 or more a polygon */
    size_t first;      /* its vertex indices are indices[first .. first + count) */
} ilf_mesh_face;

typedef struct ilf_mesh {
    size_t nvertices, nfaces, nindices, nmaterials;
    double (*vertices)[3];        /* [nvertices], all meshes' vertices placed in the file's frame, metres */
    ilf_mesh_face *faces;         /* [nfaces], over all meshes in order */
    uint32_t *indices;            /* [nindices], each < nvertices */
    ilf_mesh_material *materials; /* [nmaterials] */
    ilf_mesh_up up;               /* the up axis the file declares (see Axes above) */
} ilf_mesh;

/*
 * Imports the mesh file at path after every pre-check. On failure why
 * (why_size bytes) holds the problem, naming the file as given:
 * "cannot open 'PATH': No such file or directory", "'PATH' is not a regular
 * file", "cannot read 'PATH': the file is empty", "cannot read 'PATH': mesh
 * format not supported (...)", "cannot read 'PATH': <pre-check or assimp's
 * message>", "'PATH' holds no complete mesh", "cannot read 'PATH': mesh
 * support is not available (<each module path tried: why>)".
 * @return ILF_MESH_OK and *out (ilf_mesh_destroy it); else *out = NULL and why.
 */
ilf_mesh_status ilf_mesh_import(const char *path, ilf_mesh **out, char *why, size_t why_size);

/* Frees an imported mesh; NULL is a no-op. @return nothing. */
void ilf_mesh_destroy(ilf_mesh *m);

/* @return 1 if path's extension names an accepted format (any case), else 0. */
int ilf_mesh_format_supported(const char *path);

#endif /* ILF_MESH_H */
