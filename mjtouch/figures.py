"""Deprecated alias of :mod:`mjtouch.analysis.figures`, kept for one release.

Import from ``mjtouch.analysis.figures``; this module re-exports its public names.
"""

from mjtouch.analysis.figures import *  # noqa: F403
