"""The benchmark: builds and warms up every configuration, times them in
interleaved rounds (each configuration's minimum over rounds spread across
the phase) and assembles the result dict."""

from __future__ import annotations

import dataclasses
import math
import os
import platform
import time
from collections.abc import Callable

import mujoco
import mujoco.rollout
import numpy as np

from mjtouch.bench.accuracy import Trace, errors, fit_affine, fit_power_law, pareto_front
from mjtouch.bench.configs import (
    LEAD_IN_S,
    MIN_WINDOW_STEPS,
    SITE_RADIUS_M,
    SITE_SPACING_M,
    SKIP_S,
    SPECTRAL_MIN_S,
    BenchConfig,
    Knob,
    default_effects,
    default_knobs,
    lattice_sites,
    scene_parts,
)
from mjtouch.bench.timing import Run, States, add_native_tactile, slide_ctrl, strip_plugin
from mjtouch.progress import Progress  # the bar every long command shares
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

# --- the benchmark -----------------------------------------------------------


def _label(overrides: dict) -> str:
    parts = []
    for k, v in overrides.items():
        if k == "pitch_m":
            parts.append(f"pitch {v * 1e6:.4g} um")
        elif k == "nx":
            parts.append(f"nx {v}")
        elif k == "timestep_s":
            parts.append(f"dt {v:.3g} s")
        elif k == "density_scale":
            parts.append(f"density x{v:g}")
        elif k.startswith("skin."):
            parts.append(f"{k[5:]}={v}")
        else:
            parts.append(f"{k}={v}")
    return ", ".join(parts)


