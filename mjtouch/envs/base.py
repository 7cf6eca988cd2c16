"""Shared machinery of the mjtouch Gymnasium environments.

A :class:`TouchEnv` owns one MuJoCo model with an ``mjtouch.skin`` fingertip
and advances it one control step at a time with :func:`mujoco.rollout`
(``frame_skip`` physics steps, open-loop inputs held over the control step,
without the GIL), so that a batch of environments can step on threads
(:class:`mjtouch.envs.vector.RolloutVectorEnv`) with bit-identical results.
Every control step starts the constraint solver's warm start from zero.

Task logic lives in three hooks a subclass implements:
``_task_reset`` (sample the episode, return the user inputs' template),
``_inputs`` (action -> per-step inputs, or None to end without physics) and
``_outcome`` (sensordata of the step and its final state -> reward, termination, info).

Touch observations (documented per environment):

- ``touch``: spike counts of each class (SA1, RA, PC) summed over the class's
  receptors and the control step (``touch="counts"``), or the mean firing
  rate per receptor in Hz (``touch="rates"``);
- ``contact``: the skin's force block averaged over the control step:
  normal force and tangential force along pad x and y (N);
- ``pressure`` (only with ``pressure_image=p``): the taxel pressure at the
  end of the control step, averaged into p x p blocks (kPa), row-major.

Every entry has finite bounds (the observation space's Box). Counts and rates
are bounded exactly by the refractory period (at most ceil(T / t_ref) + 1
spikes per receptor in a control step T). The measured quantities (finger
motion, forces, pressure) have a full-scale range, like a real sensor's,
several times what the task's actuators can produce in steady state; they
saturate (are clipped) there, which the tests check never happens under
random or bang-bang actions.

``touch="none"`` builds the scene without the skin plugin (and these blocks
from the observation): the same task with MuJoCo alone, the baseline for
the benchmark and for showing what touch adds.
"""

from __future__ import annotations

import dataclasses
import math

import gymnasium as gym
import mujoco
import mujoco.rollout
import numpy as np

from mjtouch._validate import choice
from mjtouch.scene.sensor import CLASSES, SkinLayout

TOUCH_MODES = ("counts", "rates", "none")
FULLPHYSICS = mujoco.mjtState.mjSTATE_FULLPHYSICS.value
# The skin's `refractory` attribute default (plugin/README.md), all classes.
REFRACTORY_DEFAULT_S = 1e-3
# Full-scale skin force: this many times the largest commanded force. The
# mean over a control step exceeds the command only by impact transients
# (measured: 1.09 x at 1 N with bang-bang actions).
FORCE_FULL_SCALE_FACTOR = 5.0


@dataclasses.dataclass(frozen=True)
class ObsBlock:
    name: str
    size: int
    units: str
    meaning: str
    low: float | tuple  # bounds of the entries (a scalar, or one per entry)
    high: float | tuple

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo = np.broadcast_to(np.asarray(self.low, np.float64), (self.size,))
        hi = np.broadcast_to(np.asarray(self.high, np.float64), (self.size,))
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo <= hi)):
            raise ValueError(f"observation block {self.name!r} has bad bounds {lo}, {hi}")
        return lo, hi


def max_spikes_per_receptor(span_s: float, refractory_s: float) -> int:
    """Most spikes one receptor can emit in span_s: spikes are at least a
    refractory period apart."""
    return math.ceil(span_s / refractory_s) + 1


