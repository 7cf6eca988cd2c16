"""Skin on any robot: :func:`attach` puts an ``mjtouch.skin`` sensor on any
fingertip geom of a user's ``mujoco.MjSpec`` (several fingertips, each its
own plugin instance and sensor), and :func:`layouts` reads every skin's
:class:`~mjtouch.scene.sensor.SkinLayout` by sensor name.

The skin touches the -z side of its geom (sphere, ellipsoid, capsule or
box; plugin/README.md): turn the geom so its local -z points out of the
fingertip's pad. A texture the skin feels but MuJoCo does not collide is a
non-colliding geom (contype = conaffinity = 0) in the skin's
``texture_group`` (default here: scenes.TEXTURE_GROUP), or named by the
``texture`` attribute.
"""

from __future__ import annotations

import mujoco

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

PAD_TYPES = {
    mujoco.mjtGeom.mjGEOM_SPHERE: "sphere",
    mujoco.mjtGeom.mjGEOM_ELLIPSOID: "ellipsoid",
    mujoco.mjtGeom.mjGEOM_CAPSULE: "capsule",
    mujoco.mjtGeom.mjGEOM_BOX: "box",
}


def _value(key: str, v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return scenes.fmt_number(v)
    if isinstance(v, (list, tuple)):
        return " ".join(_value(key, x) for x in v)
    if isinstance(v, str):
        return v
    raise ValueError(f"attribute {key} = {v!r}: give a str, number, bool or a list of them")


def attach(
    spec: mujoco.MjSpec, geom: str, name: str | None = None, **attributes
) -> mujoco.MjsPlugin:
    """Add an ``mjtouch.skin`` sensor named ``name`` (default ``skin_<geom>``)
    on ``geom`` with the given plugin attributes (``nx=48, pitch=2e-4,
    ridges=True, outputs="spikes stress force"``, ...; values as Python
    numbers, bools, strings or lists; None leaves one out). Without
    ``texture`` the skin feels the non-colliding geoms of group
    scenes.TEXTURE_GROUP; with several fingers on one object, name each
    skin's own texture geoms instead. Returns its plugin instance (named
    like the sensor): edit ``.config`` to change attributes later.
    Attribute values are checked when the spec compiles."""
    if not isinstance(geom, str) or not geom:
        raise ValueError(f"geom = {geom!r} must be the name of a geom in the spec")
    g = spec.geom(geom)
    if g is None:
        names = [x.name for x in spec.geoms if x.name]
        raise ValueError(f"geom = {geom!r} is not in the spec; named geoms: {names}")
    if g.type not in PAD_TYPES:
        raise ValueError(
            f"geom {geom!r} is a {g.type.name}; a skin needs a pad geom of type "
            f"{', '.join(PAD_TYPES.values())}"
        )
    name = name or f"skin_{geom}"
    if any(s.name == name for s in spec.sensors) or any(p.name == name for p in spec.plugins):
        raise ValueError(
            f"name = {name!r} is taken by a sensor or plugin of the spec; pass another name"
        )
    # Textures: named ones only when named (a skin would otherwise also feel
    # the group's textures on the far side of an object, seen from behind as
    # deep overlap); else the non-colliding geoms of scenes.TEXTURE_GROUP.
    config = {} if "texture" in attributes else {"texture_group": str(scenes.TEXTURE_GROUP)}
    config.update({str(k): _value(k, v) for k, v in attributes.items() if v is not None})
    spec.activate_plugin(scenes.SKIN_PLUGIN)  # the <extension> entry
    plugin = spec.add_plugin(name=name, plugin_name=scenes.SKIN_PLUGIN, active=True)
    plugin.config = config
    sensor = spec.add_sensor(
        name=name,
        type=mujoco.mjtSensor.mjSENS_PLUGIN,
        objtype=mujoco.mjtObj.mjOBJ_GEOM,
        objname=geom,
    )
    # the sensor keeps a copy of the reference: assign after naming the plugin
    sensor.plugin = plugin
    return plugin


def layouts(model: mujoco.MjModel) -> dict[str, SkinLayout]:
    """Every mjtouch.skin sensor's layout, by sensor name."""
    out = {}
    for i in range(model.nsensor):
        if model.sensor_type[i] != mujoco.mjtSensor.mjSENS_PLUGIN:
            continue
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_SENSOR, i)
        if name is None:
            raise ValueError(f"plugin sensor {i} has no name; name it to read it by name")
        out[name] = SkinLayout.from_model(model, name)
    return out
