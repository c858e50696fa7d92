/*
 * ilfpy.h - what the files of the C extension _ilfkit share: the Python and
 * NumPy headers (NumPy's C API table is defined in py_module.c, declared here for
 * the others), the one exception type, and the conversion of a radiance map
 * to Python objects.
 *
 * Invariants of the whole module: every entry point holds the GIL except
 * across calls into lfio and relight that read files or compute (those run
 * between Py_BEGIN_ALLOW_THREADS and Py_END_ALLOW_THREADS and touch no
 * Python object); a library failure becomes ilfkit.Error carrying the
 * library's own message (lfio_errmsg() or rl_errmsg(), read in the thread
 * that failed); arrays handed to Python are C-contiguous and own their data,
 * except the radiance of a light field's slab, a read-only view kept alive
 * by its LightField.
 */
#ifndef ILFPY_H
#define ILFPY_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>

#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#define PY_ARRAY_UNIQUE_SYMBOL ilfpy_array_api
#ifndef ILFPY_DEFINE_ARRAY_API
#define NO_IMPORT_ARRAY
#endif
#include <numpy/arrayobject.h>

#include <lfio/radmap.h>

/** ilfkit.Error, a subclass of RuntimeError; its attribute `status` names the library's status. */
extern PyObject *ilfpy__error;

/** Raises ilfkit.Error(message) with .status = status. @return NULL, for `return ilfpy__raise(...)`. */
PyObject *ilfpy__raise(const char *status, const char *message);

/** Raises ilfkit.Error for an lfio failure s with lfio_errmsg(). @return NULL. */
PyObject *ilfpy__raise_lfio(lfio_status s);

/** @return a new C-contiguous array of the given shape and type holding a copy of data (count = product of dims). */
PyObject *ilfpy__array_copy(int nd, const npy_intp *dims, int type, const void *data);

/** @return a new tuple of the n doubles of v. */
PyObject *ilfpy__tuple(const double *v, int n);

/** @return a dict describing patch p (its geometry, material and cells as arrays), as ilfkit.Map takes it. */
PyObject *ilfpy__map_dict(const lfio_radmap_patch *p);

/** Module functions of the other files. */
extern PyMethodDef ilfpy__lightfield_methods[];
extern PyMethodDef ilfpy__relight_methods[];
extern PyMethodDef ilfpy__radmap_methods[];

/** Readies the LightField type and adds it to module m. @return 0, or -1 with an exception set. */
int ilfpy__lightfield_add_type(PyObject *m);

#endif /* ILFPY_H */
