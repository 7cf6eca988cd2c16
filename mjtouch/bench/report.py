"""The text report and the figure of a benchmark result."""

from __future__ import annotations

import sys

import numpy as np


def _fmt(v, spec: str, none: str = "-") -> str:
    return none if v is None else format(v, spec)


def print_report(o: dict, stream=None) -> None:
    out = stream or sys.stdout

    def p(s=""):
        print(s, file=out)

    b, r = o["baselines"], o["ratios"]
    m = o["machine"]
    p(
        f"mjtouch bench: default sliding scene (ridged fingertip, {o['scene']['force_n']:g} N, "
        f"{o['scene']['speed_m_s'] * 1e3:g} mm/s over the {o['scene']['period_m'] * 1e3:g} mm "
        f"grating); {m['cpu_count']} CPUs, load average {_fmt(m.get('loadavg_start') and m['loadavg_start'][0], '.2f')}"
        f" -> {_fmt(m.get('loadavg_end') and m['loadavg_end'][0], '.2f')}; wall {o['wall_s']:.0f} s"
    )
    p()
    p(
        f"Baselines (us per step, dt = {b['timestep_s']:g} s, {b['taxels']} taxels, "
        f"{b['receptors']} receptors, ~{b['active_taxels']:.0f} taxels in contact)"
    )
    for k, label in [
        ("bare_mujoco", "bare MuJoCo step (no plugin)"),
        ("native_tactile", f"native tactile sensor, {b['native_tactile_taxels']} taxels"),
        ("native_tactile_sensors_off", "  same model, sensors disabled"),
        ("full_pipeline", "full pipeline (default skin)"),
        ("homogeneous_kernel", "  half-space (homogeneous) kernel"),
        ("idle_plugin", "idle plugin (finger lifted)"),
        ("bare_mujoco_idle", "  bare MuJoCo, finger lifted"),
        ("idle_plugin_rollout", "idle plugin, mujoco.rollout (records state)"),
        ("bare_mujoco_idle_rollout", "  bare MuJoCo, mujoco.rollout"),
    ]:
        p(f"  {label:44s} {b[k + '_us_per_step']:10.2f}")
    p(
        f"  full / bare {r['full_over_bare']:.1f};  plugin {r['plugin_us_per_step']:.1f} us vs native "
        f"tactile {r['native_tactile_sensor_us_per_step']:.1f} us "
        f"({_fmt(r['plugin_over_native_tactile_sensor'], '.2f')}x, "
        f"{r['native_tactile_ns_per_taxel']:.1f} ns/taxel);  idle over bare "
        f"{r['idle_overhead_pct']:+.1f}% (in rollout {r['idle_rollout_overhead_pct']:+.1f}%);  layered / half-space {r['layered_over_homogeneous']:.2f};  "
        f"{r['full_wall_s_per_sim_s']:.2f} s wall per simulated s ({r['full_over_100us_goal']:.1f}x "
        f"the 100 us goal)"
    )
    p()
    p(
        "Accuracy vs time (errors against each knob's reference, '*' = Pareto front of wall per "
        "simulated s vs stress error, within the knob)"
    )
    hdr = (
        f"  {'knob':13s} {'setting':40s} {'us/step':>9s} {'s/sim s':>8s} {'stress':>8s} "
        f"{'peak Hz':>8s} {'peak amp':>8s} {'rates':>8s} {'nrec':>5s}"
    )
    p(hdr)

    def pct(v):
        return _fmt(None if v is None else 100 * v, "7.2f") + ("%" if v is not None else " ")

    for row in o["rows"]:
        e = row["errors"]
        p(
            f"{'*' if row['pareto'] else ' '} {row['knob']:13s} "
            f"{(row['setting'] + (' (ref)' if row['reference'] else ''))[:40]:40s} "
            f"{row['us_per_step']:9.1f} {row['wall_s_per_sim_s']:8.2f} {pct(e['stress_rms_rel'])} "
            f"{_fmt(e['peak_freq_hz'], '8.3f')} {pct(e['peak_amp_rel'])} {pct(e['spike_rate_rel'])} "
            f"{row['receptors']:5d}"
        )
    if o.get("effects"):
        p()
        p(
            "Effects: per-step cost of each effect alone (over the minimal skin), all together, and "
            "the default without each"
        )
        for r in o["effects"]:
            p(
                f"  {r['group']:8s} {r['effect'][:64]:64s} {r['us_per_step']:9.1f} us "
                f"({r['over_minimal_us']:+8.1f} vs minimal, {r['over_default_us']:+8.1f} vs default)"
            )
        if o.get("profile"):
            pr = o["profile"]
            p(
                f"  profile of the default: MuJoCo {pr['mujoco_us']:.1f} us, surface + pressure "
                f"{pr['surface_pressure_us']:.1f} us, stress + receptors {pr['stress_receptors_us']:.1f} us"
            )
    if o.get("threads"):
        t = o["threads"]
        p()
        p(
            f"Threads: mujoco.rollout of {t['nbatch']} MjData x {t['steps']} steps: 1 thread "
            f"{t['wall_s_1_thread']:.3f} s, 2 threads {t['wall_s_2_thread']:.3f} s, speedup "
            f"{t['speedup_2_threads']:.2f} on {t['cpu_count']} CPUs (identical results: "
            f"{t['identical_across_threads']})"
        )
    s = o.get("scaling", {})
    p()
    for key, what in (
        ("active_taxels", "active taxels (pitch sweep)"),
        ("receptors", "receptors (density sweep)"),
    ):
        if key in s:
            f, a = s[key]["power_law"], s[key]["affine"]
            p(
                f"Scaling of the plugin's cost with {what}: exponent {_fmt(f['exponent'], '.2f')} "
                f"(log-log R^2 {_fmt(f['r2'], '.3f')}, {f['n']} points); affine "
                f"{_fmt(a['intercept'], '.1f')} us + {_fmt(a['slope'] and a['slope'] * 1e3, '.2f')} ns "
                f"per unit (R^2 {_fmt(a['r2'], '.3f')})"
            )


