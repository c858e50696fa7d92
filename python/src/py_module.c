/*
 * py_module.c - the C extension _ilfkit, which the package ilfkit wraps: its
 * initialisation (NumPy's C API, the exception ilfkit.Error, the functions
 * of py_lightfield.c, py_relight.c and py_radmap.c). The helpers they share
 * are in py_common.c; conventions of the whole module are in ilfpy.h.
 */
#define ILFPY_DEFINE_ARRAY_API
#include "ilfpy.h"


#include <lfio/lfio.h>

static PyObject *version(PyObject *self, PyObject *args)
{
    (void)self;
    (void)args;
    return PyUnicode_FromString(lfio_version());
}

static PyMethodDef module_methods[] = {
    {"version", version, METH_NOARGS, "version() -> str: the version of the lfio library the module runs on."},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT, "_ilfkit",
    "The C extension of ilfkit: light fields (lfio), relighting (relight) and radiance maps. Use the package "
    "ilfkit, which wraps it.",
    -1, module_methods, NULL, NULL, NULL, NULL};

static int add_error(PyObject *m)
{
    ilfpy__error = PyErr_NewExceptionWithDoc(
        "ilfkit.Error",
        "A failure reported by ilfkit's libraries: the message names the file, object and problem; the "
        "attribute status names the library's status ('not found', 'invalid file format', 'invalid input', ...).",
        PyExc_RuntimeError, NULL);
    if (ilfpy__error == NULL)
        return -1;
    Py_INCREF(ilfpy__error);
    if (PyModule_AddObject(m, "Error", ilfpy__error) < 0) {
        Py_DECREF(ilfpy__error);
        return -1;
    }
    return 0;
}

PyMODINIT_FUNC PyInit__ilfkit(void)
{
    import_array();
    PyObject *m = PyModule_Create(&module_def);
    if (m == NULL)
        return NULL;
    if (add_error(m) < 0 || ilfpy__lightfield_add_type(m) < 0 ||
        PyModule_AddFunctions(m, ilfpy__lightfield_methods) < 0 ||
        PyModule_AddFunctions(m, ilfpy__relight_methods) < 0 || PyModule_AddFunctions(m, ilfpy__radmap_methods) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
