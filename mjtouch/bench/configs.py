"""Benchmark settings: knobs and their settings, presets, the receptor site
lattice, BenchConfig and how an override dict becomes a scene."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from mjtouch.scene import scenes

EXTENT_M = 12.8e-3  # skin grid side kept by the pitch sweep (default: 128 x 0.1 mm)
SITE_SPACING_M = 0.6e-3  # multiple of every swept pitch: 200, 150, 120, 100, 75, 60, 50, 37.5 um
SITE_RADIUS_M = 4.8e-3  # the contact patch at 0.5 N spans |x| < 4.2 mm, |y| < 3.7 mm
SITE_DEPTH_M = {"SA1": 0.75e-3, "RA": 0.75e-3, "PC": 2.0e-3}  # the plugin's defaults
# Classes along the lattice (sorted by radius): 3 SA1 : 7 RA : 1 PC, close to
# the default densities 70 : 140 : 21 per cm^2 (Johansson & Vallbo 1979).
SITE_CLASS_CYCLE = ("RA", "SA1", "RA", "RA", "SA1", "RA", "RA", "SA1", "RA", "RA", "PC")
DEFAULT_DENSITY = (70.0, 140.0, 21.0)  # per cm^2, SA1 RA PC (plugin defaults)
LEAD_IN_S = 0.05  # sliding simulated before the timed phase: friction at steady slip
SKIP_S = 0.01  # skin start-up (receptor priming, RA/PC filters) left out of the errors
SPECTRAL_MIN_S = 0.1  # >= 2.5 periods of V/D = 25 Hz and 4 bins below it
FMIN_HZ, FMAX_HZ = 5.0, 500.0
MIN_WINDOW_STEPS = 20  # the shortest error window  # spectral band searched for the strongest peak


OVERRIDE_KEYS = ("nx", "pitch_m", "ridges", "timestep_s", "density_scale", "skin.<attribute>")


def odd_nx(pitch_m: float, extent_m: float = EXTENT_M) -> int:
    """The odd taxel count nearest extent / pitch: an odd grid has a taxel
    centred on the pole, so a site lattice at multiples of the pitch is
    shared by every pitch that divides its spacing."""
    n = int(round(extent_m / pitch_m))
    return n if n % 2 else n + 1


def pitch_grid(pitch_m: float, extent_m: float = EXTENT_M) -> dict:
    return {"pitch_m": pitch_m, "nx": odd_nx(pitch_m, extent_m)}


def tree(theta: float) -> dict:
    return {"skin.stress_method": "tree", "skin.stress_theta": theta}


@dataclasses.dataclass(frozen=True)
class Knob:
    """One accuracy knob: settings (override dicts, cheapest first) swept
    against a converged reference setting, each applied over ``base``."""

    name: str
    settings: tuple
    reference: dict
    base: dict = dataclasses.field(default_factory=dict)
    sites: bool = True  # the same explicit receptor sites in every setting
    steps: int | None = None  # sliding steps per row (default: duration / dt)
    labels: tuple | None = None  # row names, settings then reference (default: the overrides)

    def all_settings(self) -> list[tuple[dict, dict, bool]]:
        """(overrides, the setting's own overrides, is reference), reference last."""
        return [({**self.base, **s}, s, False) for s in self.settings] + [
            ({**self.base, **self.reference}, self.reference, True)
        ]


def knob(name: str, key: str, values, reference, **kw) -> Knob:
    """A knob over one override key (one line per knob)."""
    return Knob(name, tuple({key: v} for v in values), {key: reference}, **kw)


SHIFT = {"skin.grid_shift": "true"}
ONE_GRID = {"skin.grid_cycle": "1"}


def default_knobs(cfg: BenchConfig) -> list[Knob]:
    """The swept knobs. Default grid: 128 x 0.1 mm (the default skin); the
    pressure knob runs on 64 x 0.2 mm for the elastic model's sake."""
    grid = {"nx": cfg.nx, "pitch_m": cfg.pitch_m}
    coarse = {"nx": cfg.coarse_nx, "pitch_m": cfg.coarse_pitch_m}
    if cfg.quick:
        return [
            Knob(
                "pitch",
                tuple(pitch_grid(p, cfg.extent_m) for p in (200e-6, 150e-6)),
                pitch_grid(100e-6, cfg.extent_m),
            ),
            knob(
                "pressure",
                "skin.pressure",
                ("winkler",),
                "elastic",
                base=coarse,
                steps=cfg.elastic_steps,
            ),
            Knob("stress_method", (tree(1.0),), {"skin.stress_method": "direct"}, base=grid),
            Knob(
                "oversample",
                ({"timestep_s": 1e-3, "skin.oversample": 2},),
                {"timestep_s": 2e-4, "skin.oversample": 1},
                base=grid,
            ),
            knob("receptors", "density_scale", (0.5,), 1.0, base=grid, sites=False),
            knob("timestep", "timestep_s", (4e-4,), 1e-4, base=grid),
        ]
    return [
        # the reference with grid_shift, its convergence shown by the row at
        # 50 um with grid_shift (within 5% of it in rates); the one-grid
        # rows show what the default grid cycle buys at the coarse pitches
        Knob(
            "pitch",
            tuple(pitch_grid(p) for p in (200e-6, 150e-6, 100e-6, 75e-6, 50e-6))
            + tuple({**pitch_grid(p), **ONE_GRID} for p in (200e-6, 150e-6, 100e-6))
            + ({**pitch_grid(50e-6), **SHIFT},),
            {**pitch_grid(37.5e-6), **SHIFT},
        ),
        knob(
            "pressure",
            "skin.pressure",
            ("contacts", "winkler"),
            "elastic",
            base=coarse,
            steps=cfg.elastic_steps,
        ),
        knob("skin", "skin.skin", ("halfspace",), "layered", base=grid),
        Knob(
            "stress_method",
            ({"skin.stress_method": "fft"}, tree(1.5), tree(1.0), tree(0.5), tree(0.25)),
            {"skin.stress_method": "direct"},
            base=grid,
        ),
        knob("receptors", "density_scale", (0.25, 0.5, 1.0, 2.0), 4.0, base=grid, sites=False),
        knob("timestep", "timestep_s", (1e-3, 5e-4, 2e-4, 1e-4, 5e-5), 2.5e-5, base=grid),
        # physics at 1 ms, the skin K times per step (auto gives K = 2 there)
        Knob(
            "oversample",
            tuple({"timestep_s": 1e-3, "skin.oversample": k} for k in (2, 4, 10)),
            {"timestep_s": 1e-4, "skin.oversample": 1},
            base=grid,
        ),
        # shear="partial" (Coulomb stick and slip per cell) against full slip,
        # and against its own tight tangential (and, elastic, normal) solve
        Knob(
            "partial_winkler",
            ({"skin.shear": "true"}, {"skin.shear": "partial"}),
            {"skin.shear": "partial", "skin.tolerance": 1e-10},
            base={**grid, "skin.pressure": "winkler"},
            labels=("full slip", "partial", "partial, tolerance 1e-10"),
        ),
        Knob(
            "partial_elastic",
            ({"skin.shear": "true"}, {"skin.shear": "partial"}),
            {"skin.shear": "partial", "skin.tolerance": 1e-10},
            base={**coarse, "skin.pressure": "elastic"},
            steps=cfg.elastic_steps,
            labels=("full slip", "partial", "partial, tolerance 1e-10"),
        ),
        Knob(
            "presets",
            (PRESETS["rl"], RL_FULL_GRID, PRESETS["interactive"]),
            PRESETS["science"],
            labels=(
                "rl (fast)",
                "former rl: 65 x 0.2 mm, ridged, full",
                "interactive",
                "science (accurate)",
            ),
        ),
    ]


# Recommended settings (docs_bench.md), measured as the `presets` knob: odd
# grids of pitches dividing the 0.6 mm site lattice, timesteps multiples of
# the science preset's.
PRESETS = {
    # Exact stress: since the folded direct sum (#13) it costs no more than
    # the tree at these grids (bench: pitch 200 um exact 158 us/step vs the
    # tree at theta 1.0, 151 per substep), at 1/20 of its stress error.
    # rl: Winkler contact (stages 1-2 ~10x cheaper than elastic; ridges pressed
    # flat, textures still resolved), a 0.3 mm grid without ridges, half the
    # receptor density and stages 1-3 once per physics step (substep):
    # speed first (a whole hand at 2 ms within ~10x the bare step).
    "rl": {
        "nx": 43,
        "pitch_m": 300e-6,
        "ridges": False,
        "timestep_s": 1e-3,
        "density_scale": 0.5,
        "skin.stress_method": "auto",
        "skin.pressure": "winkler",
        "skin.substep": "receptors",
    },
    "interactive": {"nx": 85, "pitch_m": 150e-6, "timestep_s": 1e-3, "skin.stress_method": "auto"},
    # science: grid_shift cancels the elastic contact's V / pitch line (PC
    # 164 -> 41 Hz at 50 um on the default slide; README "What accuracy costs").
    "science": {
        "nx": 257,
        "pitch_m": 50e-6,
        "timestep_s": 1e-4,
        "skin.stress_method": "auto",
        "skin.grid_shift": "true",
    },
}

# What the rl preset gives up for its speed (a row of the presets knob): its
# former grid, ridges, receptor density and substeps.
RL_FULL_GRID = {
    "nx": 65,
    "pitch_m": 200e-6,
    "timestep_s": 1e-3,
    "skin.stress_method": "auto",
    "skin.pressure": "winkler",
}


MINIMAL = {
    "ridges": False,
    "skin.shear": "false",
    "skin.skin": "halfspace",
    "skin.pressure": "winkler",
    "skin.classes": "SA1",
    "skin.outputs": "spikes",
}
ALL_OUTPUTS = "spikes stress voltage force pressure rate"


def default_effects(cfg: BenchConfig) -> list[tuple[str, str, dict]]:
    """(group, label, overrides over the default skin): each effect alone
    over the minimal skin, all together (the default), and the default
    without each."""
    m = MINIMAL
    if cfg.quick:
        return [
            ("alone", "minimal", m),
            ("together", "default (all)", {}),
            ("without", "outputs force only (stages 1-2)", {"skin.outputs": "force"}),
        ]
    rows = [
        ("alone", "minimal: winkler, half-space, no ridges/shear, SA1, spikes", m),
        ("alone", "+ ridges", {**m, "ridges": True}),
        ("alone", "+ shear", {**m, "skin.shear": "true"}),
        ("alone", "+ shear partial (stick and slip)", {**m, "skin.shear": "partial"}),
        ("alone", "+ layered skin", {**m, "skin.skin": "layered"}),
        ("alone", "pressure contacts", {**m, "skin.pressure": "contacts"}),
        ("alone", "pressure elastic", {**m, "skin.pressure": "elastic"}),
        ("alone", "class RA instead of SA1", {**m, "skin.classes": "RA"}),
        ("alone", "class PC instead of SA1", {**m, "skin.classes": "PC"}),
    ]
    rows += [
        ("alone", f"+ output {o}", {**m, "skin.outputs": f"spikes {o}"})
        for o in ("stress", "voltage", "force", "pressure", "rate")
    ]
    rows += [
        (
            "together",
            "default (all: ridges, shear, layered, elastic, SA1 RA PC, spikes stress force)",
            {},
        )
    ]
    rows += [
        ("without", "- ridges", {"ridges": False}),
        ("without", "- shear", {"skin.shear": "false"}),
        ("without", "shear partial (stick and slip)", {"skin.shear": "partial"}),
        ("without", "half-space skin", {"skin.skin": "halfspace"}),
        ("without", "pressure contacts", {"skin.pressure": "contacts"}),
        ("without", "pressure winkler", {"skin.pressure": "winkler"}),
        ("without", "- SA1", {"skin.classes": "RA PC"}),
        ("without", "- RA", {"skin.classes": "SA1 PC"}),
        ("without", "- PC", {"skin.classes": "SA1 RA"}),
        ("without", "outputs spikes only", {"skin.outputs": "spikes"}),
        ("without", "outputs force only (stages 1-2)", {"skin.outputs": "force"}),
        ("without", "+ all outputs", {"skin.outputs": ALL_OUTPUTS}),
        ("without", "+ grid_shift (cancels the V / pitch line)", {"skin.grid_shift": "true"}),
        ("without", "threads 2 (wall time; same bits)", {"skin.threads": "2"}),
    ]
    return rows


@dataclasses.dataclass
class BenchConfig:
    quick: bool = False
    duration_s: float = 0.25  # sliding simulated per row (errors need >= SPECTRAL_MIN_S + SKIP_S)
    time_steps: int = 200  # steps per timed repeat
    repeats: int = 8  # timing rounds; each configuration's minimum over them is reported
    elastic_steps: int = 300  # sliding steps of the pressure knob (elastic: ~5 ms/step at 64^2)
    elastic_time_steps: int = 20  # steps per timed repeat of elastic rows (effects: 128^2)
    cheap_steps: int = 5000  # steps per timed repeat of the bare and idle baselines
    knob_steps: dict = dataclasses.field(default_factory=dict)  # knob -> sliding steps
    knobs: tuple | None = None  # names to run (default: all)
    effects: bool = True
    threads: bool = True
    threads_batch: int = 8  # MjData rolled out per threaded call
    nx: int = 128
    pitch_m: float = 1e-4
    coarse_nx: int = 64
    coarse_pitch_m: float = 2e-4
    extent_m: float = EXTENT_M

    @classmethod
    def quick_config(cls, **kw) -> BenchConfig:
        """A tiny sweep for CI: small grids, short runs (well under a minute)."""
        base = dict(
            quick=True,
            duration_s=0.11,
            time_steps=60,
            repeats=3,
            elastic_steps=150,
            elastic_time_steps=10,
            cheap_steps=1000,
            threads_batch=4,
            nx=48,
            pitch_m=2e-4,
            coarse_nx=48,
            coarse_pitch_m=2e-4,
            extent_m=9.6e-3,
        )
        base.update(kw)
        return cls(**base)

    def validate(self) -> None:
        def integer(name, lo, hi):
            v = getattr(self, name)
            if not (isinstance(v, (int, np.integer)) and lo <= v <= hi):
                raise ValueError(f"{name} = {v!r} is out of range; valid range [{lo}, {hi}]")

        integer("time_steps", 10, 1_000_000)
        integer("repeats", 1, 100)
        integer("elastic_steps", 1, 1_000_000)
        integer("elastic_time_steps", 1, 1_000_000)
        integer("cheap_steps", 10, 10_000_000)
        integer("threads_batch", 2, 1024)
        if not (math.isfinite(self.duration_s) and 2 * SKIP_S <= self.duration_s <= 5.0):
            raise ValueError(
                f"duration_s = {self.duration_s} is out of range; valid range [{2 * SKIP_S}, 5] s"
            )
        names = [k.name for k in default_knobs(self)]
        for name, n in self.knob_steps.items():
            if name not in names:
                raise ValueError(f"knob_steps: unknown knob {name!r}; valid: {', '.join(names)}")
            if not (isinstance(n, (int, np.integer)) and 2 <= n <= 10_000_000):
                raise ValueError(
                    f"knob_steps[{name!r}] = {n!r} is out of range; valid range [2, 1e7] steps"
                )
        for name in self.knobs or ():
            if name not in names:
                raise ValueError(f"unknown knob {name!r}; valid: {', '.join(names)}")


def scene_parts(
    overrides: dict, sites: str | None = None
) -> tuple[scenes.Fingertip, scenes.Protocol]:
    """The default scene's fingertip and protocol with overrides applied."""
    tip_kw, skin, proto_kw = {}, {}, {}
    for key, value in overrides.items():
        if key in ("nx", "pitch_m", "ridges"):
            tip_kw[key] = value
        elif key == "timestep_s":
            proto_kw[key] = value
        elif key == "density_scale":
            if not (isinstance(value, (int, float)) and 0 < value <= 40):
                raise ValueError(f"density_scale = {value!r} is out of range; valid (0, 40]")
            skin["density"] = " ".join(f"{d * value:.9g}" for d in DEFAULT_DENSITY)
        elif key.startswith("skin."):
            skin[key[5:]] = value if isinstance(value, str) else f"{value:.9g}"
        else:
            raise ValueError(f"unknown override {key!r}; valid: {', '.join(OVERRIDE_KEYS)}")
    if sites is not None:  # explicit sites replace the density population
        skin.pop("density", None)
        skin["sites"] = sites
    return scenes.Fingertip(skin=skin, **tip_kw), scenes.Protocol(**proto_kw)


def lattice_sites(grids: list[tuple[int, float]], radius_m: float = SITE_RADIUS_M) -> str:
    """The `sites` attribute: a SITE_SPACING_M lattice within radius_m of
    the pole, on taxel centres of every grid (nx, pitch) given (odd grids:
    centres at multiples of the pitch; even grids: offset by half a pitch)."""
    parity = {nx % 2 for nx, _ in grids}
    if len(parity) != 1:
        raise ValueError(f"grids {grids} mix odd and even nx: no common taxel centres")
    offset = 0.0 if parity == {1} else grids[0][1] / 2
    limit = min(nx * p / 2 - p for nx, p in grids)
    m = int(radius_m // SITE_SPACING_M) + 1
    pts = []
    for i in range(-m, m + 1):
        for j in range(-m, m + 1):
            x, y = i * SITE_SPACING_M + offset, j * SITE_SPACING_M + offset
            if math.hypot(x, y) <= radius_m + 1e-12 and max(abs(x), abs(y)) <= limit + 1e-12:
                pts.append((round(math.hypot(x, y), 12), round(math.atan2(y, x), 12), x, y))
    pts.sort()
    for nx, p in grids:  # each site must be a taxel centre, (k - (nx - 1) / 2) p
        k = np.array([[x, y] for *_, x, y in pts]) / p + (nx - 1) / 2
        if np.abs(k - np.round(k)).max() > 1e-6:
            raise ValueError(
                f"the {SITE_SPACING_M} m site lattice (offset {offset} m) is not on "
                f"the taxel centres of nx = {nx}, pitch = {p} m"
            )
    out = []
    for k, (_, _, x, y) in enumerate(pts):
        c = SITE_CLASS_CYCLE[k % len(SITE_CLASS_CYCLE)]
        out.append(f"{c} {x:.9g} {y:.9g} {SITE_DEPTH_M[c]:.9g}")
    return "; ".join(out)
