"""Scene builders on ``mujoco.MjSpec``: the ridged fingertip, textured plates,
the sliding scene and the sphere-press oracle scene.

Each ``add_*`` function adds a part to a spec; ``scene_spec`` and
``sphere_press_spec`` return whole scenes as specs that callers edit
(``set_skin``, ``remove_skin``, attach, any MjSpec edit) and compile. No MJCF
text is written by hand: ``scene_xml`` is ``MjSpec.to_xml`` (which writes 6
significant digits: compile the spec, not its XML, when digits matter).

The fingertip is a smooth ellipsoid pad that MuJoCo collides with a flat,
colliding plate proxy; MuJoCo supplies the motion and the total contact force.
The fine texture is a non-colliding height field (``contype=0``) that only
the ``mjtouch.skin`` plugin renders against, so a fine texture costs nothing in
MuJoCo's collision (a colliding fine height field costs ~3 ms per step).
The skin's fingerprint ridges are rendered by the plugin too.

``write_models(dir)`` regenerates the committed files in ``models/`` (the
parts, and each shipped scene as one complete file); a test checks they are
in sync with these builders.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
from typing import Literal

import mujoco
import numpy as np

from mjtouch._validate import positive
from mjtouch.scene.textures import Texture


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
        positive("semi_axes_m", *self.semi_axes_m)
        positive("mass_kg", self.mass_kg)
        positive("ridge_pitch_m", self.ridge_pitch_m)
        positive("ridge_height_m", self.ridge_height_m)
        positive("pitch_m", self.pitch_m)
        if not (4 <= int(self.nx) <= 512):
            raise ValueError(f"nx = {self.nx} is out of range; valid range [4, 512]")
        if not 0 <= self.friction <= 10:
            raise ValueError(f"friction = {self.friction} is out of range; valid range [0, 10]")


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
            raise ValueError(
                f"speed_m_s = {self.speed_m_s} is out of range; valid range [0, 2] m/s"
            )
        if not 1e-6 <= self.timestep_s <= 5e-3:
            raise ValueError(
                f"timestep_s = {self.timestep_s} is out of range; valid [1e-6, 5e-3] s"
            )
        if not 0.02 <= self.press_s <= 10:
            raise ValueError(f"press_s = {self.press_s} is out of range; valid [0.02, 10] s")


def fmt_number(x: float) -> str:
    """x as MJCF attribute text: 9 significant digits."""
    return f"{x:.9g}"


# MuJoCo contact of the pad (with anything). A stiff impedance (solimp
# 0.95-0.99) makes MuJoCo's elliptic friction cone inflate the normal force
# while sliding: the pad chatters at 100-600 Hz and lifts off (0.08 N rms at
# 40 mm/s, measured).
CONTACT_SOLREF = [0.01, 1.0]
CONTACT_SOLIMP = [0.5, 0.9, 0.001, 0.5, 2.0]  # the last two: MuJoCo's defaults
# Pad-plate pair: impedance rising from 0.5 to 0.9999 over 4 mm stiffens like
# a fingertip (~1.6 mm at 0.5 N, ~3 mm at 50 N) and never lets the pad through.
PAIR_SOLIMP = [0.5, 0.9999, 0.004, 0.5, 2.0]
# Soft constraints make friction rate dependent: its reference acceleration
# grows as slip speed / solreffriction time constant. Too stiff for the slip
# speed and the cone inflates the normal force (chatter, lift-off); too soft
# and friction stays below mu * F_n (viscous). tau_f = 5 m V / F_n puts the
# friction demand just past saturation: Coulomb friction (F_t = mu F_n) with
# a steady normal force from 10 mm/s to 1 m/s and 0.05 to 50 N (measured:
# tests/robustness/test_hard_cases.py).
FRICTION_TAU_PER_MV_F = 5.0
SLIDE_KP = 2e4  # N/m, sliding servo stiffness


def friction_timeconst(tip: Fingertip, protocol: Protocol) -> float:
    """solreffriction time constant (s) for sliding at protocol speed/force."""
    tau = FRICTION_TAU_PER_MV_F * tip.mass_kg * protocol.speed_m_s / protocol.force_n
    return max(tau, 2 * protocol.timestep_s)


# Non-colliding geoms in this group are textures that the skin renders.
TEXTURE_GROUP = 3


def skin_config(tip: Fingertip) -> dict[str, str]:
    cfg = {
        "nx": str(int(tip.nx)),
        "pitch": fmt_number(tip.pitch_m),
        "ridges": "true" if tip.ridges else "false",
        "ridge_pitch": fmt_number(tip.ridge_pitch_m),
        "ridge_height": fmt_number(tip.ridge_height_m),
        "ridge_angle": fmt_number(tip.ridge_angle_deg),
    }
    cfg["texture_group"] = str(TEXTURE_GROUP)
    cfg.update(tip.skin)
    return cfg


def quantize(x: float) -> float:
    """x as the 9 significant digits MJCF files carry, so a model built from
    the spec and one read from its XML are the same bit for bit."""
    return float(fmt_number(x))


def quantize_all(*xs: float) -> list[float]:
    """Each x through :func:`quantize`."""
    return [quantize(x) for x in xs]


def start_x(texture_length_m: float) -> float:
    """Where the fingertip starts (m): above the plate's left quarter, so a
    slide of up to half the plate's length stays on the texture."""
    return -texture_length_m / 4


