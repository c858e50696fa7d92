/*
 * test_read.c - base's input readers on their own: the strict JSON reader
 * (ilf/json.h) where its two predecessors differed (byte order mark, nesting
 * depth, repeated keys, empty files, NUL bytes, integers, one message format)
 * and the mesh importer (ilf/mesh.h: the soup of a small OBJ, the formats
 * and pre-checks refused with the file named; the mesh module, and with it
 * assimp, mapped only by the first import that passes the checks; a
 * missing module refused as bad input naming the mesh and the path tried,
 * in a child process, since the module loads once per process).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "ilf/json.h"
#include "ilf/mesh.h"

static char folder[512];

/* Writes len bytes of text to folder/name. @return the path (static storage, one at a time). */
static const char *put(const char *name, const char *text, size_t len)
{
    static char path[640];
    snprintf(path, sizeof path, "%s/%s", folder, name);
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "cannot write %s", path);
    if (f) {
        fwrite(text, 1, len, f);
        fclose(f);
    }
    return path;
}

/* Loads text as the file name. @return the status; *root is freed unless keep. */
static ilf_json_status load(const char *name, const char *text, size_t len, ilf_json_ctx *c)
{
    c->file = put(name, text, len);
    ilf_json *root = NULL;
    ilf_json_status st = ilf_json_load(c, 1 << 20, &root);
    CHECK((st == ILF_JSON_OK) == (root != NULL), "%s: a root exactly on success", name);
    ilf_json_free(root);
    return st;
}

static void test_json_files(void)
{
    ilf_json_ctx c;
    CHECK(load("bom.json", "\xEF\xBB\xBF{\"a\": 1}", 11, &c) == ILF_JSON_OK, "a byte order mark is skipped: %s",
          c.message);
    CHECK(load("empty.json", " \n", 2, &c) == ILF_JSON_ERR_INPUT && strstr(c.message, "not valid JSON") &&
              strstr(c.message, "the file is empty"), "empty: %s", c.message);
    CHECK(load("nul.json", "{\"a\":\0 1}", 9, &c) == ILF_JSON_ERR_INPUT && strstr(c.message, "nul.json:1:6: not valid JSON: a NUL byte"),
          "NUL: %s", c.message);
    CHECK(load("trail.json", "{}\n{}", 5, &c) == ILF_JSON_ERR_INPUT && strstr(c.message, "trail.json:2:1: not valid JSON"),
          "trailing text: %s", c.message);
    /* exactly the limit nests fine; one more level is refused with the limit named */
    size_t n = ILF_JSON_MAX_DEPTH;
    char *deep = malloc(2 * n + 2);
    memset(deep, '[', n);
    memset(deep + n, ']', n);
    CHECK(load("deep_ok.json", deep, 2 * n, &c) == ILF_JSON_OK, "%zu levels: %s", n, c.message);
    memset(deep, '[', n + 1);
    memset(deep + n + 1, ']', n + 1);
    CHECK(load("deep.json", deep, 2 * n + 2, &c) == ILF_JSON_ERR_INPUT && strstr(c.message, "not valid JSON") &&
              strstr(c.message, "nested more than 1000 deep"), "too deep: %s", c.message);
    free(deep);
    char missing[600];
    snprintf(missing, sizeof missing, "%s/none/x.json", folder);
    c.file = missing;
    ilf_json *root = NULL;
    CHECK(ilf_json_load(&c, 100, &root) == ILF_JSON_ERR_IO && strstr(c.message, "cannot open"), "missing: %s", c.message);
    c.file = folder;
    CHECK(ilf_json_load(&c, 100, &root) == ILF_JSON_ERR_IO && strstr(c.message, "is a directory"), "folder: %s", c.message);
    c.file = put("big.json", "[1, 2, 3]", 9);
    CHECK(ilf_json_load(&c, 8, &root) == ILF_JSON_ERR_INPUT && strstr(c.message, "9 bytes, more than the limit of 8"),
          "size: %s", c.message);
}

