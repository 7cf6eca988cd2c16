"""A tangential ramp on a pressed fingertip: feeling slip coming.

The fingertip pad is pressed on a plate at a constant normal force P (a
motor on a slide joint) while a second motor ramps the tangential force Q
from zero past mu P, so the pad first sticks, then slips at its rim while its
centre sticks (partial slip), then slides (gross slip: Q reaches mu P and the
finger accelerates away). The skin runs ``shear="partial"``: its stick / slip
map follows Cattaneo-Mindlin (stuck share of the contact area
(1 - Q / mu P)^(2k), k = 1/4 on a Winkler skin, 1/3 on a half-space), and its
receptors see the partial-slip tractions. Humans feel this coming: the
afferents fire before the object moves (Johansson & Westling 1987; Barrea et
al. 2018: felt when about half the area slips; Delhaye et al. 2021). Here RA
(FA I) rises as the slip ring grows (with uniform full-slip shear it does
not), SA1 rises with the load, and PC answers the slip's onset.

:func:`run` returns, per physics step, Q / mu P (MuJoCo's contact force as the
skin reports it), the stuck share, the spike count of each class, and the
gross-slip time, detected from the finger's motion over the plate::

    from mjtouch.experiments import slip_ramp
    out = slip_ramp.run(slip_ramp.SlipRampParams(normal_force_n=2.0))
    out.q_over_mu_p, out.stuck_share, out.spikes["RA"], out.gross_slip_s
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from mjtouch._validate import in_range
from mjtouch.scene import scenes
from mjtouch.scene.sensor import CLASSES, SkinLayout

# Cattaneo-Mindlin stick radius c/a = (1 - Q / mu P)^k per skin model
# (Winkler: parabolic pressure on uniform tangential springs; half-space: Hertz).
STICK_RADIUS_EXPONENT = {"winkler": 0.25, "elastic": 1.0 / 3.0}
PAD_FRICTION = 0.1  # below the plate's: MuJoCo takes the larger, the plate's
# Windows of the ramp, in Q / mu P: stick-dominated (Cattaneo's stuck share
# >= 0.8 on a Winkler skin) and around half the area slipping (0.63 to 0.45).
STICK_WINDOW = (0.1, 0.35)
HALF_SLIP_WINDOW = (0.6, 0.8)
ONSET_HALF_WIDTH_S = 0.01  # slip onset window: gross slip +- this


@dataclasses.dataclass(frozen=True)
class SlipRampParams:
    """A press, then a tangential force ramp past the friction limit."""

    normal_force_n: float = 2.0  # P, held constant
    friction: float = 1.0  # the plate's mu (the contact's: the pad's is lower)
    ramp_s: float = 0.6  # Q rises from 0 to overshoot x mu P over this time
    overshoot: float = 1.2  # the ramp's end, in units of mu P
    press_s: float = 0.2  # pressing and settling before the ramp
    texture: str = "flat"  # "flat" or "grating" (ridges across the ramp)
    grating_period_m: float = 1.5e-3
    grating_height_m: float = 5e-5
    timestep_s: float = 5e-4
    nx: int = 64
    pitch_m: float = 2.5e-4
    pressure: str = "winkler"  # the skin's contact model: winkler or elastic
    # winkler: foundation stiffness, Pa/m (the skin's default: a contact 9-13 mm
    # across at 1-4 N, as a human fingertip's)
    stiffness_pa_per_m: float = 2e7
    young_pa: float = 1e6  # elastic (half-space): Young's modulus
    shear: str = "partial"  # the skin's `shear`: partial, or true (uniform full slip)
    # the finger counts as sliding above this speed over the plate (MuJoCo's
    # soft contact creeps below the friction limit, here at up to ~0.9 mm/s)
    slip_speed_m_s: float = 2e-3
    after_slip_s: float = 0.06  # the run ends this long after gross slip
    seed: int = 0

    def validate(self) -> None:
        in_range("normal_force_n", self.normal_force_n, 0.05, 20.0, "N")
        in_range("friction", self.friction, 2 * PAD_FRICTION, 3.0)
        in_range("ramp_s", self.ramp_s, 0.01, 20.0, "s")
        in_range("overshoot", self.overshoot, 1.0, 3.0)
        in_range("press_s", self.press_s, 0.05, 5.0, "s")
        if self.texture not in ("flat", "grating"):
            raise ValueError(f"texture = {self.texture!r} is not one of 'flat', 'grating'")
        in_range("grating_period_m", self.grating_period_m, 2e-4, 1e-2, "m")
        in_range("grating_height_m", self.grating_height_m, 1e-6, 1e-3, "m")
        in_range("timestep_s", self.timestep_s, 1e-5, 2e-3, "s")
        in_range("nx", self.nx, 16, 256)
        in_range("pitch_m", self.pitch_m, 5e-5, 1e-3, "m")
        if self.pressure not in STICK_RADIUS_EXPONENT:
            raise ValueError(
                f"pressure = {self.pressure!r} is not one of {sorted(STICK_RADIUS_EXPONENT)}"
            )
        if self.shear not in ("partial", "true"):
            raise ValueError(f"shear = {self.shear!r} is not one of 'partial', 'true'")
        in_range("stiffness_pa_per_m", self.stiffness_pa_per_m, 1e5, 1e12, "Pa/m")
        in_range("young_pa", self.young_pa, 100.0, 1e10, "Pa")
        in_range("slip_speed_m_s", self.slip_speed_m_s, 1e-4, 1.0, "m/s")
        in_range("after_slip_s", self.after_slip_s, 2 * ONSET_HALF_WIDTH_S, 10.0, "s")


@dataclasses.dataclass
class SlipRampResult:
    params: SlipRampParams
    layout: SkinLayout
    time_s: np.ndarray  # (n,) from the ramp's start (negative while pressing)
    q_over_mu_p: np.ndarray  # (n,) |F_t| / (mu F_n), the skin's force block
    stuck_share: np.ndarray  # (n,) stuck share of the loaded cells (1 unloaded; NaN: full slip)
    spikes: dict[str, np.ndarray]  # class -> (n,) spike count of the class in the step
    receptors: dict[str, int]  # class -> receptor count
    finger_x_m: np.ndarray  # (n,) finger displacement along the ramp from the ramp's start
    finger_speed_m_s: np.ndarray  # (n,)
    gross_slip_s: float  # first time the finger slides faster than slip_speed_m_s
    sensordata: np.ndarray  # (n, nsensordata)

    def oracle_stuck_share(self) -> np.ndarray:
        """Cattaneo-Mindlin's stuck share (1 - Q / mu P)^(2k) at each step."""
        k = STICK_RADIUS_EXPONENT[self.params.pressure]
        return np.clip(1.0 - self.q_over_mu_p, 0.0, 1.0) ** (2 * k)

    def rate_hz(self, cls: str, start_s: float, stop_s: float) -> float:
        """Mean firing rate per receptor of class cls over [start_s, stop_s)."""
        sel = (self.time_s >= start_s) & (self.time_s < stop_s)
        if not sel.any():
            raise ValueError(f"no steps in [{start_s}, {stop_s}) s")
        dt = self.params.timestep_s
        return float(self.spikes[cls][sel].sum() / (self.receptors[cls] * sel.sum() * dt))

    def window_s(self, q_window: tuple[float, float]) -> tuple[float, float]:
        """The ramp's times [start, stop) where Q / mu P crosses the window's ends."""
        return self.time_at(q_window[0]), self.time_at(q_window[1])

    def summary(self) -> dict:
        """Rates per receptor (Hz) of each class in the stick-dominated and the
        half-slip windows and around gross slip (+- ONSET_HALF_WIDTH_S), and
        how long before gross slip the half-slip window ends (s)."""
        stick, half = self.window_s(STICK_WINDOW), self.window_s(HALF_SLIP_WINDOW)
        g = self.gross_slip_s
        onset = (g - ONSET_HALF_WIDTH_S, g + ONSET_HALF_WIDTH_S)
        return {
            "stick_hz": {c: self.rate_hz(c, *stick) for c in CLASSES},
            "half_slip_hz": {c: self.rate_hz(c, *half) for c in CLASSES},
            "onset_hz": {c: self.rate_hz(c, *onset) for c in CLASSES},
            "half_slip_lead_s": g - half[1],
        }

    def time_at(self, q_over_mu_p: float) -> float:
        """First time on the ramp the load reaches q_over_mu_p."""
        on = np.flatnonzero((self.time_s >= 0) & (self.q_over_mu_p >= q_over_mu_p))
        if not len(on):
            raise ValueError(f"the load never reaches Q / mu P = {q_over_mu_p}")
        return float(self.time_s[on[0]])


