"""Tuning of the built afferent models, measured as a physiologist would:
threshold-frequency curves (absolute and entrainment) and rate-intensity
curves per class, from a displacement-controlled pin (mjtouch.experiments.stimuli), with
published ranges beside ours.

``python -m mjtouch tuning [--quick] [--json] [--plot FILE]``.

Definitions (Johansson, Landstrom & Lundstrom 1982, Brain Res 244:17-25;
Muniak, Ray, Hsiao, Dammann & Bensmaia 2007, J Neurosci 27:11687-11699; used
to validate TouchSim, Saal, Delhaye, Rayhaun & Bensmaia 2017, PNAS
114:E5693-E5702). A sine of amplitude A (m) and frequency f on a pin held at a
pre-indentation, counted over the sine's steady part (after its ramp), which
lasts ``steady_s`` or ``min_cycles`` cycles, whichever is longer (below):
- absolute threshold: the lowest A at which the afferent responds: it fires
  more than unstimulated (at least 2 and ``ABSOLUTE_SPIKES_PER_CYCLE`` extra
  spikes per cycle: a tonic train gains or loses one spike at the window's
  edge for any tiny perturbation), or its spikes are locked to the sine
  (Rayleigh test p < ``LOCK_P`` at f or 2f) at that many spikes per cycle.
  Both, because SA1s fire tonically under the pre-indentation: the sine
  may raise their rate without locking them, or lock them without adding
  spikes;
- entrainment threshold: the lowest A at which it fires at least one spike
  per cycle (1:1) more than unstimulated, or one locked spike per cycle.
Per class, two afferents: the ``centred`` unit (nearest the probe's axis, the
afferent a recording centres the probe on) and the ``best`` (most sensitive)
unit. In a noise-free model a unit whose static drive sits just below its
rheobase fires for any sine, so ``best`` can fall to the range's floor; real
afferents' noise hides such units, and ``centred`` is the curve to compare
with published data. Each threshold is found on a log-spaced grid, then
refined by bisection in log A; all runs of a round are one mujoco.rollout
batch over threads.

Counting window: at least ``min_cycles`` (20) cycles. The gap between the
two thresholds (the "atonal interval") depends on how many cycles are
counted: a cat foot-pad study (Acta Physiol Scand 1984, 120:321-327, doi
10.1111/j.1748-1716.1984.tb07390.x) measured absolute (1 impulse per train)
and tuning (1 impulse per cycle) thresholds with 100, 400 and 800 ms trains
at 20, 80 and 240 Hz: absolute thresholds did not depend on the duration, RA
and SA tuning thresholds rose with it, so their atonal interval widened with
duration (PC's did not); it widened with frequency for all classes. A window
of fixed duration compares frequencies at different cycle counts (0.2 s is 1
cycle at 5 Hz, 50 at 250 Hz); a minimum count keeps the criteria per cycle
comparable. 20 cycles: the receptor-stage tests' count
(tests/unit/test_afferent_tuning.py), near that study's longest train at its
lowest frequency (800 ms at 20 Hz, 16 cycles), and at the absolute
criterion's 0.1 spike per cycle the 2 extra spikes a tonic unit needs.

Rate-intensity: ramp-and-hold indentations with the same pin: the centred
unit's rate in the hold (SA1) and on the ramps (RA, PC), per class.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from mjtouch import core
from mjtouch._validate import in_range
from mjtouch.analysis import signals
from mjtouch.experiments import stimuli
from mjtouch.scene import scenes

ABSOLUTE_SPIKES_PER_CYCLE = 0.1
LOCK_P = 0.01  # Rayleigh test: phases locked to the sine
UNITS = ("centred", "best")
CLASSES = ("SA1", "RA", "PC")
CRITERIA = ("absolute", "entrainment")

# Published ranges drawn beside ours. Read off the cited figures/text; they
# are ranges across units and studies (order of magnitude), not fits.
# Thresholds: (f_lo, f_hi) Hz -> (A_lo, A_hi) m, for the class's most
# sensitive units in that band. Checked (issue 14): the bands' frequencies
# follow Johansson, Landstrom & Lundstrom 1982's abstract (FA I most easily
# excited at 8-64 Hz, FA II above 64 Hz, SA I and SA II most sensitive at
# lower frequencies; amplitudes tested 1 um-1 mm). The amplitudes could not be
# read from the papers here; TouchSim's fits under this module's protocol
# (1 mm pin, 0.5 mm pre-indentation, its noise on; computed from
# hsaal/touchsim's constants and Sneddon pin mechanics) give RA absolute
# thresholds of 22-57 um at 20 Hz, 14-41 um at 40 Hz, 5.8-26 um at 80 Hz and
# PC 0.04-1.9 um at 250 Hz (median 0.3 um): inside or near the RA and PC
# boxes (RA's box sits up to 2x below TouchSim's units).
PUBLISHED_THRESHOLDS = {
    "SA1": [
        dict(
            band_hz=(5, 20),
            amplitude_m=(10e-6, 100e-6),
            criterion="absolute",
            source="Johansson et al. 1982 (human SA I, most sensitive at low frequencies); "
            "Muniak et al. 2007 (macaque SA1)",
        ),
        dict(
            band_hz=(100, 400),
            amplitude_m=(50e-6, 1e-3),
            criterion="absolute",
            source="Johansson et al. 1982: SA I thresholds rise above ~100 Hz",
        ),
    ],
    "RA": [
        dict(
            band_hz=(20, 80),
            amplitude_m=(2e-6, 30e-6),
            criterion="absolute",
            source="Johansson et al. 1982 (FA I most easily excited at 8-64 Hz); Muniak et "
            "al. 2007; TouchSim's RA fits under this protocol: 14-41 um at 40 Hz",
        )
    ],
    "PC": [
        dict(
            band_hz=(150, 400),
            amplitude_m=(0.02e-6, 1e-6),
            criterion="absolute",
            source="Johansson et al. 1982 (FA II most easily excited above 64 Hz); Muniak "
            "et al. 2007; Saal et al. 2017 (tens of nm to ~0.3 um at 200-300 Hz); "
            "TouchSim's PC fits under this protocol: 0.04-1.9 um at 250 Hz",
        )
    ],
}
# Entrainment over absolute threshold: issue 14 asks > 1.5x for RA and PC.
# TouchSim's fits under this pin (0.5 mm pre-indentation, its noise on, this
# module's criteria; computed from hsaal/touchsim as above): RA 1.1-1.7x at
# 5-20 Hz (median 1.2-1.3x), 3.4-6.3x at 40 Hz, 8-15x at 80 Hz; PC 5-11x at
# 40-80 Hz and >= 13x at 150-400 Hz (some fits never entrain below 0.4 mm).
# Those TouchSim ratios predate min_cycles (5 cycles at 5-10 Hz, 0.2 s above
# 25 Hz) and were not recomputed; ours under both windows are in README.
PUBLISHED_ENTRAINMENT_RATIO = dict(
    RA=(1.5, 10.0), PC=(1.5, 10.0), source="Saal et al. 2017; Muniak et al. 2007"
)
# Rate-intensity under a ramp-and-hold with this pin (1 mm diameter, finger
# still), hold rate of the unit under the probe. The band is TouchSim's
# (Saal et al. 2017) four SA1 fits under the same pin, computed from
# hsaal/touchsim (constants.affparamsSA, transduction.py's Sneddon pin
# mechanics, noise-free, 1 s ramp-and-hold, 50 ms ramps): 22-44 Hz at 0.7 mm,
# 35-61 Hz at 1.0 mm (50-89 Hz at 1.5 mm; thresholds 0.1-0.4 mm). The old
# band (10-100 Hz at 0.5-1 mm, "Knibestol & Vallbo 1980") was wider than any
# number we could check. RA fires on the ramps only, PC on the transients
# only (Johansson & Vallbo 1983; Knibestol 1973, J Physiol 232:427: human RA
# and PC respond to the indentation's velocity, not its hold).
PUBLISHED_RATE_INTENSITY = dict(
    SA1=dict(
        depth_m=(0.7e-3, 1.0e-3),
        hold_rate_hz=(22.0, 61.0),
        source="TouchSim SA1 fits (Saal et al. 2017; hsaal/touchsim constants.affparamsSA) "
        "under a 1 mm pin, noise-free: 22-44 Hz at 0.7 mm, 35-61 Hz at 1.0 mm",
    ),
    RA=dict(
        hold_rate_hz=(0.0, 0.0), source="Johansson & Vallbo 1983; Knibestol 1973 (FA I: ramps only)"
    ),
    PC=dict(
        hold_rate_hz=(0.0, 0.0),
        source="Johansson & Vallbo 1983; Knibestol 1973 (FA II: transients only)",
    ),
)


@dataclasses.dataclass
class TuningConfig:
    freqs_hz: Sequence[float] = (5.0, 10.0, 20.0, 40.0, 80.0, 150.0, 250.0, 400.0, 600.0)
    amp_range_m: tuple[float, float] = (1e-8, 5e-4)
    grid_points: int = 12  # log-spaced amplitudes of the first round
    refine: int = 4  # bisection rounds in log A after the grid: (5e4^(1/11))^(1/16), 6%
    steady_s: float = 0.2  # counting window, s, at least min_cycles cycles
    min_cycles: int = 20  # cycles counted at least (module docstring)
    ramp_s: float = 0.03
    preindent_m: float = 0.5e-3
    pin_radius_m: float = 0.5e-3  # a 1 mm diameter flat probe
    depths_m: Sequence[float] = (0.05e-3, 0.1e-3, 0.2e-3, 0.4e-3, 0.7e-3, 1.0e-3, 1.5e-3)
    hold_s: float = 0.3
    timestep_s: float = 1e-4
    nx: int = 49  # odd: a taxel centre, and so the centred units, on the pin's axis
    pitch_m: float = 1.5e-4
    threads: int = 2

    @classmethod
    def quick(cls) -> TuningConfig:
        """A few seconds: 2 frequencies, a coarse grid, a small skin."""
        return cls(
            freqs_hz=(40.0, 250.0),
            grid_points=6,
            refine=2,
            steady_s=0.06,
            min_cycles=5,
            ramp_s=0.01,
            depths_m=(0.1e-3, 0.4e-3, 1.0e-3),
            hold_s=0.1,
            timestep_s=2e-4,
            nx=25,
            pitch_m=3e-4,
        )

    def validate(self) -> None:
        if not len(self.freqs_hz):
            raise ValueError("freqs_hz must hold at least one frequency")
        for f in self.freqs_hz:
            in_range(
                "freqs_hz",
                f,
                0,
                0.25 / self.timestep_s,
                "Hz (a quarter of the sampling rate)",
                lo_open=True,
            )
        lo, hi = self.amp_range_m
        in_range("amp_range_m[0]", lo, 0, 1e-3, "m", lo_open=True)
        in_range(
            "amp_range_m[1]",
            hi,
            lo,
            min(1e-3, self.preindent_m),
            "m (at most the pre-indentation, so the pin stays in contact)",
            lo_open=True,
        )
        in_range("grid_points", self.grid_points, 2, 100, "")
        in_range("refine", self.refine, 0, 30, "")
        # >= 5: a Rayleigh p < 0.01 needs >= 4-5 locked spikes
        in_range("min_cycles", self.min_cycles, 5, 1000, "cycles")
        for d in self.depths_m:
            in_range("depths_m", d, 0, 3e-3, "m", lo_open=True)


def _responses(
    result: stimuli.StimulusResult, freq_hz: float, cycles: float, base: np.ndarray
) -> dict[str, np.ndarray]:
    """Per criterion, (nrec,) bool: does each receptor meet it in this run?
    base: the unstimulated spike counts in the same window."""
    sp = result.spikes[result.window("steady")]
    count = sp.sum(axis=0)
    extra = count - base
    # locked at f or at 2f: a unit driven by rectified velocity fires on both
    # half-cycles, and its phases then cancel at f
    locked = np.array(
        [
            count[r] > 0
            and min(
                signals.vector_strength_counts(sp[:, r], result.dt_s, h * freq_hz).p_value
                for h in (1, 2)
            )
            < LOCK_P
            for r in range(sp.shape[1])
        ]
    )
    least = ABSOLUTE_SPIKES_PER_CYCLE * cycles
    return dict(
        absolute=(extra >= max(2.0, least)) | (locked & (count >= max(1.0, least))),
        entrainment=(extra >= cycles) | (locked & (count >= cycles)),
    )


def threshold_curves(cfg: TuningConfig, scene: stimuli.ProbeScene) -> dict:
    """Absolute and entrainment thresholds (m) per class, unit and frequency,
    and the grid's rates (vibratory rate-intensity)."""
    freqs = [float(f) for f in cfg.freqs_hz]
    grid = np.geomspace(*cfg.amp_range_m, cfg.grid_points)
    classes = scene.layout.classes

    def steady(f):
        return max(cfg.steady_s, cfg.min_cycles / f)

    def wave(a, f):
        return stimuli.sine(a, f, duration_s=2 * cfg.ramp_s + steady(f), ramp_s=cfg.ramp_s)

    # round 0: the grid (and amplitude 0: the unstimulated counts)
    runs = [(f, a) for f in freqs for a in [0.0, *grid]]
    res = scene.run([wave(a, f) for f, a in runs], threads=cfg.threads)
    base = {f: r.spikes[r.window("steady")].sum(axis=0) for (f, a), r in zip(runs, res) if a == 0.0}
    cen = res[0].centred_units()
    unit_of = {c: dict(centred=np.arange(classes.size) == cen[c], best=classes == c) for c in cen}
    meets = {}
    rates = {c: {str(f): [] for f in freqs} for c in cen}
    for (f, a), r in zip(runs, res):
        if a > 0:
            meets[(f, a)] = _responses(r, f, steady(f) * f, base[f])
            w = r.window("steady")
            for c in cen:
                n = r.spikes[w][:, cen[c]].sum()
                rates[c][str(f)].append(float(n / ((w.stop - w.start) * scene.dt_s)))

    def hit(c, unit, crit, f, m):
        return bool(np.any(m[crit] & unit_of[c][unit]))

    # bracket each (class, unit, criterion, frequency) on the grid
    tasks = {}
    for c in cen:
        for unit in UNITS:
            for crit in CRITERIA:
                for f in freqs:
                    ok = [a for a in grid if hit(c, unit, crit, f, meets[(f, a)])]
                    if not ok:
                        tasks[(c, unit, crit, f)] = (None, math.inf)  # above the range
                    elif ok[0] == grid[0]:
                        tasks[(c, unit, crit, f)] = (None, grid[0])  # at the range's floor
                    else:
                        k = int(np.nonzero(grid == ok[0])[0][0])
                        tasks[(c, unit, crit, f)] = (grid[k - 1], grid[k])
    # bisection in log A, every open bracket of a round in one batch; brackets
    # that share (f, A) (often centred and best, or two classes) share a run
    for _ in range(cfg.refine):
        open_ = [(k, math.sqrt(lo * hi)) for k, (lo, hi) in tasks.items() if lo is not None]
        if not open_:
            break
        todo = sorted({(k[3], mid) for k, mid in open_})
        res = scene.run([wave(mid, f) for f, mid in todo], threads=cfg.threads)
        meets_mid = {
            (f, mid): _responses(r, f, steady(f) * f, base[f]) for (f, mid), r in zip(todo, res)
        }
        for k, mid in open_:
            c, unit, crit, f = k
            lo, hi = tasks[k]
            tasks[k] = (lo, mid) if hit(c, unit, crit, f, meets_mid[(f, mid)]) else (mid, hi)
    thresholds = {
        c: {
            unit: {crit: [tasks[(c, unit, crit, f)][1] for f in freqs] for crit in CRITERIA}
            for unit in UNITS
        }
        for c in cen
    }
    return dict(
        freqs_hz=freqs,
        thresholds_m=thresholds,
        grid_m=grid.tolist(),
        grid_rates_centred_hz=rates,
        centred_offaxis_m=res[0].centred_offaxis_m(),
        floor_m=cfg.amp_range_m[0],
        precision=float((grid[1] / grid[0]) ** (0.5**cfg.refine)),
    )


