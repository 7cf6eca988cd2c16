"""What accuracy costs in time: ``python -m mjtouch bench``.

The default sliding scene (:mod:`mjtouch.scenes`: ridged fingertip pressed
with 0.5 N on the 1 mm grating, slid at 25 mm/s) is run with one knob changed
at a time. For every setting the benchmark reports the cost per step and per
simulated second, and the error against that knob's converged reference,
computed in the same run from the same starting state:

- ``stress_rms_rel``: RMS over the window and receptors of the receptor
  stress error, over the reference's RMS stress (``stress_rms_pa``: in Pa);
- ``peak_freq_hz``: |strongest stress spectral peak - the reference's|;
- ``peak_amp_rel``: |spectral amplitude at the reference's peak / the
  reference's - 1| (amplitude = sqrt of the periodogram power);
- ``spike_rate_rel``: sum over classes of |population rate - reference's|
  over the sum of the reference's rates (``spike_rate_hz``: signed, per class).

Every knob but ``receptors`` gives all its settings the same explicit
receptor ``sites`` (a 0.6 mm lattice, a common multiple of every swept pitch,
so each site is a taxel centre of every grid and no setting moves a
receptor); ``receptors`` scales the density, so its stress error compares
the class-mean stress traces instead (``stress_basis``). Spectral errors need
``SPECTRAL_MIN_S`` of window; shorter rows (the elastic pressure model)
report them as null.

Timing: one process, same-process ratios; every run starts from one settled
state (the press and a lead-in of sliding are simulated once per timestep on
the scene without the plugin, then set with ``mj_setState``; the skin's own
state starts fresh, and its first ``SKIP_S`` are left out of the errors);
only the sliding phase is timed, as ``mj_step(model, data, nstep)`` (a C
loop, nothing recorded per step). Each configuration is warmed up once
(the knob rows record their data then, step by step); then timing rounds
run over all configurations, each round timing every configuration once,
and each configuration reports its minimum over the rounds: on a shared
machine the load changes over seconds to minutes, and interleaving spreads
every configuration's samples over the whole phase. Every timed run must
end on the warm-up's sensordata bit for bit (``repeats_identical``).
Threads are timed separately as wall time of ``mujoco.rollout`` calls.

Adding a knob is one line in :func:`default_knobs`: a :class:`Knob` lists
its settings as override dicts (keys in ``OVERRIDE_KEYS``), cheapest first,
and the reference setting.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import platform
import sys
import time
from typing import Callable

import mujoco
import mujoco.rollout
import numpy as np

from mjtouch import analysis, scenes
from mjtouch.sensor import CLASSES, SkinLayout

# --- scene, sites, state ------------------------------------------------------

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

_PHYSICS_SPEC = int(mujoco.mjtState.mjSTATE_FULLPHYSICS) & ~int(mujoco.mjtState.mjSTATE_PLUGIN)
_FULL_SPEC = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)

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
        return [({**self.base, **s}, s, False) for s in self.settings] + \
               [({**self.base, **self.reference}, self.reference, True)]


def knob(name: str, key: str, values, reference, **kw) -> Knob:
    """A knob over one override key (one line per knob)."""
    return Knob(name, tuple({key: v} for v in values), {key: reference}, **kw)


def default_knobs(cfg: "BenchConfig") -> list[Knob]:
    """The swept knobs. Default grid: 128 x 0.1 mm (the default skin); the
    pressure knob runs on 64 x 0.2 mm for the elastic model's sake."""
    grid = {"nx": cfg.nx, "pitch_m": cfg.pitch_m}
    coarse = {"nx": cfg.coarse_nx, "pitch_m": cfg.coarse_pitch_m}
    if cfg.quick:
        return [
            Knob("pitch", tuple(pitch_grid(p, cfg.extent_m) for p in (200e-6, 150e-6)),
                 pitch_grid(100e-6, cfg.extent_m)),
            knob("pressure", "skin.pressure", ("winkler",), "elastic", base=coarse,
                 steps=cfg.elastic_steps),
            Knob("stress_method", (tree(1.0),), {"skin.stress_method": "direct"}, base=grid),
            Knob("oversample", ({"timestep_s": 1e-3, "skin.oversample": 2},),
                 {"timestep_s": 2e-4, "skin.oversample": 1}, base=grid),
            knob("receptors", "density_scale", (0.5,), 1.0, base=grid, sites=False),
            knob("timestep", "timestep_s", (4e-4,), 1e-4, base=grid),
        ]
    return [
        Knob("pitch", tuple(pitch_grid(p) for p in (200e-6, 150e-6, 100e-6, 75e-6, 50e-6)),
             pitch_grid(37.5e-6)),
        knob("pressure", "skin.pressure", ("contacts", "winkler"), "elastic", base=coarse,
             steps=cfg.elastic_steps),
        knob("skin", "skin.skin", ("halfspace",), "layered", base=grid),
        Knob("stress_method", ({"skin.stress_method": "fft"}, tree(1.5), tree(1.0), tree(0.5),
                               tree(0.25)), {"skin.stress_method": "direct"}, base=grid),
        knob("receptors", "density_scale", (0.25, 0.5, 1.0, 2.0), 4.0, base=grid, sites=False),
        knob("timestep", "timestep_s", (1e-3, 5e-4, 2e-4, 1e-4, 5e-5), 2.5e-5, base=grid),
        # physics at 1 ms, the skin K times per step (auto gives K = 2 there)
        Knob("oversample", tuple({"timestep_s": 1e-3, "skin.oversample": k} for k in (2, 4, 10)),
             {"timestep_s": 1e-4, "skin.oversample": 1}, base=grid),
        Knob("presets", (PRESETS["rl"], PRESETS["interactive"]), PRESETS["science"],
             labels=("rl (fast)", "interactive", "science (accurate)")),
    ]


# Recommended settings (docs_bench.md), measured as the `presets` knob: odd
# grids of pitches dividing the 0.6 mm site lattice, timesteps multiples of
# the science preset's.
PRESETS = {
    "rl": {"nx": 65, "pitch_m": 200e-6, "timestep_s": 1e-3, **tree(1.0)},
    "interactive": {"nx": 85, "pitch_m": 150e-6, "timestep_s": 1e-3, **tree(0.5)},
    "science": {"nx": 257, "pitch_m": 50e-6, "timestep_s": 1e-4, "skin.stress_method": "auto"},
}


MINIMAL = {"ridges": False, "skin.shear": "false", "skin.skin": "halfspace",
           "skin.pressure": "winkler", "skin.classes": "SA1", "skin.outputs": "spikes"}
ALL_OUTPUTS = "spikes stress voltage force pressure rate"