def winkler_stuck_share(pressure_pa: np.ndarray, q_over_mu_p: float) -> float:
    """The stuck share of a Winkler skin loaded monotonically from zero, for any
    pressure map: each cell's traction is min(k s, mu p) (uniform tangential
    springs at the rigid shift s, clamped by Coulomb), their sum is Q, and a
    cell sticks while k s < mu p. On a parabolic pressure this is Cattaneo's
    (1 - Q / mu P)^(1/2)."""
    p = np.asarray(pressure_pa, dtype=np.float64).ravel()
    p = p[p > 0]
    if not len(p):
        raise ValueError("the pressure map has no loaded cell")
    if not 0.0 <= q_over_mu_p < 1.0:
        raise ValueError(f"q_over_mu_p = {q_over_mu_p} must be in [0, 1)")
    target = q_over_mu_p * p.sum()
    lo, hi = 0.0, float(p.max())  # k s / mu, bisected: sum min(., p) rises with it
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if np.minimum(mid, p).sum() < target else (lo, mid)
    return float(np.count_nonzero(p > hi) / len(p))


def ramp_spec(p: SlipRampParams) -> mujoco.MjSpec:
    """The pad (Fingertip semi-axes) on slide joints x and z over a plate."""
    tip = scenes.Fingertip()
    a, b, c = tip.semi_axes_m
    q = scenes.quantize_all
    spec = mujoco.MjSpec()
    spec.modelname = "mjtouch_slip_ramp"
    spec.option.timestep = scenes.quantize(p.timestep_s)
    spec.option.gravity = [0, 0, 0]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    # stiff friction: the held pad creeps < 1 mm/s below the friction limit
    spec.option.impratio = 100
    world = spec.worldbody
    world.add_geom(
        name="plate",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.04, 0.02, 0.002],
        pos=[0, 0, -0.002],
        friction=[scenes.quantize(p.friction), 0.005, 0.0001],
    )
    if p.texture == "grating":
        tex = scenes.Texture(
            period_m=p.grating_period_m,
            height_m=p.grating_height_m,
            edge_m=min(5e-5, p.grating_period_m / 8),
            length_m=0.08,
            resolution_m=min(5e-5, p.grating_period_m / 12),
        )
        scenes.add_grating_hfield(spec, "texture", tex, 0.02)
        world.add_geom(
            name="texture",
            type=mujoco.mjtGeom.mjGEOM_HFIELD,
            hfieldname="texture",
            contype=0,
            conaffinity=0,
            group=scenes.TEXTURE_GROUP,
        )
    finger = world.add_body(name="finger", pos=q(0, 0, c + 1e-4))
    for name, axis in (("x", [1, 0, 0]), ("z", [0, 0, 1])):
        finger.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
    finger.add_geom(
        name="pad",
        type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        size=q(a, b, c),
        mass=scenes.quantize(tip.mass_kg),
        friction=[PAD_FRICTION, 0.005, 0.0001],
        solref=[0.004, 1],
    )
    for joint in ("x", "z"):
        spec.add_actuator(
            name=joint, target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT, gear=[1, 0, 0, 0, 0, 0]
        )
    cfg = {
        "nx": str(p.nx),
        "pitch": scenes.fmt_number(p.pitch_m),
        "ridges": "false",
        "pressure": p.pressure,
        "shear": p.shear,
        "outputs": "spikes force pressure stick slip" if p.shear == "partial" else "spikes force",
        "seed": str(p.seed),
        "texture_group": str(scenes.TEXTURE_GROUP),
    }
    if p.pressure == "elastic":
        cfg.update(skin="halfspace", young=scenes.fmt_number(p.young_pa))
    else:
        cfg.update(stiffness=scenes.fmt_number(p.stiffness_pa_per_m))
    scenes.add_skin_sensor(spec, "pad", cfg)
    return spec


