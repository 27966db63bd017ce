/*
 * gen_host_fast.h - the Python fast paths of Simulator.rhs and rhs_batch
 * (gen/sim/simulator.py). For rhs:
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
