"""The `elastic` contact solver's two methods (plugin/core/contact/contact_solver.*):
the preconditioned CG (`pcg`, the plugin's default) against Polonsky & Keer's
plain CG (`pk`, the reference path) on a ridged fingertip pressed on a
grating, for the layered (Shao 2010) skin and a homogeneous half-space.

The operator's FFTs run in double (the reference arithmetic) unless a test
asks for float (the plugin's default, elastic_precision).

Both methods minimise the same convex energy under the same load, so at a
tight tolerance they must reach the same pressure; at the plugin's default
tolerance (1e-4) the preconditioned method must not be less accurate than
P&K against that tight reference, and it must take fewer iterations (the
point of it). Measured here (64 x 0.1 mm, cold start): tight solutions agree
to 2e-10 (relative RMS); at 1e-4, pcg 4e-5 - 5e-5 vs pk 8e-5 - 1.8e-4.
"""

import numpy as np
import pytest

from mjtouch import core

N, H = 64, 1e-4
E, NU = 8e4, 0.48


def ridged_grating_gap(shift_cells: int = 0) -> np.ndarray:
    # ellipsoid-like pad (R = 8 mm) with 0.45 mm, 50 um ridges on a 1 mm
    # square grating 40 um deep: a fragmented contact like the slide scenes'
    x = (np.arange(N) - (N - 1) / 2) * H
    X, Y = np.meshgrid(x, x)
    grating = 40e-6 * (np.cos(2 * np.pi * (X + shift_cells * H + 0.2e-3) / 1e-3) > 0)
    return (X**2 + Y**2) / (2 * 8e-3) + 25e-6 * (1 - np.cos(2 * np.pi * X / 0.45e-3)) + grating


def solve(gap, force_n, skin, method, tolerance, initial=None, precision="double"):
    kw = (
        dict(compliance_m_per_pa=core.LayeredSkin().compliance_table(H, N))
        if skin == "layered"
        else dict(young_pa=E, poisson=NU)
    )
    return core.elastic_pressure(
        gap,
        H,
        force_n,
        tolerance=tolerance,
        max_iterations=20000,
        method=method,
        initial_pa=initial,
        precision=precision,
        **kw,
    )


def rms_rel(p, ref):
    return float(np.sqrt(((p - ref) ** 2).sum() / (ref**2).sum()))


@pytest.mark.parametrize("skin", ["layered", "halfspace"])
@pytest.mark.parametrize("force_n", [0.1, 0.3])
def test_pcg_reaches_the_reference_solution(skin, force_n):
    gap = ridged_grating_gap()
    ref, st_ref = solve(gap, force_n, skin, "pk", 1e-10)
    tight, st_tight = solve(gap, force_n, skin, "pcg", 1e-10)
    assert st_ref["converged"] and st_tight["converged"]
    assert rms_rel(tight, ref) < 1e-8, rms_rel(tight, ref)
    assert np.array_equal(tight > 0, ref > 0)  # the same contact set
    assert tight.sum() * H**2 == pytest.approx(force_n, rel=1e-12)
    # at the plugin's default tolerance: no less accurate than P&K, fewer iterations
    p_pk, st_pk = solve(gap, force_n, skin, "pk", 1e-4)
    p_pcg, st_pcg = solve(gap, force_n, skin, "pcg", 1e-4)
    err_pk, err_pcg = rms_rel(p_pk, ref), rms_rel(p_pcg, ref)
    assert err_pcg <= err_pk, (err_pcg, err_pk)
    assert err_pcg < 1e-4, err_pcg
    assert st_pcg["iterations"] < st_pk["iterations"], (st_pcg, st_pk)
    assert abs(st_pcg["approach_m"] - st_ref["approach_m"]) < 1e-8


def test_pcg_warm_start_while_sliding_takes_fewer_iterations():
    # the plugin's situation: each step starts from the last step's pressure,
    # the grating one cell further along
    its = {"pk": [], "pcg": []}
    errs = {"pk": [], "pcg": []}
    for method in its:
        p = None
        for step in range(1, 5):
            gap = ridged_grating_gap(step)
            p, st = solve(gap, 0.3, "layered", method, 1e-4, initial=p)
            ref, _ = solve(gap, 0.3, "layered", "pk", 1e-10, initial=p)
            its[method].append(st["iterations"])
            errs[method].append(rms_rel(p, ref))
    assert sum(its["pcg"]) * 1.5 <= sum(its["pk"]), its
    assert max(errs["pcg"]) <= max(errs["pk"]), errs


@pytest.mark.parametrize("skin", ["layered", "halfspace"])
@pytest.mark.parametrize("force_n", [0.1, 0.3])
def test_float_ffts_reach_the_double_solution_within_float_rounding(skin, force_n):
    # The plugin's default (elastic_precision="float") rounds the operator's
    # FFTs to float: ~1e-7 relative on K p (the compliance table itself is
    # float), amplified by the contact problem's conditioning. Measured here:
    # converged float solutions 4.6e-7 - 1.5e-6 (relative RMS) from the tight
    # double reference, the same iteration counts; at the plugin's tolerance
    # (1e-4) errors 3e-5 - 8e-5 in both, within 1e-6 of each other.
    gap = ridged_grating_gap()
    ref, st_ref = solve(gap, force_n, skin, "pk", 1e-10)
    tight, st_tight = solve(gap, force_n, skin, "pcg", 1e-8, precision="float")
    assert st_tight["converged"]
    assert rms_rel(tight, ref) < 5e-6, rms_rel(tight, ref)  # the float floor, 100x below 1e-4
    assert abs(st_tight["approach_m"] - st_ref["approach_m"]) < 1e-10
    assert tight.sum() * H**2 == pytest.approx(force_n, rel=1e-12)
    p_d, st_d = solve(gap, force_n, skin, "pcg", 1e-4)
    p_f, st_f = solve(gap, force_n, skin, "pcg", 1e-4, precision="float")
    err_d, err_f = rms_rel(p_d, ref), rms_rel(p_f, ref)
    assert err_f < 1e-4 and abs(err_f - err_d) < 5e-6, (err_f, err_d)
    assert abs(st_f["iterations"] - st_d["iterations"]) <= 1, (st_f, st_d)


def test_unknown_precision_is_rejected():
    with pytest.raises(ValueError, match="precision = 'half'.*'double'.*'float'"):
        core.elastic_pressure(ridged_grating_gap(), H, 0.1, E, NU, precision="half")


def test_unknown_method_is_rejected():
    with pytest.raises(ValueError, match="method = 'cg'.*'pcg'.*'pk'"):
        core.elastic_pressure(ridged_grating_gap(), H, 0.1, E, NU, method="cg")
