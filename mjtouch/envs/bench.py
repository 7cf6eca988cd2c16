"""Environment steps per second, with and without touch.

``python -m mjtouch.envs.bench [--env ID] [--num-envs N] [--steps S] [--timestep-s T] [--quick]``

Measures, in this process and on this machine:

- one environment stepped alone, with touch (``touch="counts"``) and without
  (``touch="none"``: the same scene without the skin plugin): the ratio is
  what the skin costs;
- N environments in :class:`~mjtouch.envs.vector.RolloutVectorEnv` (the
  environments stepped on worker threads, one per core) and in Gymnasium's
  ``SyncVectorEnv``, with touch.

Each rate is given per wall second and per CPU second of this process (all
its threads): on a machine shared with other work the wall rate falls, the
CPU rate does not; the CPU rate times the cores is what the vector env
reaches on idle cores. The vector env's line also gives the cores it kept
busy (CPU seconds per wall second).

Random actions (TextureExplore never commits, so episodes run to the limit).
``--quick`` (20 steps, 2 environments) only shows that it works: its numbers
are too short to compare.
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym
import numpy as np

import mjtouch.envs  # noqa: F401  (registers the ids)

QUICK_STEPS, QUICK_NUM_ENVS = 20, 2


def _actions(space: gym.Space, n: int, env_id: str, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.uniform(space.low, space.high, (n,) + space.shape).astype(space.dtype)
    if "TextureExplore" in env_id:
        a[..., 2] = -1.0  # never commit: episodes run to the time limit
    return a


def _timed(fn) -> tuple[float, float]:
    """(wall s, process CPU s) of fn()."""
    w0, c0 = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - w0, time.process_time() - c0


def single_steps_per_s(env_id: str, steps: int, seed: int = 0, **kwargs) -> tuple[float, float]:
    """Env steps per (wall, CPU) second of one environment."""
    env = gym.make(env_id, **kwargs)
    actions = _actions(env.action_space, steps, env_id, seed)
    env.reset(seed=seed)

    def run():
        for a in actions:
            _, _, term, trunc, _ = env.step(a)
            if term or trunc:
                env.reset()

    wall, cpu = _timed(run)
    env.close()
    return steps / wall, steps / cpu


def vector_steps_per_s(
    env_id: str, num_envs: int, steps: int, mode: str, seed: int = 0, **kwargs
) -> tuple[float, float]:
    """Env steps per (wall, CPU) second (num_envs x vector steps / time)."""
    venv = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode, **kwargs)
    actions = _actions(venv.action_space, steps, env_id, seed)
    venv.reset(seed=seed)

    def run():
        for a in actions:
            venv.step(a)

    wall, cpu = _timed(run)
    venv.close()
    return num_envs * steps / wall, num_envs * steps / cpu


def benchmark(
    env_id: str = "mjtouch/TextureExplore-v0",
    num_envs: int = 4,
    steps: int = 200,
    seed: int = 0,
    **env_kwargs,
) -> dict:
    """env_kwargs: passed to every environment (e.g. timestep_s)."""
    if steps < 1 or num_envs < 1:
        raise ValueError(f"steps = {steps} and num_envs = {num_envs} must be >= 1")
    touch, touch_cpu = single_steps_per_s(env_id, steps, seed, **env_kwargs)
    none, none_cpu = single_steps_per_s(env_id, steps, seed, touch="none", **env_kwargs)
    vec_steps = max(1, steps // num_envs)
    rollout, rollout_cpu = vector_steps_per_s(
        env_id, num_envs, vec_steps, "vector_entry_point", seed, **env_kwargs
    )
    sync, sync_cpu = vector_steps_per_s(env_id, num_envs, vec_steps, "sync", seed, **env_kwargs)
    return {
        "env": env_id,
        **env_kwargs,
        "single_touch_steps_per_s": touch,
        "single_no_touch_steps_per_s": none,
        "touch_over_no_touch": touch / none,
        "num_envs": num_envs,
        "rollout_vector_steps_per_s": rollout,
        "sync_vector_steps_per_s": sync,
        "rollout_over_sync": rollout / sync,
        "single_touch_steps_per_cpu_s": touch_cpu,
        "single_no_touch_steps_per_cpu_s": none_cpu,
        "rollout_vector_steps_per_cpu_s": rollout_cpu,
        "sync_vector_steps_per_cpu_s": sync_cpu,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m mjtouch.envs.bench",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--env", default="mjtouch/TextureExplore-v0", choices=sorted(mjtouch.envs.ENV_IDS)
    )
    p.add_argument("--num-envs", type=int, default=4)
    p.add_argument("--steps", type=int, default=200, help="env steps per measurement")
    p.add_argument(
        "--timestep-s",
        type=float,
        default=None,
        help="the environments' physics timestep (s; default theirs, 1 ms)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="a smoke run: 20 steps, 2 environments (overrides --steps, --num-envs)",
    )
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    if args.quick:
        args.steps, args.num_envs = QUICK_STEPS, QUICK_NUM_ENVS
    if args.steps < 1 or args.num_envs < 1:
        p.error(f"--steps {args.steps} and --num-envs {args.num_envs} must be >= 1")
    env_kwargs = {} if args.timestep_s is None else {"timestep_s": args.timestep_s}
    r = benchmark(args.env, args.num_envs, args.steps, **env_kwargs)
    if args.json:
        print(json.dumps(r))
        return 0
    print(
        f"{r['env']}: env steps per second (control step 10 ms"
        f"{', timestep %g ms' % (args.timestep_s * 1e3) if args.timestep_s else ''}, "
        f"{args.steps} steps each); "
        "in brackets per CPU second of this process"
    )
    c = {k: r[k.replace("_per_s", "_per_cpu_s")] for k in r if k.endswith("_per_s")}
    print(
        f"  single env, touch      {r['single_touch_steps_per_s']:10.1f}"
        f"   [{c['single_touch_steps_per_s']:8.1f}]"
    )
    print(
        f"  single env, no touch   {r['single_no_touch_steps_per_s']:10.1f}"
        f"   [{c['single_no_touch_steps_per_s']:8.1f}]"
        f"   (touch / no touch = {r['touch_over_no_touch']:.4f})"
    )
    print(
        f"  {r['num_envs']} envs, rollout      {r['rollout_vector_steps_per_s']:10.1f}"
        f"   [{c['rollout_vector_steps_per_s']:8.1f}]"
        f"   ({r['rollout_vector_steps_per_s'] / c['rollout_vector_steps_per_s']:.2f} cores busy)"
    )
    print(
        f"  {r['num_envs']} envs, sync         {r['sync_vector_steps_per_s']:10.1f}"
        f"   [{c['sync_vector_steps_per_s']:8.1f}]"
        f"   (rollout / sync = {r['rollout_over_sync']:.2f})"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
