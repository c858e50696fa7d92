/*
 * mesh_import.c - the one mesh importer (ilf/mesh.h): the checks made before
 * assimp reads a file, assimp's C API, and the copy of what it read into a
 * plain polygon soup. The only file of ilfkit that includes assimp
 * (test_assimp_contained); PLY files are checked by plycheck.c first.
 *
 * Checks, in order, each refusing with a message naming the file: the file
 * exists and is a regular, non-empty file (assimp reads uninitialised memory
 * on an empty glTF); its extension names an accepted format (ilf/mesh.h);
 * a PLY file's declared counts fit its size (plycheck.h: assimp trusts
 * them); a GLB file's header and chunk lengths fit its size, and a glTF
 * file's position and index accessors have the types glTF 2.0 requires
 * (assimp copies positions of any type as raw bytes into its vertices: a
 * position accessor of another type would load silently as garbage or
 * nothing), and every KHR_materials_emissive_strength is a number >= 0;
 * assimp reads it with its data-structure validation; the result is
 * complete.
 *
 * Materials and axes (ilf/mesh.h): assimp 5.2 drops glTF's
 * KHR_materials_emissive_strength, so the strengths are read from the JSON
 * the check parses anyway and multiply assimp's emissive colour (glTF
 * material k is assimp's material k: its importer keeps their order and
 * appends its default material). assimp's 3DS reader turns the file's Z-up
 * frame to Y-up by its root node's transform; the vertices are turned back.
 * An FBX file's lengths are scaled to metres by its UnitScaleFactor, which
 * assimp reports but does not apply.
 *
 * Every file is opened through ilf/file_kind.h, the mesh itself and every
 * file it names (an OBJ's mtllib, a glTF buffer's uri): assimp reads through
 * an aiFileIO of this file's own that opens without blocking and refuses
 * anything but a regular file, and a refusal fails the import, where assimp
 * would have gone on without the material library or waited on a FIFO.
 *
 * Invariants: an imported soup satisfies ilf/mesh.h's invariants, or
 * nothing is returned and everything allocated on the way is freed; a
 * pre-check never rejects a file because it cannot make sense of it, it
 * leaves that to assimp, which reports it.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* stat(); the build defines it too */
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
#include <unistd.h>

#include "ilf/file_kind.h"
#include "ilf/json.h"
#include "ilf/limits.h"
#include "ilf/mesh.h"
#include "plycheck.h"

/* ------------------------------------------------------------ files */

/* @return path opened for reading if it is a regular file (ilf/file_kind.h), else NULL. */
static FILE *open_regular(const char *path)
{
    char why[160];
    int fd;
    if (ilf_input_open(path, &fd, why, sizeof why) != 0)
        return NULL;
    FILE *f = fdopen(fd, "rb");
    if (f == NULL)
        close(fd);
    return f;
}

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

/* ------------------------------------------------------------ glTF */

/* glTF 2.0 accessor component types. */
enum { GLTF_UBYTE = 5121, GLTF_USHORT = 5123, GLTF_UINT = 5125, GLTF_FLOAT = 5126 };

/* Largest glTF JSON read for the check (ilf/limits.h). */
#define GLTF_JSON_MAX ILF_GLTF_JSON_MAX_BYTES

/* @return the name of glTF component type t. */
static const char *gltf_type_name(int t)
{
    switch (t) {
    case 5120: return "byte";
    case GLTF_UBYTE: return "unsigned byte";
    case 5122: return "short";
    case GLTF_USHORT: return "unsigned short";
    case GLTF_UINT: return "unsigned int";
    case GLTF_FLOAT: return "float";
    default: return "unknown";
    }
}

/*
 * Checks accessor number `at` of the glTF accessors array, used by `use` of
 * meshes[mi].primitives[prim]: positions must be FLOAT VEC3 (glTF 2.0, 3.7.2.1),
 * indices SCALAR of an unsigned integer type. @return 1, or 0 with why.
 */
