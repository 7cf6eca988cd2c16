"""Gymnasium-Robotics' HandManipulateBlock with five fingertip skins in place
of its 92 MuJoCo touch sensors (``pip install 'mjtouch[robots]'``).

``HandManipulateBlock_ContinuousTouchSensors-v1`` appends the readings of
92 ``touch`` sensors (site volumes over the palm and phalanges) to the
block task's observation. :class:`HandBlockSkinEnv` is the same task
(Gymnasium-Robotics' ``MujocoHandBlockEnv``: model, actions, goal, reward
unchanged) whose model is rebuilt with an ``mjtouch.skin`` on each distal
phalanx's capsule, one ``mjtouch.attach(spec, body=...)`` call each, facing
the pad side (the side that flexing the finger moves forward) tilted 40
degrees toward the tip (PAD_TILT_DEG), where the fingers press the block,
with the RL preset (`mjtouch.scene.robot.RL_SKIN`) at 0.45 mm pitch: a
19 mm patch from mid-pad over the tip (SKIN_PRESET). Gymnasium-Robotics loads its
XML with ``MjModel.from_xml_path``; the env overrides that one step
(``_initialize_simulation``) to load it as an ``MjSpec``, attach the skins
and compile.

Observation (``observation`` key; ``achieved_goal`` and ``desired_goal`` as
in HandManipulateBlock):

| slice | size | units | meaning |
|---|---|---|---|
| 0:61 | 61 | rad, m, ... | HandManipulateBlock's: hand qpos and qvel, block qvel, block pose |
| 61:86 | 5 x 5 | | per fingertip (ff, mf, rf, lf, th), in that order: |
| | 3 | spikes | SA1, RA, PC spike counts summed over the skin's receptors and the env step |
| | 1 | N | the skin's normal force, mean over the env step |
| | 1 | 1 | share of MuJoCo's normal force on the fingertip geom that lands on the skin's patch over the env step (1 without contact) |

Version history: v0, the first.
"""

from __future__ import annotations

import importlib.util
import time

import mujoco
import numpy as np

import mjtouch
from mjtouch.scene.robot import RL_SKIN, distal_joint, flexion_facing

FINGERS = ("ff", "mf", "rf", "lf", "th")
FEATURES = ("SA1", "RA", "PC", "force_n", "coverage")
BASE_OBS = 61  # HandManipulateBlock's observation length

# Where the skins sit. Grasping the block, the fingers press it with the
# capsule's end cap (12-17 mm along a 7 mm capsule whose cylinder spans
# +-12 mm), not mid-pad: a patch facing the palm side straight carries a
# fifth of MuJoCo's fingertip normal force. Facing 40 degrees from the palm
# side toward the tip puts the patch's pole on the cap's palm-side shoulder,
# and a 19 mm patch (the rl preset's 43 x 43 grid, hence its cost, at
# 0.45 mm pitch: still finer than the receptors' 1.2-1.7 mm spacing) spans
# the capsule's width and reaches from mid-pad over the tip, so contacts on
# the cap and on the pad's far half (normals within 45 degrees of the pole)
# are felt. Less tilt leaves the tip's contacts past 45 degrees; more leaves
# the pad's.
PAD_TILT_DEG = 40.0
SKIN_PRESET = dict(RL_SKIN, pitch=4.5e-4)


def _require_gymnasium_robotics():
    if importlib.util.find_spec("gymnasium_robotics") is None:
        raise ImportError(
            "mjtouch.envs.hand_block needs Gymnasium-Robotics: pip install 'mjtouch[robots]'"
        )


def _robot_obs(model: mujoco.MjModel, data: mujoco.MjData, joint_names) -> np.ndarray:
    """Gymnasium-Robotics' robot_get_obs (qpos then qvel of the joints named
    robot*, all hinges here), which fails on MuJoCo 4.0: its
    ``jnt_type in (mjtJoint.mjJNT_HINGE, ...)`` compares a numpy int to an
    enum that is no longer an int."""
    ids = [model.joint(n).id for n in joint_names if n.startswith("robot")]
    return np.concatenate([data.qpos[model.jnt_qposadr[ids]], data.qvel[model.jnt_dofadr[ids]]])


def _block_obs(env, touch: np.ndarray) -> dict:
    """HandManipulateBlock's observation (61) with `touch` appended."""
    object_qvel = env._utils.get_joint_qvel(env.model, env.data, "object:joint")  # a free joint
    achieved_goal = env._get_achieved_goal().ravel()
    robot = _robot_obs(env.model, env.data, env._model_names.joint_names)
    observation = np.concatenate([robot, object_qvel, achieved_goal, touch])
    return {
        "observation": observation,
        "achieved_goal": achieved_goal.copy(),
        "desired_goal": env.goal.ravel().copy(),
    }


