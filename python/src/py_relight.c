/*
 * py_relight.c - the relighting engine in Python: relight(scene, settings,
 * threads), which solves a scene file and returns its radiance maps, and
 * irradiance(scene, points, settings, threads), the irradiance at points.
 * Settings are the scene's "sampling" keys (relight/relight.h's table),
 * replacing the scene's own values.
 *
 * Invariants: the scene is loaded, run and freed without the GIL; the one
 * function run_engine() makes every call that runs the engine, so that a
 * change of the engine's calling convention is met there alone; results are
 * copied into new arrays before the solution is freed.
 */
#include "ilfpy.h"

#include <stdio.h>
#include <string.h>

#include <lfio/lightfield.h>
#include <relight/engine.h>

/* ------------------------------------------------------------ settings */

/* Reads one setting's value into *s: a method's name for the method, else a number within the setting's rule.
 * @return 0, or -1 with ValueError or TypeError. */
static int set_setting(rl_sampling *s, size_t k, PyObject *value)
{
    const rl_setting_info *set = rl_sampling_setting(k);
    char rule[128];
    rl_sampling_setting_rule(k, rule, sizeof rule);
    if (set->type == RL_SETTING_METHOD) {
        const char *name = PyUnicode_Check(value) ? PyUnicode_AsUTF8(value) : NULL;
        if (name == NULL || !rl_method_parse(name, &s->method)) {
            PyErr_Format(PyExc_ValueError, "sampling setting 'method': expected %s", rule);
            return -1;
        }
        return 0;
    }
    if (PyBool_Check(value) || !PyNumber_Check(value)) {
        PyErr_Format(PyExc_TypeError, "sampling setting '%s': expected a number", set->key);
        return -1;
    }
    double v = PyFloat_AsDouble(value);
    if (v == -1.0 && PyErr_Occurred())
        return -1;
    /* the bounds of values written as text: integers a double holds exactly, as a scene file's */
    if (!rl_sampling_setting_allows(k, v, 1) || (set->type != RL_SETTING_REAL && v != (double)(int64_t)v) ||
        !rl_sampling_set(s, k, v)) {
        PyErr_Format(PyExc_ValueError, "sampling setting '%s': %R is not %s", set->key, value, rule);
        return -1;
    }
    return 0;
}

/* Applies the dict settings (may be None) over *s. @return 0, or -1 with an exception naming the key. */
static int apply_settings(rl_sampling *s, PyObject *settings)
{
    PyObject *key, *value;
    Py_ssize_t pos = 0;
    while (settings != Py_None && PyDict_Next(settings, &pos, &key, &value)) {
        const char *name = PyUnicode_Check(key) ? PyUnicode_AsUTF8(key) : NULL;
        size_t k = name != NULL ? rl_sampling_setting_find(name) : rl_sampling_setting_count();
        if (k == rl_sampling_setting_count()) {
            PyErr_Format(PyExc_ValueError, "%R is not a sampling setting (docs/scene.md lists them)", key);
            return -1;
        }
        if (set_setting(s, k, value) < 0)
            return -1;
    }
    return 0;
}

/* ------------------------------------------------------------ the engine */

/* One run: the settings over the scene's own, what to compute, and what it gave. */
typedef struct engine_call {
    rl_job job;            /* the job the scene suggests, with the caller's settings and threads */
    unsigned threads;      /* 0: every core */
    const double *points;  /* irradiance: [count][6] x y z nx ny nz; NULL: relight */
    size_t count;
    double *irradiance;    /* irradiance: [count][3] */
    rl_scene *scene;       /* the scene loaded (the solution reads it) */
    rl_solution *solution; /* relight: the result */
} engine_call;

/*
 * Runs the engine on call->scene with call->job: irradiance at call->points,
 * or a relighting into call->solution.
 */
static rl_status run_engine(engine_call *call)
{
    if (call->points != NULL)
        return rl_irradiance(call->scene, &call->job, call->points, call->count, call->irradiance, NULL);
    return rl_relight(call->scene, &call->job, &call->solution);
}

/* Frees what call holds: the solution, then the scene it reads. */
static void engine_call_free(engine_call *call)
{
    rl_solution_destroy(call->solution);
    rl_scene_destroy(call->scene);
    call->solution = NULL;
    call->scene = NULL;
}