PRESS_KP = 2e3  # N/m, the displacement-control servo (critically damped by kv)
PAD_CLEARANCE_M = 3e-4  # the pad's pole starts this far above the plate
SKIN_PLUGIN = "mjtouch.skin"


def add_skin_sensor(
    spec: mujoco.MjSpec, geom: str, config: dict[str, str], name: str = "skin"
) -> mujoco.MjsPlugin:
    """An ``mjtouch.skin`` sensor on ``geom`` with attributes ``config``
    (key -> value string). Returns its plugin instance: edit the attributes
    through ``plugin.config`` (MuJoCo 4.0.0's ``sensor.plugin.config`` of a
    sensor made in Python crashes: read them through :func:`skin_plugins`)."""
    spec.activate_plugin(SKIN_PLUGIN)
    plugin = spec.add_plugin(plugin_name=SKIN_PLUGIN, active=True)
    plugin.config = {str(k): str(v) for k, v in config.items()}
    sensor = spec.add_sensor(
        name=name,
        type=mujoco.mjtSensor.mjSENS_PLUGIN,
        objtype=mujoco.mjtObj.mjOBJ_GEOM,
        objname=geom,
    )
    sensor.plugin = plugin
    return plugin


def skin_plugins(spec: mujoco.MjSpec) -> list[mujoco.MjsPlugin]:
    """The spec's mjtouch.skin plugin instances (``.config`` to edit)."""
    return [p for p in spec.plugins if p.plugin_name == SKIN_PLUGIN]


def set_skin(spec: mujoco.MjSpec, **attributes: str) -> mujoco.MjSpec:
    """Set (or, with value None, remove) attributes of every skin instance."""
    targets = skin_plugins(spec)
    if not targets:
        # A spec read from MJCF with the instance inline in <sensor><plugin>
        # (the shipped scenes) names the plugin on the sensor's copy only.
        targets = [
            s.plugin
            for s in spec.sensors
            if s.type == mujoco.mjtSensor.mjSENS_PLUGIN and s.plugin.plugin_name == SKIN_PLUGIN
        ]
    if not targets:
        raise ValueError("set_skin: the spec has no mjtouch.skin instance or sensor to edit")
    for p in targets:
        cfg = dict(p.config)
        for k, v in attributes.items():
            if v is None:
                cfg.pop(k, None)
            else:
                cfg[k] = str(v)
        p.config = cfg
    return spec


SHIPPED_SCENES = ("slide_grating", "slide_grating_smooth", "slide_flat")


def shipped_scene_spec(name: str, **skin: object) -> mujoco.MjSpec:
    """A shipped scene (``models/<name>.xml``) as an MjSpec, with the skin
    attributes ``skin`` (values as strings, None removes one) set on its
    sensor's plugin config (:func:`set_skin`)."""
    if name not in SHIPPED_SCENES:
        raise ValueError(f"shipped_scene_spec: name {name!r} must be one of {SHIPPED_SCENES}")
    spec = mujoco.MjSpec.from_file(str(models_dir() / f"{name}.xml"))
    if skin:
        set_skin(spec, **{k: None if v is None else str(v) for k, v in skin.items()})
    return spec


