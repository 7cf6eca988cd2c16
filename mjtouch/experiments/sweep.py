"""Sweeps of ``slide`` runs on Ray: ``python -m mjtouch sweep`` and :func:`run`.

A sweep takes ``slide``'s options, each with one or several values, lists or
inclusive ranges ``START:STOP:STEP`` (on the command line, in a TOML file or
a dict), and runs their product. Every run is ``mjtouch slide`` with those
options (:func:`mjtouch.cli.slide_with_result`), so a sweep row and a slide
with the same options agree, and new slide options are swept without a change
here (their columns keep the option's name).

Execution: on Ray by default, a local cluster started on this machine's
cores (``num_cpus``), or an existing cluster (``address``, as printed by
``ray start --head``); ``serial`` runs in this process without Ray. Runs are
deterministic by their parameters (the texture ``seed`` included), so the
backend changes nothing in the table but ``wall_s``.

Output directory ``out``:

- ``runs/<run_id>.parquet``: one row per finished run, written as it finishes
  (atomically), so an interrupted sweep loses only the runs in flight;
  ``run_id`` is a hash of the run's parameters, and runs whose file exists are
  skipped (resume by running the same command again, or a larger sweep);
- ``sweep.parquet``: this sweep's rows in product order, written at the end.
  ``pyarrow.parquet.read_table(out / "runs")`` reads every run ever written.

Row columns: the parameters (``period_m``, ``speed_m_s``, ``force_n``, ...),
per receptor class the rate over the steady-sliding window, its spike count
and receptor count (``sa1_rate_hz``, ``sa1_spike_count``, ``sa1_receptors``),
the stress spectral peaks (``peaks_hz``, strongest first), the expected lines
V/D and V/lambda and the stress power there (``power_at_texture_pa2``,
``power_at_ridges_pa2``), ``wall_s``, and the spike trains: per receptor its
class, position and spike times over the whole run (``spike_times_s``, a
list of lists; a step with k spikes gives its time k times).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import hashlib
import itertools
import json
import os
import pathlib
import socket
import sys
import time
from typing import Any, Mapping

import numpy as np

from mjtouch.progress import Progress

# slide options that are not run parameters
NOT_SWEPT = frozenset({"help", "json", "plot", "progress"})
# slide option (argparse dest) -> table column, units in the name
COLUMN = {"period": "period_m", "plateau": "plateau_m", "height": "height_m", "rms": "rms_m",
          "corr_length": "corr_length_m", "dot_spacing": "dot_spacing_m",
          "dot_radius": "dot_radius_m", "speed": "speed_m_s", "force": "force_n",
          "ridge_pitch": "ridge_pitch_m", "duration": "duration_s", "dt": "dt_s",
          "pitch": "pitch_m"}
TABLE = "sweep.parquet"
RAY_NICENESS_ENV = "RAY_worker_niceness"
RUNS = "runs"
TRUE, FALSE = ("true", "on", "yes", "1"), ("false", "off", "no", "0")


def _needs_pyarrow():
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        raise ImportError("mjtouch sweep writes Parquet and needs pyarrow: "
                          "pip install 'mjtouch[ray]'") from None
    return pyarrow


# --- parameters --------------------------------------------------------------


def slide_options() -> list[argparse.Action]:
    """slide's parameter options, in its order (read from its parser, so
    options added to slide are swept too)."""
    from mjtouch import cli
    p = cli._slide_parser(argparse.ArgumentParser().add_subparsers())
    return [a for a in p._actions if a.dest not in NOT_SWEPT]


def _kind(action: argparse.Action) -> str:
    """bool, str, int or float: how a sweep parses and stores the option."""
    flags = (argparse.BooleanOptionalAction, argparse._StoreTrueAction,
             argparse._StoreFalseAction)
    if isinstance(action, flags):
        return "bool"
    if action.choices is not None or action.type in (None, str):
        return "str"
    # slide's float options parse with checking closures (cli._positive_float)
    return "int" if action.type is int else "float"


def _aliases(actions) -> dict[str, argparse.Action]:
    """Every spelling of a parameter: dest, column, option without dashes."""
    out = {}
    for a in actions:
        for name in (a.dest, COLUMN.get(a.dest, a.dest), a.option_strings[0].lstrip("-")):
            out[name] = a
    return out


def _convert(action: argparse.Action, token: str, where: str):
    kind = _kind(action)
    if kind == "bool":
        if token.lower() in TRUE:
            return True
        if token.lower() in FALSE:
            return False
        raise ValueError(f"{where} {token!r} is not a boolean; valid: true/false, on/off")
    try:
        value = action.type(token) if action.type else token
    except (argparse.ArgumentTypeError, ValueError) as e:
        if action.type is int:
            raise ValueError(f"{where} {token!r} is not an integer") from None
        msg = str(e)  # slide's own checks name the option already
        raise ValueError(msg if msg.startswith(where) else f"{where}: {msg}") from None
    if action.choices is not None and value not in action.choices:
        raise ValueError(f"{where} {token!r} is not one of {', '.join(map(str, action.choices))}")
    return value


def _expand_range(action: argparse.Action, token: str, where: str) -> list:
    """START:STOP:STEP, both ends included; STOP - START a whole number of STEPs."""
    parts = token.split(":")
    if len(parts) != 3 or _kind(action) not in ("int", "float"):
        raise ValueError(f"{where} {token!r}: a range is START:STOP:STEP of a numeric option")
    start, stop = (_convert(action, t, where) for t in parts[:2])
    try:
        step = (int if _kind(action) == "int" else float)(parts[2])
    except ValueError:
        raise ValueError(f"{where} {token!r}: STEP {parts[2]!r} is not a number") from None
    if not (np.isfinite(step) and step > 0) or stop < start:
        raise ValueError(f"{where} {token!r}: needs STEP > 0 and STOP >= START")
    n = (stop - start) / step
    k = round(n)
    if abs(n - k) > 1e-9 * max(1.0, abs(n)):
        raise ValueError(f"{where} {token!r}: STOP - START is not a whole number of STEPs")
    if k >= 10_000:
        raise ValueError(f"{where} {token!r}: {k + 1} values; valid up to 10000")
    # 12 significant digits: 0.02 + 3 * 0.01 is the parameter 0.05, not 0.05000000000000001
    return [_convert(action, repr(float(f"{start + i * step:.12g}")) if _kind(action) == "float"
                     else str(start + i * step), where) for i in range(k + 1)]


def _tokens(value) -> list[str]:
    """A TOML / Python value as command-line tokens: scalars, lists, ranges."""
    if isinstance(value, Mapping):
        try:
            return [f"{value['start']!r}:{value['stop']!r}:{value['step']!r}"]
        except KeyError:
            raise ValueError(f"range {value!r} needs start, stop and step") from None
    if isinstance(value, (list, tuple, np.ndarray)):
        return [t for v in value for t in _tokens(v)]
    if isinstance(value, bool):
        return ["true" if value else "false"]
    return [repr(value) if isinstance(value, float) else str(value)]


def parse_values(values: Mapping[str, Any], where: str = "") -> dict[str, list]:
    """{parameter: value(s)} -> {slide dest: [values]}; a parameter is named by
    its slide option (``ridge-pitch``), dest (``ridge_pitch``) or column
    (``ridge_pitch_m``); a value is a scalar, a list, a ``START:STOP:STEP``
    string or a {start, stop, step} table."""
    actions = slide_options()
    names = _aliases(actions)
    out = {}
    for key, value in values.items():
        if key not in names:
            valid = ", ".join(COLUMN.get(a.dest, a.dest) for a in actions)
            raise ValueError(f"{where}unknown sweep parameter {key!r}; valid: {valid}")
        action = names[key]
        label = f"{where}{key}" if where else action.option_strings[0]
        tokens = _tokens(value)
        if not tokens:
            raise ValueError(f"{label}: no values")
        vals = []
        for t in tokens:
            vals += _expand_range(action, t, label) if ":" in t else [_convert(action, t, label)]
        out[action.dest] = list(dict.fromkeys(vals))  # repeated values run once
    return out


def read_config(path: str | os.PathLike) -> dict[str, list]:
    """A TOML sweep file: ``period = [0.8e-3, 1.2e-3]``, ``speed = "0.02:0.04:0.01"``,
    ``force = {start = 0.25, stop = 1.0, step = 0.25}``, ``texture = "grating"``."""
    import tomllib
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise ValueError(f"sweep config {path}: {e}") from None
    return parse_values(data, where=f"{path}: ")


def expand(values: Mapping[str, list]) -> list[dict]:
    """The product of the values ({slide dest: [values]}, others at slide's
    defaults), in slide's option order: a list of {dest: value}."""
    actions = slide_options()
    axes = [values.get(a.dest, [a.default]) for a in actions]
    runs = [dict(zip((a.dest for a in actions), combo)) for combo in itertools.product(*axes)]
    for r in runs:  # as slide's command line checks it, before any run starts
        if "nx" in r and not 4 <= r["nx"] <= 512:
            raise ValueError(f"--nx {r['nx']} is out of range; valid range [4, 512]")
    return runs


