"""The speed-up of `mjtouch sweep` on Ray over --serial, same sweep, same machine.

    python examples/bench_sweep.py                 # 8 runs x 3 repeats (~10 min on 2 cores)
    python examples/bench_sweep.py --json

Each repeat runs the sweep serially and then on a fresh local Ray cluster
(`--num-cpus`, default all cores), each into an empty directory, alternating so
both see the same load on a shared machine. It reports, per backend, the min
and median wall time over the repeats and the ratios serial / Ray: with Ray's
startup (what a user waits for) and without it (the runs alone). The tables
of the two backends are compared too: identical but for wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

# 8 runs of 0.3 s of sliding on a 64 x 0.15 mm grid (about 5-10 s each alone)
DEFAULT_SWEEP = [
    "--period",
    "0.8e-3",
    "1e-3",
    "1.2e-3",
    "1.5e-3",
    "--speed",
    "0.02",
    "0.04",
    "--duration",
    "0.3",
    "--nx",
    "64",
    "--pitch",
    "1.5e-4",
    "--dt",
    "2e-4",
]


def sweep(out: str, args: list[str]) -> dict:
    r = subprocess.run(
        [sys.executable, "-m", "mjtouch", "sweep", "--json", "--out", out, *args],
        capture_output=True,
        text=True,
    )
    if r.returncode != 0:
        raise RuntimeError(f"mjtouch sweep failed:\n{r.stderr}")
    return json.loads(r.stdout)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--num-cpus", type=int, default=os.cpu_count())
    p.add_argument("--json", action="store_true")
    p.add_argument(
        "sweep",
        nargs=argparse.REMAINDER,
        help="sweep options after --, e.g. -- --period 1e-3 2e-3 (default: 8 runs)",
    )
    a = p.parse_args(argv)
    args = [x for x in a.sweep if x != "--"] or DEFAULT_SWEEP
    import pyarrow.parquet as pq

    times = {"serial": [], "ray": [], "ray_runs_only": []}
    identical = True
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.repeats):
            s = sweep(f"{tmp}/serial{r}", [*args, "--serial"])
            y = sweep(f"{tmp}/ray{r}", [*args, "--num-cpus", str(a.num_cpus)])
            times["serial"].append(s["wall_s"])
            times["ray"].append(y["wall_s"])
            times["ray_runs_only"].append(y["wall_s"] - y["startup_s"])
            load.append(os.getloadavg()[0])
            ts, ty = (pq.read_table(x["table"]).drop_columns(["wall_s"]) for x in (s, y))
            identical &= ts.num_rows == s["runs"] and ts.equals(ty)
    stats = {
        k: {"min_s": min(v), "median_s": statistics.median(v), "all_s": v} for k, v in times.items()
    }
    out = {
        "runs": s["runs"],
        "repeats": a.repeats,
        "num_cpus": a.num_cpus,
        "cores": os.cpu_count(),
        "wall": stats,
        "speedup_min": stats["serial"]["min_s"] / stats["ray"]["min_s"],
        "speedup_median": stats["serial"]["median_s"] / stats["ray"]["median_s"],
        "speedup_runs_only_median": (
            stats["serial"]["median_s"] / stats["ray_runs_only"]["median_s"]
        ),
        "ray_startup_median_s": statistics.median(
            t - u for t, u in zip(times["ray"], times["ray_runs_only"])
        ),
        "load_average_1min": load,
        "tables_identical": identical,
    }
    if a.json:
        print(json.dumps(out))
        return 0
    print(
        f"{out['runs']} runs x {a.repeats} repeats, Ray on {a.num_cpus} CPUs "
        f"({out['cores']} cores); 1-min load average during: " + ", ".join(f"{x:.1f}" for x in load)
    )
    for k, v in stats.items():
        print(f"  {k:14s} min {v['min_s']:7.1f} s   median {v['median_s']:7.1f} s")
    print(
        f"speed-up serial / Ray: {out['speedup_median']:.2f} (median), "
        f"{out['speedup_min']:.2f} (min); runs only (without Ray's "
        f"{out['ray_startup_median_s']:.1f} s startup): {out['speedup_runs_only_median']:.2f}"
    )
    print(f"tables identical but for wall time: {'yes' if identical else 'NO'}")
    return 0 if identical else 1


if __name__ == "__main__":
    sys.exit(main())
