/*
 * gen_host_fast.c - the Python fast paths of Simulator.rhs,
 * Simulator.rhs_batch and a product's workspace calls: see gen_host_fast.h. One vectorcall (METH_FASTCALL)
 * function object per model table and path, its self a capsule holding the
 * table: the call checks its arguments' types and sizes with numpy's C API,
 * allocates the result (unless given), calls the model's eval_rhs (per
 * state for the batch, the GIL released) and returns. A cffi call costs a
 * from_buffer per array and a conversion per argument; this costs none.
 */
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>
#include <string.h>

#define EOMGEN_FAST_CAPSULE "eomgen_api"

static int eomgen_fast_type(void)
{
    return sizeof(eomgen_real) == sizeof(double) ? NPY_DOUBLE : NPY_FLOAT;
}

/* arr: an exact ndarray of eomgen_real, 1-D, n long, aligned, C-contiguous */
static int eomgen_fast_vector(PyObject *arr, npy_intp n)
{
    PyArrayObject *a = (PyArrayObject *)arr;
    return PyArray_CheckExact(arr) && PyArray_NDIM(a) == 1 && PyArray_DIM(a, 0) == n
        && PyArray_TYPE(a) == eomgen_fast_type()
        && PyArray_ISCARRAY_RO(a) && PyArray_ISNOTSWAPPED(a);
}

/* t: a Python float or int, into *t; 0 for anything else (no error set) */
static int eomgen_fast_time(PyObject *arg, double *t)
{
    if (!PyFloat_Check(arg) && !PyLong_Check(arg))
        return 0;
    *t = PyFloat_AsDouble(arg);
    if (*t == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        return 0;
    }
    return 1;
}

/* an optional vector (r, p): None (*v = NULL) or a vector of n; 0 else */
static int eomgen_fast_optional(PyObject *arg, npy_intp n, const eomgen_real **v)
{
    *v = NULL;
    if (arg == Py_None)
        return 1;
    if (!eomgen_fast_vector(arg, n))
        return 0;
    *v = (const eomgen_real *)PyArray_DATA((PyArrayObject *)arg);
    return 1;
}

static PyObject *eomgen_fast_rhs(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    const eomgen_api *api = (const eomgen_api *)PyCapsule_GetPointer(self, EOMGEN_FAST_CAPSULE);
    const eomgen_real *r = NULL;
    npy_intp nx;
    double t;
    PyObject *out;
    int st;
    if (api == NULL)
        return NULL;
    if (nargs < 2 || nargs > 3) {
        PyErr_SetString(PyExc_TypeError, "eomgen fast rhs: (t, x[, r])");
        return NULL;
    }
    nx = api->nx;
    if (!eomgen_fast_time(args[0], &t) || !eomgen_fast_vector(args[1], nx)
        || (nargs == 3 && !eomgen_fast_optional(args[2], api->nr, &r)))
        Py_RETURN_NONE;
    out = PyArray_SimpleNew(1, &nx, eomgen_fast_type());
    if (out == NULL)
        return NULL;
    st = api->eval_rhs((eomgen_real)t, (const eomgen_real *)PyArray_DATA((PyArrayObject *)args[1]),
                       r, NULL, (eomgen_real *)PyArray_DATA((PyArrayObject *)out), NULL);
    if (st) {
        Py_DECREF(out);
        Py_RETURN_NONE;
    }
    return out;
}

/* arr: an exact, writable ndarray of eomgen_real, 2-D (n, ncol), aligned,
 * C-contiguous */
static int eomgen_fast_matrix(PyObject *arr, npy_intp ncol, int writable)
{
    PyArrayObject *a = (PyArrayObject *)arr;
    return PyArray_CheckExact(arr) && PyArray_NDIM(a) == 2 && PyArray_DIM(a, 1) == ncol
        && PyArray_TYPE(a) == eomgen_fast_type()
        && (writable ? PyArray_ISCARRAY(a) : PyArray_ISCARRAY_RO(a))
        && PyArray_ISNOTSWAPPED(a);
}

