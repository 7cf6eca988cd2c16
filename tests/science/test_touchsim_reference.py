"""mjtouch's median units against TouchSim's median fitted afferents (Saal et
al. 2017, PNAS 114:E5693; hsaal/touchsim) under the same 1 mm flat pin.

TouchSim's numbers come from tests/data/touchsim_reference.json, written by
examples/touchsim_reference.py (its command, TouchSim commit and protocol
are in the file). Ours: tuning.pin_reference_stress / pin_reference_table,
the same stimuli (1 s, 50 ms linear ramps, whole-second counts; sines at
0.5 mm pre-indentation), one receptor per class on the pin's axis at
mjtouch's depths, noise off, median parameter set.

Asserted: the SA1's ramp-and-hold rate within 1.5x of TouchSim's at 0.5,
1.0 and 1.5 mm and the same slope; below 0.5 mm ours fires where TouchSim's
fits barely do, as human SA I units do (Johansson & Vallbo 1979, J Physiol
286:283: median threshold 56 um). The RA's and the PC's within 2x at 0.5
and 1.0 mm, on our stress and on TouchSim's.
The stress at the receptor against TouchSim's, a check of the mechanics
(bounds derived below), for the ramps and for the sines. "On TouchSim's
stress": our afferent model driven by our stress traces scaled to
TouchSim's s_z at the receptor (tuning.pin_reference_rescaled), so each
difference splits into the mechanics (ours / TouchSim's stress) and the
afferent model (ours on TouchSim's stress / TouchSim). The thresholds are
split so: the mechanics give 1.65-2.2x, the RA's model 2.2-10x (its gain,
kept for the RA's response to scanned gratings), the PC's 1-3.2x (its
gain, kept for the slip burst and the textures; docs/science/afferents.md,
"Against TouchSim", has the tables and the reasons).

Cost: ~25 s (six 1 s ramps and nine pairs of 1 s sines on a 49 x 49 skin
at dt 1e-4, two threads; the thresholds by bisection through
core.receptor_run, twice ~3 s).
"""

import json
import pathlib
import re
import runpy

import numpy as np
import pytest

from mjtouch import _core, core
from mjtouch.experiments import tuning

REF = json.loads(
    (pathlib.Path(__file__).parents[1] / "data" / "touchsim_reference.json").read_text()
)
RAMP = REF["ramp_and_hold"]
SINES = REF["sines"]
SA1_RATE_BOUND = 1.5
RA_PC_RATE_BOUND = 2.0  # issue bound for the rapidly adapting classes
# the PC's absolute thresholds on TouchSim's stress: its gain, kept for the
# slip burst and the textures, leaves them 1-3.2x TouchSim's
PC_THRESHOLD_MODEL_BOUND = 3.5
# TouchSim's mechanics (Saal et al. 2017; the file's stress_note): Sneddon's
# flat punch on an elastic half-space
TOUCHSIM_YOUNG_PA, TOUCHSIM_POISSON = 50e3, 0.4
STRESS_COMPARED_TO_MM = 0.5  # deeper, ours is no longer linear in depth (below)


def _layers():
    """The default skin layers (thickness m, E Pa, nu) from the attribute table."""
    for line in _core.attribute_table_markdown().splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 2 and cells[1] == "`layers`":
            text = re.search(r"default ([-0-9e.; ]+)", cells[5]).group(1)
            return [tuple(float(x) for x in layer.split()) for layer in text.split(";")]
    raise KeyError("layers")


def _touchsim_stress_key(c):
    # SA1 at TouchSim's own class depth (0.3 mm, its fits' input); RA and PC
    # at ours (TouchSim drives them by a surface-velocity wave, not s_z)
    return "stress_kpa" if c == "SA1" else "stress_kpa_mjtouch_depth"


def _touchsim_stress(classes):
    """TouchSim's s_z at the receptor (Pa): per ramp depth, at the sines'
    pre-indentation, and per metre of sine (Sneddon's punch is linear in
    depth: the 0.5 mm ramp's value over 0.5 mm)."""
    i = RAMP["depths_mm"].index(SINES["preindent_mm"])
    ramp = {c: [x * 1e3 for x in RAMP[c][_touchsim_stress_key(c)]] for c in classes}
    pre = {c: ramp[c][i] for c in classes}
    per_m = {c: pre[c] / (SINES["preindent_mm"] * 1e-3) for c in classes}
    return ramp, pre, per_m


@pytest.fixture(scope="module")
def stress():
    return tuning.pin_reference_stress(
        [d * 1e-3 for d in RAMP["depths_mm"]],
        SINES["freqs_hz"],
        duration_s=REF["duration_s"],
        ramp_s=REF["ramp_s"],
        preindent_m=SINES["preindent_mm"] * 1e-3,
    )


