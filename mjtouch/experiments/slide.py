"""The slide experiment: a ridged fingertip pressed on a textured plate and slid.

:class:`SlideParams` is the one description of a slide: every option, with its
type, default, units, help text and valid range in the field's metadata. The
command line (``mjtouch slide``) builds its options from these fields, the
sweep (:mod:`mjtouch.experiments.sweep`) sweeps them and names its Parquet
columns after them, and :func:`run` runs one::

    from mjtouch.experiments import slide
    out = slide.run(slide.SlideParams(texture="random", speed_m_s=0.05))
    out.summary["rates_hz"], out.result.spikes
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from mjtouch import _validate, progress
from mjtouch.analysis import signals
from mjtouch.experiments import rollout
from mjtouch.scene import meshes, scenes

# Shortest slide: rollout.SETTLE_S settling plus 0.05 s analysed (a 20 Hz FFT bin).
MIN_DURATION_S = 0.15
# A field name ends in its units; the option drops them (speed_m_s -> --speed).
UNIT_SUFFIXES = ("_m_s", "_m", "_n", "_s")
INF = math.inf


def _field(
    default: Any,
    kind: str,
    doc: str,
    *,
    units: str = "",
    bounds: tuple[float, float] | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
    choices: tuple | None = None,
    metavar: str | None = None,
):
    """A SlideParams field: kind is how it parses (float, int, bool, str), doc its
    help text, bounds its valid range (ends closed unless lo_open / hi_open)."""
    meta = {
        "kind": kind,
        "help": doc,
        "units": units,
        "range": bounds,
        "lo_open": lo_open,
        "hi_open": hi_open,
        "choices": choices,
        "metavar": metavar,
    }
    return dataclasses.field(default=default, metadata=meta)


def _positive(default: float | None, doc: str, units: str):
    return _field(default, "float", doc, units=units, bounds=(0.0, INF), lo_open=True, hi_open=True)


@dataclasses.dataclass(frozen=True)
class SlideParams:
    """Every option of a slide. Field names carry units and are the sweep's
    Parquet columns; the command-line option is the name without its units
    (:func:`flag`). Invalid values raise ``ValueError`` naming the field and
    its valid range."""

    texture: str = _field(
        "grating",
        "str",
        "plate texture (flat: none)",
        choices=("grating", "random", "dots", "flat"),
    )
    period_m: float | None = _positive(
        None,
        "texture spatial period D; default 1e-3; with --texture-mesh: the mesh's period, "
        "to report peaks against V/D",
        "m",
    )
    plateau_m: float | None = _positive(None, "grating plateau width; default period/2", "m")
    height_m: float = _positive(0.1e-3, "grating height", "m")
    rms_m: float = _positive(20e-6, "random texture: RMS height", "m")
    corr_length_m: float = _positive(60e-6, "random texture: Gaussian correlation length", "m")
    dot_spacing_m: float = _positive(2.5e-3, "dots texture: hexagonal lattice spacing", "m")
    dot_radius_m: float = _positive(0.6e-3, "dots texture: dot base radius", "m")
    speed_m_s: float = _field(
        0.025, "float", "sliding speed V", units="m/s", bounds=(0.0, 2.0), lo_open=True
    )
    force_n: float = _field(
        0.5, "float", "normal force", units="N", bounds=(0.0, 100.0), lo_open=True
    )
    ridges: bool = _field(True, "bool", "fingerprint ridges on the skin")
    ridge_pitch_m: float = _positive(0.45e-3, "ridge pitch lambda", "m")
    duration_s: float = _field(
        1.0,
        "float",
        "sliding time (the first 0.1 s settle and are not analysed)",
        units="s",
        bounds=(MIN_DURATION_S, INF),
        hi_open=True,
    )
    dt_s: float = _field(1e-4, "float", "simulation timestep", units="s", bounds=(1e-6, 5e-3))
    nx: int = _field(128, "int", "taxels per side", bounds=(4, 512))
    pitch_m: float = _positive(1e-4, "taxel pitch", "m")
    seed: int = _field(
        0,
        "int",
        "seed of the random texture (the pipeline itself is deterministic)",
        bounds=(0, 2**32 - 1),
    )
    pressure: str = _field(
        "elastic",
        "str",
        "pressure model (elastic: the skin's own compliance, which lets the "
        "ridges carry the load in partial contact; winkler: a foundation, faster, presses the "
        "ridges flat; contacts: MuJoCo's contact points)",
        choices=("winkler", "elastic", "contacts"),
    )
    grid_shift: bool = _field(
        False,
        "bool",
        "elastic: also solve on the half-cell shifted grid and average (skin "
        "attribute grid_shift; cancels the V/pitch grid line that PC rates pick up, ~1.8x the "
        "step)",
    )
    grid_cycle: int = _field(
        4,
        "int",
        "elastic: solve each step on one of this many sub-cell offset grids in turn and "
        "average the last ones (skin attribute grid_cycle; keeps the texture's sub-cell "
        "position from locking to the grid; 1: the taxel grid alone)",
        bounds=(1, 4),
    )
    texture_mesh: str | None = _field(
        None,
        "str",
        "texture from a mesh file's top surface (STL, OBJ, PLY, GLB; trimesh), "
        "sliding along the mesh's x after placement; overrides --texture",
        metavar="FILE",
    )
    mesh_scale: float = _positive(1.0, "mesh units to m (1e-3 for a file in mm)", "")
    mesh_up: str = _field(
        "+z",
        "str",
        "mesh axis out of the textured face",
        choices=("+z", "-z", "+x", "-x", "+y", "-y"),
    )
    mesh_rotate: float = _field(
        0.0,
        "float",
        "turn the mesh about the up axis",
        units="deg",
        bounds=(-INF, INF),
        lo_open=True,
        hi_open=True,
    )
    mesh_resolution: float = _positive(2e-5, "height-field cell of the mesh texture", "m")

    def __post_init__(self):
        for f in dataclasses.fields(self):
            check(f.name, getattr(self, f.name))
        if self.grid_shift and self.pressure != "elastic":
            raise ValueError(
                f"grid_shift (--grid-shift) needs pressure 'elastic' "
                f"(--pressure elastic), got {self.pressure!r}"
            )

    @property
    def effective_period_m(self) -> float | None:
        """period_m, or 1e-3 for a generated texture when unset."""
        if self.period_m is None and not self.texture_mesh:
            return 1.0e-3
        return self.period_m

    def fingertip(self) -> scenes.Fingertip:
        skin = {"pressure": self.pressure}
        if self.grid_shift:
            skin["grid_shift"] = "true"
        skin["grid_cycle"] = str(self.grid_cycle)
        return scenes.Fingertip(
            ridges=self.ridges,
            ridge_pitch_m=self.ridge_pitch_m,
            nx=self.nx,
            pitch_m=self.pitch_m,
            skin=skin,
        )

    def protocol(self) -> scenes.Protocol:
        return scenes.Protocol(force_n=self.force_n, speed_m_s=self.speed_m_s, timestep_s=self.dt_s)

    def plate_length_m(self) -> float:
        """The plate holds the whole slide with margin for the contact patch."""
        return 2 * (self.speed_m_s * self.duration_s) + 0.02

    def texture_spec(self) -> tuple[scenes.Texture, float | None, str]:
        """(texture, its period along the slide or None, its kind label)."""
        need = self.plate_length_m()
        if self.texture_mesh:
            mt = meshes.from_mesh(
                self.texture_mesh,
                scale=self.mesh_scale,
                up=self.mesh_up,
                rotate_deg=self.mesh_rotate,
                resolution_m=self.mesh_resolution,
            )
            if mt.length_m < need:
                raise ValueError(
                    f"--texture-mesh {self.texture_mesh}: its top surface is "
                    f"{mt.length_m * 1e3:.3g} mm long after --mesh-scale {self.mesh_scale:g}; "
                    f"sliding {self.duration_s:g} s at {self.speed_m_s:g} m/s needs "
                    f"{need * 1e3:.3g} mm (the slide and the pad, both ways): shorten "
                    "--duration or slow --speed"
                )
            return mt.texture(), self.period_m, "mesh"
        period = self.effective_period_m
        texture = scenes.Texture(
            kind=self.texture,
            period_m=period,
            plateau_m=self.plateau_m,
            height_m=self.height_m,
            rms_m=self.rms_m,
            corr_length_m=self.corr_length_m,
            dot_spacing_m=self.dot_spacing_m,
            dot_radius_m=self.dot_radius_m,
            seed=self.seed,
        )
        # 2D textures are sized to the slide to keep the height field small
        if self.texture in ("random", "dots"):
            texture.length_m, texture.width_m = need, 0.016
        else:
            texture.length_m = max(texture.length_m, need)
        periodic = {"grating": period, "dots": self.dot_spacing_m}.get(self.texture)
        return texture, periodic, self.texture


def fields() -> tuple[dataclasses.Field, ...]:
    """SlideParams' fields, in order."""
    return dataclasses.fields(SlideParams)


