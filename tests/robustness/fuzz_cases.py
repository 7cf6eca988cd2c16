"""Bad-input cases on models/slide_grating.xml, each compiled and stepped in a
worker process with a time limit (a hang is a result, not a stalled run),
and the outcome classified:

  error  a clear error: the plugin's one message line, once, naming (in
         backticks or quotes) what is wrong; or MuJoCo's own XML error
  ran    compiled and stepped with finite output, and no requested block
         silently empty
  hang   the case did not finish within the time limit
  crash  the worker died (signal or sanitizer abort)
  silent anything else: a vague error, a message twice, a NaN, an empty
         receptor block

tests/robustness/test_fuzz_composite.py draws the cases (hypothesis);
`python tests/robustness/fuzz_cases.py` runs a fixed sweep of every
attribute and the structural cases and prints the counts.
"""

from __future__ import annotations

import json
import os
import pathlib
import re
import selectors
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "models" / "slide_grating.xml"
ANCHOR = '<config key="texture_group" value="3"/>'
# Values the scene itself sets (replaced, not added: MuJoCo refuses a
# duplicate config key).
SCENE_KEYS = {
    "texture_group",
    "nx",
    "pitch",
    "ridges",
    "ridge_pitch",
    "ridge_height",
    "ridge_angle",
}
OUTCOMES = ("error", "ran", "hang", "crash", "silent")


def scene_xml(attrs: dict[str, str] | None = None, edit=None) -> str:
    """slide_grating with skin attributes set (replacing the scene's own) and
    an optional text edit of the rest."""
    xml = SCENE.read_text()
    for key, value in (attrs or {}).items():
        value = (
            value.replace("&", "&amp;")
            .replace('"', "&quot;")
            .replace("<", "&lt;")
            .replace("\t", "&#9;")
            .replace("\n", "&#10;")
        )
        own = re.search(rf'<config key="{re.escape(key)}" value="[^"]*"/>', xml)
        if own:
            xml = xml.replace(own.group(0), f'<config key="{key}" value="{value}"/>')
        else:
            xml = xml.replace(ANCHOR, ANCHOR + f'<config key="{key}" value="{value}"/>')
    return edit(xml) if edit else xml


# -- the worker (a separate process) ------------------------------------------


def _evaluate(xml: str, steps: int) -> dict:
    import mujoco
    import numpy as np

    from mjtouch.sensor import SkinLayout

    t0 = time.perf_counter()
    try:
        m = mujoco.MjModel.from_xml_string(xml)
    except ValueError as e:
        return {"kind": "error", "message": str(e), "seconds": time.perf_counter() - t0}
    try:
        d = mujoco.MjData(m)
    except Exception as e:  # noqa: BLE001 - init failing after compile is reported as is
        return {"kind": "error", "message": str(e), "seconds": time.perf_counter() - t0}
    skins = []
    for i in range(m.nplugin):
        try:
            skins.append(SkinLayout.from_model(m, instance=i))
        except Exception:  # noqa: BLE001 - another plugin
            pass
    press = m.actuator("press").id if "press" in [m.actuator(i).name for i in range(m.nu)] else None
    for _ in range(steps):
        if press is not None:
            d.ctrl[press] = -0.5
        mujoco.mj_step(m, d)
    finite = bool(np.all(np.isfinite(d.sensordata)) and np.all(np.isfinite(d.plugin_state)))
    blocks = [{name: s.stop - s.start for name, s in lay.blocks.items()} for lay in skins]
    classes = [sorted(set(lay.classes)) for lay in skins]
    return {
        "kind": "ran",
        "finite": finite,
        "blocks": blocks,
        "classes": classes,
        "seconds": time.perf_counter() - t0,
    }


def _serve() -> None:
    import mjtouch  # noqa: F401 - registers the plugin before the first case

    for line in sys.stdin:
        case = json.loads(line)
        out = _evaluate(case["xml"], case["steps"])
        sys.stdout.write(json.dumps(out) + "\n")
        sys.stdout.flush()


class Runner:
    """A worker process that evaluates cases one at a time; a case that
    exceeds `timeout_s` kills it (the next case starts a new one)."""

    def __init__(self, timeout_s: float = 30.0):
        self.timeout_s = timeout_s
        self.proc = None

    def _start(self):
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            env=os.environ.copy(),
        )

    def close(self):
        if self.proc:
            self.proc.kill()
            self.proc.wait()
            self.proc.stdin.close()
            self.proc.stdout.close()
            self.proc = None

    def run(self, xml: str, steps: int = 300) -> dict:
        if self.proc is None or self.proc.poll() is not None:
            self._start()
        self.proc.stdin.write(json.dumps({"xml": xml, "steps": steps}) + "\n")
        self.proc.stdin.flush()
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        ready = sel.select(self.timeout_s)
        sel.close()
        if not ready:
            self.close()
            return {"kind": "hang"}
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            self.close()
            return {"kind": "crash", "returncode": code}
        return json.loads(line)


