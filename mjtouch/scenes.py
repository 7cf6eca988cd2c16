"""MJCF builders: the ridged fingertip, textured plates and sliding scenes.

The fingertip is a smooth ellipsoid pad that MuJoCo collides with a flat,
colliding plate proxy; MuJoCo supplies the motion and the total contact force.
The fine texture is a non-colliding height field (``contype=0``) that only
the ``mjtouch.skin`` plugin renders against, so a fine texture costs nothing in
MuJoCo's collision (a colliding fine height field costs ~3 ms per step).
The skin's fingerprint ridges are rendered by the plugin too.

``write_models(dir)`` regenerates the committed files in ``models/``; a test
checks they are in sync with these builders.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
from typing import Literal

import mujoco
import numpy as np

from mjtouch import textures

TextureKind = Literal["grating", "random", "dots", "flat"]


@dataclasses.dataclass
class Fingertip:
    """Human index fingertip pad (Shao et al. 2010: 20 x 14 mm ellipse)."""

    semi_axes_m: tuple[float, float, float] = (0.008, 0.007, 0.007)
    mass_kg: float = 0.02
    ridges: bool = True
    ridge_pitch_m: float = 0.45e-3  # Shao et al. 2010
    ridge_height_m: float = 0.05e-3  # Shao et al. 2010 (ridge relief)
    ridge_angle_deg: float = 0.0  # 0: ridges perpendicular to sliding (x)
    nx: int = 128  # taxels per side
    pitch_m: float = 1e-4  # taxel pitch: 4.5 taxels per ridge
    friction: float = 0.5
    # Any further mjtouch.skin attributes (key -> value string).
    skin: dict[str, str] = dataclasses.field(default_factory=dict)

    def validate(self) -> None:
        _positive("semi_axes_m", *self.semi_axes_m)
        _positive("mass_kg", self.mass_kg)
        _positive("ridge_pitch_m", self.ridge_pitch_m)
        _positive("ridge_height_m", self.ridge_height_m)
        _positive("pitch_m", self.pitch_m)
        if not (4 <= int(self.nx) <= 512):
            raise ValueError(f"nx = {self.nx} is out of range; valid range [4, 512]")
        if not 0 <= self.friction <= 10:
            raise ValueError(f"friction = {self.friction} is out of range; valid range [0, 10]")


@dataclasses.dataclass
class Texture:
    """A plate texture (see :mod:`mjtouch.textures`).

    - ``grating``: raised plateaux of width ``plateau_m`` every ``period_m``
      along x, ``height_m`` tall, edges rounded over ``edge_m``;
    - ``random``: isotropic Gaussian roughness of RMS height ``rms_m`` and
      Gaussian correlation length ``corr_length_m`` (seeded by ``seed``);
    - ``dots``: hexagonal array of spherical-cap dots (``dot_spacing_m``,
      ``dot_radius_m``, ``height_m``);
    - ``flat``: no texture.
    Gratings are 1D (a 2-row height field, inline in MJCF); random and dot
    textures are 2D height fields set through MjSpec (:func:`build_model`)."""

    kind: TextureKind = "grating"
    period_m: float = 1.0e-3
    plateau_m: float | None = None  # default: half the period
    height_m: float = 0.1e-3
    edge_m: float = 0.05e-3
    length_m: float = 0.08
    width_m: float = 0.03
    resolution_m: float = 2e-5  # height-field sample spacing
    rms_m: float = 20e-6
    corr_length_m: float = 100e-6
    dot_spacing_m: float = 2.5e-3
    dot_radius_m: float = 0.6e-3
    seed: int = 0

    def validate(self) -> None:
        if self.kind not in ("grating", "flat", "random", "dots"):
            raise ValueError(f"texture kind {self.kind!r} is not one of "
                             "'grating', 'random', 'dots', 'flat'")
        _positive("height_m", self.height_m)
        _positive("length_m", self.length_m)
        _positive("width_m", self.width_m)
        _positive("resolution_m", self.resolution_m)
        if self.kind == "grating":
            _positive("period_m", self.period_m)
            plateau = self.plateau
            if not 0 < plateau < self.period_m:
                raise ValueError(f"plateau_m = {plateau} is out of range; valid range "
                                 f"(0, period_m = {self.period_m})")
            if not 0 <= self.edge_m <= min(plateau, self.period_m - plateau) / 2:
                raise ValueError(f"edge_m = {self.edge_m} is out of range; valid range "
                                 f"[0, {min(plateau, self.period_m - plateau) / 2}]")
            if self.period_m < 4 * self.resolution_m:
                raise ValueError(f"period_m = {self.period_m} needs at least 4 height-field "
                                 f"samples; lower resolution_m (now {self.resolution_m})")
        if self.kind == "random":
            _positive("rms_m", self.rms_m)
            _positive("corr_length_m", self.corr_length_m)
        if self.kind == "dots":
            _positive("dot_spacing_m", self.dot_spacing_m)
            _positive("dot_radius_m", self.dot_radius_m)
        if self.kind != "flat" and self.nrow * self.ncol > 8_000_000:
            raise ValueError(f"texture needs {self.nrow} x {self.ncol} height-field samples; "
                             "valid up to 8e6 (shrink the plate or coarsen resolution_m)")

    @property
    def plateau(self) -> float:
        return self.period_m / 2 if self.plateau_m is None else self.plateau_m

    @property
    def ncol(self) -> int:
        return int(round(self.length_m / self.resolution_m)) + 1

    @property
    def nrow(self) -> int:
        if self.kind in ("grating", "flat"):
            return 2
        return int(round(self.width_m / self.resolution_m)) + 1

    def profile(self, x_m: np.ndarray) -> np.ndarray:
        """Height (m) along x of a grating: plateaux centred on x = k * period."""
        if self.kind == "flat":
            return np.zeros_like(x_m)
        if self.kind != "grating":
            raise ValueError("profile() is for gratings; use heights()")
        return textures.grating(x_m, self.period_m, self.plateau, self.height_m, self.edge_m)

    def heights(self) -> np.ndarray:
        """Height map (m), nrow x ncol, MuJoCo height-field order."""
        x = np.linspace(-self.length_m / 2, self.length_m / 2, self.ncol)
        if self.kind in ("grating", "flat"):
            return np.tile(self.profile(x), (2, 1))
        if self.kind == "random":
            h = textures.random_rough(self.nrow, self.ncol, self.resolution_m, self.rms_m,
                                      corr_length_m=self.corr_length_m, seed=self.seed)
            return h - h.min()
        y = np.linspace(-self.width_m / 2, self.width_m / 2, self.nrow)
        return textures.dots(x, y, self.dot_spacing_m, self.dot_radius_m, self.height_m)


@dataclasses.dataclass
class Protocol:
    """Press, hold, then slide at a set speed along +x. ``control="force"``
    (default) presses with ``force_n`` (a motor); ``control="displacement"``
    drives the pad's pole ``depth_m`` below the plate's top (a stiff,
    critically damped position servo), the force then being MuJoCo's contact
    force at that penetration (its soft-contact impedance, not the skin's
    layers: see README, Wang 2016)."""

    force_n: float = 0.5
    speed_m_s: float = 0.025
    press_s: float = 0.15  # press and settle before sliding
    timestep_s: float = 1e-4
    control: Literal["force", "displacement"] = "force"
    depth_m: float = 1e-3  # displacement control: the pole's depth below the plate top

    def validate(self) -> None:
        if self.control not in ("force", "displacement"):
            raise ValueError(f"control = {self.control!r} is not one of 'force', 'displacement'")
        if self.control == "displacement" and not 0 < self.depth_m <= 5e-3:
            raise ValueError(f"depth_m = {self.depth_m} is out of range; valid range (0, 5e-3] m")
        if not 0 < self.force_n <= 100:
            raise ValueError(f"force_n = {self.force_n} is out of range; valid range (0, 100] N")
        if not 0 <= self.speed_m_s <= 2:
            raise ValueError(f"speed_m_s = {self.speed_m_s} is out of range; valid range [0, 2] m/s")
        if not 1e-6 <= self.timestep_s <= 5e-3:
            raise ValueError(f"timestep_s = {self.timestep_s} is out of range; valid [1e-6, 5e-3] s")
        if not 0.02 <= self.press_s <= 10:
            raise ValueError(f"press_s = {self.press_s} is out of range; valid [0.02, 10] s")


def _positive(name: str, *values: float) -> None:
    for v in values:
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} = {v!r} must be a positive finite number")


def _fmt(x: float) -> str:
    return f"{x:.9g}"


# MuJoCo contact of the pad (with anything). A stiff impedance (solimp
# 0.95-0.99) makes MuJoCo's elliptic friction cone inflate the normal force
# while sliding: the pad chatters at 100-600 Hz and lifts off (0.08 N rms at
# 40 mm/s, measured).
CONTACT_SOLREF = "0.01 1"
CONTACT_SOLIMP = "0.5 0.9 0.001"
# Pad-plate pair: impedance rising from 0.5 to 0.9999 over 4 mm stiffens like
# a fingertip (~1.6 mm at 0.5 N, ~3 mm at 50 N) and never lets the pad through.
PAIR_SOLIMP = "0.5 0.9999 0.004 0.5 2"
# Soft constraints make friction rate dependent: its reference acceleration
# grows as slip speed / solreffriction time constant. Too stiff for the slip
# speed and the cone inflates the normal force (chatter, lift-off); too soft
# and friction stays below mu * F_n (viscous). tau_f = 5 m V / F_n puts the
# friction demand just past saturation: Coulomb friction (F_t = mu F_n) with
# a steady normal force from 10 mm/s to 1 m/s and 0.05 to 50 N (measured:
# tests/test_hard_cases.py).
FRICTION_TAU_PER_MV_F = 5.0
SLIDE_KP = 2e4  # N/m, sliding servo stiffness


def friction_timeconst(tip: "Fingertip", protocol: "Protocol") -> float:
    """solreffriction time constant (s) for sliding at protocol speed/force."""
    tau = FRICTION_TAU_PER_MV_F * tip.mass_kg * protocol.speed_m_s / protocol.force_n
    return max(tau, 2 * protocol.timestep_s)

# Non-colliding geoms in this group are textures that the skin renders.
TEXTURE_GROUP = 3


def skin_config(tip: Fingertip) -> dict[str, str]:
    cfg = {
        "nx": str(int(tip.nx)),
        "pitch": _fmt(tip.pitch_m),
        "ridges": "true" if tip.ridges else "false",
        "ridge_pitch": _fmt(tip.ridge_pitch_m),
        "ridge_height": _fmt(tip.ridge_height_m),
        "ridge_angle": _fmt(tip.ridge_angle_deg),
    }
    cfg["texture_group"] = str(TEXTURE_GROUP)
    cfg.update(tip.skin)
    return cfg


@dataclasses.dataclass
class Fragment:
    """Pieces of MJCF that a part contributes to each top-level section."""

    extension: str = ""
    asset: str = ""
    worldbody: str = ""
    actuator: str = ""
    sensor: str = ""
    contact: str = ""

    def standalone(self, model_name: str) -> str:
        """The part as its own file, for <include>."""
        return _document(model_name, [self])


# Where the fingertip starts: above the plate's left quarter, so a slide of up
# to half the plate's length stays on the texture.
def _start_x(texture_length_m: float) -> float:
    return -texture_length_m / 4


PRESS_KP = 2e3  # N/m, the displacement-control servo (critically damped by kv)
PAD_CLEARANCE_M = 3e-4  # the pad's pole starts this far above the plate


def fingertip_fragment(tip: Fingertip, start_x_m: float = -0.02,
                       travel_m: float = 0.04, control: str = "force") -> Fragment:
    """The fingertip: slide joints in x (sliding) and z (pressing), the pad
    geom, its actuators and the skin sensor plugin instance. The `press`
    actuator is a motor (ctrl = -force, N) or, for control="displacement", a
    position servo on press_z (ctrl = the joint's target, m; the pole's depth
    below the plate top is -ctrl - PAD_CLEARANCE_M)."""
    tip.validate()
    a, b, c = tip.semi_axes_m
    z0 = c + PAD_CLEARANCE_M
    cfg = skin_config(tip)
    slide_damping = 2 * math.sqrt(SLIDE_KP * tip.mass_kg)
    config = "\n".join(f'        <config key="{k}" value="{v}"/>' for k, v in cfg.items())
    if control == "displacement":
        kv = 2 * math.sqrt(PRESS_KP * tip.mass_kg)
        press = (f'    <position name="press" joint="press_z" kp="{_fmt(PRESS_KP)}" '
                 f'kv="{_fmt(kv)}" ctrlrange="-0.01 0.01"/>\n')
    elif control == "force":
        press = '    <motor name="press" joint="press_z" ctrlrange="-100 100"/>\n'
    else:
        raise ValueError(f"control = {control!r} is not one of 'force', 'displacement'")
    return Fragment(
        extension='    <plugin plugin="mjtouch.skin"/>\n',
        worldbody=f"""    <body name="finger" pos="{_fmt(start_x_m)} 0 {_fmt(z0)}" gravcomp="1">
      <joint name="slide_x" type="slide" axis="1 0 0" damping="{_fmt(slide_damping)}"/>
      <joint name="press_z" type="slide" axis="0 0 1" damping="2"/>
      <geom name="pad" type="ellipsoid" size="{_fmt(a)} {_fmt(b)} {_fmt(c)}" mass="{_fmt(tip.mass_kg)}"
            friction="{_fmt(tip.friction)} 0.005 0.0001" solref="{CONTACT_SOLREF}" solimp="{CONTACT_SOLIMP}"
            rgba="0.93 0.72 0.62 1"/>
    </body>
