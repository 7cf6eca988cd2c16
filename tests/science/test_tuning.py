"""mjtouch.tuning and the `probe` / `tuning` commands (issue 14): structure of
the results, what must hold whatever the afferent model, the monotonic SA1
rate-intensity of the built model, and RA's and PC's entrainment over absolute
threshold on the protocol's own stress."""

import contextlib
import io
import json
import math
import types

import numpy as np
import pytest

from mjtouch import cli
from mjtouch.experiments import tuning


def run_cli(*args):
    """`python -m mjtouch ARGS` in this process (the subprocess start costs
    more than the quick runs)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = cli.main(list(args))
    return types.SimpleNamespace(returncode=code, stdout=out.getvalue(), stderr=err.getvalue())


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    path = tmp_path_factory.mktemp("tuning")
    out = run_cli(
        "tuning", "--quick", "--json", "--out", str(path / "t.json"), "--plot", str(path / "t.png")
    )
    assert out.returncode == 0, out.stderr
    o = json.loads(out.stdout)
    o["_dir"] = path
    return o


def test_tuning_json_structure(quick):
    cfg = tuning.TuningConfig.quick()
    th = quick["thresholds"]
    assert th["freqs_hz"] == list(cfg.freqs_hz)
    for c in tuning.CLASSES:
        assert quick["receptors"][c] > 0
        for unit in tuning.UNITS:
            for crit in tuning.CRITERIA:
                v = th["thresholds_m"][c][unit][crit]
                assert len(v) == len(cfg.freqs_hz)
                # a threshold is inside the searched range or inf (none found)
                assert all(
                    x == math.inf or cfg.amp_range_m[0] <= x <= cfg.amp_range_m[1] for x in v
                ), v
            # the most sensitive unit is at least as sensitive as the centred one
            for crit in tuning.CRITERIA:
                best = np.array(th["thresholds_m"][c]["best"][crit])
                centred = np.array(th["thresholds_m"][c]["centred"][crit])
                assert np.all(best <= centred * th["precision"] * (1 + 1e-12)), (c, crit)
    ri = quick["rate_intensity"]
    assert ri["depths_m"] == list(cfg.depths_m)
    for c in tuning.CLASSES:
        assert len(ri["rates"][c]["hold_hz"]) == len(cfg.depths_m)
    # published ranges travel with the result, each with its source
    for boxes in quick["published"]["thresholds"].values():
        assert boxes and all(
            b["source"] and b["amplitude_m"][0] < b["amplitude_m"][1] for b in boxes
        )
    assert json.loads((quick["_dir"] / "t.json").read_text())["thresholds"] == th
    assert (quick["_dir"] / "t.png").read_bytes()[:4] == b"\x89PNG"


def test_entrainment_needs_at_least_the_absolute_amplitude(quick):
    # Entrainment (>= 1 locked spike per cycle, over >= min_cycles cycles)
    # implies the absolute criterion (>= 0.1 per cycle and >= 1, locked), so
    # whatever the model its threshold is not lower, up to the bisection's
    # final bracket ratio.
    th = quick["thresholds"]
    for c in tuning.CLASSES:
        for unit in tuning.UNITS:
            a = np.array(th["thresholds_m"][c][unit]["absolute"], dtype=float)
            e = np.array(th["thresholds_m"][c][unit]["entrainment"], dtype=float)
            assert np.all(a <= e * th["precision"] * (1 + 1e-12)), (c, unit, a, e)


def test_sa1_rate_rises_monotonically_with_indentation(quick):
    # Knibestol & Vallbo 1980: the SA I static rate grows with indentation;
    # the built model's centred SA1 must not fall as the pin goes deeper and
    # must fire at the deepest indentation.
    hold = np.array(quick["rate_intensity"]["rates"]["SA1"]["hold_hz"])
    assert np.all(np.diff(hold) >= 0), hold
    assert hold[-1] > hold[0] and hold[-1] > 0


def test_tuning_human_output_and_bad_config():
    out = run_cli("tuning", "--quick", "--freqs", "100")
    assert out.returncode == 0, out.stderr
    assert "thresholds (um)" in out.stdout and "rate-intensity" in out.stdout
    with pytest.raises(ValueError, match=r"freqs_hz = 4000.0 is out of range"):
        tuning.run(tuning.TuningConfig(freqs_hz=(4000.0,)))
    with pytest.raises(ValueError, match=r"amp_range_m\[1\] = 0.001 is out of range"):
        tuning.TuningConfig(amp_range_m=(1e-8, 1e-3), preindent_m=0.5e-3).validate()
    bad = run_cli("tuning", "--quick", "--min-cycles", "3")
    assert bad.returncode == 2 and "min_cycles = 3 is out of range" in bad.stderr


def test_probe_cli_json_and_errors():
    out = run_cli(
        "probe",
        "--json",
        "--waveform",
        "sine",
        "--freq",
        "100",
        "--amplitude",
        "5e-6",
        "--duration",
        "0.2",
        "--nx",
        "24",
        "--pitch",
        "3e-4",
    )
    assert out.returncode == 0, out.stderr
    o = json.loads(out.stdout)
    assert o["waveform"] == dict(
        kind="sine", amplitude_m=5e-6, freq_hz=100.0, duration_s=0.2, ramp_s=0.05
    )
    assert set(o["rates_hz"]) == {"SA1", "RA", "PC"}
    assert o["max_displacement_error_m"] < 1e-7
    bad = run_cli("probe", "--depth", "0.01")
    assert bad.returncode == 2 and "depth_m = 0.01 is out of range" in bad.stderr
    bad = run_cli("probe", "--waveform", "trace")
    assert bad.returncode == 2 and "--trace FILE" in bad.stderr


def test_probe_cli_trace_file_and_plate(tmp_path):
    f = tmp_path / "trace.txt"
    np.savetxt(f, 1e-4 * np.sin(np.linspace(0, 2 * np.pi, 101)))
    out = run_cli(
        "probe",
        "--json",
        "--waveform",
        "trace",
        "--trace",
        str(f),
        "--trace-dt",
        "1e-3",
        "--nx",
        "24",
        "--pitch",
        "3e-4",
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["waveform"]["samples"] == 101
    out = run_cli(
        "probe",
        "--json",
        "--probe",
        "plate",
        "--waveform",
        "sine",
        "--freq",
        "200",
        "--amplitude",
        "1e-6",
        "--duration",
        "0.15",
        "--press",
        "0.3",
        "--nx",
        "24",
        "--pitch",
        "3e-4",
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["force_steady_mean_n"] == pytest.approx(0.3, rel=0.03)


# --- atonal interval on the protocol's own stress (issue 14) -------------------------------

# Entrainment (1:1) over absolute threshold for RA and PC, one low and one best
# frequency each, on the stress the full pipeline computes at the centred unit
# under tuning.run's pin (1 mm flat pin, 0.5 mm pre-indentation, 48 x 48
# taxels at 0.15 mm, dt 1e-4 s), counted over TuningConfig's minimum of 20
# cycles after the ramp with the module's count criteria (absolute: >= max(2,
# 0.1/cycle) extra spikes; 1:1: >= 1 extra per cycle; RA and PC are silent
# under the static pre-indentation, so the phase-lock alternatives add
# nothing). The stress is linear in the amplitude (checked below), so each
# threshold follows by bisection on the scale of one run's stress change,
# driving core.receptor_run as the plugin's receptor stage (tuning.atonal_ratio;
# tests/science/test_afferents.py: it reproduces the plugin's spikes bit for
# bit with the receptor's stream). With noise a unit's ratio is a random draw:
# 12 seeds (each a noise path and a population variant), their median against
# tuning.PUBLISHED_ENTRAINMENT_RATIO (1.5-10x; issue 14: > 1.5x) and each
# above 1.2x, as the receptor-stage test does at 5-20 Hz. At 5 Hz the median
# over 24 seeds is 1.65x with 17% of units below 1.5x (README), so 5 Hz is
# not asserted here.
ATONAL_CASES = (("RA", 10.0), ("RA", 40.0), ("PC", 40.0), ("PC", 250.0))
ATONAL_REF_M = 10e-6  # the sine amplitude whose stress change is scaled
ATONAL_SEEDS = range(12)


# RA at 80 Hz: TouchSim's nine RA fits need 8-15x their absolute threshold
# to follow every cycle (mjtouch/tuning.py, computed from hsaal/touchsim);
# the 12-seed median is held to that range widened by 25% each way, the
# spread of such a median here (24 seeds: 10-90% of single units 7-20x). With
# `ra_saturation` 5 the median was ~100x (plugin/README.md, RA).
RA_80HZ_RATIO = (8.0 / 1.25, 15.0 * 1.25)
PIN_FREQS_HZ = sorted({f for _, f in ATONAL_CASES} | {80.0})


@pytest.fixture(scope="module")
def pin_sine_stress():
    return tuning.pin_sine_stress(
        tuning.TuningConfig(), PIN_FREQS_HZ, (0.0, ATONAL_REF_M, 2 * ATONAL_REF_M)
    )


@pytest.mark.parametrize("f", PIN_FREQS_HZ)
def test_pin_stress_is_linear_in_amplitude(pin_sine_stress, f):
    # tuning.atonal_ratio scales the first amplitude's stress change
    run = pin_sine_stress[f]
    q0, q1, q2 = (s[:, [run["units"]["RA"], run["units"]["PC"]]] for s in run["stress"])
    d1, d2 = q1 - q0, q2 - q0
    assert np.abs(d2 - 2 * d1).max() <= 0.01 * np.abs(d2).max(), np.abs(d2 - 2 * d1).max()


@pytest.mark.parametrize("cls, f", ATONAL_CASES)
def test_entrainment_over_1_5x_absolute_on_the_pin(pin_sine_stress, cls, f):
    ratios = np.array([tuning.atonal_ratio(pin_sine_stress[f], cls, s) for s in ATONAL_SEEDS])
    assert np.all(np.isfinite(ratios)), ratios
    lo, hi = tuning.PUBLISHED_ENTRAINMENT_RATIO[cls]
    assert lo < np.median(ratios) < hi, ratios
    assert ratios.min() > 1.2, ratios


def test_ra_follows_80_hz_within_touchsims_range(pin_sine_stress):
    ratios = np.array([tuning.atonal_ratio(pin_sine_stress[80.0], "RA", s) for s in ATONAL_SEEDS])
    assert np.all(np.isfinite(ratios)), ratios
    lo, hi = RA_80HZ_RATIO
    assert lo < np.median(ratios) < hi, ratios