def default_effects(cfg: "BenchConfig") -> list[tuple[str, str, dict]]:
    """(group, label, overrides over the default skin): each effect alone
    over the minimal skin, all together (the default), and the default
    without each."""
    m = MINIMAL
    if cfg.quick:
        return [("alone", "minimal", m), ("together", "default (all)", {}),
                ("without", "outputs force only (stages 1-2)", {"skin.outputs": "force"})]
    rows = [("alone", "minimal: winkler, half-space, no ridges/shear, SA1, spikes", m),
            ("alone", "+ ridges", {**m, "ridges": True}),
            ("alone", "+ shear", {**m, "skin.shear": "true"}),
            ("alone", "+ layered skin", {**m, "skin.skin": "layered"}),
            ("alone", "pressure contacts", {**m, "skin.pressure": "contacts"}),
            ("alone", "pressure elastic", {**m, "skin.pressure": "elastic"}),
            ("alone", "class RA instead of SA1", {**m, "skin.classes": "RA"}),
            ("alone", "class PC instead of SA1", {**m, "skin.classes": "PC"})]
    rows += [("alone", f"+ output {o}", {**m, "skin.outputs": f"spikes {o}"})
             for o in ("stress", "voltage", "force", "pressure", "rate")]
    rows += [("together", "default (all: ridges, shear, layered, winkler, SA1 RA PC, "
                          "spikes stress force)", {})]
    rows += [("without", "- ridges", {"ridges": False}),
             ("without", "- shear", {"skin.shear": "false"}),
             ("without", "half-space skin", {"skin.skin": "halfspace"}),
             ("without", "pressure contacts", {"skin.pressure": "contacts"}),
             ("without", "pressure elastic", {"skin.pressure": "elastic"}),
             ("without", "- SA1", {"skin.classes": "RA PC"}),
             ("without", "- RA", {"skin.classes": "SA1 PC"}),
             ("without", "- PC", {"skin.classes": "SA1 RA"}),
             ("without", "outputs spikes only", {"skin.outputs": "spikes"}),
             ("without", "outputs force only (stages 1-2)", {"skin.outputs": "force"}),
             ("without", "+ all outputs", {"skin.outputs": ALL_OUTPUTS})]
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
    def quick_config(cls, **kw) -> "BenchConfig":
        """A tiny sweep for CI: small grids, short runs (well under a minute)."""
        base = dict(quick=True, duration_s=0.11, time_steps=60, repeats=3, elastic_steps=150,
                    elastic_time_steps=10, cheap_steps=1000, threads_batch=4, nx=48,
                    pitch_m=2e-4, coarse_nx=48, coarse_pitch_m=2e-4, extent_m=9.6e-3)
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
            raise ValueError(f"duration_s = {self.duration_s} is out of range; valid range "
                             f"[{2 * SKIP_S}, 5] s")
        names = [k.name for k in default_knobs(self)]
        for name, n in self.knob_steps.items():
            if name not in names:
                raise ValueError(f"knob_steps: unknown knob {name!r}; valid: {', '.join(names)}")
            if not (isinstance(n, (int, np.integer)) and 2 <= n <= 10_000_000):
                raise ValueError(f"knob_steps[{name!r}] = {n!r} is out of range; valid range "
                                 "[2, 1e7] steps")
        for name in self.knobs or ():
            if name not in names:
                raise ValueError(f"unknown knob {name!r}; valid: {', '.join(names)}")