class TouchEnv(gym.Env):
    """Base class: a skin scene advanced by ``mujoco.rollout`` per control step."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        model_spec: mujoco.MjSpec,
        *,
        touch: str,
        pressure_image: int,
        frame_skip: int,
        user_spec: int,
        render_mode: str | None,
        render_size: tuple[int, int],
        max_force_n: float,
        max_friction: float,
        refractory_s: float = REFRACTORY_DEFAULT_S,
    ):
        choice("touch", touch, TOUCH_MODES)
        if render_mode is not None:
            choice("render_mode", render_mode, tuple(self.metadata["render_modes"]))
        self.touch = touch
        self.render_mode = render_mode
        self._render_size = render_size
        self.model = model_spec.compile()
        self.data = mujoco.MjData(self.model)
        self.frame_skip = int(frame_skip)
        self.control_dt_s = self.frame_skip * self.model.opt.timestep
        self.user_spec = int(user_spec)
        self.nuser = mujoco.mj_stateSize(self.model, self.user_spec)
        self.layout: SkinLayout | None = None
        self._class_masks: list[np.ndarray] = []
        self.pressure_image = int(pressure_image)
        if touch != "none":
            self.layout = SkinLayout.from_model(self.model)
            self._class_masks = [self.layout.mask(c) for c in CLASSES]
            # each receptor's class index (bincount sums per class), the
            # receptors per class, and the spike and force blocks' columns
            self._class_index = np.zeros(self.layout.classes.size, dtype=np.intp)
            for k, m in enumerate(self._class_masks):
                self._class_index[m] = k
            n = np.array([max(1, int(m.sum())) for m in self._class_masks])
            self._rate_divisor = n * self.control_dt_s
            adr = self.layout.sensor_adr
            spikes = self.layout.blocks["spikes"]
            force = self.layout.blocks["force"]
            self._touch_slices = (
                slice(adr + spikes.start, adr + spikes.stop),
                slice(adr + force.start, adr + force.start + 3),
            )
            if self.pressure_image:
                nx = self.layout.nx
                if "pressure" not in self.layout.blocks:
                    raise ValueError("pressure_image needs the skin's `pressure` output block")
                if self.pressure_image < 0 or nx % self.pressure_image:
                    raise ValueError(
                        f"pressure_image = {pressure_image} must divide the skin's "
                        f"nx = {nx} (e.g. {nx // 4}, {nx // 8})"
                    )
        elif self.pressure_image:
            raise ValueError('pressure_image needs touch; with touch="none" it must be 0')
        self._runner = mujoco.rollout.Rollout(nthread=0)
        self._zero_warmstart = np.zeros((1, self.model.nv))
        self._state = np.zeros(mujoco.mj_stateSize(self.model, FULLPHYSICS))
        # rollout's sensordata, reused every control step (the hooks read it
        # before the next step)
        self._out_sensordata = np.empty((1, self.frame_skip, self.model.nsensordata))
        self._action_bounds: tuple | None = None  # (space, low, high) as float64
        self._qpos_adr: dict[str, int] = {}
        self._qvel_adr: dict[str, int] = {}
        self._renderer = None
        self._blocks: list[ObsBlock] = []
        # full scales of the touch blocks (see the module docstring)
        self.force_full_scale_n = FORCE_FULL_SCALE_FACTOR * float(max_force_n)
        self.max_friction = float(max_friction)
        self.refractory_s = float(refractory_s)

    # ----- observation layout ---------------------------------------------
    def _touch_blocks(self) -> list[ObsBlock]:
        if self.touch == "none":
            return []
        unit = "spikes" if self.touch == "counts" else "Hz"
        what = (
            "spike count per class (SA1, RA, PC), summed over the class's receptors and the "
            "control step"
            if self.touch == "counts"
            else "mean firing rate per receptor of each class (SA1, RA, PC) over the control step"
        )
        per_receptor = max_spikes_per_receptor(self.control_dt_s, self.refractory_s)
        if self.touch == "counts":
            touch_high = tuple(float(per_receptor * m.sum()) for m in self._class_masks)
        else:
            touch_high = per_receptor / self.control_dt_s
        f = self.force_full_scale_n
        ft = self.max_friction * f  # Coulomb: tangential <= mu x normal
        blocks = [
            ObsBlock("touch", 3, unit, what, low=0.0, high=touch_high),
            ObsBlock(
                "contact",
                3,
                "N",
                "skin force, mean over the control step: normal, "
                "tangential along pad x, along pad y",
                low=(0.0, -ft, -ft),
                high=(f, ft, ft),
            ),
        ]
        if self.pressure_image:
            p = self.pressure_image
            # pressure x area sums to the normal force, so a block's mean is
            # at most the force over the block's area
            block_area_m2 = (self.layout.nx // p * self.layout.pitch_m) ** 2
            blocks.append(
                ObsBlock(
                    "pressure",
                    p * p,
                    "kPa",
                    f"taxel pressure at the end of the step, {p} x {p} block means",
                    low=0.0,
                    high=f / block_area_m2 * 1e-3,
                )
            )
        return blocks

    def _set_blocks(self, blocks: list[ObsBlock]) -> None:
        self._blocks = blocks
        self.observation_blocks: dict[str, slice] = {}
        start = 0
        for b in blocks:
            self.observation_blocks[b.name] = slice(start, start + b.size)
            start += b.size
        bounds = [b.bounds() for b in blocks]
        self._obs_low = np.concatenate([lo for lo, _ in bounds])
        self._obs_high = np.concatenate([hi for _, hi in bounds])
        self.observation_space = gym.spaces.Box(self._obs_low, self._obs_high, (start,), np.float64)

    def _bounded(self, obs: np.ndarray) -> np.ndarray:
        """Saturate obs (a fresh array, clipped in place) at the full-scale
        range (see the module docstring)."""
        np.maximum(obs, self._obs_low, out=obs)
        return np.minimum(obs, self._obs_high, out=obs)

    def describe_observation(self) -> str:
        """A table of the observation blocks (name, slice, units, range, meaning)."""
        rows = [f"{'block':10s} {'slice':>9s}  {'units':10s} meaning"]
        for b in self._blocks:
            s = self.observation_blocks[b.name]
            lo, hi = b.bounds()
            if np.all(lo == lo[0]) and np.all(hi == hi[0]):
                rng = f"[{lo[0]:.3g}, {hi[0]:.3g}]"
            else:
                rng = " ".join(f"[{a:.3g}, {z:.3g}]" for a, z in zip(lo, hi))
            rows.append(
                f"{b.name:10s} {f'{s.start}:{s.stop}':>9s}  {b.units:10s} {b.meaning}\n"
                f"{'':33s}range {rng}"
            )
        return "\n".join(rows)

    def split_observation(self, obs: np.ndarray) -> dict[str, np.ndarray]:
        return {k: obs[..., s] for k, s in self.observation_blocks.items()}

    def _touch_features(self, sensordata: np.ndarray | None) -> list[np.ndarray]:
        if self.touch == "none":
            return []
        lay = self.layout
        if sensordata is None:  # before the first step: no spikes, no force yet
            out = [np.zeros(3), np.zeros(3)]
            if self.pressure_image:
                out.append(np.zeros(self.pressure_image**2))
            return out
        spikes, force_cols = self._touch_slices
        # spike counts are whole numbers, so any summation order is exact
        per_receptor = np.add.reduce(sensordata[:, spikes], axis=0)
        counts = np.bincount(self._class_index, per_receptor, len(CLASSES))
        if self.touch == "rates":
            counts = counts / self._rate_divisor
        # np.mean's arithmetic (a sum along the steps, then one division)
        force = np.add.reduce(sensordata[:, force_cols], axis=0) / sensordata.shape[0]
        out = [counts, force]
        if self.pressure_image:
            nx, p = lay.nx, self.pressure_image
            img = lay.block(sensordata[-1], "pressure").reshape(p, nx // p, p, nx // p)
            out.append(img.mean(axis=(1, 3)).ravel() * 1e-3)
        return out

    # ----- physics ---------------------------------------------------------
    def _initial_state(self, physics_state: np.ndarray) -> np.ndarray:
        """A full-physics state at time 0 with the given physics (qpos, qvel,
        act) and a fresh skin (plugin state reset)."""
        mujoco.mj_resetData(self.model, self.data)
        mujoco.mj_setState(self.model, self.data, physics_state, mujoco.mjtState.mjSTATE_PHYSICS)
        state = np.empty_like(self._state)
        mujoco.mj_getState(self.model, self.data, state, FULLPHYSICS)
        return state

    def _physics_state(self) -> np.ndarray:
        spec = mujoco.mjtState.mjSTATE_PHYSICS
        out = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, self.data, out, spec)
        return out

    def check_inputs(self, inputs: np.ndarray) -> np.ndarray:
        """inputs as rollout takes them unchecked: float64, C-contiguous,
        (frame_skip, user state size)."""
        inputs = np.ascontiguousarray(inputs, dtype=np.float64)
        if inputs.shape != (self.frame_skip, self.nuser):
            raise ValueError(
                f"inputs have shape {inputs.shape}; expected {(self.frame_skip, self.nuser)}"
            )
        return inputs

    def _advance(self, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(final state, sensordata of each physics step) of a control step.
        The final state is written into self._state (rollout has read it)."""
        # Shapes and types are fixed here, so rollout's own checks are
        # skipped; no state is recorded per step: the rollout leaves
        # self.data in the final one.
        self._runner.rollout(
            [self.model],
            [self.data],
            self._state[None],
            self.check_inputs(inputs)[None],
            control_spec=self.user_spec,
            skip_checks=True,
            nstep=self.frame_skip,
            initial_warmstart=self._zero_warmstart,
            state=None,
            sensordata=self._out_sensordata,
            chunk_size=1,
        )
        mujoco.mj_getState(self.model, self.data, self._state, FULLPHYSICS)
        return self._state, self._out_sensordata[0]

    def _qpos(self, state: np.ndarray, joint: str) -> float:
        adr = self._qpos_adr.get(joint)
        if adr is None:
            adr = self._qpos_adr[joint] = 1 + int(self.model.joint(joint).qposadr[0])
        return float(state[adr])

    def _qvel(self, state: np.ndarray, joint: str) -> float:
        adr = self._qvel_adr.get(joint)
        if adr is None:
            adr = self._qvel_adr[joint] = 1 + self.model.nq + int(self.model.joint(joint).dofadr[0])
        return float(state[adr])

    # ----- task hooks ------------------------------------------------------
    def _task_reset(self, options: dict | None) -> None:
        raise NotImplementedError

    def _inputs(self, action: np.ndarray) -> np.ndarray | None:
        raise NotImplementedError

    def _outcome(
        self, final_state: np.ndarray | None, sensordata: np.ndarray | None, action: np.ndarray
    ) -> tuple[np.ndarray, float, bool, dict]:
        raise NotImplementedError

    def _observe(self, final_state: np.ndarray | None, sensordata: np.ndarray | None) -> np.ndarray:
        raise NotImplementedError

    # ----- gymnasium API ---------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self._task_reset(options)
        obs = self._observe(None, None)
        if self.render_mode is not None:
            self._sync_render_data()
        return obs, self._reset_info()

    def _reset_info(self) -> dict:
        return {}

    def _check_action(self, action) -> np.ndarray:
        a = np.asarray(action, dtype=np.float64)
        space = self.action_space
        if a.shape != space.shape:
            raise ValueError(f"action has shape {a.shape}; expected {space.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"action {a} is not finite")
        if self._action_bounds is None or self._action_bounds[0] is not space:
            self._action_bounds = (
                space,
                space.low.astype(np.float64),
                space.high.astype(np.float64),
            )
        _, low, high = self._action_bounds
        return np.minimum(np.maximum(a, low), high)

    def step(self, action):
        a = self._check_action(action)
        inputs = self._inputs(a)
        if inputs is None:
            return self._finish(None, None, a)
        final_state, sensordata = self._advance(inputs)
        return self._finish(final_state, sensordata, a)

    def _finish(self, final_state, sensordata, action):
        """final_state: the full-physics state the control step ends in
        (None: no physics); sensordata: (frame_skip, nsensordata)."""
        if final_state is not None and final_state is not self._state:
            self._state = final_state.copy()
        obs, reward, terminated, info = self._outcome(final_state, sensordata, action)
        return obs, float(reward), bool(terminated), False, info

    # ----- rendering -------------------------------------------------------
    def _sync_render_data(self) -> None:
        mujoco.mj_setState(self.model, self.data, self._state, FULLPHYSICS)
        mujoco.mj_forward(self.model, self.data)

    def _camera(self) -> mujoco.MjvCamera:
        cam = mujoco.MjvCamera()
        mujoco.mjv_defaultFreeCamera(self.model, cam)
        return cam

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array'")
            return None
        if self._renderer is None:
            h, w = self._render_size
            self._renderer = mujoco.Renderer(self.model, h, w)
        self._sync_render_data()
        self._renderer.update_scene(self.data, self._camera())
        return self._renderer.render()

    def close(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._runner is not None:
            self._runner.close()
            self._runner = None
