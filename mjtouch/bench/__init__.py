"""What accuracy costs in time: ``python -m mjtouch bench``.

The default sliding scene (:mod:`mjtouch.scene.scenes`: ridged fingertip pressed
with 0.5 N on the 1 mm grating, slid at 25 mm/s) is run with one knob changed
at a time. For every setting the benchmark reports the cost per step and per
simulated second, and the error against that knob's converged reference,
computed in the same run from the same starting state:

- ``stress_rms_rel``: RMS over the window and receptors of the receptor
  stress error, over the reference's RMS stress (``stress_rms_pa``: in Pa);
- ``peak_freq_hz``: |strongest stress spectral peak - the reference's|;
- ``peak_amp_rel``: |spectral amplitude at the reference's peak / the
  reference's - 1| (amplitude = sqrt of the periodogram power);
- ``spike_rate_rel``: sum over classes of |population rate - reference's|
  over the sum of the reference's rates (``spike_rate_hz``: signed, per class).

Every knob but ``receptors`` gives all its settings the same explicit
receptor ``sites`` (a 0.6 mm lattice, a common multiple of every swept pitch,
so each site is a taxel centre of every grid and no setting moves a
receptor); ``receptors`` scales the density, so its stress error compares
the class-mean stress traces instead (``stress_basis``). Spectral errors need
``SPECTRAL_MIN_S`` of window; shorter rows (the elastic pressure model)
report them as null.

Timing: one process, same-process ratios; every run starts from one settled
state (the press and a lead-in of sliding are simulated once per timestep on
the scene without the plugin, then set with ``mj_setState``; the skin's own
state starts fresh, and its first ``SKIP_S`` are left out of the errors);
only the sliding phase is timed, as ``mj_step(model, data, nstep)`` (a C
loop, nothing recorded per step). Each configuration is warmed up once
(the knob rows record their data then, step by step); then timing rounds
run over all configurations, each round timing every configuration once,
and each configuration reports its minimum over the rounds: on a shared
machine the load changes over seconds to minutes, and interleaving spreads
every configuration's samples over the whole phase. Every timed run must
end on the warm-up's sensordata bit for bit (``repeats_identical``).
Threads are timed separately as wall time of ``mujoco.rollout`` calls.

Adding a knob is one line in :func:`default_knobs`: a :class:`Knob` lists
its settings as override dicts (keys in ``OVERRIDE_KEYS``), cheapest first,
and the reference setting.

The package, by concern: ``configs`` (knobs, presets, BenchConfig, receptor
sites), ``timing`` (baseline scenes, settled states, timed runs), ``accuracy``
(errors against references, Pareto front, fits), ``runner`` (the Bench: warm-up,
interleaved timing rounds, the result), ``report`` (table, figure), ``cli``.
"""

from __future__ import annotations

from mjtouch.bench.accuracy import (
    Trace,
    class_means,
    errors,
    fit_affine,
    fit_power_law,
    pareto_front,
)
from mjtouch.bench.cli import add_arguments, config_from_args, main
from mjtouch.bench.configs import (
    ALL_OUTPUTS,
    DEFAULT_DENSITY,
    EXTENT_M,
    FMAX_HZ,
    FMIN_HZ,
    LEAD_IN_S,
    MINIMAL,
    OVERRIDE_KEYS,
    PRESETS,
    SITE_DEPTH_M,
    SITE_RADIUS_M,
    SITE_SPACING_M,
    SKIP_S,
    SPECTRAL_MIN_S,
    BenchConfig,
    Knob,
    default_effects,
    default_knobs,
    knob,
    lattice_sites,
    odd_nx,
    pitch_grid,
    scene_parts,
    tree,
)
from mjtouch.bench.report import plot, print_markdown, print_report
from mjtouch.bench.runner import Bench, Progress
from mjtouch.bench.timing import (
    Run,
    States,
    add_native_tactile,
    bare_model,
    slide_ctrl,
    strip_plugin,
)

__all__ = [
    "ALL_OUTPUTS",
    "DEFAULT_DENSITY",
    "EXTENT_M",
    "FMAX_HZ",
    "FMIN_HZ",
    "LEAD_IN_S",
    "MINIMAL",
    "OVERRIDE_KEYS",
    "PRESETS",
    "SITE_DEPTH_M",
    "SITE_RADIUS_M",
    "SITE_SPACING_M",
    "SKIP_S",
    "SPECTRAL_MIN_S",
    "Bench",
    "BenchConfig",
    "Knob",
    "Progress",
    "Run",
    "States",
    "Trace",
    "add_arguments",
    "add_native_tactile",
    "bare_model",
    "class_means",
    "config_from_args",
    "default_effects",
    "default_knobs",
    "errors",
    "fit_affine",
    "fit_power_law",
    "knob",
    "lattice_sites",
    "main",
    "odd_nx",
    "pareto_front",
    "pitch_grid",
    "plot",
    "print_markdown",
    "print_report",
    "scene_parts",
    "slide_ctrl",
    "strip_plugin",
    "tree",
]
