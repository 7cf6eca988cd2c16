"""Gymnasium environments: API (check_env), seeding, batched stepping, the
documented task logic, and the benchmark's smoke run.

Rendering (check_env's render check) needs an OpenGL backend chosen before
mujoco is imported, so it runs in a subprocess in tests/plugin/test_viewer.py.
"""

import math
import re

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import mjtouch.envs
from mjtouch import core
from mjtouch.envs import bench
from mjtouch.envs.base import REFRACTORY_DEFAULT_S, max_spikes_per_receptor
from mjtouch.envs.slip_hold import BLOCK_MASS_KG

TEX = "mjtouch/TextureExplore-v0"
SLIP = "mjtouch/SlipHold-v0"


def make(env_id, **kw):
    return gym.make(env_id, **kw)


def force_action(env, force_n: float) -> float:
    """The action entry that commands force_n (maps [-1, 1] onto force_range_n)."""
    lo, hi = env.unwrapped.force_range_n
    return 2 * (force_n - lo) / (hi - lo) - 1


def random_actions(env, n: int, seed: int, commit: bool = False) -> np.ndarray:
    rng = np.random.default_rng(seed)
    space = env.action_space
    a = rng.uniform(space.low, space.high, (n,) + space.shape).astype(space.dtype)
    if env.unwrapped.spec.id == TEX and not commit:
        a[:, 2] = -1.0  # never commit
    return a


def rollout(env, seed, actions):
    """Observations, rewards, terminations and infos of one episode."""
    obs, info = env.reset(seed=seed)
    out = {"obs": [obs], "reward": [], "terminated": [], "info": [info]}
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out["obs"].append(obs)
        out["reward"].append(r)
        out["terminated"].append(term)
        out["info"].append(info)
        if term or trunc:
            break
    out["obs"] = np.array(out["obs"])
    return out


# ----- API ---------------------------------------------------------------


@pytest.mark.parametrize(
    "env_id,kw",
    [
        (TEX, {}),
        (TEX, {"touch": "rates", "pressure_image": 6}),
        (TEX, {"touch": "none"}),
        (SLIP, {}),
        (SLIP, {"touch": "rates", "pressure_image": 4}),
        (SLIP, {"touch": "none"}),
    ],
)
def test_check_env_passes_without_warnings(env_id, kw):
    # pytest's filterwarnings=error turns any gymnasium warning into a failure
    env = make(env_id, **kw)
    check_env(env.unwrapped, skip_render_check=True)
    space = env.observation_space
    assert np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high))
    env.close()


def test_spike_bound_matches_a_saturated_receptor():
    """The touch block's upper bound: a receptor driven as hard as possible
    fires once per refractory period, so at most ceil(T / t_ref) + 1 spikes
    in a control step T (10 ms: 11)."""
    dt = 0.01
    bound = max_spikes_per_receptor(dt, REFRACTORY_DEFAULT_S)
    assert bound == math.ceil(dt / REFRACTORY_DEFAULT_S) + 1
    # Without adaptation, the RA and SA1 saturations and the RA's gain control (the defaults
    # keep them well below the bound), the bound is reached.
    unlimited = {"adapt": "0 0 0", "ra_saturation": "0", "ra_sustained": "0", "sa1_saturation": "0"}
    for cls in ("SA1", "RA"):  # PC is band-pass: a ramp is not its drive
        spikes, _ = core.receptor_run(cls, 1e12 * np.arange(51) * dt, dt, unlimited)
        # saturated: one spike per refractory period, 10 in 10 ms
        assert spikes.max() == bound - 1, (cls, spikes.max())
        assert spikes.max() <= bound


@pytest.mark.parametrize("env_id", [TEX, SLIP])
def test_full_scale_ranges_do_not_saturate(env_id):
    """The saturating blocks (finger/grip motion, contact force, pressure)
    stay strictly inside their full-scale range under random and bang-bang
    actions, so clipping never changes what the agent sees."""
    env = make(env_id, pressure_image=4)
    u = env.unwrapped
    blocks = u.observation_blocks
    motion = blocks["finger" if env_id == TEX else "grip"]
    saturating = np.zeros(u.observation_space.shape, bool)
    saturating[motion.start : motion.start + 2] = True  # position, velocity
    saturating[blocks["contact"]] = True
    saturating[blocks["pressure"]] = True
    low, high = u.observation_space.low, u.observation_space.high
    rng = np.random.default_rng(3)
    for episode in range(3):
        if episode == 0:
            actions = random_actions(env, 40, episode)
        else:  # bang-bang: every entry flips between -1 and +1 every 5 steps
            signs = np.repeat(rng.choice([-1.0, 1.0], (8,) + env.action_space.shape), 5, axis=0)
            actions = signs.astype(np.float32)
            if env_id == TEX:
                actions[:, 2] = -1.0
        obs = rollout(env, episode, actions)["obs"]
        assert np.all(obs[:, saturating] < high[saturating]), "saturated high"
        # lower bounds: 0 for the normal force and pressure is exact (no
        # contact), so only the signed entries must stay above theirs
        signed = saturating & (low < 0)
        assert np.all(obs[:, signed] > low[signed]), "saturated low"
    env.close()


