/*
 * py_radmap.c - reading a radiance-map file (radiance.h5, lfio/radmap.h) into
 * Python: its creator, scene and format, and each patch as the dict
 * ilfpy__map_dict() makes (arrays copied, so nothing outlives the lfio
 * object, which is freed before returning). The read runs without the GIL.
 */
#include "ilfpy.h"

/* @return a list of the map dicts of every patch of map. */
static PyObject *patch_list(const lfio_radmap *map)
{
    size_t count = lfio_radmap_count(map);
    PyObject *list = PyList_New((Py_ssize_t)count);
    for (size_t k = 0; list != NULL && k < count; k++) {
        lfio_radmap_patch p;
        lfio_status s = lfio_radmap_get(map, k, &p);
        PyObject *d = s == LFIO_OK ? ilfpy__map_dict(&p) : ilfpy__raise_lfio(s);
        if (d == NULL)
            Py_CLEAR(list);
        else
            PyList_SET_ITEM(list, (Py_ssize_t)k, d);
    }
    return list;
}

static PyObject *read_radiance(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *path;
    if (!PyArg_ParseTuple(args, "O&:read_radiance", PyUnicode_FSConverter, &path))
        return NULL;
    lfio_radmap *map = NULL;
    lfio_status s;
    Py_BEGIN_ALLOW_THREADS
    s = lfio_radmap_read(PyBytes_AS_STRING(path), &map);
    Py_END_ALLOW_THREADS
    Py_DECREF(path);
    if (s != LFIO_OK)
        return ilfpy__raise_lfio(s);
    PyObject *maps = patch_list(map);
    PyObject *out = maps == NULL ? NULL
                                 : Py_BuildValue("{s:s,s:s,s:i,s:N}", "creator", lfio_radmap_creator(map), "scene",
                                                 lfio_radmap_scene(map), "format_version",
                                                 lfio_radmap_format_version(map), "maps", maps);
    lfio_radmap_destroy(map);
    return out;
}

PyMethodDef ilfpy__radmap_methods[] = {
    {"read_radiance", read_radiance, METH_VARARGS,
     "read_radiance(path) -> dict: creator, scene, format_version and maps (a list of map dicts) of a "
     "radiance-map file."},
    {NULL, NULL, 0, NULL}};