static int gltf_accessor_ok(const ilf_json *accessors, const ilf_json *at, int indices, int mi, int prim, char *why,
                            size_t size)
{
    const char *use = indices ? "indices" : "POSITION";
    int n = ilf_json_type_of(accessors) == ILF_JSON_ARRAY ? (int)ilf_json_count(accessors) : 0;
    int number = ilf_json_type_of(at) == ILF_JSON_NUMBER;
    double a = ilf_json_value(at);
    if (!number || a < 0 || a >= n || a != (int)a) {
        snprintf(why, size, "meshes[%d].primitives[%d]: %s refers to accessor %g of %d", mi, prim, use,
                 number ? a : -1.0, n);
        return 0;
    }
    const ilf_json *acc = ilf_json_at(accessors, (size_t)a);
    const ilf_json *ct = ilf_json_get(acc, "componentType");
    const ilf_json *type = ilf_json_get(acc, "type");
    int t = ilf_json_type_of(ct) == ILF_JSON_NUMBER ? (int)ilf_json_value(ct) : 0;
    const char *ty = ilf_json_type_of(type) == ILF_JSON_STRING ? ilf_json_text(type) : "(none)";
    int ok = indices ? (t == GLTF_UBYTE || t == GLTF_USHORT || t == GLTF_UINT) && strcmp(ty, "SCALAR") == 0
                     : t == GLTF_FLOAT && strcmp(ty, "VEC3") == 0;
    if (!ok)
        snprintf(why, size,
                 "meshes[%d].primitives[%d]: %s accessor %d has componentType %d (%s) and type %s; glTF 2.0 %s",
                 mi, prim, use, (int)a, t, gltf_type_name(t), ty,
                 indices ? "indices are SCALAR unsigned byte, short or int" : "positions are VEC3 float (5126)");
    return ok;
}

/*
 * Reads materials[k].extensions.KHR_materials_emissive_strength.emissiveStrength
 * of each glTF material into a new array (1 where absent; *out NULL when
 * there are no materials). @return 1; 0 with why for a strength that is not
 * a finite number >= 0, or for memory (*nomem set).
 */
static int gltf_strengths(const ilf_json *root, double **out, size_t *count, int *nomem, char *why, size_t size)
{
    const ilf_json *materials = ilf_json_get(root, "materials");
    size_t n = ilf_json_type_of(materials) == ILF_JSON_ARRAY ? ilf_json_count(materials) : 0;
    if (n == 0)
        return 1;
    double *s = malloc(n * sizeof *s);
    if (!s) {
        *nomem = 1;
        snprintf(why, size, "out of memory");
        return 0;
    }
    size_t k = 0;
    for (const ilf_json *m = ilf_json_first(materials); m; m = ilf_json_next(m), k++) {
        const ilf_json *ext = ilf_json_get(ilf_json_get(m, "extensions"), "KHR_materials_emissive_strength");
        const ilf_json *v = ilf_json_get(ext, "emissiveStrength");
        s[k] = 1.0; /* the extension's default, and glTF's without it */
        if (!v)
            continue;
        s[k] = ilf_json_type_of(v) == ILF_JSON_NUMBER ? ilf_json_value(v) : -1.0;
        if (!(s[k] >= 0) || !isfinite(s[k])) {
            snprintf(why, size, "materials[%zu]: KHR_materials_emissive_strength.emissiveStrength must be a "
                     "number >= 0", k);
            free(s);
            return 0;
        }
    }
    *out = s;
    *count = n;
    return 1;
}

/* The emissive strengths of a glTF file's materials, by glTF material index. */
typedef struct gltf_info {
    double *strength; /* [count], or NULL */
    size_t count;
    int nomem;        /* the check failed for memory, not for the file */
} gltf_info;

/*
 * Reads the JSON of a glTF 2.0 file (.gltf: the file; .glb: its first
 * chunk), checks every mesh primitive's POSITION and indices accessors and
 * reads its materials' emissive strengths into info (zeroed first).
 * Anything it cannot make sense of is left to assimp, which reports it.
 * @return 1 (fine, or not a glTF 2.0 file), or 0 with why.
 */
