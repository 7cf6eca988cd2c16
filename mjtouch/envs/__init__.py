"""Gymnasium environments with a tactile fingertip (``pip install 'mjtouch[envs]'``).

Importing this module registers, in Gymnasium's registry:

| id | task | max steps |
|---|---|---|
| ``mjtouch/TextureExplore-v0`` | press and slide, then name the texture (:mod:`.texture_explore`) | 50 (0.5 s) |
| ``mjtouch/SlipHold-v0`` | hold a slipping object with the least grip force (:mod:`.slip_hold`) | 100 (1 s) |
| ``mjtouch/HandManipulateBlockSkin-v0`` | Gymnasium-Robotics' block rotation, five fingertip skins instead of its 92 touch sensors (registered by importing :mod:`.hand_block`; ``mjtouch[robots]``) | 100 |

```python
try:
    import gymnasium as gym
except ImportError as e:  # an optional dependency
    raise ImportError("mjtouch.envs needs gymnasium >= 1.1: pip install 'mjtouch[envs]'") from e
import mjtouch.envs  # noqa: F401 (registers the ids)
env = gym.make("mjtouch/TextureExplore-v0")
envs = gym.make_vec("mjtouch/SlipHold-v0", num_envs=8)  # stepped on threads
```

Every environment takes ``touch="counts" | "rates" | "none"`` (``none``: the
same task without the skin) and ``pressure_image=p`` (add a p x p pressure
image). ``gym.make_vec`` uses :class:`.vector.RolloutVectorEnv` (the
environments stepped on worker threads); ``vectorization_mode="sync"``
gives Gymnasium's ``SyncVectorEnv``. :func:`.bench.benchmark` reports env
steps per second, with and without touch.
"""

from __future__ import annotations

import gymnasium as gym

from mjtouch.envs.base import TOUCH_MODES, TouchEnv
from mjtouch.envs.slip_hold import SlipHoldEnv
from mjtouch.envs.texture_explore import TextureExploreEnv
from mjtouch.envs.vector import RolloutVectorEnv

ENV_IDS = {
    "mjtouch/TextureExplore-v0": dict(
        entry_point="mjtouch.envs.texture_explore:TextureExploreEnv",
        vector_entry_point="mjtouch.envs.vector:texture_explore_vec",
        max_episode_steps=50,
    ),
    "mjtouch/SlipHold-v0": dict(
        entry_point="mjtouch.envs.slip_hold:SlipHoldEnv",
        vector_entry_point="mjtouch.envs.vector:slip_hold_vec",
        max_episode_steps=100,
    ),
}

for _id, _kw in ENV_IDS.items():
    if _id not in gym.registry:
        gym.register(id=_id, **_kw)

__all__ = [
    "ENV_IDS",
    "TOUCH_MODES",
    "RolloutVectorEnv",
    "SlipHoldEnv",
    "TextureExploreEnv",
    "TouchEnv",
]
