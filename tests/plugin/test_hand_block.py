"""HandManipulateBlock with five fingertip skins instead of 92 touch sensors
(mjtouch.envs.hand_block): Gymnasium's checks, the observation layout, the
touch block against SkinLayout read step by step, spikes only where a skin
touches, and episodes that repeat."""

import warnings

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from mjtouch.envs import hand_block


@pytest.fixture(scope="module")
def env():
    e = gym.make(hand_block.ENV_ID).unwrapped
    yield e
    e.close()


def close_hand(env, seed: int, steps: int, level: float = 0.5):
    """Observations and per-substep sensordata while every actuator is
    driven to `level` of its range (the fingers close on the block)."""
    obs, _ = env.reset(seed=seed)
    out, rows = [obs["observation"]], []
    action = np.full(env.action_space.shape, level, dtype=np.float32)
    step = env._mujoco_step

    def recording(a):  # the env's step, keeping each substep's sensordata
        record = []
        original = mujoco.mj_step

        def mj_step(m, d, *args, **kw):
            original(m, d, *args, **kw)
            record.append(d.sensordata.copy())

        mujoco.mj_step = mj_step
        try:
            step(a)
        finally:
            mujoco.mj_step = original
        rows.append(np.array(record))

    env._mujoco_step = recording
    try:
        for _ in range(steps):
            out.append(env.step(action)[0]["observation"])
    finally:
        del env._mujoco_step
    return np.array(out), rows


def test_check_env_passes(env):
    # Gymnasium-Robotics' own Boxes are unbounded: their warnings, only
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
    others = [str(w.message) for w in caught if "value is infinity" not in str(w.message)]
    others = [m for m in others if "value is -infinity" not in m]
    assert others == []


def test_observation_is_the_block_task_plus_five_skins(env):
    obs, _ = env.reset(seed=0)
    o = obs["observation"]
    assert o.shape == (hand_block.BASE_OBS + 5 * len(hand_block.FEATURES),)
    np.testing.assert_array_equal(o[54:61], obs["achieved_goal"])  # block pose
    assert env.observation_space["observation"].shape == o.shape
    assert env.skins == [f"skin_{f}" for f in hand_block.FINGERS]
    assert [lay.sensor_adr for lay in env.layouts] == sorted(
        env.model.sensor(n).adr[0] for n in env.skins
    )


def test_touch_block_is_each_skins_step_summary(env):
    obs, rows = close_hand(env, seed=1, steps=6)
    touched = 0
    for k in range(6):
        sd, touch = rows[k], obs[k + 1][61:].reshape(5, 5)
        assert len(sd) == env.n_substeps
        for f, lay in enumerate(env.layouts):
            spikes = lay.block(sd, "spikes").sum(axis=0)  # per receptor over the step
            counts = [spikes[lay.mask(c)].sum() for c in ("SA1", "RA", "PC")]
            force = lay.block(sd, "force")[:, 0].mean()
            cov = lay.block(sd, "coverage")
            mj = cov[:, 1].sum()
            share = (cov[:, 0] * cov[:, 1]).sum() / mj if mj > 0 else 1.0
            np.testing.assert_allclose(touch[f], [*counts, force, share], rtol=1e-12)
            if mj == 0:  # no contact on this fingertip over the step: silent
                assert touch[f, :4].tolist() == [0, 0, 0, 0]
            elif share == 0:  # MuJoCo's contacts all off the patch: not felt
                assert touch[f, 3] == 0.0
            elif force > 0.5:  # pressed: its receptors fire
                assert touch[f, :3].sum() > 0
                touched += 1
    assert touched >= 3  # the closing hand presses several fingertips


def test_episodes_repeat_bit_for_bit(env):
    a, _ = close_hand(env, seed=3, steps=3)
    close_hand(env, seed=4, steps=2)  # another episode between
    b, _ = close_hand(env, seed=3, steps=3)
    np.testing.assert_array_equal(a, b)
