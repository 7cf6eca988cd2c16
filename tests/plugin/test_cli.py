"""The main job's command line."""

import json
import subprocess
import sys

import numpy as np
import pytest


def run(*args):
    return subprocess.run(
        [sys.executable, "-m", "mjtouch", *args], capture_output=True, text=True, timeout=600
    )


def test_slide_json_keys_and_peak():
    out = run(
        "slide",
        "--json",
        "--duration",
        "0.4",
        "--nx",
        "64",
        "--pitch",
        "1.5e-4",
        "--dt",
        "2e-4",
        "--speed",
        "0.03",
        "--period",
        "1e-3",
    )
    assert out.returncode == 0, out.stderr
    o = json.loads(out.stdout)
    for key in (
        "rates_hz",
        "peaks_hz",
        "expected_hz",
        "speed_m_s",
        "period_m",
        "ridge_pitch_m",
        "duration_s",
    ):
        assert key in o
    assert set(o["rates_hz"]) == {"SA1", "RA", "PC"}
    assert o["expected_hz"]["texture"] == pytest.approx(30.0)
    assert o["expected_hz"]["ridges"] == pytest.approx(0.03 / 0.45e-3)
    assert abs(o["peaks_hz"][0] - 30.0) <= o["fft_bin_hz"]
    assert all(np.isfinite(v) for v in o["rates_hz"].values())
    assert o["power_at_expected"]["ridges"] > 0
    # a grating is periodic: its stress has V/D harmonics only, no V/lambda line
    assert o["ridge_line_expected"] is False
    assert abs(o["nearest_peak_hz"]["texture"] - 30.0) <= o["fft_bin_hz"]
    assert o["nearest_peak_hz"]["ridges"] in o["peaks_hz"]
    # each expected line is judged in its own +-15% band: the grating's line
    # is the band's peak and stands far above its flanks
    line = o["lines"]["texture"]
    assert line["lo_hz"] == pytest.approx(30.0 * 0.85) and line["hi_hz"] == pytest.approx(34.5)
    assert abs(line["peak_hz"] - 30.0) <= o["fft_bin_hz"]
    assert line["contrast"] > 10 and 0 < line["share"] <= 1
    assert o["lines"]["ridges"]["expected_hz"] == pytest.approx(0.03 / 0.45e-3)
    # the default elastic contact cycles offset grids (two at dt 0.2 ms):
    # no grid line to report
    assert o["pressure"] == "elastic" and o["grid_line_hz"] is None
    assert o["grids_cycled"] == 2  # 4 grids x 0.2 ms exceed the 0.5 ms cycle; 2 do not


def test_grid_line_is_reported_where_one_grid_is_solved():
    # the slide's rule follows the plugin's CycleLength: a divisor of
    # grid_cycle whose cycle lasts at most 0.5 ms
    from mjtouch.experiments.slide import SlideParams, cycling_grids

    assert [
        cycling_grids(SlideParams(grid_cycle=4, dt_s=dt)) for dt in (1e-4, 1.25e-4, 2e-4, 5e-4)
    ] == [
        4,
        4,
        2,
        1,
    ]
    assert cycling_grids(SlideParams(grid_cycle=3, dt_s=2e-4)) == 1  # 2 does not divide 3


def test_slide_json_reports_ridge_line_power_for_smooth_skin():
    # smooth skin: no expected ridge line, but the power at V/lambda of the
    # configured pitch is reported for comparison with a ridged run
    out = run(
        "slide",
        "--json",
        "--no-ridges",
        "--duration",
        "0.2",
        "--nx",
        "48",
        "--pitch",
        "1.5e-4",
        "--dt",
        "2e-4",
        "--speed",
        "0.03",
        "--ridge-pitch",
        "6e-4",
    )
    assert out.returncode == 0, out.stderr
    o = json.loads(out.stdout)
    assert o["expected_hz"]["ridges"] is None
    assert o["ridge_line_expected"] is False and o["nearest_peak_hz"]["ridges"] is None
    assert np.isfinite(o["power_at_expected"]["ridges"]) and o["power_at_expected"]["ridges"] >= 0
    # the band at V/lambda of the configured pitch, for the same comparison
    assert o["lines"]["ridges"]["expected_hz"] == pytest.approx(0.03 / 6e-4)


def test_slide_human_output_and_plot(tmp_path):
    png = tmp_path / "s.png"
    out = run(
        "slide",
        "--duration",
        "0.2",
        "--nx",
        "48",
        "--pitch",
        "1.5e-4",
        "--dt",
        "2e-4",
        "--no-ridges",
        "--plot",
        str(png),
    )
    assert out.returncode == 0, out.stderr
    assert "V/D band" in out.stdout and "firing rates" in out.stdout
    assert "pressure model: elastic" in out.stdout
    assert "2 sub-cell offset grids in turn" in out.stdout  # at dt 0.2 ms
    assert "grid line" not in out.stdout
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--speed", "-1"], "argument --speed: -1.0 is out of range; valid range (0, 2] m/s"),
        (["--nx", "2"], "argument --nx: 2 is out of range; valid range [4, 512]"),
        (["--texture", "wood"], "invalid choice"),
        (["--pressure", "foam"], "invalid choice"),
        (["--dt", "0.1"], "argument --dt: 0.1 is out of range; valid range [1e-06, 0.005] s"),
    ],
)
def test_slide_bad_arguments(args, msg):
    out = run("slide", "--duration", "0.2", *args)
    assert out.returncode != 0
    assert msg in out.stderr


def test_slide_grid_shift_option():
    # --grid-shift sets the skin's grid_shift: the V/pitch line is cancelled,
    # so no grid line is reported; the texture line stays at V/D
    out = run(
        "slide",
        "--json",
        "--grid-shift",
        "--duration",
        "0.2",
        "--nx",
        "48",
        "--pitch",
        "1.5e-4",
        "--dt",
        "2e-4",
        "--speed",
        "0.03",
        "--period",
        "1e-3",
    )
    assert out.returncode == 0, out.stderr
    o = json.loads(out.stdout)
    assert o["grid_shift"] is True and o["grid_line_hz"] is None and o["grids_cycled"] == 0
    assert abs(o["nearest_peak_hz"]["texture"] - 30.0) <= o["fft_bin_hz"]
    assert all(np.isfinite(v) for v in o["rates_hz"].values())
    # it is an option of the elastic contact only: a clear error otherwise
    bad = run("slide", "--grid-shift", "--pressure", "winkler", "--duration", "0.2")
    assert bad.returncode == 2
    assert "--grid-shift" in bad.stderr and "elastic" in bad.stderr


def test_slide_too_short_to_analyse_is_a_clear_error():
    # the first 0.1 s of sliding settle and are not analysed: a shorter run
    # has no spectrum; the error names the option and its bound
    bad = run("slide", "--duration", "0.1", "--nx", "32", "--pitch", "3e-4")
    assert bad.returncode == 2
    assert "argument --duration: 0.1 is out of range; valid range [0.15, inf) s" in bad.stderr
    assert "Traceback" not in bad.stderr