/* Raises ilfkit.Error for a failure st on scene file path, the path added when the message lacks it. */
static PyObject *raise_relight(rl_status st, const char *path)
{
    static const char *const names[] = {"ok", "bad argument", "out of memory", "input/output error", "invalid input",
                                        "internal error"};
    const char *msg = rl_errmsg();
    const char *name = (unsigned)st < sizeof names / sizeof names[0] ? names[st] : "error";
    if (strstr(msg, path) != NULL)
        return ilfpy__raise(name, msg);
    msg = msg[0] != '\0' ? msg : "cannot load the scene";
    size_t size = strlen(path) + strlen(msg) + 3;
    char *text = PyMem_Malloc(size);
    if (text == NULL)
        return PyErr_NoMemory();
    snprintf(text, size, "%s: %s", path, msg);
    ilfpy__raise(name, text);
    PyMem_Free(text);
    return NULL;
}

/*
 * Loads the scene file path, applies settings and runs call, without the GIL
 * while the library works. On failure call holds nothing.
 * @return 0, or -1 with an exception set.
 */
static int load_and_run(const char *path, PyObject *settings, engine_call *call)
{
    /* a setting out of its range is refused before a large scene is loaded for nothing */
    rl_sampling early;
    rl_sampling_default(&early);
    if (apply_settings(&early, settings) < 0)
        return -1;
    rl_status st;
    Py_BEGIN_ALLOW_THREADS
    rl_scene_load_options load;
    rl_scene_load_options_default(&load);
    load.threads = call->threads;
    st = rl_scene_load_with(path, &load, &call->scene);
    Py_END_ALLOW_THREADS
    if (st != RL_OK)
        return raise_relight(st, path), -1;
    /* the file's job (cell size, time budget, sampling), as `ilf relight`'s, with the caller's settings */
    rl_job_default(call->scene, &call->job);
    call->job.run.threads = call->threads;
    if (apply_settings(&call->job.sampling, settings) < 0) {
        engine_call_free(call);
        return -1;
    }
    Py_BEGIN_ALLOW_THREADS
    st = run_engine(call);
    Py_END_ALLOW_THREADS
    if (st != RL_OK) {
        raise_relight(st, path);
        engine_call_free(call);
        return -1;
    }
    return 0;
}

/* ------------------------------------------------------------ results */

/* @return the dict of map k of solution (ilfpy__map_dict()), its cells copied out of the solution. */
static PyObject *solution_map(const rl_solution *solution, size_t k)
{
    rl_map_info info;
    if (rl_solution_map_info(solution, k, &info) != RL_OK)
        return ilfpy__raise("bad argument", rl_errmsg());
    size_t n = info.ncells;
    /* one block: ij (2 uint32), area (1 double), centre (3 doubles), irradiance and radiosity (3 floats each) */
    char *block = PyMem_Malloc(n ? n * (2 * sizeof(uint32_t) + 4 * sizeof(double) + 6 * sizeof(float)) : 1);
    if (block == NULL)
        return PyErr_NoMemory();
    double *area = (double *)block, *centre = area + n;
    float *irr = (float *)(centre + 3 * n), *rad = irr + 3 * n;
    uint32_t *ij = (uint32_t *)(rad + 3 * n);
    PyObject *d = NULL;
    if (rl_solution_map_cells(solution, k, ij, area, centre, irr, rad) != RL_OK)
        ilfpy__raise("bad argument", rl_errmsg());
    else {
        lfio_radmap_patch p = {info.label, info.polygon, info.nvertices, info.vertices, {0}, {0}, {0}, {0},
                               info.cell_size, info.u0, info.v0, info.nu, info.nv, info.ncells, ij, area, centre,
                               irr, rad, {0}, {0}};
        memcpy(p.origin, info.origin, sizeof p.origin);
        memcpy(p.e1, info.e1, sizeof p.e1);
        memcpy(p.e2, info.e2, sizeof p.e2);
        memcpy(p.normal, info.normal, sizeof p.normal);
        memcpy(p.albedo, info.albedo, sizeof p.albedo);
        memcpy(p.emission, info.emission, sizeof p.emission);
        d = ilfpy__map_dict(&p);
    }
    PyMem_Free(block);
    return d;
}