def _num(v: float) -> str:
    """us and ratios as the docs print them: three significant figures."""
    if v >= 100:
        return f"{v:.0f}"
    return f"{v:.3g}"


def _pct_md(v) -> str:
    if v is None:
        return "-"
    pct = 100 * v
    if pct == 0:
        return "0"
    if pct < 0.01:
        return "<0.01%"
    if pct >= 10:
        return f"{pct:.0f}%"
    text = f"{pct:.2g}"
    return (text if "." in text else f"{pct:.1f}") + "%"


def print_markdown(o: dict, stream=None) -> None:
    """The accuracy table and the baselines as Markdown (docs/performance.md
    prints them as this writes them): ``python -m mjtouch bench --from-json
    bench.json --markdown``."""
    out = stream or sys.stdout

    def p(s=""):
        print(s, file=out)

    p("| knob | setting | us/step | s wall / s sim | stress err | peak amp err | rate err |")
    p("|---|---|---:|---:|---:|---:|---:|")
    last = None
    for row in o["rows"]:
        e = row["errors"]
        setting = row["setting"] + (", reference" if row["reference"] else "")
        if row["reference"]:
            setting = f"**{setting}**"
        knob = row["knob"] if row["knob"] != last else ""
        last = row["knob"]
        p(
            f"| {knob} | {setting} | {_num(row['us_per_step'])} | "
            f"{_num(row['wall_s_per_sim_s'])} | {_pct_md(e['stress_rms_rel'])} | "
            f"{_pct_md(e.get('peak_amp_rel'))} | {_pct_md(e['spike_rate_rel'])} |"
        )
    b = o["baselines"]
    p()
    p("| baseline | us/step |")
    p("|---|---:|")
    for k, label in [
        ("bare_mujoco", "bare MuJoCo step (plugin removed from the MJCF)"),
        ("native_tactile", f"MuJoCo native `tactile` sensor, {b['native_tactile_taxels']} taxels"),
        ("full_pipeline", "full pipeline, default skin (`elastic` contact, exact stress)"),
        ("homogeneous_kernel", "same with the homogeneous (half-space) kernel"),
        ("idle_plugin", "idle plugin (finger lifted)"),
        ("bare_mujoco_idle", "bare MuJoCo, finger lifted"),
        ("idle_plugin_rollout", "idle plugin, timed through `mujoco.rollout`"),
        ("bare_mujoco_idle_rollout", "bare MuJoCo, through `mujoco.rollout`"),
    ]:
        p(f"| {label} | {_num(b[k + '_us_per_step'])} |")