/* rhs_batch(t, X, r, p, out) -> out (new when None), or None where it does
 * not apply (t not a number; X, r, p or out not exact arrays of the type,
 * shapes (N, nx), (nr,), (np,), (N, nx)) or a state fails (the caller's
 * general path then names it) */
static PyObject *eomgen_fast_rhs_batch(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    const eomgen_api *api = (const eomgen_api *)PyCapsule_GetPointer(self, EOMGEN_FAST_CAPSULE);
    const eomgen_real *x, *r, *p;
    eomgen_real *dxdt;
    npy_intp n, dims[2];
    long nx, i;
    double t;
    PyObject *out;
    int st = 0;
    if (api == NULL)
        return NULL;
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "eomgen fast rhs_batch: (t, X, r, p, out)");
        return NULL;
    }
    nx = api->nx;
    if (!eomgen_fast_time(args[0], &t) || !eomgen_fast_matrix(args[1], nx, 0)
        || !eomgen_fast_optional(args[2], api->nr, &r)
        || !eomgen_fast_optional(args[3], api->np, &p))
        Py_RETURN_NONE;
    n = PyArray_DIM((PyArrayObject *)args[1], 0);
    if (args[4] != Py_None) {
        if (!eomgen_fast_matrix(args[4], nx, 1) || PyArray_DIM((PyArrayObject *)args[4], 0) != n)
            Py_RETURN_NONE;
        out = args[4];
        Py_INCREF(out);
    } else {
        dims[0] = n;
        dims[1] = nx;
        out = PyArray_SimpleNew(2, dims, eomgen_fast_type());
        if (out == NULL)
            return NULL;
    }
    x = (const eomgen_real *)PyArray_DATA((PyArrayObject *)args[1]);
    dxdt = (eomgen_real *)PyArray_DATA((PyArrayObject *)out);
    /* the GIL released, as cffi's calls do: the caller holds X and out */
    Py_BEGIN_ALLOW_THREADS
    for (i = 0; i < (long)n && !st; ++i)
        st = api->eval_rhs((eomgen_real)t, x + i * nx, r, p, dxdt + i * nx, NULL);
    Py_END_ALLOW_THREADS
    if (st) {
        Py_DECREF(out);
        Py_RETURN_NONE;
    }
    return out;
}

static PyMethodDef eomgen_fast_rhs_batch_def = {
    "rhs_batch", (PyCFunction)(void (*)(void))eomgen_fast_rhs_batch, METH_FASTCALL,
    "rhs_batch(t, X, r, p, out) -> out, or None: the fast path of Simulator.rhs_batch"
};

static PyMethodDef eomgen_fast_rhs_def = {
    "rhs", (PyCFunction)(void (*)(void))eomgen_fast_rhs, METH_FASTCALL,
    "rhs(t, x, r=None) -> x', or None: the fast path of Simulator.rhs"
};

/* The end of every eomgen_fast_*_new: the function def bound to the capsule
 * cap (its reference taken over; NULL: none made), or NULL with the error
 * cleared (the caller takes the general path); the GIL the caller took
 * released. */
static void *eomgen_fast_made(PyMethodDef *def, PyObject *cap, PyGILState_STATE gil)
{
    PyObject *fn = NULL;
    if (cap != NULL) {
        fn = PyCFunction_NewEx(def, cap, NULL);
        Py_DECREF(cap);
    }
    if (fn == NULL)
        PyErr_Clear();
    PyGILState_Release(gil);
    return fn;
}

/* cffi calls these with the GIL released: take it for the Python API */
static void *eomgen_fast_new(const eomgen_api *api, PyMethodDef *def)
{
    PyObject *cap = NULL;
    PyGILState_STATE gil = PyGILState_Ensure();
    if (PyArray_API != NULL || _import_array() >= 0)
        cap = PyCapsule_New((void *)api, EOMGEN_FAST_CAPSULE, NULL);
    return eomgen_fast_made(def, cap, gil);
}

void *eomgen_fast_rhs_new(const eomgen_api *api)
{
    return eomgen_fast_new(api, &eomgen_fast_rhs_def);
}

void *eomgen_fast_rhs_batch_new(const eomgen_api *api)
{
    return eomgen_fast_new(api, &eomgen_fast_rhs_batch_def);
}

