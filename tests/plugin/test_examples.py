"""Every example runs, with small arguments, and shows what it claims."""

from __future__ import annotations

import json
import math
import os
import pathlib
import re
import runpy
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
RIDGE_PITCH_M = 0.45e-3  # scenes.Fingertip's default lambda


def example_main(name: str):
    return runpy.run_path(str(EXAMPLES / name), run_name="example")["main"]


def run_json(name: str, args: list[str], capsys):
    assert example_main(name)(args + ["--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_quickstart_peak_at_v_over_d(capsys):
    speed, period = 0.025, 1e-3
    small = ["--nx", "48", "--pitch", "2e-4", "--dt", "5e-4", "--duration", "0.3"]
    r = run_json("quickstart.py", small, capsys)
    assert r["v_over_d_hz"] == pytest.approx(speed / period)
    assert r["v_over_lambda_hz"] == pytest.approx(speed / RIDGE_PITCH_M)
    # a grating of period D scanned at V: the strongest line at V/D, within
    # one FFT bin (the window is 0.2 s: 5 Hz bins)
    assert abs(r["peaks_hz"][0] - speed / period) <= r["fft_bin_hz"]
    assert r["peak_at_v_over_d"] is True
    rates = r["rates_hz"]
    assert set(rates) == {"SA1", "RA", "PC"}
    assert all(math.isfinite(v) and v >= 0 for v in rates.values())
    assert rates["SA1"] > 0  # SA1 sustains while pressed
    assert example_main("quickstart.py")(small) == 0
    text = capsys.readouterr().out
    assert "V/D = 25.00 Hz" in text and "within one bin: yes" in text


def test_spectral_rollout_lines_and_ridge_filtering(tmp_path, capsys):
    png = tmp_path / "spectra.png"
    speed, period = 0.04, 1e-3
    r = run_json("spectral_rollout.py", ["--duration", "0.3", "--plot", str(png)], capsys)
    assert r["pressure"] == "elastic"
    for name in ("grating_ridged", "grating_smooth"):
        s = r["spectra"][name]
        assert abs(s["peaks_hz"][0] - speed / period) <= s["fft_bin_hz"], (name, s["peaks_hz"])
    # fingerprint ridges raise the power at V/lambda over a fine random
    # texture (Scheibert et al. 2009); mjtouch.testing's documented check
    # is a factor 10 (measured: 10.3 with the layered skin over 0.3 s)
    assert r["v_over_lambda_hz"] == pytest.approx(speed / RIDGE_PITCH_M)
    assert r["random_ridged_over_smooth_at_v_over_lambda"] >= 10
    img = np.asarray(Image.open(png).convert("RGB"))
    assert img.shape == (700, 800, 3)  # figsize 8 x 7 in at 100 dpi
    blue = (img[..., 2].astype(int) - img[..., 0] > 80).sum()  # the ridged curves
    orange = (img[..., 0].astype(int) - img[..., 2] > 120).sum()  # the smooth ones
    assert blue > 500 and orange > 500, (blue, orange)


def binomial_tail(n: int, k: int, p: float) -> float:
    """P(X >= k) for X ~ Binomial(n, p)."""
    return sum(math.comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k, n + 1))


def test_texture_classification_beats_chance_with_touch_only(capsys):
    results = run_json("texture_classification.py", ["--episodes", "4", "--steps", "20"], capsys)
    by_touch = {r["touch"]: r for r in results}
    touch, none = by_touch["counts"], by_touch["none"]
    nclass = len(touch["classes_m"])
    chance = 1.0 / nclass
    assert touch["chance"] == pytest.approx(chance) == none["chance"]
    n = touch["test_episodes"]
    assert n == nclass * 2  # 4 episodes per class, half of them tested
    correct = round(touch["accuracy"] * n)
    # well above chance: guessing would do this well with probability < 1e-3
    assert binomial_tail(n, correct, chance) < 1e-3, (touch["accuracy"], chance)
    assert np.trace(touch["confusion"]) == correct
    # without touch every texture gives the same observations (they do not
    # collide in MuJoCo), so the classifier answers one class for all:
    # exactly chance
    assert none["accuracy"] == pytest.approx(chance)
    assert sum(1 for row in none["confusion"] if row == none["confusion"][0]) == nclass


def test_viewer_demo_writes_offscreen_frames(tmp_path):
    out = tmp_path / "frames"
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    proc = subprocess.run(
        [
            sys.executable,
            str(EXAMPLES / "viewer_demo.py"),
            "--offscreen",
            str(out),
            "--frames",
            "3",
            "--every",
            "0.02",
            "--settle",
            "0.3",
            "--size",
            "480",
            "300",
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    # no backend: the demo fails naming what to install (the test fails too)
    assert proc.returncode == 0, proc.stderr
    times = [float(t) for t in re.findall(r"^t = ([0-9.]+) s", proc.stdout, re.M)]
    assert times == pytest.approx([0.30, 0.32, 0.34], abs=1e-9)
    assert proc.stdout.count("F = 0.50 N   V = 25 mm/s   grating D = 1 mm") == 3
    frames = [np.asarray(Image.open(out / f"frame_{k:03d}.png").convert("RGB")) for k in range(3)]
    for a, b in zip(frames, frames[1:]):
        assert a.shape == (300, 480, 3)
        changed = (np.abs(a.astype(int) - b.astype(int)).max(axis=2) > 30).mean()
        assert changed > 0.002, changed  # the drawing and the figures move


def test_bench_pressure_runs_every_model_and_grid():
    # a benchmark, so no timing assertion: every model at every grid reports
    # finite positive costs and ratios against baselines of the same run
    ex = runpy.run_path(str(EXAMPLES / "bench_pressure.py"))
    rows = ex["measure"](steps=5, elastic_steps=2, rounds=1)
    assert {(r["taxels"], r["model"]) for r in rows} == {
        (n * n, m) for n in (64, 128, 256) for m in ("contacts", "winkler", "elastic")
    }
    for r in rows:
        for k in ("us_per_step", "over_bare", "over_native_tactile", "native_tactile_us_per_step"):
            assert np.isfinite(r[k]) and r[k] > 0, (r, k)


def test_bench_elastic_compares_the_solvers_against_the_reference():
    # a benchmark, so no timing assertion: both solvers report iterations and
    # errors against the tight reference, and finite positive costs
    ex = runpy.run_path(str(EXAMPLES / "bench_elastic.py"))
    start = ex["settled"]("slide_grating")
    acc = ex["accuracy"]("slide_grating", start, 4)
    solvers = ("pk", "pcg double", "pcg float")  # pcg with double and float FFTs
    for s in solvers:
        assert acc[s]["iterations_median"] >= 1
        assert 0 < acc[s]["pressure_rms_rel"] < 1e-2, acc
    t = ex["timing"]("slide_grating", start, 2, 1)
    assert set(t) == {(s, st) for s in (*solvers, "winkler") for st in ("stages 1-2", "full")}
    assert all(np.isfinite(v).all() and min(v) > 0 for v in t.values()), t
    tt, yard = ex["thread_timing"]("slide_grating", start, 2, 1, 2)
    assert set(tt) == {(n, st) for n in (1, 2) for st in ("stages 1-2", "full", "winkler")}
    assert all(c > 0 and w > 0 for v in tt.values() for c, w in v), tt
    assert len(yard) == 1 and yard[0] > 0


@pytest.mark.parametrize("yaw", ["0", "20"])
def test_bench_surface_fast_paths_match_reference(yaw, capsys):
    # a benchmark, so no timing assertion: stages 1-2 of the default scene,
    # replayed through the fast and the reference paths, give bit-identical
    # pressures with the pad aligned (fast paths taken) and turned (general)
    main = example_main("bench_surface.py")
    assert main(["--steps", "5", "--repeats", "1", "--lead-in-s", "0.005", "--yaw-deg", yaw])
    out = capsys.readouterr().out
    assert "100% of steps in contact" in out and "bit-identical: True" in out


def test_mesh_textures_braille_and_knurl_from_mesh_files(tmp_path, capsys):
    # coarse meshes and a small skin: the example's pipeline in seconds
    out = run_json(
        "mesh_textures.py",
        [
            "--out",
            str(tmp_path),
            "--mesh-grid",
            "1e-4",
            "--resolution",
            "5e-5",
            "--duration",
            "0.25",
            "--nx",
            "48",
            "--pitch",
            "2e-4",
        ],
        capsys,
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["braille.stl", "knurl.ply"]
    # the meshes' reliefs (their highest vertices) survive export in mm and
    # from_mesh: cell means sit below the highest vertex by at most the
    # steepest facet slope there times half a mesh step (0.05 mm): dots,
    # slope <= (0.07 + 0.1) / 0.89 (curvature radius 0.89 mm) -> 8.5 um; the
    # knurl's 0.2 mm crests, faceted on a 0.1 mm grid, by the flank slope
    # 0.25 mm / 0.4 mm -> 31 um. Measured: 1.4 um and 2.7 um.
    ex = runpy.run_path(str(EXAMPLES / "mesh_textures.py"), run_name="example")
    x = np.arange(-0.02, 0.02 + 5e-5, 1e-4)
    y = np.arange(-0.008, 0.008 + 5e-5, 1e-4)
    for name, drop in (("braille", 8.5e-6), ("knurl", 31e-6)):
        top = ex["SURFACES"][name][0](x, y).max()
        assert top - drop <= out[name]["relief_m"] <= top + 1e-9
    k = out["knurl"]
    assert abs(k["peaks_hz"][0] - k["expected_hz"]) <= k["fft_bin_hz"]
    assert out["braille"]["expected_hz"] is None
    for r in out.values():
        assert sum(r["rates_hz"].values()) > 0


def test_pc_grid_line_elastic_not_winkler(capsys):
    # README "What accuracy costs": the elastic contact set moving cell by
    # cell puts a line at V / pitch into the PC stress; Winkler's pressure,
    # continuous in the overlap, does not (measured 1300x apart at 0.2 mm)
    rows = run_json("pc_grid_line.py", ["--small", "--duration", "0.2"], capsys)
    el, wk = rows[0], rows[2]
    assert (el["pressure"], wk["pressure"]) == ("elastic", "winkler")
    assert el["pitch_m"] == wk["pitch_m"] == 2e-4
    assert el["power_at_v_over_pitch_pa2"] > 100 * wk["power_at_v_over_pitch_pa2"] > 0
    assert el["pc_rate_hz"] > 5 * wk["pc_rate_hz"]
    # grid_cycle=4 (four sub-cell offset grids in turn) cancels
    # most of the line and of the PC rate it drove
    cyc = rows[3]
    assert (cyc["pressure"], cyc["grid_cycle"], el["grid_cycle"]) == ("elastic", 4, 1)
    assert cyc["power_at_v_over_pitch_pa2"] * 10 < el["power_at_v_over_pitch_pa2"]
    assert cyc["pc_rate_hz"] < 0.7 * el["pc_rate_hz"]


def test_pc_grid_line_static_follows_the_texture_edges(capsys):
    # Quasi-static slide, 64 x 0.2 mm, texture x2 (period 2 mm, edges rounded
    # over 0.1 mm: a one-cell ramp): the grid line (harmonic D / pitch = 10)
    # stands out of its neighbours; rounding the edges over 2 pitches (a
    # 4-cell ramp) removes it (measured 1170x), and so does averaging the
    # grid with the grid shifted by half a cell (140x), which keeps the
    # grating's fundamental (measured 0.92x)
    rows = {r["case"]: r for r in run_json("pc_grid_line_static.py", ["--small"], capsys)}
    base, edges, avg = rows["default"], rows["edges resolved"], rows["grid shift average"]
    m = base["grid_harmonic"]
    assert m == 10
    p = base["power_pa2"]
    assert p[str(m)] > 3 * max(p[str(m - 1)], p[str(m + 1)])
    assert edges["power_pa2"][str(m)] * 100 < p[str(m)]
    assert avg["power_pa2"][str(m)] * 30 < p[str(m)]
    assert avg["power_pa2"]["1"] == pytest.approx(p["1"], rel=0.25)


def test_pc_grid_shift_average_cancels_the_line(capsys):
    # The sliding scene at 0.2 mm on an odd and an even grid (centres half a
    # cell apart), the same PC receptors: the PC stress line at V / pitch
    # (125 Hz) is the same on both grids and cancels in their average
    # (measured 38 / 35 -> 0.35 Pa^2), and the PC rate, which the line drove,
    # drops (146 / 153 -> 112 Hz; 186 -> 102 before the PC's 2.5 ms
    # refractory period capped its bursts at 400 Hz)
    rows = run_json("pc_grid_shift.py", ["--small"], capsys)
    odd, even, avg = rows
    assert odd["v_over_pitch_hz"] == pytest.approx(125.0)
    for r in (odd, even):
        assert r["power_at_v_over_pitch_pa2"] > 30 * avg["power_at_v_over_pitch_pa2"] > 0
    assert avg["pc_rate_hz"] < 0.9 * min(odd["pc_rate_hz"], even["pc_rate_hz"])
