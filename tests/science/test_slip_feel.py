"""The afferents feel slip coming: a tangential ramp on a pressed fingertip.

:func:`mjtouch.experiments.slip_ramp.run` presses the pad at P (1, 2, 4 N) on
a flat plate and on a grating and ramps the tangential force Q past mu P
(force control: gross slip is the pad sliding away once Q reaches mu P). The
skin (Winkler, shear="partial", 64 x 0.25 mm: the whole 9-13 mm contact at
~20-25 cells per radius) must show Cattaneo's stuck share, RA and SA1 rising
in the window where about half the area slips (Q / mu P 0.6-0.8) over the
stick-dominated window (0.1-0.35), at least 0.1 s before gross slip, and PC
answering the slip's onset (Johansson & Westling 1987; Barrea et al. 2018).
"""

import numpy as np
import pytest

from mjtouch.experiments import slip_ramp
from mjtouch.scene.sensor import CLASSES

FORCES_N = (1.0, 2.0, 4.0)
SEEDS = (0, 1, 2)  # receptor noise seeds: rates are pooled over them
TEXTURES = ("flat", "grating")
# Required rises (half-slip window over stick window, pooled rates). Measured
# on these runs: RA 8-140x, SA1 1.13-1.17x (printed by the test).
RA_RISE, SA1_RISE = 4.0, 1.05
# The ramp climbs 2 mu P per second: Q / mu P = 0.8 comes 0.1 s before 1.
MIN_LEAD_S = 0.09


def _params(texture, force_n, seed, **kw):
    return slip_ramp.SlipRampParams(
        texture=texture, normal_force_n=force_n, seed=seed, grating_height_m=1e-4, **kw
    )


@pytest.fixture(scope="module")
def ramps():
    return {
        (tex, f, s): slip_ramp.run(_params(tex, f, s))
        for tex in TEXTURES
        for f in FORCES_N
        for s in SEEDS
    }


def _pooled(runs, key):
    """Rates (Hz per receptor) pooled over runs of equal windows' lengths."""
    return {c: float(np.mean([r.summary()[key][c] for r in runs])) for c in CLASSES}


def test_gross_slip_is_the_pad_sliding_when_q_reaches_mu_p(ramps):
    for (tex, f, s), out in ramps.items():
        g = out.gross_slip_s
        at = np.flatnonzero(out.time_s == g)[0]
        # MuJoCo's friction saturates at mu P (its solver's tolerance)
        assert out.q_over_mu_p[at] > 1 - 1e-4, (tex, f, s, out.q_over_mu_p[at])
        assert 0.95 / out.params.overshoot * out.params.ramp_s < g, (tex, f, s, g)
        # before: creep (< 1 mm/s, < 0.5 mm in all); 50 ms after: a slide
        before = out.time_s < g
        assert np.abs(out.finger_x_m[before]).max() < 5e-4
        later = np.flatnonzero(out.time_s >= g + 0.05)[0]  # (the run ends at g + 0.06 s)
        assert out.finger_x_m[later] - out.finger_x_m[at] > 1e-3


def test_a_sliding_pad_is_in_full_slip(ramps):
    # Kinematics decide: wherever the pad slides (faster than the gross-slip
    # speed) under a loaded contact, the skin reports (next to) no stuck
    # cell. MuJoCo's friction force dips up to ~2.5e-5 of mu P below the
    # limit while sliding, which the force history alone would read as
    # unloading, the whole contact sticking.
    for (tex, f, s), out in ramps.items():
        sliding = (out.finger_speed_m_s > out.params.slip_speed_m_s) & (out.q_over_mu_p > 0.5)
        assert sliding.sum() >= 20, (tex, f, s)
        share = out.stuck_share[sliding]
        assert np.all(np.isnan(share) | (share <= 0.01)), (tex, f, s, np.nanmax(share))


def test_stuck_share_follows_cattaneo_on_the_flat_plate(ramps):
    # 1 and 2 N: contact radii 4.6 and 5.5 mm on the pad's 7 mm. At 4 N
    # (6.5 mm) the ellipsoid's Winkler pressure leaves the paraboloid and
    # the share runs up to 0.05 over Cattaneo's (the per-cell test below
    # holds it there).
    for f in (1.0, 2.0):
        out = ramps[("flat", f, 0)]
        pressure = out.layout.block(out.sensordata, "pressure")
        ratio, share = out.q_over_mu_p, out.stuck_share
        oracle = out.oracle_stuck_share()
        on = np.flatnonzero((out.time_s >= 0) & (ratio > 0.05) & (ratio < 0.9))[::25]
        assert len(on) >= 15
        for k in on:
            loaded = np.count_nonzero(pressure[k])
            # Cattaneo on the grid: the stick and contact ellipses' sizes
            # resolved to half a cell each (share (c/a)^2 moves by
            # share (1/c + 1/a), c, a the equivalent radii in cells), plus
            # one cell of the count (as tests/plugin/test_partial_slip.py).
            a = np.sqrt(loaded / np.pi)
            c = a * np.sqrt(oracle[k])
            tol = oracle[k] * (1.0 / max(c, 0.5) + 1.0 / a) + 1.0 / loaded
            assert abs(share[k] - oracle[k]) <= tol, (f, ratio[k], share[k], oracle[k], tol)