/* ---- a product's call on its workspace ---------------------------------- */

#define EOMGEN_FAST_CALL_CAPSULE "eomgen_call"

typedef int (*eomgen_fast_call1_fn)(void *, const eomgen_real *);
typedef int (*eomgen_fast_call2_fn)(void *, const eomgen_real *, const eomgen_real *);

typedef struct {
    uintptr_t fn;
    PyObject *owner;
    void *ws;
    int nargs;
    eomgen_real *buf[2];
    npy_intp n[2];
} eomgen_fast_call_ctx;

static void eomgen_fast_call_free(PyObject *cap)
{
    eomgen_fast_call_ctx *c =
        (eomgen_fast_call_ctx *)PyCapsule_GetPointer(cap, EOMGEN_FAST_CALL_CAPSULE);
    if (c == NULL)
        return;
    Py_XDECREF(c->owner);
    PyMem_Free(c);
}

/* f(a[, b]) -> fn's status, or None where an argument is not an exact
 * array of the type and size (nothing copied then) */
static PyObject *eomgen_fast_call(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    eomgen_fast_call_ctx *c =
        (eomgen_fast_call_ctx *)PyCapsule_GetPointer(self, EOMGEN_FAST_CALL_CAPSULE);
    int i, st;
    if (c == NULL)
        return NULL;
    if (nargs != c->nargs) {
        PyErr_SetString(PyExc_TypeError, "eomgen fast call: wrong number of arguments");
        return NULL;
    }
    for (i = 0; i < c->nargs; ++i)
        if (!eomgen_fast_vector(args[i], c->n[i]))
            Py_RETURN_NONE;
    for (i = 0; i < c->nargs; ++i)
        if (c->n[i] > 0)
            memcpy(c->buf[i], PyArray_DATA((PyArrayObject *)args[i]),
                   (size_t)c->n[i] * sizeof(eomgen_real));
    /* the GIL released, as cffi's calls do (the owner holds ws and the
     * buffers; a call on one workspace from two threads at once is the
     * caller's race, as through cffi) */
    Py_BEGIN_ALLOW_THREADS
    if (c->nargs == 1)
        st = ((eomgen_fast_call1_fn)c->fn)(c->ws, c->buf[0]);
    else
        st = ((eomgen_fast_call2_fn)c->fn)(c->ws, c->buf[0], c->buf[1]);
    Py_END_ALLOW_THREADS
    return PyLong_FromLong(st);
}

static PyMethodDef eomgen_fast_call_def = {
    "call", (PyCFunction)(void (*)(void))eomgen_fast_call, METH_FASTCALL,
    "call(a[, b]) -> status, or None: the fast path of a product's call"
};

void *eomgen_fast_call_new(uintptr_t fn, void *owner, void *ws, int nargs,
                           eomgen_real *buf0, long n0, eomgen_real *buf1, long n1)
{
    PyObject *cap = NULL;
    eomgen_fast_call_ctx *c;
    PyGILState_STATE gil;
    if (!fn || !owner || !ws || nargs < 1 || nargs > 2 || !buf0 || n0 < 0
        || (nargs == 2 && (!buf1 || n1 < 0)))
        return NULL;
    gil = PyGILState_Ensure();
    if (PyArray_API == NULL && _import_array() < 0)
        goto done;
    c = (eomgen_fast_call_ctx *)PyMem_Malloc(sizeof(*c));
    if (c == NULL)
        goto done;
    c->fn = fn;
    c->owner = (PyObject *)owner;
    Py_INCREF(c->owner);
    c->ws = ws;
    c->nargs = nargs;
    c->buf[0] = buf0;
    c->buf[1] = nargs == 2 ? buf1 : NULL;
    c->n[0] = (npy_intp)n0;
    c->n[1] = nargs == 2 ? (npy_intp)n1 : 0;
    cap = PyCapsule_New(c, EOMGEN_FAST_CALL_CAPSULE, eomgen_fast_call_free);
    if (cap == NULL) {
        Py_DECREF(c->owner);
        PyMem_Free(c);
    }
done:
    return eomgen_fast_made(&eomgen_fast_call_def, cap, gil);
}
