"""``mjtouch/TextureExplore-v0``: identify a texture by touching it.

A ridged fingertip rests on a plate with one of K textures (gratings of
different spatial periods, or flat), drawn at random each episode with a
random phase. The agent presses and slides the fingertip and, when it is
ready, commits to an answer. The textures do not collide in MuJoCo (the skin
renders them), so the finger's motion and MuJoCo's contact force are the
same for every texture: without touch the task is at chance.

Action (Box, [-1, 1]^(3+K)):

| index | meaning |
|---|---|
| 0 | normal force: -1 -> ``force_range_n[0]``, +1 -> ``force_range_n[1]`` (N) |
| 1 | sliding speed along x: ``a * max_speed_m_s`` (m/s) |
| 2 | commit: > 0 ends the episode with the answer argmax(a[3:]) |
| 3.. | one score per texture class (``classes``) |

Observation (Box, float64), blocks in this order (``env.unwrapped.describe_observation()``),
with their bounds (F = ``force_range_n[1]``, V = ``max_speed_m_s``, T = control step,
n_c = receptors of the class, mu = the pad's friction; *: full scale, saturates):

| block | size | units | meaning | bounds |
|---|---|---|---|---|
| ``finger`` | 2 | m, m/s | fingertip x from its start, x velocity | +-25 mm*, +-(2 V + 0.01)* |
| ``command`` | 2 | N, m/s | the normal force and sliding speed being applied | the action's |
| ``touch`` | 3 | spikes or Hz | SA1, RA, PC spike counts over the control step (or rates) | 0 to n_c (ceil(T / 1 ms) + 1) |
| ``contact`` | 3 | N | skin force (normal, tangential x, y), mean over the step | 0 to 5 F*, +-5 mu F* |
| ``pressure`` | p*p | kPa | optional, ``pressure_image=p``: end-of-step pressure, p x p | 0 to 5 F / block area* |

``touch="none"``: only ``finger`` and ``command`` (the skin is not in the scene).

Reward: +1 for a correct answer, 0 for a wrong one, and ``-step_cost`` per
control step. The episode terminates on commit and is truncated by the time
limit (``max_episode_steps``, 50 control steps = 0.5 s by default).

``reset(options={"texture": k})`` fixes the class (for collecting data).
"""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np

from mjtouch._validate import in_range
from mjtouch.envs.base import ObsBlock, TouchEnv
from mjtouch.scene import scenes

DEFAULT_CLASSES = (0.0, 0.6e-3, 1.0e-3, 1.5e-3, 2.5e-3)  # grating period D (m); 0: flat
PARK_Y_M = 0.5  # unused textures wait here, far outside the pad's footprint
TEXTURE_LENGTH_M = 0.06
TRAVEL_M = 0.02  # the finger stays within +-20 mm of its start
# Full scales of the finger block: the slide servo's setpoint is clamped to
# +-TRAVEL_M (actrange); it is critically damped, so it barely overshoots
# (measured: 1.04 x the commanded speed with bang-bang actions).
FINGER_X_FULL_SCALE_M = TRAVEL_M + 5e-3
FINGER_SPEED_MARGIN_M_S = 0.01


# Receptor densities of the environments' skin, SA1 RA PC per cm^2: a
# quarter of the human fingertip's SA1 and RA (mjtouch.bench.configs.
# DEFAULT_DENSITY), all of its PC (the slip and texture vibration channel).
ENV_DENSITY_PER_CM2 = (17.5, 35.0, 21.0)


def env_fingertip(
    nx: int = 48, pitch_m: float = 2e-4, radius_m: float = 3.5e-3, outputs: str = "spikes force"
) -> scenes.Fingertip:
    """The environments' skin: 48 x 48 taxels at 0.2 mm (9.6 mm, the whole
    contact up to ~0.8 N), receptors within 3.5 mm of the pole at
    ENV_DENSITY_PER_CM2 (~28: 7 SA1, 13 RA, 8 PC); exact stress and
    Winkler contact, stages 1-3 once per physics step (the receptors'
    substeps interpolate their input), as the RL preset (README "What
    accuracy costs": the elastic contact costs ~10x in stages 1-2; pass a tip
    with skin={"pressure": "elastic"} where fingerprint filtering matters)."""
    return scenes.Fingertip(
        nx=nx,
        pitch_m=pitch_m,
        skin={
            "radius": f"{radius_m:.9g}",
            "density": " ".join(f"{d:.9g}" for d in ENV_DENSITY_PER_CM2),
            "outputs": outputs,
            "pressure": "winkler",
            "substep": "receptors",
        },
    )


