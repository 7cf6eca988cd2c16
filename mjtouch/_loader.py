"""Locates and loads the compiled plugin library (libmjtouch.so).

Loading the library registers the ``mjtouch.skin`` MuJoCo plugin (its
constructor calls ``mjp_registerPlugin``). Nothing else is called through
ctypes: the stages and live plugin instances are reached through the
extension ``mjtouch._core`` (see mjtouch.core). This module must not import
``mujoco``: ``import mujoco`` calls :func:`register` through the
``mujoco.plugins`` entry point while it is still initialising.
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import importlib.util
import os
import pathlib

_LIB_NAME = "libmjtouch.so"
_handle: ctypes.CDLL | None = None


class PluginNotBuiltError(ImportError):
    """The compiled part of mjtouch is missing."""


def _candidates() -> list[pathlib.Path]:
    found = []
    env = os.environ.get("MJTOUCH_PLUGIN_PATH")
    if env:
        found.append(pathlib.Path(env))
    # Installed (and editable) distributions list the library in their RECORD;
    # in an editable install it is not next to this file.
    try:
        for f in importlib.metadata.files("mjtouch") or []:
            if f.name == _LIB_NAME:
                found.append(pathlib.Path(f.locate()))
    except importlib.metadata.PackageNotFoundError:
        pass
    found.append(pathlib.Path(__file__).with_name(_LIB_NAME))
    return found


def library_path() -> pathlib.Path:
    for path in _candidates():
        if path.is_file():
            return path.resolve()
    raise PluginNotBuiltError(
        "mjtouch's compiled plugin (libmjtouch.so) was not found. Was the package built? "
        "Run `pip install .` (or `pip install -e .`) from the mjtouch source tree; "
        "or set MJTOUCH_PLUGIN_PATH to the library."
    )


def _preload_mujoco() -> None:
    # libmjtouch.so links libmujoco by its soname; make sure the copy inside
    # the installed mujoco package is the one resolved, without importing it.
    spec = importlib.util.find_spec("mujoco")
    if spec is None or not spec.submodule_search_locations:
        raise ImportError("mjtouch needs the mujoco package (pip install mujoco==4.0.0)")
    root = pathlib.Path(list(spec.submodule_search_locations)[0])
    libs = sorted(root.glob("libmujoco.so.*"))
    if libs:
        ctypes.CDLL(str(libs[0]), mode=ctypes.RTLD_GLOBAL)


def loaded_path() -> str:
    """Path of the plugin library as loaded (loads it if needed)."""
    return load()._name


def load() -> ctypes.CDLL:
    """Load the plugin library once and return its handle (ctypes.CDLL)."""
    global _handle
    if _handle is None:
        path = library_path()
        _preload_mujoco()
        lib = ctypes.CDLL(str(path))
        _check_versions(lib)
        _handle = lib
    return _handle


def _check_versions(lib: ctypes.CDLL) -> None:
    built = lib.mjtouch_built_mujoco_version()
    try:
        installed = importlib.metadata.version("mujoco")
    except importlib.metadata.PackageNotFoundError:
        installed = "?"
    parts = installed.split(".")
    try:
        running = int(parts[0]) * 1000000 + int(parts[1]) * 1000 + int(parts[2])  # mjVERSION_HEADER
    except (ValueError, IndexError):
        running = -1
    if running != built:
        raise PluginNotBuiltError(
            f"mjtouch's plugin was compiled against MuJoCo {built // 1000000}."
            f"{built // 1000 % 1000}.{built % 1000} but mujoco {installed} is installed; reinstall mjtouch "
            "(pip install .) or install the matching mujoco."
        )


def register() -> None:
    """Entry point for ``mujoco.plugins``: registers ``mjtouch.skin``."""
    load()