def rate_intensity(cfg: TuningConfig, scene: stimuli.ProbeScene) -> dict:
    """Ramp-and-hold indentations from first touch: per class, the centred
    unit's rate on the ramps (on + off) and in the hold's last 80%."""
    ramp = 0.05 if cfg.hold_s > 0.15 else 0.02
    waves = [
        stimuli.ramp_and_hold(d, ramp_s=ramp, hold_s=cfg.hold_s, rest_s=0.05) for d in cfg.depths_m
    ]
    res = scene.run(waves, threads=cfg.threads)
    out = {c: dict(hold_hz=[], ramp_hz=[]) for c in CLASSES}
    dt = scene.dt_s
    for r in res:
        cen = r.centred_units()
        n_ramp = int(round(ramp / dt))
        n_hold = int(round(cfg.hold_s / dt))
        hold = slice(n_ramp + int(0.2 * n_hold), n_ramp + n_hold)
        ramps = np.r_[0:n_ramp, n_ramp + n_hold : 2 * n_ramp + n_hold]
        for c in CLASSES:
            if c in cen:
                u = cen[c]
                out[c]["hold_hz"].append(
                    float(r.spikes[hold, u].sum() / ((hold.stop - hold.start) * dt))
                )
                out[c]["ramp_hz"].append(float(r.spikes[ramps, u].sum() / (ramps.size * dt)))
    return dict(
        depths_m=[float(d) for d in cfg.depths_m],
        ramp_s=ramp,
        hold_s=cfg.hold_s,
        rates=out,
        centred_offaxis_m=res[0].centred_offaxis_m(),
    )