def _make_sensor_env_class():
    """The reference: Gymnasium-Robotics' 92-sensor env (``touch_get_obs``
    "sensordata"), its observation read as on MuJoCo 4.0 (_robot_obs)."""
    _require_gymnasium_robotics()
    from gymnasium_robotics.envs.shadow_dexterous_hand.manipulate_block_touch_sensors import (
        MujocoHandBlockTouchSensorsEnv,
    )

    class HandBlockTouchSensorsEnv(MujocoHandBlockTouchSensorsEnv):
        def _get_obs(self):
            return _block_obs(self, self.data.sensordata[self._touch_sensor_id])

    return HandBlockTouchSensorsEnv


def shadow_pad_facing(
    model: mujoco.MjModel, finger: str, tilt_deg: float = PAD_TILT_DEG
) -> np.ndarray:
    """The pad side of Shadow fingertip `finger`'s distal capsule
    (``robot0:C_<finger>distal``) in the geom's frame: where flexing its
    distal joint moves it (mjtouch.scene.robot.flexion_facing), across the
    capsule's axis (its cylinder) and rounded to the nearest geom axis, then
    turned by `tilt_deg` toward the tip (the capsule's end away from the
    distal joint) about the axis across both."""
    if not (np.isfinite(tilt_deg) and 0.0 <= tilt_deg <= 90.0):
        raise ValueError(f"tilt_deg = {tilt_deg!r}: valid 0 (pad side) to 90 (tip), in degrees")
    name = f"robot0:C_{finger}distal"
    move = flexion_facing(model, name)
    move[2] = 0.0
    axis = int(np.argmax(np.abs(move)))
    pad = np.zeros(3)
    pad[axis] = np.sign(move[axis])
    # the tip: the capsule's +z or -z end, whichever lies away from the joint
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    g = model.geom(name).id
    j = distal_joint(model, model.geom_bodyid[g])
    anchor = data.geom_xmat[g].reshape(3, 3).T @ (data.xanchor[j] - data.geom_xpos[g])
    tip = np.array([0.0, 0.0, -np.sign(anchor[2]) or 1.0])
    t = np.radians(tilt_deg)
    f = np.cos(t) * pad + np.sin(t) * tip
    return np.where(np.abs(f) < 1e-15, 0.0, f)


def add_shadow_skins(
    spec: mujoco.MjSpec, tilt_deg: float = PAD_TILT_DEG, **attributes
) -> list[str]:
    """Attach a skin (named ``skin_<finger>``) to each Shadow fingertip of
    `spec` (Gymnasium-Robotics' hand), on its pad side tilted `tilt_deg`
    toward the tip, with SKIN_PRESET updated by `attributes`. Returns the
    skin names in FINGERS order."""
    model = spec.compile()
    attrs = dict(SKIN_PRESET, outputs="spikes force coverage")
    attrs.update(attributes)
    names = []
    for f in FINGERS:
        name = f"skin_{f}"
        mjtouch.attach(
            spec,
            body=f"robot0:{f}distal",
            name=name,
            facing=shadow_pad_facing(model, f, tilt_deg),
            **attrs,
        )
        names.append(name)
    return names