static void test_json_values(void)
{
    ilf_json_ctx c;
    const char *text = "{\"a\": 1, \"b\": [1, 2.5, 1e400], \"a\": 2, \"s\": \"\", \"p\": 6}";
    c.file = put("v.json", text, strlen(text));
    ilf_json *root = NULL;
    CHECK(ilf_json_load(&c, 1 << 20, &root) == ILF_JSON_OK, "%s", c.message);
    static const char *const keys[] = {"a", "b", "s", "p", NULL}, *const few[] = {"a", NULL};
    CHECK(ilf_json_keys(&c, root, "top", keys) == ILF_JSON_ERR_INPUT &&
              strstr(c.message, "v.json: top: duplicate key 'a'") && strstr(c.message, "repeated"),
          "repeated key: %s", c.message);
    CHECK(ilf_json_keys(&c, root, "", few) == ILF_JSON_ERR_INPUT && strstr(c.message, "v.json: unknown key 'b' (expected a)"),
          "unknown key: %s", c.message);
    const ilf_json *b = ilf_json_get(root, "b");
    double v[3];
    CHECK(ilf_json_count(b) == 3 && ilf_json_type_of(b) == ILF_JSON_ARRAY, "array of 3");
    CHECK(ilf_json_vector(&c, b, "b", 3, v) == ILF_JSON_ERR_INPUT && strstr(c.message, "v.json: b[2]: not a finite number"),
          "infinite: %s", c.message);
    uint64_t u = 0;
    CHECK(ilf_json_integer(&c, ilf_json_at(b, 1), "b[1]", 0, 10, 0, &u) == ILF_JSON_ERR_INPUT &&
              strstr(c.message, "must be an integer in 0..10, got 2.5 (expected a whole number)"), "whole: %s", c.message);
    CHECK(ilf_json_integer(&c, ilf_json_get(root, "p"), "p", 1, 4, 0, &u) == ILF_JSON_ERR_INPUT &&
              strstr(c.message, "6 is outside 1..4"), "range: %s", c.message);
    CHECK(ilf_json_integer(&c, ilf_json_get(root, "p"), "p", 1, 64, 1, &u) == ILF_JSON_ERR_INPUT &&
              strstr(c.message, "must be a power of two in 1..64, got 6"), "power of two: %s", c.message);
    CHECK(ilf_json_integer(&c, ilf_json_at(b, 0), "b[0]", 1, 64, 1, &u) == ILF_JSON_OK && u == 1, "1 = 2^0");
    const char *s = NULL;
    CHECK(ilf_json_string(&c, ilf_json_get(root, "s"), "s", &s) == ILF_JSON_ERR_INPUT && s != NULL && s[0] == '\0' &&
              strstr(c.message, "s: must not be empty"), "empty string: %s", c.message);
    CHECK(ilf_json_member(&c, root, "", "zz", 1, &b) == ILF_JSON_ERR_INPUT && b == NULL &&
              strstr(c.message, "missing key 'zz'"), "missing: %s", c.message);
    CHECK(ilf_json_kind(NULL) != NULL && strcmp(ilf_json_kind(ilf_json_get(root, "s")), "a string") == 0, "kinds");
    ilf_json_free(root);
    ilf_json_free(NULL);
}

/* Imports an OBJ quad in a child process whose mesh module is pinned to a missing file: refused as bad
 * input, naming the mesh, the module path tried, and what is missing; nothing of assimp mapped. */
static void test_mesh_without_module(void)
{
    const char *obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    char path[640], module[640];
    snprintf(path, sizeof path, "%s", put("tri.obj", obj, strlen(obj)));
    snprintf(module, sizeof module, "%s/no-such/libilfkit_assimp.so", folder);
    fflush(stdout);
    fflush(stderr);
    long failed_before = check_failed;
    pid_t pid = fork();
    if (pid == 0) {
        setenv("ILFKIT_MESH_MODULE", module, 1);
        ilf_mesh *m = NULL;
        char why[1024] = "";
        CHECK(ilf_mesh_import(path, &m, why, sizeof why) == ILF_MESH_ERR_INPUT && m == NULL,
              "a missing module is bad input: %s", why);
        CHECK(strstr(why, path) && strstr(why, module) && strstr(why, "mesh support is not available"),
              "the message names the mesh, the module tried and what is missing: %s", why);
        CHECK(check_mapped("libassimp") == 0, "no assimp mapped after a failed load");
        _exit(check_failed > failed_before ? 1 : 0);
    }
    int status = -1;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0,
          "the child without a mesh module passed its checks (wait status %d)", status);
}

/* Must be this process's first import. */
static void test_mesh(void)
{
    ilf_mesh *m = NULL;
    char why[1024] = "";
    const char *ply = "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n";
    const char *path = put("huge.ply", ply, strlen(ply));
    CHECK(ilf_mesh_import(path, &m, why, sizeof why) == ILF_MESH_ERR_INPUT && m == NULL &&
              strstr(why, "huge.ply") && strstr(why, "declares 1000000000 'vertex' elements"), "PLY check: %s", why);
    path = put("x.dae", "<COLLADA/>", 10);
    CHECK(ilf_mesh_import(path, &m, why, sizeof why) == ILF_MESH_ERR_INPUT && strstr(why, "x.dae': mesh format not supported"),
          "format: %s", why);
    path = put("empty.gltf", "", 0);
    CHECK(ilf_mesh_import(path, &m, why, sizeof why) == ILF_MESH_ERR_INPUT && strstr(why, "the file is empty"),
          "empty: %s", why);
    CHECK(ilf_mesh_format_supported("a/B.GLB") && !ilf_mesh_format_supported("a.b/noext"), "extensions");
    CHECK(check_mapped("libilfkit_assimp") == 0 && check_mapped("libassimp") == 0,
          "files refused by the pre-checks load no mesh module");
    const char *obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nl 1 3\n";
    path = put("quad.obj", obj, strlen(obj));
    CHECK(ilf_mesh_import(path, &m, why, sizeof why) == ILF_MESH_OK && m != NULL, "quad.obj: %s", why);
    CHECK(check_mapped("libilfkit_assimp") == 1 && check_mapped("libassimp") == 1,
          "the mesh module and assimp are mapped after the first import");
    if (m) {
        CHECK(m->nfaces >= 1 && m->faces[0].count == 4, "one quad first: %zu faces", m->nfaces);
        for (size_t k = 0; k < m->nindices; k++)
            CHECK(m->indices[k] < m->nvertices, "index %zu in range", k);
        const double *c = m->vertices[m->indices[m->faces[0].first + 2]];
        CHECK(c[0] == 1 && c[1] == 1 && c[2] == 0, "the third corner");
    }
    ilf_mesh_destroy(m);
    ilf_mesh_destroy(NULL);
}

int main(int argc, char **argv)
{
    snprintf(folder, sizeof folder, "%s", argc > 1 ? argv[1] : ".");
    test_json_files();
    test_json_values();
    test_mesh_without_module();
    test_mesh();
    return check_report();
}