static int gltf_check(const char *path, gltf_info *info, char *why, size_t size)
{
    memset(info, 0, sizeof *info);
    const char *dot = strrchr(path, '.');
    int glb = dot && strcasecmp(dot, ".glb") == 0;
    if (!dot || (!glb && strcasecmp(dot, ".gltf") != 0))
        return 1;
    FILE *f = open_regular(path);
    if (!f)
        return 1;
    size_t len = 0, fsize = 0;
    if (fseek(f, 0, SEEK_END) == 0) {
        long end = ftell(f);
        fsize = end > 0 ? (size_t)end : 0;
        rewind(f);
    }
    if (glb) {
        /* header: magic, version 2, total length; then a chunk: length, type
         * "JSON". assimp reserves what these lengths claim before it reads,
         * so they are held to the file's size first (glTF 2.0, 4.4). */
        unsigned char h[20];
        if (fread(h, 1, sizeof h, f) != sizeof h || memcmp(h, "glTF", 4) != 0) {
            fclose(f);
            snprintf(why, size, "not a binary glTF file: no 20-byte header starting with 'glTF'");
            return 0;
        }
        size_t version = (size_t)h[4] | (size_t)h[5] << 8 | (size_t)h[6] << 16 | (size_t)h[7] << 24;
        size_t total = (size_t)h[8] | (size_t)h[9] << 8 | (size_t)h[10] << 16 | (size_t)h[11] << 24;
        len = (size_t)h[12] | (size_t)h[13] << 8 | (size_t)h[14] << 16 | (size_t)h[15] << 24;
        const char *bad = version != 2                  ? "version is not 2"
                          : total != fsize              ? "header length differs from the file's size"
                          : memcmp(h + 16, "JSON", 4)   ? "first chunk is not JSON"
                          : len == 0 || len % 4 != 0    ? "JSON chunk length is 0 or not a multiple of 4"
                          : len > fsize - sizeof h      ? "JSON chunk is longer than the rest of the file"
                          : len > GLTF_JSON_MAX         ? "JSON chunk is larger than the checker reads"
                                                        : NULL;
        if (bad) {
            fclose(f);
            snprintf(why, size, "binary glTF: %s (header length %zu, JSON chunk %zu bytes, file %zu bytes)", bad,
                     total, len, fsize);
            return 0;
        }
        /* the binary chunk, when present, must fit too */
        size_t next = sizeof h + len;
        unsigned char c[8];
        if (next < fsize &&
            (fseek(f, (long)next, SEEK_SET) != 0 || fread(c, 1, sizeof c, f) != sizeof c ||
             ((size_t)c[0] | (size_t)c[1] << 8 | (size_t)c[2] << 16 | (size_t)c[3] << 24) > fsize - next - 8)) {
            fclose(f);
            snprintf(why, size, "binary glTF: the chunk after the JSON is longer than the rest of the file");
            return 0;
        }
        fseek(f, (long)sizeof h, SEEK_SET);
    } else {
        len = fsize;
    }
    char *text = len > 0 && len <= GLTF_JSON_MAX ? malloc(len) : NULL;
    size_t got = text ? fread(text, 1, len, f) : 0;
    fclose(f);
    ilf_json *root = got == len && text ? ilf_json_parse_quiet(text, len) : NULL;
    free(text);
    const ilf_json *version = ilf_json_get(ilf_json_get(root, "asset"), "version");
    const ilf_json *meshes = ilf_json_get(root, "meshes");
    const ilf_json *accessors = ilf_json_get(root, "accessors");
    int ok = 1;
    if (ilf_json_type_of(version) == ILF_JSON_STRING && ilf_json_text(version)[0] == '2' &&
        ilf_json_type_of(meshes) == ILF_JSON_ARRAY) {
        int mi = 0;
        for (const ilf_json *m = ilf_json_first(meshes); m && ok; m = ilf_json_next(m), mi++) {
            const ilf_json *prims = ilf_json_get(m, "primitives");
            int prim = 0;
            for (const ilf_json *p = ilf_json_first(prims); p && ok; p = ilf_json_next(p), prim++) {
                const ilf_json *attrs = ilf_json_get(p, "attributes");
                const ilf_json *pos = ilf_json_get(attrs, "POSITION");
                const ilf_json *idx = ilf_json_get(p, "indices");
                if (pos)
                    ok = gltf_accessor_ok(accessors, pos, 0, mi, prim, why, size);
                if (ok && idx)
                    ok = gltf_accessor_ok(accessors, idx, 1, mi, prim, why, size);
            }
        }
    }
    if (ok && ilf_json_type_of(version) == ILF_JSON_STRING && ilf_json_text(version)[0] == '2')
        ok = gltf_strengths(root, &info->strength, &info->count, &info->nomem, why, size);
    ilf_json_free(root);
    return ok;
}

