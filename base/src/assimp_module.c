/*
 * assimp_module.c - the mesh module libilfkit_assimp.so (mesh_module.h):
 * assimp's C API and the copy of what it read into a plain polygon soup
 * (ilf/mesh.h). The only file of ilfkit that includes assimp
 * (test_assimp_contained); base/src/mesh_import.c makes every check before
 * it and loads this module on the first import (ilf/module.h).
 *
 * Materials and axes (ilf/mesh.h): assimp 5.2 drops glTF's
 * KHR_materials_emissive_strength, so the strengths mesh_import.c read
 * from the file's JSON come in and multiply assimp's emissive colour (glTF
 * material k is assimp's material k: its importer keeps their order and
 * appends its default material). assimp's 3DS reader turns the file's Z-up
 * frame to Y-up by its root node's transform; the vertices are turned back.
 * An FBX file's lengths are scaled to metres by its UnitScaleFactor, which
 * assimp reports but does not apply.
 *
 * Every file assimp opens, the mesh itself and every file it names (an
 * OBJ's mtllib, a glTF buffer's uri), goes through an aiFileIO of this
 * file's own that opens without blocking (ilf/file_kind.h) and refuses
 * anything but a regular file, and a refusal fails the import, where assimp
 * would have gone on without the material library or waited on a FIFO.
 *
 * Invariants: an imported soup satisfies ilf/mesh.h's invariants, or
 * nothing is returned and everything allocated on the way is freed; the
 * module holds no state, so concurrent imports share nothing of it.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* fseeko(); the build defines it too */
#endif

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "ilf/file_kind.h"
#include "ilf/mesh.h"
#include "mesh_module.h"

/* ------------------------------------------------------------ files */

/* What the files assimp opened through mesh_io_open() came to: the first refusal, if any. */
typedef struct mesh_io {
    char refused[512];
    int nomem; /* an open failed for want of memory: the import fails as ILF_MESH_ERR_NOMEM */
} mesh_io;

static size_t mesh_io_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
    return fread(buf, size, count, (FILE *)f->UserData);
}

static size_t mesh_io_write(struct aiFile *f, const char *buf, size_t size, size_t count)
{
    (void)f, (void)buf, (void)size, (void)count;
    return 0; /* assimp only reads here */
}

static size_t mesh_io_tell(struct aiFile *f)
{
    long at = ftell((FILE *)f->UserData);
    return at < 0 ? 0 : (size_t)at;
}

static size_t mesh_io_size(struct aiFile *f)
{
    struct stat sb;
    return fstat(fileno((FILE *)f->UserData), &sb) == 0 ? (size_t)sb.st_size : 0;
}