def controls(p: SlipRampParams) -> np.ndarray:
    """ctrl per step (x force, z force): pressed at P, then Q ramped to overshoot x mu P."""
    n_press = round(p.press_s / p.timestep_s)
    n_ramp = round(p.ramp_s / p.timestep_s)
    ctrl = np.zeros((n_press + n_ramp, 2))
    ctrl[:, 1] = -p.normal_force_n
    ctrl[n_press:, 0] = (
        np.arange(1, n_ramp + 1) / n_ramp * p.overshoot * p.friction * p.normal_force_n
    )
    return ctrl


def run(p: SlipRampParams | None = None) -> SlipRampResult:
    """Press, ramp, and read the skin (see the module docstring)."""
    p = p or SlipRampParams()
    p.validate()
    m = ramp_spec(p).compile()
    d = mujoco.MjData(m)
    lay = SkinLayout.from_model(m)
    ctrl = controls(p)
    n = len(ctrl)
    n_press = round(p.press_s / p.timestep_s)
    sd = np.empty((n, m.nsensordata))
    x = np.empty(n)
    v = np.empty(n)
    jx = m.joint("x").id
    stop = n
    for k in range(n):
        d.ctrl[:] = ctrl[k]
        mujoco.mj_step(m, d)
        sd[k] = d.sensordata
        x[k] = d.qpos[m.jnt_qposadr[jx]]
        v[k] = d.qvel[m.jnt_dofadr[jx]]
        if stop == n and k >= n_press and v[k] > p.slip_speed_m_s:
            stop = min(n, k + 1 + round(p.after_slip_s / p.timestep_s))
        if k + 1 >= stop:
            break
    n = stop
    sd, x, v = sd[:n], x[:n], v[:n]
    t = (np.arange(n) + 1 - n_press) * p.timestep_s
    force = lay.block(sd, "force")
    touching = force[:, 0] > 0
    mu_p = scenes.quantize(p.friction) * np.where(touching, force[:, 0], 1.0)
    ratio = np.where(touching, np.hypot(force[:, 1], force[:, 2]) / mu_p, 0.0)
    if p.shear == "partial":
        share = np.where(touching & (ratio > 0), lay.block(sd, "slip")[:, 0], 1.0)
    else:  # no stick map: uniform full slip
        share = np.full(n, np.nan)
    spikes_rec = lay.block(sd, "spikes")
    spikes = {c: spikes_rec[:, lay.mask(c)].sum(axis=1) for c in CLASSES}
    receptors = {c: int(lay.mask(c).sum()) for c in CLASSES}
    sliding = np.flatnonzero((t >= 0) & (v > p.slip_speed_m_s))
    gross = float(t[sliding[0]]) if len(sliding) else float("nan")
    return SlipRampResult(
        params=p,
        layout=lay,
        time_s=t,
        q_over_mu_p=ratio,
        stuck_share=share,
        spikes=spikes,
        receptors=receptors,
        finger_x_m=x - x[n_press - 1],
        finger_speed_m_s=v,
        gross_slip_s=gross,
        sensordata=sd,
    )