def classify(result: dict, attrs: dict[str, str] | None = None) -> tuple[str, str]:
    """(outcome, why) of one result; attrs: the skin attributes set."""
    kind = result["kind"]
    if kind in ("hang", "crash"):
        return kind, json.dumps(result)
    if kind == "error":
        msg = result["message"]
        ours = [line for line in msg.splitlines() if line.startswith("mjtouch.skin: ")]
        if not ours:
            if msg.startswith("XML Error") or "Error: " in msg and "plugin->init" not in msg:
                return "error", msg  # MuJoCo's own message (a structural case)
            return "silent", "no plugin message: " + msg
        if len(ours) != 1 or msg.count(ours[0]) != 1:
            return "silent", "message repeated: " + msg
        if "plugin->init failed" in msg:
            return "silent", "behind MuJoCo's init failure: " + msg
        if not re.search(r"`[a-z0-9_]+`|'[^']+'|\"[^\"]+\"", ours[0]):
            return "silent", "names nothing: " + ours[0]
        return "error", ours[0]
    if not result["finite"]:
        return "silent", "non-finite output"
    for blocks, classes in zip(result["blocks"], result["classes"]):
        empty = [b for b in ("spikes", "stress", "voltage", "rate") if blocks.get(b) == 0]
        if empty:
            return "silent", f"empty blocks {empty}"
        wanted = (attrs or {}).get("classes")
        if wanted and not (attrs or {}).get("sites"):
            missing = set(wanted.split()) - set(classes)
            if missing and any(blocks.get(b) for b in ("spikes", "stress", "voltage", "rate")):
                return "silent", f"no receptor of {sorted(missing)}"
    return "ran", ""


# -- the fixed sweep (counts for the docs) -------------------------------------

NUMBER_PROBES = [
    "",
    " ",
    "nan",
    "inf",
    "-inf",
    "0",
    "-1",
    "1e-30",
    "1e30",
    "1e-300",
    "abc",
    "1 2",
    "99999999999999999999999",
]
COMPOSITE_PROBES = {
    "layers": [
        "1e-30 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4",
        "1e-300 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4",
        "1e-6 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4",
        "7e-4 1e12 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4",
        "7e-4 8e4 0.48, 8e-4 5e4 0.48",
        ";",
        "7e-4 8e4 0.48;;",
        "7e-4 8e4",
        "7e-4 8e4 0.6",
        "7e-4 8e4 nan",
        "1 8e4 0.48",
        "; ".join(["1e-4 8e4 0.48"] * 65),
    ],
    "sites": [
        ";",
        "SA1,0,0,1e-3",
        "SA1 0 0 1e-3",
        "SA1 0 0 1e-3; RA 1e-3 0 7.5e-4",
        "SA1 0 0",
        "XX 0 0 1e-3",
        "SA1 0 0 0",
        "SA1 1 0 1e-3",
        "SA1 nan 0 1e-3",
    ],
    "density": ["0 0 0", "70 140", "70,140,21", "1e30 1 1", "70 140 0"],
    "depth": ["0 0 0", "7.5e-4 7.5e-4 5e-3", "1e-30 1e-3 2e-3", "a b c"],
    "noise": ["0.3; 0.3; 0.1", "-1 0 0", "inf 0 0", "0 0 0"],
    "outputs": ["spikes;force", "bogus", "force", "pressure rate", "spikes,stress"],
    "classes": ["SA1,RA", "XX", "PC", "SA1 SA1"],
    "quantity": ["szz szz", "sed sed sed", "bogus szz szz"],
    "sa1_merkel": ["1 2 3 4 5", "-1", "1,2"],
    "base": ["rigid", "5e4 0.45", "5e4", "1e12 0.3", "5e4,0.45"],
    "seed": ["-1", "18446744073709551616", "1.5"],
    "oversample": ["auto", "0", "65", "2.5"],
    "radius": ["0", "1e-30"],
    "pc_lowpass": ["1e5"],
}
GRID_PROBES = [
    {"nx": "4", "pitch": "1e-6"},
    {"nx": "512", "pitch": "1e-6"},
    {"nx": "4", "pitch": "1e-2", "ridges": "false"},
]