class Bench:
    """The benchmark. Every configuration is built and warmed up first (the
    knob rows also record their data for the errors); then one timing
    phase runs interleaved rounds over all of them, each round timing every
    configuration once, so each configuration's minimum is taken over
    samples spread across the whole phase (the load of a shared machine
    changes over seconds to minutes)."""

    def __init__(self, cfg: BenchConfig, progress: Progress | None = None):
        cfg.validate()
        self.cfg = cfg
        self.texture = scenes.Texture()
        self.states = States(self.texture)
        self.progress = progress
        self._items = []  # (run, nstep, last sensordata, recorded, result dict)

    def _tick(self, label: str) -> None:
        if self.progress:
            self.progress.step(label)

    def _run(
        self,
        overrides: dict,
        sites: str | None = None,
        pressed: bool = True,
        nstep: int = 1,
        edit: Callable[[mujoco.MjSpec], object] | None = None,
        disable_sensors: bool = False,
    ) -> tuple[Run, scenes.Protocol, scenes.Fingertip]:
        tip, proto = scene_parts(overrides, sites)
        spec = scenes.scene_spec(tip, self.texture, proto)
        if edit is not None:
            edit(spec)
        model = spec.compile()
        if disable_sensors:
            model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        state0, warm = self.states.initial(model, pressed)
        return Run(model, state0, warm, slide_ctrl(proto, nstep, pressed)), proto, tip

    def _queue(
        self, run: Run, nstep: int, last: np.ndarray, result: dict, recorded: bool = False
    ) -> None:
        """Time run later (nstep steps per repeat); the repeats must end on
        sensordata `last`. Fills result["us_per_step"], ["repeats_identical"]."""
        self._items.append((run, nstep, last, recorded, result))

    def time_all(self) -> None:
        """The timing phase: repeats rounds over every queued configuration
        (mj_step(nstep) from the settled state, or a rollout if recorded)."""
        items = self._items
        best = [math.inf] * len(items)
        same = [True] * len(items)
        for r in range(self.cfg.repeats):
            for i, (run, nstep, ref, rec, _) in enumerate(items):
                if rec:
                    wall, sd = run.rollout(nstep)
                    last = sd[nstep - 1]
                else:
                    wall, last = run.step(nstep)
                best[i] = min(best[i], wall / nstep)
                same[i] &= bool(np.array_equal(last, ref))
            self._tick(f"timing round {r + 1}/{self.cfg.repeats} ({len(items)} configurations)")
        for (_, _, _, _, result), t, ok in zip(items, best, same):
            result["us_per_step"] = t * 1e6
            result["repeats_identical"] = ok
        self._items = []

    # baselines ----------------------------------------------------------------
    BASELINES = (
        "bare_mujoco",
        "native_tactile",
        "native_tactile_sensors_off",
        "full_pipeline",
        "homogeneous_kernel",
        "idle_plugin",
        "bare_mujoco_idle",
        "idle_plugin_rollout",
        "bare_mujoco_idle_rollout",
    )

    def baselines(self) -> dict:
        """Builds and warms up the baselines; their times come from time_all()."""
        c = self.cfg
        grid = {"nx": c.nx, "pitch_m": c.pitch_m}
        tip = scene_parts(grid)[0]
        tactile = lambda s: add_native_tactile(s, tip.nx, tip.pitch_m, tip.semi_axes_m)  # noqa: E731
        cheap = max(c.cheap_steps, c.time_steps)  # ~20 ms per repeat: call overhead < 0.1%
        recorded = min(cheap, 1000)  # rollout's buffers stay small (23 kB of state per step)
        configs = {  # name: (options, steps per timed repeat, timed through mujoco.rollout)
            "bare_mujoco": (dict(edit=strip_plugin), cheap, False),
            "native_tactile": (dict(edit=tactile), c.time_steps, False),
            "native_tactile_sensors_off": (
                dict(edit=tactile, disable_sensors=True),
                c.time_steps,
                False,
            ),
            "full_pipeline": ({}, c.time_steps, False),
            "homogeneous_kernel": (dict(extra={"skin.skin": "halfspace"}), c.time_steps, False),
            "idle_plugin": (dict(pressed=False), cheap, False),
            "bare_mujoco_idle": (dict(edit=strip_plugin, pressed=False), cheap, False),
            "idle_plugin_rollout": (dict(pressed=False), recorded, True),
            "bare_mujoco_idle_rollout": (dict(edit=strip_plugin, pressed=False), recorded, True),
        }
        self._baseline_results = {}
        models = {}
        for name, (kw, nstep, rec) in configs.items():
            kw = dict(kw)
            extra = kw.pop("extra", {})
            run, proto, _ = self._run({**grid, **extra}, nstep=nstep, **kw)
            # warm-up; its last sensordata is what every timed repeat must reproduce
            last = run.rollout(nstep)[1][-1].copy() if rec else run.step(nstep)[1]
            self._baseline_results[name] = {}
            self._queue(run, nstep, last, self._baseline_results[name], rec)
            models[name] = run.model
            self._tick(f"baseline {name}")
        layout = SkinLayout.from_model(models["full_pipeline"])
        dt = float(models["full_pipeline"].opt.timestep)
        out = {
            "taxels": layout.nx**2,
            "native_tactile_taxels": int(models["native_tactile"].mesh_vertnum[0]),
            "receptors": int(len(layout.classes)),
            "active_taxels": self.active_taxels(grid),
            "timestep_s": dt,
            "contacts_pressed": int(self.states.physics(dt, True)[2]),
            "contacts_idle": int(self.states.physics(dt, False)[2]),
        }
        if out["native_tactile_taxels"] != layout.nx**2:
            raise RuntimeError("the native tactile mesh does not have one vertex per taxel")
        return out

    def finish_baselines(self, out: dict) -> None:
        for name in self.BASELINES:
            out[f"{name}_us_per_step"] = self._baseline_results[name]["us_per_step"]
        out["repeats_identical"] = all(
            r["repeats_identical"] for r in self._baseline_results.values()
        )

    @staticmethod
    def ratios(b: dict) -> dict:
        bare, full = b["bare_mujoco_us_per_step"], b["full_pipeline_us_per_step"]
        plugin = full - bare
        tactile = b["native_tactile_us_per_step"] - b["native_tactile_sensors_off_us_per_step"]
        idle = b["idle_plugin_us_per_step"] / b["bare_mujoco_idle_us_per_step"]
        return {
            "full_over_bare": full / bare,
            "plugin_us_per_step": plugin,
            "native_tactile_sensor_us_per_step": tactile,
            "native_tactile_ns_per_taxel": tactile * 1e3 / b["native_tactile_taxels"],
            "plugin_over_native_tactile_sensor": plugin / tactile if tactile > 0 else None,
            "full_over_native_tactile": full / b["native_tactile_us_per_step"],
            "idle_over_bare_idle": idle,
            "idle_overhead_pct": 100 * (idle - 1),
            "idle_rollout_overhead_pct": 100
            * (
                b["idle_plugin_rollout_us_per_step"] / b["bare_mujoco_idle_rollout_us_per_step"] - 1
            ),
            "layered_over_homogeneous": full / b["homogeneous_kernel_us_per_step"],
            "full_wall_s_per_sim_s": full * 1e-6 / b["timestep_s"],
            "full_over_100us_goal": full / 100.0,
        }

    def active_taxels(self, overrides: dict, sites: str | None = None, nstep: int = 20) -> float:
        """Mean count of taxels with pressure over nstep sliding steps (a
        copy of the configuration with the pressure block output; untimed)."""
        ov = dict(overrides)
        outs = ov.get("skin.outputs", "spikes stress force")
        ov["skin.outputs"] = outs + " pressure"
        run, _, _ = self._run(ov, sites, nstep=nstep)
        sd = run.record(nstep)
        p = SkinLayout.from_model(run.model).block(sd, "pressure")
        return float((p > 0).sum(axis=1).mean())

    # knobs --------------------------------------------------------------------
    def knob_rows(self, k: Knob) -> list[dict]:
        """Builds every setting and records its data; errors against the
        reference and the Pareto front come in finish_rows() after timing."""
        c = self.cfg
        settings = k.all_settings()
        sites = None
        if k.sites:
            grids = []
            for ov, _, _ in settings:
                tip = scene_parts(ov)[0]
                grids.append((tip.nx, tip.pitch_m))
            sites = lattice_sites(grids, min(SITE_RADIUS_M, c.extent_m / 2 - 2 * c.pitch_m))
        rows = []
        for ov, own, is_ref in settings:
            tip, proto = scene_parts(ov, sites)
            nstep = c.knob_steps.get(k.name, k.steps)
            if nstep is None:
                nstep = int(round(c.duration_s / proto.timestep_s))
            need = int(round(SKIP_S / proto.timestep_s)) + MIN_WINDOW_STEPS
            if nstep < need:
                raise ValueError(
                    f"knob {k.name!r}: {nstep} steps of {proto.timestep_s} s leave "
                    f"no error window after the skin's start-up ({SKIP_S} s); "
                    f"valid: >= {need} steps"
                )
            run, proto, tip = self._run(ov, sites, nstep=nstep)
            layout = SkinLayout.from_model(run.model)
            sd = run.record(nstep)  # the data for the errors, and the warm-up
            nt = min(c.time_steps, nstep)
            if ov.get("skin.pressure") == "elastic":
                nt = min(nt, c.elastic_time_steps)
            row = {
                "knob": k.name,
                "overrides": dict(ov),
                "setting": k.labels[len(rows)] if k.labels else _label(own),
                "reference": is_ref,
                "timestep_s": proto.timestep_s,
                "steps": nstep,
                "timed_steps": nt,
                "nx": tip.nx,
                "pitch_m": tip.pitch_m,
                "taxels": tip.nx**2,
                "receptors": int(len(layout.classes)),
                "kernel_build_s": layout.kernel_build_s,
                "stress_basis": "receptor" if k.sites else "class mean",
                "_trace": Trace(
                    layout.block(sd, "stress").copy(),
                    layout.block(sd, "spikes").astype(np.int64),
                    layout.classes,
                    proto.timestep_s,
                ),
            }
            self._queue(run, nt, sd[nt - 1].copy(), row)
            if k.name == "pitch":  # for the scaling fit
                row["active_taxels"] = self.active_taxels(ov, sites)
            rows.append(row)
            self._tick(f"{k.name}: {row['setting']}")
        return rows

    @staticmethod
    def finish_rows(rows: list[dict]) -> None:
        for name in dict.fromkeys(r["knob"] for r in rows):
            kr = [r for r in rows if r["knob"] == name]
            ref = kr[-1]["_trace"]
            for r in kr:
                r["wall_s_per_sim_s"] = r["us_per_step"] * 1e-6 / r["timestep_s"]
                r["errors"] = errors(r.pop("_trace"), ref, r["stress_basis"])
            cost = [r["wall_s_per_sim_s"] for r in kr]
            front = pareto_front(cost, [r["errors"]["stress_rms_rel"] for r in kr])
            front_rate = pareto_front(cost, [r["errors"]["spike_rate_rel"] for r in kr])
            for r, f, fr in zip(kr, front, front_rate):
                r["pareto"] = f  # of the stress error (the table's '*')
                r["pareto_spike_rate"] = fr

    # effects ------------------------------------------------------------------
    def effects(self) -> list[dict]:
        c = self.cfg
        grid = {"nx": c.nx, "pitch_m": c.pitch_m}
        out = []
        for group, label, ov in default_effects(c):
            ov = {**grid, **ov}
            elastic = ov.get("skin.pressure") == "elastic"
            nt = min(c.time_steps, c.elastic_time_steps) if elastic else c.time_steps
            run, _, _ = self._run(ov, nstep=nt)
            r = {
                "group": group,
                "effect": label,
                "overrides": ov,
                "timed_steps": nt,
                "receptors": int(len(SkinLayout.from_model(run.model).classes)),
                "sensordata": int(run.model.nsensordata),
            }
            self._queue(run, nt, run.step(nt)[1], r)  # warm-up
            out.append(r)
            self._tick(f"effect: {label}")
        return out

    @staticmethod
    def finish_effects(out: list[dict]) -> None:
        minimal = next((r["us_per_step"] for r in out if r["group"] == "alone"), None)
        full = next((r["us_per_step"] for r in out if r["group"] == "together"), None)
        for r in out:
            r["over_minimal_us"] = r["us_per_step"] - minimal if minimal is not None else None
            r["over_default_us"] = r["us_per_step"] - full if full is not None else None

    # threads ------------------------------------------------------------------
    def threads(self) -> dict:
        """Wall time of one mujoco.rollout call over threads_batch MjData,
        with 1 and 2 threads (alternating, minimum of repeats)."""
        c = self.cfg
        nb, nt = c.threads_batch, max(10, c.time_steps)
        run, proto, _ = self._run({"nx": c.nx, "pitch_m": c.pitch_m}, nstep=nt)
        states = np.repeat(run.state0[None], nb, axis=0)
        warm = np.repeat(run.warm[None], nb, axis=0)
        state_buf = np.zeros((nb, nt, run.state0.size))
        sd_buf = {n: np.full((nb, nt, run.model.nsensordata), np.nan) for n in (1, 2)}
        pools = {n: mujoco.rollout.Rollout(nthread=n) for n in (1, 2)}
        datas = {n: [mujoco.MjData(run.model) for _ in range(n)] for n in (1, 2)}
        best = {1: math.inf, 2: math.inf}
        try:
            for r in range(c.repeats + 1):
                for n in (1, 2):
                    t0 = time.perf_counter()
                    pools[n].rollout(
                        run.model,
                        datas[n],
                        states,
                        run.ctrl[None, :nt],
                        initial_warmstart=warm,
                        state=state_buf,
                        sensordata=sd_buf[n],
                    )
                    wall = time.perf_counter() - t0
                    if r:  # the first is the warm-up
                        best[n] = min(best[n], wall)
                self._tick(f"threads: round {r + 1}/{c.repeats + 1}")
        finally:
            for pool in pools.values():
                pool.close()
        return {
            "nbatch": nb,
            "steps": nt,
            "wall_s_1_thread": best[1],
            "wall_s_2_thread": best[2],
            "us_per_step_1_thread": best[1] / (nb * nt) * 1e6,
            "us_per_step_2_thread": best[2] / (nb * nt) * 1e6,
            "speedup_2_threads": best[1] / best[2],
            "cpu_count": os.cpu_count(),
            "identical_across_threads": bool(np.array_equal(sd_buf[1], sd_buf[2])),
        }

    # all ----------------------------------------------------------------------
    def knobs(self) -> list[Knob]:
        ks = default_knobs(self.cfg)
        if self.cfg.knobs:
            ks = [k for k in ks if k.name in self.cfg.knobs]
        return ks

    def count_tasks(self) -> int:
        n = len(self.BASELINES) + self.cfg.repeats
        for k in self.knobs():
            n += len(k.settings) + 1
        if self.cfg.effects:
            n += len(default_effects(self.cfg))
        if self.cfg.threads:
            n += self.cfg.repeats + 1
        return n

    def run(self) -> dict:
        t0 = time.perf_counter()
        load0 = _loadavg()
        base = self.baselines()
        rows = []
        for k in self.knobs():
            rows += self.knob_rows(k)
        effects = self.effects() if self.cfg.effects else None
        self.time_all()
        self.finish_baselines(base)
        self.finish_rows(rows)
        out = {
            "machine": _machine(),
            "config": {
                k: (list(v) if isinstance(v, tuple) else v)
                for k, v in dataclasses.asdict(self.cfg).items()
            },
            "scene": {
                "texture": "grating",
                "period_m": self.texture.period_m,
                "force_n": scenes.Protocol().force_n,
                "speed_m_s": scenes.Protocol().speed_m_s,
                "skip_s": SKIP_S,
                "lead_in_s": LEAD_IN_S,
                "spectral_min_s": SPECTRAL_MIN_S,
                "site_spacing_m": SITE_SPACING_M,
            },
            "baselines": base,
            "ratios": self.ratios(base),
            "rows": rows,
        }
        if effects is not None:
            self.finish_effects(effects)
            out["effects"] = effects
            out["profile"] = _profile(base, effects)
        if self.cfg.threads:
            out["threads"] = self.threads()
        out["scaling"] = _scaling(rows, base)
        out["machine"]["loadavg_start"] = load0
        out["machine"]["loadavg_end"] = _loadavg()
        out["machine"]["peak_rss_mb"] = _peak_rss_mb()
        out["wall_s"] = time.perf_counter() - t0
        return out


