"""Reference solutions: analytic and independent numerical results that the
pipeline's stages are checked against (as ContactMechanics' ReferenceSolutions).

- :mod:`~mjtouch.analysis.reference_solutions.hertz`: a rigid sphere on an
  elastic half-space (Hertz 1882; Johnson, *Contact Mechanics*, 1985, sec. 4.2),
  and the errors of a computed pressure field against it.
- :mod:`~mjtouch.analysis.reference_solutions.layered`: stress under surface
  tractions on a stack of elastic layers over bone or a half-space, computed by
  a route independent of the C++ kernel (Navier equations per wavenumber,
  direct inverse Fourier integration; Burmister 1945).

``Hertz`` and ``hertz_errors`` are re-exported here (``mjtouch.oracles`` is
their deprecated alias); ``layered`` is imported by name
(``from mjtouch.analysis.reference_solutions import layered``).
"""

from mjtouch.analysis.reference_solutions.hertz import Hertz, hertz_errors

__all__ = ["Hertz", "hertz_errors"]
