"""gen.verify: the compiled code against sympy's own evaluation; a tampered
generated source is caught."""
import pytest

import gen
import rolling_disc
import seed_pendulum as sp
from gen.export.verify import verify


@pytest.mark.parametrize("build", [sp.kane_model, sp.lagrange_model, rolling_disc.model],
                         ids=["kane", "lagrange", "rolling_disc"])
def test_verify_passes_on_generated_code(build):
    report = verify(build(), samples=8)
    print(report.table())
    assert report.ok, report.table()
    names = [r[0] for r in report.rows]
    for need in ("eval_mass_matrix", "eval_forcing", "eval_rhs", "linearize"):
        assert need in names
    assert all(err < 1e-12 for _, err, _ in report.rows)


def test_verify_catches_a_tampered_source(tmp_path, kane_model):
    out = tmp_path / "pend"
    gen.generate(kane_model, out)
    assert verify(kane_model, samples=4, sources=out).ok
    src = out / f"{kane_model.name}_kernels.c"
    text = src.read_text()
    assert "sqrt(" in text
    src.write_text(text.replace("sqrt(", "fabs(", 1))     # compiles, computes something else
    report = verify(kane_model, samples=4, sources=out)
    print(report.table())
    assert not report.ok
    assert "MISMATCH" in report.table()


def test_verify_refuses_a_folder_that_is_not_the_project(tmp_path, kane_model):
    with pytest.raises(gen.ModelError, match="does not exist"):
        verify(kane_model, sources=tmp_path / "nothing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(gen.ModelError, match="is missing"):
        verify(kane_model, sources=tmp_path / "empty")