def _profile(base: dict, effects: list[dict]) -> dict | None:
    """Per-step cost split of the default skin: MuJoCo, stages 1-2 (surface
    and pressure: outputs force only), stages 3-4 (stress and receptors)."""
    full = next((r["us_per_step"] for r in effects if r["group"] == "together"), None)
    force = next(
        (r["us_per_step"] for r in effects if r["effect"].startswith("outputs force")), None
    )
    if full is None or force is None:
        return None
    bare = base["bare_mujoco_us_per_step"]
    return {
        "mujoco_us": bare,
        "surface_pressure_us": force - bare,
        "stress_receptors_us": full - force,
        "total_us": full,
    }


def _scaling(rows: list[dict], base: dict) -> dict:
    """Plugin cost (step minus the bare step) vs active taxels (pitch knob)
    and vs receptors (receptor knob): log-log exponents and affine fits."""
    bare = base["bare_mujoco_us_per_step"]
    out = {"bare_mujoco_us_per_step": bare}
    pitch = [r for r in rows if r["knob"] == "pitch" and "active_taxels" in r]
    if pitch:
        x = [r["active_taxels"] for r in pitch]
        y = [r["us_per_step"] - bare for r in pitch]
        out["active_taxels"] = {
            "points": [[a, b] for a, b in zip(x, y)],
            "power_law": fit_power_law(x, y),
            "affine": fit_affine(x, y),
            "grid_taxels": [r["taxels"] for r in pitch],
            "power_law_vs_grid_taxels": fit_power_law([r["taxels"] for r in pitch], y),
        }
    rec = [r for r in rows if r["knob"] == "receptors"]
    if rec:
        x = [r["receptors"] for r in rec]
        y = [r["us_per_step"] - bare for r in rec]
        out["receptors"] = {
            "points": [[a, b] for a, b in zip(x, y)],
            "power_law": fit_power_law(x, y),
            "affine": fit_affine(x, y),
        }
    return out


def _peak_rss_mb():
    try:
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux
    except (ImportError, OSError):
        return None


def _loadavg():
    try:
        return list(os.getloadavg())
    except OSError:
        return None


def _machine() -> dict:
    return {
        "platform": platform.platform(),
        "processor": platform.processor(),
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "cpu_count": os.cpu_count(),
    }