static enum aiReturn mesh_io_seek(struct aiFile *f, size_t offset, enum aiOrigin origin)
{
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    /* assimp passes a backward offset as a size_t that wrapped: off_t takes it back */
    return fseeko((FILE *)f->UserData, (off_t)offset, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
}

static void mesh_io_flush(struct aiFile *f) { (void)f; }

/* aiFileIO's open: a regular file only, read-only; any other kind is recorded as the import's failure. */
static struct aiFile *mesh_io_open(struct aiFileIO *io, const char *path, const char *mode)
{
    if (mode == NULL || mode[0] != 'r')
        return NULL;
    mesh_io *m = (mesh_io *)io->UserData;
    char why[160];
    int fd;
    int err = ilf_input_open(path, &fd, why, sizeof why);
    if (err != 0) {
        if ((err == EISDIR || err == EINVAL) && m->refused[0] == '\0')
            snprintf(m->refused, sizeof m->refused, "'%s' %s", path, why);
        return NULL;
    }
    FILE *fp = fdopen(fd, "rb");
    struct aiFile *f = fp != NULL ? calloc(1, sizeof *f) : NULL;
    if (f == NULL) {
        if (fp != NULL)
            fclose(fp);
        else
            close(fd);
        m->nomem = 1;
        return NULL;
    }
    f->ReadProc = mesh_io_read;
    f->WriteProc = mesh_io_write;
    f->TellProc = mesh_io_tell;
    f->FileSizeProc = mesh_io_size;
    f->SeekProc = mesh_io_seek;
    f->FlushProc = mesh_io_flush;
    f->UserData = (aiUserData)fp;
    return f;
}

static void mesh_io_close(struct aiFileIO *io, struct aiFile *f)
{
    (void)io;
    if (f != NULL) {
        fclose((FILE *)f->UserData);
        free(f);
    }
}

/* ------------------------------------------------------------ the soup */

/* Copies material m's name (or "" for assimp's stand-in and unnamed ones) and colours into out, its
 * emissive colour times strength (the file's own factor, 1 for most formats). */
static void copy_material(const struct aiMaterial *m, double strength, ilf_mesh_material *out)
{
    struct aiString name;
    struct aiColor4D c;
    if (aiGetMaterialString(m, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && name.length > 0 &&
        strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) != 0)
        snprintf(out->name, sizeof out->name, "%s", name.data);
    if ((out->has_diffuse = aiGetMaterialColor(m, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS))
        out->diffuse[0] = c.r, out->diffuse[1] = c.g, out->diffuse[2] = c.b;
    if ((out->has_emissive = aiGetMaterialColor(m, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS))
        out->emissive[0] = c.r * strength, out->emissive[1] = c.g * strength, out->emissive[2] = c.b * strength;
}

/* @return whether path's extension is ext (with its dot, any case). */
static int has_extension(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.');
    return dot && strcasecmp(dot, ext) == 0;
}

/* @return the number sc's metadata holds under key (an int32, float or double), or fallback. */
static double metadata_number(const struct aiScene *sc, const char *key, double fallback)
{
    const struct aiMetadata *md = sc->mMetaData;
    for (unsigned k = 0; md && k < md->mNumProperties; k++) {
        const void *v = md->mValues[k].mData;
        if (!v || strcmp(md->mKeys[k].data, key) != 0)
            continue;
        switch (md->mValues[k].mType) {
        case AI_INT32: return *(const int32_t *)v;
        case AI_FLOAT: return *(const float *)v;
        case AI_DOUBLE: return *(const double *)v;
        default: return fallback;
        }
    }
    return fallback;
}

/* @return the up axis that sc's file declares (ilf/mesh.h): glTF's +Y, FBX's GlobalSettings, 3DS's +Z. */
static ilf_mesh_up declared_up(const char *path, const struct aiScene *sc)
{
    if (has_extension(path, ".gltf") || has_extension(path, ".glb"))
        return ILF_MESH_UP_Y;
    if (has_extension(path, ".3ds"))
        return ILF_MESH_UP_Z;
    if (!has_extension(path, ".fbx"))
        return ILF_MESH_UP_UNKNOWN;
    double axis = metadata_number(sc, "UpAxis", -1), sign = metadata_number(sc, "UpAxisSign", 0);
    return sign == 1 && axis == 1 ? ILF_MESH_UP_Y : sign == 1 && axis == 2 ? ILF_MESH_UP_Z : ILF_MESH_UP_UNKNOWN;
}

/* @return metres per unit of sc's file: an FBX file's GlobalSettings UnitScaleFactor (centimetres per unit,
 * which assimp 5.2 reports but does not apply) over 100; 1 for other formats and for a factor that is not
 * a positive finite number. */
static double metres_per_unit(const char *path, const struct aiScene *sc)
{
    double cm = has_extension(path, ".fbx") ? metadata_number(sc, "UnitScaleFactor", 100) : 100;
    return cm > 0 && isfinite(cm) ? cm / 100 : 1;
}

/* Copies what assimp read into a new soup. @return ILF_MESH_OK and *out, ILF_MESH_ERR_INPUT (an index out of
 * range, or more than SIZE_MAX of something) with why, or ILF_MESH_ERR_NOMEM. */
static ilf_mesh_status soup_new(const char *path, const struct aiScene *sc, const double *strength, size_t nstrength,
                                ilf_mesh **out, char *why, size_t size)
{
    ilf_mesh *m = calloc(1, sizeof *m);
    if (!m)
        return ILF_MESH_ERR_NOMEM;
    for (unsigned mi = 0; mi < sc->mNumMeshes; mi++) {
        const struct aiMesh *a = sc->mMeshes[mi];
        m->nvertices += a->mNumVertices;
        m->nfaces += a->mNumFaces;
        for (unsigned fi = 0; fi < a->mNumFaces; fi++)
            m->nindices += a->mFaces[fi].mNumIndices;
    }
    m->nmaterials = sc->mNumMaterials;
    m->vertices = malloc((m->nvertices ? m->nvertices : 1) * sizeof *m->vertices);
    m->faces = malloc((m->nfaces ? m->nfaces : 1) * sizeof *m->faces);
    m->indices = malloc((m->nindices ? m->nindices : 1) * sizeof *m->indices);
    m->materials = calloc(m->nmaterials ? m->nmaterials : 1, sizeof *m->materials);
    if (!m->vertices || !m->faces || !m->indices || !m->materials) {
        ilf_mesh_destroy(m);
        return ILF_MESH_ERR_NOMEM;
    }
    for (size_t k = 0; k < m->nmaterials; k++)
        copy_material(sc->mMaterials[k], k < nstrength ? strength[k] : 1.0, &m->materials[k]);
    m->up = declared_up(path, sc);
    int unturn = has_extension(path, ".3ds"); /* assimp's (x, y, z) is the file's (x, -z, y) */
    double unit = metres_per_unit(path, sc);
    size_t v0 = 0, nf = 0, ni = 0;
    for (unsigned mi = 0; mi < sc->mNumMeshes; mi++) {
        const struct aiMesh *a = sc->mMeshes[mi];
        for (unsigned k = 0; k < a->mNumVertices; k++) {
            m->vertices[v0 + k][0] = unit * a->mVertices[k].x;
            m->vertices[v0 + k][1] = unit * (unturn ? -a->mVertices[k].z : a->mVertices[k].y);
            m->vertices[v0 + k][2] = unit * (unturn ? a->mVertices[k].y : a->mVertices[k].z);
        }
        uint32_t material = a->mMaterialIndex < sc->mNumMaterials ? a->mMaterialIndex : ILF_MESH_NO_MATERIAL;
        for (unsigned fi = 0; fi < a->mNumFaces; fi++, nf++) {
            const struct aiFace *f = &a->mFaces[fi];
            m->faces[nf] = (ilf_mesh_face){mi, fi, material, f->mNumIndices, ni};
            for (unsigned k = 0; k < f->mNumIndices; k++, ni++) {
                if (f->mIndices[k] >= a->mNumVertices) { /* assimp's validation refuses these; kept as a guard */
                    snprintf(why, size, "cannot read '%s': mesh %u face %u refers to vertex %u of %u", path, mi, fi,
                             f->mIndices[k], a->mNumVertices);
                    ilf_mesh_destroy(m);
                    return ILF_MESH_ERR_INPUT;
                }
                m->indices[ni] = (uint32_t)(v0 + f->mIndices[k]);
            }
        }
        v0 += a->mNumVertices;
    }
    *out = m;
    return ILF_MESH_OK;
}

/* ------------------------------------------------------------ reading */

/* mesh_module.h's import. */
static ilf_mesh_status import(const char *path, const double *strength, size_t nstrength, ilf_mesh **out, char *why,
                              size_t why_size)
{
    mesh_io files = {"", 0};
    struct aiFileIO io = {mesh_io_open, mesh_io_close, (aiUserData)&files};
    const struct aiScene *sc =
        aiImportFileEx(path, aiProcess_PreTransformVertices | aiProcess_ValidateDataStructure, &io);
    if (!sc || files.refused[0] != '\0' || files.nomem) {
        ilf_mesh_status failure = files.nomem && files.refused[0] == '\0' ? ILF_MESH_ERR_NOMEM : ILF_MESH_ERR_INPUT;
        if (failure == ILF_MESH_ERR_NOMEM)
            snprintf(why, why_size, "'%s': out of memory", path);
        else if (files.refused[0] != '\0')
            snprintf(why, why_size, "cannot read '%s': %s", path, files.refused);
        else
            snprintf(why, why_size, "cannot read '%s': %s", path, aiGetErrorString());
        aiReleaseImport(sc);
        return failure;
    }
    ilf_mesh_status st = ILF_MESH_OK;
    if (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE) {
        snprintf(why, why_size, "'%s' holds no complete mesh", path);
        st = ILF_MESH_ERR_INPUT;
    } else {
        st = soup_new(path, sc, strength, nstrength, out, why, why_size);
        if (st == ILF_MESH_ERR_NOMEM)
            snprintf(why, why_size, "'%s': out of memory", path);
    }
    aiReleaseImport(sc);
    return st;
}

/* ------------------------------------------------------------ the table */

static const ilf__mesh_module table = {ILF__MESH_MODULE_VERSION, import};

/* @return the module's table (mesh_module.h); the one name this module exports. */
__attribute__((visibility("default"))) const ilf__mesh_module *ilfkit_mesh_module(void);

const ilf__mesh_module *ilfkit_mesh_module(void)
{
    return &table;
}