# ----- seeding -----------------------------------------------------------


@pytest.mark.parametrize("env_id", [TEX, SLIP])
def test_same_seed_gives_bit_identical_episodes(env_id):
    env_a, env_b = make(env_id), make(env_id)
    actions = random_actions(env_a, 12, seed=5)
    a = rollout(env_a, 11, actions)
    env_a.reset(seed=99)  # another episode in between changes nothing
    a2 = rollout(env_a, 11, actions)
    b = rollout(env_b, 11, actions)
    for other in (a2, b):
        assert np.array_equal(a["obs"], other["obs"])
        assert a["reward"] == other["reward"]
        assert a["info"] == other["info"]


@pytest.mark.parametrize("env_id", [TEX, SLIP])
def test_different_seeds_give_different_episodes(env_id):
    env = make(env_id)
    actions = random_actions(env, 10, seed=5)
    runs = {seed: rollout(env, seed, actions) for seed in (0, 1, 2)}
    if env_id == TEX:
        # precondition: the seeds draw episodes touch can tell apart (two
        # flat plates would rightly feel the same; flat has no phase)
        drawn = [
            (r["info"][0]["texture"], env.unwrapped.classes[r["info"][0]["texture"]])
            for r in runs.values()
        ]
        assert sum(period == 0 for _, period in drawn) <= 1, drawn
    else:
        frictions = [r["info"][0]["friction"] for r in runs.values()]
        assert len(set(frictions)) == 3
    seeds = list(runs)
    for i in range(3):
        for j in range(i + 1, 3):
            a, b = runs[seeds[i]]["obs"], runs[seeds[j]]["obs"]
            assert not np.array_equal(a, b), (seeds[i], seeds[j])


# ----- batched stepping --------------------------------------------------


def reference_vector(env_id, seeds, actions, max_episode_steps):
    """Single environments stepped one by one with Gymnasium's next-step
    autoreset (the step after an episode ends resets, reward 0)."""
    n = len(seeds)
    envs = [make(env_id, max_episode_steps=max_episode_steps) for _ in range(n)]
    obs = [e.reset(seed=s)[0] for e, s in zip(envs, seeds)]
    out = {"obs": [np.array(obs)], "reward": [], "terminated": [], "truncated": []}
    pending = [False] * n
    for a in actions:
        row = ([], [], [], [])
        for i, e in enumerate(envs):
            if pending[i]:
                o, r, term, trunc = e.reset()[0], 0.0, False, False
            else:
                o, r, term, trunc, _ = e.step(a[i])
            pending[i] = term or trunc
            for lst, v in zip(row, (o, r, term, trunc)):
                lst.append(v)
        for key, lst in zip(("obs", "reward", "terminated", "truncated"), row):
            out[key].append(np.array(lst))
    return {k: np.array(v) for k, v in out.items()}