@pytest.fixture(scope="module")
def ours(stress):
    return tuning.pin_reference_table(stress)


@pytest.fixture(scope="module")
def on_touchsim(stress):
    """Our afferent model on TouchSim's stress at the receptor (our traces'
    time course scaled to its level): what is left against TouchSim is the
    afferent model; what this removes, the mechanics."""
    return tuning.pin_reference_table(
        tuning.pin_reference_rescaled(stress, *_touchsim_stress(stress["classes"]))
    )


def test_reference_file_is_touchsims_and_self_consistent():
    assert REF["source"] == "hsaal/touchsim" and len(REF["commit"]) == 40
    assert "examples/touchsim_reference.py" in REF["command"]
    assert "E 50 kPa, nu 0.4" in REF["stress_note"]
    fits = {"SA1": 4, "RA": 9, "PC": 4}
    for c, n in fits.items():
        per = np.array(RAMP[c]["rates_hz"])
        assert per.shape == (len(RAMP["depths_mm"]), n)
        np.testing.assert_array_equal(RAMP[c]["median_hz"], np.median(per, axis=1))
        for crit in ("absolute", "entrainment"):
            thr = np.array(SINES[c][f"{crit}_um"])
            assert thr.shape == (len(SINES["freqs_hz"]), n)
            np.testing.assert_array_equal(SINES[c][f"{crit}_median_um"], np.median(thr, axis=1))


def test_units_sit_on_the_pin_axis(ours):
    for c in ("SA1", "RA", "PC"):
        assert ours[c]["offaxis_m"] == 0.0, (c, ours[c]["offaxis_m"])


def test_sa1_ramp_and_hold_rates_against_touchsim(ours):
    depths = RAMP["depths_mm"]
    ts = np.array(RAMP["SA1"]["median_hz"])
    us = np.array(ours["SA1"]["rates_hz"])
    print("SA1 rates (Hz) at", depths, "ours", us, "touchsim", ts)
    # where TouchSim's median fit fires at least 10 spikes (0.5 mm on): 1.5x
    for d in (0.5, 1.0, 1.5):
        i = depths.index(d)
        assert ts[i] / SA1_RATE_BOUND <= us[i] <= ts[i] * SA1_RATE_BOUND, (d, us[i], ts[i])
    # the same rate-intensity slope over 0.5-1.5 mm (Hz/mm), within 1.5x
    i, j = depths.index(0.5), depths.index(1.5)
    slope_us = (us[j] - us[i]) / (depths[j] - depths[i])
    slope_ts = (ts[j] - ts[i]) / (depths[j] - depths[i])
    assert slope_ts / SA1_RATE_BOUND <= slope_us <= slope_ts * SA1_RATE_BOUND, (slope_us, slope_ts)
    # Below 0.5 mm TouchSim's fits start at 0.1-0.4 mm (its median: silent at
    # 0.1 mm, 7.5 Hz at 0.25 mm); human SA I units respond to tens of um
    # (Johansson & Vallbo 1979), so ours fires from 0.05 mm and the
    # threshold, not the slope, makes ours exceed TouchSim's at 0.25 mm.
    assert us[depths.index(0.05)] > 0 and np.all(np.diff(us) > 0), us
    k = depths.index(0.25)
    assert us[k] > ts[k], (us[k], ts[k])


def test_stress_at_the_receptor_against_touchsims_half_space(ours):
    # Both prescribe the pin's displacement. Under a flat punch of radius a
    # the total force is 2 a E* d (E* = E / (1 - nu^2); Sneddon 1965) and the
    # vertical stress on the axis is that force times a shape factor of z / a
    # that does not depend on the moduli (Boussinesq). So with the same
    # geometry the stress ratio is the ratio of the effective moduli. Ours is
    # layered: the stress bulb of a 0.5 mm punch (to ~2a deep) samples the
    # epidermis and the dermis, so our E* lies between theirs; TouchSim's is
    # one half-space of E 50 kPa, nu 0.4. Hence ours / TouchSim's in
    # [E*_dermis, E*_epidermis] / E*_touchsim, while the skin stays linear
    # in depth (to 0.5 mm; deeper, the curved pad wraps round the pin's edge
    # and the 4 mm stack over its rigid base stiffens: docs/science/afferents.md).
    (_, e_epi, nu_epi), (_, e_der, nu_der) = _layers()[:2]
    e_star = lambda e, nu: e / (1 - nu**2)  # noqa: E731
    ts_star = e_star(TOUCHSIM_YOUNG_PA, TOUCHSIM_POISSON)
    lo, hi = e_star(e_der, nu_der) / ts_star, e_star(e_epi, nu_epi) / ts_star
    depths = np.array(RAMP["depths_mm"])
    for c in ("SA1", "RA", "PC"):
        us = np.array(ours[c]["stress_kpa"])
        ts = np.array(RAMP[c]["stress_kpa_mjtouch_depth"])
        ratio = us / ts
        print(
            c,
            "stress kPa ours",
            np.round(us, 2),
            "touchsim",
            np.round(ts, 2),
            "ratio",
            np.round(ratio, 2),
            "bound",
            round(lo, 2),
            round(hi, 2),
        )
        m = depths <= STRESS_COMPARED_TO_MM
        assert np.all((lo <= ratio[m]) & (ratio[m] <= hi)), (c, ratio)
        assert np.all(np.diff(us) > 0) and np.all(np.diff(ts) > 0)


