"""Batch entry points for Python: loops in C over the public API, compiled
into the cffi module (not into the model library, whose API is the same
for every backend). One call evaluates N states; the GIL is released for
the whole loop (cffi releases it around every C call).

    <p>_rhs_batch(n, t, x, r, r_stride, p, p_stride, dxdt)         -> index of the first failure or -1, status in *st
    <p>_mass_matrix_batch(n, q, q_stride, p, p_stride, M)
    <p>_linearize_batch(n, x, r, r_stride, p, p_stride, t, A, B)

Strides are in elements: 0 means "the same vector for every state".
"""
from __future__ import annotations

__all__ = ["batch_cdef", "batch_source"]


def batch_cdef(p: str) -> str:
    R = f"{p}_real"
    return "\n".join([
        f"int {p}_rhs_batch(int n, const {R} *t, int t_stride, const {R} *x, const {R} *r, "
        f"int r_stride, const {R} *p, int p_stride, {R} *dxdt, int *status);",
        f"int {p}_mass_matrix_batch(int n, const {R} *q, int q_stride, const {R} *p, "
        f"int p_stride, {R} *M, int *status);",
        f"int {p}_linearize_batch(int n, const {R} *x, const {R} *r, int r_stride, "
        f"const {R} *p, int p_stride, {R} t, {R} *A, {R} *B, int *status);",
    ]) + "\n"


def batch_source(p: str, nu: int, nx: int, ns: int, nr: int) -> str:
    """C source of the batch loops (returns the index of the first failing
    state, or -1 when all succeeded; *status holds that state's code)."""
    R = f"{p}_real"
    nrB = max(1, ns * nr)
    return f"""
int {p}_rhs_batch(int n, const {R} *t, int t_stride, const {R} *x, const {R} *r,
                  int r_stride, const {R} *p, int p_stride, {R} *dxdt, int *status)
{{
    int i, st;
    *status = 0;
    for (i = 0; i < n; ++i) {{
        st = {p}_eval_rhs(t ? t[(long)i * t_stride] : 0, x + (long)i * {nx},
                          r ? r + (long)i * r_stride : 0, p ? p + (long)i * p_stride : 0,
                          dxdt + (long)i * {nx}, 0);
        if (st) {{ *status = st; return i; }}
    }}
    return -1;
}}

int {p}_mass_matrix_batch(int n, const {R} *q, int q_stride, const {R} *p, int p_stride,
                          {R} *M, int *status)
{{
    int i, st;
    *status = 0;
    for (i = 0; i < n; ++i) {{
        st = {p}_eval_mass_matrix(q + (long)i * q_stride, p ? p + (long)i * p_stride : 0, 0,
                                  M + (long)i * {nu * nu});
        if (st) {{ *status = st; return i; }}
    }}
    return -1;
}}

int {p}_linearize_batch(int n, const {R} *x, const {R} *r, int r_stride, const {R} *p,
                        int p_stride, {R} t, {R} *A, {R} *B, int *status)
{{
    int i, st;
    {R} Bdummy[{nrB}];
    *status = 0;
    for (i = 0; i < n; ++i) {{
        st = {p}_linearize(x + (long)i * {nx}, r ? r + (long)i * r_stride : 0,
                           p ? p + (long)i * p_stride : 0, t, A + (long)i * {ns * ns},
                           {"B + (long)i * " + str(ns * nr) if nr else "Bdummy"});
        if (st) {{ *status = st; return i; }}
    }}
    (void)Bdummy;
    return -1;
}}
"""