def run_vector(venv, seeds, actions):
    obs, _ = venv.reset(seed=seeds)
    out = {"obs": [obs], "reward": [], "terminated": [], "truncated": []}
    for a in actions:
        obs, r, term, trunc, _ = venv.step(a)
        for key, v in zip(("obs", "reward", "terminated", "truncated"), (obs, r, term, trunc)):
            out[key].append(np.array(v))
    venv.close()
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("env_id", [TEX, SLIP])
def test_rollout_vector_env_equals_single_envs_bit_for_bit(env_id):
    n, steps, limit = 3, 10, 6
    seeds = [21, 22, 23]
    probe = make(env_id)
    actions = np.stack(
        [random_actions(probe, steps, seed=40 + i, commit=False) for i in range(n)], axis=1
    )
    if env_id == TEX:
        actions[3, 0, 2] = 1.0  # env 0 commits at step 4: terminates, resets at step 5
    else:
        actions[:, 1, 0] = -1.0  # env 1 grips with the least force: the block drops
    probe.close()
    ref = reference_vector(env_id, seeds, actions, limit)
    fast = run_vector(gym.make_vec(env_id, num_envs=n, max_episode_steps=limit), seeds, actions)
    sync = run_vector(
        gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", max_episode_steps=limit),
        seeds,
        actions,
    )
    # in the calling thread, and on more worker threads than environments
    vec_of = {TEX: mjtouch.envs.vector.texture_explore_vec, SLIP: mjtouch.envs.vector.slip_hold_vec}
    inline, wide = (
        run_vector(vec_of[env_id](n, nthread=k, max_episode_steps=limit), seeds, actions)
        for k in (0, n + 1)
    )
    assert isinstance(gym.make_vec(env_id, num_envs=1), mjtouch.envs.RolloutVectorEnv)
    # the sequence exercises both episode ends and the autoreset after them
    assert ref["truncated"].any()
    assert ref["terminated"].any()
    runs = {"RolloutVectorEnv": fast, "nthread=0": inline, f"nthread={n + 1}": wide}
    for name, got in (*runs.items(), ("SyncVectorEnv", sync)):
        for key in ref:
            assert np.array_equal(got[key], ref[key]), (name, key)


def test_rollout_vector_env_rejects_a_bad_action_before_stepping_any_env():
    def fresh():
        venv = mjtouch.envs.vector.slip_hold_vec(2, nthread=2)
        venv.reset(seed=0)
        return venv

    venv, ref = fresh(), fresh()
    actions = np.zeros((2, 1), np.float32)
    for row in (0, 1):  # the calling thread's share, then the worker's
        bad = actions.copy()
        bad[row, 0] = np.nan
        with pytest.raises(ValueError, match="not finite"):
            venv.step(bad)
    # nothing stepped: the next step is the first
    assert np.array_equal(venv.step(actions)[0], ref.step(actions)[0])
    venv.close()
    ref.close()


# ----- task logic (the docstrings) ---------------------------------------


def texture_action(env, force_n=0.5, speed_m_s=0.03, commit=False, guess=0):
    u = env.unwrapped
    a = np.zeros(env.action_space.shape, np.float32)
    a[0] = force_action(env, force_n)
    a[1] = speed_m_s / u.max_speed_m_s
    a[2] = 1.0 if commit else -1.0
    a[3 + guess] = 1.0
    return a


def test_texture_explore_rewards_and_commit():
    """+1 for a correct answer, 0 for a wrong one, -step_cost per control
    step; commit ends the episode without physics."""
    env = make(TEX)
    u = env.unwrapped
    cost = u.step_cost
    obs0, info = env.reset(seed=0, options={"texture": 2})
    assert info["texture"] == 2 and info["period_m"] == u.classes[2]
    obs1, r, term, trunc, _ = env.step(texture_action(env))
    assert (r, term, trunc) == (-cost, False, False)
    assert not np.array_equal(obs1, obs0)
    obs2, r, term, trunc, info = env.step(texture_action(env, commit=True, guess=2))
    assert (r, term, trunc) == (1.0 - cost, True, False)
    assert info["correct"] and info["guess"] == 2
    assert np.array_equal(obs2, obs1)  # committing runs no physics
    env.reset(seed=1, options={"texture": 2})
    _, r, term, _, info = env.step(texture_action(env, commit=True, guess=4))
    assert (r, term) == (0.0 - cost, True) and not info["correct"] and info["guess"] == 4


def test_texture_explore_truncates_at_the_time_limit():
    env = make(TEX, touch="none")
    env.reset(seed=0)
    limit = env.spec.max_episode_steps
    assert limit == 50  # the docstring's 0.5 s at 10 ms per step
    ends = [env.step(texture_action(env))[2:4] for _ in range(limit)]
    assert ends[-1] == (False, True)
    assert all(e == (False, False) for e in ends[:-1])


