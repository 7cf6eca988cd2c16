"""Skin on any robot: :func:`attach` puts an ``mjtouch.skin`` sensor on any
fingertip geom of a user's ``mujoco.MjSpec`` (several fingertips, each its
own plugin instance and sensor), and :func:`layouts` reads every skin's
:class:`~mjtouch.scene.sensor.SkinLayout` by sensor name.

The skin touches the side of its geom (sphere, ellipsoid, capsule, box or
mesh) that ``facing`` names, in the geom's frame; default its -z side. The
pad's surface is the geom's exact near side seen along ``facing`` (a
sideways capsule's cylinder; a mesh's convex hull, which is what MuJoCo
collides), its curvature entering through the gap to what it touches; the
elastic skin under it is a flat layered half-space (plugin/README.md). A texture the skin feels but MuJoCo does not collide is a
non-colliding geom (contype = conaffinity = 0) that the user names in the
``texture`` attribute, or any such geom of a group the user opts into with
``texture_group``. :func:`attach` sets no group: a robot's own visual
meshes (often in group 3, non-colliding) never become textures unasked.

``MjSpec.attach(child, prefix=..., suffix=...)`` renames the child's geoms;
the skin's ``texture`` names follow, because :func:`attach` records the pad
geom's name as written (attribute ``pad_geom``) and the plugin applies the
prefix and suffix the pad's compiled name gained to each texture name.
"""

from __future__ import annotations

import numbers

import mujoco
import numpy as np

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

# attach()'s attributes for the bench's `rl` preset (mjtouch.bench.configs.PRESETS["rl"],
# held equal by tests/plugin/test_robot_shadow.py): a 43 x 0.3 mm Winkler grid without
# ridges, half the default receptor density, the render once per physics step.
RL_SKIN = {
    "nx": 43,
    "pitch": 3e-4,
    "ridges": False,
    "density": [35.0, 70.0, 10.5],
    "pressure": "winkler",
    "stress_method": "auto",
    "substep": "receptors",
}

PAD_TYPES = {
    mujoco.mjtGeom.mjGEOM_SPHERE: "sphere",
    mujoco.mjtGeom.mjGEOM_ELLIPSOID: "ellipsoid",
    mujoco.mjtGeom.mjGEOM_CAPSULE: "capsule",
    mujoco.mjtGeom.mjGEOM_BOX: "box",
    mujoco.mjtGeom.mjGEOM_MESH: "mesh",
}


def _value(key: str, v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, numbers.Real):
        return scenes.fmt_number(float(v))
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return " ".join(_value(key, x) for x in v)
    if isinstance(v, str):
        return v
    raise ValueError(f"attribute {key} = {v!r}: give a str, number, bool or a list of them")


def _geom_label(g: mujoco.MjsGeom, k: int) -> str:
    return repr(g.name) if g.name else f"(unnamed geom {k} of the body, a {g.type.name})"


def _pad_geom(spec: mujoco.MjSpec, geom, body, facing) -> mujoco.MjsGeom:
    """The pad geom: `geom` (a name or an MjsGeom) or `body`'s colliding geom
    (a name or an MjsBody) nearest the facing side (_nearest_facing)."""
    if (geom is None) == (body is None):
        raise ValueError(
            f"geom = {geom!r}, body = {body!r}: give exactly one (a geom's name "
            "or MjsGeom, or a body's name or MjsBody)"
        )
    if geom is not None:
        if isinstance(geom, mujoco.MjsGeom):
            return geom
        if not isinstance(geom, str) or not geom:
            raise ValueError(
                f"geom = {geom!r} must be the name of a geom in the spec, or an MjsGeom"
            )
        g = spec.geom(geom)
        if g is None:
            names = [x.name for x in spec.geoms if x.name]
            raise ValueError(f"geom = {geom!r} is not in the spec; named geoms: {names}")
        return g
    if isinstance(body, str):
        b = spec.body(body) if body else None
        if b is None:
            names = [x.name for x in spec.bodies if x.name]
            raise ValueError(f"body = {body!r} is not in the spec; named bodies: {names}")
        body = b
    if not isinstance(body, mujoco.MjsBody):
        raise ValueError(f"body = {body!r} must be the name of a body in the spec, or an MjsBody")
    colliding = [(k, g) for k, g in enumerate(body.geoms) if g.contype or g.conaffinity]
    label = repr(body.name) if body.name else "(unnamed body)"
    if not colliding:
        raise ValueError(
            f"body {label} has no colliding geom; valid: a body with one, or pass "
            "geom= (a name or the MjsGeom)"
        )
    if len(colliding) == 1:
        return colliding[0][1]
    return _nearest_facing(spec, body, label, colliding, facing)


# Two geoms whose surfaces reach within this of each other along `facing`
# are a tie: the choice is left to the user.
TIE_M = 1e-4


def geom_written_xmat(model: mujoco.MjModel, data: mujoco.MjData, gid: int) -> np.ndarray:
    """Geom gid's world rotation in its frame as written: a mesh geom's
    compiled frame is turned to the mesh's principal axes (mesh_quat)."""
    xmat = data.geom_xmat[gid].reshape(3, 3)
    if model.geom_type[gid] != mujoco.mjtGeom.mjGEOM_MESH:
        return xmat
    turn = np.zeros(9)
    mujoco.mju_quat2Mat(turn, model.mesh_quat[model.geom_dataid[gid]])
    return xmat @ turn.reshape(3, 3).T


