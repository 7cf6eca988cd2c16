"""Timed runs: the bare and native-tactile baselines as spec edits, settled
starting states (simulated once without the plugin) and Run, which steps or
rolls out a configuration from its state with reused buffers."""

from __future__ import annotations

import dataclasses
import time

import mujoco
import mujoco.rollout
import numpy as np

from mjtouch.bench.configs import LEAD_IN_S
from mjtouch.scene import scenes

_PHYSICS_SPEC = int(mujoco.mjtState.mjSTATE_FULLPHYSICS) & ~int(mujoco.mjtState.mjSTATE_PLUGIN)
_FULL_SPEC = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


def strip_plugin(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """The scene without the mjtouch.skin plugin (the bare MuJoCo scene)."""
    return scenes.remove_skin(spec)


def add_native_tactile(spec: mujoco.MjSpec, nx: int, pitch_m: float, semi_axes_m) -> mujoco.MjSpec:
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
        name="tactile_surface",
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname="tactile_plate",
        pos=[0, 0, -semi_axes_m[2]],
        contype=0,
        conaffinity=0,
        group=4,
    )
    spec.add_sensor(
        name="tactile",
        type=mujoco.mjtSensor.mjSENS_TACTILE,
        objtype=mujoco.mjtObj.mjOBJ_MESH,
        objname="tactile_plate",
        reftype=mujoco.mjtObj.mjOBJ_GEOM,
        refname="tactile_surface",
    )
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
            raise RuntimeError(
                "configuration changes the physics state size; it must differ "
                "from the default scene in the skin only"
            )
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
        mujoco.rollout.rollout(
            self.model,
            self.data,
            self.state0[None],
            self.ctrl[None, :nstep],
            initial_warmstart=self.warm[None],
            state=self._state[:, :nstep],
            sensordata=self._sensordata[:, :nstep],
        )
        return time.perf_counter() - t0, self._sensordata[0, :nstep]
