"""Running sliding scenes and collecting spikes, stress and forces."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import mujoco
import mujoco.rollout
import numpy as np

from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

# Sliding left out of SlideResult.window() while the contact settles (s).
SETTLE_S = 0.1


@dataclasses.dataclass
class SlideResult:
    time_s: np.ndarray  # (nstep,)
    # Output blocks the skin's `outputs` enables (None when disabled):
    spikes: np.ndarray | None  # (nstep, nrec) spike counts per step
    stress: np.ndarray | None  # (nstep, nrec) receptor quantity, Pa
    force: np.ndarray | None  # (nstep, 4) normal, tangential x, y (N), indentation (m)
    finger_x_m: np.ndarray  # (nstep,) fingertip x
    layout: SkinLayout
    tip: scenes.Fingertip
    texture: scenes.Texture
    protocol: scenes.Protocol
    slide_start_s: float

    @property
    def dt(self) -> float:
        return self.protocol.timestep_s

    def window(self, settle_s: float = SETTLE_S) -> slice:
        """Steps of steady sliding: from slide start + settle_s to the end."""
        start = int(round((self.slide_start_s + settle_s) / self.dt))
        return slice(min(start, len(self.time_s) - 1), len(self.time_s))


def run_slide(
    tip: scenes.Fingertip | None = None,
    texture: scenes.Texture | None = None,
    protocol: scenes.Protocol | None = None,
    duration_s: float = 1.0,
    progress: Callable[[int], object] | None = None,
) -> SlideResult:
    """Press the fingertip onto the plate, then slide it for duration_s.
    progress, if given, is called with the number of steps simulated since its
    last call (about 100 calls per run; the result is bit-identical)."""
    tip = tip or scenes.Fingertip()
    texture = texture or scenes.Texture()
    protocol = protocol or scenes.Protocol()
    if not 0 < duration_s <= 60:
        raise ValueError(f"duration_s = {duration_s} is out of range; valid range (0, 60] s")
    travel = protocol.speed_m_s * duration_s
    if travel > texture.length_m / 2:
        raise ValueError(
            f"sliding {travel * 1e3:.1f} mm exceeds the plate's usable half length "
            f"({texture.length_m / 2 * 1e3:.1f} mm); lengthen the texture or shorten "
            "the run"
        )
    model = scenes.build_model(tip, texture, protocol)
    data = mujoco.MjData(model)
    layout = SkinLayout.from_model(model)
    ctrl = scenes.controls(protocol, duration_s)
    return _collect(model, data, layout, ctrl, tip, texture, protocol, progress)


def chunked_rollout(
    model,
    data,
    state0,
    ctrl,
    progress=None,
    min_chunk: int = 50,
    max_chunk: int = 200,
    control_spec: int | None = None,
):
    """mujoco.rollout in consecutive chunks (about 100, at most max_chunk
    steps each), reporting each to progress: every chunk starts from the
    previous one's last full physics state (plugin state included) and solver
    warm start, so the trajectory is the one-call trajectory bit for bit
    (tests/plugin/test_rollout.py). Keeps only time and qpos of each state:
    the full state carries the plugin's (the elastic warm start, 3 x nx^2
    doubles), 0.4 MB a step at 128^2, which for a whole run would not fit."""
    n = len(ctrl)
    size = min(max(min_chunk, -(-n // 100)), max_chunk)
    keep = 1 + model.nq
    spec = {} if control_spec is None else {"control_spec": control_spec}
    states, sensordata, warmstart = [], [], None
    for i in range(0, n, size):
        st, sd = mujoco.rollout.rollout(
            model, data, state0[None], ctrl[None, i : i + size], initial_warmstart=warmstart, **spec
        )
        states.append(st[0, :, :keep].copy())
        sensordata.append(sd[0])
        state0, warmstart = st[0, -1].copy(), data.qacc_warmstart.copy()[None]
        if progress is not None:
            progress(st.shape[1])
    return np.concatenate(states), np.concatenate(sensordata)


def _collect(model, data, layout, ctrl, tip, texture, protocol, progress=None) -> SlideResult:
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state0, spec)
    state, sensordata = chunked_rollout(model, data, state0, ctrl, progress)
    # state: time, qpos (slide_x, press_z)
    time = state[:, 0]

    def block(name):
        return layout.block(sensordata, name) if name in layout.blocks else None

    spikes = block("spikes")
    spikes = None if spikes is None else spikes.astype(np.int32)
    stress, force = block("stress"), block("force")
    return SlideResult(
        time_s=time,
        spikes=spikes,
        stress=stress,
        force=force,
        finger_x_m=state[:, 1].copy(),
        layout=layout,
        tip=tip,
        texture=texture,
        protocol=protocol,
        slide_start_s=protocol.press_s,
    )