def _vibration_scene(cfg: TuningConfig) -> stimuli.ProbeScene:
    tip = scenes.Fingertip(nx=int(cfg.nx), pitch_m=cfg.pitch_m, ridges=False)
    return stimuli.ProbeScene(
        stimuli.Probe("pin", radius_m=cfg.pin_radius_m),
        tip,
        preindent_m=cfg.preindent_m,
        settle_s=0.1,
        timestep_s=cfg.timestep_s,
    )


def pin_sine_stress(
    cfg: TuningConfig,
    freqs_hz: Sequence[float],
    amplitudes_m: Sequence[float] = (0.0, 10e-6),
    threads: int = 2,
) -> dict:
    """Per frequency, the receptor stress of :func:`run`'s pin under sines of
    ``amplitudes_m`` (the first 0), with the counting window, its cycles, the
    centred units and dt: input of :func:`atonal_ratio`."""
    scene = _vibration_scene(cfg)
    out = {}
    for f in freqs_hz:
        steady = max(cfg.steady_s, cfg.min_cycles / f)
        res = scene.run(
            [
                stimuli.sine(a, f, duration_s=2 * cfg.ramp_s + steady, ramp_s=cfg.ramp_s)
                for a in amplitudes_m
            ],
            threads=threads,
        )
        out[float(f)] = dict(
            stress=[r.stress for r in res],
            amplitudes_m=list(amplitudes_m),
            window=res[0].window("steady"),
            cycles=steady * f,
            units=res[0].centred_units(),
            dt_s=res[0].dt_s,
        )
    return out


