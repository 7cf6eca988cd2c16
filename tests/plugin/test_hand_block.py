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


def grasp_forces(env, seeds, steps: int, facings: dict, action=None):
    """Per fingertip, summed over the physics steps of a closing-hand grasp
    (or of `action()`'s actions):
    MuJoCo's normal force on the capsule and the skin's coverage-weighted
    share of it (coverage block), the skin's normal force, its spikes, and
    for each `facings` entry (name: (facing per finger in the geom's frame,
    grid side in m)) the normal force of the contacts a patch there surely
    carries: normal within 45 degrees of the facing, point within the disk
    inscribed in the grid seen along it."""
    m, d = env.model, env.data
    gids = [m.geom(f"robot0:C_{f}distal").id for f in hand_block.FINGERS]
    out = {k: np.zeros(5) for k in ("mj", "carried", "force", "spikes", *facings)}
    cos45 = np.cos(np.radians(45.0))

    def step(action):
        sd = d.sensordata
        for _ in range(env.n_substeps):
            mujoco.mj_step(m, d)
            for k, lay in enumerate(env.layouts):
                cov = lay.block(sd, "coverage")
                out["mj"][k] += cov[1]
                out["carried"][k] += cov[0] * cov[1]
                out["force"][k] += lay.block(sd, "force")[0]
                out["spikes"][k] += lay.block(sd, "spikes").sum()
            for i in range(d.ncon):
                c = d.contact[i]
                for k, g in enumerate(gids):
                    if g not in (c.geom[0], c.geom[1]):
                        continue
                    f6 = np.zeros(6)
                    mujoco.mj_contactForce(m, d, i, f6)
                    # the normal from the pad into the other geom
                    n_into = c.frame[:3] * (1.0 if c.geom[0] == g else -1.0)
                    R = d.geom_xmat[g].reshape(3, 3)
                    rel = c.pos - d.geom_xpos[g]
                    for name, (facing, side_m) in facings.items():
                        u = R @ facing[k]
                        across = rel - (rel @ u) * u
                        if n_into @ u > cos45 and np.linalg.norm(across) < side_m / 2:
                            out[name][k] += f6[0]
        env._touch[:] = 0.0

    env._mujoco_step = step
    try:
        closing = np.full(env.action_space.shape, 0.5, dtype=np.float32)
        for s in seeds:
            env.reset(seed=s)
            for _ in range(steps):
                env.step(closing if action is None else action())
    finally:
        del env._mujoco_step
    return out


def test_grasp_presses_the_patches(env):
    m = env.model
    side = hand_block.SKIN_PRESET["nx"] * hand_block.SKIN_PRESET["pitch"]
    rl = hand_block.RL_SKIN["nx"] * hand_block.RL_SKIN["pitch"]
    facings = {
        "tilted": ([hand_block.shadow_pad_facing(m, f) for f in hand_block.FINGERS], side),
        "palm": ([hand_block.shadow_pad_facing(m, f, 0.0) for f in hand_block.FINGERS], rl),
    }
    out = grasp_forces(env, seeds=(0, 1), steps=30, facings=facings)
    total = out["mj"].sum()
    assert total > 0
    # The plugin's share is at least the contacts surely on the patch (it
    # adds those past the disk but on the grid, and overlap shares).
    assert out["carried"].sum() >= out["tilted"].sum() * (1 - 1e-9)
    # Most of the grasp's force lands where the tilted patch surely carries
    # it (0.59 of it here; rf and lf press the cap's shoulder, ff and mf
    # touch with the very tip, past 45 degrees); an rl grid facing the palm
    # side straight surely carries none of it (the contacts lie on the caps).
    assert out["tilted"].sum() > 0.5 * total
    assert out["palm"].sum() < 0.1 * total
    # The skin's force is the felt contacts' force along its pole, each
    # pressing within 45 degrees of it: cos 45 = 0.71 of their normal force
    # but for friction's part (0.8 here).
    assert out["force"].sum() > 0.5 * out["carried"].sum()
    # the fingertips that carry a fair part of the grip spike
    pressed = out["carried"] > 0.2 * total / 5
    assert pressed.sum() >= 2
    assert (out["spikes"][pressed] > 0).all()


def test_pad_facing_tilts_toward_the_tip(env):
    # Each distal capsule runs along its geom z from the distal joint
    # (at -z) to the tip; the pad side is -y (fingers) or -x (thumb).
    m = env.model
    t = np.radians(hand_block.PAD_TILT_DEG)
    for f in hand_block.FINGERS:
        g = m.geom(f"robot0:C_{f}distal").id
        assert m.geom_pos[g][2] > 0  # the capsule lies on the joint's +z side
        pad = np.array([-1.0, 0, 0]) if f == "th" else np.array([0, -1.0, 0])
        np.testing.assert_array_equal(hand_block.shadow_pad_facing(m, f, 0.0), pad)
        want = np.cos(t) * pad + np.sin(t) * np.array([0, 0, 1.0])
        np.testing.assert_allclose(hand_block.shadow_pad_facing(m, f), want, atol=1e-15)
    for bad in (-1.0, 91.0, float("nan")):
        with pytest.raises(ValueError, match="tilt_deg"):
            hand_block.shadow_pad_facing(m, "ff", bad)