def _within(us, ts, bound):
    return ts / bound <= us <= ts * bound


def test_ra_ramp_and_hold_rates_within_2x_of_touchsim(ours):
    ts, us = RAMP["RA"]["median_hz"], ours["RA"]["rates_hz"]
    print("RA rates (Hz) at", RAMP["depths_mm"], "ours", us, "touchsim", ts)
    for d in (0.5, 1.0):
        i = RAMP["depths_mm"].index(d)
        assert _within(us[i], ts[i], RA_PC_RATE_BOUND), (d, us[i], ts[i])


def _trapezoid_counts(cls, level_pa, dt_s):
    """Our cls model's whole-stimulus count under TouchSim's stimulus timing
    (ramps of REF's ramp_s in REF's duration_s) at a stress level."""
    t = np.arange(int(round(REF["duration_s"] / dt_s)) + 1) * dt_s
    d, r = REF["duration_s"], REF["ramp_s"]
    q = level_pa * np.interp(t, [0, r, d - r, d], [0, 1, 1, 0])
    return int(core.receptor_run(cls, q, dt_s, tuning.PIN_AFFERENTS)[0].sum())


def test_pc_ramp_and_hold_rates_within_2x_of_touchsim(ours, on_touchsim):
    ts, us = RAMP["PC"]["median_hz"], ours["PC"]["rates_hz"]
    on_ts = on_touchsim["PC"]["rates_hz"]
    print("PC rates (Hz) at", RAMP["depths_mm"], "ours", us, "on TouchSim's stress", on_ts)
    print("  touchsim", ts)
    for d in (0.5, 1.0):
        i = RAMP["depths_mm"].index(d)
        assert _within(us[i], ts[i], RA_PC_RATE_BOUND), (d, us[i], ts[i])
        assert _within(on_ts[i], ts[i], RA_PC_RATE_BOUND), (d, on_ts[i], ts[i])
    # The model alone, on an ideal trapezoid at TouchSim's level (no trace of
    # our skin's stiffening through the ramp): one spike per rising corner
    # and one or two per falling corner (the high-pass's rebound lobe),
    # within 2x of TouchSim's at every depth from 0.5 mm.
    for k, d in enumerate(RAMP["depths_mm"]):
        level = RAMP["PC"]["stress_kpa_mjtouch_depth"][k] * 1e3
        n = _trapezoid_counts("PC", level, ours["PC"]["dt_s"]) / REF["duration_s"]
        print("  trapezoid at TouchSim's stress,", d, "mm:", n)
        if d >= 0.5:
            assert _within(n, ts[k], RA_PC_RATE_BOUND), (d, n, ts[k])
    # 1.5 mm: ours over 2x, on TouchSim's stress less so: the mechanics
    # (our stress at 2 mm 3x TouchSim's, convex through the ramp)
    j = RAMP["depths_mm"].index(1.5)
    assert on_ts[j] < us[j], (on_ts[j], us[j])


def _sine_stress_ratio(stress):
    """Ours over TouchSim's stress amplitude at the receptor per um of pin
    sine, per class and frequency: the mechanics' part of the thresholds."""
    _, _, per_m = _touchsim_stress(stress["classes"])
    gain = tuning.pin_sine_gain(stress)
    return {c: np.array(gain[c]) / per_m[c] for c in stress["classes"]}


def test_sine_stress_at_the_receptor_against_touchsims(stress, ours):
    # TouchSim's s_z is quasi-static and linear: per um of sine it is its
    # ramp stress over depth. Ours about the 0.5 mm pre-indentation is the
    # tangent of our (convex) stress-depth curve, so at frequencies where the
    # skin is quasi-static it lies between the secants of our ramp-and-hold
    # stress below (0.25-0.5 mm) and above (0.5-1.0 mm): an independent
    # check of the sine runs against the ramp runs.
    freqs = np.array(SINES["freqs_hz"])
    depths = RAMP["depths_mm"]
    i0, i1, i2 = (depths.index(d) for d in (0.25, 0.5, 1.0))
    gain = tuning.pin_sine_gain(stress)
    ratio = _sine_stress_ratio(stress)
    for c in ("RA", "PC"):
        kpa = ours[c]["stress_kpa"]
        below = (kpa[i1] - kpa[i0]) / (depths[i1] - depths[i0])  # kPa/mm
        above = (kpa[i2] - kpa[i1]) / (depths[i2] - depths[i1])
        g = np.array(gain[c]) / 1e6  # Pa/m -> kPa/mm
        print(c, "sine stress kPa/mm", np.round(g, 2), "secants", round(below, 2), round(above, 2))
        print(c, "ours / TouchSim's at the receptor", np.round(ratio[c], 2))
        quasi = freqs <= 80.0
        assert np.all((below <= g[quasi]) & (g[quasi] <= above)), (c, g, below, above)


