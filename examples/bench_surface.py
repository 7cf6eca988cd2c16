"""Stages 1-2 (surface rendering; Winkler pressure and shear) of the shipped
scene, fast paths against the general (reference) code, interleaved in one
process (a benchmark, not a test).

    python examples/bench_surface.py [--scene models/slide_grating.xml] [--steps 200]
                                     [--repeats 15] [--yaw-deg 0]

The scene is simulated once with MuJoCo; its per-step inputs to the skin
(pad pose, contact force, counter-surfaces: the plate's top face and the
texture height field) are recorded after a lead-in and replayed through
mjtouch._core.traction_steps, which runs stages 1-2 as the plugin does, from
a fresh state, alternating the reference and the fast paths. Prints min and
median per-step CPU times (the thread's, not wall time: the development
machine is shared) over the repeats, their ratios, and the largest
pressure difference between the paths (0: bit-identical). --yaw-deg turns
the recorded pad about its z axis (the texture no longer aligned with the
taxel grid: the general rendering path).
"""

from __future__ import annotations

import argparse
import pathlib
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

import mjtouch  # noqa: F401  (loads the plugin)
from mjtouch import _core
from mjtouch.scene import scenes

ROOT = pathlib.Path(__file__).resolve().parents[1]
RECTANGLE, HEIGHT_FIELD = 1, 2  # CounterSurface::Type codes (render_gap)


def skin_config(xml_path: pathlib.Path) -> dict:
    plugin = ET.parse(xml_path).getroot().find("sensor/plugin")
    # Winkler: the fast paths under test (the elastic solve has its own
    # bench, bench_elastic.py); the scene's own attributes may say otherwise
    return {
        "pressure": "winkler",
        **{
            c.get("key"): c.get("value")
            for c in plugin.findall("config")
            if c.get("key") != "texture_group"
        },
    }


def record(xml_path: pathlib.Path, steps: int, lead_in_s: float = 0.1):
    """Per-step pad pose, force on the pad (pad frame: normal, x, y) and the
    counter-surfaces (plate top face, texture), as skin_plugin.cc gathers them."""
    spec = mujoco.MjSpec.from_file(str(xml_path))
    scenes.remove_skin(spec)  # the skin does not change the physics: simulate without it
    m = spec.compile()
    d = mujoco.MjData(m)
    pad = m.geom("pad").id
    plate, tex = m.geom("plate"), m.geom("texture")
    ctrl = scenes.controls(
        scenes.Protocol(timestep_s=m.opt.timestep), lead_in_s + steps * m.opt.timestep
    )
    pos, mat, forces = [], [], []
    f6 = np.zeros(6)
    for k, row in enumerate(ctrl):
        d.ctrl[:] = row
        mujoco.mj_step(m, d)
        if k < len(ctrl) - steps:
            continue
        total = np.zeros(3)
        for i in range(d.ncon):
            c = d.contact[i]
            if pad not in (c.geom[0], c.geom[1]) or c.efc_address < 0:
                continue
            mujoco.mj_contactForce(m, d, i, f6)
            sign = 1.0 if c.geom[1] == pad else -1.0
            total += sign * (c.frame.reshape(3, 3).T @ f6[:3])
        R = d.geom_xmat[pad].reshape(3, 3)
        fx, fy, fn = R.T @ total
        pos.append(d.geom_xpos[pad].copy())
        mat.append(d.geom_xmat[pad].copy())
        forces.append([fn, fx, fy])
    h = m.geom_dataid[tex.id]
    samples = m.hfield_data[m.hfield_adr[h] : m.hfield_adr[h] + m.hfield_nrow[h] * m.hfield_ncol[h]]
    samples = samples.reshape(m.hfield_nrow[h], m.hfield_ncol[h]).astype(np.float32)
    top = np.zeros(20)  # the plate box's +z face (the box is not rotated in the scene)
    top[0] = RECTANGLE
    top[1:4] = d.geom_xpos[plate.id] + d.geom_xmat[plate.id].reshape(3, 3) @ [
        0,
        0,
        m.geom_size[plate.id][2],
    ]
    top[4:13] = d.geom_xmat[plate.id]
    top[16:18] = m.geom_size[plate.id][:2]
    hf = np.zeros(20)
    hf[0] = HEIGHT_FIELD
    hf[1:4] = d.geom_xpos[tex.id]
    hf[4:13] = d.geom_xmat[tex.id]
    hf[16:19] = m.hfield_size[h][:3]
    hf[19] = m.hfield_size[h][2] * float(samples.max())
    return (
        np.array(pos),
        np.array(mat),
        np.array(forces),
        np.array([top, hf]),
        samples,
        m.geom_size[pad].copy(),
    )


def main(argv: list[str] | None = None) -> bool:
    """Runs the benchmark; returns whether the paths were bit-identical."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(ROOT / "models" / "slide_grating.xml"))
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--yaw-deg", type=float, default=0.0)
    ap.add_argument("--lead-in-s", type=float, default=0.1, help="sliding before the record")
    args = ap.parse_args(argv)
    path = pathlib.Path(args.scene)
    pos, mat, forces, surfaces, samples, semi_axes = record(path, args.steps, args.lead_in_s)
    if args.yaw_deg:
        a = np.radians(args.yaw_deg)
        yaw = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
        mat = np.ascontiguousarray([(m.reshape(3, 3) @ yaw).ravel() for m in mat])
        forces = np.ascontiguousarray(  # the same force, seen in the turned pad frame
            [[f[0], *(yaw[:2, :2].T @ f[1:])] for f in forces]
        )
    config = skin_config(path)
    times = {True: [], False: []}
    results = {}
    for _ in range(args.repeats):
        for reference in (True, False):  # interleaved: a load change hits both alike
            render_s, total_s, approach, pressure = _core.traction_steps(
                list(semi_axes), config, pos, mat, forces, surfaces, samples, reference=reference
            )
            times[reference].append((render_s.mean(), (total_s - render_s).mean(), total_s.mean()))
            results[reference] = (approach, pressure)
    diff = float(np.nanmax(np.abs(results[True][1] - results[False][1])))
    same = np.array_equal(results[True][1], results[False][1]) and np.array_equal(
        results[True][0], results[False][0], equal_nan=True
    )
    print(
        f"{path.name}, pad yaw {args.yaw_deg:g} deg: {args.steps} steps, "
        f"{args.repeats} interleaved repeats, "
        f"{np.mean(np.isfinite(results[False][0])):.0%} of steps in contact"
    )
    print(f"{'stage':<28}{'reference us':>16}{'fast us':>16}{'ratio (min, median)':>24}")
    for col, name in enumerate(
        ("1 render (RenderGap)", "2 pressure + shear", "1-2 (ComputeTraction)")
    ):
        ref = np.array([t[col] for t in times[True]]) * 1e6
        new = np.array([t[col] for t in times[False]]) * 1e6
        print(
            f"{name:<28}{np.min(ref):7.1f} / {np.median(ref):6.1f}"
            f"{np.min(new):7.1f} / {np.median(new):6.1f}"
            f"{np.min(ref) / np.min(new):11.2f}x {np.median(ref) / np.median(new):7.2f}x"
        )
    print(f"pressure and approach bit-identical: {same} (max |difference| {diff:.3g} Pa)")
    return same


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)
