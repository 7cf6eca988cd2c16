"""Learning to hold with least grip in SlipHold, with and without touch.

The cross-entropy method (numpy, CPU) trains a linear policy, action =
clip(w . features + b, -1, 1), from the same start, on the same training
episodes, with the same budget, once on the observation with touch (grip,
spikes, skin force, slip zone) and once on the observation without it
(``touch="none"``: the grip block only). Each trained policy (the CEM's
final mean) is scored on the fixed test episodes (``slip_hold.TEST_SEEDS``)
that examples/slip_reflex.py uses::

    nice -n 10 python examples/slip_learn.py                 # 3 seeds, the README table
    python examples/slip_learn.py --iterations 1 --population 4 --episodes 1 --test 2 --seeds 0
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from mjtouch.envs import slip_hold

# Training episodes come from their own seeds, apart from the test seeds.
TRAIN_SEED_BASE = 10_000
START_GRIP_N = 1.2  # the initial mean policy: this constant grip (no weights)


def features(env: slip_hold.SlipHoldEnv, obs: np.ndarray) -> np.ndarray:
    """The observation scaled to order 1: positions over the grip's full
    scale, forces in N, spike counts as log(1 + n) / 5, slip shares as they are."""
    b = env.split_observation(obs)
    lo, hi = env.force_range_n
    grip = b["grip"] / np.array([slip_hold.GRIP_X_FULL_SCALE_M, 2 * hi, hi])
    parts = [grip]
    if env.touch != "none":
        parts += [np.log1p(b["touch"]) / 5.0, b["contact"], b["slip"]]
    return np.concatenate(parts)


class LinearPolicy:
    def __init__(self, params: np.ndarray):
        self.params = params

    def __call__(self, obs, env):
        phi = features(env, obs)
        a = float(self.params[:-1] @ phi + self.params[-1])
        return np.array([np.clip(a, -1.0, 1.0)], np.float32)


def start_params(env: slip_hold.SlipHoldEnv) -> np.ndarray:
    n = len(features(env, env.observation_space.sample() * 0))
    p = np.zeros(n + 1)
    p[-1] = slip_hold.grip_action(env, START_GRIP_N)[0]
    return p


def cem(
    touch: str,
    seed: int,
    iterations: int,
    population: int,
    episodes: int,
    elite_share: float = 0.25,
    init_std: float = 0.5,
    log=None,
) -> tuple[np.ndarray, list[float]]:
    """Train; returns the final mean parameters and each iteration's best mean return."""
    env = slip_hold.SlipHoldEnv(touch=touch)
    rng = np.random.default_rng(seed)
    mean = start_params(env)
    std = np.full_like(mean, init_std)
    n_elite = max(1, round(elite_share * population))
    history = []
    for it in range(iterations):
        # the same training episodes for every candidate (and both arms: the
        # seeds depend on seed and iteration only)
        ep_seeds = TRAIN_SEED_BASE + 1000 * seed + episodes * it + np.arange(episodes)
        cands = mean + std * rng.standard_normal((population, len(mean)))
        scores = np.array(
            [slip_hold.evaluate(LinearPolicy(c), ep_seeds, env)["mean_return"] for c in cands]
        )
        elite = cands[np.argsort(scores)[-n_elite:]]
        mean, std = elite.mean(axis=0), elite.std(axis=0) + 0.02
        history.append(float(scores.max()))
        if log:
            log(f"  touch={touch} seed {seed} iteration {it}: best {scores.max():.3f}")
    return mean, history


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--iterations", type=int, default=9)
    ap.add_argument("--population", type=int, default=9)
    ap.add_argument("--episodes", type=int, default=3, help="training episodes per candidate")
    ap.add_argument("--test", type=int, default=len(slip_hold.TEST_SEEDS), help="test episodes")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    for name in ("iterations", "population", "episodes"):
        if getattr(args, name) < 1:
            raise SystemExit(f"--{name} must be >= 1")
    if not 1 <= args.test <= len(slip_hold.TEST_SEEDS):
        raise SystemExit(f"--test must be in [1, {len(slip_hold.TEST_SEEDS)}]")
    test_seeds = slip_hold.TEST_SEEDS[: args.test]
    log = None if args.json else (lambda s: print(s, file=sys.stderr, flush=True))
    rows = []
    for touch in ("none", "counts"):
        for seed in args.seeds:
            t0 = time.perf_counter()
            params, history = cem(
                touch, seed, args.iterations, args.population, args.episodes, log=log
            )
            test = slip_hold.evaluate(LinearPolicy(params), test_seeds, touch=touch)
            rows.append(
                {
                    "touch": touch,
                    "seed": seed,
                    "test_return": test["mean_return"],
                    "test_drops": test["drops"],
                    "test_mean_grip_n": test["mean_grip_n_all"],
                    "train_best": history,
                    "train_episodes": args.iterations * args.population * args.episodes,
                    "wall_s": time.perf_counter() - t0,
                }
            )
            if log:
                log(f"  {json.dumps(rows[-1])}")
    if args.json:
        print(json.dumps(rows))
        return 0
    budget = rows[0]["train_episodes"]
    print(
        f"CEM, linear policy, {budget} training episodes per run; {len(test_seeds)} test episodes"
    )
    print(f"{'observation':12s} {'seed':>4s} {'return':>8s} {'drops':>6s} {'mean grip N':>12s}")
    for r in rows:
        print(
            f"{'touch' if r['touch'] != 'none' else 'no touch':12s} {r['seed']:4d} "
            f"{r['test_return']:8.3f} {r['test_drops']:6d} {r['test_mean_grip_n']:12.3f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