@pytest.mark.parametrize("cls", ["RA", "PC"])
def test_thresholds_split_into_mechanics_and_model(stress, ours, on_touchsim, cls):
    ratio = _sine_stress_ratio(stress)[cls]
    for crit in ("absolute", "entrainment"):
        us = np.array(ours[cls][f"{crit}_um"])
        on = np.array(on_touchsim[cls][f"{crit}_um"])
        ts = np.array(SINES[cls][f"{crit}_median_um"])
        print(cls, crit, "um ours", np.round(us, 3))
        print(cls, crit, "um on TouchSim's stress", np.round(on, 3))
        print(cls, crit, "um touchsim", np.round(ts, 3))
        # Our RA and PC see the stress through its derivatives only, so on
        # TouchSim's stress every threshold is ours times the stress ratio:
        # ours / TouchSim = (on TouchSim's stress / TouchSim) [the model] /
        # ratio [the mechanics]. To 1e-3: the held pin's own small stress
        # fluctuations scale with the pre-indentation, not with the wave.
        f = np.isfinite(us)
        np.testing.assert_array_equal(np.isfinite(on), f)
        np.testing.assert_allclose(on[f], us[f] * ratio[f], rtol=1e-3)
        # each threshold is a real bisection result, absolute <= 1:1
    a = np.array(ours[cls]["absolute_um"])
    e = np.array(ours[cls]["entrainment_um"])
    assert np.all(a[np.isfinite(e)] <= e[np.isfinite(e)]), (a, e)
    # The model's part of the absolute thresholds, on TouchSim's stress
    # (docs/science/afferents.md, "Against TouchSim", says why the gains are
    # kept): the PC within MODEL_BOUND of TouchSim at every frequency, its
    # best frequency where TouchSim's is (250-400 Hz); the RA more sensitive
    # at every frequency, its best within one step of TouchSim's (40-80 Hz).
    on = np.array(on_touchsim[cls]["absolute_um"])
    ts = np.array(SINES[cls]["absolute_median_um"])
    freqs = SINES["freqs_hz"]
    best_on, best_ts = int(np.argmin(on)), int(np.argmin(ts))
    assert abs(best_on - best_ts) <= 1, (freqs[best_on], freqs[best_ts])
    if cls == "PC":
        b = PC_THRESHOLD_MODEL_BOUND
        assert np.all((ts / b <= on) & (on <= ts * b)), on / ts
    else:
        f = np.isfinite(ts)
        assert np.all(on[f] < ts[f]), on / ts


def test_reference_script_guvectorize_shim_loops_like_numba():
    # examples/touchsim_reference.py runs TouchSim's numba gufuncs through a
    # Python loop over the broadcast dimensions: check it on gufuncs of the
    # signatures TouchSim uses, against the same arithmetic in numpy.
    script = pathlib.Path(__file__).parents[2] / "examples" / "touchsim_reference.py"
    shim = runpy.run_path(str(script), run_name="shim")["_guvectorize"]

    @shim(None, "(m),(n),(n)->(n)")
    def weighted(p, a, b, out):
        for i in range(a.shape[0]):
            out[i] = p[0] * a[i] + p[1] * b[i]

    @shim(None, "(n),()->(n)")
    def leaky(x, s, out):
        acc = 0.0
        for i in range(x.shape[0]):
            acc = acc * s[0] + x[i]
            out[i] = acc

    rng = np.random.default_rng(0)
    p, a, b = rng.normal(size=(3, 2)), rng.normal(size=(3, 7)), rng.normal(size=(3, 7))
    np.testing.assert_array_equal(weighted(p, a, b), p[:, :1] * a + p[:, 1:] * b)
    x, s = rng.normal(size=(4, 5)), np.array([0.5, 0.9, 0.0, 1.0])
    want = np.zeros_like(x)
    for r in range(4):
        acc = 0.0
        for i in range(5):
            acc = acc * s[r] + x[r, i]
            want[r, i] = acc
    np.testing.assert_array_equal(leaky(x, s), want)
    np.testing.assert_array_equal(leaky(x[0], 0.5), want[0])  # no loop dims
