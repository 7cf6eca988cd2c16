"""``mjtouch/SlipHold-v0``: hold an object with as little force as possible.

The fingertip pinches a block against a frictionless wall; gravity and an
external load pull the block down, and only the friction at the fingertip
holds it: it holds while the load stays under mu x grip force. Each episode
draws the friction coefficient mu, a base load, and a rise of the load over
a random interval at a random time (an object being filled, say). Neither is observed: the skin must tell
when the object starts to slip (the tangential force approaching mu x normal
force, and the burst of RA/PC spikes as the block's textured face slides over
the skin). Without touch the only safe policy is the worst-case grip.

Action (Box, [-1, 1]): grip force, -1 -> ``force_range_n[0]``, +1 -> ``force_range_n[1]`` (N).

Observation (Box, float64), blocks in this order (``env.unwrapped.describe_observation()``),
with their bounds (F = ``force_range_n[1]``, mu = ``friction_range[1]``, T = control step,
n_c = receptors of the class; *: full scale, saturates):

| block | size | units | meaning | bounds |
|---|---|---|---|---|
| ``grip`` | 3 | m, m/s, N | fingertip position (towards the wall, from its start), velocity, grip force applied | +-20 mm*, +-2 F / (2 N s/m)*, ``force_range_n`` |
| ``touch`` | 3 | spikes or Hz | SA1, RA, PC spike counts over the control step (or rates) | 0 to n_c (ceil(T / 1 ms) + 1) |
| ``contact`` | 3 | N | skin force (normal; tangential along pad x = up, along pad y), mean over the step | 0 to 5 F*, +-5 mu F* |
| ``pressure`` | p*p | kPa | optional, ``pressure_image=p``: end-of-step pressure, p x p | 0 to 5 F / block area* |
| ``slip`` | 4 | 1 | stuck share of the contact (cells that did not slip in the last physics step; least over the step), slip zone share (traction within 1% of mu p), the slip zone's mean radius / the contact's equivalent radius | 0 to 1; ring 0 to 2 |

``touch="none"``: only ``grip`` (the skin is not in the scene). With touch the skin
solves its own tangential contact (``shear="partial"``): under the load the contact's
rim slips while its centre sticks, and the slip zone grows as the load nears mu x grip
(Cattaneo-Mindlin), before the block moves. The stuck share reads 1 in a step where
the load eases off (no cell slips on unloading, Mindlin-Deresiewicz); the slip zone
keeps its size then.

Reward per control step: ``-force_cost * grip force (N) - slip_cost * slip (mm)``
(slip: how far the block moved down in the step). The episode terminates
with ``-drop_penalty`` when the block has slipped ``drop_m`` below where it
started, and is truncated by the time limit (100 control steps = 1 s).
"""

from __future__ import annotations

import functools
import math

import gymnasium as gym
import mujoco
import numpy as np

from mjtouch._validate import in_range
from mjtouch.envs.base import ObsBlock, TouchEnv
from mjtouch.envs.texture_explore import env_fingertip
from mjtouch.scene import scenes

BLOCK_HALF_M = (0.01, 0.015, 0.02)  # the held block's half sizes: towards the wall, across, up
BLOCK_MASS_KG = 0.02
GRATING_PERIOD_M = 1e-3  # ridges across the block's face, perpendicular to slip
PAD_FRICTION = 0.1  # below every block friction, so the block's sets the contact's
GRIP_DAMPING_N_S_M = 2.0  # the grip joint's damping
EPISODE_STEPS = 100  # the registered time limit (1 s at the default control step)
# Full scales of the grip block: the block (2 x 10 mm deep) stops the finger
# towards the wall and nothing pulls it back; its speed is at most the
# terminal speed F / damping under the largest grip force, doubled for
# contact rebounds.
GRIP_X_FULL_SCALE_M = 2 * BLOCK_HALF_M[0]
SLIP_FEATURES = 4
SLIP_ZONE_TOLERANCE = 0.01
# The slip zone's mean radius over the contact's equivalent radius is at
# most the farthest loaded cell's: for the pad's near-elliptic contact
# (semi-axes ratio <= 8/7), under 1.2; a pressure split by the block's
# grating rims it at most one cell (0.2 mm of ~2 mm) further.
RING_RADIUS_MAX = 2.0


