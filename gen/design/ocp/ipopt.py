"""The IPOPT problem of a transcribed optimal control problem (cyipopt): its
callbacks are the library's evaluations (OptimalControl._call), its
sparsity the assembly's index tables; IPOPT's outcome in plain words."""
from __future__ import annotations

import numpy as np

from ...core.errors import InputError
from ...core.optional import require
from .guess import row_scaling

__all__ = ["IPOPT_MESSAGES", "run_ipopt", "status_message"]

# IPOPT's return statuses in plain words (IpReturnCodes.h)
IPOPT_MESSAGES = {
    0: "solved: an optimum was found to the requested tolerance",
    1: "solved to the acceptable tolerance only (not the requested one)",
    2: "the problem is infeasible: IPOPT converged to a point that violates the "
       "constraints least, not to a feasible one; check the bounds, the initial and final "
       "values, the path constraints and the duration",
    3: "stopped: the search direction became too small (the problem may be badly scaled)",
    4: "the iterates diverged: a variable grew without bound (add bounds)",
    5: "stopped at the user's request",
    6: "a feasible point was found (the objective was not minimised further)",
    -1: "not solved: the maximum number of iterations was reached "
        "(raise max_iter, or give a better guess)",
    -2: "not solved: the restoration phase failed to find a feasible point "
        "(the problem is likely infeasible)",
    -3: "not solved: an error in the step computation (the problem may be singular)",
    -4: "not solved: the maximum CPU time was reached",
    -5: "not solved: the maximum wall time was reached",
    -10: "not solved: not enough degrees of freedom (more equality constraints than "
         "variables: the initial, final and instance constraints over-determine the problem)",
    -11: "not solved: invalid problem definition",
    -12: "not solved: an invalid IPOPT option",
    -13: "not solved: a NaN or infinite value was computed (the model is undefined at "
         "some iterate; add bounds)",
}


def cyipopt():
    """The cyipopt module (MissingDependencyError naming the ocp extra)."""
    return require("cyipopt", "gen.OptimalControl")


def _problem_class(ocp, hessian, iters):
    """The cyipopt problem object's class over ocp's evaluations."""
    what = ocp._what
    n, mrows = ocp._lay.n, ocp._m_rows
    nj, nh = len(ocp._jrows), len(ocp._hrows)

    class NLP:
        def objective(self, z):
            return float(ocp._call(what["objective"], z, 1)[0])

        def gradient(self, z):
            return ocp._call(what["gradient"], z, n)

        def constraints(self, z):
            return ocp._call(what["constraints"], z, mrows)

        def jacobian(self, z):
            return ocp._call(what["jacobian"], z, nj)

        def jacobianstructure(self):
            return ocp._jrows, ocp._jcols

        def intermediate(self, alg_mod, iter_count, obj_value, inf_pr, inf_du, *args):
            iters[0] = iter_count
            if iter_count == 0:
                iters[1] = (float(inf_pr), float(inf_du))
            return True

    if hessian == "exact":
        def hess(self, z, lagrange, obj_factor):
            return ocp._call(what["hessian"], z, nh, np.asarray(lagrange, float),
                             float(obj_factor))

        def hstruct(self):
            return ocp._hrows, ocp._hcols
        NLP.hessian = hess
        NLP.hessianstructure = hstruct
    return NLP


def run_ipopt(ocp, z0, lb, ub, hessian, ipopt_options):
    """Solve ocp's assembled problem from z0 within the bounds: (z, IPOPT's
    info with "first_iterate": IPOPT's (inf_pr, inf_du) at iteration 0,
    the iterations)."""
    ipopt = cyipopt()
    iters = [0, (float("nan"), float("nan"))]
    nlp = ipopt.Problem(n=ocp._lay.n, m=ocp._m_rows,
                        problem_obj=_problem_class(ocp, hessian, iters)(),
                        lb=lb, ub=ub, cl=ocp._cl, cu=ocp._cu)
    nlp.set_problem_scaling(1.0, None, row_scaling(ocp, z0))
    # user-scaling: the point rows by h over their slopes' coefficients
    # (guess.row_scaling). MUMPS's permuting scaling (its default, a
    # maximum-weight matching on the KKT matrix) is off: on these KKT
    # matrices it pairs pivots that are then delayed, and a factorization
    # of a few thousand unknowns took up to 0.8 s instead of a millisecond
    # (the brachistochrone of issue 47: 2.4 s -> 0.3 s for 44 iterations).
    # With a free final time, the initial and final values (variables fixed
    # by equal bounds) are equality constraints, as a transcription written
    # by hand has them: removed instead (IPOPT's default), the
    # brachistochrone took 46 iterations against 25. With a fixed duration
    # they are removed: kept, the fixed T would stay a variable coupled to
    # every slope (a dense row and column of the KKT matrix)
    opts = {"print_level": 0, "sb": "yes", "nlp_scaling_method": "user-scaling",
            "mumps_permuting_scaling": 0,
            "fixed_variable_treatment": "make_constraint" if ocp.free_time else "make_parameter"}
    if hessian == "limited-memory":
        opts["hessian_approximation"] = "limited-memory"
    opts.update(ipopt_options)
    for k, v in opts.items():
        try:
            nlp.add_option(k, v)
        except (TypeError, ValueError) as e:
            raise InputError(f"IPOPT option {k}={v!r}: {e}") from None
    z, info = nlp.solve(z0)
    info["first_iterate"] = iters[1]
    return z, info, iters[0]


def status_message(info):
    """(status, message in words) of IPOPT's info."""
    status = int(info["status"])
    msg = IPOPT_MESSAGES.get(status)
    if msg is None:
        raw = info.get("status_msg", b"")
        raw = raw.decode() if isinstance(raw, bytes) else str(raw)
        msg = f"IPOPT failed (status {status}): {raw}"
    return status, msg