def atonal_ratio(
    run: dict, cls: str, seed: int = 0, scale_range=(1e-4, 20.0), iters: int = 14
) -> float:
    """Entrainment over absolute threshold of the centred ``cls`` unit of one
    :func:`pin_sine_stress` entry, with this module's count criteria, by
    bisection on s in q0 + s (q1 - q0) (the stress is linear in amplitude;
    tests/science/test_tuning.py checks it) through core.receptor_run with
    the plugin's default attributes, ``seed`` (noise path and population
    variant) and the unit's stream. RA and PC are silent under the static
    pre-indentation, so the phase-lock alternatives add nothing. inf: no 1:1
    within ``scale_range``; nan: no response at all."""
    u = run["units"][cls]
    q0, q1 = run["stress"][0][:, u], run["stress"][1][:, u]
    w, cycles, cfg = run["window"], run["cycles"], {"seed": str(int(seed))}
    rest = core.receptor_run(cls, q0, run["dt_s"], cfg, stream=u)[0][w].sum()

    def extra(s):  # stimulated minus unstimulated spikes in the window
        return (
            core.receptor_run(cls, q0 + s * (q1 - q0), run["dt_s"], cfg, stream=u)[0][w].sum()
            - rest
        )

    def threshold(need):
        lo, hi = scale_range
        if extra(hi) < need:
            return math.inf
        for _ in range(iters):
            mid = math.sqrt(lo * hi)
            lo, hi = (lo, mid) if extra(mid) >= need else (mid, hi)
        return hi

    a = threshold(max(2.0, ABSOLUTE_SPIKES_PER_CYCLE * cycles))
    return math.nan if math.isinf(a) else threshold(cycles) / a


