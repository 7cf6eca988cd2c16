"""The SlipHold examples run, with small arguments, and show what they claim:
the slip reflex (skin only, 75 ms late) holds with less grip than the best
constant grip; the learner trains with and without touch on equal terms."""

from __future__ import annotations

import json
import pathlib
import runpy

import numpy as np

from mjtouch.envs import slip_hold

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"


def example(name: str) -> dict:
    return runpy.run_path(str(EXAMPLES / name), run_name="example")


def test_slip_reflex_holds_with_less_grip_than_the_test_set_needs(capsys):
    # The example's claim is over all 30 test episodes (README: the reflex
    # holds them all at a lower mean grip than the best constant grip, found
    # by the same sweep). Here, to stay short: that sweep (touch="none", the
    # same physics, fast), and the reflex on the first 4 test episodes: it
    # holds each, at a mean grip below that constant. (On so few episodes
    # their own best constant can be lower: the hardest test episodes set it.)
    mod = example("slip_reflex.py")
    best = mod["best_constant"](slip_hold.TEST_SEEDS)
    assert best["drops"] == 0
    n = 4
    assert mod["main"](["--episodes", str(n), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["episodes"] == n and r["delay_s"] >= 0.075
    assert r["reflex"]["drops"] == 0
    assert r["reflex"]["mean_grip_n_all"] < best["grip_n"], (r, best)


def test_slip_reflex_sees_only_the_delayed_skin():
    mod = example("slip_reflex.py")
    env = slip_hold.SlipHoldEnv()
    obs0, _ = env.reset(seed=0)
    frames = [obs0]
    for _ in range(12):
        frames.append(env.step(slip_hold.grip_action(env, 1.0))[0])
    actions = {}
    for variant in ("as seen", "last steps changed"):
        reflex = mod["SlipReflex"]()
        seq = [f.copy() for f in frames]
        if variant != "as seen":  # what the delay hides must not matter
            for f in seq[-reflex.delay_steps :]:
                f[env.observation_blocks["slip"]] = [0.0, 0.0, 1.0, 0.67]
                f[env.observation_blocks["contact"]] *= 3.0
        actions[variant] = [reflex(f, env) for f in seq]
    assert reflex.delay_steps == 8  # 75 ms at 10 ms control steps, rounded up
    np.testing.assert_array_equal(actions["as seen"], actions["last steps changed"])


def test_slip_learn_smoke_trains_both_arms_on_equal_terms(capsys):
    args = ["--iterations", "1", "--population", "2", "--episodes", "1", "--test", "1"]
    assert example("slip_learn.py")["main"](args + ["--seeds", "0", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["touch"] for r in rows} == {"counts", "none"}
    assert len({r["train_episodes"] for r in rows}) == 1
    for r in rows:
        assert np.isfinite(r["test_return"]) and r["test_drops"] in (0, 1)
        assert 0.0 < r["test_mean_grip_n"] <= 2.0