def columns(params: Mapping[str, Any]) -> dict[str, Any]:
    return {COLUMN.get(k, k): v for k, v in params.items()}


def run_id(params: Mapping[str, Any]) -> str:
    """A hash of the run's parameters (float repr round-trips, so equal
    parameters give equal ids on every machine)."""
    text = json.dumps(columns(params), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


# --- one run -----------------------------------------------------------------


def spike_trains(spikes: np.ndarray, time_s: np.ndarray) -> list[list[float]]:
    """Per receptor, the times of its spikes (spikes: nstep x nrec counts; a
    step with k spikes gives its time k times)."""
    counts = np.asarray(spikes, dtype=np.int64).T  # nrec x nstep
    return [np.repeat(time_s, c).tolist() for c in counts]


def run_one(params: Mapping[str, Any]) -> dict:
    """One slide run with these parameters ({slide dest: value}) -> its row."""
    from mjtouch import cli
    args = argparse.Namespace(**params, json=True, plot=None, progress="off")
    out, res = cli.slide_with_result(args)
    w = res.window()
    classes = res.layout.classes
    row = {"run_id": run_id(params), **columns(params)}
    for c, rate in out["rates_hz"].items():
        key = c.lower()
        row[f"{key}_rate_hz"] = rate
        row[f"{key}_spike_count"] = int(res.spikes[w][:, classes == c].sum())
        row[f"{key}_receptors"] = int((classes == c).sum())
    peaks = out["peaks_hz"]
    expected, power = out["expected_hz"], out["power_at_expected"]
    row.update({
        "peaks_hz": list(peaks),
        "strongest_peak_hz": peaks[0] if peaks else None,
        "expected_texture_hz": expected["texture"],
        "expected_ridges_hz": expected["ridges"],
        "power_at_texture_pa2": power["texture"],
        "power_at_ridges_pa2": power["ridges"],
        "fft_bin_hz": out["fft_bin_hz"],
        "window_start_s": float(res.time_s[w.start]),
        "normal_force_mean_n": out["normal_force_mean_n"],
        "receptor_class": classes.tolist(),
        "receptor_x_m": res.layout.positions_m[:, 0].tolist(),
        "receptor_y_m": res.layout.positions_m[:, 1].tolist(),
        "receptor_depth_m": res.layout.positions_m[:, 2].tolist(),
        "spike_times_s": spike_trains(res.spikes, res.time_s),
        "wall_s": out["wall_s"],
    })
    return row


def _remote_run(params: dict) -> tuple[dict, str]:
    """run_one on a Ray worker; also says which process ran it."""
    return run_one(params), f"{socket.gethostname()}:{os.getpid()}"


def _schema(row: dict):
    """The row's Arrow schema: parameter types from slide's options (a None
    plateau is a float null), list columns typed, results float64 unless int."""
    pa = _needs_pyarrow()
    kinds = {COLUMN.get(a.dest, a.dest): _kind(a) for a in slide_options()}
    arrow = {"bool": pa.bool_(), "str": pa.string(), "int": pa.int64(), "float": pa.float64()}
    fields = []
    for k, v in row.items():
        if k in kinds:
            t = arrow[kinds[k]]
        elif k == "spike_times_s":
            t = pa.list_(pa.list_(pa.float64()))
        elif k == "receptor_class":
            t = pa.list_(pa.string())
        elif k in ("peaks_hz",) or k.startswith("receptor_"):
            t = pa.list_(pa.float64())
        elif k == "run_id":
            t = pa.string()
        elif isinstance(v, (int, np.integer)) and not isinstance(v, bool):
            t = pa.int64()
        else:
            t = pa.float64()
        fields.append(pa.field(k, t))
    return pa.schema(fields)


def _write_row(runs_dir: pathlib.Path, row: dict) -> None:
    pa = _needs_pyarrow()
    table = pa.Table.from_pylist([row], schema=_schema(row))
    path = runs_dir / f"{row['run_id']}.parquet"
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    pa.parquet.write_table(table, tmp)
    os.replace(tmp, path)  # atomic: a killed sweep never leaves half a row


# --- the sweep ---------------------------------------------------------------


@dataclasses.dataclass
class SweepResult:
    table: Any  # pyarrow.Table: this sweep's rows in product order
    path: pathlib.Path  # out / sweep.parquet
    ran: int  # runs simulated now
    skipped: int  # runs already in the output
    failed: list[tuple[dict, str]]  # (parameters, error) of runs that raised
    backend: str  # "serial" or "ray"
    workers: set[str]  # host:pid of the processes that ran (ray: workers, not the driver)
    wall_s: float  # the whole sweep, startup included
    startup_s: float  # starting or joining Ray (0 serially)

    def summary(self) -> dict:
        return {"runs": self.table.num_rows + len(self.failed), "ran": self.ran,
                "skipped": self.skipped, "failed": [{"params": columns(p), "error": e}
                                                    for p, e in self.failed],
                "backend": self.backend, "workers": len(self.workers),
                "wall_s": self.wall_s, "startup_s": self.startup_s, "table": str(self.path)}


def run(values: Mapping[str, Any] | None = None, out: str | os.PathLike = "sweep", *,
        config: str | os.PathLike | None = None, serial: bool = False,
        address: str | None = None, num_cpus: int | None = None,
        progress: bool = False) -> SweepResult:
    """Run the product of ``values`` (see :func:`parse_values`; ``config``, a
    TOML file, supplies the parameters ``values`` does not) into directory
    ``out``; runs already there are skipped. ``serial`` runs here without
    Ray; otherwise on the Ray cluster at ``address``, or a local one of
    ``num_cpus`` CPUs (default: all) started and stopped here."""
    pa = _needs_pyarrow()
    merged = read_config(config) if config else {}
    merged.update(parse_values(values or {}))
    runs = list({run_id(p): p for p in expand(merged)}.items())
    out = pathlib.Path(out)
    runs_dir = out / RUNS
    runs_dir.mkdir(parents=True, exist_ok=True)
    done = {p.stem for p in runs_dir.glob("*.parquet")}
    todo = [(rid, p) for rid, p in runs if rid not in done]
    failed, workers = [], set()
    t0 = time.perf_counter()
    with contextlib.ExitStack() as stack:
        # Ray starts (seconds) before the bar, so its rate and ETA are the runs'
        ray = None if serial or not todo else stack.enter_context(_ray_session(address, num_cpus))
        startup = time.perf_counter() - t0
        bar = stack.enter_context(Progress(len(runs), progress, desc="sweep", unit="run",
                                           initial=len(runs) - len(todo)))
        if ray is None:
            workers.add(f"{socket.gethostname()}:{os.getpid()}")
            for _, p in todo:
                try:
                    _write_row(runs_dir, run_one(p))
                except ValueError as e:  # a bad parameter combination: report it, run the rest
                    failed.append((p, str(e)))
                bar.step(_label(p))
        else:
            _run_ray(ray, todo, runs_dir, bar, failed, workers)
    wall = time.perf_counter() - t0
    ids = [rid for rid, _ in runs if (runs_dir / f"{rid}.parquet").exists()]
    tables = [pa.parquet.read_table(runs_dir / f"{rid}.parquet") for rid in ids]
    table = pa.concat_tables(tables, promote_options="default") if tables else pa.table({})
    path = out / TABLE
    pa.parquet.write_table(table, path)
    return SweepResult(table, path, len(todo) - len(failed), len(runs) - len(todo), failed,
                       "serial" if serial else "ray", workers, wall, startup)


def _label(p: Mapping[str, Any]) -> str:
    return " ".join(f"{k}={v}" for k, v in p.items()
                    if k in ("texture", "period", "speed", "force", "seed"))


def _run_ray(ray, todo, runs_dir, bar, failed, workers) -> None:
    # one CPU per run: a run is one single-threaded simulation
    remote = ray.remote(num_cpus=1, max_retries=0)(_remote_run)
    pending = {remote.remote(p): p for _, p in todo}
    while pending:
        # whatever finished within a second: one wait per batch, not per run
        # (each wait walks all pending refs; sweeps have thousands)
        ready, _ = ray.wait(list(pending), num_returns=len(pending), timeout=1.0)
        for ref in ready:
            p = pending.pop(ref)
            try:
                row, worker = ray.get(ref)
            except ray.exceptions.RayTaskError as e:
                if not isinstance(e.cause, ValueError):
                    raise
                failed.append((p, str(e.cause)))
            else:
                _write_row(runs_dir, row)  # the driver writes: cluster nodes share no disk
                workers.add(worker)
            bar.step(_label(p))


@contextlib.contextmanager
def _ray_session(address: str | None, num_cpus: int | None):
    """Ray, connected: the caller's session if one is up; else the cluster at
    address, or a local cluster of num_cpus CPUs (stopped at the end). Local
    workers import the mjtouch the driver sees (Ray puts the driver's
    working directory on their path)."""
    try:
        import ray
    except ImportError:
        raise ImportError("Ray is not installed: pip install 'mjtouch[ray]', or run with "
                          "--serial (serial=True)") from None
    if ray.is_initialized():
        yield ray
        return
    import logging
    kw = dict(logging_level=logging.WARNING, include_dashboard=False)
    if address:
        _check_reachable(address)
        try:
            ray.init(address=address, **kw)
        except (ConnectionError, RuntimeError) as e:  # no cluster, wrong token, ...
            raise ConnectionError(f"could not join the Ray cluster at --address {address}: "
                                  f"{str(e).splitlines()[0]} (see `ray status` on the head "
                                  "node; Ray's token authentication: README, Sweeps)") from e
    else:
        # Ray renices its workers by +15 to keep its control plane responsive;
        # here the runs are the cluster's only work, and on a shared machine
        # +15 made a Ray sweep slower than --serial (README, Sweeps). The
        # workers run at the driver's niceness, unless RAY_worker_niceness says.
        config = {} if RAY_NICENESS_ENV in os.environ else {"worker_niceness": 0}
        # "local": a new cluster even when `ray start` runs one here (--address auto joins that)
        ray.init(address="local", num_cpus=num_cpus, _system_config=config, **kw)
    try:
        yield ray
    finally:
        ray.shutdown()


def _check_reachable(address: str, timeout_s: float = 5.0) -> None:
    """A HOST:PORT address must answer: ray.init retries an absent cluster
    without end (measured: still waiting after 12 min with Ray 2.60)."""
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit() or "://" in address:
        return  # "auto", ray:// client addresses: Ray resolves them
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as e:
        raise ConnectionError(f"could not join the Ray cluster at --address {address}: nothing "
                              f"answers there ({e}); start one with `ray start --head --port "
                              f"{port}`") from None


# --- command line ------------------------------------------------------------


def add_arguments(p: argparse.ArgumentParser) -> None:
    """sweep's options: every slide parameter option taking several values,
    then where and how to run."""
    for a in slide_options():
        kind = _kind(a)
        metavar = {"bool": "BOOL", "str": "CHOICE", "int": "N"}.get(kind, "X")
        help_ = (a.help or a.dest) + (f"; choices {', '.join(a.choices)}" if a.choices else "")
        if kind == "bool":
            help_ = (a.help or a.dest) + "; true, false or both"
        p.add_argument(*a.option_strings[:1], dest=a.dest, nargs="+", metavar=metavar,
                       default=None, help=help_ + ("; values or START:STOP:STEP"
                                                   if kind in ("int", "float") else ""))
    p.add_argument("--config", metavar="TOML",
                   help="a TOML file of parameters (command-line options override its keys)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output directory: DIR/sweep.parquet and DIR/runs/ (runs already "
                        "there are skipped)")
    p.add_argument("--serial", action="store_true", help="run in this process, without Ray")
    p.add_argument("--address", default=None,
                   help="join the Ray cluster at this address (e.g. HEAD_IP:6379, as printed by "
                        "`ray start --head`; or auto); default: start a local one")
    p.add_argument("--num-cpus", type=int, default=None,
                   help="CPUs of the local Ray cluster (default: all of this machine's)")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    from mjtouch import progress
    progress.add_argument(p)


def main(args) -> int:
    from mjtouch import progress
    given = {a.dest: getattr(args, a.dest) for a in slide_options()
             if getattr(args, a.dest) is not None}
    problem = None
    if args.num_cpus is not None and args.num_cpus < 1:
        problem = f"--num-cpus {args.num_cpus} must be >= 1"
    elif args.num_cpus is not None and (args.address or args.serial):
        problem = "--num-cpus sizes the local Ray cluster; not with --address or --serial"
    elif args.address and args.serial:
        problem = "--address joins a Ray cluster; not with --serial"
    if problem:
        print(f"mjtouch sweep: error: {problem}", file=sys.stderr)
        return 2
    try:
        result = run(given, args.out, config=args.config, serial=args.serial,
                     address=args.address, num_cpus=args.num_cpus,
                     progress=progress.wanted(args.progress, args.json))
    except (ValueError, ImportError, ConnectionError) as e:
        print(f"mjtouch sweep: error: {e}", file=sys.stderr)
        return 2
    s = result.summary()
    if args.json:
        print(json.dumps(s))
    else:
        n, w = s["runs"], s["workers"]
        print(f"mjtouch sweep: {n} run{'s' * (n != 1)} ({s['ran']} ran, {s['skipped']} already "
              f"in {args.out}, {len(s['failed'])} failed) on {s['backend']} ({w} worker "
              f"process{'es' * (w != 1)}), wall {s['wall_s']:.1f} s ({s['startup_s']:.1f} s "
              f"starting) -> {s['table']}")
    for f in s["failed"]:
        print(f"mjtouch sweep: run failed: {f['error']}  ({f['params']})", file=sys.stderr)
    return 1 if s["failed"] else 0