def texture_explore_spec(
    classes=DEFAULT_CLASSES,
    tip: scenes.Fingertip | None = None,
    timestep_s: float = 1e-3,
    skin: bool = True,
) -> mujoco.MjSpec:
    """Fingertip over a flat colliding plate; one non-colliding grating per
    textured class on a mocap body (placed under the pad, or parked)."""
    tip = tip or env_fingertip()
    spec = mujoco.MjSpec()
    spec.modelname = "mjtouch_texture_explore"
    scenes.set_options(spec, scenes.Protocol(timestep_s=timestep_s))
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 640, 480
    world = spec.worldbody
    world.add_light(pos=[0, 0, 0.3], dir=[0, 0, -1])
    world.add_geom(
        name="plate",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.04, 0.015, 0.002],
        pos=[0, 0, -0.002],
        friction=[0.5, 0.005, 0.0001],
        rgba=[0.55, 0.6, 0.65, 1],
    )
    res = 5e-5  # height-field spacing: >= 12 samples per period for D >= 0.6 mm
    for k, period in enumerate(classes):
        if period == 0:
            continue
        tex = scenes.Texture(period_m=period, length_m=TEXTURE_LENGTH_M, resolution_m=res)
        scenes.add_grating_hfield(spec, f"tex{k}", tex, 0.012)
        body = world.add_body(name=f"tex{k}", mocap=True, pos=[0, PARK_Y_M, 0])
        body.add_geom(
            type=mujoco.mjtGeom.mjGEOM_HFIELD,
            hfieldname=f"tex{k}",
            contype=0,
            conaffinity=0,
            group=scenes.TEXTURE_GROUP,
            rgba=[0.45, 0.5, 0.55, 1],
        )
    scenes.add_fingertip(spec, tip, start_x_m=0.0, travel_m=TRAVEL_M, skin=skin)
    # The project's pad-plate contact, its friction tuned to a mid exploration
    # (0.5 N, 25 mm/s): Coulomb friction with a steady normal force.
    scenes.add_pad_plate_contact(
        spec, tip, scenes.Protocol(force_n=0.5, speed_m_s=0.025, timestep_s=timestep_s)
    )
    return spec