/* @return a dict of pass k's statistics. */
static PyObject *solution_pass(const rl_solution *solution, uint32_t k)
{
    rl_pass_stats s;
    if (rl_solution_pass_stats(solution, k, &s) != RL_OK)
        return ilfpy__raise("bad argument", rl_errmsg());
    return Py_BuildValue("{s:d,s:d,s:K,s:K,s:K,s:K}", "wall_seconds", s.wall_seconds, "cpu_seconds", s.cpu_seconds,
                         "samples", (unsigned long long)s.samples, "rays_cast", (unsigned long long)s.rays_cast,
                         "rays_kept", (unsigned long long)s.rays_kept, "rays_free",
                         (unsigned long long)s.rays_free);
}

/* @return a list of fn(solution, k) for k < count, or NULL. */
static PyObject *solution_list(const rl_solution *solution, size_t count,
                               PyObject *(*fn)(const rl_solution *, size_t))
{
    PyObject *list = PyList_New((Py_ssize_t)count);
    for (size_t k = 0; list != NULL && k < count; k++) {
        PyObject *item = fn(solution, k);
        if (item == NULL)
            Py_CLEAR(list);
        else
            PyList_SET_ITEM(list, (Py_ssize_t)k, item);
    }
    return list;
}

static PyObject *pass_at(const rl_solution *solution, size_t k) { return solution_pass(solution, (uint32_t)k); }

/* ------------------------------------------------------------ entry points */

static PyObject *relight(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *path, *settings;
    engine_call call = {.threads = 0};
    if (!PyArg_ParseTuple(args, "O&O!I:relight", PyUnicode_FSConverter, &path, &PyDict_Type, &settings, &call.threads))
        return NULL;
    PyObject *out = NULL;
    if (load_and_run(PyBytes_AS_STRING(path), settings, &call) == 0) {
        PyObject *maps = solution_list(call.solution, rl_solution_map_count(call.solution), solution_map);
        PyObject *passes = maps ? solution_list(call.solution, rl_solution_pass_count(call.solution), pass_at) : NULL;
        if (passes != NULL)
            out = Py_BuildValue("{s:N,s:N}", "maps", maps, "passes", passes); /* takes both, even on failure */
        else
            Py_XDECREF(maps);
        engine_call_free(&call);
    }
    Py_DECREF(path);
    return out;
}

static PyObject *irradiance(PyObject *self, PyObject *args)
{
    (void)self;
    PyObject *path, *settings, *obj;
    engine_call call = {.threads = 0};
    if (!PyArg_ParseTuple(args, "O&OO!I:irradiance", PyUnicode_FSConverter, &path, &obj, &PyDict_Type, &settings,
                          &call.threads))
        return NULL;
    PyArrayObject *pts = (PyArrayObject *)PyArray_FROMANY(obj, NPY_DOUBLE, 2, 2, NPY_ARRAY_IN_ARRAY);
    PyArrayObject *out = NULL;
    if (pts != NULL && PyArray_DIM(pts, 1) != 6)
        PyErr_SetString(PyExc_ValueError, "points must have shape (N, 6): x y z nx ny nz");
    else if (pts != NULL) {
        npy_intp dims[2] = {PyArray_DIM(pts, 0), 3};
        out = (PyArrayObject *)PyArray_SimpleNew(2, dims, NPY_DOUBLE);
        call.points = PyArray_DATA(pts);
        call.count = (size_t)dims[0];
        call.irradiance = out ? PyArray_DATA(out) : NULL;
        if (out != NULL && load_and_run(PyBytes_AS_STRING(path), settings, &call) < 0)
            Py_CLEAR(out);
        engine_call_free(&call);
    }
    Py_XDECREF(pts);
    Py_DECREF(path);
    return (PyObject *)out;
}

PyMethodDef ilfpy__relight_methods[] = {
    {"relight", relight, METH_VARARGS,
     "relight(scene, settings: dict, threads: int) -> dict: maps (a list of map dicts) and passes (statistics)"},
    {"irradiance", irradiance, METH_VARARGS,
     "irradiance(scene, points (N, 6), settings: dict, threads: int) -> (N, 3) W m^-2"},
    {NULL, NULL, 0, NULL}};