def field(name: str) -> dataclasses.Field:
    for f in fields():
        if f.name == name:
            return f
    raise KeyError(name)


def flag(f: dataclasses.Field | str) -> str:
    """The command-line option of a field: its name without the units suffix,
    dashed (``ridge_pitch_m`` -> ``--ridge-pitch``)."""
    name = f if isinstance(f, str) else f.name
    for suffix in UNIT_SUFFIXES:
        if name.endswith(suffix):
            name = name[: -len(suffix)]
            break
    return "--" + name.replace("_", "-")


def describe(f: dataclasses.Field) -> str:
    """Help text of a field: its help, units, default and valid range."""
    m = f.metadata
    units = f" ({m['units']})" if m["units"] else ""
    parts = [m["help"] + units]
    if m["range"] is not None and m["range"] != (0.0, INF):
        lo, hi = m["range"]
        parts.append(
            f"valid {'(' if m['lo_open'] else '['}{lo:g}, {hi:g}{')' if m['hi_open'] else ']'}"
        )
    if f.default is not None and m["kind"] != "bool":
        parts.append(
            f"default {f.default:g}" if isinstance(f.default, float) else f"default {f.default}"
        )
    elif m["kind"] == "bool":
        parts.append(f"default {'on' if f.default else 'off'}")
    return ", ".join(parts)