def scene_parts(overrides: dict, sites: str | None = None
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
    if sites is not None:
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
            raise ValueError(f"the {SITE_SPACING_M} m site lattice (offset {offset} m) is not on "
                             f"the taxel centres of nx = {nx}, pitch = {p} m")
    out = []
    for k, (_, _, x, y) in enumerate(pts):
        c = SITE_CLASS_CYCLE[k % len(SITE_CLASS_CYCLE)]
        out.append(f"{c} {x:.9g} {y:.9g} {SITE_DEPTH_M[c]:.9g}")
    return "; ".join(out)


def strip_plugin(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """The scene without the mjtouch.skin plugin (the bare MuJoCo scene)."""
    return scenes.remove_skin(spec)


def add_native_tactile(spec: mujoco.MjSpec, nx: int, pitch_m: float,
                       semi_axes_m) -> mujoco.MjSpec:
    """The bare scene plus MuJoCo's native tactile sensor on an nx x nx
    vertex plate mesh (non-colliding, on the finger body at the pad's pole,
    the plugin grid's extent): it reports at every vertex while the pad
    touches the plate box."""
    half = nx * pitch_m / 2
    strip_plugin(spec)
    mesh = spec.add_mesh(name="tactile_plate")
    mesh.make_plate([nx, nx])
    mesh.scale = [half, half, 0.0005]
    spec.geom("pad").parent.add_geom(
        name="tactile_surface", type=mujoco.mjtGeom.mjGEOM_MESH, meshname="tactile_plate",
        pos=[0, 0, -semi_axes_m[2]], contype=0, conaffinity=0, group=4)
    spec.add_sensor(name="tactile", type=mujoco.mjtSensor.mjSENS_TACTILE,
                    objtype=mujoco.mjtObj.mjOBJ_MESH, objname="tactile_plate",
                    reftype=mujoco.mjtObj.mjOBJ_GEOM, refname="tactile_surface")
    return spec


class States:
    """Settled states, one per (timestep, pressed): the press and a lead-in
    of sliding simulated on the scene without the plugin (a sensor plugin
    does not change the physics), so every configuration starts from the
    same state."""

    def __init__(self, texture: scenes.Texture):
        self.texture = texture
        self._cache = {}

    def physics(self, timestep_s: float, pressed: bool = True):
        key = (timestep_s, pressed)
        if key not in self._cache:
            proto = scenes.Protocol(timestep_s=timestep_s)
            model = bare_model(scenes.Fingertip(), self.texture, proto)
            data = mujoco.MjData(model)
            ctrl = scenes.controls(proto, LEAD_IN_S)
            if not pressed:
                ctrl[:, 1] = 0.0  # no press: the gravity-compensated finger hovers 0.3 mm up
            for row in ctrl:
                data.ctrl[:] = row
                mujoco.mj_step(model, data)
            state = np.empty(mujoco.mj_stateSize(model, _PHYSICS_SPEC))
            mujoco.mj_getState(model, data, state, _PHYSICS_SPEC)
            self._cache[key] = (state, data.qacc_warmstart.copy(), data.ncon)
        return self._cache[key]

    def initial(self, model: mujoco.MjModel, pressed: bool = True):
        """(full state with a fresh skin, solver warm start) for model."""
        phys, warm, _ = self.physics(float(model.opt.timestep), pressed)
        if mujoco.mj_stateSize(model, _PHYSICS_SPEC) != phys.size:
            raise RuntimeError("configuration changes the physics state size; it must differ "
                               "from the default scene in the skin only")
        data = mujoco.MjData(model)
        mujoco.mj_setState(model, data, phys, _PHYSICS_SPEC)
        full = np.empty(mujoco.mj_stateSize(model, _FULL_SPEC))
        mujoco.mj_getState(model, data, full, _FULL_SPEC)
        return full, warm


def bare_model(tip, texture, proto) -> mujoco.MjModel:
    model = scenes.scene_spec(tip, texture, proto, skin=False).compile()
    if model.nplugin:
        raise RuntimeError("the bare scene still holds a plugin")
    return model


def slide_ctrl(proto: scenes.Protocol, nstep: int, pressed: bool = True) -> np.ndarray:
    ctrl = np.zeros((nstep, 2))
    ctrl[:, 0] = proto.speed_m_s
    ctrl[:, 1] = -proto.force_n if pressed else 0.0
    return ctrl


@dataclasses.dataclass
class Run:
    """A configuration ready to roll out from its settled state. Output
    buffers are allocated once and reused: a fresh rollout output costs the
    kernel's page zeroing per step (~1 us per 3 kB of sensordata), which
    would be timed as if it were the sensor's cost."""

    model: mujoco.MjModel
    state0: np.ndarray
    warm: np.ndarray
    ctrl: np.ndarray  # (nstep, nu), the longest rollout wanted
    data: mujoco.MjData = None

    def __post_init__(self):
        self.data = mujoco.MjData(self.model)
        self._state = self._sensordata = None

    def _buffers(self):
        if self._state is None:
            n = self.ctrl.shape[0]
            self._state = np.zeros((1, n, self.state0.size))
            self._sensordata = np.zeros((1, n, self.model.nsensordata))

    def step(self, nstep: int) -> tuple[float, np.ndarray]:
        """Time nstep steps of mj_step(nstep=...) from the settled state, the
        slide control held (what a simulation loop pays: no per-step
        recording; rollout copies the full state each step, the skin's 16
        doubles per receptor included). Returns (wall seconds, the last
        step's sensordata)."""
        mujoco.mj_setState(self.model, self.data, self.state0, _FULL_SPEC)
        self.data.qacc_warmstart[:] = self.warm
        self.data.ctrl[:] = self.ctrl[0]
        t0 = time.perf_counter()
        mujoco.mj_step(self.model, self.data, nstep=nstep)
        return time.perf_counter() - t0, self.data.sensordata.copy()

    def record(self, nstep: int) -> np.ndarray:
        """sensordata (nstep, nsensordata) of nstep mj_steps from the settled
        state: the same computation that step() times (untimed)."""
        mujoco.mj_setState(self.model, self.data, self.state0, _FULL_SPEC)
        self.data.qacc_warmstart[:] = self.warm
        self.data.ctrl[:] = self.ctrl[0]
        out = np.empty((nstep, self.model.nsensordata))
        for k in range(nstep):
            mujoco.mj_step(self.model, self.data)
            out[k] = self.data.sensordata
        return out

    def rollout(self, nstep: int) -> tuple[float, np.ndarray]:
        """(wall seconds, sensordata (nstep, nsensordata), a view of the buffer)."""
        self._buffers()
        t0 = time.perf_counter()
        mujoco.rollout.rollout(self.model, self.data, self.state0[None], self.ctrl[None, :nstep],
                               initial_warmstart=self.warm[None], state=self._state[:, :nstep],
                               sensordata=self._sensordata[:, :nstep])
        return time.perf_counter() - t0, self._sensordata[0, :nstep]


# --- errors ------------------------------------------------------------------


@dataclasses.dataclass
class Trace:
    stress: np.ndarray  # (nstep, nrec), Pa
    spikes: np.ndarray  # (nstep, nrec), counts
    classes: np.ndarray  # (nrec,)
    dt_s: float


def class_means(stress: np.ndarray, classes: np.ndarray) -> tuple[np.ndarray, list[str]]:
    present = [c for c in CLASSES if (classes == c).any()]
    return np.stack([stress[:, classes == c].mean(axis=1) for c in present], axis=1), present


def errors(row: Trace, ref: Trace, basis: str = "receptor", skip_s: float = SKIP_S) -> dict:
    """Errors of row against ref over their common window after skip_s.
    The row's timestep must be a whole multiple of the reference's; stress
    is compared at the row's sample times. basis "receptor": receptor by
    receptor (same sites); "class mean": the class-mean traces."""
    m = row.dt_s / ref.dt_s
    if m < 1 - 1e-9 or abs(m - round(m)) > 1e-6 * m:
        raise ValueError(f"row timestep {row.dt_s} s is not a whole multiple of the reference's "
                         f"{ref.dt_s} s")
    m = int(round(m))
    k0 = int(round(skip_s / row.dt_s))
    n = min(row.stress.shape[0], ref.stress.shape[0] // m)
    if n - k0 < 2:
        raise ValueError(f"the window after skip_s = {skip_s} s has {n - k0} steps; run longer")
    window_s = (n - k0) * row.dt_s
    idx = (np.arange(k0, n) + 1) * m - 1  # reference rows at the row's sample times
    a, b = row.stress[k0:n], ref.stress[idx]
    if basis == "class mean":
        a, ca = class_means(a, row.classes)
        b, cb = class_means(b, ref.classes)
        if ca != cb:
            raise ValueError(f"classes differ: {ca} vs {cb}")
    elif basis != "receptor" or a.shape != b.shape or not np.array_equal(row.classes, ref.classes):
        raise ValueError("basis 'receptor' needs the same receptors in row and reference")
    diff = np.sqrt(np.mean((a - b) ** 2))
    scale = np.sqrt(np.mean(b ** 2))
    out = {"stress_rms_pa": float(diff),
           "stress_rms_rel": float(diff / scale) if scale > 0 else (0.0 if diff == 0 else None),
           "peak_freq_hz": None, "peak_amp_rel": None, "ref_peak_hz": None}
    ref_win = slice(k0 * m, n * m)
    if window_s >= SPECTRAL_MIN_S - 1e-12:
        fmax = min(FMAX_HZ, 0.5 / row.dt_s)
        f, p = analysis.stress_spectrum(row.stress[k0:n], row.dt_s)
        fr, pr = analysis.stress_spectrum(ref.stress[ref_win], ref.dt_s)
        peak_ref = analysis.spectral_peaks(fr, pr, n=1, fmin_hz=FMIN_HZ, fmax_hz=fmax)
        peak_row = analysis.spectral_peaks(f, p, n=1, fmin_hz=FMIN_HZ, fmax_hz=fmax)
        if peak_ref and peak_row:
            amp = math.sqrt(analysis.power_at(f, p, peak_ref[0]))
            amp_ref = math.sqrt(analysis.power_at(fr, pr, peak_ref[0]))
            out["ref_peak_hz"] = peak_ref[0]
            out["peak_freq_hz"] = abs(peak_row[0] - peak_ref[0])
            out["peak_amp_rel"] = abs(amp / amp_ref - 1) if amp_ref > 0 else None
    r = analysis.rates_hz(row.spikes[k0:n], row.dt_s, row.classes)
    rr = analysis.rates_hz(ref.spikes[ref_win], ref.dt_s, ref.classes)
    total = sum(rr.values())
    dev = sum(abs(r[c] - rr[c]) for c in CLASSES)
    out["spike_rate_rel"] = dev / total if total > 0 else (0.0 if dev == 0 else None)
    out["spike_rate_hz"] = {c: r[c] - rr[c] for c in CLASSES}
    out["ref_rate_hz"] = rr
    out["window_s"] = window_s
    return out


def pareto_front(costs, errs) -> list[bool]:
    """True where no other point is at most as costly and at most as wrong
    and better in one (None errors are never on the front)."""
    pts = list(zip(costs, errs))
    out = []
    for i, (c, e) in enumerate(pts):
        if e is None or c is None:
            out.append(False)
            continue
        dominated = any(j != i and e2 is not None and c2 <= c and e2 <= e and (c2 < c or e2 < e)
                        for j, (c2, e2) in enumerate(pts))
        out.append(not dominated)
    return out


def fit_power_law(x, y) -> dict:
    """Least squares of log y = log a + b log x: the exponent b, prefactor a
    and R^2 of the log-log fit (points with x, y <= 0 are dropped)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 2 or np.ptp(np.log(x[ok])) == 0:
        return {"exponent": None, "prefactor": None, "r2": None, "n": int(ok.sum())}
    lx, ly = np.log(x[ok]), np.log(y[ok])
    b, a = np.polyfit(lx, ly, 1)
    res = ly - (a + b * lx)
    ss = np.sum((ly - ly.mean()) ** 2)
    return {"exponent": float(b), "prefactor": float(math.exp(a)),
            "r2": float(1 - np.sum(res ** 2) / ss) if ss > 0 else 1.0, "n": int(ok.sum())}


def fit_affine(x, y) -> dict:
    """Least squares of y = intercept + slope x, with R^2."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.size < 2 or np.ptp(x) == 0:
        return {"intercept": None, "slope": None, "r2": None, "n": int(x.size)}
    slope, intercept = np.polyfit(x, y, 1)
    ss = np.sum((y - y.mean()) ** 2)
    res = y - (intercept + slope * x)
    return {"intercept": float(intercept), "slope": float(slope),
            "r2": float(1 - np.sum(res ** 2) / ss) if ss > 0 else 1.0, "n": int(x.size)}


# --- progress ----------------------------------------------------------------


class Progress:
    """A text progress bar on stderr (one line per item when not a TTY)."""

    def __init__(self, total: int, enabled: bool = True, stream=None, width: int = 30):
        self.total, self.done, self.enabled, self.width = max(total, 1), 0, enabled, width
        self.stream = stream or sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self.t0 = time.perf_counter()

    def step(self, label: str) -> None:
        self.done += 1
        if not self.enabled:
            return
        k = int(self.width * min(self.done, self.total) / self.total)
        line = (f"[{'#' * k}{'.' * (self.width - k)}] {self.done}/{self.total} "
                f"{time.perf_counter() - self.t0:6.1f} s  {label}")
        if self.tty:
            self.stream.write("\r" + line[:110].ljust(110))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()


# --- the benchmark -----------------------------------------------------------


def _label(overrides: dict) -> str:
    parts = []
    for k, v in overrides.items():
        if k == "pitch_m":
            parts.append(f"pitch {v * 1e6:.4g} um")
        elif k == "nx":
            parts.append(f"nx {v}")
        elif k == "timestep_s":
            parts.append(f"dt {v:.3g} s")
        elif k == "density_scale":
            parts.append(f"density x{v:g}")
        elif k.startswith("skin."):
            parts.append(f"{k[5:]}={v}")
        else:
            parts.append(f"{k}={v}")
    return ", ".join(parts)


class Bench:
    """The benchmark. Every configuration is built and warmed up first (the
    knob rows also record their data for the errors); then one timing
    phase runs interleaved rounds over all of them, each round timing every
    configuration once, so each configuration's minimum is taken over
    samples spread across the whole phase (the load of a shared machine
    changes over seconds to minutes)."""

    def __init__(self, cfg: BenchConfig, progress: Progress | None = None):
        cfg.validate()
        self.cfg = cfg
        self.texture = scenes.Texture()
        self.states = States(self.texture)
        self.progress = progress
        self._items = []  # (run, nstep, last sensordata, recorded, result dict)

    def _tick(self, label: str) -> None:
        if self.progress:
            self.progress.step(label)

    def _run(self, overrides: dict, sites: str | None = None, pressed: bool = True,
             nstep: int = 1, edit: Callable[[mujoco.MjSpec], object] | None = None,
             disable_sensors: bool = False) -> tuple[Run, scenes.Protocol, scenes.Fingertip]:
        tip, proto = scene_parts(overrides, sites)
        spec = scenes.scene_spec(tip, self.texture, proto)
        if edit is not None:
            edit(spec)
        model = spec.compile()
        if disable_sensors:
            model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        state0, warm = self.states.initial(model, pressed)
        return Run(model, state0, warm, slide_ctrl(proto, nstep, pressed)), proto, tip

    def _queue(self, run: Run, nstep: int, last: np.ndarray, result: dict,
               recorded: bool = False) -> None:
        """Time run later (nstep steps per repeat); the repeats must end on
        sensordata `last`. Fills result["us_per_step"], ["repeats_identical"]."""
        self._items.append((run, nstep, last, recorded, result))

    def time_all(self) -> None:
        """The timing phase: repeats rounds over every queued configuration
        (mj_step(nstep) from the settled state, or a rollout if recorded)."""
        items = self._items
        best = [math.inf] * len(items)
        same = [True] * len(items)
        for r in range(self.cfg.repeats):
            for i, (run, nstep, ref, rec, _) in enumerate(items):
                if rec:
                    wall, sd = run.rollout(nstep)
                    last = sd[nstep - 1]
                else:
                    wall, last = run.step(nstep)
                best[i] = min(best[i], wall / nstep)
                same[i] &= bool(np.array_equal(last, ref))
            self._tick(f"timing round {r + 1}/{self.cfg.repeats} ({len(items)} configurations)")
        for (_, _, _, _, result), t, ok in zip(items, best, same):
            result["us_per_step"] = t * 1e6
            result["repeats_identical"] = ok
        self._items = []

    # baselines ----------------------------------------------------------------
    BASELINES = ("bare_mujoco", "native_tactile", "native_tactile_sensors_off", "full_pipeline",
                 "homogeneous_kernel", "idle_plugin", "bare_mujoco_idle", "idle_plugin_rollout",
                 "bare_mujoco_idle_rollout")

    def baselines(self) -> dict:
        """Builds and warms up the baselines; their times come from time_all()."""
        c = self.cfg
        grid = {"nx": c.nx, "pitch_m": c.pitch_m}
        tip = scene_parts(grid)[0]
        tactile = lambda s: add_native_tactile(s, tip.nx, tip.pitch_m, tip.semi_axes_m)  # noqa: E731
        cheap = max(c.cheap_steps, c.time_steps)  # ~20 ms per repeat: call overhead < 0.1%
        recorded = min(cheap, 1000)  # rollout's buffers stay small (23 kB of state per step)
        configs = {  # name: (options, steps per timed repeat, timed through mujoco.rollout)
            "bare_mujoco": (dict(edit=strip_plugin), cheap, False),
            "native_tactile": (dict(edit=tactile), c.time_steps, False),
            "native_tactile_sensors_off": (dict(edit=tactile, disable_sensors=True),
                                           c.time_steps, False),
            "full_pipeline": ({}, c.time_steps, False),
            "homogeneous_kernel": (dict(extra={"skin.skin": "halfspace"}), c.time_steps, False),
            "idle_plugin": (dict(pressed=False), cheap, False),
            "bare_mujoco_idle": (dict(edit=strip_plugin, pressed=False), cheap, False),
            "idle_plugin_rollout": (dict(pressed=False), recorded, True),
            "bare_mujoco_idle_rollout": (dict(edit=strip_plugin, pressed=False), recorded, True),
        }
        self._baseline_results = {}
        models = {}
        for name, (kw, nstep, rec) in configs.items():
            kw = dict(kw)
            extra = kw.pop("extra", {})
            run, proto, _ = self._run({**grid, **extra}, nstep=nstep, **kw)
            # warm-up; its last sensordata is what every timed repeat must reproduce
            last = run.rollout(nstep)[1][-1].copy() if rec else run.step(nstep)[1]
            self._baseline_results[name] = {}
            self._queue(run, nstep, last, self._baseline_results[name], rec)
            models[name] = run.model
            self._tick(f"baseline {name}")
        layout = SkinLayout.from_model(models["full_pipeline"])
        dt = float(models["full_pipeline"].opt.timestep)
        out = {
            "taxels": layout.nx ** 2,
            "native_tactile_taxels": int(models["native_tactile"].mesh_vertnum[0]),
            "receptors": int(len(layout.classes)),
            "active_taxels": self.active_taxels(grid),
            "timestep_s": dt,
            "contacts_pressed": int(self.states.physics(dt, True)[2]),
            "contacts_idle": int(self.states.physics(dt, False)[2]),
        }
        if out["native_tactile_taxels"] != layout.nx ** 2:
            raise RuntimeError("the native tactile mesh does not have one vertex per taxel")
        return out

    def finish_baselines(self, out: dict) -> None:
        for name in self.BASELINES:
            out[f"{name}_us_per_step"] = self._baseline_results[name]["us_per_step"]
        out["repeats_identical"] = all(r["repeats_identical"]
                                       for r in self._baseline_results.values())

    @staticmethod
    def ratios(b: dict) -> dict:
        bare, full = b["bare_mujoco_us_per_step"], b["full_pipeline_us_per_step"]
        plugin = full - bare
        tactile = b["native_tactile_us_per_step"] - b["native_tactile_sensors_off_us_per_step"]
        idle = b["idle_plugin_us_per_step"] / b["bare_mujoco_idle_us_per_step"]
        return {
            "full_over_bare": full / bare,
            "plugin_us_per_step": plugin,
            "native_tactile_sensor_us_per_step": tactile,
            "native_tactile_ns_per_taxel": tactile * 1e3 / b["native_tactile_taxels"],
            "plugin_over_native_tactile_sensor": plugin / tactile if tactile > 0 else None,
            "full_over_native_tactile": full / b["native_tactile_us_per_step"],
            "idle_over_bare_idle": idle,
            "idle_overhead_pct": 100 * (idle - 1),
            "idle_rollout_overhead_pct": 100 * (b["idle_plugin_rollout_us_per_step"] /
                                                b["bare_mujoco_idle_rollout_us_per_step"] - 1),
            "layered_over_homogeneous": full / b["homogeneous_kernel_us_per_step"],
            "full_wall_s_per_sim_s": full * 1e-6 / b["timestep_s"],
            "full_over_100us_goal": full / 100.0,
        }

    def active_taxels(self, overrides: dict, sites: str | None = None, nstep: int = 20) -> float:
        """Mean count of taxels with pressure over nstep sliding steps (a
        copy of the configuration with the pressure block output; untimed)."""
        ov = dict(overrides)
        outs = ov.get("skin.outputs", "spikes stress force")
        ov["skin.outputs"] = outs + " pressure"
        run, _, _ = self._run(ov, sites, nstep=nstep)
        sd = run.record(nstep)
        p = SkinLayout.from_model(run.model).block(sd, "pressure")
        return float((p > 0).sum(axis=1).mean())

    # knobs --------------------------------------------------------------------
    def knob_rows(self, k: Knob) -> list[dict]:
        """Builds every setting and records its data; errors against the
        reference and the Pareto front come in finish_rows() after timing."""
        c = self.cfg
        settings = k.all_settings()
        sites = None
        if k.sites:
            grids = []
            for ov, _, _ in settings:
                tip = scene_parts(ov)[0]
                grids.append((tip.nx, tip.pitch_m))
            sites = lattice_sites(grids, min(SITE_RADIUS_M, c.extent_m / 2 - 2 * c.pitch_m))
        rows = []
        for ov, own, is_ref in settings:
            tip, proto = scene_parts(ov, sites)
            nstep = c.knob_steps.get(k.name, k.steps)
            if nstep is None:
                nstep = int(round(c.duration_s / proto.timestep_s))
            need = int(round(SKIP_S / proto.timestep_s)) + MIN_WINDOW_STEPS
            if nstep < need:
                raise ValueError(f"knob {k.name!r}: {nstep} steps of {proto.timestep_s} s leave "
                                 f"no error window after the skin's start-up ({SKIP_S} s); "
                                 f"valid: >= {need} steps")
            run, proto, tip = self._run(ov, sites, nstep=nstep)
            layout = SkinLayout.from_model(run.model)
            sd = run.record(nstep)  # the data for the errors, and the warm-up
            nt = min(c.time_steps, nstep)
            if ov.get("skin.pressure") == "elastic":
                nt = min(nt, c.elastic_time_steps)
            row = {
                "knob": k.name, "overrides": dict(ov),
                "setting": k.labels[len(rows)] if k.labels else _label(own),
                "reference": is_ref, "timestep_s": proto.timestep_s,
                "steps": nstep, "timed_steps": nt, "nx": tip.nx, "pitch_m": tip.pitch_m,
                "taxels": tip.nx ** 2, "receptors": int(len(layout.classes)),
                "kernel_build_s": layout.kernel_build_s,
                "stress_basis": "receptor" if k.sites else "class mean",
                "_trace": Trace(layout.block(sd, "stress").copy(),
                                layout.block(sd, "spikes").astype(np.int64),
                                layout.classes, proto.timestep_s),
            }
            self._queue(run, nt, sd[nt - 1].copy(), row)
            if k.name == "pitch":  # for the scaling fit
                row["active_taxels"] = self.active_taxels(ov, sites)
            rows.append(row)
            self._tick(f"{k.name}: {row['setting']}")
        return rows

    @staticmethod
    def finish_rows(rows: list[dict]) -> None:
        for name in dict.fromkeys(r["knob"] for r in rows):
            kr = [r for r in rows if r["knob"] == name]
            ref = kr[-1]["_trace"]
            for r in kr:
                r["wall_s_per_sim_s"] = r["us_per_step"] * 1e-6 / r["timestep_s"]
                r["errors"] = errors(r.pop("_trace"), ref, r["stress_basis"])
            cost = [r["wall_s_per_sim_s"] for r in kr]
            front = pareto_front(cost, [r["errors"]["stress_rms_rel"] for r in kr])
            front_rate = pareto_front(cost, [r["errors"]["spike_rate_rel"] for r in kr])
            for r, f, fr in zip(kr, front, front_rate):
                r["pareto"] = f  # of the stress error (the table's '*')
                r["pareto_spike_rate"] = fr

    # effects ------------------------------------------------------------------
    def effects(self) -> list[dict]:
        c = self.cfg
        grid = {"nx": c.nx, "pitch_m": c.pitch_m}
        out = []
        for group, label, ov in default_effects(c):
            ov = {**grid, **ov}
            elastic = ov.get("skin.pressure") == "elastic"
            nt = min(c.time_steps, c.elastic_time_steps) if elastic else c.time_steps
            run, _, _ = self._run(ov, nstep=nt)
            r = {"group": group, "effect": label, "overrides": ov, "timed_steps": nt,
                 "receptors": int(len(SkinLayout.from_model(run.model).classes)),
                 "sensordata": int(run.model.nsensordata)}
            self._queue(run, nt, run.step(nt)[1], r)  # warm-up
            out.append(r)
            self._tick(f"effect: {label}")
        return out

    @staticmethod
    def finish_effects(out: list[dict]) -> None:
        minimal = next((r["us_per_step"] for r in out if r["group"] == "alone"), None)
        full = next((r["us_per_step"] for r in out if r["group"] == "together"), None)
        for r in out:
            r["over_minimal_us"] = r["us_per_step"] - minimal if minimal is not None else None
            r["over_default_us"] = r["us_per_step"] - full if full is not None else None

    # threads ------------------------------------------------------------------
    def threads(self) -> dict:
        """Wall time of one mujoco.rollout call over threads_batch MjData,
        with 1 and 2 threads (alternating, minimum of repeats)."""
        c = self.cfg
        nb, nt = c.threads_batch, max(10, c.time_steps)
        run, proto, _ = self._run({"nx": c.nx, "pitch_m": c.pitch_m}, nstep=nt)
        states = np.repeat(run.state0[None], nb, axis=0)
        warm = np.repeat(run.warm[None], nb, axis=0)
        state_buf = np.zeros((nb, nt, run.state0.size))
        sd_buf = {n: np.full((nb, nt, run.model.nsensordata), np.nan) for n in (1, 2)}
        pools = {n: mujoco.rollout.Rollout(nthread=n) for n in (1, 2)}
        datas = {n: [mujoco.MjData(run.model) for _ in range(n)] for n in (1, 2)}
        best = {1: math.inf, 2: math.inf}
        try:
            for r in range(c.repeats + 1):
                for n in (1, 2):
                    t0 = time.perf_counter()
                    pools[n].rollout(run.model, datas[n], states, run.ctrl[None, :nt],
                                     initial_warmstart=warm, state=state_buf,
                                     sensordata=sd_buf[n])
                    wall = time.perf_counter() - t0
                    if r:  # the first is the warm-up
                        best[n] = min(best[n], wall)
                self._tick(f"threads: round {r + 1}/{c.repeats + 1}")
        finally:
            for pool in pools.values():
                pool.close()
        return {
            "nbatch": nb, "steps": nt,
            "wall_s_1_thread": best[1], "wall_s_2_thread": best[2],
            "us_per_step_1_thread": best[1] / (nb * nt) * 1e6,
            "us_per_step_2_thread": best[2] / (nb * nt) * 1e6,
            "speedup_2_threads": best[1] / best[2], "cpu_count": os.cpu_count(),
            "identical_across_threads": bool(np.array_equal(sd_buf[1], sd_buf[2])),
        }

    # all ----------------------------------------------------------------------
    def knobs(self) -> list[Knob]:
        ks = default_knobs(self.cfg)
        if self.cfg.knobs:
            ks = [k for k in ks if k.name in self.cfg.knobs]
        return ks

    def count_tasks(self) -> int:
        n = len(self.BASELINES) + self.cfg.repeats
        for k in self.knobs():
            n += len(k.settings) + 1
        if self.cfg.effects:
            n += len(default_effects(self.cfg))
        if self.cfg.threads:
            n += self.cfg.repeats + 1
        return n

    def run(self) -> dict:
        t0 = time.perf_counter()
        load0 = _loadavg()
        base = self.baselines()
        rows = []
        for k in self.knobs():
            rows += self.knob_rows(k)
        effects = self.effects() if self.cfg.effects else None
        self.time_all()
        self.finish_baselines(base)
        self.finish_rows(rows)
        out = {
            "machine": _machine(),
            "config": {k: (list(v) if isinstance(v, tuple) else v)
                       for k, v in dataclasses.asdict(self.cfg).items()},
            "scene": {"texture": "grating", "period_m": self.texture.period_m,
                      "force_n": scenes.Protocol().force_n,
                      "speed_m_s": scenes.Protocol().speed_m_s,
                      "skip_s": SKIP_S, "lead_in_s": LEAD_IN_S,
                      "spectral_min_s": SPECTRAL_MIN_S, "site_spacing_m": SITE_SPACING_M},
            "baselines": base,
            "ratios": self.ratios(base),
            "rows": rows,
        }
        if effects is not None:
            self.finish_effects(effects)
            out["effects"] = effects
            out["profile"] = _profile(base, effects)
        if self.cfg.threads:
            out["threads"] = self.threads()
        out["scaling"] = _scaling(rows, base)
        out["machine"]["loadavg_start"] = load0
        out["machine"]["loadavg_end"] = _loadavg()
        out["machine"]["peak_rss_mb"] = _peak_rss_mb()
        out["wall_s"] = time.perf_counter() - t0
        return out


def _profile(base: dict, effects: list[dict]) -> dict | None:
    """Per-step cost split of the default skin: MuJoCo, stages 1-2 (surface
    and pressure: outputs force only), stages 3-4 (stress and receptors)."""
    full = next((r["us_per_step"] for r in effects if r["group"] == "together"), None)
    force = next((r["us_per_step"] for r in effects if r["effect"].startswith("outputs force")),
                 None)
    if full is None or force is None:
        return None
    bare = base["bare_mujoco_us_per_step"]
    return {"mujoco_us": bare, "surface_pressure_us": force - bare,
            "stress_receptors_us": full - force, "total_us": full}


def _scaling(rows: list[dict], base: dict) -> dict:
    """Plugin cost (step minus the bare step) vs active taxels (pitch knob)
    and vs receptors (receptor knob): log-log exponents and affine fits."""
    bare = base["bare_mujoco_us_per_step"]
    out = {"bare_mujoco_us_per_step": bare}
    pitch = [r for r in rows if r["knob"] == "pitch" and "active_taxels" in r]
    if pitch:
        x = [r["active_taxels"] for r in pitch]
        y = [r["us_per_step"] - bare for r in pitch]
        out["active_taxels"] = {"points": [[a, b] for a, b in zip(x, y)],
                                "power_law": fit_power_law(x, y), "affine": fit_affine(x, y),
                                "grid_taxels": [r["taxels"] for r in pitch],
                                "power_law_vs_grid_taxels":
                                    fit_power_law([r["taxels"] for r in pitch], y)}
    rec = [r for r in rows if r["knob"] == "receptors"]
    if rec:
        x = [r["receptors"] for r in rec]
        y = [r["us_per_step"] - bare for r in rec]
        out["receptors"] = {"points": [[a, b] for a, b in zip(x, y)],
                            "power_law": fit_power_law(x, y), "affine": fit_affine(x, y)}
    return out


def _peak_rss_mb():
    try:
        import resource
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux
    except (ImportError, OSError):
        return None


def _loadavg():
    try:
        return list(os.getloadavg())
    except OSError:
        return None


def _machine() -> dict:
    return {"platform": platform.platform(), "processor": platform.processor(),
            "python": platform.python_version(), "mujoco": mujoco.__version__,
            "cpu_count": os.cpu_count()}


# --- output ------------------------------------------------------------------


def _fmt(v, spec: str, none: str = "-") -> str:
    return none if v is None else format(v, spec)


def print_report(o: dict, stream=None) -> None:
    out = stream or sys.stdout

    def p(s=""):
        print(s, file=out)
    b, r = o["baselines"], o["ratios"]
    m = o["machine"]
    p(f"mjtouch bench: default sliding scene (ridged fingertip, {o['scene']['force_n']:g} N, "
      f"{o['scene']['speed_m_s'] * 1e3:g} mm/s over the {o['scene']['period_m'] * 1e3:g} mm "
      f"grating); {m['cpu_count']} CPUs, load average {_fmt(m.get('loadavg_start') and m['loadavg_start'][0], '.2f')}"
      f" -> {_fmt(m.get('loadavg_end') and m['loadavg_end'][0], '.2f')}; wall {o['wall_s']:.0f} s")
    p()
    p(f"Baselines (us per step, dt = {b['timestep_s']:g} s, {b['taxels']} taxels, "
      f"{b['receptors']} receptors, ~{b['active_taxels']:.0f} taxels in contact)")
    for k, label in [("bare_mujoco", "bare MuJoCo step (no plugin)"),
                     ("native_tactile", f"native tactile sensor, {b['native_tactile_taxels']} taxels"),
                     ("native_tactile_sensors_off", "  same model, sensors disabled"),
                     ("full_pipeline", "full pipeline (default skin)"),
                     ("homogeneous_kernel", "  half-space (homogeneous) kernel"),
                     ("idle_plugin", "idle plugin (finger lifted)"),
                     ("bare_mujoco_idle", "  bare MuJoCo, finger lifted"),
                     ("idle_plugin_rollout", "idle plugin, mujoco.rollout (records state)"),
                     ("bare_mujoco_idle_rollout", "  bare MuJoCo, mujoco.rollout")]:
        p(f"  {label:44s} {b[k + '_us_per_step']:10.2f}")
    p(f"  full / bare {r['full_over_bare']:.1f};  plugin {r['plugin_us_per_step']:.1f} us vs native "
      f"tactile {r['native_tactile_sensor_us_per_step']:.1f} us "
      f"({_fmt(r['plugin_over_native_tactile_sensor'], '.2f')}x, "
      f"{r['native_tactile_ns_per_taxel']:.1f} ns/taxel);  idle over bare "
      f"{r['idle_overhead_pct']:+.1f}% (in rollout {r['idle_rollout_overhead_pct']:+.1f}%);  layered / half-space {r['layered_over_homogeneous']:.2f};  "
      f"{r['full_wall_s_per_sim_s']:.2f} s wall per simulated s ({r['full_over_100us_goal']:.1f}x "
      f"the 100 us goal)")
    p()
    p("Accuracy vs time (errors against each knob's reference, '*' = Pareto front of wall per "
      "simulated s vs stress error, within the knob)")
    hdr = (f"  {'knob':13s} {'setting':40s} {'us/step':>9s} {'s/sim s':>8s} {'stress':>8s} "
           f"{'peak Hz':>8s} {'peak amp':>8s} {'rates':>8s} {'nrec':>5s}")
    p(hdr)
    for row in o["rows"]:
        e = row["errors"]
        pct = lambda v: _fmt(None if v is None else 100 * v, "7.2f") + ("%" if v is not None else " ")
        p(f"{'*' if row['pareto'] else ' '} {row['knob']:13s} "
          f"{(row['setting'] + (' (ref)' if row['reference'] else ''))[:40]:40s} "
          f"{row['us_per_step']:9.1f} {row['wall_s_per_sim_s']:8.2f} {pct(e['stress_rms_rel'])} "
          f"{_fmt(e['peak_freq_hz'], '8.3f')} {pct(e['peak_amp_rel'])} {pct(e['spike_rate_rel'])} "
          f"{row['receptors']:5d}")
    if o.get("effects"):
        p()
        p("Effects: per-step cost of each effect alone (over the minimal skin), all together, and "
          "the default without each")
        for r in o["effects"]:
            p(f"  {r['group']:8s} {r['effect'][:64]:64s} {r['us_per_step']:9.1f} us "
              f"({r['over_minimal_us']:+8.1f} vs minimal, {r['over_default_us']:+8.1f} vs default)")
        if o.get("profile"):
            pr = o["profile"]
            p(f"  profile of the default: MuJoCo {pr['mujoco_us']:.1f} us, surface + pressure "
              f"{pr['surface_pressure_us']:.1f} us, stress + receptors {pr['stress_receptors_us']:.1f} us")
    if o.get("threads"):
        t = o["threads"]
        p()
        p(f"Threads: mujoco.rollout of {t['nbatch']} MjData x {t['steps']} steps: 1 thread "
          f"{t['wall_s_1_thread']:.3f} s, 2 threads {t['wall_s_2_thread']:.3f} s, speedup "
          f"{t['speedup_2_threads']:.2f} on {t['cpu_count']} CPUs (identical results: "
          f"{t['identical_across_threads']})")
    s = o.get("scaling", {})
    p()
    for key, what in (("active_taxels", "active taxels (pitch sweep)"),
                      ("receptors", "receptors (density sweep)")):
        if key in s:
            f, a = s[key]["power_law"], s[key]["affine"]
            p(f"Scaling of the plugin's cost with {what}: exponent {_fmt(f['exponent'], '.2f')} "
              f"(log-log R^2 {_fmt(f['r2'], '.3f')}, {f['n']} points); affine "
              f"{_fmt(a['intercept'], '.1f')} us + {_fmt(a['slope'] and a['slope'] * 1e3, '.2f')} ns "
              f"per unit (R^2 {_fmt(a['r2'], '.3f')})")


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
    for k, style, label in (("bare_mujoco", ":", "bare MuJoCo"),
                            ("native_tactile", "--", "native tactile"),
                            ("full_pipeline", "-", "full pipeline")):
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
        raise SystemExit("--plot needs matplotlib: pip install 'mjtouch[plot]'")
    fig = matplotlib.figure.Figure(figsize=(16, 5.5))
    a, a2, bx = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1, 1, 0.9]})
    _error_panel(a, o, "stress_rms_rel", "relative RMS stress error at receptors", "pareto")
    a.set_title("stress error vs cost (circles: Pareto front; triangles: references)",
                fontsize=9)
    a.legend(fontsize=8)
    _error_panel(a2, o, "spike_rate_rel", "relative spike-rate error (classes summed)",
                 "pareto_spike_rate")
    a2.set_title("spike-rate error vs cost (circles: its Pareto front)", fontsize=9)
    base = o["baselines"]
    labels = ["bare MuJoCo", "native tactile", "full pipeline", "half-space kernel",
              "idle plugin"]
    vals = [base[k + "_us_per_step"] for k in ("bare_mujoco", "native_tactile", "full_pipeline",
                                               "homogeneous_kernel", "idle_plugin")]
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