""",
        # intvelocity: ctrl is the sliding speed (m/s), integrated into a
        # position setpoint, so the mean speed is exact despite friction;
        # stiff and critically damped (joint damping) so it does not ring.
        actuator=f"""    <intvelocity name="slide" joint="slide_x" kp="{_fmt(SLIDE_KP)}" actrange="{_fmt(-travel_m)} {_fmt(travel_m)}" ctrlrange="-2 2"/>
{press}""",
        sensor=f"""    <plugin name="skin" plugin="mjtouch.skin" objtype="geom" objname="pad">
{config}
    </plugin>
""")


def plate_fragment(texture: Texture) -> Fragment:
    """A plate: a colliding flat box proxy (MuJoCo's contact) and a
    non-colliding geom named ``texture`` that the skin renders against.
    2D textures declare the height field without data: :func:`build_model`
    fills it."""
    texture.validate()
    L, W = texture.length_m, texture.width_m
    # 1 cm thick: a hard press (50 N) sinks ~3 mm into MuJoCo's soft contact
    proxy = (f'    <geom name="plate" type="box" size="{_fmt(L / 2)} {_fmt(W / 2)} 0.01" '
             f'pos="0 0 -0.01" friction="0.5 0.005 0.0001" rgba="0.55 0.6 0.65 1"/>\n')
    if texture.kind == "flat":
        return Fragment(worldbody=proxy + (
            f'    <geom name="texture" type="box" size="{_fmt(L / 2)} {_fmt(W / 2)} 0.01" '
            f'pos="0 0 -0.01" contype="0" conaffinity="0" group="{TEXTURE_GROUP}" rgba="0 0 0 0"/>\n'))
    relief = _relief(texture)
    data = ""
    if texture.nrow == 2:
        h = texture.heights()
        data = ("\n            elevation=\"" + " ".join(f"{v:.4g}" for v in (h / relief).ravel())
                + "\"")
    asset = (f'    <hfield name="texture" nrow="{texture.nrow}" ncol="{texture.ncol}" '
             f'size="{_fmt(L / 2)} {_fmt(W / 2)} {_fmt(relief)} 0.001"{data}/>\n')
    body = proxy + ('    <geom name="texture" type="hfield" hfield="texture" contype="0" '
                    f'conaffinity="0" group="{TEXTURE_GROUP}" rgba="0.45 0.5 0.55 1"/>\n')
    return Fragment(asset=asset, worldbody=body)


def _relief(texture: Texture) -> float:
    """Peak-to-valley height of the texture (the height field's elevation)."""
    if texture.kind in ("grating", "dots"):
        return texture.height_m
    h = texture.heights()
    return float(h.max() - h.min())


def build_model(tip: Fingertip | None = None, texture: Texture | None = None,
                protocol: Protocol | None = None) -> mujoco.MjModel:
    """Compile a scene; 2D textures' height data are set through MjSpec
    (a million-sample height field does not belong in XML text)."""
    texture = texture or Texture()
    xml = scene_xml(tip, texture, protocol)
    if texture.kind == "flat" or texture.nrow == 2:
        return mujoco.MjModel.from_xml_string(xml)
    spec = mujoco.MjSpec.from_string(xml)
    h = texture.heights()
    spec.hfields[0].userdata = (h.ravel() / (h.max() - h.min())).tolist()
    return spec.compile()


def _options(protocol: Protocol) -> str:
    return (f'  <option timestep="{_fmt(protocol.timestep_s)}" integrator="implicitfast" '
            'cone="elliptic"/>\n')


def _document(model_name: str, parts: list[Fragment], head: str = "",
              includes: list[str] = ()) -> str:
    out = [f'<mujoco model="{model_name}">\n']
    out += [f'  <include file="{f}"/>\n' for f in includes]
    out.append(head)
    for section in ("extension", "asset", "worldbody", "contact", "actuator", "sensor"):
        body = "".join(getattr(p, section) for p in parts)
        if section == "worldbody" and head:
            body = '    <light pos="0 0 0.3" dir="0 0 -1"/>\n' + body
        if body:
            out.append(f"  <{section}>\n{body}  </{section}>\n")
    out.append("</mujoco>\n")
    return "".join(out)


def scene_xml(tip: Fingertip | None = None, texture: Texture | None = None,
              protocol: Protocol | None = None, model_name: str = "mjtouch_slide") -> str:
    """A complete single-file MJCF scene: fingertip over a plate."""
    tip = tip or Fingertip()
    texture = texture or Texture()
    protocol = protocol or Protocol()
    protocol.validate()
    parts = [plate_fragment(texture),
             fingertip_fragment(tip, _start_x(texture.length_m), texture.length_m,
                                protocol.control),
             pad_plate_contact(tip, protocol)]
    return _document(model_name, parts, head=_options(protocol))


def pad_plate_contact(tip: Fingertip, protocol: Protocol) -> Fragment:
    """The pad-plate contact pair, its friction tuned to the protocol."""
    mu = _fmt(tip.friction)
    return Fragment(contact=(
        f'    <pair geom1="pad" geom2="plate" condim="3" friction="{mu} {mu} 0.005 0.0001 0.0001"\n'
        f'          solref="{CONTACT_SOLREF}" solimp="{PAIR_SOLIMP}" '
        f'solreffriction="{_fmt(friction_timeconst(tip, protocol))} 1"/>\n'))


def controls(protocol: Protocol, duration_s: float) -> np.ndarray:
    """Open-loop controls (nstep x 2: slide speed, press) for press then
    slide; press is -force (N) or, under displacement control, the press
    joint's target (m)."""
    n_press = int(round(protocol.press_s / protocol.timestep_s))
    n_slide = int(round(duration_s / protocol.timestep_s))
    ctrl = np.zeros((n_press + n_slide, 2))
    if protocol.control == "displacement":
        ctrl[:, 1] = -(protocol.depth_m + PAD_CLEARANCE_M)
    else:
        ctrl[:, 1] = -protocol.force_n
    ctrl[n_press:, 0] = protocol.speed_m_s
    return ctrl


def sphere_press_xml(radius_m: float, skin: dict[str, str], timestep_s: float = 1e-3) -> str:
    """A rigid-plate oracle scene: a sphere pad (the skin) on a slide joint,
    pushed down onto a flat box plate by the motor `press` (ctrl = force, N),
    no gravity. The Hertz set-up of mjtouch.oracles."""
    _positive("radius_m", radius_m)
    conf = "".join(f'<config key="{k}" value="{v}"/>' for k, v in skin.items())
    return f"""<mujoco model="sphere_press">
  <extension><plugin plugin="mjtouch.skin"/></extension>
  <option timestep="{_fmt(timestep_s)}" gravity="0 0 0"/>
  <worldbody>
    <geom name="plate" type="box" size="0.05 0.05 0.002" pos="0 0 -0.002"/>
    <body name="finger" pos="0 0 {_fmt(radius_m)}">
      <joint name="press_z" type="slide" axis="0 0 1" damping="5"/>
      <geom name="pad" type="sphere" size="{_fmt(radius_m)}" mass="0.01" solref="0.01 1"/>
    </body>
  </worldbody>
  <actuator><motor name="press" joint="press_z" gear="-1"/></actuator>
  <sensor>
    <plugin name="skin" plugin="mjtouch.skin" objtype="geom" objname="pad">{conf}</plugin>
  </sensor>
</mujoco>
"""


def write_models(directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Regenerate the committed MJCF files in ``models/``: parts (fingertips,
    plates) and scenes that include them."""
    d = pathlib.Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    texture = Texture()
    x0 = _start_x(texture.length_m)
    files = {
        "fingertip.xml": fingertip_fragment(Fingertip(), x0, texture.length_m).standalone(
            "fingertip"),
        "fingertip_smooth.xml": fingertip_fragment(Fingertip(ridges=False), x0,
                                                   texture.length_m).standalone("fingertip_smooth"),
        "plate_grating.xml": plate_fragment(texture).standalone("plate_grating"),
        "plate_flat.xml": plate_fragment(Texture(kind="flat")).standalone("plate_flat"),
    }
    head = _options(Protocol())
    contact = pad_plate_contact(Fingertip(), Protocol())
    for scene, parts in {
        "slide_grating.xml": ["plate_grating.xml", "fingertip.xml"],
        "slide_grating_smooth.xml": ["plate_grating.xml", "fingertip_smooth.xml"],
        "slide_flat.xml": ["plate_flat.xml", "fingertip.xml"],
    }.items():
        files[scene] = _document(scene[:-4], [contact], head=head, includes=parts)
    paths = []
    for name, xml in files.items():
        p = d / name
        p.write_text(xml)
        paths.append(p)
    return paths


def models_dir() -> pathlib.Path:
    """The models/ folder: installed with the package, or the source tree's."""
    here = pathlib.Path(__file__).resolve().parent
    for cand in (here / "models", here.parent / "models"):
        if cand.is_dir():
            return cand
    raise FileNotFoundError("mjtouch models/ folder not found")