class TextureExploreEnv(TouchEnv):
    __doc__ = __doc__

    def __init__(
        self,
        classes=DEFAULT_CLASSES,
        *,
        touch: str = "counts",
        pressure_image: int = 0,
        force_range_n=(0.1, 1.0),
        max_speed_m_s: float = 0.05,
        control_dt_s: float = 0.01,
        timestep_s: float = 1e-3,
        step_cost: float = 0.01,
        settle_force_n: float = 0.5,
        render_mode: str | None = None,
        render_size=(480, 640),
    ):
        classes = tuple(float(c) for c in classes)
        if not 2 <= len(classes) <= 16:
            raise ValueError(f"classes has {len(classes)} entries; valid 2 to 16")
        for c in classes:
            if c != 0:
                in_range("classes entry (grating period)", c, 2e-4, 1e-2, "m (0: flat)")
        if len(set(classes)) != len(classes):
            raise ValueError(f"classes {classes} has duplicates")
        lo, hi = (float(v) for v in force_range_n)
        in_range("force_range_n[0]", lo, 0.01, 5.0, "N")
        in_range("force_range_n[1]", hi, lo, 5.0, "N")
        in_range("max_speed_m_s", max_speed_m_s, 0.0, 0.2, "m/s")
        in_range("timestep_s", timestep_s, 1e-4, 2e-3, "s")
        in_range("control_dt_s", control_dt_s, timestep_s, 0.1, "s")
        in_range("step_cost", step_cost, 0.0, 1.0)
        in_range("settle_force_n", settle_force_n, lo, hi, "N")
        frame_skip = round(control_dt_s / timestep_s)
        if not math.isclose(frame_skip * timestep_s, control_dt_s, rel_tol=1e-9):
            raise ValueError(
                f"control_dt_s = {control_dt_s} must be a multiple of timestep_s = {timestep_s}"
            )
        outputs = "spikes force pressure" if pressure_image else "spikes force"
        tip = env_fingertip(outputs=outputs)
        model_spec = texture_explore_spec(classes, tip, timestep_s, skin=touch != "none")
        spec = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_MOCAP_POS
        super().__init__(
            model_spec,
            touch=touch,
            pressure_image=pressure_image,
            frame_skip=frame_skip,
            user_spec=int(spec),
            render_mode=render_mode,
            render_size=render_size,
            max_force_n=hi,
            max_friction=tip.friction,
        )
        self.classes = classes
        self.force_range_n = (lo, hi)
        self.max_speed_m_s = float(max_speed_m_s)
        self.step_cost = float(step_cost)
        m = self.model
        self._mocap = {
            k: m.body_mocapid[m.body(f"tex{k}").id] for k, c in enumerate(classes) if c != 0
        }
        self._x0 = self._qpos_model("slide_x")
        self.action_space = gym.spaces.Box(-1.0, 1.0, (3 + len(classes),), np.float32)
        v_fs = 2 * self.max_speed_m_s + FINGER_SPEED_MARGIN_M_S
        self._set_blocks(
            [
                ObsBlock(
                    "finger",
                    2,
                    "m, m/s",
                    "fingertip x from its start, x velocity",
                    low=(-FINGER_X_FULL_SCALE_M, -v_fs),
                    high=(FINGER_X_FULL_SCALE_M, v_fs),
                ),
                ObsBlock(
                    "command",
                    2,
                    "N, m/s",
                    "normal force and sliding speed applied",
                    low=(lo, -self.max_speed_m_s),
                    high=(hi, self.max_speed_m_s),
                ),
            ]
            + self._touch_blocks()
        )
        self.settle_force_n = float(settle_force_n)
        self._settled = self._settle(self.settle_force_n)
        self.label = 0
        self._command = np.array([self.settle_force_n, 0.0])
        self._last_obs = None
        self._mocap_pos = np.zeros((m.nmocap, 3))
        self._inputs_buffer = np.zeros((frame_skip, self.nuser))
        # the slide joint's entries in the full-physics state (qpos, qvel)
        self._slide_adr = (
            1 + int(m.joint("slide_x").qposadr[0]),
            1 + m.nq + int(m.joint("slide_x").dofadr[0]),
        )

    def _qpos_model(self, joint: str) -> float:
        return float(self.model.qpos0[self.model.jnt_qposadr[self.model.joint(joint).id]])

    def _settle(self, force_n: float, duration_s: float = 0.15) -> np.ndarray:
        """Physics state after pressing with force_n, at rest (the same for
        every texture: textures do not collide)."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.mocap_pos[:] = [0, PARK_Y_M, 0]
        d.ctrl[:] = [0.0, -force_n]
        for _ in range(round(duration_s / m.opt.timestep)):
            mujoco.mj_step(m, d)
        return self._physics_state()

    def _task_reset(self, options):
        options = dict(options or {})
        k = options.pop("texture", None)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; valid: 'texture'")
        if k is None:
            k = int(self.np_random.integers(len(self.classes)))
        elif not (isinstance(k, (int, np.integer)) and 0 <= k < len(self.classes)):
            raise ValueError(f"reset option texture = {k!r}; valid 0 to {len(self.classes) - 1}")
        self.label = int(k)
        self._mocap_pos = np.tile([0.0, PARK_Y_M, 0.0], (self.model.nmocap, 1))
        if self.classes[k] != 0:
            phase = float(self.np_random.uniform(0.0, self.classes[k]))
            self._mocap_pos[self._mocap[k]] = [phase, 0.0, 0.0]
        self._state = self._initial_state(self._settled)
        self._inputs_buffer[:, 2:] = self._mocap_pos.ravel()
        self._command = np.array([self.settle_force_n, 0.0])
        self._last_obs = None

    def _reset_info(self) -> dict:
        return {"texture": self.label, "period_m": self.classes[self.label]}

    def _inputs(self, a: np.ndarray) -> np.ndarray | None:
        if a[2] > 0:
            return None
        lo, hi = self.force_range_n
        force = lo + 0.5 * (a[0] + 1.0) * (hi - lo)
        speed = a[1] * self.max_speed_m_s
        self._command = np.array([force, speed])
        # a buffer reused every step: ctrl (speed, -force), then the
        # episode's mocap positions (written at reset)
        inputs = self._inputs_buffer
        inputs[:, 0] = speed
        inputs[:, 1] = -force
        return inputs

    def _observe(self, final_state, sensordata) -> np.ndarray:
        s = self._state
        obs = np.empty(self.observation_space.shape[0])
        obs[0] = s[self._slide_adr[0]] - self._x0
        obs[1] = s[self._slide_adr[1]]
        obs[2:4] = self._command
        k = 4
        for block in self._touch_features(sensordata):
            obs[k : k + block.size] = block
            k += block.size
        return self._bounded(obs)

    def _outcome(self, final_state, sensordata, a):
        info = {"texture": self.label, "period_m": self.classes[self.label]}
        if final_state is None:  # committed
            guess = int(np.argmax(a[3:]))
            correct = guess == self.label
            info.update(guess=guess, correct=correct)
            obs = self._last_obs.copy() if self._last_obs is not None else self._observe(None, None)
            return obs, float(correct) - self.step_cost, True, info
        obs = self._observe(final_state, sensordata)
        self._last_obs = obs
        return obs, -self.step_cost, False, info

    def _camera(self) -> mujoco.MjvCamera:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        cam.trackbodyid = self.model.body("finger").id
        cam.distance, cam.elevation, cam.azimuth = 0.045, -45.0, 120.0
        return cam
