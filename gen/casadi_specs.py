"""The CasADi face's function table: which functions the generated library
holds (names, inputs and outputs with their sparsity in CasADi's compressed
column storage, derivative blocks), from a gen.Model alone. Read by the
casadi backend (gen/backends.py) to render the library and by gen.casadi to
load it; it imports no stage of the pipeline."""
from __future__ import annotations

__all__ = ["NAMES", "function_specs", "block_specs"]

#: the functions, in the order of the dict functions() returns
NAMES = ("rhs", "implicit", "step", "outputs", "constraints")


def _dense(m, n):
    """CasADi's compressed column storage of a dense m x n matrix."""
    return [m, n, *[j * m for j in range(n + 1)], *[i for _ in range(n) for i in range(m)]]


def block_specs(model):
    """The functions whose Jacobian blocks the library computes."""
    return [{"name": n} for n in _with_jac(model)]


def _with_jac(model):
    m = model
    if m.mc or m.mv:
        return ["rhs"]
    return ["rhs", "implicit", "step"] + (["outputs"] if m.output_names else [])


def function_specs(model):
    """The functions of a model's CasADi library, as the template's data:
    [{"sym", "kind", "ins": [(name, sparsity, default)], "outs": [(name,
    sparsity)], "sz_w", "sz_out", ...}], with jac_, fwd1_ and adj1_ of
    each function that has derivatives (their "base", "mode", "blocks"
    and "nodiff": what the template's code needs)."""
    m = model
    p = m.name
    nx, nr, np_, mc, mv, ny = m.nx, m.nr, m.np, m.mc, m.mv, len(m.output_names)
    nan = "NAN"
    # defaults: r, p, h are NaN when missing (the call fails), t is 0
    x_, r_, p_, t_ = ("x", nx, 0), ("r", nr, nan if nr else 0), ("p", np_, nan if np_ else 0), \
        ("t", 1, 0)
    base = {
        "rhs": ([x_, r_, p_, t_], [("xdot", nx)]),
        "implicit": ([x_, ("xdot", nx, 0), r_, p_, t_], [("residual", nx + mc + mv)]),
        "step": ([x_, r_, p_, t_, ("h", 1, nan)], [("x_next", nx)]),
        "outputs": ([x_, r_, p_, t_], [("y", ny)]),
        "constraints": ([x_, p_, t_], [("c", mc + mv)]),
    }
    have = [n for n in NAMES if (n != "outputs" or ny) and (n != "constraints" or mc + mv)]
    with_jac = set(_with_jac(m))
    sz_out = max(1, nx + mc + mv, ny)
    specs = []
    for n in have:
        ins, outs = base[n]
        specs.append({"sym": f"{p}_{n}", "kind": n, "name": n,
                      "ins": [(a, _dense(k, 1), d) for a, k, d in ins],
                      "outs": [(a, _dense(k, 1)) for a, k in outs],
                      "sz_w": 0, "sz_out": sz_out, "nodiff": []})
        if n not in with_jac:
            continue
        nrow = outs[0][1]
        # the row-major blocks <p>_<n>_blocks writes: (input index, offset, columns)
        offs, blocks, nodiff_in = 0, [], []
        for i, (a, k, _) in enumerate(ins):
            if a in ("p", "t", "h"):
                nodiff_in.append((i, k))
            else:
                blocks.append((i, offs, k))
                offs += nrow * k
        sz_w = 2 * nx * nx + nx * nr + ny * nx + ny * nr + 1
        common = {"base": n, "nrow": nrow, "sz_out": sz_out, "sz_w": sz_w}
        nin, nout = len(ins), len(outs)
        nom = [(a, _dense(k, 1), 0) for a, k, _ in ins] + [(f"out_{a}", _dense(k, 1), 0)
                                                           for a, k in outs]
        # jac_<f>: the blocks jac_<out>_<in> (one output: block i is input i)
        specs.append({**common, "sym": f"jac_{p}_{n}", "kind": f"jac_{n}", "name": f"jac_{n}",
                      "mode": "jac", "ins": nom,
                      "outs": [(f"jac_{outs[0][0]}_{a}", _dense(nrow, k)) for a, k, _ in ins],
                      "nodiff": [i for i, _ in nodiff_in], "blocks": blocks})
        # fwd1_<f>: J times the forward seeds of the inputs
        specs.append({**common, "sym": f"fwd1_{p}_{n}", "kind": f"fwd1_{n}", "name": f"fwd1_{n}",
                      "mode": "fwd",
                      "ins": nom + [(f"fwd_{a}", _dense(k, 1), 0) for a, k, _ in ins],
                      "outs": [(f"fwd_{outs[0][0]}", _dense(nrow, 1))],
                      "nodiff": [(nin + nout + i, k) for i, k in nodiff_in],
                      "blocks": [(nin + nout + i, off, k) for i, off, k in blocks]})
        # adj1_<f>: J^T times the adjoint seed of the output
        specs.append({**common, "sym": f"adj1_{p}_{n}", "kind": f"adj1_{n}", "name": f"adj1_{n}",
                      "mode": "adj",
                      "ins": nom + [(f"adj_{outs[0][0]}", _dense(nrow, 1), 0)],
                      "outs": [(f"adj_{a}", _dense(k, 1)) for a, k, _ in ins],
                      "nodiff": nodiff_in, "blocks": blocks, "seed": nin + nout})
    return specs