def slip_zone(pressure_pa: np.ndarray, shear_pa: np.ndarray, mu: float) -> tuple[float, float]:
    """The slip zone of a contact: the loaded cells whose traction is within
    SLIP_ZONE_TOLERANCE of the Coulomb limit mu p (unlike the stick map's
    "did not slip in this step", it outlasts the slight unloadings of a
    steady hold, which take every cell just off the limit). Returns its share
    of the loaded cells and its cells' mean distance from the loaded cells'
    centroid over the contact's equivalent radius sqrt(area / pi) (0, 0
    without contact or slip). Cattaneo's annulus between c and a:
    share 1 - (c/a)^2, radius 2 (1 - (c/a)^3) / (3 (1 - (c/a)^2)), 2/3 to 1.
    pressure_pa (nx, nx); shear_pa (2, nx, nx)."""
    nx = pressure_pa.shape[-1]
    pressure = pressure_pa.reshape(-1)
    loaded = np.flatnonzero(pressure > 0)  # row-major, as np.nonzero
    n = loaded.size
    if n == 0:
        return 0.0, 0.0
    shear = shear_pa.reshape(2, -1)
    limit = (1 - SLIP_ZONE_TOLERANCE) * mu * pressure[loaded]
    at_limit = loaded[np.hypot(shear[0, loaded], shear[1, loaded]) >= limit]
    if at_limit.size == 0:
        return 0.0, 0.0
    rows, cols = _cell_indices(nx)
    # means of whole numbers: the sums are exact, so these are np.mean's bits
    j_mean, i_mean = rows[loaded].sum() / n, cols[loaded].sum() / n
    radius = np.hypot(rows[at_limit] - j_mean, cols[at_limit] - i_mean).mean()
    return float(at_limit.size / n), float(radius / math.sqrt(n / math.pi))


