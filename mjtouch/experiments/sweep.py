"""Sweeps of ``slide`` runs on Ray: ``python -m mjtouch sweep`` and :func:`run`.

A sweep takes the fields of :class:`mjtouch.experiments.slide.SlideParams`,
each with one or several values, lists or inclusive ranges ``START:STOP:STEP``
(on the command line, in a TOML file or a dict), and runs their product. Every
run is :func:`mjtouch.experiments.slide.run` of those parameters, so a sweep
row and a slide with the same parameters agree, and new SlideParams fields are
swept without a change here; the table's parameter columns are the field
names.

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

import contextlib
import dataclasses
import hashlib
import itertools
import json
import os
import pathlib
import socket
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from mjtouch.experiments import slide
from mjtouch.progress import Progress

TABLE = "sweep.parquet"
RAY_NICENESS_ENV = "RAY_worker_niceness"
RUNS = "runs"


def _needs_pyarrow():
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        raise ImportError(
            "mjtouch sweep writes Parquet and needs pyarrow: pip install 'mjtouch[ray]'"
        ) from None
    return pyarrow


# --- parameters --------------------------------------------------------------


def parameters() -> tuple[str, ...]:
    """The swept parameters, in order: the SlideParams field names, which are
    also the table's parameter columns."""
    return tuple(f.name for f in slide.fields())


def _aliases() -> dict[str, str]:
    """Every spelling of a parameter -> its field: the field (``ridge_pitch_m``),
    the option without dashes (``ridge-pitch``) or with underscores (``ridge_pitch``)."""
    out = {}
    for f in slide.fields():
        option = slide.flag(f)[2:]
        for name in (f.name, option, option.replace("-", "_")):
            out[name] = f.name
    return out


def _kind(name: str) -> str:
    return slide.field(name).metadata["kind"]


def _expand_range(name: str, token: str, where: str) -> list:
    """START:STOP:STEP, both ends included; STOP - START a whole number of STEPs."""
    parts = token.split(":")
    kind = _kind(name)
    if len(parts) != 3 or kind not in ("int", "float"):
        raise ValueError(f"{where} {token!r}: a range is START:STOP:STEP of a numeric option")
    start, stop = (slide.parse(name, t, where) for t in parts[:2])
    try:
        step = (int if kind == "int" else float)(parts[2])
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
    return [
        slide.parse(
            name,
            repr(float(f"{start + i * step:.12g}")) if kind == "float" else str(start + i * step),
            where,
        )
        for i in range(k + 1)
    ]


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
    """{parameter: value(s)} -> {SlideParams field: [values]}; a parameter is
    named by its field (``ridge_pitch_m``) or its slide option (``ridge-pitch``,
    ``ridge_pitch``); a value is a scalar, a list, a ``START:STOP:STEP`` string
    or a {start, stop, step} table. Each value is checked as SlideParams
    checks it."""
    names = _aliases()
    out = {}
    for key, value in values.items():
        if key not in names:
            raise ValueError(
                f"{where}unknown sweep parameter {key!r}; valid: {', '.join(parameters())}"
            )
        name = names[key]
        label = f"{where}{key}" if where else slide.flag(name)
        tokens = _tokens(value)
        if not tokens:
            raise ValueError(f"{label}: no values")
        vals = []
        for t in tokens:
            vals += _expand_range(name, t, label) if ":" in t else [slide.parse(name, t, label)]
        out[name] = list(dict.fromkeys(vals))  # repeated values run once
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
    """The product of the values ({field: [values]}, others at SlideParams'
    defaults), in field order: a list of {field: value}."""
    fields = slide.fields()
    axes = [values.get(f.name, [f.default]) for f in fields]
    return [dict(zip((f.name for f in fields), combo)) for combo in itertools.product(*axes)]


def run_id(params: Mapping[str, Any]) -> str:
    """A hash of the run's parameters (float repr round-trips, so equal
    parameters give equal ids on every machine)."""
    text = json.dumps(dict(params), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


# --- one run -----------------------------------------------------------------


def spike_trains(spikes: np.ndarray, time_s: np.ndarray) -> list[list[float]]:
    """Per receptor, the times of its spikes (spikes: nstep x nrec counts; a
    step with k spikes gives its time k times)."""
    counts = np.asarray(spikes, dtype=np.int64).T  # nrec x nstep
    return [np.repeat(time_s, c).tolist() for c in counts]


def run_one(params: Mapping[str, Any]) -> dict:
    """One slide run with these parameters ({field: value}) -> its row."""
    run = slide.run(slide.SlideParams(**params))
    out, res = run.summary, run.result
    w = res.window()
    classes = res.layout.classes
    row = {"run_id": run_id(params), **params}
    for c, rate in out["rates_hz"].items():
        key = c.lower()
        row[f"{key}_rate_hz"] = rate
        row[f"{key}_spike_count"] = int(res.spikes[w][:, classes == c].sum())
        row[f"{key}_receptors"] = int((classes == c).sum())
    peaks = out["peaks_hz"]
    expected, power = out["expected_hz"], out["power_at_expected"]
    row.update(
        {
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
        }
    )
    return row


def _remote_run(params: dict) -> tuple[dict, str]:
    """run_one on a Ray worker; also says which process ran it."""
    return run_one(params), f"{socket.gethostname()}:{os.getpid()}"


def _schema(row: dict):
    """The row's Arrow schema: parameter types from SlideParams' fields (a None
    plateau is a float null), list columns typed, results float64 unless int."""
    pa = _needs_pyarrow()
    kinds = {name: _kind(name) for name in parameters()}
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
        return {
            "runs": self.table.num_rows + len(self.failed),
            "ran": self.ran,
            "skipped": self.skipped,
            "failed": [{"params": dict(p), "error": e} for p, e in self.failed],
            "backend": self.backend,
            "workers": len(self.workers),
            "wall_s": self.wall_s,
            "startup_s": self.startup_s,
            "table": str(self.path),
        }


def run(
    values: Mapping[str, Any] | None = None,
    out: str | os.PathLike = "sweep",
    *,
    config: str | os.PathLike | None = None,
    serial: bool = False,
    address: str | None = None,
    num_cpus: int | None = None,
    progress: bool = False,
) -> SweepResult:
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
        bar = stack.enter_context(
            Progress(len(runs), progress, desc="sweep", unit="run", initial=len(runs) - len(todo))
        )
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
    return SweepResult(
        table,
        path,
        len(todo) - len(failed),
        len(runs) - len(todo),
        failed,
        "serial" if serial else "ray",
        workers,
        wall,
        startup,
    )


def _label(p: Mapping[str, Any]) -> str:
    return " ".join(
        f"{k}={v}"
        for k, v in p.items()
        if k in ("texture", "period_m", "speed_m_s", "force_n", "seed")
    )


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
        raise ImportError(
            "Ray is not installed: pip install 'mjtouch[ray]', or run with --serial (serial=True)"
        ) from None
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
            raise ConnectionError(
                f"could not join the Ray cluster at --address {address}: "
                f"{str(e).splitlines()[0]} (see `ray status` on the head "
                "node; Ray's token authentication: README, Sweeps)"
            ) from e
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
        raise ConnectionError(
            f"could not join the Ray cluster at --address {address}: nothing "
            f"answers there ({e}); start one with `ray start --head --port "
            f"{port}`"
        ) from None
