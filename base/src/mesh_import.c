/*
 * mesh_import.c - the one mesh importer (ilf/mesh.h): the checks made before
 * assimp reads a file, and the call into the mesh module libilfkit_assimp.so
 * (mesh_module.h, assimp_module.c), which reads it with assimp and copies
 * what it read into a plain polygon soup. The module is loaded through
 * base's module loader (ilf/module.h: ILFKIT_MESH_MODULE pins it; the build
 * tree, beside a shared library, the install location) on the first import
 * that passes the checks, so a program that imports no mesh never maps
 * assimp. PLY files are checked by plycheck.c first.
 *
 * Checks, in order, each refusing with a message naming the file: the file
 * exists and is a regular, non-empty file (assimp reads uninitialised memory
 * on an empty glTF); its extension names an accepted format (ilf/mesh.h);
 * a PLY file's declared counts fit its size (plycheck.h: assimp trusts
 * them); a GLB file's header and chunk lengths fit its size, and a glTF
 * file's position and index accessors have the types glTF 2.0 requires
 * (assimp copies positions of any type as raw bytes into its vertices: a
 * position accessor of another type would load silently as garbage or
 * nothing), and every KHR_materials_emissive_strength is a number >= 0
 * (assimp 5.2 drops the extension: the strengths read here go to the
 * module, which applies them); the module then reads the file with assimp's
 * data-structure validation and checks that the result is complete.
 *
 * Invariants: an imported soup satisfies ilf/mesh.h's invariants, or
 * nothing is returned and everything allocated on the way is freed; a
 * pre-check never rejects a file because it cannot make sense of it, it
 * leaves that to assimp, which reports it; a missing or stale module fails
 * the import as bad input, naming the mesh file and every module path tried.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* stat(); the build defines it too */
#endif

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
#include "ilf/module.h"
#include "mesh_module.h"
#include "plycheck.h"

#ifndef ILFKIT_MESH_MODULE_RELATIVE
#error "ILFKIT_MESH_MODULE_RELATIVE (LIBDIR/ilfkit/<file>, relative to a prefix) must be defined"
#endif
#ifndef ILFKIT_MESH_MODULE_INSTALLED
#error "ILFKIT_MESH_MODULE_INSTALLED (the module's installed path) must be defined"
#endif

/* The mesh module, found and loaded by base's module loader once per process. */
static ilf_module mesh_module = ILF_MODULE_INIT("ILFKIT_MESH_MODULE", ILFKIT_MESH_MODULE_RELATIVE,
                                                ILFKIT_MESH_MODULE_INSTALLED, ILF__MESH_MODULE_ENTRY,
                                                ILF__MESH_MODULE_VERSION);

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

/* ------------------------------------------------------------ importing */

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
    const ilf__mesh_module *module = ilf_module_get(&mesh_module);
    if (module == NULL) {
        snprintf(why, why_size, "cannot read '%s': mesh support is not available (%s)", path,
                 ilf_module_failure(&mesh_module));
        free(gltf.strength);
        return ILF_MESH_ERR_INPUT;
    }
    ilf_mesh_status st = module->import(path, gltf.strength, gltf.count, out, why, why_size);
    free(gltf.strength);
    return st;
}