@functools.cache
def _cell_indices(nx: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column index (as float) of each cell of an nx x nx image, row-major."""
    index = np.arange(nx, dtype=np.float64)
    rows, cols = np.repeat(index, nx), np.tile(index, nx)
    rows.flags.writeable = cols.flags.writeable = False  # shared by every call
    return rows, cols


# The finger's and the block face's frame: pad x along world +z (up), pad y
# along world -x, pad z along world -y (the skin, pad -z, faces the block at
# +y). A rotation whose quaternion and matrix are exact (0, +-1, +-0.5): the
# box's face, the face's texture and the pad then share one frame bit for bit,
# so the skin renders the face through its aligned-face path and skips the
# box under the texture (mjtouch.skin's render).
PAD_QUAT = (0.5, 0.5, -0.5, 0.5)


def slip_hold_spec(
    tip: scenes.Fingertip | None = None, timestep_s: float = 1e-3, skin: bool = True
) -> mujoco.MjSpec:
    """A block between the fingertip pad (pressing along +y) and a wall."""
    tip = tip or env_fingertip()
    tip.validate()
    q = scenes.quantize_all
    a, b, c = tip.semi_axes_m
    bx, by, bz = BLOCK_HALF_M
    # the texture spans the face exactly (the render's texture-on-face case)
    tex = scenes.Texture(period_m=GRATING_PERIOD_M, length_m=2 * bz, resolution_m=5e-5)
    spec = mujoco.MjSpec()
    spec.modelname = "mjtouch_slip_hold"
    spec.option.timestep = scenes.quantize(timestep_s)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    # stiff friction, so a held block creeps < 0.1 mm/s (MuJoCo's soft
    # friction otherwise lets it slide at ~mm/s under any grip)
    spec.option.impratio = 100
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 640, 480
    scenes.add_grating_hfield(spec, "face", tex, by)
    world = spec.worldbody
    world.add_light(pos=[0.3, 0, 0.3], dir=[-1, 0, -1])
    world.add_geom(
        name="wall",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.03, 0.005, 0.04],
        pos=q(0, bx + 0.005, 0),
        priority=2,
        condim=1,
        rgba=[0.55, 0.6, 0.65, 1],
    )
    block = world.add_body(name="object")
    # towards the wall
    block.add_joint(name="object_y", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 1, 0], damping=0.1)
    block.add_joint(name="object_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    block.add_geom(
        name="object",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=q(by, bx, bz),
        mass=BLOCK_MASS_KG,
        friction=[0.5, 0.005, 0.0001],
        rgba=[0.3, 0.5, 0.8, 1],
    )
    block.add_geom(
        name="face",
        type=mujoco.mjtGeom.mjGEOM_HFIELD,
        hfieldname="face",
        pos=q(0, -bx, 0),
        quat=PAD_QUAT,
        contype=0,
        conaffinity=0,
        group=scenes.TEXTURE_GROUP,
        rgba=[0.25, 0.4, 0.7, 1],
    )
    finger = world.add_body(name="finger", pos=q(0, -(bx + c + 3e-4), 0), quat=PAD_QUAT, gravcomp=1)
    finger.add_joint(
        name="grip", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, -1], damping=GRIP_DAMPING_N_S_M
    )
    finger.add_geom(
        name="pad",
        type=mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        size=q(a, b, c),
        mass=scenes.quantize(tip.mass_kg),
        friction=[PAD_FRICTION, 0.005, 0.0001],
        solref=scenes.CONTACT_SOLREF,
        solimp=scenes.CONTACT_SOLIMP,
        rgba=[0.93, 0.72, 0.62, 1],
    )
    grip = spec.add_actuator(name="grip", target="grip", trntype=mujoco.mjtTrn.mjTRN_JOINT)
    grip.set_to_motor()
    grip.ctrlrange = [0, 5]
    if skin:
        scenes.add_skin_sensor(spec, "pad", scenes.skin_config(tip))
    return spec


class SlipHoldEnv(TouchEnv):
    __doc__ = __doc__

    def __init__(
        self,
        *,
        touch: str = "counts",
        pressure_image: int = 0,
        force_range_n=(0.05, 2.0),
        friction_range=(0.5, 1.0),
        base_load_range_n=(0.0, 0.1),
        rise_load_range_n=(0.1, 0.4),
        rise_start_range_s=(0.2, 0.6),
        rise_time_range_s=(0.1, 0.3),
        control_dt_s: float = 0.01,
        timestep_s: float = 1e-3,
        force_cost: float = 0.01,
        slip_cost: float = 0.1,
        drop_m: float = 5e-3,
        drop_penalty: float = 5.0,
        settle_force_n: float = 1.5,
        render_mode: str | None = None,
        render_size=(480, 640),
    ):
        def pair(name, v, lo, hi, units):
            v0, v1 = (float(x) for x in v)
            in_range(f"{name}[0]", v0, lo, hi, units)
            in_range(f"{name}[1]", v1, v0, hi, units)
            return v0, v1

        self.force_range_n = pair("force_range_n", force_range_n, 0.0, 5.0, "N")
        self.friction_range = pair("friction_range", friction_range, 2 * PAD_FRICTION, 2.0, "")
        self.base_load_range_n = pair("base_load_range_n", base_load_range_n, 0.0, 2.0, "N")
        self.rise_load_range_n = pair("rise_load_range_n", rise_load_range_n, 0.0, 2.0, "N")
        self.rise_start_range_s = pair("rise_start_range_s", rise_start_range_s, 0.0, 100.0, "s")
        self.rise_time_range_s = pair("rise_time_range_s", rise_time_range_s, 1e-3, 100.0, "s")
        in_range("timestep_s", timestep_s, 1e-4, 2e-3, "s")
        in_range("control_dt_s", control_dt_s, timestep_s, 0.1, "s")
        in_range("force_cost", force_cost, 0.0, 100.0)
        in_range("slip_cost", slip_cost, 0.0, 100.0)
        in_range("drop_m", drop_m, 1e-4, 0.02, "m")
        in_range("drop_penalty", drop_penalty, 0.0, 1e3)
        in_range("settle_force_n", settle_force_n, 0.1, 5.0, "N")
        frame_skip = round(control_dt_s / timestep_s)
        if not math.isclose(frame_skip * timestep_s, control_dt_s, rel_tol=1e-9):
            raise ValueError(
                f"control_dt_s = {control_dt_s} must be a multiple of timestep_s = {timestep_s}"
            )
        outputs = "spikes force pressure slip shear"  # what the observation reads
        tip = env_fingertip(outputs=outputs)
        tip.skin["shear"] = "partial"  # Coulomb stick and slip per taxel
        model_spec = slip_hold_spec(tip, timestep_s, skin=touch != "none")
        spec = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_XFRC_APPLIED
        super().__init__(
            model_spec,
            touch=touch,
            pressure_image=pressure_image,
            frame_skip=frame_skip,
            user_spec=int(spec),
            render_mode=render_mode,
            render_size=render_size,
            max_force_n=self.force_range_n[1],
            max_friction=self.friction_range[1],
        )
        self.force_cost, self.slip_cost = float(force_cost), float(slip_cost)
        self.drop_m, self.drop_penalty = float(drop_m), float(drop_penalty)
        self.settle_force_n = float(settle_force_n)
        m = self.model
        self._object_body = m.body("object").id
        self._object_geom = m.geom("object").id
        self.action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
        lo, hi = self.force_range_n
        v_fs = 2 * max(hi, 0.1) / GRIP_DAMPING_N_S_M
        self._set_blocks(
            [
                ObsBlock(
                    "grip",
                    3,
                    "m, m/s, N",
                    "fingertip position towards the wall "
                    "(from its start), velocity, grip force applied",
                    low=(-GRIP_X_FULL_SCALE_M, -v_fs, lo),
                    high=(GRIP_X_FULL_SCALE_M, v_fs, hi),
                )
            ]
            + self._touch_blocks()
            + self._slip_blocks()
        )
        self._settled = self._settle()
        self._z0 = self._qpos(np.concatenate([[0.0], self._settled]), "object_z")
        self._x0 = self._qpos(np.concatenate([[0.0], self._settled]), "grip")
        self.friction = self.friction_range[1]
        self._load = (0.0, 0.0, 0.0, 1.0)  # N, N, s, s: base, rise, rise start, rise time
        self._grip = self.settle_force_n
        # the per-step layout: state entries of the grip joint (qpos, qvel),
        # the inputs' columns, each physics step's time offset, the
        # sensordata columns the slip features read
        self._grip_adr = (
            1 + int(m.joint("grip").qposadr[0]),
            1 + m.nq + int(m.joint("grip").dofadr[0]),
        )
        self._inputs_buffer = np.zeros((frame_skip, self.nuser))
        self._load_column = m.nu + 6 * self._object_body + 2
        self._step_offsets_s = (m.opt.timestep * np.arange(frame_skip)).tolist()
        if touch != "none":
            lay = self.layout
            adr, b = lay.sensor_adr, lay.blocks
            self._slip_columns = (
                adr + b["force"].start,
                adr + b["slip"].start,
                adr + b["slip"].start + 1,
                slice(adr + b["pressure"].start, adr + b["pressure"].stop),
                slice(adr + b["shear"].start, adr + b["shear"].stop),
            )

    def _slip_blocks(self) -> list[ObsBlock]:
        if self.touch == "none":
            return []
        return [
            ObsBlock(
                "slip",
                SLIP_FEATURES,
                "1",
                "stuck share of the contact area (cells that did not slip in the step's "
                "last physics step, and the least over the step; 1 without contact), "
                "slip zone share (cells whose traction is within 1% of the Coulomb limit mu p, "
                "end of step), the slip zone's mean distance from the contact's centre over the "
                "contact's equivalent radius (0: no slip zone)",
                low=0.0,
                high=(1.0, 1.0, 1.0, RING_RADIUS_MAX),
            )
        ]

    def _slip_features(self, sensordata: np.ndarray | None) -> np.ndarray:
        if sensordata is None:  # before the first step: nothing loaded, nothing slips
            return np.array([1.0, 1.0, 0.0, 0.0])
        normal_col, stuck_col, mu_col, pressure, shear = self._slip_columns
        share = np.where(sensordata[:, normal_col] > 0, sensordata[:, stuck_col], 1.0)
        last = sensordata[-1]
        nx = self.layout.nx
        zone = slip_zone(
            last[pressure].reshape(nx, nx), last[shear].reshape(2, nx, nx), last[mu_col]
        )
        return np.array([share[-1], share.min(), *zone])

    def _settle(self, duration_s: float = 0.2) -> np.ndarray:
        """Physics state with the block gripped at settle_force_n, at rest."""
        m, d = self.model, self.data
        m.geom_friction[self._object_geom, 0] = self.friction_range[1]
        mujoco.mj_resetData(m, d)
        d.ctrl[:] = self.settle_force_n
        for _ in range(round(duration_s / m.opt.timestep)):
            mujoco.mj_step(m, d)
        return self._physics_state()

    def load_n(self, time_s: np.ndarray | float) -> np.ndarray:
        """External load on the block (N, downwards) at time_s; gravity comes on top."""
        base, rise, t0, duration = self._load
        if isinstance(time_s, float):  # the per-step path, without numpy's overhead
            return base + rise * min(max((time_s - t0) / duration, 0.0), 1.0)
        return base + rise * np.clip((np.asarray(time_s) - t0) / duration, 0.0, 1.0)

    def _task_reset(self, options):
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; SlipHold takes none")
        rng = self.np_random
        self.friction = float(rng.uniform(*self.friction_range))
        self._load = (
            float(rng.uniform(*self.base_load_range_n)),
            float(rng.uniform(*self.rise_load_range_n)),
            float(rng.uniform(*self.rise_start_range_s)),
            float(rng.uniform(*self.rise_time_range_s)),
        )
        self.model.geom_friction[self._object_geom, 0] = self.friction
        self._state = self._initial_state(self._settled)
        self._grip = self.settle_force_n
        self._z_last = self._z0

    def _reset_info(self) -> dict:
        return self._info(0.0)

    def _info(self, slip_m: float) -> dict:
        t = float(self._state[0])
        load = float(self.load_n(t))
        return {
            "friction": self.friction,
            "load_n": load,
            "total_load_n": load + BLOCK_MASS_KG * -self.model.opt.gravity[2],
            "grip_force_n": self._grip,
            "slip_m": slip_m,
            "object_drop_m": self._z0 - self._qpos(self._state, "object_z"),
        }

    def _inputs(self, a: np.ndarray) -> np.ndarray:
        """The control step's inputs, in a buffer reused every step: ctrl
        (the grip force), then xfrc_applied (only the load on the block)."""
        lo, hi = self.force_range_n
        self._grip = lo + 0.5 * (float(a[0]) + 1.0) * (hi - lo)
        t0_s = float(self._state[0])
        inputs = self._inputs_buffer
        inputs[:, : self.model.nu] = self._grip
        # load_n's per-step path for each physics step: a few floats, cheaper than numpy
        inputs[:, self._load_column] = [-self.load_n(t0_s + dt) for dt in self._step_offsets_s]
        return inputs

    def _observe(self, final_state, sensordata) -> np.ndarray:
        s = self._state
        obs = np.empty(self.observation_space.shape[0])
        obs[0] = s[self._grip_adr[0]] - self._x0
        obs[1] = s[self._grip_adr[1]]
        obs[2] = self._grip
        if self.touch != "none":
            k = 3
            for block in self._touch_features(sensordata):
                obs[k : k + block.size] = block
                k += block.size
            obs[k:] = self._slip_features(sensordata)
        return self._bounded(obs)

    def _outcome(self, final_state, sensordata, a):
        z_end = self._qpos(self._state, "object_z")
        slip = max(0.0, self._z_last - z_end)  # how far the block moved down this step
        self._z_last = z_end
        reward = -self.force_cost * self._grip - self.slip_cost * slip * 1e3
        terminated = self._z0 - z_end >= self.drop_m
        if terminated:
            reward -= self.drop_penalty
        return self._observe(final_state, sensordata), reward, terminated, self._info(slip)

    def _camera(self) -> mujoco.MjvCamera:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = [0.0, -0.006, 0.0]
        # from behind the finger: the skin's drawing above the pad faces -y
        cam.distance, cam.elevation, cam.azimuth = 0.07, -15.0, 110.0
        return cam


# The fixed test episodes (reset seeds) that examples/slip_reflex.py and
# examples/slip_learn.py score on; training draws from other seeds.
TEST_SEEDS = tuple(range(1000, 1030))


def evaluate(policy, seeds=TEST_SEEDS, env: SlipHoldEnv | None = None, **env_kwargs) -> dict:
    """Run policy on the episodes reset with seeds (one each, to the time
    limit of 100 steps or the drop). policy: ``policy(obs, env) -> action``,
    with an optional ``reset()`` called before each episode. Returns per
    episode: ``returns``, ``dropped`` (bool), ``mean_grip_n`` (over the steps
    held), and their means ``mean_return``, ``drops``, ``mean_grip_n_all``."""
    env = env or SlipHoldEnv(**env_kwargs)
    returns, dropped, grips = [], [], []
    for seed in seeds:
        if hasattr(policy, "reset"):
            policy.reset()
        obs, _ = env.reset(seed=int(seed))
        total, forces, term = 0.0, [], False
        for _ in range(EPISODE_STEPS):
            obs, r, term, _, info = env.step(policy(obs, env))
            total += r
            forces.append(info["grip_force_n"])
            if term:
                break
        returns.append(total)
        dropped.append(bool(term))
        grips.append(float(np.mean(forces)))
    return {
        "returns": returns,
        "dropped": dropped,
        "mean_grip_n": grips,
        "mean_return": float(np.mean(returns)),
        "drops": int(np.sum(dropped)),
        "mean_grip_n_all": float(np.mean(grips)),
    }


def grip_action(env: SlipHoldEnv, force_n: float) -> np.ndarray:
    """The action that commands force_n (clipped to force_range_n)."""
    lo, hi = env.force_range_n
    return np.array([np.clip(2 * (force_n - lo) / (hi - lo) - 1, -1, 1)], np.float32)