def remove_skin(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """Delete every mjtouch.skin sensor and instance: the bare MuJoCo scene
    (a sensor plugin does not change the physics)."""
    for s in list(spec.sensors):
        if s.type == mujoco.mjtSensor.mjSENS_PLUGIN:
            spec.delete(s)
    for p in skin_plugins(spec):
        spec.delete(p)
    return spec


def add_fingertip(
    spec: mujoco.MjSpec,
    tip: Fingertip,
    start_x_m: float = -0.02,
    travel_m: float = 0.04,
    control: str = "force",
    skin: bool = True,
) -> mujoco.MjsBody:
    """The fingertip: slide joints in x (sliding) and z (pressing), the pad
    geom, its actuators and (``skin``) the skin sensor plugin instance. The
    `press` actuator is a motor (ctrl = -force, N) or, for
    control="displacement", a position servo on press_z (ctrl = the joint's
    target, m; the pole's depth below the plate top is -ctrl - PAD_CLEARANCE_M)."""
    tip.validate()
    if control not in ("force", "displacement"):
        raise ValueError(f"control = {control!r} is not one of 'force', 'displacement'")
    a, b, c = tip.semi_axes_m
    z0 = c + PAD_CLEARANCE_M
    finger = spec.worldbody.add_body(name="finger", pos=quantize_all(start_x_m, 0, z0), gravcomp=1)
    finger.add_joint(
        name="slide_x",
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[1, 0, 0],
        damping=quantize(2 * math.sqrt(SLIDE_KP * tip.mass_kg)),
    )
    finger.add_joint(name="press_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1], damping=2)
    finger.add_geom(
        name="pad",
        type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        size=quantize_all(a, b, c),
        mass=quantize(tip.mass_kg),
        friction=[quantize(tip.friction), 0.005, 0.0001],
        solref=CONTACT_SOLREF,
        solimp=CONTACT_SOLIMP,
        rgba=[0.93, 0.72, 0.62, 1],
    )
    # intvelocity: ctrl is the sliding speed (m/s), integrated into a
    # position setpoint, so the mean speed is exact despite friction;
    # stiff and critically damped (joint damping) so it does not ring.
    slide = spec.add_actuator(name="slide", target="slide_x", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    slide.set_to_intvelocity(kp=SLIDE_KP)
    slide.actrange = quantize_all(-travel_m, travel_m)
    slide.ctrlrange = [-2, 2]
    press = spec.add_actuator(name="press", target="press_z", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    if control == "displacement":
        press.set_to_position(kp=PRESS_KP, kv=quantize(2 * math.sqrt(PRESS_KP * tip.mass_kg)))
        press.ctrlrange = [-0.01, 0.01]
    else:
        press.set_to_motor()
        press.ctrlrange = [-100, 100]
    if skin:
        add_skin_sensor(spec, "pad", skin_config(tip))
    return finger


def add_grating_hfield(
    spec: mujoco.MjSpec,
    name: str,
    texture: Texture,
    half_width_m: float,
    x_m: np.ndarray | None = None,
) -> mujoco.MjsHField:
    """A 2-row height field of a grating's profile, ``texture.height_m`` tall
    (samples at 4 digits, as the committed MJCF carries them)."""
    if x_m is None:
        x_m = np.linspace(-texture.length_m / 2, texture.length_m / 2, texture.ncol)
    row = texture.profile(x_m) / texture.height_m
    return spec.add_hfield(
        name=name,
        nrow=2,
        ncol=len(x_m),
        size=quantize_all(texture.length_m / 2, half_width_m, texture.height_m, 0.001),
        userdata=[float(f"{v:.4g}") for v in np.concatenate([row, row])],
    )


def add_plate(spec: mujoco.MjSpec, texture: Texture, parent: mujoco.MjsBody | None = None) -> None:
    """A plate on ``parent`` (default: the world): a colliding flat box proxy
    (MuJoCo's contact) and a non-colliding geom named ``texture`` that the
    skin renders against."""
    texture.validate()
    L, W = texture.length_m, texture.width_m
    # 1 cm thick: a hard press (50 N) sinks ~3 mm into MuJoCo's soft contact
    world = parent or spec.worldbody
    world.add_geom(
        name="plate",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=quantize_all(L / 2, W / 2, 0.01),
        pos=[0, 0, -0.01],
        friction=[0.5, 0.005, 0.0001],
        rgba=[0.55, 0.6, 0.65, 1],
    )
    hidden = dict(contype=0, conaffinity=0, group=TEXTURE_GROUP)
    if texture.kind == "flat":
        world.add_geom(
            name="texture",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=quantize_all(L / 2, W / 2, 0.01),
            pos=[0, 0, -0.01],
            rgba=[0, 0, 0, 0],
            **hidden,
        )
        return
    if texture.kind == "mesh":  # exact cell means of the mesh (meshes.from_mesh)
        h = texture.heights()
        spec.add_hfield(
            name="texture",
            nrow=texture.nrow,
            ncol=texture.ncol,
            size=quantize_all(L / 2, W / 2, _relief(texture), 0.001),
            userdata=(h.ravel() / (h.max() - h.min())).tolist(),
        )
    elif texture.nrow == 2:
        add_grating_hfield(spec, "texture", texture, W / 2)
    else:  # a million samples: exact values, no 4-digit rounding
        h = texture.heights()
        spec.add_hfield(
            name="texture",
            nrow=texture.nrow,
            ncol=texture.ncol,
            size=quantize_all(L / 2, W / 2, _relief(texture), 0.001),
            userdata=(h.ravel() / (h.max() - h.min())).tolist(),
        )
    world.add_geom(
        name="texture",
        type=mujoco.mjtGeom.mjGEOM_HFIELD,
        hfieldname="texture",
        rgba=[0.45, 0.5, 0.55, 1],
        **hidden,
    )


def _relief(texture: Texture) -> float:
    """Peak-to-valley height of the texture (the height field's elevation)."""
    if texture.kind in ("grating", "dots"):
        return texture.height_m
    h = texture.heights()
    return float(h.max() - h.min())


def add_pad_plate_contact(spec: mujoco.MjSpec, tip: Fingertip, protocol: Protocol) -> None:
    """The pad-plate contact pair, its friction tuned to the protocol."""
    mu = quantize(tip.friction)
    spec.add_pair(
        geomname1="pad",
        geomname2="plate",
        condim=3,
        friction=[mu, mu, 0.005, 0.0001, 0.0001],
        solref=CONTACT_SOLREF,
        solimp=PAIR_SOLIMP,
        solreffriction=[quantize(friction_timeconst(tip, protocol)), 1],
    )


def set_options(spec: mujoco.MjSpec, protocol: Protocol) -> None:
    spec.option.timestep = quantize(protocol.timestep_s)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC


def add_light(spec: mujoco.MjSpec) -> None:
    spec.worldbody.add_light(pos=[0, 0, 0.3], dir=[0, 0, -1])


def fingertip_spec(
    tip: Fingertip, start_x_m: float = -0.02, travel_m: float = 0.04, model_name: str = "fingertip"
) -> mujoco.MjSpec:
    """The fingertip alone (the part file models/fingertip.xml)."""
    spec = mujoco.MjSpec()
    spec.modelname = model_name
    add_fingertip(spec, tip, start_x_m, travel_m)
    return spec


def plate_spec(texture: Texture, model_name: str = "plate") -> mujoco.MjSpec:
    """The plate alone (the part files models/plate_*.xml)."""
    spec = mujoco.MjSpec()
    spec.modelname = model_name
    add_plate(spec, texture)
    return spec


def scene_spec(
    tip: Fingertip | None = None,
    texture: Texture | None = None,
    protocol: Protocol | None = None,
    model_name: str = "mjtouch_slide",
    skin: bool = True,
) -> mujoco.MjSpec:
    """The sliding scene, fingertip over a plate, as an MjSpec to edit
    (:func:`set_skin`, attach, ...) and compile.
    ``skin=False``: the bare MuJoCo scene without the plugin."""
    tip = tip or Fingertip()
    texture = texture or Texture()
    protocol = protocol or Protocol()
    protocol.validate()
    spec = mujoco.MjSpec()
    spec.modelname = model_name
    set_options(spec, protocol)
    add_plate(spec, texture)
    add_fingertip(
        spec, tip, start_x(texture.length_m), texture.length_m, protocol.control, skin=skin
    )
    add_light(spec)
    add_pad_plate_contact(spec, tip, protocol)
    return spec


def scene_xml(
    tip: Fingertip | None = None,
    texture: Texture | None = None,
    protocol: Protocol | None = None,
    model_name: str = "mjtouch_slide",
) -> str:
    """A complete single-file MJCF scene: fingertip over a plate."""
    return scene_spec(tip, texture, protocol, model_name).to_xml()


def build_model(
    tip: Fingertip | None = None, texture: Texture | None = None, protocol: Protocol | None = None
) -> mujoco.MjModel:
    """Compile the sliding scene (:func:`scene_spec`)."""
    return scene_spec(tip, texture, protocol).compile()


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


def sphere_press_spec(
    radius_m: float, skin: dict[str, str], timestep_s: float = 1e-3
) -> mujoco.MjSpec:
    """A rigid-plate oracle scene: a sphere pad (the skin) on a slide joint,
    pushed down onto a flat box plate by the motor `press` (ctrl = force, N),
    no gravity. The Hertz set-up of mjtouch.analysis.reference_solutions."""
    positive("radius_m", radius_m)
    spec = mujoco.MjSpec()
    spec.modelname = "sphere_press"
    spec.option.timestep = quantize(timestep_s)
    spec.option.gravity = [0, 0, 0]
    spec.worldbody.add_geom(
        name="plate", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.05, 0.05, 0.002], pos=[0, 0, -0.002]
    )
    finger = spec.worldbody.add_body(name="finger", pos=[0, 0, quantize(radius_m)])
    finger.add_joint(name="press_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1], damping=5)
    finger.add_geom(
        name="pad",
        type=mujoco.mjtGeom.mjGEOM_SPHERE,
        size=[quantize(radius_m), 0, 0],
        mass=0.01,
        solref=[0.01, 1],
    )
    press = spec.add_actuator(name="press", target="press_z", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    press.set_to_motor()
    press.gear[0] = -1
    add_skin_sensor(spec, "pad", skin)
    return spec


def sphere_press_xml(radius_m: float, skin: dict[str, str], timestep_s: float = 1e-3) -> str:
    return sphere_press_spec(radius_m, skin, timestep_s).to_xml()


def write_models(directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Regenerate the committed MJCF files in ``models/`` from the same
    specs the Python scenes compile: the parts (fingertips, plates) and the
    three shipped scenes, each scene a complete file (MjSpec.to_xml)."""
    d = pathlib.Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    texture = Texture()
    x0 = start_x(texture.length_m)
    specs = {
        "fingertip.xml": fingertip_spec(Fingertip(), x0, texture.length_m, "fingertip"),
        "fingertip_smooth.xml": fingertip_spec(
            Fingertip(ridges=False), x0, texture.length_m, "fingertip_smooth"
        ),
        "plate_grating.xml": plate_spec(texture, "plate_grating"),
        "plate_flat.xml": plate_spec(Texture(kind="flat"), "plate_flat"),
        "slide_grating.xml": scene_spec(texture=texture, model_name="slide_grating"),
        "slide_grating_smooth.xml": scene_spec(
            Fingertip(ridges=False), texture, model_name="slide_grating_smooth"
        ),
        "slide_flat.xml": scene_spec(texture=Texture(kind="flat"), model_name="slide_flat"),
    }
    paths = []
    for name, spec in specs.items():
        p = d / name
        p.write_text(spec.to_xml())
        paths.append(p)
    return paths


def models_dir() -> pathlib.Path:
    """The models/ folder: installed with the package, or the source tree's."""
    here = pathlib.Path(__file__).resolve().parent
    # installed: mjtouch/models; source tree (editable): models/ beside mjtouch/
    for cand in (here.parent / "models", here.parents[1] / "models"):
        if cand.is_dir():
            return cand
    raise FileNotFoundError("mjtouch models/ folder not found")