def _make_env_class():
    _require_gymnasium_robotics()
    from gymnasium_robotics.envs.shadow_dexterous_hand.manipulate_block import (
        MujocoHandBlockEnv as base,
    )

    class HandBlockSkinEnv(base):
        def __init__(self, skin: dict | None = None, pad_tilt_deg: float = PAD_TILT_DEG, **kwargs):
            # skin: attributes replacing SKIN_PRESET's (attach's keywords)
            self._skin_attributes = dict(skin or {})
            self._pad_tilt_deg = pad_tilt_deg
            base.__init__(self, **kwargs)

        # Gymnasium-Robotics' MujocoRobotEnv._initialize_simulation, with the
        # model loaded as a spec and the skins attached before compiling.
        def _initialize_simulation(self):
            spec = mujoco.MjSpec.from_file(self.fullpath)
            self.skins = add_shadow_skins(spec, self._pad_tilt_deg, **self._skin_attributes)
            self.model = spec.compile()
            self.data = mujoco.MjData(self.model)
            self._model_names = self._utils.MujocoModelNames(self.model)
            self.model.vis.global_.offwidth = self.width
            self.model.vis.global_.offheight = self.height
            self._index_skins()
            self._env_setup(initial_qpos=self.initial_qpos)
            self.initial_time = self.data.time
            self.initial_qpos = np.copy(self.data.qpos)
            self.initial_qvel = np.copy(self.data.qvel)

        def _index_skins(self):
            lays = mjtouch.layouts(self.model)
            self.layouts = [lays[n] for n in self.skins]
            # sensordata indices: every skin's spikes (summed per class later),
            # force normal, coverage share and MuJoCo's normal force
            spikes, classes, force, share, mj = [], [], [], [], []
            for k, lay in enumerate(self.layouts):
                base_adr = lay.sensor_adr
                s = lay.blocks["spikes"]
                idx = np.arange(s.start, s.stop) + base_adr
                spikes.append(idx)
                per = np.empty(idx.size, int)
                for c, cls in enumerate(FEATURES[:3]):
                    per[lay.mask(cls)] = 3 * k + c
                classes.append(per)
                fb, cb = lay.blocks["force"], lay.blocks["coverage"]
                force.append(base_adr + fb.start)
                share.append(base_adr + cb.start)
                mj.append(base_adr + cb.start + 1)
            self._spike_idx = np.concatenate(spikes)
            self._spike_class = np.concatenate(classes)
            self._force_idx, self._share_idx, self._mj_idx = map(np.array, (force, share, mj))
            self._touch = np.zeros((len(FINGERS), len(FEATURES)))
            self._touch[:, 4] = 1.0

        def _mujoco_step(self, action):
            # one physics step at a time: spikes are per step
            sd = self.data.sensordata
            spikes = np.zeros(self._spike_idx.size)
            force = np.zeros(len(FINGERS))
            carried = np.zeros(len(FINGERS))
            total = np.zeros(len(FINGERS))
            for _ in range(self.n_substeps):
                mujoco.mj_step(self.model, self.data)
                spikes += sd[self._spike_idx]
                force += sd[self._force_idx]
                mj = sd[self._mj_idx]
                carried += sd[self._share_idx] * mj
                total += mj
            t = self._touch
            t[:, :3] = np.bincount(self._spike_class, spikes, 3 * len(FINGERS)).reshape(-1, 3)
            t[:, 3] = force / self.n_substeps
            t[:, 4] = np.divide(carried, total, out=np.ones_like(total), where=total > 0)

        def _reset_sim(self):
            # Gymnasium-Robotics' manipulate envs reset qpos, qvel and time
            # only; a fresh MjData state also resets the skins (plugin
            # state) and the solver's warm start, so that episodes repeat
            mujoco.mj_resetData(self.model, self.data)
            ok = super()._reset_sim()
            self._touch[:] = 0.0
            self._touch[:, 4] = 1.0
            return ok

        def _get_obs(self):
            return _block_obs(self, self._touch.ravel())

    HandBlockSkinEnv.__doc__ = __doc__  # the observation table
    return HandBlockSkinEnv


_LAZY = {"HandBlockSkinEnv": _make_env_class, "HandBlockTouchSensorsEnv": _make_sensor_env_class}


def __getattr__(name):  # the env classes are built on first use (optional dependency)
    if name in _LAZY:
        cls = _LAZY[name]()
        globals()[name] = cls
        return cls
    raise AttributeError(name)


ENV_ID = "mjtouch/HandManipulateBlockSkin-v0"


def _register():
    import gymnasium as gym

    if ENV_ID not in gym.registry:
        gym.register(
            id=ENV_ID, entry_point="mjtouch.envs.hand_block:HandBlockSkinEnv", max_episode_steps=100
        )


_register()


def steps_per_second(env, steps: int, seed: int = 0) -> float:
    """Env steps per second under uniform random actions (resets included)."""
    env.reset(seed=seed)
    env.action_space.seed(seed)
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - start)


def main(argv=None) -> None:
    """Print env steps/s of HandManipulateBlock with its 92 touch sensors and
    with five skins, interleaved and repeated (min and median)."""
    import argparse

    import gymnasium as gym

    p = argparse.ArgumentParser(description=main.__doc__)
    p.add_argument("--steps", type=int, default=100, help="env steps per measurement")
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args(argv)
    sensors = __getattr__("HandBlockTouchSensorsEnv")
    envs = {
        "92 MuJoCo touch sensors": gym.wrappers.TimeLimit(sensors(), max_episode_steps=100),
        "5 mjtouch skins": gym.make(ENV_ID),
    }
    rates = {k: [] for k in envs}
    for r in range(args.repeats):
        for k, env in envs.items():
            rates[k].append(steps_per_second(env, args.steps, seed=r))
    for k, v in rates.items():
        print(f"{k:30s} env steps/s: min {min(v):7.1f}  median {np.median(v):7.1f}")


if __name__ == "__main__":
    main()