/* ------------------------------------------------------------ formats */

/* The accepted formats (ilf/mesh.h says why these and no others). */
static const char *const MESH_FORMATS[] = {"obj", "ply", "gltf", "glb", "stl", "fbx", "3ds", NULL};

int ilf_mesh_format_supported(const char *path)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return 0;
    for (size_t k = 0; MESH_FORMATS[k]; k++)
        if (strcasecmp(dot + 1, MESH_FORMATS[k]) == 0)
            return 1;
    return 0;
}

/* ------------------------------------------------------------ the soup */

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
static ilf_mesh_status soup_new(const char *path, const struct aiScene *sc, const gltf_info *gltf, ilf_mesh **out,
                                char *why, size_t size)
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
        copy_material(sc->mMaterials[k], k < gltf->count ? gltf->strength[k] : 1.0, &m->materials[k]);
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

ilf_mesh_status ilf_mesh_import(const char *path, ilf_mesh **out, char *why, size_t why_size)
{
    *out = NULL;
    struct stat sb;
    char problem[256];
    int fd, err = ilf_input_open(path, &fd, problem, sizeof problem);
    if (err == EISDIR || err == EINVAL) {
        if (err == EISDIR)
            snprintf(why, why_size, "'%s' is not a regular file (a folder)", path);
        else
            snprintf(why, why_size, "'%s' %s", path, problem);
        return ILF_MESH_ERR_INPUT;
    }
    if (err != 0 || fstat(fd, &sb) != 0) {
        snprintf(why, why_size, "cannot open '%s': %s", path, strerror(err != 0 ? err : errno));
        if (err == 0)
            close(fd);
        return ILF_MESH_ERR_INPUT;
    }
    close(fd);
    /* assimp reads uninitialised memory on an empty glTF (valgrind, a fuzz_mesh input) */
    if (sb.st_size == 0) {
        snprintf(why, why_size, "cannot read '%s': the file is empty", path);
        return ILF_MESH_ERR_INPUT;
    }
    if (!ilf_mesh_format_supported(path)) {
        snprintf(why, why_size, "cannot read '%s': mesh format not supported (OBJ, PLY, glTF, GLB, STL, FBX "
                 "and 3DS are: their readers check their counts)", path);
        return ILF_MESH_ERR_INPUT;
    }
    gltf_info gltf = {0};
    /* assimp would trust a PLY header's counts (plycheck.h), and copy positions of any type (gltf_check) */
    if (!ilf__ply_check(path, problem, sizeof problem) || !gltf_check(path, &gltf, problem, sizeof problem)) {
        if (gltf.nomem)
            snprintf(why, why_size, "'%s': out of memory", path);
        else
            snprintf(why, why_size, "cannot read '%s': %s", path, problem);
        return gltf.nomem ? ILF_MESH_ERR_NOMEM : ILF_MESH_ERR_INPUT;
    }
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
        free(gltf.strength);
        return failure;
    }
    ilf_mesh_status st = ILF_MESH_OK;
    if (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE) {
        snprintf(why, why_size, "'%s' holds no complete mesh", path);
        st = ILF_MESH_ERR_INPUT;
    } else {
        st = soup_new(path, sc, &gltf, out, why, why_size);
        if (st == ILF_MESH_ERR_NOMEM)
            snprintf(why, why_size, "'%s': out of memory", path);
    }
    aiReleaseImport(sc);
    free(gltf.strength);
    return st;
}