def test_stuck_share_is_winklers_on_each_cell_on_both_plates(ramps):
    # Cattaneo's construction cell by cell on the pressure the skin renders
    # (grating or pad shape off the paraboloid): exact up to the few rim
    # cells the creeping pad moves over the ramp (history the oracle lacks).
    worst = 0.0
    for tex in TEXTURES:
        for f in FORCES_N:
            out = ramps[(tex, f, 0)]
            pressure = out.layout.block(out.sensordata, "pressure")
            ramp = (out.time_s >= 0) & (out.time_s < out.gross_slip_s)
            on = np.flatnonzero(ramp & (out.q_over_mu_p < 0.95))[::40]
            for k in on:
                loaded = np.count_nonzero(pressure[k])
                expected = slip_ramp.winkler_stuck_share(pressure[k], out.q_over_mu_p[k])
                err = abs(out.stuck_share[k] - expected) * loaded
                worst = max(worst, err)
                assert err <= 4, (tex, f, out.q_over_mu_p[k], out.stuck_share[k], expected)
    print(f"per-cell Winkler oracle: worst {worst:.1f} cells")


def test_afferents_rise_before_gross_slip_where_half_the_area_slips(ramps):
    rows = []
    for tex in TEXTURES:
        for f in FORCES_N:
            runs = [ramps[(tex, f, s)] for s in SEEDS]
            stick = _pooled(runs, "stick_hz")
            half = _pooled(runs, "half_slip_hz")
            lead = min(r.summary()["half_slip_lead_s"] for r in runs)
            share = [
                float(r.stuck_share[r.time_s < r.time_at(slip_ramp.HALF_SLIP_WINDOW[1])][-1])
                for r in runs
            ]
            rows.append((tex, f, stick, half, lead, min(share)))
            assert lead >= MIN_LEAD_S, (tex, f, lead)
            # about half the area slips by the window's end
            assert 0.3 <= min(share) <= 0.6, (tex, f, share)
            for cls, rise in (("RA", RA_RISE), ("SA1", SA1_RISE)):
                assert half[cls] >= rise * stick[cls], (tex, f, cls, stick[cls], half[cls])
    for tex, f, stick, half, lead, share in rows:
        print(
            f"{tex:7s} P {f} N: RA {stick['RA']:.2f} -> {half['RA']:.2f} Hz "
            f"({half['RA'] / max(stick['RA'], 1e-9):.1f}x), SA1 {stick['SA1']:.1f} -> "
            f"{half['SA1']:.1f} Hz ({half['SA1'] / stick['SA1']:.2f}x), "
            f"{lead * 1e3:.0f} ms before gross slip, stuck share {share:.2f}"
        )


def test_pc_answers_slip_onset(ramps):
    for tex in TEXTURES:
        for f in FORCES_N:
            runs = [ramps[(tex, f, s)] for s in SEEDS]
            before = _pooled(runs, "half_slip_hz")["PC"]
            onset = _pooled(runs, "onset_hz")["PC"]
            print(f"{tex:7s} P {f} N: PC {before:.1f} Hz before, {onset:.1f} Hz at slip onset")
            # a burst: several spikes per receptor-second over the 20 ms window
            assert onset >= 20.0 and onset >= 10.0 * before, (tex, f, before, onset)


def test_ra_rise_comes_from_the_slip_ring():
    # The same ramp with uniform full-slip shear (no stick zone): RA stays
    # flat, so its rise above is the partial-slip tractions', not the load's.
    # (SA1's rise, 1.15x either way, follows the load itself.)
    ratios = {}
    for shear in ("true", "partial"):
        runs = [slip_ramp.run(_params("flat", 2.0, s, shear=shear)) for s in SEEDS]
        stick, half = _pooled(runs, "stick_hz"), _pooled(runs, "half_slip_hz")
        ratios[shear] = half["RA"] / max(stick["RA"], 1e-9)
        print(f"shear={shear}: SA1 rise {half['SA1'] / stick['SA1']:.2f}x")
    print(f"RA rise at 2 N: full slip {ratios['true']:.2f}x, partial {ratios['partial']:.1f}x")
    assert ratios["true"] < 2.0 < RA_RISE <= ratios["partial"]


@pytest.mark.parametrize(
    "field, value", [("normal_force_n", 0.0), ("texture", "dots"), ("overshoot", 0.9)]
)
def test_bad_params_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        slip_ramp.run(slip_ramp.SlipRampParams(**{field: value}))