def run(cfg: TuningConfig | None = None) -> dict:
    """Both measurements on one probe scene; a JSON-ready dict."""
    cfg = cfg or TuningConfig()
    cfg.validate()
    vib = _vibration_scene(cfg)
    touch = stimuli.ProbeScene(
        vib.probe, vib.tip, preindent_m=0.0, settle_s=0.0, timestep_s=cfg.timestep_s
    )
    return dict(
        config={
            k: (list(v) if isinstance(v, (tuple, list)) else v)
            for k, v in dataclasses.asdict(cfg).items()
        },
        definitions=dict(
            absolute=f">= max(2, {ABSOLUTE_SPIKES_PER_CYCLE}/cycle) spikes more "
            "than unstimulated in the steady window, or >= max(1, "
            f"{ABSOLUTE_SPIKES_PER_CYCLE}/cycle) spikes phase-locked at "
            f"f or 2f (Rayleigh p < {LOCK_P})",
            window=f"the sine's steady part: max(steady_s, min_cycles / f) = "
            f"max({cfg.steady_s}, {cfg.min_cycles} / f) s",
            entrainment=">= 1 spike per cycle more than unstimulated, or >= 1 "
            "phase-locked spike per cycle",
            centred="the unit of the class on the probe's axis (stimuli."
            "ProbeScene's axis_units; its distance in thresholds."
            "centred_offaxis_m)",
            best="the class's most sensitive unit",
        ),
        receptors={c: int((vib.layout.classes == c).sum()) for c in CLASSES},
        thresholds=threshold_curves(cfg, vib),
        rate_intensity=rate_intensity(cfg, touch),
        published=dict(
            thresholds=PUBLISHED_THRESHOLDS,
            entrainment_ratio=PUBLISHED_ENTRAINMENT_RATIO,
            rate_intensity=PUBLISHED_RATE_INTENSITY,
        ),
    )


