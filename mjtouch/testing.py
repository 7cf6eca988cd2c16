"""Deprecated alias of :mod:`mjtouch.analysis.testing`, kept for one release.

Import from ``mjtouch.analysis.testing``; this module re-exports its public names.
"""

from mjtouch.analysis.testing import *  # noqa: F403
