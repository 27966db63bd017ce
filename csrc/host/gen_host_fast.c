/*
 * gen_host_fast.c - the Python fast path of Simulator.rhs: see
 * gen_host_fast.h. One vectorcall (METH_FASTCALL) function object per model
 * table, its self a capsule holding the table: the call checks its
 * arguments' types and sizes with numpy's C API, allocates x', calls the
 * model's eval_rhs with the GIL held (a call of well under a microsecond)
 * and returns. A cffi call costs a from_buffer per array and a conversion
 * per argument; this costs none.
 */
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

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
    if (!PyFloat_Check(args[0]) && !PyLong_Check(args[0]))
        Py_RETURN_NONE;
    t = PyFloat_AsDouble(args[0]);
    if (t == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        Py_RETURN_NONE;
    }
    if (!eomgen_fast_vector(args[1], nx))
        Py_RETURN_NONE;
    if (nargs == 3 && args[2] != Py_None) {
        if (!eomgen_fast_vector(args[2], api->nr))
            Py_RETURN_NONE;
        r = (const eomgen_real *)PyArray_DATA((PyArrayObject *)args[2]);
    }
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

static PyMethodDef eomgen_fast_rhs_def = {
    "rhs", (PyCFunction)(void (*)(void))eomgen_fast_rhs, METH_FASTCALL,
    "rhs(t, x, r=None) -> x', or None: the fast path of Simulator.rhs"
};

/* cffi calls this with the GIL released: take it for the Python API */
void *eomgen_fast_rhs_new(const eomgen_api *api)
{
    PyObject *cap, *fn = NULL;
    PyGILState_STATE gil = PyGILState_Ensure();
    if (PyArray_API == NULL && _import_array() < 0)
        goto done;
    cap = PyCapsule_New((void *)api, EOMGEN_FAST_CAPSULE, NULL);
    if (cap == NULL)
        goto done;
    fn = PyCFunction_NewEx(&eomgen_fast_rhs_def, cap, NULL);
    Py_DECREF(cap);
done:
    if (fn == NULL)
        PyErr_Clear();    /* the caller takes the general path */
    PyGILState_Release(gil);
    return fn;
}
