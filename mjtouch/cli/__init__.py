"""Command line: ``python -m mjtouch slide | view | bench | sweep | probe | tuning`` (also the
``mjtouch`` script)."""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def _positive_float(name):
    def parse(s):
        try:
            v = float(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {s!r}")
        if not (np.isfinite(v) and v > 0):
            raise argparse.ArgumentTypeError(f"{name} must be a positive number, got {s}")
        return v
    return parse


def _slide_parser(sub):
    p = sub.add_parser("slide", help="ridged fingertip pressed on a plate and slid; prints "
                                     "spike rates and stress spectral peaks vs V/D and V/lambda")
    p.add_argument("--texture", choices=["grating", "random", "dots", "flat"], default="grating")
    p.add_argument("--period", type=_positive_float("--period"), default=None,
                   help="texture spatial period D (m), default 1e-3; with --texture-mesh: the "
                        "mesh's period, to report peaks against V/D")
    p.add_argument("--plateau", type=_positive_float("--plateau"), default=None,
                   help="grating plateau width (m), default period/2")
    p.add_argument("--height", type=_positive_float("--height"), default=0.1e-3,
                   help="grating height (m), default 1e-4")
    p.add_argument("--rms", type=_positive_float("--rms"), default=20e-6,
                   help="random texture: RMS height (m), default 2e-5")
    p.add_argument("--corr-length", type=_positive_float("--corr-length"), default=60e-6,
                   help="random texture: Gaussian correlation length (m), default 6e-5")
    p.add_argument("--dot-spacing", type=_positive_float("--dot-spacing"), default=2.5e-3,
                   help="dots texture: hexagonal lattice spacing (m), default 2.5e-3")
    p.add_argument("--dot-radius", type=_positive_float("--dot-radius"), default=0.6e-3,
                   help="dots texture: dot base radius (m), default 6e-4")
    p.add_argument("--speed", type=_positive_float("--speed"), default=0.025,
                   help="sliding speed V (m/s), default 0.025")
    p.add_argument("--force", type=_positive_float("--force"), default=0.5,
                   help="normal force (N), default 0.5")
    p.add_argument("--ridges", action=argparse.BooleanOptionalAction, default=True,
                   help="fingerprint ridges on the skin (default on)")
    p.add_argument("--ridge-pitch", type=_positive_float("--ridge-pitch"), default=0.45e-3,
                   help="ridge pitch lambda (m), default 4.5e-4")
    p.add_argument("--duration", type=_positive_float("--duration"), default=1.0,
                   help="sliding time (s), default 1")
    p.add_argument("--dt", type=_positive_float("--dt"), default=1e-4,
                   help="simulation timestep (s), default 1e-4")
    p.add_argument("--nx", type=int, default=128, help="taxels per side, default 128")
    p.add_argument("--pitch", type=_positive_float("--pitch"), default=1e-4,
                   help="taxel pitch (m), default 1e-4")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the random texture (the pipeline itself is deterministic)")
    p.add_argument("--pressure", choices=["winkler", "elastic", "contacts"], default="elastic",
                   help="pressure model (default elastic: the skin's own compliance, which lets "
                        "the ridges carry the load in partial contact; winkler: a foundation, "
                        "faster, presses the ridges flat; contacts: MuJoCo's contact points)")
    p.add_argument("--grid-shift", action="store_true",
                   help="elastic: also solve on the half-cell shifted grid and average "
                        "(skin attribute grid_shift; cancels the V/pitch grid line that PC "
                        "rates pick up, ~1.8x the step)")
    p.add_argument("--texture-mesh", metavar="FILE",
                   help="texture from a mesh file's top surface (STL, OBJ, PLY, GLB; trimesh), "
                        "sliding along the mesh's x after placement; overrides --texture")
    p.add_argument("--mesh-scale", type=_positive_float("--mesh-scale"), default=1.0,
                   help="mesh units to m (1e-3 for a file in mm), default 1")
    p.add_argument("--mesh-up", default="+z", choices=["+z", "-z", "+x", "-x", "+y", "-y"],
                   help="mesh axis out of the textured face, default +z")
    p.add_argument("--mesh-rotate", type=float, default=0.0,
                   help="turn the mesh about the up axis (deg), default 0")
    p.add_argument("--mesh-resolution", type=_positive_float("--mesh-resolution"),
                   default=2e-5, help="height-field cell of the mesh texture (m), default 2e-5")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write a PNG of the spectrum and raster")
    from mjtouch import progress
    progress.add_argument(p)
    return p


def slide(args) -> dict:
    return slide_with_result(args)[0]


def _slide_skin(args) -> dict:
    skin = {"pressure": args.pressure}
    if getattr(args, "grid_shift", False):
        if args.pressure != "elastic":
            raise ValueError(f"--grid-shift: needs --pressure elastic (got {args.pressure!r})")
        skin["grid_shift"] = "true"
    return skin


def slide_with_result(args):
    """slide(args) and the run's rollout.SlideResult (spikes, stress, force)."""
    from mjtouch.scene import scenes

    tip = scenes.Fingertip(ridges=args.ridges, ridge_pitch_m=args.ridge_pitch, nx=args.nx,
                           pitch_m=args.pitch, skin=_slide_skin(args))
    if getattr(args, "texture_mesh", None):
        return _slide_run(args, tip, _mesh_texture(args), args.period, "mesh")
    args.period = args.period or 1.0e-3
    texture = scenes.Texture(kind=args.texture, period_m=args.period, plateau_m=args.plateau,
                             height_m=args.height, rms_m=args.rms,
                             corr_length_m=args.corr_length, dot_spacing_m=args.dot_spacing,
                             dot_radius_m=args.dot_radius, seed=args.seed)
    # the plate must hold the whole slide with margin for the contact patch;
    # 2D textures are sized to the slide to keep the height field small
    need = 2 * (args.speed * args.duration) + 0.02
    if args.texture in ("random", "dots"):
        texture.length_m, texture.width_m = need, 0.016
    else:
        texture.length_m = max(texture.length_m, need)
    periodic = {"grating": args.period, "dots": args.dot_spacing}.get(args.texture)
    return _slide_run(args, tip, texture, periodic, args.texture)


def _mesh_texture(args):
    from mjtouch.scene import textures
    need = 2 * (args.speed * args.duration) + 0.02
    mt = textures.from_mesh(args.texture_mesh, scale=args.mesh_scale, up=args.mesh_up,
                            rotate_deg=args.mesh_rotate, resolution_m=args.mesh_resolution)
    if mt.length_m < need:
        raise ValueError(f"--texture-mesh {args.texture_mesh}: its top surface is "
                         f"{mt.length_m * 1e3:.3g} mm long after --mesh-scale "
                         f"{args.mesh_scale:g}; sliding {args.duration:g} s at {args.speed:g} m/s "
                         f"needs {need * 1e3:.3g} mm (the slide and the pad, both ways): "
                         "shorten --duration or slow --speed")
    return mt.texture()


# Shortest `slide`: rollout.SETTLE_S settling plus 0.05 s analysed (a 20 Hz FFT bin).
MIN_DURATION_S = 0.15


def _slide_run(args, tip, texture, periodic, kind):
    from mjtouch import progress
    from mjtouch.analysis import signals
    from mjtouch.experiments import rollout
    from mjtouch.scene import scenes
    # rates and spectra leave out the first SETTLE_S of sliding (SlideResult.window)
    if args.duration < MIN_DURATION_S:
        raise ValueError(f"--duration {args.duration:g} s: must be at least "
                         f"{MIN_DURATION_S:g} s (rates and spectra leave out "
                         f"the first {rollout.SETTLE_S:g} s of sliding, while it settles)")
    protocol = scenes.Protocol(force_n=args.force, speed_m_s=args.speed, timestep_s=args.dt)
    t0 = time.perf_counter()
    # the step count scenes.controls will make (not the array: a bad --duration is
    # reported by run_slide, not by an allocation)
    nstep = round(protocol.press_s / args.dt) + round(args.duration / args.dt)
    with progress.Progress(nstep, progress.wanted(args.progress, args.json), desc="slide",
                           unit="step") as bar:
        res = rollout.run_slide(tip, texture, protocol, duration_s=args.duration,
                                progress=bar.update if bar.enabled else None)
    wall = time.perf_counter() - t0
    w = res.window()
    dt = res.dt
    rates = signals.rates_hz(res.spikes[w], dt, res.layout.classes)
    f, p = signals.stress_spectrum(res.stress[w], dt)
    peaks = signals.spectral_peaks(f, p, n=6, fmin_hz=5.0, fmax_hz=min(1000.0, 0.5 / dt))
    expected = {"texture": args.speed / periodic if periodic else None,
                "ridges": args.speed / args.ridge_pitch if args.ridges else None}
    power_expected = {k: (signals.power_at(f, p, v) if v else None) for k, v in expected.items()}
    # at V/lambda of the configured ridge pitch for smooth skin too, so ridged
    # and smooth runs compare from the CLI
    power_expected["ridges"] = signals.power_at(f, p, args.speed / args.ridge_pitch)
    # A periodic texture's stress repeats every D/V: its lines are V/D
    # harmonics whatever the ridges do, so a V/lambda line is expected only
    # on aperiodic (broadband) textures, which the ridges band-pass.
    ridge_line_expected = bool(args.ridges and not periodic)
    nearest = {k: (min(peaks, key=lambda x, v=v: abs(x - v)) if v and len(peaks) else None)
               for k, v in expected.items()}
    fn = res.force[w, 0]
    out = {
        "rates_hz": rates,
        "peaks_hz": peaks,
        "expected_hz": expected,
        "nearest_peak_hz": nearest,
        "ridge_line_expected": ridge_line_expected,
        # the elastic contact misplaces texture edges sharper than a cell: a
        # stress line at V / pitch unless grid_shift cancels it (README "What
        # accuracy costs"; examples/pc_grid_line.py)
        "grid_line_hz": (args.speed / args.pitch
                         if args.pressure == "elastic" and not getattr(args, "grid_shift", False)
                         else None),
        "grid_shift": bool(getattr(args, "grid_shift", False)),
        "power_at_expected": power_expected,
        "speed_m_s": args.speed,
        "period_m": periodic,
        "ridge_pitch_m": args.ridge_pitch,
        "ridges": args.ridges,
        "texture": kind,
        "pressure": args.pressure,
        "force_n": args.force,
        "duration_s": args.duration,
        "dt_s": dt,
        "fft_bin_hz": float(f[1] - f[0]),
        "normal_force_mean_n": float(fn.mean()),
        "receptors": {c: int((res.layout.classes == c).sum()) for c in ("SA1", "RA", "PC")},
        "wall_s": wall,
        "seed": args.seed,
    }
    if args.plot:
        _plot(args.plot, res, f, p, expected, w)
    return out, res


def _plot(path, res, f, p, expected, w):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("--plot needs matplotlib: pip install 'mjtouch[plot]'")
    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 7))
    a.semilogy(f[1:], p[1:], lw=0.8)
    for name, v in expected.items():
        if v:
            a.axvline(v, ls="--", c="r" if name == "texture" else "g", label=f"{name} {v:.1f} Hz")
    a.set_xlim(0, min(600, f[-1]))
    a.set_xlabel("frequency (Hz)")
    a.set_ylabel("stress power (Pa$^2$)")
    a.legend()
    t = res.time_s[w]
    spikes = res.spikes[w]
    colors = {"SA1": "tab:blue", "RA": "tab:orange", "PC": "tab:green"}
    for r in range(spikes.shape[1]):
        ts = t[spikes[:, r] > 0]
        b.plot(ts, np.full_like(ts, r), "|", ms=2, c=colors[res.layout.classes[r]])
    b.set_xlabel("time (s)")
    b.set_ylabel("receptor (SA1, RA, PC)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _print_human(o: dict) -> None:
    period = f"{o['period_m'] * 1e3:.3g} mm" if o["period_m"] else "-"
    print(f"mjtouch slide: {o['texture']} texture, D = {period}, "
          f"V = {o['speed_m_s'] * 1e3:.3g} mm/s, F = {o['force_n']:.3g} N, "
          f"ridges {'on' if o['ridges'] else 'off'} (lambda = {o['ridge_pitch_m'] * 1e3:.3g} mm), "
          f"{o['duration_s']:.3g} s sliding (wall {o['wall_s']:.1f} s)")
    print("firing rates (Hz):  " + "  ".join(f"{k} {v:.1f}" for k, v in o["rates_hz"].items())
          + "   receptors: " + " ".join(f"{k} {v}" for k, v in o["receptors"].items()))
    e = o["expected_hz"]
    print("expected:  V/D = " + (f"{e['texture']:.2f} Hz" if e["texture"] else "-")
          + "   V/lambda = " + (f"{e['ridges']:.2f} Hz" if e["ridges"] else "-")
          + f"   (FFT bin {o['fft_bin_hz']:.2f} Hz)")
    print("stress spectral peaks (Hz, strongest first): "
          + ", ".join(f"{x:.2f}" for x in o["peaks_hz"]))
    near = o["nearest_peak_hz"]
    for key, name in (("texture", "V/D"), ("ridges", "V/lambda")):
        if not e[key]:
            continue
        if key == "ridges" and not o["ridge_line_expected"]:
            print(f"{name}: no line expected on a periodic texture (its stress repeats every "
                  "D/V, so its lines are V/D harmonics); ridges band-pass broadband textures: "
                  "--texture random")
        elif near[key] is not None:
            print(f"{name}: nearest peak {near[key]:.2f} Hz "
                  f"({round(100 * (near[key] / e[key] - 1)) + 0:+d}%)")
    if o.get("grid_line_hz"):
        print(f"note: the elastic contact adds a grid line at V/pitch = {o['grid_line_hz']:.0f} Hz "
              "to the stress; PC rates include it (--grid-shift cancels it; README, "
              "\"What accuracy costs\")")


def _view_parser(sub):
    from mjtouch.viewer import KEY_HELP, TEXTURES
    p = sub.add_parser("view", help="MuJoCo's viewer on a sliding scene: live pressure heatmap, "
                                    "flashing receptors, raster and stress spectrum",
                       description="Keys: " + KEY_HELP + ". MJCF scenes also open in plain "
                                   "`python -m mujoco.viewer --mjcf=FILE`.")
    p.add_argument("scene", nargs="?", default=None,
                   help="an MJCF file with an mjtouch.skin sensor (default: the built-in "
                        "sliding scene, whose texture and ridges the keys change)")
    p.add_argument("--force", type=_positive_float("--force"), default=0.5,
                   help="normal force (N), default 0.5")
    p.add_argument("--speed", type=_positive_float("--speed"), default=0.025,
                   help="sliding speed (m/s), default 0.025")
    p.add_argument("--texture", type=int, default=0, choices=range(len(TEXTURES)),
                   help="; ".join(f"{i}: {name}" for i, (name, _) in enumerate(TEXTURES)))
    p.add_argument("--ridges", action=argparse.BooleanOptionalAction, default=True)
    p.add_argument("--nx", type=int, default=48, help="taxels per side, default 48")
    p.add_argument("--dt", type=_positive_float("--dt"), default=1e-3,
                   help="simulation timestep (s), default 1e-3")
    p.add_argument("--offscreen", metavar="PNG",
                   help="no window: simulate --duration seconds and write what the viewer "
                        "would show to PNG (needs MUJOCO_GL=egl or osmesa)")
    p.add_argument("--duration", type=_positive_float("--duration"), default=1.0,
                   help="simulated seconds before --offscreen renders, default 1")
    return p


def view(args) -> int:
    from mjtouch import viewer
    try:
        settings = viewer.ViewSettings(force_n=args.force, speed_m_s=args.speed,
                                       texture=args.texture, ridges=args.ridges, nx=args.nx,
                                       timestep_s=args.dt)
        if args.offscreen:
            session = viewer.SlideSession(settings, args.scene)
            session.advance(int(round(args.duration / session.dt)))
            from PIL import Image
            Image.fromarray(session.render()).save(args.offscreen)
            session.close()
            print(f"mjtouch view: wrote {args.offscreen} ({session.status()})")
        else:
            viewer.launch(args.scene, settings)
    except (ValueError, FileNotFoundError) as e:
        print(f"mjtouch: error: {e}", file=sys.stderr)
        return 2
    return 0


def _bench_parser(sub):
    from mjtouch import bench
    p = sub.add_parser("bench", help="what accuracy costs in time: sweeps each knob of the "
                                     "default sliding scene against a converged reference",
                       description=bench.__doc__.split("\n\n")[0])
    bench.add_arguments(p)
    return p


def _sweep_parser(sub):
    from mjtouch.experiments import sweep
    p = sub.add_parser("sweep", help="slide over the product of several values of its options, "
                                     "on Ray (or --serial); one Parquet row per run",
                       description=sweep.__doc__.split("\n\n")[1])
    sweep.add_arguments(p)
    return p


# --- probe and tuning (issue 14): stimuli a physiologist uses ----------------------------------

def _probe_parser(sub):
    p = sub.add_parser("probe", help="a stimulus on the fingertip (displacement-controlled pin, "
                                     "sphere, or a vibrating plate under a pressed finger); "
                                     "prints firing rates per class")
    p.add_argument("--waveform", choices=["ramp", "sine", "sines", "noise", "trace"],
                   default="ramp", help="ramp-and-hold (default), sine, sum of sines, "
                                        "band-limited noise, or a trace from --trace FILE")
    p.add_argument("--probe", choices=["pin", "sphere", "plate"], default="pin",
                   help="flat pin (default), sphere, or a vibrating plate under the finger "
                        "pressed with --press")
    p.add_argument("--radius", type=_positive_float("--radius"), default=0.5e-3,
                   help="pin / sphere radius (m), default 5e-4")
    p.add_argument("--depth", type=_positive_float("--depth"), default=0.5e-3,
                   help="ramp: indentation (m), default 5e-4")
    p.add_argument("--ramp", type=_positive_float("--ramp"), default=0.05,
                   help="ramp time (s) of ramp-and-hold and of the sine envelopes, default 0.05")
    p.add_argument("--hold", type=_positive_float("--hold"), default=0.5,
                   help="ramp: hold time (s), default 0.5")
    p.add_argument("--amplitude", type=_positive_float("--amplitude"), nargs="+",
                   default=[10e-6], help="sine(s): amplitude(s) (m), default 1e-5")
    p.add_argument("--freq", type=_positive_float("--freq"), nargs="+", default=[40.0],
                   help="sine(s): frequency(ies) (Hz), default 40")
    p.add_argument("--duration", type=_positive_float("--duration"), default=1.0,
                   help="sine / noise duration (s), default 1")
    p.add_argument("--rms", type=_positive_float("--rms"), default=5e-6,
                   help="noise: RMS displacement (m), default 5e-6")
    p.add_argument("--band", type=float, nargs=2, default=[10.0, 500.0], metavar=("LO", "HI"),
                   help="noise: band (Hz), default 10 500")
    p.add_argument("--seed", type=int, default=0, help="noise: seed, default 0")
    p.add_argument("--trace", metavar="FILE", help="trace: displacement samples (m), a .npy "
                                                   "or a text file of numbers")
    p.add_argument("--trace-dt", type=_positive_float("--trace-dt"), default=1e-3,
                   help="trace: sample spacing (s), default 1e-3")
    p.add_argument("--preindent", type=float, default=None,
                   help="pin/sphere: static indentation (m) under the waveform; default 0 for "
                        "ramp, 5e-4 otherwise (so the probe stays in contact)")
    p.add_argument("--press", type=_positive_float("--press"), default=0.5,
                   help="plate: the finger's press force (N), default 0.5")
    p.add_argument("--dt", type=_positive_float("--dt"), default=1e-4,
                   help="simulation timestep (s), default 1e-4")
    p.add_argument("--nx", type=int, default=48, help="taxels per side, default 48")
    p.add_argument("--pitch", type=_positive_float("--pitch"), default=1.5e-4,
                   help="taxel pitch (m), default 1.5e-4")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    return p


def probe(args) -> dict:
    from mjtouch.experiments import stimuli
    from mjtouch.scene import scenes
    if args.waveform == "ramp":
        w = stimuli.ramp_and_hold(args.depth, ramp_s=args.ramp, hold_s=args.hold)
    elif args.waveform == "sine":
        w = stimuli.sine(args.amplitude[0], args.freq[0], args.duration, args.ramp)
    elif args.waveform == "sines":
        w = stimuli.sum_of_sines(args.amplitude, args.freq, args.duration, args.ramp)
    elif args.waveform == "noise":
        w = stimuli.noise(args.rms, tuple(args.band), args.duration, args.seed, args.ramp)
    else:
        if not args.trace:
            raise ValueError("--waveform trace needs --trace FILE")
        vals = (np.load(args.trace) if args.trace.endswith(".npy")
                else np.loadtxt(args.trace).ravel())
        w = stimuli.trace(vals, args.trace_dt)
    tip = scenes.Fingertip(nx=args.nx, pitch_m=args.pitch, ridges=False)
    t0 = time.perf_counter()
    if args.probe == "plate":
        res = stimuli.PlateScene(args.press, tip, timestep_s=args.dt).run(w)
    else:
        pre = args.preindent if args.preindent is not None else (
            0.0 if args.waveform == "ramp" else 0.5e-3)
        shape = stimuli.Probe(args.probe, radius_m=args.radius)
        res = stimuli.ProbeScene(shape, tip, preindent_m=pre, timestep_s=args.dt).run(w)
    out = res.summary()
    out.update(probe=args.probe, wall_s=time.perf_counter() - t0)
    return out


def _print_probe(o: dict) -> None:
    w = o["waveform"]
    print(f"mjtouch probe: {o['probe']}, {w['kind']} "
          + " ".join(f"{k}={v}" for k, v in w.items() if k != "kind" and not isinstance(v, list))
          + f" (wall {o['wall_s']:.1f} s)")
    print("rates in the steady part (Hz), mean / max / centred unit:")
    for c, r in o["rates_hz"].items():
        print(f"  {c:3s} {r['mean']:8.1f} {r['max']:8.1f} {r['centre']:8.1f}   "
              f"({o['receptors'][c]} receptors)")
    print(f"force {o['force_steady_mean_n']:.4g} N; displacement achieved to "
          f"{o['max_displacement_error_m'] * 1e6:.3g} um of commanded; finger moved "
          f"{o['finger_motion_max_m'] * 1e6:.3g} um")


def _tuning_parser(sub):
    p = sub.add_parser("tuning", help="threshold-frequency (absolute, entrainment) and "
                                      "rate-intensity curves per afferent class, with "
                                      "published ranges")
    p.add_argument("--quick", action="store_true",
                   help="a few seconds: 2 frequencies, coarse grid, small skin (for tests)")
    p.add_argument("--freqs", type=_positive_float("--freqs"), nargs="+", default=None,
                   help="vibration frequencies (Hz); default 5-600 Hz in 9 steps")
    p.add_argument("--min-cycles", type=int, default=None,
                   help="cycles counted at least per sine (default 20; --quick 5)")
    p.add_argument("--threads", type=int, default=2, help="rollout threads, default 2")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", metavar="FILE", help="also write the JSON to FILE")
    p.add_argument("--plot", metavar="FILE", help="write a PNG of both curves (matplotlib)")
    return p


def tuning_main(args) -> dict:
    from mjtouch.experiments import tuning
    cfg = tuning.TuningConfig.quick() if args.quick else tuning.TuningConfig()
    if args.freqs:
        cfg.freqs_hz = tuple(args.freqs)
    if args.min_cycles is not None:
        cfg.min_cycles = args.min_cycles
    cfg.threads = args.threads
    t0 = time.perf_counter()
    out = tuning.run(cfg)
    out["wall_s"] = time.perf_counter() - t0
    if args.out:
        with open(args.out, "w") as f:
            json.dump(out, f, indent=1)
    if args.plot:
        tuning.plot(out, args.plot)
    return out


def _print_tuning(o: dict) -> None:
    th = o["thresholds"]
    print(f"mjtouch tuning: thresholds (um) of the unit under the probe, absolute / 1:1, "
          f"[most sensitive unit's absolute] (wall {o['wall_s']:.1f} s)")
    print("  f (Hz) " + "".join(f"{c:>26s}" for c in th["thresholds_m"]))
    for i, f in enumerate(th["freqs_hz"]):
        cells = []
        for v in th["thresholds_m"].values():
            a, e, b = (v["centred"]["absolute"][i], v["centred"]["entrainment"][i],
                       v["best"]["absolute"][i])
            cells.append(f"{a * 1e6:8.3g} /{e * 1e6:8.3g} [{b * 1e6:6.3g}]")
        print(f"  {f:6.1f} " + "".join(f"{x:>26s}" for x in cells))
    ri = o["rate_intensity"]
    print("rate-intensity (centred unit, Hz): depth (mm) " +
          " ".join(f"{d * 1e3:.2f}" for d in ri["depths_m"]))
    for c, r in ri["rates"].items():
        print(f"  {c:3s} hold  " + " ".join(f"{x:.0f}" for x in r["hold_hz"])
              + "   ramps " + " ".join(f"{x:.0f}" for x in r["ramp_hz"]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="mjtouch", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    _slide_parser(sub)
    _view_parser(sub)
    _bench_parser(sub)
    _sweep_parser(sub)
    _probe_parser(sub)
    _tuning_parser(sub)
    args = parser.parse_args(argv)
    if args.command == "sweep":
        from mjtouch.experiments import sweep
        return sweep.main(args)
    if args.command in ("probe", "tuning"):
        try:
            out = probe(args) if args.command == "probe" else tuning_main(args)
        except ValueError as e:
            print(f"mjtouch: error: {e}", file=sys.stderr)
            return 2
        if args.json:
            print(json.dumps(out))
        else:
            (_print_probe if args.command == "probe" else _print_tuning)(out)
        return 0
    if args.command == "bench":
        from mjtouch import bench
        return bench.main(args)
    if args.command == "view":
        return view(args)
    if args.command == "slide":
        if not 4 <= args.nx <= 512:
            parser.error(f"--nx {args.nx} is out of range; valid range [4, 512]")
        try:
            out = slide(args)
        except (ValueError, FileNotFoundError) as e:
            print(f"mjtouch: error: {e}", file=sys.stderr)
            return 2
        if args.json:
            print(json.dumps(out))
        else:
            _print_human(out)
    return 0
