"""A slip reflex holds SlipHold with less grip than any safe constant grip.

The reflex reads only the skin, 75 ms late (rounded up to whole control
steps: the human grip response comes 74 +- 9 ms after a slip, Johansson &
Westling 1987): the tangential force it carries (the ``contact`` block) and
its slip zone (the ``slip`` block: the share of the contact whose traction is
at the Coulomb limit). Like a human grip it scales the grip with the load,
grip = (tangential force extrapolated over the delay + 0.15 N) / (0.8 mu).
It learns mu from the slip zone, as a finger feels the friction at first
contact: it eases its grip until the rim slips (a zone over 20% of the
contact), reads Q / mu P = 1 - (1 - zone)^2 there (Cattaneo-Mindlin on
the Winkler skin) and so mu; it updates mu whenever the zone shows again,
and cuts it by 20% when the whole contact slips. Its parameters were
set on training episodes (seeds 0-29), not on the test episodes.

Compared on the fixed test episodes (``slip_hold.TEST_SEEDS``) with the best
constant grip, found by a sweep on the same episodes::

    python examples/slip_reflex.py            # sweep + reflex on the 30 test episodes
    python examples/slip_reflex.py --episodes 5 --json
"""

from __future__ import annotations

import argparse
import collections
import json
import math
import sys

import numpy as np

from mjtouch.envs import slip_hold

HUMAN_DELAY_S = 0.075
FELT_N = 1e-3  # a tangential force the skin reports (the reset observation's is 0)


class SlipReflex:
    """Grip in proportion to the load, at a margin over the friction the slip
    zone reveals; every input seen delay_s late."""

    def __init__(
        self,
        delay_s: float = HUMAN_DELAY_S,
        control_dt_s: float = 0.01,
        target_ratio: float = 0.8,
        probe_decay: float = 0.96,
        informative_zone: float = 0.2,
        slip_cut: float = 0.8,
        margin_n: float = 0.15,
        min_grip_n: float = 0.1,
    ):
        self.delay_steps = math.ceil(delay_s / control_dt_s - 1e-9)
        self.target_ratio = target_ratio  # load / (mu x grip) to hold at
        self.probe_decay = probe_decay  # grip factor per step while friction is unknown
        self.informative_zone = informative_zone  # smaller zones resolve too few cells
        self.slip_cut = slip_cut  # friction estimate factor when the contact slips
        self.margin_n = margin_n  # load the grip is set to bear beyond the predicted load
        self.min_grip_n = min_grip_n
        self.reset()

    def reset(self) -> None:
        self.seen: collections.deque = collections.deque(maxlen=self.delay_steps + 2)
        self.grip_n = None
        self.mu = None  # the friction coefficient as the slip zone reveals it

    def __call__(self, obs: np.ndarray, env) -> np.ndarray:
        u = env.unwrapped
        self.seen.append(u.split_observation(obs))
        if self.grip_n is None:
            self.grip_n = u.settle_force_n  # the grip the episode starts with
        # what the skin felt delay_steps control steps ago, and the step before
        if len(self.seen) <= self.delay_steps:
            return slip_hold.grip_action(u, self.grip_n)
        now = self.seen[-1 - self.delay_steps]
        before = self.seen[-2 - self.delay_steps] if len(self.seen) > self.delay_steps + 1 else now
        normal = float(now["contact"][0])
        q = float(np.hypot(*now["contact"][1:]))
        q_before = float(np.hypot(*before["contact"][1:]))
        if q < FELT_N or normal < FELT_N:  # nothing felt yet
            return slip_hold.grip_action(u, self.grip_n)
        if q_before < FELT_N:
            q_before = q
        stuck_least, zone = float(now["slip"][1]), float(now["slip"][2])
        if stuck_least == 0.0:  # the whole contact slipped: less friction than thought
            self.mu = self.slip_cut * (self.mu if self.mu is not None else q / normal)
        elif zone >= self.informative_zone:
            # Cattaneo on the Winkler skin: zone share 1 - (1 - Q / mu P)^(1/2)
            ratio = 1.0 - (1.0 - zone) ** 2
            self.mu = q / (normal * ratio)
        if self.mu is None:  # friction unknown: ease the grip until the rim slips
            self.grip_n *= self.probe_decay
        else:  # the load extrapolated over the delay, at the target margin
            q_pred = q + max(0.0, q - q_before) * (self.delay_steps + 1)
            self.grip_n = (q_pred + self.margin_n) / (self.mu * self.target_ratio)
        self.grip_n = max(self.min_grip_n, self.grip_n)
        return slip_hold.grip_action(u, self.grip_n)


def constant_grip_sweep(seeds, grips_n) -> list[dict]:
    """Each constant grip on the episodes (touch="none": the same physics)."""
    env = slip_hold.SlipHoldEnv(touch="none")
    rows = []
    for g in grips_n:
        r = slip_hold.evaluate(lambda obs, e, g=g: slip_hold.grip_action(e, g), seeds, env)
        rows.append({"grip_n": float(g), **{k: r[k] for k in ("mean_return", "drops")}})
    return rows


def best_constant(seeds) -> dict:
    """The least constant grip that drops nothing: coarse then fine sweep."""
    coarse = constant_grip_sweep(seeds, np.round(np.arange(0.5, 2.0001, 0.1), 3))
    safe = [r["grip_n"] for r in coarse if r["drops"] == 0]
    if not safe:
        raise RuntimeError("no constant grip up to 2 N holds every episode")
    lo = min(safe)
    fine = constant_grip_sweep(seeds, np.round(np.arange(lo - 0.1, lo + 1e-9, 0.01), 3))
    held = [r for r in fine if r["drops"] == 0]
    return min(held, key=lambda r: r["grip_n"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=len(slip_hold.TEST_SEEDS))
    ap.add_argument("--delay", type=float, default=HUMAN_DELAY_S, help="reflex latency, s")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if not 1 <= args.episodes <= len(slip_hold.TEST_SEEDS):
        raise SystemExit(f"--episodes must be in [1, {len(slip_hold.TEST_SEEDS)}]")
    seeds = slip_hold.TEST_SEEDS[: args.episodes]
    best = best_constant(seeds)
    reflex = SlipReflex(delay_s=args.delay)
    r = slip_hold.evaluate(reflex, seeds)
    out = {
        "episodes": len(seeds),
        "delay_s": reflex.delay_steps * 0.01,
        "best_constant": best,
        "reflex": {k: r[k] for k in ("mean_return", "drops", "mean_grip_n_all")},
        "reflex_grip_n_per_episode": r["mean_grip_n"],
    }
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{len(seeds)} test episodes (SlipHold, seeds {seeds[0]}..{seeds[-1]})")
    print(f"{'policy':32s} {'return':>8s} {'drops':>6s} {'mean grip N':>12s}")
    print(
        f"{'best constant grip':32s} {best['mean_return']:8.3f} {best['drops']:6d} "
        f"{best['grip_n']:12.3f}"
    )
    rr = out["reflex"]
    label = f"slip reflex ({out['delay_s'] * 1e3:.0f} ms late)"
    print(f"{label:32s} {rr['mean_return']:8.3f} {rr['drops']:6d} {rr['mean_grip_n_all']:12.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
