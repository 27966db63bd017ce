"""Shared numeric helpers for the tests."""
import numpy as np


def rel_err(c, s):
    """max |c - s| relative to max |s| (absolute when s is all zero)."""
    c = np.asarray(c, dtype=float)
    s = np.asarray(s, dtype=float)
    assert c.shape == s.shape, (c.shape, s.shape)
    if c.size == 0:
        return 0.0
    scale = np.max(np.abs(s))
    d = np.max(np.abs(c - s))
    return float(d / scale) if scale > 0 else float(d)


def crossing_times(t, y, direction=+1):
    """Times where y crosses zero in the given direction, by cubic
    interpolation through the four samples around each crossing."""
    out = []
    for i in range(1, len(y) - 2):
        if direction > 0 and y[i] <= 0 < y[i + 1] or direction < 0 and y[i] >= 0 > y[i + 1]:
            tt = t[i - 1:i + 3]
            yy = y[i - 1:i + 3]
            c = np.polyfit(tt - t[i], yy, 3)
            roots = np.roots(c)
            h = t[i + 1] - t[i]
            good = [r.real + t[i] for r in roots
                    if abs(r.imag) < 1e-12 and -1e-12 <= r.real <= h + 1e-12]
            if good:
                out.append(min(good, key=lambda v: abs(v - t[i])))
    return np.array(out)


def pendulum_state(theta, thetadot, L, order):
    """A consistent state of the nonminimal pendulum (gravity along +x,
    x = L cos(theta), y = L sin(theta)). order: 'kane' -> [q2, q1, u2, u1],
    'lagrange' -> [q1, q2, q1', q2']."""
    x, y = L * np.cos(theta), L * np.sin(theta)
    vx, vy = -L * np.sin(theta) * thetadot, L * np.cos(theta) * thetadot
    if order == "kane":
        return np.array([y, x, vy, vx])
    return np.array([x, y, vx, vy])


def ldlt_solve_c(prefix, n, nonzero, real, rtol_macro="GEN_RT_PIVOT_RTOL"):
    """C99 source of

        static int <prefix>_mass_solve(const real *M, const real *f, real *x)

    solving M x = f for a symmetric positive definite M (row-major; only the
    lower triangle and the diagonal are read). Returns GEN_RT_ERR_SINGULAR
    when a pivot is not positive relative to the largest diagonal entry
    (also for NaN); x is written only on success. Rendered from the
    template the generated models use (templates/c/mass_solve.j2), for the
    tests of the solve on its own."""
    from gen.codegen.templating import template_env
    from gen.plan.ldlt import ldlt_program, ldlt_statements
    macro = template_env().get_template("c/mass_solve.j2").module.mass_solve
    plan = ldlt_program(n, nonzero)
    return str(macro(prefix, real, plan, ldlt_statements(plan), rtol_macro))


def cortex_m4_tables(src, cfile, obj, flags, flash):
    """Compile a tracker's float sources for the Cortex-M4F (hard float) and
    check its tables are const data only (nothing in .data/.bss, .rodata at
    least the footprint's flash bytes); the object's section sizes, or None
    without arm-none-eabi-gcc."""
    import shutil
    import subprocess
    if not shutil.which("arm-none-eabi-gcc"):
        return None
    subprocess.run(["arm-none-eabi-gcc", "-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16",
                    "-mfloat-abi=hard", "-Os", *flags, "-c", "-I", str(src),
                    str(src / cfile), "-o", str(obj)], check=True)
    from gen.toolchain.footprint import section_sizes
    sec = section_sizes(obj, "arm-none-eabi-")
    assert sec["data"] == 0 and sec["bss"] == 0, sec
    assert sec["rodata"] >= flash, sec
    return sec


def load_test_file(path):
    """A test file's module by its path under tests/ ("physics/test_auxiliary.py"):
    its model builders shared with a test of another folder, imported once
    under its own name (no folder of tests/ needs to be on sys.path)."""
    import importlib.util
    import sys
    from pathlib import Path
    file = Path(__file__).resolve().parent / path
    name = "_tests_" + path.replace("/", "_").removesuffix(".py")
    mod = sys.modules.get(name)
    if mod is None:
        spec = importlib.util.spec_from_file_location(name, file)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return mod
