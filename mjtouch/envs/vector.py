"""Batched stepping over threads.

:class:`RolloutVectorEnv` holds N environments of one class and steps them
on ``nthread`` threads: each environment advances its control step with its
own ``mujoco.rollout`` call (the physics, which releases the GIL) on a
thread, and its task logic (actions to inputs, observations, rewards) runs
in Python in the calling thread, where it overlaps the other threads'
physics instead of contending with it for the GIL. Each
environment's results are bit-identical to stepping it alone (it is the same
code on the same data). It is the registered ``vector_entry_point``, so
``gymnasium.make_vec("mjtouch/TextureExplore-v0", num_envs=8)`` returns it;
``vectorization_mode="sync"`` or ``"async"`` give Gymnasium's own.

Autoreset follows Gymnasium's default (``AutoresetMode.NEXT_STEP``): the step
after an episode ends resets that environment and returns its first
observation with reward 0.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor, wait

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from mjtouch.envs.base import TouchEnv


def _usable_cores() -> int:
    """Cores this process may run on (its affinity where the OS tells)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1


class RolloutVectorEnv(gym.vector.VectorEnv):
    """num_envs environments of env_cls (built with env_kwargs), stepped on
    nthread threads (default: one per core this process may run on, at most
    num_envs; 0 or 1: in the calling thread, in turn); max_episode_steps
    truncates."""

    def __init__(
        self,
        env_cls: type[TouchEnv],
        num_envs: int,
        *,
        max_episode_steps: int | None = None,
        nthread: int | None = None,
        **env_kwargs,
    ):
        if not (isinstance(num_envs, int) and num_envs >= 1):
            raise ValueError(f"num_envs = {num_envs!r} must be a positive integer")
        if max_episode_steps is not None and max_episode_steps < 1:
            raise ValueError(f"max_episode_steps = {max_episode_steps} must be >= 1 or None")
        if env_kwargs.get("render_mode") is not None:
            raise ValueError("RolloutVectorEnv does not render; render a single environment")
        env_kwargs.pop("render_mode", None)
        if nthread is None:
            nthread = min(num_envs, _usable_cores())
        if not (isinstance(nthread, int) and nthread >= 0):
            raise ValueError(f"nthread = {nthread!r} must be a non-negative integer")
        if env_cls.step is not TouchEnv.step:
            raise ValueError(
                f"{env_cls.__name__} overrides step; RolloutVectorEnv steps TouchEnv's parts "
                "(_check_action, _inputs, _advance, _finish)"
            )
        self.envs = [env_cls(**env_kwargs) for _ in range(num_envs)]
        e0 = self.envs[0]
        self.num_envs = num_envs
        self.single_observation_space = e0.observation_space
        self.single_action_space = e0.action_space
        self.observation_space = batch_space(e0.observation_space, num_envs)
        self.action_space = batch_space(e0.action_space, num_envs)
        self.metadata = {**e0.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self.render_mode = None
        self.max_episode_steps = max_episode_steps
        self.nthread = nthread
        # The calling thread steps one share of the environments and
        # nthread - 1 workers the others (nthread <= 1: all in turn).
        self._pool = (
            ThreadPoolExecutor(nthread - 1, thread_name_prefix="mjtouch-env")
            if nthread > 1
            else None
        )
        self._elapsed = np.zeros(num_envs, dtype=np.int64)
        self._autoreset = np.zeros(num_envs, dtype=bool)

    def reset(self, *, seed=None, options=None):
        if seed is None:
            seeds = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"{len(seeds)} seeds for {self.num_envs} environments")
        obs, infos = [], {}
        for i, (env, s) in enumerate(zip(self.envs, seeds)):
            o, info = env.reset(seed=s, options=options)
            obs.append(o)
            infos = self._add_info(infos, info, i)
        self._elapsed[:] = 0
        self._autoreset[:] = False
        return np.stack(obs), infos

    def step(self, actions):
        actions = np.asarray(actions)
        n = self.num_envs
        if actions.shape[0] != n:
            raise ValueError(f"actions has {actions.shape[0]} rows for {n} environments")
        obs = np.zeros((n,) + self.single_observation_space.shape)
        rewards = np.zeros(n)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        infos: dict = {}
        stepping = []
        for i, env in enumerate(self.envs):
            if self._autoreset[i]:
                o, info = env.reset()
                obs[i] = o
                self._elapsed[i] = 0
                infos = self._add_info(infos, info, i)
            else:
                stepping.append(i)

        # TouchEnv.step split in its parts: every action checked before any
        # environment steps, then each environment's inputs, its physics (the
        # rollouts, which release the GIL) on the threads and its task logic
        # (observation, reward) in this thread, the first share's while the
        # workers' physics still runs. Each environment runs the same calls
        # in the same order as stepped alone.
        checked = {i: self.envs[i]._check_action(actions[i]) for i in stepping}
        inputs = {i: self.envs[i]._inputs(a) for i, a in checked.items()}
        physics = [i for i in stepping if inputs[i] is not None]
        results = [
            (i, self.envs[i]._finish(None, None, checked[i])) for i in stepping if inputs[i] is None
        ]

        def advance_share(share):
            return [(i, self.envs[i]._advance(inputs[i])) for i in share]

        def finish(advanced):
            for i, (final_state, sensordata) in advanced:
                results.append((i, self.envs[i]._finish(final_state, sensordata, checked[i])))

        if self._pool is None or len(physics) < 2:
            finish(advance_share(physics))
        else:
            shares = [physics[k :: self.nthread] for k in range(self.nthread)]
            futures = [self._pool.submit(advance_share, s) for s in shares[1:] if s]
            try:
                finish(advance_share(shares[0]))
                for f in futures:
                    finish(f.result())
            finally:  # no worker still stepping when this returns or raises
                wait(futures)
        for i, (o, r, term, trunc, info) in sorted(results, key=lambda x: x[0]):
            self._elapsed[i] += 1
            if self.max_episode_steps is not None and self._elapsed[i] >= self.max_episode_steps:
                trunc = True
            obs[i], rewards[i], terminated[i], truncated[i] = o, r, term, trunc
            infos = self._add_info(infos, info, i)
        self._autoreset = terminated | truncated
        return obs, rewards, terminated, truncated, infos

    def close_extras(self, **kwargs):
        for env in self.envs:
            env.close()
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None


def texture_explore_vec(num_envs: int = 1, **kwargs) -> RolloutVectorEnv:
    from mjtouch.envs.texture_explore import TextureExploreEnv

    return RolloutVectorEnv(TextureExploreEnv, num_envs, **kwargs)


def slip_hold_vec(num_envs: int = 1, **kwargs) -> RolloutVectorEnv:
    from mjtouch.envs.slip_hold import SlipHoldEnv

    return RolloutVectorEnv(SlipHoldEnv, num_envs, **kwargs)