def _error_panel(ax, o: dict, key: str, ylabel: str, front_key: str) -> None:
    rows = o["rows"]
    nonzero = [r["errors"][key] for r in rows if r["errors"][key]]
    floor = min(nonzero) / 10 if nonzero else 1e-6
    for i, name in enumerate(dict.fromkeys(r["knob"] for r in rows)):
        kr = [r for r in rows if r["knob"] == name and r["errors"][key] is not None]
        x = [r["wall_s_per_sim_s"] for r in kr]
        y = [max(r["errors"][key], floor) for r in kr]
        colour = f"C{i}"
        ax.plot(x, y, "-o", c=colour, ms=4, lw=0.8, label=name)
        for xi, yi, r in zip(x, y, kr):
            if r.get(front_key):
                ax.plot(xi, yi, "o", ms=9, mfc="none", c=colour)
            if r["reference"]:
                ax.plot(xi, yi, "v", ms=8, c=colour)
    base = o["baselines"]
    dt = base["timestep_s"]
    for k, style, label in (
        ("bare_mujoco", ":", "bare MuJoCo"),
        ("native_tactile", "--", "native tactile"),
        ("full_pipeline", "-", "full pipeline"),
    ):
        x = base[k + "_us_per_step"] * 1e-6 / dt
        ax.axvline(x, ls=style, c="grey", lw=0.8)
        ax.text(x, floor, " " + label, rotation=90, va="bottom", fontsize=7, color="grey")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall seconds per simulated second")
    ax.set_ylabel(ylabel)


def plot(o: dict, path: str) -> None:
    """Stress and spike-rate error vs cost per knob (circles: the Pareto
    front of stress error; triangles: references, drawn at the floor), and
    the baselines and effects in us per step."""
    try:
        import matplotlib.figure
    except ImportError:
        raise SystemExit("--plot needs matplotlib: pip install 'mjtouch[plot]'") from None
    fig = matplotlib.figure.Figure(figsize=(16, 5.5))
    a, a2, bx = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1, 1, 0.9]})
    _error_panel(a, o, "stress_rms_rel", "relative RMS stress error at receptors", "pareto")
    a.set_title("stress error vs cost (circles: Pareto front; triangles: references)", fontsize=9)
    a.legend(fontsize=8)
    _error_panel(
        a2, o, "spike_rate_rel", "relative spike-rate error (classes summed)", "pareto_spike_rate"
    )
    a2.set_title("spike-rate error vs cost (circles: its Pareto front)", fontsize=9)
    base = o["baselines"]
    labels = ["bare MuJoCo", "native tactile", "full pipeline", "half-space kernel", "idle plugin"]
    vals = [
        base[k + "_us_per_step"]
        for k in (
            "bare_mujoco",
            "native_tactile",
            "full_pipeline",
            "homogeneous_kernel",
            "idle_plugin",
        )
    ]
    for r in o.get("effects", []):
        labels.append(f"{r['group'][0]}: {r['effect'][:38]}")
        vals.append(r["us_per_step"])
    ypos = np.arange(len(vals))
    bx.barh(ypos, vals, color=["grey"] * 5 + ["C0"] * (len(vals) - 5))
    bx.set_yticks(ypos, labels, fontsize=6)
    bx.invert_yaxis()
    bx.set_xscale("log")
    bx.set_xlabel("us per step")
    bx.set_title("baselines; effects (a: alone, t: together, w: default changed)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
