"""TouchSim's fitted afferents (Saal et al. 2017, PNAS 114:E5693; hsaal/touchsim)
under a 1 mm flat pin, the reference tests/science/test_touchsim_reference.py
holds mjtouch's median units to.

    git --git-dir=<mirror of hsaal/touchsim> archive HEAD | tar -x -C touchsim
    python examples/touchsim_reference.py touchsim --out tests/data/touchsim_reference.json

TouchSim is not on the package index; it is imported from its source tree with
three shims applied here, none to its files: numba's ``guvectorize`` is
replaced by a pure-Python loop over the broadcast dimensions (numba is not
installed; same arithmetic in float64), ``skimage`` (used only to read the
hand outline) is stubbed, and the module-level ``hand_surface`` (built from
that outline) is skipped: every afferent here lies on the infinite sheet
(``null_surface``), TouchSim's default.

Stimuli (TouchSim's generators, 5 kHz, pin radius 0.5 mm at the origin):
- ramp-and-hold ``stim_ramp(amp, len=1, ramp_len=0.05)`` (linear 50 ms
  ramps inside the second), rate = spikes / 1 s;
- sines ``stim_sine(freq, amp, len=1, ramp_len=0.05, pre_indent=0.5)``:
  absolute threshold = the least amplitude with >= 1 spike/s more than the
  pre-indentation alone (a sine-free run of the same trace), entrainment =
  the least with >= 0.9 f spikes/s, each by bisection in log amplitude.
  TouchSim's mechanics are linear in the trace while the pin stays in contact
  (the 0.5 mm pre-indentation exceeds every amplitude searched), so the
  stress and its wave component are computed once for the pre-indentation
  and once per unit sine and combined per amplitude (checked against a full
  run at one amplitude per frequency).
Afferents on the pin's axis at TouchSim's class depths (SA1 0.3, RA 1.6,
PC 2.0 mm), noise off (``noisy=False``), no conduction delay. "Median": the
median over the class's fitted afferents (4 SA1, 9 RA, 4 PC) of each
quantity (rate per depth, threshold per frequency); with an even count the
mean of the middle two. Per-afferent values are stored too.

Stress: TouchSim's static input is the vertical stress s_z of Sneddon's
flat-punch solution (half-space, E 50 kPa, nu 0.4) at the receptor;
``stress_kpa`` stores it during the hold at the class depth and at
mjtouch's receptor depths (0.75 mm SA1/RA, 2 mm PC) for the comparison of
mechanics.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import subprocess
import sys
import types

import numpy as np

CLASSES = ("SA1", "RA", "PC")
DEPTHS_MM = (0.05, 0.1, 0.25, 0.5, 1.0, 1.5)
FREQS_HZ = (5.0, 10.0, 20.0, 40.0, 80.0, 150.0, 250.0, 400.0, 600.0)
PIN_RADIUS_MM = 0.5
PREINDENT_MM = 0.5
FS_HZ = 5000.0
RAMP_S = 0.05
DURATION_S = 1.0
MJTOUCH_DEPTH_MM = {"SA1": 0.75, "RA": 0.75, "PC": 2.0}
AMP_RANGE_MM = (1e-6, 0.45)  # below the pre-indentation: the pin stays in contact
BISECTION_STEPS = 16


def _guvectorize(_types, signature, **_kw):
    """numba.guvectorize as a Python loop over the loop (broadcast) dims."""
    ins, out = signature.replace(" ", "").split("->")
    in_dims = [tuple(d for d in s.strip("()").split(",") if d) for s in ins.split("),(")]
    out_dims = tuple(d for d in out.strip("()").split(",") if d)

    def deco(fn):
        def wrapper(*args):
            arrs = [
                np.asarray(a, dtype=float if np.asarray(a).dtype != bool else bool) for a in args
            ]
            sizes, loops = {}, []
            for a, dims in zip(arrs, in_dims):
                core = a.ndim - len(dims)
                loops.append(a.shape[:core])
                for name, n in zip(dims, a.shape[core:]):
                    sizes[name] = n
            loop = np.broadcast_shapes(*loops)
            res = np.zeros(loop + tuple(sizes[d] for d in out_dims))
            for idx in np.ndindex(*loop):
                parts = []
                for a, dims in zip(arrs, in_dims):
                    core = a.ndim - len(dims)
                    sub = (
                        a[
                            tuple(
                                i if s > 1 else 0
                                for i, s in zip(idx[len(idx) - core :], a.shape[:core])
                            )
                        ]
                        if core
                        else a
                    )
                    sub = np.array(sub, copy=True)
                    parts.append(sub.reshape(1) if not dims else sub)
                o = np.zeros(tuple(sizes[d] for d in out_dims) or (1,))
                fn(*parts, o)
                res[idx] = o if out_dims else o[0]
            return res

        return wrapper

    return deco


def load_touchsim(src: str) -> types.SimpleNamespace:
    """Import TouchSim's modules from its source tree with the shims above."""
    numba = types.ModuleType("numba")
    numba.guvectorize = _guvectorize

    class _Type:  # float64[:], boolean[:, :]: only read by numba
        def __getitem__(self, _):
            return self

    numba.float64 = numba.boolean = _Type()
    sys.modules.setdefault("numba", numba)
    for name in ("skimage", "skimage.measure", "skimage.morphology"):
        m = types.ModuleType(name)
        m.label = m.find_contours = m.regionprops = m.thin = None
        sys.modules.setdefault(name, m)
    pkg = types.ModuleType("touchsim")
    pkg.__path__ = [os.path.join(src, "touchsim")]
    sys.modules["touchsim"] = pkg
    mods = {}
    for name in ("constants", "surface", "transduction", "classes", "generators"):
        path = os.path.join(src, "touchsim", name + ".py")
        spec = importlib.util.spec_from_file_location("touchsim." + name, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules["touchsim." + name] = mod
        code = open(path).read()
        if name == "surface":  # the hand outline needs skimage; unused on the sheet
            code = code[: code.index("hand_surface = Surface(")] + "hand_surface = None\n"
        exec(compile(code, path, "exec"), mod.__dict__)
        mods[name] = mod
    return types.SimpleNamespace(**mods)


def _population(ts, cls: str, depth_mm: float | None = None):
    n = ts.classes.Afferent.affparams[cls].shape[0]
    kw = {} if depth_mm is None else {"depth": depth_mm}
    return ts.classes.AfferentPopulation(
        *[
            ts.classes.Afferent(cls, idx=i, location=np.array([[0.0, 0.0]]), noisy=False, **kw)
            for i in range(n)
        ]
    )


def _median(v):
    return float(np.median(np.asarray(v, dtype=float)))


def ramp_table(ts) -> dict:
    out = {c: {"rates_hz": [], "stress_kpa": [], "stress_kpa_mjtouch_depth": []} for c in CLASSES}
    for depth in DEPTHS_MM:
        s = ts.generators.stim_ramp(
            amp=depth, len=DURATION_S, ramp_len=RAMP_S, fs=FS_HZ, pin_radius=PIN_RADIUS_MM
        )
        hold = int(round(DURATION_S / 2 * FS_HZ))  # mid-hold sample
        for c in CLASSES:
            pop = _population(ts, c)
            r = pop.response(s).rate()[:, 0]
            out[c]["rates_hz"].append([float(x) for x in r])
            stat, _, _ = s.propagate(pop)
            out[c]["stress_kpa"].append(float(stat[hold, 0]) * 1e3)  # MPa -> kPa
            stat2, _, _ = s.propagate(_population(ts, c, MJTOUCH_DEPTH_MM[c]))
            out[c]["stress_kpa_mjtouch_depth"].append(float(stat2[hold, 0]) * 1e3)
    for c in CLASSES:
        out[c]["median_hz"] = [_median(r) for r in out[c]["rates_hz"]]
    return out


def _spike_counts(ts, pop, stat, dyn):
    """Spike counts of each afferent of pop, row i driven by stat[:, i], dyn[:, i]."""
    spikes = ts.transduction.lif_neuron(pop, stat.copy(), dyn.copy())
    return np.array([len(x) for x in spikes])


def sine_thresholds(ts) -> dict:
    out = {c: {"absolute_um": [], "entrainment_um": []} for c in CLASSES}
    base = ts.generators.stim_sine(
        freq=10.0,
        amp=0.0,
        len=DURATION_S,
        ramp_len=RAMP_S,
        fs=FS_HZ,
        pin_radius=PIN_RADIUS_MM,
        pre_indent=PREINDENT_MM,
    )
    for c in CLASSES:
        pop = _population(ts, c)
        n = len(pop)
        st0, dy0, _ = base.propagate(pop)
        rest = _spike_counts(ts, pop, st0, dy0)
        for f in FREQS_HZ:
            unit = ts.generators.stim_sine(
                freq=f,
                amp=1.0,
                len=DURATION_S,
                ramp_len=RAMP_S,
                fs=FS_HZ,
                pin_radius=PIN_RADIUS_MM,
                pre_indent=PREINDENT_MM,
            )
            st1, dy1, _ = unit.propagate(pop)
            dst, ddy = st1 - st0, dy1 - dy0  # per mm of sine amplitude

            def counts(amps, pop=pop, st0=st0, dst=dst, dy0=dy0, ddy=ddy):
                return _spike_counts(ts, pop, st0 + dst * amps, dy0 + ddy * amps)

            # linearity check against a full run at one amplitude
            a_chk = 0.01
            full = ts.generators.stim_sine(
                freq=f,
                amp=a_chk,
                len=DURATION_S,
                ramp_len=RAMP_S,
                fs=FS_HZ,
                pin_radius=PIN_RADIUS_MM,
                pre_indent=PREINDENT_MM,
            )
            stf, dyf, _ = full.propagate(pop)
            assert np.allclose(stf, st0 + dst * a_chk, rtol=1e-9, atol=1e-12)
            assert np.allclose(dyf, dy0 + ddy * a_chk, rtol=1e-9, atol=1e-9)
            for crit, need in (
                ("absolute", rest + 1),
                ("entrainment", np.full(n, 0.9 * f * DURATION_S)),
            ):
                lo = np.full(n, AMP_RANGE_MM[0])
                hi = np.full(n, AMP_RANGE_MM[1])
                ok_hi = counts(hi) >= need
                for _ in range(BISECTION_STEPS):
                    mid = np.sqrt(lo * hi)
                    ok = counts(mid) >= need
                    hi = np.where(ok, mid, hi)
                    lo = np.where(ok, lo, mid)
                thr = np.where(ok_hi, hi * 1e3, np.inf)  # um; inf: not reached
                out[c][f"{crit}_um"].append([float(x) for x in thr])
            print(
                c,
                f,
                "abs",
                np.round(out[c]["absolute_um"][-1], 4),
                "ent",
                np.round(out[c]["entrainment_um"][-1], 3),
                flush=True,
            )
        for crit in ("absolute", "entrainment"):
            out[c][f"{crit}_median_um"] = [_median(t) for t in out[c][f"{crit}_um"]]
        out[c]["rest_spikes"] = [int(x) for x in rest]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("touchsim", help="hsaal/touchsim source tree (git archive of a commit)")
    ap.add_argument(
        "--commit",
        help="the commit the tree was archived from "
        "(default: git rev-parse HEAD in the tree, if it is a work tree)",
    )
    ap.add_argument("--out", default="tests/data/touchsim_reference.json")
    ap.add_argument("--skip-sines", action="store_true")
    a = ap.parse_args()
    commit = a.commit
    if commit is None:
        commit = (
            subprocess.run(
                ["git", "-C", a.touchsim, "rev-parse", "HEAD"], capture_output=True, text=True
            ).stdout.strip()
            or "unknown"
        )
    ts = load_touchsim(a.touchsim)
    ramp = ramp_table(ts)
    for c in CLASSES:
        print(
            c,
            "median",
            ramp[c]["median_hz"],
            "stress kPa",
            np.round(ramp[c]["stress_kpa"], 2),
            flush=True,
        )
    res = dict(
        source="hsaal/touchsim",
        commit=commit,
        command="python examples/touchsim_reference.py " + " ".join(sys.argv[1:]),
        shims="numba.guvectorize as a Python loop; skimage stubbed; hand_surface skipped",
        pin_radius_mm=PIN_RADIUS_MM,
        fs_hz=FS_HZ,
        ramp_s=RAMP_S,
        duration_s=DURATION_S,
        afferent_depth_mm=dict(ts.constants.affdepths),
        noisy=False,
        median="median over the class's fitted afferents (4 SA1, 9 RA, 4 PC) of each value",
        ramp_and_hold=dict(depths_mm=list(DEPTHS_MM), **ramp),
        stress_note="static vertical stress s_z (Sneddon flat punch, E 50 kPa, nu 0.4) "
        "mid-hold, kPa; at TouchSim's class depth and at mjtouch's",
        mjtouch_depth_mm=MJTOUCH_DEPTH_MM,
    )
    if not a.skip_sines:
        res["sines"] = dict(
            freqs_hz=list(FREQS_HZ),
            preindent_mm=PREINDENT_MM,
            absolute="spikes in 1 s >= the pre-indentation's + 1",
            entrainment="spikes in 1 s >= 0.9 f",
            amplitude_range_mm=list(AMP_RANGE_MM),
            bisection_steps=BISECTION_STEPS,
            **sine_thresholds(ts),
        )
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "w") as fh:
        json.dump(res, fh, indent=1)
        fh.write("\n")
    print("wrote", a.out)


if __name__ == "__main__":
    main()
