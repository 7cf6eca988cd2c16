"""SlideParams is the one description of a slide: the CLI's options, the
sweep's parameters and its Parquet columns are its fields, and nothing else."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import subprocess
import sys

import pytest

from mjtouch import cli
from mjtouch.cli import sweep as sweep_cli
from mjtouch.experiments import slide, sweep

FIELDS = [f.name for f in slide.fields()]
CLI_ONLY = {"help", "json", "plot", "progress"}  # output options, not parameters of a run
SWEEP_ONLY = {"help", "config", "out", "serial", "address", "num_cpus", "json", "progress"}
SMALL = dict(duration_s=0.2, nx=32, pitch_m=2e-4, dt_s=5e-4, speed_m_s=0.03)


def _subparser(name: str) -> argparse.ArgumentParser:
    parser = cli.parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


def test_every_slide_option_is_a_field():
    actions = [a for a in _subparser("slide")._actions if a.dest not in CLI_ONLY]
    assert [a.dest for a in actions] == FIELDS
    for a, f in zip(actions, slide.fields(), strict=True):
        assert a.option_strings[0] == slide.flag(f)
        assert a.default == f.default, f.name


def test_sweep_parameters_and_options_are_the_fields():
    assert list(sweep.parameters()) == FIELDS
    p = argparse.ArgumentParser()
    sweep_cli.add_arguments(p)
    assert [a.dest for a in p._actions if a.dest not in SWEEP_ONLY] == FIELDS
    runs = sweep.expand(sweep.parse_values({"period": [1e-3]}))
    assert list(runs[0]) == FIELDS
    assert runs[0] == dataclasses.asdict(slide.SlideParams(period_m=1e-3))


def test_sweep_accepts_every_spelling_of_a_field():
    # a valid value for the fields whose default is None (unset)
    example = {"period_m": 1e-3, "plateau_m": 4e-4, "texture_mesh": "plate.stl"}
    assert {f.name for f in slide.fields() if f.default is None} == set(example)
    for f in slide.fields():
        value = example.get(f.name, f.default)
        option = slide.flag(f)[2:]
        for name in {f.name, option, option.replace("-", "_")}:
            assert sweep.parse_values({name: value}) == {f.name: [value]}, name


def test_sweep_row_columns_are_the_fields():
    params = dict(dataclasses.asdict(slide.SlideParams(**SMALL)))
    row = sweep.run_one(params)
    keys = list(row)
    assert keys[0] == "run_id" and keys[1 : 1 + len(FIELDS)] == FIELDS
    assert slide.SlideParams(**{k: row[k] for k in FIELDS}) == slide.SlideParams(**SMALL)
    schema = sweep._schema(row)
    arrow = {"bool": "bool", "str": "string", "int": "int64", "float": "double"}
    for f in slide.fields():
        assert str(schema.field(f.name).type) == arrow[f.metadata["kind"]], f.name
    # the row's results are the library run's
    out = slide.run(slide.SlideParams(**SMALL)).summary
    assert row["sa1_rate_hz"] == out["rates_hz"]["SA1"]
    assert row["peaks_hz"] == list(out["peaks_hz"])


def test_cli_is_the_library():
    argv = [
        "--duration",
        "0.2",
        "--nx",
        "32",
        "--pitch",
        "2e-4",
        "--dt",
        "5e-4",
        "--speed",
        "0.03",
        "--json",
    ]
    r = subprocess.run(
        [sys.executable, "-m", "mjtouch", "slide", *argv],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    want = json.loads(json.dumps(slide.run(slide.SlideParams(**SMALL)).summary))
    got.pop("wall_s"), want.pop("wall_s")
    assert got == want


def _outside(f: dataclasses.Field) -> list:
    """Values just outside field f's valid range (from its metadata)."""
    m = f.metadata
    if m["kind"] == "bool":
        return ["yes", 1]
    if m["kind"] == "str":
        return ["not-a-choice"] if m["choices"] else [3.0]
    lo, hi = m["range"]
    bad = [float("nan"), "1"]
    if math.isfinite(lo):
        bad.append(lo if m["lo_open"] else lo - max(abs(lo), 1.0) * 1e-3)
    if math.isfinite(hi):
        bad.append(hi if m["hi_open"] else hi + max(abs(hi), 1.0) * 1e-3)
    if m["kind"] == "int":
        bad.append(float(f.default) + 0.5)
    return bad


@pytest.mark.parametrize("f", slide.fields(), ids=FIELDS)
def test_bad_values_name_the_field(f):
    for value in _outside(f):
        with pytest.raises(ValueError, match=f"^{f.name} = "):
            slide.SlideParams(**{f.name: value})


@pytest.mark.parametrize("f", slide.fields(), ids=FIELDS)
def test_metadata_is_complete(f):
    m = f.metadata
    assert m["kind"] in ("bool", "str", "int", "float") and m["help"]
    if m["kind"] in ("int", "float"):
        lo, hi = m["range"]
        assert lo < hi
        if f.default is not None:
            assert slide.check(f.name, f.default) == f.default


def test_grid_shift_needs_the_elastic_contact():
    with pytest.raises(ValueError, match="grid_shift .* needs pressure 'elastic'"):
        slide.SlideParams(grid_shift=True, pressure="winkler")
    assert slide.SlideParams(grid_shift=True).grid_shift