def test_texture_explore_actions_drive_the_fingertip():
    """Action 0 sets the normal force, action 1 the sliding speed; the skin
    measures both."""
    env = make(TEX)
    u = env.unwrapped
    b = u.observation_blocks
    for force_n, speed in ((0.3, 0.03), (0.8, -0.02)):
        env.reset(seed=0, options={"texture": 0})
        obs = np.array([env.step(texture_action(env, force_n, speed))[0] for _ in range(20)])
        # the command block echoes the mapped action (float32 actions)
        assert np.allclose(obs[-1, b["command"]], [force_n, speed], rtol=1e-6)
        steady = obs[10:]  # after 100 ms
        # the slide actuator is an integrated-velocity servo (exact mean
        # speed) and the README measures the normal force steady to < 1e-4
        # relative while sliding: 1e-3 leaves room for the settling after
        # the command change (measured: 3e-6 and 1.6e-4)
        assert np.allclose(steady[:, b["finger"]][:, 1], speed, rtol=1e-3)
        assert np.allclose(steady[:, b["contact"]][:, 0], force_n, rtol=1e-3)
    # out-of-range actions are clipped to the action space, bad ones refused
    env.reset(seed=0)
    big = texture_action(env)
    big[0] = 7.0
    obs = env.step(big)[0]
    assert obs[b["command"]][0] == pytest.approx(u.force_range_n[1])
    with pytest.raises(ValueError, match="not finite"):
        env.step(np.full(env.action_space.shape, np.nan))
    with pytest.raises(ValueError, match="expected"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="valid 0 to 4"):
        env.reset(options={"texture": 5})
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"speed": 1})


def test_texture_explore_needs_touch():
    """The textures do not collide in MuJoCo: without touch two textures give
    bit-identical observations; with touch they differ."""
    actions = [texture_action(make(TEX, touch="none"), 0.5, 0.04)] * 12
    seen = {}
    for touch in ("none", "counts"):
        env = make(TEX, touch=touch)
        for k in (1, 3):
            env.reset(seed=0, options={"texture": k})
            seen[touch, k] = np.array([env.step(a)[0] for a in actions])
    assert np.array_equal(seen["none", 1], seen["none", 3])
    assert not np.array_equal(seen["counts", 1], seen["counts", 3])
    # and the non-touch part of the touch observation is the same physics
    n = seen["none", 1].shape[1]
    assert np.array_equal(seen["counts", 1][:, :n], seen["none", 1])


def test_slip_hold_reward_is_force_and_slip_cost():
    """Reward per step: -force_cost x grip (N) - slip_cost x slip (mm), and
    -drop_penalty on the step the block has dropped drop_m."""
    env = make(SLIP, touch="none")
    u = env.unwrapped
    actions = random_actions(env, 100, seed=8)
    actions[20:, 0] = -1.0  # let go: the block must drop
    run = rollout(env, 3, actions)
    infos = run["info"]
    assert run["terminated"][-1] and not any(run["terminated"][:-1])
    for k, r in enumerate(run["reward"]):
        info, before = infos[k + 1], infos[k]
        slip = max(0.0, info["object_drop_m"] - before["object_drop_m"])
        assert info["slip_m"] == pytest.approx(slip, abs=1e-15)
        expected = -u.force_cost * info["grip_force_n"] - u.slip_cost * slip * 1e3
        if run["terminated"][k]:
            expected -= u.drop_penalty
            assert info["object_drop_m"] >= u.drop_m
        else:
            assert info["object_drop_m"] < u.drop_m
        assert r == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("margin,holds", [(1.2, True), (0.8, False)])
def test_slip_hold_holds_while_load_is_under_friction_times_grip(margin, holds):
    """Coulomb: the block holds for the whole episode if mu x grip exceeds the
    load plus its weight (by 20%), and drops (terminates) if it is 20% short."""
    mu, load = 0.7, 0.1
    weight = BLOCK_MASS_KG * 9.81
    env = make(
        SLIP,
        touch="none",
        friction_range=(mu, mu),
        base_load_range_n=(load, load),
        rise_load_range_n=(0.0, 0.0),
    )
    grip = margin * (load + weight) / mu
    a = np.array([force_action(env, grip)], np.float32)
    run = rollout(env, 0, [a] * 100)
    assert run["info"][-1]["grip_force_n"] == pytest.approx(grip, rel=1e-6)
    if holds:
        assert len(run["reward"]) == 100 and not any(run["terminated"])
        assert run["info"][-1]["object_drop_m"] < env.unwrapped.drop_m
    else:
        assert run["terminated"][-1] and len(run["reward"]) < 100