def check(name: str, value: Any, label: str | None = None) -> Any:
    """value if valid for field ``name``; else ValueError naming ``label``
    (default: the field name) with the valid range."""
    f = field(name)
    m, label = f.metadata, label or name
    if value is None and f.default is None:
        return value
    kind = m["kind"]
    if kind == "bool":
        if not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"{label} = {value!r} must be true or false")
        return bool(value)
    if kind == "str":
        if m["choices"] is not None:
            return _validate.choice(label, value, m["choices"])
        if not isinstance(value, (str, os.PathLike)):
            raise ValueError(f"{label} = {value!r} must be a string")
        return value
    lo, hi = m["range"]
    if kind == "int":
        return _validate.integer_in_range(label, value, lo, hi)
    return _validate.in_range(
        label, value, lo, hi, m["units"], lo_open=m["lo_open"], hi_open=m["hi_open"]
    )


def parse(name: str, token: str, label: str | None = None) -> Any:
    """A command-line / TOML token as field ``name``'s value, checked."""
    f = field(name)
    kind, label = f.metadata["kind"], label or flag(f)
    if kind == "bool":
        low = token.lower()
        if low in ("true", "on", "yes", "1"):
            return True
        if low in ("false", "off", "no", "0"):
            return False
        raise ValueError(f"{label} {token!r} is not a boolean; valid: true/false, on/off")
    if kind in ("int", "float"):
        try:
            value = int(token) if kind == "int" else float(token)
        except ValueError:
            what = "an integer" if kind == "int" else "a number"
            raise ValueError(f"{label} {token!r} is not {what}") from None
        return check(name, value, label)
    return check(name, token, label)


@dataclasses.dataclass
class SlideRun:
    """What :func:`run` returns: the summary (rates, spectral peaks, expected
    lines; JSON-ready) and the rollout (spikes, stress, force per step)."""

    params: SlideParams
    summary: dict
    result: rollout.SlideResult


def run(params: SlideParams, *, progress_bar: bool = False) -> SlideRun:
    """Run one slide: press, slide, and analyse the steady part."""
    tip = params.fingertip()
    texture, periodic, kind = params.texture_spec()
    protocol = params.protocol()
    t0 = time.perf_counter()
    # the step count scenes.controls will make
    nstep = round(protocol.press_s / params.dt_s) + round(params.duration_s / params.dt_s)
    with progress.Progress(nstep, progress_bar, desc="slide", unit="step") as bar:
        res = rollout.run_slide(
            tip,
            texture,
            protocol,
            duration_s=params.duration_s,
            progress=bar.update if bar.enabled else None,
        )
    wall = time.perf_counter() - t0
    return SlideRun(params, summarize(params, res, periodic, kind, wall), res)


# grid_cycle's longest cycle, s (plugin/core/pipeline/elastic/grid_cycle.h)
MAX_CYCLE_PERIOD_S = 0.5e-3


def cycling_grids(p: SlideParams) -> int:
    """How many of `grid_cycle`'s offset grids the plugin cycles at the
    slide's timestep: the largest divisor of grid_cycle whose cycle lasts at
    most MAX_CYCLE_PERIOD_S (the plugin's CycleLength). The plugin counts
    evaluations, so where it oversamples a long timestep more grids cycle
    than this says: it errs towards reporting the grid line."""
    n = p.grid_cycle
    length = n
    while length > 1 and (n % length or length * p.dt_s > MAX_CYCLE_PERIOD_S * (1 + 1e-9)):
        length -= 1
    return length


