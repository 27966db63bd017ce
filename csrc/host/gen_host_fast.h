/*
 * gen_host_fast.h - the Python fast paths of Simulator.rhs and rhs_batch
 * (gen/sim/simulator.py), and of a product's calls on its workspace
 * (gen.EKF's predict, update and step). For rhs:
 * a CPython function, made once per model table, that takes (t, x, r) and
 * returns x' as a new numpy array, or None where it does not apply (x or r
 * not an exact, aligned, C-contiguous array of the model's scalar type and
 * size) or where the model returns a nonzero status: the caller then takes
 * its general path, which converts, checks and raises in the user's names.
 * Hand-written; part of eomgen's Python host module (gen/toolchain/host.py). Also
 * the module's cffi declarations: plain C.
 */

/* a new reference to the function (a PyObject *), bound to api; NULL if
 * it cannot be made (numpy's C API not importable): the general path then */
void *eomgen_fast_rhs_new(const eomgen_api *api);

/* the same for rhs_batch(t, X, r, p, out): a number t, X (N, nx), r and p
 * None or vectors, out None or (N, nx), all exact C-contiguous arrays of the
 * type; returns out (a new array for None) or None (the general path) */
void *eomgen_fast_rhs_batch_new(const eomgen_api *api);

/* a product's call fn(ws, a) (nargs 1) or fn(ws, a, b) (nargs 2), an
 * int (*)(void *, const eomgen_real *[, const eomgen_real *]) of its
 * library at the address fn: the function takes a (and b), each an exact,
 * aligned, C-contiguous 1-D array of the type and of n0 (n1) entries,
 * copies them into buf0 (buf1: the workspace's own buffers, which the call
 * reads) and returns fn's status as an int; anything else returns None
 * (the caller's general path converts, checks and names). ws, buf0 and buf1
 * belong to owner (a PyObject *), which the function keeps alive. */
void *eomgen_fast_call_new(uintptr_t fn, void *owner, void *ws, int nargs,
                           eomgen_real *buf0, long n0, eomgen_real *buf1, long n1);
