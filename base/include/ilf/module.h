/*
 * ilf/module.h - the one loader of ilfkit's optional modules: shared objects
 * in LIBDIR/ilfkit (the image module libilfkit_oiio.so, the mesh module
 * libilfkit_assimp.so) that a library opens with dlopen() on first use, so
 * that a program that never reads an image or a mesh never maps OpenImageIO
 * or assimp and their dependencies.
 *
 * A module exports one C function (entry) returning a static table whose
 * first member is an unsigned version; a table of another version is
 * refused, not called. Where a module is looked for, in order, stopping at
 * the first place that gives a table of the right version:
 *   1. $<env>, a full path, when set and not empty: then the only place
 *      tried, so that a test or a user can pin the module;
 *   2. <folder of /proc/self/exe>/../<relative>: the build tree (programs in
 *      BUILD/tools and BUILD/tests, modules in BUILD/LIBDIR/ilfkit) and a
 *      relocated install (PREFIX/bin, PREFIX/LIBDIR/ilfkit);
 *   3. when the loader runs inside a shared library (PREFIX/LIBDIR/librelight.so,
 *      libcapture.so), <folder of that library>/../<relative>: a user's
 *      program, wherever it lives, finds the modules of the install it links;
 *   4. <installed>, the configured install location.
 * base is a static library with hidden symbols, so this loader is always
 * linked into the same file (program or shared library) as its caller: its
 * own address tells which shared library place 3 starts from.
 *
 * Invariants: each module is loaded at most once per process (under one
 * lock), with dlopen(RTLD_NOW | RTLD_LOCAL), and never unloaded; a refused
 * file stays mapped, unused (it may have run initialisers). After the load,
 * table and failure never change. The failure text names every path tried
 * and why each failed, in one line.
 */
#ifndef ILF_MODULE_H
#define ILF_MODULE_H

#include <stddef.h>

/* Room for the failure text: up to four paths and dlerror()'s reasons. */
#define ILF_MODULE_FAILURE_BYTES 4096u

/* One module: where to look (set by the caller, constant) and what came of it (the loader's). */
typedef struct ilf_module {
    const char *env;       /* variable that pins the module's full path */
    const char *relative;  /* LIBDIR/ilfkit/<file>, relative to a prefix */
    const char *installed; /* the configured install path */
    const char *entry;     /* name of the exported function returning the table */
    unsigned version;      /* the table version this build needs (the table's first member) */
    int tried;             /* the loader's: set once the module was looked for */
    const void *table;     /* the loader's: the module's table, or NULL */
    char failure[ILF_MODULE_FAILURE_BYTES]; /* the loader's: "path: reason; path: reason" when table is NULL */
} ilf_module;

/* A module's initialiser: ilf_module m = ILF_MODULE_INIT(env, relative, installed, entry, version); */
#define ILF_MODULE_INIT(env, relative, installed, entry, version)                                                   \
    {(env), (relative), (installed), (entry), (version), 0, NULL, ""}

/* Loads m on its first call (thread-safe). @return m's table, or NULL: then ilf_module_failure(m) says why. */
const void *ilf_module_get(ilf_module *m);

/* @return the text of m's failed load (every path tried and why), "" if it loaded; to be read after
 * ilf_module_get() returned NULL (the text never changes after that). */
const char *ilf_module_failure(const ilf_module *m);

#endif /* ILF_MODULE_H */