def _replace_geom_attr(xml, name, attr, value):
    def sub(mt):
        tag = mt.group(0)
        if re.search(rf'\b{attr}="', tag):
            return re.sub(rf'\b{attr}="[^"]*"', f'{attr}="{value}"', tag)
        return tag.replace("<geom ", f'<geom {attr}="{value}" ', 1)

    return re.sub(rf'<geom name="{name}"[^>]*/>', sub, xml)


STRUCTURAL = {
    "pad cylinder": lambda x: _replace_geom_attr(x, "pad", "type", "cylinder"),
    "pad sphere": lambda x: _replace_geom_attr(
        _replace_geom_attr(x, "pad", "type", "sphere"), "pad", "size", "0.008"
    ),
    "pad box": lambda x: _replace_geom_attr(x, "pad", "type", "box"),
    "pad capsule": lambda x: _replace_geom_attr(
        _replace_geom_attr(x, "pad", "type", "capsule"), "pad", "size", "0.007 0.003"
    ),
    "pad tiny": lambda x: _replace_geom_attr(x, "pad", "size", "1e-5 1e-5 1e-5"),
    "sensor on a body": lambda x: x.replace(
        'objtype="geom" objname="pad"', 'objtype="body" objname="finger"'
    ),
    "two sensors, one instance": lambda x: x.replace(
        "</sensor>",
        '<plugin objtype="geom" objname="pad" plugin="mjtouch.skin" name="skin2"/></sensor>',
    ),
    "texture names a missing geom": lambda x: x.replace(
        ANCHOR, ANCHOR + '<config key="texture" value="nothere"/>'
    ),
    "texture names the pad": lambda x: x.replace(
        ANCHOR, ANCHOR + '<config key="texture" value="pad"/>'
    ),
    "timestep 1e-6": lambda x: x.replace('timestep="0.0001"', 'timestep="1e-6"'),
    "timestep 1e-2": lambda x: x.replace('timestep="0.0001"', 'timestep="1e-2"'),
    "hfield z-size 1e30": lambda x: x.replace(
        'size="0.04 0.015 0.0001 0.001"', 'size="0.04 0.015 1e30 0.001"'
    ),
    "hfield z-size 0": lambda x: x.replace(
        'size="0.04 0.015 0.0001 0.001"', 'size="0.04 0.015 0 0.001"'
    ),
    "no contact pair": lambda x: re.sub(r"<contact>.*?</contact>", "", x, flags=re.S),
    "friction 0": lambda x: x.replace('friction="0.5 0.5"', 'friction="0 0"'),
    "integrator RK4": lambda x: x.replace('integrator="implicitfast"', 'integrator="RK4"'),
    "integrator Euler": lambda x: x.replace('integrator="implicitfast"', 'integrator="Euler"'),
    "gravity 1e4": lambda x: x.replace("<option ", '<option gravity="0 0 -1e4" '),
    "pad mass 1e-9": lambda x: x.replace('mass="0.02"', 'mass="1e-9"'),
    "finger starts 5 mm inside the plate": lambda x: x.replace(
        'pos="-0.02 0 0.0073"', 'pos="-0.02 0 0.0023"'
    ),
}


def sweep_cases():
    """(label, attrs, edit) of the fixed sweep: every attribute of the table
    with the number probes, the composite probes, the grid probes and the
    structural cases."""
    sys.path.insert(0, str(ROOT / "tests"))
    from conftest import registered_attributes

    cases = []
    for key in registered_attributes():
        for v in NUMBER_PROBES:
            cases.append((f"{key}={v!r}", {key: v}, None))
    for key, values in COMPOSITE_PROBES.items():
        for v in values:
            cases.append((f"{key}={v!r}", {key: v}, None))
    for attrs in GRID_PROBES:
        cases.append((repr(attrs), attrs, None))
    for label, edit in STRUCTURAL.items():
        cases.append((label, {}, edit))
    return cases


def main() -> None:
    runner = Runner(timeout_s=float(os.environ.get("FUZZ_TIMEOUT_S", "60")))
    counts = dict.fromkeys(OUTCOMES, 0)
    worst = []
    try:
        for label, attrs, edit in sweep_cases():
            result = runner.run(scene_xml(attrs, edit), steps=300)
            outcome, why = classify(result, attrs)
            counts[outcome] += 1
            worst.append((result.get("seconds", float("inf")), label))
            if outcome not in ("error", "ran"):
                print(f"{outcome}: {label}: {why[:300]}", flush=True)
    finally:
        runner.close()
    total = sum(counts.values())
    print(f"cases {total}: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
    worst.sort(reverse=True)
    print(
        "slowest (compile + 300 steps, s):", ", ".join(f"{label} {s:.1f}" for s, label in worst[:5])
    )


if __name__ == "__main__":
    if sys.argv[1:] == ["--serve"]:
        _serve()
    else:
        main()
