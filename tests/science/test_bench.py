"""`python -m mjtouch bench`: structure, error metrics and the accuracy trend.

Timings are never asserted (the machine is shared and noisy); the run's
structure, finiteness, determinism and its errors are.
"""

import io
import json
import math
import re
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from mjtouch import bench, cli
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

ERROR_KEYS = ("stress_rms_rel", "stress_rms_pa", "peak_freq_hz", "peak_amp_rel", "spike_rate_rel")


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    png = tmp_path_factory.mktemp("bench") / "bench.png"
    # --progress on: the bar is quiet with --json and off a terminal, and its
    # count is checked below
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "mjtouch",
            "bench",
            "--quick",
            "--json",
            "--progress",
            "on",
            "--plot",
            str(png),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout), out.stderr, png


def test_quick_structure_and_finiteness(quick):
    o, stderr, png = quick
    b = o["baselines"]
    for key in (
        "bare_mujoco_us_per_step",
        "native_tactile_us_per_step",
        "idle_plugin_us_per_step",
        "full_pipeline_us_per_step",
        "homogeneous_kernel_us_per_step",
    ):
        assert math.isfinite(b[key]) and b[key] > 0, key
    assert b["native_tactile_taxels"] == b["taxels"]
    assert b["contacts_pressed"] >= 1 and b["contacts_idle"] == 0  # pressed vs lifted state
    assert all(v is None or math.isfinite(v) for v in o["ratios"].values())
    knobs = [r["knob"] for r in o["rows"]]
    assert {"pitch", "pressure", "stress_method", "receptors", "timestep"} <= set(knobs)
    for row in o["rows"]:
        assert {"knob", "setting", "us_per_step", "errors", "pareto", "pareto_spike_rate"} <= set(
            row
        )
        assert math.isfinite(row["us_per_step"]) and row["us_per_step"] > 0
        assert row["wall_s_per_sim_s"] == pytest.approx(
            row["us_per_step"] * 1e-6 / row["timestep_s"]
        )
        for key in ERROR_KEYS:
            v = row["errors"][key]
            assert v is None or (math.isfinite(v) and v >= 0), (row["setting"], key)
        assert row["errors"]["stress_rms_rel"] is not None
        assert row["errors"]["spike_rate_rel"] is not None
    for name in dict.fromkeys(knobs):  # one reference per knob, listed last
        refs = [r["reference"] for r in o["rows"] if r["knob"] == name]
        assert refs[-1] and sum(refs) == 1, name
    assert o["effects"] and all(math.isfinite(r["us_per_step"]) for r in o["effects"])
    t = o["threads"]
    assert t["speedup_2_threads"] > 0 and t["identical_across_threads"]
    s = o["scaling"]
    assert s["active_taxels"]["power_law"]["exponent"] is not None
    assert s["receptors"]["power_law"]["exponent"] is not None
    # active taxels grow as the pitch shrinks (same contact patch, finer cells)
    active = [p[0] for p in s["active_taxels"]["points"]]
    assert active == sorted(active)
    assert png.stat().st_size > 10_000
    # the progress bar (tqdm: "done/total [") counts exactly the items it announced
    seen = [(int(a), int(b)) for a, b in re.findall(r"(\d+)/(\d+) \[", stderr)]
    done = [d for d, _ in seen]
    assert seen and len({t for _, t in seen}) == 1 and done == sorted(done)
    assert done[-1] == seen[-1][1]


def test_quick_references_are_exact_and_runs_repeat(quick):
    o, _, _ = quick
    for row in o["rows"]:
        if row["reference"]:
            for key in ERROR_KEYS:
                assert row["errors"][key] in (0.0, None), (row["knob"], key)
            assert row["errors"]["stress_rms_rel"] == 0.0
        else:  # a different setting is measurably different
            assert row["errors"]["stress_rms_rel"] > 0, row["setting"]
        assert row["repeats_identical"], row["setting"]
    assert o["baselines"]["repeats_identical"]
    assert all(r["repeats_identical"] for r in o["effects"])