# --- command line ------------------------------------------------------------


def add_arguments(p) -> None:
    p.add_argument("--quick", action="store_true",
                   help="a tiny sweep on small grids (well under a minute; for CI)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write a PNG: error vs cost, baselines, effects")
    p.add_argument("--save-json", metavar="FILE", help="also write the JSON object to FILE")
    p.add_argument("--from-json", metavar="FILE",
                   help="run nothing: print the table (and --plot) of a saved --save-json FILE")
    p.add_argument("--duration", type=float, default=None,
                   help="sliding seconds per knob row (default 0.25; --quick 0.12)")
    p.add_argument("--time-steps", type=int, default=None,
                   help="steps per timed repeat (default 200; --quick 60)")
    p.add_argument("--repeats", type=int, default=None,
                   help="timing rounds over every configuration; the minimum is reported "
                        "(default 8; --quick 3)")
    p.add_argument("--elastic-steps", type=int, default=None,
                   help="sliding steps of the pressure knob, whose reference is the slow elastic "
                        "model (default 300; --quick 120)")
    p.add_argument("--knob-steps", action="append", default=[], metavar="KNOB=N",
                   help="sliding steps of one knob's rows (repeatable)")
    p.add_argument("--knobs", default=None,
                   help="comma-separated knobs to sweep (default all: pitch, pressure, skin, "
                        "stress_method, receptors, timestep, presets)")
    p.add_argument("--no-effects", action="store_true", help="skip the effects table")
    p.add_argument("--no-threads", action="store_true", help="skip the threads measurement")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def config_from_args(args) -> BenchConfig:
    kw = {}
    for name, attr in (("duration", "duration_s"), ("time_steps", "time_steps"),
                       ("repeats", "repeats"), ("elastic_steps", "elastic_steps")):
        v = getattr(args, name)
        if v is not None:
            kw[attr] = v
    steps = {}
    for item in args.knob_steps:
        name, sep, n = item.partition("=")
        try:
            steps[name.strip()] = int(n)
        except ValueError:
            raise ValueError(f"--knob-steps {item!r} is not KNOB=N with N an integer") from None
        if not sep:
            raise ValueError(f"--knob-steps {item!r} is not KNOB=N")
    kw["knob_steps"] = steps
    if args.knobs:
        kw["knobs"] = tuple(s.strip() for s in args.knobs.split(",") if s.strip())
    kw["effects"] = not args.no_effects
    kw["threads"] = not args.no_threads
    cfg = BenchConfig.quick_config(**kw) if args.quick else BenchConfig(**kw)
    cfg.validate()
    return cfg


def main(args) -> int:
    try:
        cfg = config_from_args(args)
    except ValueError as e:
        print(f"mjtouch bench: error: {e}", file=sys.stderr)
        return 2
    if args.plot:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            print("mjtouch bench: error: --plot needs matplotlib: pip install 'mjtouch[plot]'",
                  file=sys.stderr)
            return 2
    if args.from_json:
        try:
            with open(args.from_json) as f:
                out = json.load(f)
            out["rows"], out["baselines"]  # noqa: B018  (a bench JSON object)
        except (OSError, ValueError, KeyError, TypeError) as e:
            print(f"mjtouch bench: error: --from-json {args.from_json}: not a saved bench "
                  f"result ({e})", file=sys.stderr)
            return 2
    else:
        bench = Bench(cfg)
        bench.progress = Progress(bench.count_tasks(), enabled=not args.no_progress)
        out = bench.run()
        bench.progress.close()
    if args.plot:
        plot(out, args.plot)
        out["plot"] = args.plot
    text = json.dumps(out, allow_nan=False)
    if args.save_json:
        with open(args.save_json, "w") as f:
            f.write(text + "\n")
    if args.json:
        print(text)
    else:
        print_report(out)
    return 0