def summarize(
    params: SlideParams, res: rollout.SlideResult, periodic: float | None, kind: str, wall_s: float
) -> dict:
    """Rates and spectra over the steady window (SlideResult.window leaves out
    the first rollout.SETTLE_S of sliding)."""
    w = res.window()
    dt = res.dt
    p = params
    rates = signals.rates_hz(res.spikes[w], dt, res.layout.classes)
    f, power = signals.stress_spectrum(res.stress[w], dt)
    peaks = signals.spectral_peaks(f, power, n=6, fmin_hz=5.0, fmax_hz=min(1000.0, 0.5 / dt))
    expected = {
        "texture": p.speed_m_s / periodic if periodic else None,
        "ridges": p.speed_m_s / p.ridge_pitch_m if p.ridges else None,
    }
    power_expected = {
        k: (signals.power_at(f, power, v) if v else None) for k, v in expected.items()
    }
    # at V/lambda of the configured ridge pitch for smooth skin too, so ridged
    # and smooth runs compare
    power_expected["ridges"] = signals.power_at(f, power, p.speed_m_s / p.ridge_pitch_m)
    # A periodic texture's stress repeats every D/V: its lines are V/D
    # harmonics whatever the ridges do, so a V/lambda line is expected only
    # on aperiodic (broadband) textures, which the ridges band-pass.
    ridge_line_expected = bool(p.ridges and not periodic)
    nearest = {
        k: (min(peaks, key=lambda x, v=v: abs(x - v)) if v and len(peaks) else None)
        for k, v in expected.items()
    }
    # Each expected line judged in its own band (V/lambda of the configured
    # pitch for smooth skin too, so ridged and smooth runs compare): a line
    # weaker than the six strongest peaks still shows there.
    fmax = min(1000.0, 0.5 / dt)
    line_at = {"texture": expected["texture"], "ridges": p.speed_m_s / p.ridge_pitch_m}
    lines = {
        k: (dataclasses.asdict(signals.band_line(f, power, v)) if v and v < fmax else None)
        for k, v in line_at.items()
    }
    fn = res.force[w, 0]
    return {
        "rates_hz": rates,
        "peaks_hz": peaks,
        "expected_hz": expected,
        "nearest_peak_hz": nearest,
        "lines": lines,
        "ridge_line_expected": ridge_line_expected,
        # the elastic contact on one grid misplaces texture edges sharper
        # than a cell: a stress line at V / pitch unless grid_shift or
        # cycling offset grids cancel it (docs, Performance;
        # examples/pc_grid_line.py)
        "grid_line_hz": (
            p.speed_m_s / p.pitch_m
            if p.pressure == "elastic" and not p.grid_shift and cycling_grids(p) == 1
            else None
        ),
        "grid_shift": p.grid_shift,
        # offset grids the elastic contact cycles at this timestep (1: the
        # taxel grid alone; 0 without the elastic contact or with grid_shift)
        "grids_cycled": (cycling_grids(p) if p.pressure == "elastic" and not p.grid_shift else 0),
        "power_at_expected": power_expected,
        "speed_m_s": p.speed_m_s,
        "period_m": periodic,
        "ridge_pitch_m": p.ridge_pitch_m,
        "ridges": p.ridges,
        "texture": kind,
        "pressure": p.pressure,
        "force_n": p.force_n,
        "duration_s": p.duration_s,
        "dt_s": dt,
        "fft_bin_hz": float(f[1] - f[0]),
        "normal_force_mean_n": float(fn.mean()),
        "receptors": {c: int((res.layout.classes == c).sum()) for c in ("SA1", "RA", "PC")},
        "wall_s": wall_s,
        "seed": p.seed,
    }


def from_mapping(values: Mapping[str, Any]) -> SlideParams:
    """SlideParams from {field name: value}, unknown names an error."""
    names = {f.name for f in fields()}
    unknown = sorted(set(values) - names)
    if unknown:
        raise ValueError(
            f"unknown slide parameter(s) {', '.join(unknown)}; valid: "
            f"{', '.join(f.name for f in fields())}"
        )
    return SlideParams(**values)


def plot(path: str, out: SlideRun) -> None:
    """A PNG of the stress spectrum (expected lines marked) and the raster."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError("plotting needs matplotlib: pip install 'mjtouch[plot]'") from None
    res = out.result
    w = res.window()
    f, p = signals.stress_spectrum(res.stress[w], res.dt)
    expected = out.summary["expected_hz"]
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
    plt.close(fig)