def cycle_response(pitch_m: float, period_m: float = 1e-3) -> float:
    """The default grid_cycle 4's response to a line of period_m across x:
    its four offset grids' solutions are deposited on the nearest taxel
    cells, moved by 0, +-1/4 and (in halves) +-1/2 cell, a five-tap filter
    of weights 1/4, 1/4, 1/4 and 1/8, 1/8."""
    k = 2 * np.pi / period_m
    return 0.25 + 0.5 * np.cos(k * pitch_m / 4) + 0.25 * np.cos(k * pitch_m / 2)


def test_quick_pitch_errors_shrink_toward_reference(quick):
    o, _, _ = quick
    rows = [r for r in o["rows"] if r["knob"] == "pitch" and not r["reference"]]
    assert len(rows) >= 2
    rows.sort(key=lambda r: -r["pitch_m"])  # coarsest first
    # the stress converges with the pitch; spike rates need not be monotone
    # (a PC's rate depends on which grating harmonics a grid renders: README,
    # "What accuracy costs"), only finite. The V/D line's amplitude loses at
    # most the default grid cycle's low-pass against the reference's, plus
    # 1% (how a grid resolves the 0.45 mm ridges, 2.25 vs 3 cells, moves it
    # by a few 1e-3 either way).
    errs = [r["errors"]["stress_rms_rel"] for r in rows]
    assert all(a > b for a, b in zip(errs, errs[1:])), errs
    ref = next(r for r in o["rows"] if r["knob"] == "pitch" and r["reference"])
    for r in rows:
        loss = 1 - cycle_response(r["pitch_m"]) / cycle_response(ref["pitch_m"])
        assert r["errors"]["peak_amp_rel"] < loss + 0.01, (r["setting"], loss)
    assert all(np.isfinite(r["errors"]["spike_rate_rel"]) for r in rows)
    # every pitch row has the same receptors (explicit sites)
    assert len({r["receptors"] for r in o["rows"] if r["knob"] == "pitch"}) == 1


def test_markdown_has_a_row_per_setting_and_bold_references(quick):
    o, _, _ = quick
    buf = io.StringIO()
    bench.print_markdown(o, buf)
    lines = buf.getvalue().splitlines()
    table = lines[2 : 2 + len(o["rows"])]
    assert all(line.count("|") == 8 for line in table), table
    for line, row in zip(table, o["rows"]):
        assert row["setting"] in line
        assert ("**" in line) == row["reference"], line
        us = float(line.split("|")[3])
        assert us == pytest.approx(row["us_per_step"], rel=5e-3, abs=0.05), (line, row)
    assert sum("baseline" in line for line in lines) == 1


def test_report_lists_every_row_and_marks_the_front(quick):
    o, _, _ = quick
    buf = io.StringIO()
    bench.print_report(o, buf)
    text = buf.getvalue()
    table = [
        line
        for line in text.splitlines()
        if line[:2] in ("* ", "  ") and line[2:].split(" ")[0] in {r["knob"] for r in o["rows"]}
    ]
    assert len(table) == len(o["rows"])
    assert sum(line.startswith("*") for line in table) == sum(r["pareto"] for r in o["rows"])
    for key in ("Baselines", "Effects", "Threads", "Scaling"):
        assert key in text


# --- the metrics on signals with known answers ----------------------------------------


def _trace(dt, duration, amp=100.0, f_hz=25.0, spikes_per_rec=10, classes=("SA1", "RA", "PC")):
    n = int(round(duration / dt))
    t = (np.arange(n) + 1) * dt  # row k is the step ending at (k + 1) dt
    nrec = len(classes)
    phase = np.arange(nrec)[None, :]
    stress = amp * np.sin(2 * np.pi * f_hz * t[:, None] + phase)
    spikes = np.zeros((n, nrec), dtype=np.int64)
    k0 = int(round(bench.SKIP_S / dt))
    for r in range(nrec):  # spikes_per_rec spikes spread over the window
        spikes[np.linspace(k0, n - 1, spikes_per_rec).astype(int), r] = 1
    return bench.Trace(stress, spikes, np.array(classes), dt)


