"""Deprecated alias of :mod:`mjtouch.analysis.reference_solutions`, kept for one release.

Import from ``mjtouch.analysis.reference_solutions``; this module re-exports its public names.
"""

from mjtouch.analysis.reference_solutions import *  # noqa: F403
