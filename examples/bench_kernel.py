"""Per-step cost of the stress stage: layered vs homogeneous kernel, direct
summation vs FFT convolution (a benchmark, not a test).

    python examples/bench_kernel.py            # default: n = 128, 0.5 N, 250 receptors
    python examples/bench_kernel.py --repeats 400 --receptors 250
    python examples/bench_kernel.py --stage-only --threads 2   # reference/folded/threads
    python examples/bench_kernel.py --scene slide_grating      # a shipped scene's own stage
    python examples/bench_kernel.py --scene slide_grating --baseline-core OTHER/_core*.so

It presses the default fingertip (scenes.Fingertip(): 128 x 128 taxels at
0.1 mm, ridged skin) onto the default grating with 0.5 N, slides it for
50 ms (so there is friction shear), and takes the plugin's pressure field and
tangential force of the last step. Shear as in the plugin (full slip,
q = p F_t / F_n). 250 receptors on a sunflower spiral within the default
5 mm radius, split SA1 : RA : PC as the default densities (70 : 140 : 21 per
cm^2) at the default depths (0.75, 0.75, 2 mm) and quantities (SA1 maxcomp:
all six components; RA and PC s_zz). The stress stage alone is timed
(mjtouch.core.StressEngine, one core, the active cells found once as the
pressure stage hands them over), for the layered Shao skin and for the
homogeneous half-space (nu = 0.48), by both paths; and the cost model's
estimates, whose constants (plugin/core/stress/stress_field.cc) are fitted here.
First a table of the stress stage by path, interleaved: the reference direct
sum, the folded direct path (one effective table per step; what the plugin's
winkler and elastic models take) and folded on --threads threads, with ratios.
--scene NAME (models/NAME.xml) times that table on the scene's own stage
instead: its receptor sites, classes' components and depths, and the pressure
and slip ratio of its winkler contact after LEAD_IN_S of sliding (the
default scene's contact is about twice the cells of the 0.5 N press above).
--baseline-core PATH (with --scene) also times the folded path of another
build of mjtouch._core (e.g. main's installed one) in the same process,
interleaved with this build's, on the same engine inputs, and prints the
ratio and whether the two builds give the same bits. The harness itself is
not neutral: a copy of this build as the baseline reads 1.03-1.05 (the
baseline is built and run second) on the 2-core development machine; compare
against that control (or swap the builds).
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import importlib.machinery
import importlib.util
import math
import pathlib
import time

import mujoco
import numpy as np

from mjtouch import core
from mjtouch.bench.configs import LEAD_IN_S
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

ALL = range(6)
SZZ = (2,)


def default_contact(force_n: float):
    tip = scenes.Fingertip(skin={"outputs": "force pressure"})
    proto = scenes.Protocol(force_n=force_n)
    model = scenes.build_model(tip, scenes.Texture(), proto)
    data = mujoco.MjData(model)
    layout = SkinLayout.from_model(model)
    ctrl = scenes.controls(proto, 0.05)
    for row in ctrl:
        data.ctrl[:] = row
        mujoco.mj_step(model, data)
    n = layout.nx
    p = layout.block(data.sensordata, "pressure").reshape(n, n).astype(np.float32)
    f = layout.block(data.sensordata, "force")
    ratio = (f[1] / f[0], f[2] / f[0]) if f[0] > 0 else (0.0, 0.0)
    return tip, p, ratio, f


def load_baseline_core(path):
    """Another build of mjtouch._core (e.g. main's) as a module of this
    process, for interleaved A/B timing. nanobind registers each bound C++
    type once per process and domain, and both builds bind the same types: so
    the shared nanobind state of this build is hidden while the baseline
    initialises (it then makes and keeps its own) and put back after."""
    api = ctypes.pythonapi
    api.PyInterpreterState_Get.restype = ctypes.c_void_p
    api.PyInterpreterState_GetDict.restype = ctypes.py_object
    api.PyInterpreterState_GetDict.argtypes = [ctypes.c_void_p]
    state = api.PyInterpreterState_GetDict(api.PyInterpreterState_Get())
    ours = {k: v for k, v in state.items() if isinstance(k, str) and k.startswith("__nb_internals")}
    if not ours:
        raise RuntimeError(
            "nanobind's state not found where expected (nanobind >= 2 keeps it "
            "in the interpreter's dict): cannot load a baseline build"
        )
    for k in ours:
        del state[k]
    try:
        loader = importlib.machinery.ExtensionFileLoader("mjtouch_baseline._core", str(path))
        module = importlib.util.module_from_spec(
            importlib.util.spec_from_loader("mjtouch_baseline._core", loader)
        )
        loader.exec_module(module)
    finally:
        for k in [k for k in state if isinstance(k, str) and k.startswith("__nb_internals")]:
            del state[k]
        state.update(ours)
    return module


@contextlib.contextmanager
def using_core(module):
    """mjtouch.core's wrappers built on `module` (a baseline _core) inside."""
    ours = core._core
    core._core = module
    try:
        yield
    finally:
        core._core = ours


def scene_stage(name: str, baseline=None):
    """(engine, pressure, slip ratio, description, the plugin's `stress`
    block, which sites' quantity is szz) of models/<name>.xml's stress
    stage: its sites (cells as the plugin's Grid::Nearest), depths and
    components, and the winkler contact after LEAD_IN_S of sliding."""
    path = pathlib.Path(__file__).resolve().parents[1] / "models" / f"{name}.xml"
    spec = mujoco.MjSpec.from_file(str(path))
    for s in spec.sensors:  # the shipped models embed the config in <sensor><plugin>
        if s.type == mujoco.mjtSensor.mjSENS_PLUGIN:
            s.plugin.config = {
                **dict(s.plugin.config),
                "pressure": "winkler",
                "outputs": "force pressure stress",
            }
    model = spec.compile()
    data = mujoco.MjData(model)
    for row in scenes.controls(scenes.Protocol(), LEAD_IN_S):
        data.ctrl[:] = row
        mujoco.mj_step(model, data)
    lay = SkinLayout.from_model(model)
    n, pitch = lay.nx, lay.pitch_m
    p = lay.block(data.sensordata, "pressure").reshape(n, n).astype(np.float32)
    f = lay.block(data.sensordata, "force")
    ratio = (f[1] / f[0], f[2] / f[0])
    pos = lay.positions_m
    ij = np.clip(np.floor(pos[:, :2] / pitch + 0.5 * (n - 1) + 0.5).astype(int), 0, n - 1)
    depths = sorted(set(pos[:, 2]))
    depth_index = np.array([depths.index(z) for z in pos[:, 2]])
    comps = [SZZ if lay.quantity[str(c)] == "szz" else ALL for c in lay.classes]
    e = core.StressEngine(
        core.LayeredSkin(),
        n,
        pitch,
        depths,
        ij,
        depth_index=depth_index,
        components=comps,
        method="direct",
    )
    if baseline is not None:  # the same engine on another build's _core
        with using_core(baseline):
            e.baseline = core.StressEngine(
                core.LayeredSkin(),
                n,
                pitch,
                depths,
                ij,
                depth_index=depth_index,
                components=comps,
                method="direct",
            )
    counts = {c: int((lay.classes == c).sum()) for c in ("SA1", "RA", "PC")}
    macs = sum(len(c) for c in comps) * int((p > 0).sum())
    desc = (
        f"{name}: {f[0]:.3f} N normal, {int((p > 0).sum())} active cells of {n}x{n} at "
        f"{pitch * 1e3:.2g} mm; {len(ij)} receptors {counts}, quantities {lay.quantity}; "
        f"{macs / 1e6:.2f} M multiply-adds per step on the folded path"
    )
    szz = np.array([c is SZZ for c in comps])
    return e, p, ratio, desc, lay.block(data.sensordata, "stress").copy(), szz


def sites(n: int, pitch: float, count: int, radius: float = 5e-3):
    """count sites on a Vogel spiral, classes in the default density ratio."""
    dens = np.array([70.0, 140.0, 21.0])
    per = np.round(count * dens / dens.sum()).astype(int)
    per[1] += count - per.sum()
    golden = math.pi * (3 - math.sqrt(5))
    ij, cls = [], []
    for c, m in enumerate(per):
        for s in range(m):
            r = radius * math.sqrt((s + 0.5) / m)
            th = s * golden + 0.5 * c
            i = int(np.clip(round(r * math.cos(th) / pitch + n / 2 - 0.5), 0, n - 1))
            j = int(np.clip(round(r * math.sin(th) / pitch + n / 2 - 0.5), 0, n - 1))
            ij.append((i, j))
            cls.append(c)
    return np.array(ij), np.array(cls)


def engine(skin, n, pitch, ij, cls):
    """The plugin's stress stage for these sites: SA1 all six components at
    0.75 mm, RA s_zz at 0.75 mm, PC s_zz at 2 mm (one engine, so the FFT path
    shares its forward transforms as in the plugin)."""
    depth_index = np.where(cls == 2, 1, 0)
    comps = [ALL if c == 0 else SZZ for c in cls]
    return core.StressEngine(
        skin,
        n,
        pitch,
        [0.75e-3, 2.0e-3],
        ij,
        depth_index=depth_index,
        components=comps,
        method="fft",
    )


def calibrate(n, pitch, ij, p, qx, qy, repeats):
    """Fit the cost model's constants (plugin/core/stress/stress_field.cc) here:
    seconds per multiply-add (direct), per N^2 log2(N^2) of one 2D transform,
    and per N^2 x load of one output pair's spectral products (FFT)."""
    e1 = core.StressEngine(0.48, n, pitch, [0.75e-3], ij, components=SZZ, method="fft")
    e2 = core.StressEngine(
        0.48, n, pitch, [0.75e-3, 2e-3], ij, depth_index=np.arange(len(ij)) % 2, method="fft"
    )
    _, t1, _, _ = e1.stress(p, method="fft", repeats=repeats, timing=True)
    _, t2, _, _ = e2.stress(p, qx, qy, method="fft", repeats=repeats, timing=True)
    _, td, _, active = e2.stress(p, qx, qy, method="direct", repeats=repeats, timing=True)
    N = e1.fft_n
    P, Q = N * N * math.log2(N * N), N * N
    # t1 = a (1 forward + 1 pair) P + b (1 pair x 1 load) Q
    # t2 = a (2 forward + 6 pairs) P + b (6 pairs x 3 loads) Q
    a, b = np.linalg.solve([[2 * P, Q], [8 * P, 18 * Q]], [t1, t2])
    c = td / (len(ij) * 6 * 3 * active)
    print(
        f"cost model fit (N = {N}): kDirectSecondsPerMac = {c:.3g}, kFftSecondsPerPoint = "
        f"{a:.3g}, kMulSecondsPerPoint = {b:.3g}"
    )
    # Folded path (stress_fold_plan.cc): its two constants (sums, fold) in a fixed
    # ratio; the measured / modelled time scales both.
    slip = (float(qx.sum() / p.sum()), float(qy.sum() / p.sum()))
    _, tf, _, _ = e2.stress(p, qx, qy, method="direct", repeats=repeats, timing=True, slip=slip)
    model = e2.estimated_cost(active, True, folded=True)[0]
    print(
        f"folded path: measured {tf * 1e6:.1f} us, model {model * 1e6:.1f} us: scale "
        f"kFoldedSecondsPerMac and kFoldSecondsPerCell by {tf / model:.2f}"
    )


def folded_stage(e, p, ratio, rounds: int, repeats: int, threads: int):
    """The stress stage by four paths, interleaved (each round times each
    path over `repeats` calls, in turn): the reference direct sum (three
    tables per component), the folded direct path (one effective table per
    step, plugin/core/stress/stress_fold.h) on one thread, the same in its
    memory layout before #13 (fold_legacy: unaligned table loads; the same
    bits), and folded on `threads` threads. Prints min / median per call (CPU
    time on one thread, wall time on several) and the ratios."""
    paths = {
        "reference": dict(fold=False, threads=1),
        "folded (legacy layout)": dict(fold=True, threads=1, fold_legacy=True),
        "folded": dict(fold=True, threads=1),
        f"folded+{threads}threads": dict(fold=True, threads=threads),
    }
    base = getattr(e, "baseline", None)
    if base is not None:  # another build's folded path (load_baseline_core)
        paths["folded (baseline build)"] = dict(fold=True, threads=1)
    times = {k: [] for k in paths}
    outs = {}
    for rnd in range(rounds):
        order = list(paths)
        if base is not None:
            # the two builds next to each other, in turn first, before the
            # threaded run (its pool's spinning worker counts in CPU time)
            fb, f1 = "folded (baseline build)", "folded"
            order = [k for k in order if k not in (fb, f1)]
            order[2:2] = [fb, f1] if rnd % 2 == 0 else [f1, fb]
        for name in order:
            kw = paths[name]
            # one thread: the process's CPU time (on a shared machine wall time
            # also counts waiting for a core); more: wall time
            eng = base if name == "folded (baseline build)" else e
            c0 = time.process_time()
            outs[name], t, _, _ = eng.stress(
                p, slip=ratio, method="direct", repeats=repeats, timing=True, **kw
            )
            if kw["threads"] == 1:
                t = (time.process_time() - c0) / repeats
            times[name].append(t)
    ref = outs["reference"]
    if not np.array_equal(outs["folded (legacy layout)"], outs["folded"]):
        raise RuntimeError("the folded path's two layouts differ (they must give the same bits)")
    for name, ts in times.items():
        d = outs[name] - ref
        rms = math.sqrt(float((d**2).sum() / (ref**2).sum()))
        print(
            f"  {name:22s} min {min(ts) * 1e6:8.1f} us  median {np.median(ts) * 1e6:8.1f} us"
            f"  | rel. RMS vs reference {rms:.1e}"
        )
    r = {
        k: (min(times["reference"]) / min(v), np.median(times["reference"]) / np.median(v))
        for k, v in times.items()
    }
    f1, ft, fl = "folded", f"folded+{threads}threads", "folded (legacy layout)"
    print(
        f"  ratios (min / median): reference / folded {r[f1][0]:.2f} / {r[f1][1]:.2f}, "
        f"reference / {ft} {r[ft][0]:.2f} / {r[ft][1]:.2f}, folded / {ft} "
        f"{min(times[f1]) / min(times[ft]):.2f} / "
        f"{np.median(times[f1]) / np.median(times[ft]):.2f}, legacy layout / folded "
        f"{min(times[fl]) / min(times[f1]):.2f} / "
        f"{np.median(times[fl]) / np.median(times[f1]):.2f}"
    )
    if base is not None:
        fb = "folded (baseline build)"
        paired = np.median(np.array(times[fb]) / np.array(times[f1]))
        print(
            f"  baseline build / this build (folded, one thread): min "
            f"{min(times[fb]) / min(times[f1]):.3f}, median "
            f"{np.median(times[fb]) / np.median(times[f1]):.3f}, median of rounds {paired:.3f}; "
            f"same bits: {np.array_equal(outs[fb], outs[f1])}"
        )
    return times


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--force", type=float, default=0.5, help="normal force, N")
    ap.add_argument("--receptors", type=int, default=250)
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--calibrate", action="store_true", help="fit the cost model's constants")
    ap.add_argument(
        "--stage-only",
        action="store_true",
        help="only the stress stage by path: reference / folded / folded+threads",
    )
    ap.add_argument("--threads", type=int, default=2, help="threads for folded+threads")
    ap.add_argument("--rounds", type=int, default=15, help="interleaved rounds (stage table)")
    ap.add_argument("--scene", help="only the stage table, on models/SCENE.xml's own stage")
    ap.add_argument(
        "--baseline-core",
        metavar="PATH",
        help="with --scene: also time another build's mjtouch._core (a copy of its "
        "_core*.so) in this process, interleaved",
    )
    args = ap.parse_args(argv)

    if args.baseline_core and not args.scene:
        ap.error("--baseline-core needs --scene")
    if args.scene:
        base = load_baseline_core(args.baseline_core) if args.baseline_core else None
        e, p, ratio, desc, _, _ = scene_stage(args.scene, base)
        print(desc)
        print(
            f"stress stage, slip ratio ({ratio[0]:.3f}, {ratio[1]:.2g}), {args.rounds} "
            f"interleaved rounds of {max(1, args.repeats // 20)} calls:"
        )
        folded_stage(e, p, ratio, args.rounds, max(1, args.repeats // 20), args.threads)
        return

    tip, p, ratio, f = default_contact(args.force)
    n, pitch = tip.nx, tip.pitch_m
    qx, qy = (p * ratio[0]).astype(np.float32), (p * ratio[1]).astype(np.float32)
    ij, cls = sites(n, pitch, args.receptors)
    print(
        f"contact: {f[0]:.3f} N normal, {math.hypot(f[1], f[2]):.3f} N tangential, "
        f"{int((p > 0).sum())} active cells of {n}x{n} at {pitch * 1e3:.2g} mm; "
        f"{len(ij)} receptors (SA1 {int((cls == 0).sum())}, RA {int((cls == 1).sum())}, "
        f"PC {int((cls == 2).sum())})"
    )

    if args.calibrate:
        calibrate(n, pitch, ij, p, qx, qy, args.repeats)
    print(
        f"stress stage, layered skin, slip ratio ({ratio[0]:.3f}, {ratio[1]:.2g}), "
        f"{args.rounds} interleaved rounds of {max(1, args.repeats // 20)} calls:"
    )
    folded_stage(
        engine(core.LayeredSkin(), n, pitch, ij, cls),
        p,
        ratio,
        args.rounds,
        max(1, args.repeats // 20),
        args.threads,
    )
    if args.stage_only:
        return
    skins = {"layered (Shao)": core.LayeredSkin(), "homogeneous (nu 0.48)": 0.48}
    results = {}
    for name, skin in skins.items():
        t0 = time.perf_counter()
        e = engine(skin, n, pitch, ij, cls)
        build = time.perf_counter() - t0
        row = {"build_s": build}
        for method in ("direct", "fft"):  # direct: the folded path, as in the plugin
            e.stress(p, qx, qy, method=method, repeats=3, slip=ratio)  # warm up
            out, row[method], _, active = e.stress(
                p, qx, qy, method=method, slip=ratio, repeats=args.repeats, timing=True
            )
            row[method + "_out"] = out
        row["est_direct"], row["est_fft"] = e.estimated_cost(active, True, folded=True)
        results[name] = row
        print(
            f"{name:22s} tables+spectra {build:6.2f} s | direct {row['direct'] * 1e6:8.1f} us"
            f" | fft {row['fft'] * 1e6:8.1f} us | model: direct {row['est_direct'] * 1e6:8.1f}"
            f" us, fft {row['est_fft'] * 1e6:8.1f} us"
        )
        a, b = row["direct_out"], row["fft_out"]
        agree = np.abs(a - b).max() / np.abs(a).max()
        print(f"{'':22s} direct vs fft: max difference {agree:.1e} of the largest stress")

    lay, hom = results["layered (Shao)"], results["homogeneous (nu 0.48)"]
    print(
        f"ratio layered / homogeneous: direct {lay['direct'] / hom['direct']:.3f}, "
        f"fft {lay['fft'] / hom['fft']:.3f}"
    )
    best = min(lay["direct"], lay["fft"])
    print(
        f"per-step stress cost (layered, best path): {best * 1e6:.1f} us; goal 100 us: "
        f"{'met' if best <= 100e-6 else 'NOT met'}"
    )
    # What bounds the folded direct path: one multiply-add per (site,
    # component, active cell) on the effective tables (plus their fold).
    active = int((p > 0).sum())
    macs = (int((cls == 0).sum()) * 6 + int((cls != 0).sum())) * active
    print(
        f"folded direct path: {macs / 1e6:.2f} M multiply-adds per step -> "
        f"{lay['direct'] / macs * 1e9:.3f} ns each"
    )


if __name__ == "__main__":
    main()
