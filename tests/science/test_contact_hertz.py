"""The `elastic` pressure model end to end: a sphere pad pressed on a flat
plate by MuJoCo reproduces Hertz (examples/pressure_ladder.py prints how far
every pressure model is from it)."""

import pytest
from conftest import hertz_sphere_press

from mjtouch.analysis import reference_solutions

E, NU = 80e3, 0.48


def test_elastic_sphere_pad_matches_hertz():
    # R = 0.2 m keeps a / R = 0.045: the sphere's departure from Hertz's
    # paraboloid, ~(a / R)^2 / 4 = 5e-4, stays below the 1e-3 tolerance; at
    # 32 cells per contact radius the boundary elements' own error is 1e-4
    # (tests/unit/test_pressure.py).
    h = reference_solutions.Hertz(load_n=0.5, radius_m=0.2, young_pa=E, poisson=NU)
    force, p, pitch = hertz_sphere_press(h, E, NU)
    assert force[0] == pytest.approx(h.load_n, rel=1e-6)  # settled on the set load
    # sum(p A) is MuJoCo's normal force (float32 pressure output: 1e-7)
    assert p.sum() * pitch**2 == pytest.approx(force[0], rel=1e-6)
    err = reference_solutions.hertz_errors(h, p, pitch, force[3])
    assert all(abs(v) < 1e-3 for v in err.values()), err


def test_pressure_ladder_example():
    # The example's fingertip-sized sphere (R = 20 mm, a / R = 0.21): elastic
    # departs from Hertz by the sphere's non-paraboloid shape, bounded by
    # (a / R)^2 / 4 = 1.1e-2; Winkler and contact splats are far off, which is
    # what the ladder shows.
    import pathlib
    import runpy

    ex = runpy.run_path(str(pathlib.Path(__file__).parents[2] / "examples" / "pressure_ladder.py"))
    out = ex["ladder"](radius_m=0.02, force_n=0.5, steps=1500)
    h = reference_solutions.Hertz(load_n=0.5, radius_m=0.02, young_pa=E, poisson=NU)
    bound = (h.contact_radius_m / h.radius_m) ** 2 / 4
    assert all(abs(v) < bound for v in out["elastic"].values()), out
    assert abs(out["winkler"]["indentation"]) > 10 * abs(out["elastic"]["indentation"])
    assert out["contacts"]["peak"] > 10  # one splat per MuJoCo contact: a spike