def geom_reach_m(model: mujoco.MjModel, data: mujoco.MjData, gid: int, u: np.ndarray) -> float:
    """How far geom gid's surface reaches along the world unit vector u
    (max of x . u over the geom, x from the world origin)."""
    c, R, size = data.geom_xpos[gid], data.geom_xmat[gid].reshape(3, 3), model.geom_size[gid]
    w = R.T @ u  # u in the geom's compiled frame
    t = mujoco.mjtGeom(model.geom_type[gid])
    if t == mujoco.mjtGeom.mjGEOM_SPHERE:
        reach = size[0]
    elif t == mujoco.mjtGeom.mjGEOM_CAPSULE:
        reach = size[0] + size[1] * abs(w[2])
    elif t == mujoco.mjtGeom.mjGEOM_CYLINDER:
        reach = size[1] * abs(w[2]) + size[0] * np.hypot(w[0], w[1])
    elif t == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        reach = float(np.linalg.norm(size * w))
    elif t == mujoco.mjtGeom.mjGEOM_BOX:
        reach = float(np.abs(size * w).sum())
    elif t == mujoco.mjtGeom.mjGEOM_MESH:
        mid = model.geom_dataid[gid]
        adr, num = model.mesh_vertadr[mid], model.mesh_vertnum[mid]
        reach = float((model.mesh_vert[adr : adr + num] @ w).max())
    else:  # planes, height fields, sdf: not a fingertip
        return -np.inf
    return float(c @ u) + reach


def _nearest_facing(spec, body, label, colliding, facing) -> mujoco.MjsGeom:
    """Of several colliding geoms, the one whose surface reaches farthest
    along the facing direction (at the model's initial pose); an error
    listing them on a tie (within TIE_M) or when a vector `facing` names no
    one direction (the geoms' frames are turned differently)."""
    listed = ", ".join(_geom_label(g, k) for k, g in colliding)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    # compiled geom ids: the body's geoms in order
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body.name) if body.name else -1
    if bid < 0:
        raise ValueError(
            f"body {label} has {len(colliding)} colliding geoms ({listed}); name the body "
            "to let attach choose among them, or pass geom="
        )
    ids = [model.body_geomadr[bid] + k for k, _ in colliding]
    if isinstance(facing, str):
        site = spec.site(facing)
        if site is None:
            names = [x.name for x in spec.sites if x.name]
            raise ValueError(f"facing = {facing!r} is not a site of the spec; named sites: {names}")
        dirs = [-data.site(facing).xmat.reshape(3, 3)[:, 2]] * len(ids)
    else:
        f = np.asarray((0, 0, -1) if facing is None else facing, dtype=float)
        if f.shape != (3,) or not np.isfinite(f).all() or not np.linalg.norm(f) > 0:
            raise ValueError(f"facing = {facing!r} must be a 3-vector, not all zero, or a site")
        dirs = [geom_written_xmat(model, data, i) @ (f / np.linalg.norm(f)) for i in ids]
    if max(np.abs(d - dirs[0]).max() for d in dirs) > 1e-9:
        raise ValueError(
            f"body {label} has {len(colliding)} colliding geoms ({listed}) turned differently: "
            f"facing = {facing!r} (in the geom's frame) names a different side of each; "
            "valid: facing as a site's name, or geom="
        )
    reach = [geom_reach_m(model, data, i, d) for i, d in zip(ids, dirs)]
    order = np.argsort(reach)[::-1]
    best, second = order[0], order[1]
    if reach[best] - reach[second] < TIE_M:
        each = ", ".join(
            f"{_geom_label(g, k)} {reach[n] - reach[best]:+.2e} m"
            for n, (k, g) in enumerate(colliding)
        )
        raise ValueError(
            f"body {label} has {len(colliding)} colliding geoms and two reach within "
            f"{TIE_M} m of each other along facing ({each}); valid: pass geom= (a name "
            "or the MjsGeom)"
        )
    return colliding[best][1]


def _name_geom(spec: mujoco.MjSpec, g: mujoco.MjsGeom) -> str:
    """g's name; an unnamed geom is named `<body>_pad` (or `<body>_pad_2`,
    ...; `pad` on an unnamed body): a sensor names the geom it is on."""
    if g.name:
        return g.name
    base = f"{g.parent.name}_pad" if g.parent.name else "pad"
    name, k = base, 1
    while spec.geom(name) is not None:
        k += 1
        name = f"{base}_{k}"
    g.name = name
    return name


def _facing_from_site(spec: mujoco.MjSpec, g: mujoco.MjsGeom, site: str) -> list[float]:
    """The site's -z axis in the geom's frame (at the model's initial pose)."""
    if spec.site(site) is None:
        names = [x.name for x in spec.sites if x.name]
        raise ValueError(
            f"facing = {site!r} is not a site of the spec; named sites: {names} "
            "(or give a 3-vector in the geom's frame)"
        )
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    gmat = geom_written_xmat(model, data, model.geom(g.name).id)
    smat = data.site(site).xmat.reshape(3, 3)
    f = gmat.T @ (-smat[:, 2])
    return [0.0 if abs(x) < 1e-12 else float(x) for x in f]


