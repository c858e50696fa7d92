/*
 * py_common.c - what the files of the C extension _ilfkit share (ilfpy.h):
 * the exception ilfkit.Error raised with a library's message, arrays and
 * tuples copied out of C memory, and a radiance map as a dict. Conventions of
 * the whole module are in ilfpy.h.
 */
#include "ilfpy.h"

#include <string.h>

#include <lfio/lfio.h>

PyObject *ilfpy__error;

PyObject *ilfpy__raise(const char *status, const char *message)
{
    /* a message naming a file holds its path's bytes: decoded as os.fsdecode() would, never refused */
    PyObject *text = PyUnicode_DecodeUTF8(message, (Py_ssize_t)strlen(message), "surrogateescape");
    PyObject *e = text != NULL ? PyObject_CallOneArg(ilfpy__error, text) : NULL;
    Py_XDECREF(text);
    if (e == NULL)
        return NULL;
    PyObject *st = PyUnicode_FromString(status);
    if (st == NULL || PyObject_SetAttrString(e, "status", st) < 0) {
        Py_XDECREF(st);
        Py_DECREF(e);
        return NULL;
    }
    Py_DECREF(st);
    PyErr_SetObject(ilfpy__error, e);
    Py_DECREF(e);
    return NULL;
}

PyObject *ilfpy__raise_lfio(lfio_status s)
{
    return ilfpy__raise(lfio_status_name(s), lfio_errmsg());
}

PyObject *ilfpy__array_copy(int nd, const npy_intp *dims, int type, const void *data)
{
    PyObject *a = PyArray_SimpleNew(nd, (npy_intp *)dims, type);
    if (a != NULL && PyArray_NBYTES((PyArrayObject *)a) > 0)
        memcpy(PyArray_DATA((PyArrayObject *)a), data, PyArray_NBYTES((PyArrayObject *)a));
    return a;
}

PyObject *ilfpy__tuple(const double *v, int n)
{
    PyObject *t = PyTuple_New(n);
    for (int k = 0; t != NULL && k < n; k++) {
        PyObject *x = PyFloat_FromDouble(v[k]);
        if (x == NULL) {
            Py_DECREF(t);
            return NULL;
        }
        PyTuple_SET_ITEM(t, k, x);
    }
    return t;
}

/* Sets d[key] = value and drops the reference to value. @return 0, or -1 (value NULL or the set failed). */
static int put(PyObject *d, const char *key, PyObject *value)
{
    if (value == NULL)
        return -1;
    int rc = PyDict_SetItemString(d, key, value);
    Py_DECREF(value);
    return rc;
}

/* The patch's geometry and material into d. */
static int put_geometry(PyObject *d, const lfio_radmap_patch *p)
{
    npy_intp verts[2] = {p->nverts, 3}, three = 3;
    float albedo_emission[2][3];
    memcpy(albedo_emission[0], p->albedo, sizeof p->albedo);
    memcpy(albedo_emission[1], p->emission, sizeof p->emission);
    if (put(d, "label", PyUnicode_FromString(p->label ? p->label : "")) < 0 ||
        put(d, "polygon", PyLong_FromUnsignedLong(p->polygon)) < 0 ||
        put(d, "vertices", ilfpy__array_copy(2, verts, NPY_DOUBLE, p->vertices)) < 0 ||
        put(d, "origin", ilfpy__array_copy(1, &three, NPY_DOUBLE, p->origin)) < 0 ||
        put(d, "e1", ilfpy__array_copy(1, &three, NPY_DOUBLE, p->e1)) < 0 ||
        put(d, "e2", ilfpy__array_copy(1, &three, NPY_DOUBLE, p->e2)) < 0 ||
        put(d, "normal", ilfpy__array_copy(1, &three, NPY_DOUBLE, p->normal)) < 0 ||
        put(d, "cell_size", PyFloat_FromDouble(p->cell_size)) < 0 || put(d, "u0", PyFloat_FromDouble(p->u0)) < 0 ||
        put(d, "v0", PyFloat_FromDouble(p->v0)) < 0 || put(d, "nu", PyLong_FromUnsignedLong(p->nu)) < 0 ||
        put(d, "nv", PyLong_FromUnsignedLong(p->nv)) < 0 ||
        put(d, "albedo", ilfpy__array_copy(1, &three, NPY_FLOAT, albedo_emission[0])) < 0 ||
        put(d, "emission", ilfpy__array_copy(1, &three, NPY_FLOAT, albedo_emission[1])) < 0)
        return -1;
    return 0;
}

/* The patch's cells into d: ij [ncells, 2], area [ncells], centre, irradiance and radiosity [ncells, 3]. */
static int put_cells(PyObject *d, const lfio_radmap_patch *p)
{
    npy_intp two[2] = {p->ncells, 2}, one = p->ncells, three[2] = {p->ncells, 3};
    if (put(d, "ij", ilfpy__array_copy(2, two, NPY_UINT32, p->cell_ij)) < 0 ||
        put(d, "area", ilfpy__array_copy(1, &one, NPY_DOUBLE, p->cell_area)) < 0 ||
        put(d, "centre", ilfpy__array_copy(2, three, NPY_DOUBLE, p->cell_centre)) < 0 ||
        put(d, "irradiance", ilfpy__array_copy(2, three, NPY_FLOAT, p->irradiance)) < 0 ||
        put(d, "radiosity", ilfpy__array_copy(2, three, NPY_FLOAT, p->radiosity)) < 0)
        return -1;
    return 0;
}

PyObject *ilfpy__map_dict(const lfio_radmap_patch *p)
{
    PyObject *d = PyDict_New();
    if (d != NULL && (put_geometry(d, p) < 0 || put_cells(d, p) < 0))
        Py_CLEAR(d);
    return d;
}