def plot(result: dict, path: str) -> None:
    """Threshold-frequency (left) and rate-intensity (right) with the
    published ranges as shaded boxes."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("--plot needs matplotlib: pip install 'mjtouch[plot]'") from None
    colors = dict(SA1="tab:blue", RA="tab:orange", PC="tab:green")
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    th = result["thresholds"]
    f = np.array(th["freqs_hz"])
    for c in CLASSES:
        for crit, ls in (("absolute", "-o"), ("entrainment", "--s")):
            y = np.array(
                [
                    np.nan if not np.isfinite(v) else v * 1e6
                    for v in th["thresholds_m"][c]["centred"][crit]
                ]
            )
            a.loglog(f, y, ls, c=colors[c], ms=4, label=f"{c} {crit}")
        for box in result["published"]["thresholds"].get(c, []):
            (f0, f1), (y0, y1) = box["band_hz"], box["amplitude_m"]
            a.fill_between([f0, f1], y0 * 1e6, y1 * 1e6, color=colors[c], alpha=0.15, lw=0)
    a.set_xlabel("frequency (Hz)")
    a.set_ylabel("threshold amplitude (um)")
    a.set_title("threshold-frequency (shaded: published ranges)")
    a.legend(fontsize=7)
    ri = result["rate_intensity"]
    d = np.array(ri["depths_m"]) * 1e3
    for c in CLASSES:
        r = ri["rates"][c]
        if r["hold_hz"]:
            b.plot(d, r["hold_hz"], "-o", c=colors[c], label=f"{c} hold")
            b.plot(d, r["ramp_hz"], ":^", c=colors[c], label=f"{c} ramps")
    pub = result["published"]["rate_intensity"]["SA1"]
    b.fill_between(
        np.array(pub["depth_m"]) * 1e3, *pub["hold_rate_hz"], color=colors["SA1"], alpha=0.15, lw=0
    )
    b.set_xlabel("indentation (mm)")
    b.set_ylabel("rate of the centred unit (Hz)")
    b.set_title("rate-intensity, ramp-and-hold pin")
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


# --- the same pin as TouchSim's reference (tests/data/touchsim_reference.json) -------------

# TouchSim's protocol (examples/touchsim_reference.py): a 1 mm flat pin, 1 s
# stimuli with 50 ms ramps, whole-second counts, noise off and the median
# parameter set, one receptor per class on the pin's axis (a taxel centre
# of the odd grid) at mjtouch's depths.
PIN_SITES = "SA1 0 0 7.5e-4; RA 0 0 7.5e-4; PC 0 0 2e-3"
PIN_AFFERENTS = {"noise": "0 0 0", "population": "uniform"}


def pin_reference_stress(
    depths_m: Sequence[float],
    freqs_hz: Sequence[float],
    duration_s: float = 1.0,
    ramp_s: float = 0.05,
    preindent_m: float = 0.5e-3,
    ref_m: float = 10e-6,
    timestep_s: float = 1e-4,
    nx: int = 49,
    pitch_m: float = 1.5e-4,
    threads: int = 2,
) -> dict:
    """Receptor stress (Pa, one column per class) under the 1 mm pin:
    ramp-and-holds to each depth from first touch (``duration_s`` in all,
    ``ramp_s`` ramps), and per frequency a sine of 0 and of ``ref_m`` about
    ``preindent_m`` (the stress is linear in the amplitude:
    tests/science/test_tuning.py). Input of :func:`pin_reference_table`."""
    tip = scenes.Fingertip(nx=int(nx), pitch_m=pitch_m, ridges=False)
    skin = dict(PIN_AFFERENTS, sites=PIN_SITES)
    pin = stimuli.Probe("pin", radius_m=0.5e-3)
    touch = stimuli.ProbeScene(
        pin, tip, preindent_m=0.0, settle_s=0.0, timestep_s=timestep_s, skin=skin
    )
    hold = duration_s - 2 * ramp_s
    ramps = touch.run(
        [stimuli.ramp_and_hold(d, ramp_s=ramp_s, hold_s=hold, rest_s=0.0) for d in depths_m],
        threads=threads,
    )
    vib = stimuli.ProbeScene(
        pin, tip, preindent_m=preindent_m, settle_s=0.1, timestep_s=timestep_s, skin=skin
    )
    # TouchSim's sines: linear ramps (its apply_ramp), sampled at every step
    t = np.arange(int(round(duration_s / timestep_s)) + 1) * timestep_s
    env = np.clip(np.minimum(t, duration_s - t) / ramp_s, 0, 1)
    waves = [
        stimuli.trace(a * env * np.sin(2 * np.pi * f * t), timestep_s)
        for f in freqs_hz
        for a in (0.0, ref_m)
    ]
    sines = vib.run(waves, threads=threads)
    classes = list(touch.layout.classes)
    offaxis = np.hypot(*touch.layout.positions_m[:, :2].T)
    return dict(
        classes=classes,
        offaxis_m=offaxis.tolist(),
        dt_s=touch.dt_s,
        depths_m=[float(d) for d in depths_m],
        freqs_hz=[float(f) for f in freqs_hz],
        preindent_m=preindent_m,
        ref_m=ref_m,
        ramp=[r.stress for r in ramps],
        sine={
            float(f): (sines[2 * i].stress, sines[2 * i + 1].stress) for i, f in enumerate(freqs_hz)
        },
    )


def pin_reference_table(
    stress: dict, afferents: dict | None = None, scale_range=(1e-4, 45.0), iters: int = 24
) -> dict:
    """From :func:`pin_reference_stress`, TouchSim's table for our receptors:
    whole-stimulus rates (Hz) of the ramp-and-holds, the stress mid-hold
    (kPa), and per frequency the absolute (>= 1 spike more than the
    pre-indentation alone) and entrainment (>= 0.9 f spikes/s more)
    thresholds (um; inf: not within ``scale_range`` x ``ref_m``, by default
    1 nm-0.45 mm as TouchSim's reference searched), by
    bisection on the sine's stress change through core.receptor_run with
    :data:`PIN_AFFERENTS` updated by ``afferents``."""
    cfg = dict(PIN_AFFERENTS, **(afferents or {}))
    dt = stress["dt_s"]
    out = {}
    for r, c in enumerate(stress["classes"]):

        def count(q, c=c, r=r):
            return int(core.receptor_run(c, q, dt, cfg, stream=r)[0].sum())

        rates, kpa = [], []
        for q in stress["ramp"]:
            rates.append(count(q[:, r]) / (q.shape[0] * dt))
            kpa.append(float(q[q.shape[0] // 2, r]) / 1e3)
        thr = dict(absolute_um=[], entrainment_um=[])
        for f, (q0, q1) in stress["sine"].items():
            q0, dq = q0[:, r], q1[:, r] - q0[:, r]
            rest = count(q0)
            dur = q0.size * dt
            for key, need in (("absolute_um", rest + 1), ("entrainment_um", rest + 0.9 * f * dur)):
                lo, hi = scale_range
                if count(q0 + hi * dq) < need:
                    thr[key].append(math.inf)
                    continue
                for _ in range(iters):
                    mid = math.sqrt(lo * hi)
                    lo, hi = (lo, mid) if count(q0 + mid * dq) >= need else (mid, hi)
                thr[key].append(hi * stress["ref_m"] * 1e6)
        out[c] = dict(
            rates_hz=rates, stress_kpa=kpa, offaxis_m=stress["offaxis_m"][r], dt_s=dt, **thr
        )
    return out


def _wave_amplitude(dq: np.ndarray) -> float:
    """Peak |dq| over the middle 60% of a sine trace (clear of its ramps)."""
    n = dq.size
    return float(np.abs(dq[int(0.2 * n) : int(0.8 * n)]).max())


def pin_sine_gain(stress: dict) -> dict:
    """Per class, our receptor's stress amplitude per metre of pin sine about
    the pre-indentation (Pa/m), one value per frequency of ``stress``."""
    out = {}
    for r, c in enumerate(stress["classes"]):
        out[c] = [
            _wave_amplitude(q1[:, r] - q0[:, r]) / stress["ref_m"]
            for q0, q1 in stress["sine"].values()
        ]
    return out


def pin_reference_rescaled(
    stress: dict, ramp_pa: dict, preindent_pa: dict, sine_pa_per_m: dict
) -> dict:
    """``stress`` (:func:`pin_reference_stress`) with each class's traces
    scaled to another mechanics' stress at the receptor, keeping our time
    course: the k-th ramp so that its mid-hold is ``ramp_pa[c][k]``, the
    sines' pre-indentation so that it is ``preindent_pa[c]`` mid-trace and
    their wave so that its amplitude is ``sine_pa_per_m[c]`` per metre of
    the pin's sine. Input of :func:`pin_reference_table`: our afferent
    model under those mechanics."""
    out = dict(stress)
    ramps = [q.copy() for q in stress["ramp"]]
    sines = {f: (q0.copy(), q1.copy()) for f, (q0, q1) in stress["sine"].items()}
    for r, c in enumerate(stress["classes"]):
        for k, q in enumerate(ramps):
            q[:, r] *= ramp_pa[c][k] / q[q.shape[0] // 2, r]
        for q0, q1 in sines.values():
            dq = q1[:, r] - q0[:, r]
            dq *= sine_pa_per_m[c] * stress["ref_m"] / _wave_amplitude(dq)
            q0[:, r] *= preindent_pa[c] / q0[q0.shape[0] // 2, r]
            q1[:, r] = q0[:, r] + dq
    out["ramp"], out["sine"] = ramps, sines
    return out