def attach(
    spec: mujoco.MjSpec,
    geom: str | mujoco.MjsGeom | None = None,
    name: str | None = None,
    *,
    body: str | mujoco.MjsBody | None = None,
    facing=None,
    **attributes,
) -> mujoco.MjsPlugin:
    """Add an ``mjtouch.skin`` sensor named ``name`` (default
    ``skin_<geom>``) on a fingertip geom with the given plugin attributes
    (``nx=48, pitch=2e-4, ridges=True, outputs="spikes stress force"``,
    ...; values as Python numbers, bools, strings or lists; None leaves one
    out).

    The pad: ``geom`` (its name or the ``MjsGeom``; sphere, ellipsoid,
    capsule, box or mesh) or ``body`` (its name or the ``MjsBody``; its
    colliding geom, and of several the one whose surface reaches farthest
    along ``facing`` at the initial pose; a tie within 0.1 mm, or a vector
    ``facing`` that means a different side of each because their frames are
    turned differently, is an error listing them). An unnamed pad geom is
    named ``<body>_pad`` (a sensor needs the geom's name). ``facing``: the
    skin's outward direction in the geom's frame as written (a 3-vector; a
    mesh's file axes, not MuJoCo's principal axes), or a site's name (the
    site's -z axis, the way MuJoCo marks a frame); default (0, 0, -1), the
    geom's -z side.

    The skin feels the geoms MuJoCo reports in contact with the pad plus the
    textures the user asks for: ``texture="geom names"`` and/or
    ``texture_group=k`` (every non-colliding geom of group k); none by
    default. Returns its plugin instance (named like the sensor): edit
    ``.config`` to change attributes later. Attribute values are checked
    when the spec compiles."""
    g = _pad_geom(spec, geom, body, facing)
    if g.type not in PAD_TYPES:
        label = repr(g.name) if g.name else "(unnamed)"
        raise ValueError(
            f"geom {label} is a {g.type.name}; a skin needs a pad geom of type "
            f"{', '.join(PAD_TYPES.values())}"
        )
    geom_name = _name_geom(spec, g)
    name = name or f"skin_{geom_name}"
    if any(s.name == name for s in spec.sensors) or any(p.name == name for p in spec.plugins):
        raise ValueError(
            f"name = {name!r} is taken by a sensor or plugin of the spec; pass another name"
        )
    if isinstance(facing, str):
        facing = _facing_from_site(spec, g, facing)
    if facing is not None:
        attributes["facing"] = facing
    config = {str(k): _value(k, v) for k, v in attributes.items() if v is not None}
    config.setdefault("pad_geom", geom_name)  # texture names follow MjSpec.attach's renaming
    spec.activate_plugin(scenes.SKIN_PLUGIN)  # the <extension> entry
    plugin = spec.add_plugin(name=name, plugin_name=scenes.SKIN_PLUGIN, active=True)
    plugin.config = config
    sensor = spec.add_sensor(
        name=name,
        type=mujoco.mjtSensor.mjSENS_PLUGIN,
        objtype=mujoco.mjtObj.mjOBJ_GEOM,
        objname=geom_name,
    )
    # the sensor keeps a copy of the reference: assign after naming the plugin
    sensor.plugin = plugin
    return plugin


def distal_joint(model: mujoco.MjModel, body: int | str) -> int:
    """The hinge nearest `body` on its chain to the world (its own first):
    a fingertip's distal joint."""
    b = model.body(body).id
    while b > 0:
        for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
                return j
        b = model.body_parentid[b]
    raise ValueError(f"body {model.body(body).name!r} has no hinge joint on its chain to the world")


def flexion_facing(model: mujoco.MjModel, geom: int | str, joint: int | str | None = None):
    """The pad side of a fingertip geom, as ``facing`` (a unit vector in the
    geom's frame as written): the direction the geom's centre moves at the
    model's qpos0 when the hinge `joint` (default the geom body's
    distal_joint) turns towards the larger side of its range (robot hands'
    ranges reach farther into flexion than extension; an unlimited joint
    turns positive)."""
    g = model.geom(geom).id
    j = distal_joint(model, model.geom_bodyid[g]) if joint is None else model.joint(joint).id
    lo, hi = model.jnt_range[j]
    sign = -1.0 if model.jnt_limited[j] and hi + lo < 0 else 1.0
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    jacp = np.zeros((3, model.nv))
    mujoco.mj_jacGeom(model, data, jacp, None, g)
    move = sign * geom_written_xmat(model, data, g).T @ jacp[:, model.jnt_dofadr[j]]
    if not np.linalg.norm(move) > 1e-12:
        raise ValueError(
            f"geom {model.geom(g).name!r} does not move when joint "
            f"{model.joint(j).name!r} turns (on its axis?); pass facing yourself"
        )
    return move / np.linalg.norm(move)


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
