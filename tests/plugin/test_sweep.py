"""`mjtouch sweep` (mjtouch.sweep): parameters, the same table serially and on
a local two-worker Ray cluster, rows that agree with `mjtouch slide`, resume."""

import importlib.util
import json
import math
import pathlib
import re
import runpy
import subprocess
import sys

import numpy as np
import pytest

from mjtouch.experiments import sweep

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
# tiny runs: 24 x 24 taxels, 0.5 ms steps, 0.15 s of sliding (~0.3 s each)
SMALL = ["--duration", "0.15", "--dt", "5e-4", "--nx", "24", "--pitch", "2e-4"]
# four runs: two periods x two speeds
GRID = ["--period", "0.8e-3", "1.2e-3", "--speed", "0.02:0.04:0.02", *SMALL]


def require(module: str):
    """The sweep needs the `ray` extra; CI installs it with `test`. Missing, the
    test fails (a skipped sweep test would pass CI without ever running Ray)."""
    top = module.split(".")[0]
    if importlib.util.find_spec(top) is None:
        pytest.fail(
            f"{top} is not installed: the sweep tests need mjtouch's 'ray' extra, "
            "which the 'test' extra includes: pip install '.[test]'",
            pytrace=False,
        )
    return importlib.import_module(module)


def mjtouch(*args):
    return subprocess.run(
        [sys.executable, "-m", "mjtouch", *args], capture_output=True, text=True, timeout=600
    )


def run_sweep(out, *args):
    r = mjtouch("sweep", "--json", "--out", str(out), *args)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def read(path):
    return require("pyarrow.parquet").read_table(path)


# --- parameters ----------------------------------------------------------------


def test_values_ranges_and_names():
    v = sweep.parse_values(
        {
            "period": ["0.8e-3", "1.2e-3"],
            "speed_m_s": "0.02:0.05:0.01",
            "ridge-pitch": 4.5e-4,
            "ridges": [True, "off"],
            "nx": "16:24:8",
            "force": {"start": 0.25, "stop": 0.75, "step": 0.25},
        }
    )
    assert v["period_m"] == [0.8e-3, 1.2e-3]
    assert v["speed_m_s"] == [0.02, 0.03, 0.04, 0.05]  # decimal values, both ends included
    assert v["ridge_pitch_m"] == [4.5e-4] and v["ridges"] == [True, False]
    assert v["nx"] == [16, 24] and v["force_n"] == [0.25, 0.5, 0.75]
    runs = sweep.expand(v)
    assert len(runs) == 2 * 4 * 2 * 2 * 3
    assert runs[0]["texture"] == "grating" and runs[0]["duration_s"] == 1.0  # slide's defaults
    assert len({sweep.run_id(r) for r in runs}) == len(runs)
    assert sweep.run_id(dict(runs[0])) == sweep.run_id(runs[0])