def test_slip_hold_touch_signals_slip():
    """The docstring's claim that the skin tells slip: Pacinian spikes burst
    while the block slides and stay (nearly) silent in a steady hold."""
    mu, load = 0.7, 0.1
    weight = BLOCK_MASS_KG * 9.81
    pc = {}
    for margin in (1.2, 0.8):
        env = make(
            SLIP,
            friction_range=(mu, mu),
            base_load_range_n=(load, load),
            rise_load_range_n=(0.0, 0.0),
        )
        a = np.array([force_action(env, margin * (load + weight) / mu)], np.float32)
        run = rollout(env, 0, [a] * 100)
        touch = run["obs"][1:, env.unwrapped.observation_blocks["touch"]]
        slipping = np.array([i["slip_m"] > 1e-4 for i in run["info"][1:]])  # > 10 mm/s
        if margin > 1:
            assert not slipping.any()
            pc["hold"] = touch[5:, 2].mean()  # after the 50 ms grip change transient
        else:
            assert slipping.any()
            pc["slip"] = touch[slipping, 2].mean()
        n_pc = int(env.unwrapped.layout.mask("PC").sum())
        dt = env.unwrapped.control_dt_s
    # per-receptor rates (Hz): slipping, the PCs burst (tens to hundreds of
    # Hz at slip onset, Johansson & Westling 1987) at least 10x their hold
    # rate and 50 Hz (measured: ~0.4 Hz holding, ~100 Hz slipping)
    hz = {k: v / (n_pc * dt) for k, v in pc.items()}
    assert hz["slip"] >= 10 * max(hz["hold"], 5.0), hz


def test_slip_hold_slip_zone_grows_towards_the_friction_limit():
    """The slip block: in steady holds the slip zone (traction at mu p) grows
    as the load nears mu x grip (Cattaneo-Mindlin: its share is
    1 - (1 - Q / mu P)^(1/2) on a smooth Winkler skin; the ridged pad's
    pressure shifts it) while the block stays put; sliding, the whole
    contact is at the limit and nothing sticks."""
    mu, load = 0.7, 0.1
    weight = BLOCK_MASS_KG * 9.81
    zone, stuck_min = {}, {}
    for margin in (2.0, 1.5, 1.2, 0.8):
        env = make(
            SLIP,
            friction_range=(mu, mu),
            base_load_range_n=(load, load),
            rise_load_range_n=(0.0, 0.0),
        )
        u = env.unwrapped
        a = np.array([force_action(env, margin * (load + weight) / mu)], np.float32)
        run = rollout(env, 0, [a] * 30)
        slip = run["obs"][1:, u.observation_blocks["slip"]]
        assert np.all((slip[:, :3] >= 0) & (slip[:, :3] <= 1))
        assert np.all(slip[:, 3] < u.observation_space.high[u.observation_blocks["slip"]][3])
        # the last 10 steps, after the grip change settles (a sliding block
        # drops out within ~10 steps: its first 3 are the change)
        steady = slip[max(len(slip) - 10, 3) :]
        zone[margin] = steady[:, 2].mean()
        stuck_min[margin] = steady[:, 1].min()
        sliding = max(i["slip_m"] for i in run["info"][-10:]) > 1e-4  # > 10 mm/s
        assert sliding == (margin < 1), (margin, sliding)
        if margin > 1:
            cattaneo = 1 - np.sqrt(1 - 1 / margin)
            assert abs(zone[margin] - cattaneo) < 0.15, (margin, zone[margin], cattaneo)
    assert 0 < zone[2.0] < zone[1.5] < zone[1.2] < zone[0.8] == 1.0, zone
    assert stuck_min[0.8] == 0.0 < stuck_min[1.5]


# ----- benchmark ---------------------------------------------------------


def test_bench_quick_prints_finite_positive_rates_and_ratio(capsys):
    assert bench.main(["--quick"]) == 0
    text = capsys.readouterr().out
    number = r"([0-9]+(?:\.[0-9]*)?(?:[eE][+-]?[0-9]+)?)"
    rates = [
        float(re.search(label + r"\s+" + number, text).group(1))
        for label in ("single env, touch", "single env, no touch", "envs, rollout", "envs, sync")
    ]
    ratio = float(re.search(r"touch / no touch = " + number, text).group(1))
    assert all(math.isfinite(v) and v > 0 for v in rates + [ratio]), text
    # the printed ratio is the printed single-env rates' (4 decimals, rates
    # to 0.1 step/s)
    assert ratio == pytest.approx(rates[0] / rates[1], rel=2e-3, abs=1e-4), text
