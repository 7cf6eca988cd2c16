"""The example C host (examples/c_host), compiled against the installed
header and library, reads the same layout and spikes as the Python package."""

from __future__ import annotations

import os
import pathlib
import re
import shutil
import subprocess
import sys

import mujoco
import numpy as np
import pytest

import mjtouch
from mjtouch import sensor

ROOT = pathlib.Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
STEPS = 1000
PRESS_N, SPEED_M_S = 0.5, 0.025
LINE = re.compile(r"^  class (\w+) count (\d+) start (\d+) spikes (\d+)$", re.M)
BLOCK = re.compile(r"^  block (\w+) adr (\d+) size (\d+)$", re.M)


def shipped_scenes() -> list[pathlib.Path]:
    """The shipped models that have a skin (the parts have none)."""
    out = []
    for path in sorted(MODELS.glob("*.xml")):
        try:
            model = mujoco.MjModel.from_xml_path(str(path))
        except ValueError:
            continue  # a part, e.g. a fingertip without a world to press on
        if mjtouch.layouts(model):
            out.append(path)
    return out


@pytest.fixture(scope="module")
def c_host(tmp_path_factory) -> pathlib.Path:
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc, "a C compiler (gcc or cc) is needed to build examples/c_host"
    mujoco_dir = pathlib.Path(mujoco.__file__).parent
    libmujoco = sorted(mujoco_dir.glob("libmujoco.so.*"))
    assert libmujoco, f"no libmujoco.so.* in {mujoco_dir}"
    include = subprocess.run(
        [sys.executable, "-m", "mjtouch", "--include"], check=True, capture_output=True, text=True
    ).stdout.strip()
    assert (pathlib.Path(include) / "mjtouch.h").is_file(), include
    lib = pathlib.Path(mjtouch.library_path())
    exe = tmp_path_factory.mktemp("c_host") / "c_host"
    subprocess.run(
        [
            cc,
            "-std=c11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-O2",
            "-o",
            str(exe),
            str(ROOT / "examples" / "c_host" / "main.c"),
            f"-I{mujoco_dir / 'include'}",
            f"-I{include}",
            str(lib),
            str(libmujoco[-1]),
            f"-Wl,-rpath,{lib.parent}",
            f"-Wl,-rpath,{mujoco_dir}",
        ],
        check=True,
    )
    return exe


def python_spikes(model: mujoco.MjModel, layout: sensor.SkinLayout) -> dict[str, float]:
    """Spikes per class over the same run as the C host's, stepped in Python."""
    data = mujoco.MjData(model)
    for name, value in (("press", -PRESS_N), ("slide", SPEED_M_S)):
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
        if i >= 0:
            data.ctrl[i] = value
    total = np.zeros(len(layout.classes))
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
        total += layout.block(data.sensordata, "spikes")
    return {c: float(total[layout.mask(c)].sum()) for c in sensor.CLASSES}


def test_shipped_scenes_found():
    names = {p.name for p in shipped_scenes()}
    assert {"slide_grating.xml", "slide_flat.xml"} <= names, names


@pytest.mark.parametrize("scene", shipped_scenes(), ids=lambda p: p.stem)
def test_c_host_layout_and_spikes_match_python(c_host, scene):
    out = subprocess.run(
        [str(c_host), str(scene), str(STEPS), str(PRESS_N), str(SPEED_M_S)],
        check=True,
        capture_output=True,
        text=True,
        env={**os.environ, "MUJOCO_GL": "disable"},
    ).stdout
    model = mujoco.MjModel.from_xml_path(str(scene))
    ((name, layout),) = mjtouch.layouts(model).items()
    assert f"skin {name}: {len(layout.classes)} receptors" in out, out

    rows = {m[0]: tuple(int(x) for x in m[1:]) for m in LINE.findall(out)}
    assert list(rows) == list(sensor.CLASSES), out
    start = 0
    for cls in sensor.CLASSES:
        count = int(layout.mask(cls).sum())
        assert rows[cls][:2] == (count, start), (cls, rows[cls], out)
        assert layout.mask(cls)[start : start + count].all(), cls  # one run per class
        start += count

    blocks = {m[0]: (int(m[1]), int(m[2])) for m in BLOCK.findall(out)}
    assert blocks == {
        b: (layout.sensor_adr + s.start, s.stop - s.start) for b, s in layout.blocks.items()
    }, out

    spikes = python_spikes(model, layout)
    if scene.stem.startswith("slide_"):
        # pressed on a plate and slid: every class fires, so the comparison
        # sees each class's run (the fingertip parts touch nothing)
        assert all(v > 0 for v in spikes.values()), spikes
    assert {c: float(rows[c][2]) for c in sensor.CLASSES} == spikes, out