def test_toml_config(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(
        'texture = "random"\nseed = [1, 2]\nrms_m = "1e-5:3e-5:1e-5"\n'
        'pressure = ["winkler", "elastic"]\n'
    )
    v = sweep.read_config(f)
    assert v == {
        "texture": ["random"],
        "seed": [1, 2],
        "rms_m": [1e-5, 2e-5, 3e-5],
        "pressure": ["winkler", "elastic"],
    }


@pytest.mark.parametrize(
    "values,msg",
    [
        ({"perod": 1e-3}, "unknown sweep parameter 'perod'; valid: texture, period_m"),
        ({"speed": "0.02:0.05:0.02"}, "STOP - START is not a whole number of STEPs"),
        ({"speed": "0.05:0.02:0.01"}, "needs STEP > 0 and STOP >= START"),
        ({"speed": -1}, "--speed = -1.0 is out of range; valid range (0, 2] m/s"),
        (
            {"texture": "wood"},
            "--texture = 'wood' is not one of 'grating', 'random', 'dots', 'flat'",
        ),
        ({"ridges": "maybe"}, "--ridges 'maybe' is not a boolean"),
        ({"texture": "grating:flat:1"}, "a range is START:STOP:STEP of a numeric option"),
        ({"nx": [2, 24]}, "--nx = 2 is out of range; valid range [4, 512]"),
    ],
)
def test_bad_values_name_the_option_and_range(values, msg):
    with pytest.raises(ValueError, match=None) as e:
        sweep.expand(sweep.parse_values(values))
    assert msg in str(e.value)


def test_bad_toml(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text("speed = [0.02, \n")
    with pytest.raises(ValueError, match=f"sweep config {f}"):
        sweep.read_config(f)
    f.write_text("duration = -1\n")
    with pytest.raises(
        ValueError,
        match=re.escape(f"{f}: duration = -1.0 is out of range; valid range [0.15, inf) s"),
    ):
        sweep.read_config(f)


# --- runs ------------------------------------------------------------------------


def test_ray_and_serial_give_the_same_table(tmp_path):
    require("ray")
    serial = run_sweep(tmp_path / "serial", *GRID, "--serial")
    # a local Ray cluster of two CPUs: two worker processes, one run each at a time
    on_ray = run_sweep(tmp_path / "ray", *GRID, "--num-cpus", "2")
    assert serial["ran"] == on_ray["ran"] == 4 and not serial["failed"] and not on_ray["failed"]
    assert on_ray["backend"] == "ray" and 1 <= on_ray["workers"] <= 2
    a, b = read(serial["table"]), read(on_ray["table"])
    assert a.num_rows == 4
    # bit-identical but for the wall time (pyarrow compares floats exactly)
    assert a.drop_columns(["wall_s"]).equals(b.drop_columns(["wall_s"]))
    rows = a.to_pylist()
    assert [(r["period_m"], r["speed_m_s"]) for r in rows] == [
        (0.8e-3, 0.02),
        (0.8e-3, 0.04),
        (1.2e-3, 0.02),
        (1.2e-3, 0.04),
    ]  # product order
    for r in rows:
        assert r["expected_texture_hz"] == pytest.approx(r["speed_m_s"] / r["period_m"])
        assert r["expected_ridges_hz"] == pytest.approx(r["speed_m_s"] / r["ridge_pitch_m"])
        assert r["wall_s"] > 0


def test_row_is_the_slide_with_the_same_options(tmp_path):
    s = run_sweep(tmp_path, "--period", "1.2e-3", "--speed", "0.04", *SMALL, "--serial")
    row = read(s["table"]).to_pylist()[0]
    r = mjtouch("slide", "--json", "--period", "1.2e-3", "--speed", "0.04", *SMALL)
    assert r.returncode == 0, r.stderr
    o = json.loads(r.stdout)
    for c in ("SA1", "RA", "PC"):
        assert row[f"{c.lower()}_rate_hz"] == o["rates_hz"][c]
        assert row[f"{c.lower()}_receptors"] == o["receptors"][c]
    assert row["peaks_hz"] == o["peaks_hz"] and row["strongest_peak_hz"] == o["peaks_hz"][0]
    assert row["power_at_texture_pa2"] == o["power_at_expected"]["texture"]
    assert row["power_at_ridges_pa2"] == o["power_at_expected"]["ridges"]
    assert row["normal_force_mean_n"] == o["normal_force_mean_n"]
    # the spike trains hold the counts and rates: spikes inside the analysis window
    classes = np.array(row["receptor_class"])
    trains = row["spike_times_s"]
    assert len(trains) == len(classes) == len(row["receptor_x_m"])
    window_s = row["duration_s"] + 0.15 - row["window_start_s"] + row["dt_s"]
    for c in ("SA1", "RA", "PC"):
        n = sum(
            sum(t >= row["window_start_s"] for t in trains[i]) for i in np.nonzero(classes == c)[0]
        )
        assert n == row[f"{c.lower()}_spike_count"], c
        assert n / (row[f"{c.lower()}_receptors"] * window_s) == pytest.approx(
            row[f"{c.lower()}_rate_hz"], rel=1e-9
        )
    assert row["sa1_spike_count"] + row["pc_spike_count"] > 0  # the check saw spikes


def test_resume_skips_finished_runs(tmp_path):
    first = run_sweep(tmp_path, "--period", "0.8e-3", "1.2e-3", *SMALL, "--serial")
    assert (first["ran"], first["skipped"]) == (2, 0)
    runs = sorted((tmp_path / "runs").glob("*.parquet"))
    stamps = [p.stat().st_mtime_ns for p in runs]
    # an interrupted sweep: one run's file lost; and the sweep grown by a period
    runs[0].unlink()
    again = run_sweep(tmp_path, "--period", "0.8e-3", "1.2e-3", "1e-3", *SMALL, "--serial")
    assert (again["ran"], again["skipped"]) == (2, 1)
    assert runs[1].stat().st_mtime_ns == stamps[1]  # the finished run was not redone
    t = read(again["table"])
    assert t.column("period_m").to_pylist() == [0.8e-3, 1.2e-3, 1e-3]
    done = run_sweep(tmp_path, "--period", "0.8e-3", "1.2e-3", "1e-3", *SMALL, "--serial")
    assert (done["ran"], done["skipped"]) == (0, 3)
    assert read(done["table"]).equals(t)


def test_failed_run_is_reported_and_the_rest_run(tmp_path):
    # plateau 0.9 mm fits the 1.2 mm period, not the 0.8 mm one
    r = mjtouch(
        "sweep",
        "--out",
        str(tmp_path),
        "--period",
        "0.8e-3",
        "1.2e-3",
        "--plateau",
        "0.9e-3",
        *SMALL,
        "--serial",
        "--json",
    )
    assert r.returncode == 1
    s = json.loads(r.stdout)
    assert s["ran"] == 1 and len(s["failed"]) == 1
    assert "plateau_m = 0.0009 is out of range" in s["failed"][0]["error"]
    assert s["failed"][0]["params"]["period_m"] == 0.8e-3
    assert "run failed: plateau_m = 0.0009" in r.stderr
    assert read(s["table"]).column("period_m").to_pylist() == [1.2e-3]


def test_bad_arguments_exit_2_before_running(tmp_path):
    r = mjtouch("sweep", "--out", str(tmp_path), "--nx", "2", "--serial")
    assert r.returncode == 2 and "--nx = 2 is out of range; valid range [4, 512]" in r.stderr
    r = mjtouch("sweep", "--out", str(tmp_path), "--num-cpus", "0")
    assert r.returncode == 2 and "--num-cpus 0 must be >= 1" in r.stderr
    require("ray")  # an address where no cluster answers (port 1): an error, not a hang
    r = mjtouch("sweep", "--out", str(tmp_path), "--address", "127.0.0.1:1", *SMALL)
    assert (
        r.returncode == 2
        and "could not join the Ray cluster at --address 127.0.0.1:1: nothing answers there"
        in r.stderr
    )
    r = mjtouch("sweep", "--out", str(tmp_path), "--serial", "--address", "auto")
    assert r.returncode == 2 and "--address joins a Ray cluster; not with --serial" in r.stderr
    assert not (tmp_path / "runs").exists() or not any((tmp_path / "runs").iterdir())


def test_bench_sweep_example(capsys):
    # examples/bench_sweep.py (the README's speed-up) on two tiny runs
    require("ray")
    main = runpy.run_path(str(EXAMPLES / "bench_sweep.py"), run_name="example")["main"]
    assert (
        main(
            [
                "--repeats",
                "1",
                "--num-cpus",
                "2",
                "--json",
                "--",
                "--period",
                "0.8e-3",
                "1.2e-3",
                *SMALL,
            ]
        )
        == 0
    )
    o = json.loads(capsys.readouterr().out)
    assert o["runs"] == 2 and o["tables_identical"] is True
    for key in ("speedup_min", "speedup_median", "speedup_runs_only_median"):
        assert math.isfinite(o[key]) and o[key] > 0, key
    assert o["ray_startup_median_s"] > 0


def test_example_sweep_file():
    v = sweep.read_config(EXAMPLES / "sweep.toml")
    assert v["period_m"] == [0.8e-3, 1.0e-3, 1.2e-3, 1.5e-3]
    assert v["speed_m_s"] == [0.02, 0.04, 0.06]
    assert v["ridges"] == [True, False] and v["duration_s"] == [0.5]
    assert len(sweep.expand(v)) == 48  # as the file says
