/*
 * py_lightfield.c - light field files and the sphere partition in Python: the
 * type _ilfkit.LightField (an lfio_lightfield read whole, its slabs'
 * descriptions, radiance as read-only NumPy views, and point queries) and
 * the partition's lookups over arrays of directions or ids.
 *
 * Invariants: a LightField owns its lfio_lightfield until it is freed; a
 * radiance view holds a reference to its LightField, so the memory it shows
 * lives as long as the view. Partition lookups check every element and raise
 * ValueError naming the first bad one, leaving no partial result.
 */
#include "ilfpy.h"

#include <lfio/lightfield.h>
#include <lfio/partition.h>

typedef struct {
    PyObject_HEAD
    lfio_lightfield *lf;
} LightField;

static void lightfield_dealloc(LightField *self)
{
    lfio_lightfield_destroy(self->lf);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

/* @return slab k of self, or NULL with IndexError. */
static const lfio_slab *slab_at(LightField *self, Py_ssize_t k)
{
    if (k < 0 || (size_t)k >= lfio_lightfield_slab_count(self->lf)) {
        PyErr_Format(PyExc_IndexError, "no slab %zd: the light field has %zu", k, lfio_lightfield_slab_count(self->lf));
        return NULL;
    }
    return lfio_lightfield_slab(self->lf, (size_t)k);
}

static PyObject *lightfield_slab_count(LightField *self, PyObject *args)
{
    (void)args;
    return PyLong_FromSize_t(lfio_lightfield_slab_count(self->lf));
}

static PyObject *lightfield_creator(LightField *self, PyObject *args)
{
    (void)args;
    return PyUnicode_FromString(lfio_lightfield_creator(self->lf));
}

static PyObject *lightfield_slab_desc(LightField *self, PyObject *args)
{
    Py_ssize_t k;
    if (!PyArg_ParseTuple(args, "n:slab_desc", &k))
        return NULL;
    const lfio_slab *s = slab_at(self, k);
    if (s == NULL)
        return NULL;
    const lfio_slab_desc *d = lfio_slab_get_desc(s);
    return Py_BuildValue("{s:s,s:N,s:N,s:N,s:I,s:I,s:I,s:s,s:d}", "name", d->name, "origin",
                         ilfpy__tuple(d->origin, 3), "u", ilfpy__tuple(d->u, 3), "v", ilfpy__tuple(d->v, 3), "nu",
                         (unsigned)d->nu, "nv", (unsigned)d->nv, "n", (unsigned)d->n, "units",
                         d->units == LFIO_UNITS_RELATIVE ? "relative" : "radiance", "mask_threshold",
                         (double)d->mask_threshold);
}

/* A read-only view of slab k's radiance, [dir][j][i][rgb], holding a reference to self. */
static PyObject *lightfield_slab_radiance(LightField *self, PyObject *args)
{
    Py_ssize_t k;
    if (!PyArg_ParseTuple(args, "n:slab_radiance", &k))
        return NULL;
    const lfio_slab *s = slab_at(self, k);
    if (s == NULL)
        return NULL;
    const lfio_slab_desc *d = lfio_slab_get_desc(s);
    npy_intp dims[4] = {(npy_intp)lfio_slab_dir_count(s), d->nv, d->nu, 3};
    PyObject *a = PyArray_New(&PyArray_Type, 4, dims, NPY_FLOAT, NULL, (void *)lfio_slab_radiance(s), 0,
                              NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED, NULL);
    if (a == NULL)
        return NULL;
    Py_INCREF(self);
    if (PyArray_SetBaseObject((PyArrayObject *)a, (PyObject *)self) < 0) {
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

static PyObject *lightfield_slab_irradiance(LightField *self, PyObject *args)
{
    Py_ssize_t k;
    double st[2], e[3];
    if (!PyArg_ParseTuple(args, "ndd:slab_irradiance", &k, &st[0], &st[1]))
        return NULL;
    const lfio_slab *s = slab_at(self, k);
    if (s == NULL)
        return NULL;
    lfio_status rc = lfio_slab_irradiance(s, st[0], st[1], e);
    return rc == LFIO_OK ? ilfpy__tuple(e, 3) : ilfpy__raise_lfio(rc);
}

static PyObject *lightfield_slab_radiance_at(LightField *self, PyObject *args)
{
    Py_ssize_t k;
    double st[2], w[3];
    int interpolate = 1;
    if (!PyArg_ParseTuple(args, "ndd(ddd)|p:slab_radiance_at", &k, &st[0], &st[1], &w[0], &w[1], &w[2], &interpolate))
        return NULL;
    const lfio_slab *s = slab_at(self, k);
    if (s == NULL)
        return NULL;
    float rgb[3];
    lfio_status rc = interpolate ? lfio_slab_radiance_interp(s, st[0], st[1], w, rgb)
                                 : lfio_slab_radiance_nearest(s, st[0], st[1], w, rgb);
    double out[3] = {rgb[0], rgb[1], rgb[2]};
    return rc == LFIO_OK ? ilfpy__tuple(out, 3) : ilfpy__raise_lfio(rc);
}

static PyObject *lightfield_slab_position(LightField *self, PyObject *args)
{
    Py_ssize_t k;
    unsigned i, j;
    if (!PyArg_ParseTuple(args, "nII:slab_position", &k, &i, &j))
        return NULL;
    const lfio_slab *s = slab_at(self, k);
    if (s == NULL)
        return NULL;
    double x[3];
    lfio_status rc = lfio_slab_position(s, i, j, x);
    return rc == LFIO_OK ? ilfpy__tuple(x, 3) : ilfpy__raise_lfio(rc);
}

static PyMethodDef lightfield_methods[] = {
    {"slab_count", (PyCFunction)lightfield_slab_count, METH_NOARGS, "slab_count() -> int"},
    {"creator", (PyCFunction)lightfield_creator, METH_NOARGS, "creator() -> str: the program that wrote the file"},
    {"slab_desc", (PyCFunction)lightfield_slab_desc, METH_VARARGS, "slab_desc(k) -> dict: slab k's description"},
    {"slab_radiance", (PyCFunction)lightfield_slab_radiance, METH_VARARGS,
     "slab_radiance(k) -> read-only float32 array [4 n^2, nv, nu, 3] of slab k (a view)"},
    {"slab_irradiance", (PyCFunction)lightfield_slab_irradiance, METH_VARARGS,
     "slab_irradiance(k, s, t) -> (r, g, b): W m^-2 through slab k at (s, t) from its front hemisphere"},
    {"slab_radiance_at", (PyCFunction)lightfield_slab_radiance_at, METH_VARARGS,
     "slab_radiance_at(k, s, t, w, interpolate=True) -> (r, g, b) in world direction w"},
    {"slab_position", (PyCFunction)lightfield_slab_position, METH_VARARGS,
     "slab_position(k, i, j) -> (x, y, z): the world centre of position (i, j)"},
    {NULL, NULL, 0, NULL}};

static PyTypeObject lightfield_type = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "_ilfkit.LightField",
    .tp_basicsize = sizeof(LightField),
    .tp_dealloc = (destructor)lightfield_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A light field file read whole (made by read_lightfield()); ilfkit.LightField wraps it.",
    .tp_methods = lightfield_methods,
};

int ilfpy__lightfield_add_type(PyObject *m)
{
    if (PyType_Ready(&lightfield_type) < 0)
        return -1;
    Py_INCREF(&lightfield_type);
    if (PyModule_AddObject(m, "LightField", (PyObject *)&lightfield_type) < 0) {
        Py_DECREF(&lightfield_type);
        return -1;
    }
    return 0;
}

static PyObject *read_lightfield(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *path;
    if (!PyArg_ParseTuple(args, "O&:read_lightfield", PyUnicode_FSConverter, &path))
        return NULL;
    lfio_lightfield *lf = NULL;
    lfio_status s;
    Py_BEGIN_ALLOW_THREADS
    s = lfio_lightfield_read(PyBytes_AS_STRING(path), &lf);
    Py_END_ALLOW_THREADS
    Py_DECREF(path);
    if (s != LFIO_OK)
        return ilfpy__raise_lfio(s);
    LightField *obj = PyObject_New(LightField, &lightfield_type);
    if (obj == NULL) {
        lfio_lightfield_destroy(lf);
        return NULL;
    }
    obj->lf = lf;
    return (PyObject *)obj;
}

/* ------------------------------------------------------------ partition */

/* Checks level n as the partition does. @return 0, or -1 with ValueError. */
static int check_level(unsigned long n)
{
    if (n < 1 || n > LFIO_PART_MAX_N) {
        PyErr_Format(PyExc_ValueError, "partition level %lu is not in 1..%u", n, LFIO_PART_MAX_N);
        return -1;
    }
    return 0;
}

/* @return obj as a C-contiguous array of type with last dimension `last` (0: any 1-D shape), or NULL. */
static PyArrayObject *as_array(PyObject *obj, int type, npy_intp last, const char *what)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(obj, type, last ? 2 : 1, last ? 2 : 1, NPY_ARRAY_IN_ARRAY);
    if (a != NULL && last && PyArray_DIM(a, 1) != last) {
        PyErr_Format(PyExc_ValueError, "%s must have shape (N, %zd), not (N, %zd)", what, (Py_ssize_t)last,
                     (Py_ssize_t)PyArray_DIM(a, 1));
        Py_CLEAR(a);
    }
    return a;
}

static PyObject *part_id(PyObject *self, PyObject *args)
{
    (void)self;
    unsigned long n;
    PyObject *obj;
    if (!PyArg_ParseTuple(args, "kO:part_id", &n, &obj) || check_level(n) < 0)
        return NULL;
    PyArrayObject *d = as_array(obj, NPY_DOUBLE, 3, "directions");
    if (d == NULL)
        return NULL;
    npy_intp count = PyArray_DIM(d, 0);
    PyArrayObject *out = (PyArrayObject *)PyArray_SimpleNew(1, &count, NPY_UINT64);
    const double *dir = PyArray_DATA(d);
    for (npy_intp k = 0; out != NULL && k < count; k++)
        if (!lfio_part_id((uint32_t)n, dir + 3 * k, (uint64_t *)PyArray_DATA(out) + k)) {
            PyErr_Format(PyExc_ValueError, "direction %zd is zero or not finite", (Py_ssize_t)k);
            Py_CLEAR(out);
        }
    Py_DECREF(d);
    return (PyObject *)out;
}

/* What one id gives: `per` doubles at out. @return 1, or 0 if id is not a solid angle of level n. */
typedef int (*id_fn)(uint32_t n, uint64_t id, double *out);

static int id_centroid(uint32_t n, uint64_t id, double *out) { return lfio_part_centroid(n, id, out); }
static int id_vertices(uint32_t n, uint64_t id, double *out) { return lfio_part_vertices(n, id, (double(*)[3])out); }
static int id_solid_angle(uint32_t n, uint64_t id, double *out)
{
    *out = lfio_part_solid_angle(n, id);
    return *out > 0.0;
}

/* Applies fn to every id of obj at level n: an array of shape (N,) + tail (nd_tail dims, `per` doubles). */
static PyObject *map_ids(PyObject *args, const char *format, id_fn fn, int nd_tail, const npy_intp *tail)
{
    unsigned long n;
    PyObject *obj;
    if (!PyArg_ParseTuple(args, format, &n, &obj) || check_level(n) < 0)
        return NULL;
    PyArrayObject *ids = as_array(obj, NPY_UINT64, 0, "ids");
    if (ids == NULL)
        return NULL;
    npy_intp dims[3] = {PyArray_DIM(ids, 0), nd_tail > 0 ? tail[0] : 0, nd_tail > 1 ? tail[1] : 0}, per = 1;
    for (int k = 0; k < nd_tail; k++)
        per *= tail[k];
    PyArrayObject *out = (PyArrayObject *)PyArray_SimpleNew(1 + nd_tail, dims, NPY_DOUBLE);
    const uint64_t *id = PyArray_DATA(ids);
    for (npy_intp k = 0; out != NULL && k < dims[0]; k++)
        if (!fn((uint32_t)n, id[k], (double *)PyArray_DATA(out) + per * k)) {
            PyErr_Format(PyExc_ValueError, "id %llu (element %zd) is not a solid angle of level %lu (0..%llu)",
                         (unsigned long long)id[k], (Py_ssize_t)k, n, (unsigned long long)lfio_part_count(n) - 1);
            Py_CLEAR(out);
        }
    Py_DECREF(ids);
    return (PyObject *)out;
}

static PyObject *part_centroid(PyObject *self, PyObject *args)
{
    (void)self;
    npy_intp tail[1] = {3};
    return map_ids(args, "kO:part_centroid", id_centroid, 1, tail);
}

static PyObject *part_vertices(PyObject *self, PyObject *args)
{
    (void)self;
    npy_intp tail[2] = {3, 3};
    return map_ids(args, "kO:part_vertices", id_vertices, 2, tail);
}

static PyObject *part_solid_angle(PyObject *self, PyObject *args)
{
    (void)self;
    return map_ids(args, "kO:part_solid_angle", id_solid_angle, 0, NULL);
}

PyMethodDef ilfpy__lightfield_methods[] = {
    {"read_lightfield", read_lightfield, METH_VARARGS, "read_lightfield(path) -> LightField: a light field file, read whole"},
    {"part_id", part_id, METH_VARARGS, "part_id(n, directions (N, 3)) -> uint64 (N,): the solid angle of each direction"},
    {"part_centroid", part_centroid, METH_VARARGS, "part_centroid(n, ids (N,)) -> (N, 3): representative directions"},
    {"part_vertices", part_vertices, METH_VARARGS, "part_vertices(n, ids (N,)) -> (N, 3, 3): corner directions"},
    {"part_solid_angle", part_solid_angle, METH_VARARGS, "part_solid_angle(n, ids (N,)) -> (N,): steradians"},
    {NULL, NULL, 0, NULL}};