def test_errors_of_identical_and_scaled_traces():
    ref = _trace(1e-4, 0.2)
    e = bench.errors(ref, ref)
    assert all(e[k] == 0 for k in ERROR_KEYS)
    assert e["ref_peak_hz"] == pytest.approx(25.0, abs=1 / 0.19)  # within one FFT bin
    scaled = bench.Trace(1.1 * ref.stress, ref.spikes, ref.classes, ref.dt_s)
    e = bench.errors(scaled, ref)
    # every quantity is linear in the amplitude: relative errors are exactly 0.1
    assert e["stress_rms_rel"] == pytest.approx(0.1, rel=1e-9)
    assert e["peak_amp_rel"] == pytest.approx(0.1, rel=1e-9)
    assert e["peak_freq_hz"] == pytest.approx(0.0, abs=1e-9)


def test_errors_align_coarser_timesteps_with_the_reference():
    ref = _trace(1e-4, 0.2)
    row = _trace(4e-4, 0.2)  # the same signal sampled every 4th reference step
    e = bench.errors(row, ref)
    # same times: equal up to rounding of t (|error| < 1e-12 of the amplitude); off by
    # one reference step it would be 2 pi f dt ~ 1.6%
    assert e["stress_rms_rel"] < 1e-12
    # 10 spikes per receptor in both windows of equal length: equal rates
    assert e["spike_rate_rel"] == pytest.approx(0.0, abs=1e-12)
    more = bench.Trace(row.stress, row.spikes.copy(), row.classes, row.dt_s)
    extra = np.nonzero(more.spikes.sum(axis=1) == 0)[0]
    more.spikes[extra[extra >= int(round(bench.SKIP_S / row.dt_s))][:2], :] = 1
    # 12 spikes against 10 in every class: rate error 2 / 10
    assert bench.errors(more, ref)["spike_rate_rel"] == pytest.approx(0.2, rel=1e-12)
    with pytest.raises(ValueError, match="whole multiple"):
        bench.errors(_trace(1.5e-4, 0.2), ref)


def test_class_mean_basis_ignores_which_receptor_is_which():
    ref = _trace(1e-4, 0.15, classes=("RA", "RA", "PC"))
    swapped = bench.Trace(ref.stress[:, [1, 0, 2]], ref.spikes, ref.classes, ref.dt_s)
    assert bench.errors(swapped, ref)["stress_rms_rel"] > 0.1  # receptor by receptor
    assert bench.errors(swapped, ref, basis="class mean")["stress_rms_rel"] < 1e-15


def test_short_windows_have_no_spectral_errors():
    ref = _trace(1e-4, 0.05)  # 40 ms window < SPECTRAL_MIN_S
    e = bench.errors(ref, ref)
    assert e["peak_freq_hz"] is None and e["peak_amp_rel"] is None
    assert e["stress_rms_rel"] == 0.0


def test_pareto_front():
    costs = [1.0, 2.0, 3.0, 4.0, 5.0]
    errs = [0.5, 0.6, 0.1, 0.0, None]
    # (2, 0.6) is beaten by (1, 0.5) on both; no error, no place on the front
    assert bench.pareto_front(costs, errs) == [True, False, True, True, False]
    assert bench.pareto_front([1.0, 1.0], [0.2, 0.2]) == [True, True]  # ties dominate neither


def test_fits_recover_known_laws():
    x = np.array([100.0, 300.0, 1000.0, 5000.0])
    f = bench.fit_power_law(x, 3.0 * x**1.7)
    assert f["exponent"] == pytest.approx(1.7, rel=1e-10)
    assert f["prefactor"] == pytest.approx(3.0, rel=1e-9)
    assert f["r2"] == pytest.approx(1.0, abs=1e-12)
    a = bench.fit_affine(x, 5.0 + 2.0 * x)
    assert a["intercept"] == pytest.approx(5.0, rel=1e-9)
    assert a["slope"] == pytest.approx(2.0, rel=1e-12)
    assert bench.fit_power_law([1.0, 1.0], [2.0, 3.0])["exponent"] is None  # no spread in x


# --- sites, scenes, command line -------------------------------------------------------


