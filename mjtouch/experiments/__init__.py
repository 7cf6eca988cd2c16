"""Experiments: each one a dataclass of parameters and a function that runs it.

- :mod:`mjtouch.experiments.slide`    ``SlideParams`` and ``run_slide``: a ridged
  fingertip pressed on a textured plate and slid
- :mod:`mjtouch.experiments.rollout`  running a sliding scene, collecting spikes and stress
- :mod:`mjtouch.experiments.stimuli`  probes and vibrating plates (physiology stimuli)
- :mod:`mjtouch.experiments.tuning`   threshold-frequency and rate-intensity curves
- :mod:`mjtouch.experiments.slip_ramp` ``SlipRampParams`` and ``run``: a tangential ramp
  on a pressed fingertip past the friction limit (partial slip, afferents, gross slip)
- :mod:`mjtouch.experiments.sweep`    the product of several ``SlideParams`` values, on Ray
"""
