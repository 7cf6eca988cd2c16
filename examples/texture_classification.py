"""Texture classification from spike counts: touch beats chance.

    python examples/texture_classification.py [--episodes 8] [--steps 30]

Runs ``mjtouch/TextureExplore-v0`` with a fixed exploration (press 0.5 N,
slide at 40 mm/s, never commit) on every texture class, ``--episodes`` per
class with random texture phases, and summarises each episode by its mean
spike count per class (SA1, RA, PC) over the steady sliding steps. A
nearest-centroid classifier (features z-scored on the training half) is
trained on half the episodes and tested on the other half.

The same is done with ``touch="none"`` (the scene without the skin), where
the only observations are the fingertip's position, velocity and commands:
the textures do not collide in MuJoCo, so these are identical for every
texture and the classifier is at chance (1 / number of classes).
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np

import mjtouch.envs  # noqa: F401  (registers the environments)

ENV_ID = "mjtouch/TextureExplore-v0"


def explore(
    env: gym.Env, texture: int, seed: int, steps: int, force_n: float, speed_m_s: float, skip: int
) -> np.ndarray:
    """One episode's feature vector: mean of the observation's touch block
    (or, without touch, of the whole observation) over steps skip..steps."""
    u = env.unwrapped
    lo, hi = u.force_range_n
    action = np.full(env.action_space.shape, -1.0, np.float32)  # a[2] = -1: never commit
    action[0] = 2 * (force_n - lo) / (hi - lo) - 1
    action[1] = speed_m_s / u.max_speed_m_s
    env.reset(seed=seed, options={"texture": texture})
    rows = []
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(action)
        rows.append(obs)
        if terminated or truncated:
            break
    rows = np.array(rows[skip:])
    if "touch" in u.observation_blocks:
        return np.log1p(rows[:, u.observation_blocks["touch"]].mean(axis=0))
    return rows.mean(axis=0)


def nearest_centroid(train_x, train_y, test_x, nclass):
    mu, sd = train_x.mean(axis=0), train_x.std(axis=0)
    sd = np.where(sd > 0, sd, 1.0)
    z = (train_x - mu) / sd
    centroids = np.array([z[train_y == k].mean(axis=0) for k in range(nclass)])
    dist = (((test_x - mu) / sd)[:, None, :] - centroids[None]) ** 2
    return dist.sum(axis=2).argmin(axis=1)


def run(
    episodes: int = 8,
    steps: int = 30,
    touch: str = "counts",
    seed: int = 0,
    force_n: float = 0.5,
    speed_m_s: float = 0.04,
    skip: int = 5,
) -> dict:
    if episodes < 2 or steps <= skip:
        raise ValueError(f"need episodes >= 2 (now {episodes}) and steps > skip = {skip}")
    env = gym.make(ENV_ID, touch=touch)
    classes = env.unwrapped.classes
    x, y, split = [], [], []
    for k in range(len(classes)):
        for e in range(episodes):
            x.append(explore(env, k, seed + 1000 * k + e, steps, force_n, speed_m_s, skip))
            y.append(k)
            split.append(e % 2)  # even episodes train, odd test
    env.close()
    x, y, split = np.array(x), np.array(y), np.array(split)
    pred = nearest_centroid(x[split == 0], y[split == 0], x[split == 1], len(classes))
    truth = y[split == 1]
    confusion = np.zeros((len(classes), len(classes)), int)
    np.add.at(confusion, (truth, pred), 1)
    return {
        "touch": touch,
        "classes_m": list(classes),
        "accuracy": float((pred == truth).mean()),
        "chance": 1.0 / len(classes),
        "confusion": confusion.tolist(),
        "test_episodes": int(len(truth)),
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--episodes", type=int, default=8, help="episodes per class (half train)")
    p.add_argument("--steps", type=int, default=30, help="control steps (10 ms) per episode")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    results = [run(args.episodes, args.steps, touch, args.seed) for touch in ("counts", "none")]
    if args.json:
        print(json.dumps(results))
        return 0
    for r in results:
        print(
            f"touch={r['touch']:6s}  accuracy {r['accuracy']:.2f} on {r['test_episodes']} test "
            f"episodes (chance {r['chance']:.2f})"
        )
    print(
        "confusion with touch (rows: true class, periods "
        + ", ".join("flat" if c == 0 else f"{c * 1e3:g} mm" for c in results[0]["classes_m"])
        + "):"
    )
    for row in results[0]["confusion"]:
        print("   " + " ".join(f"{v:3d}" for v in row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