def test_lattice_sites_are_the_same_receptors_on_every_grid():
    grids = [(bench.odd_nx(p, 8e-3), p) for p in (200e-6, 150e-6, 100e-6)]
    sites = bench.lattice_sites(grids, radius_m=3e-3)
    positions = []
    for nx, p in grids:
        tip = scenes.Fingertip(nx=nx, pitch_m=p, ridges=False, skin={"sites": sites})
        model = scenes.build_model(tip, scenes.Texture(kind="flat"))
        layout = SkinLayout.from_model(model)
        positions.append(layout.positions_m)
        classes = layout.classes
    for pos in positions[1:]:  # the plugin snaps sites to taxel centres: none moved
        np.testing.assert_allclose(pos, positions[0], rtol=0, atol=1e-12)
    given = np.array([[float(v) for v in s.split()[1:]] for s in sites.split(";")])
    order = np.argsort(
        [{"SA1": 0, "RA": 1, "PC": 2}[s.split()[0]] for s in sites.split(";")], kind="stable"
    )  # the plugin lists SA1, RA, PC
    np.testing.assert_allclose(positions[0], given[order], rtol=0, atol=1e-12)
    counts = {c: int((classes == c).sum()) for c in ("SA1", "RA", "PC")}
    assert counts["RA"] > counts["SA1"] > counts["PC"] > 0  # density order 140 > 70 > 21
    with pytest.raises(ValueError, match="not on the taxel centres"):
        bench.lattice_sites([(33, 250e-6)], radius_m=3e-3)  # 0.6 mm is 2.4 pitches
    with pytest.raises(ValueError, match="mix odd and even"):
        bench.lattice_sites([(33, 200e-6), (64, 100e-6)])


def test_bare_and_native_tactile_scenes():
    tip = scenes.Fingertip(nx=16, pitch_m=4e-4, ridges=False)

    def spec():
        return scenes.scene_spec(tip, scenes.Texture(), scenes.Protocol(timestep_s=2e-4))

    full = spec().compile()
    bare = bench.strip_plugin(spec()).compile()
    assert full.nplugin == 1 and bare.nplugin == 0 and bare.nsensor == 0
    assert (bare.nq, bare.nv, bare.nu, bare.ngeom) == (full.nq, full.nv, full.nu, full.ngeom)
    tact = bench.add_native_tactile(spec(), tip.nx, tip.pitch_m, tip.semi_axes_m).compile()
    assert tact.mesh_vertnum[0] == 16 * 16 and tact.nsensordata == 3 * 16 * 16
    proto = scenes.Protocol(timestep_s=2e-4)
    for pressed in (True, False):
        data = mujoco.MjData(tact)
        ctrl = scenes.controls(proto, 0.01)
        if not pressed:
            ctrl[:, 1] = 0
        for row in ctrl:
            data.ctrl[:] = row
            mujoco.mj_step(tact, data)
        depth = data.sensordata[:256]
        # pressed: the pad sinks ~1 mm into the plate, the pole's vertices with it;
        # lifted: the pad hovers, no contact, no depth
        assert (depth.max() > 1e-4) if pressed else (depth.max() == 0), pressed


def test_one_line_knob_overrides_are_checked():
    k = bench.knob("ridges", "ridges", (False,), True)
    assert [own for _, own, _ in k.all_settings()] == [{"ridges": False}, {"ridges": True}]
    assert [ref for *_, ref in k.all_settings()] == [False, True]
    with pytest.raises(ValueError, match="unknown override 'colour'"):
        bench.scene_parts({"colour": 1})
    with pytest.raises(ValueError, match="density_scale"):
        bench.scene_parts({"density_scale": -1})


@pytest.mark.parametrize(
    "args,msg",
    [
        (["--knobs", "pitch,wood"], "unknown knob 'wood'; valid: pitch, pressure"),
        (["--knob-steps", "pitch=many"], "--knob-steps 'pitch=many' is not KNOB=N"),
        (["--knob-steps", "wood=100"], "knob_steps: unknown knob 'wood'"),
        (["--repeats", "0"], "repeats = 0 is out of range; valid range [1, 100]"),
        (["--duration", "0.001"], "duration_s = 0.001 is out of range"),
        (["--from-json", "/nonexistent/bench.json"], "not a saved bench result"),
    ],
)
def test_bad_arguments(args, msg, capsys):
    assert cli.main(["bench", "--quick", *args]) == 2
    assert msg in capsys.readouterr().err
