"""Locates and loads the compiled plugin library (libmjtouch.so).

Loading the library registers the ``mjtouch.skin`` MuJoCo plugin (its
constructor calls ``mjp_registerPlugin``). This module must not import
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


def load() -> ctypes.CDLL:
    """Load the plugin library once and return its handle."""
    global _handle
    if _handle is None:
        path = library_path()
        _preload_mujoco()
        lib = ctypes.CDLL(str(path))
        _declare(lib)
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


def _declare(lib: ctypes.CDLL) -> None:
    c_double_p = ctypes.POINTER(ctypes.c_double)
    c_float_p = ctypes.POINTER(ctypes.c_float)
    c_int_p = ctypes.POINTER(ctypes.c_int)
    lib.mjtouch_abi_version.restype = ctypes.c_int
    lib.mjtouch_built_mujoco_version.restype = ctypes.c_int
    lib.mjtouch_halfspace_stress.argtypes = [ctypes.c_double, ctypes.c_int] + [ctypes.c_double] * 4 + [c_double_p]
    lib.mjtouch_halfspace_field_stress.argtypes = [
        ctypes.c_double, ctypes.c_int, ctypes.c_double, ctypes.c_double,
        c_float_p, c_float_p, c_float_p, ctypes.c_int, c_int_p, c_int_p, c_double_p]
    lib.mjtouch_skin_surface.argtypes = [ctypes.c_char_p] + [ctypes.c_double] * 3 + [
        c_double_p, ctypes.c_char_p, ctypes.c_int]
    lib.mjtouch_hfield_box_mean.restype = ctypes.c_double
    lib.mjtouch_hfield_box_mean.argtypes = [ctypes.c_int, ctypes.c_int, c_float_p] + [ctypes.c_double] * 7
    lib.mjtouch_winkler_pressure.argtypes = [
        ctypes.c_int, ctypes.c_double, c_double_p, c_double_p, ctypes.c_double, ctypes.c_double,
        c_float_p, c_double_p]
    lib.mjtouch_receptor_run.argtypes = [
        ctypes.c_char_p, ctypes.c_int, c_double_p, ctypes.c_int, ctypes.c_double, c_double_p,
        c_double_p, c_double_p, ctypes.c_ulonglong, ctypes.c_char_p, ctypes.c_int]
    lib.mjtouch_check_config.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_int]
    lib.mjtouch_surface_compliance.argtypes = [ctypes.c_double] * 3 + [ctypes.c_int, c_float_p]
    lib.mjtouch_elastic_pressure.argtypes = [
        ctypes.c_int, ctypes.c_int, ctypes.c_double, c_double_p, ctypes.c_double, ctypes.c_double,
        ctypes.c_double, ctypes.c_int, ctypes.c_double, ctypes.c_int, c_double_p, c_double_p]
    lib.mjtouch_elastic_pressure_table.argtypes = [
        ctypes.c_int, ctypes.c_double, c_double_p, c_float_p, ctypes.c_double, ctypes.c_double,
        ctypes.c_int, c_double_p, c_double_p]
    lib.mjtouch_render_gap.argtypes = [
        ctypes.c_int, ctypes.c_double, c_double_p, c_double_p, c_double_p, ctypes.c_int, c_double_p,
        ctypes.c_int, ctypes.c_int, c_float_p, ctypes.c_int, c_double_p, c_double_p]
    lib.mjtouch_ridge_cell_mean.restype = ctypes.c_double
    lib.mjtouch_ridge_cell_mean.argtypes = [ctypes.c_int] + [ctypes.c_double] * 5
    lib.mjtouch_pad_surface.argtypes = [ctypes.c_int, ctypes.c_double, ctypes.c_int] + [
        ctypes.c_double] * 3 + [ctypes.c_int] + [ctypes.c_double] * 3 + [c_double_p]
    lib.mjtouch_slip_shear.argtypes = [ctypes.c_int, ctypes.c_double, c_double_p] + [
        ctypes.c_double] * 3 + [c_double_p, c_double_p]
    lib.mjtouch_splat_contacts.argtypes = [ctypes.c_int, ctypes.c_double, ctypes.c_int,
                                           c_double_p, c_double_p, c_double_p, c_double_p]
    lib.mjtouch_describe.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_int]
    lib.mjtouch_last_evaluation.argtypes = [ctypes.c_void_p, ctypes.c_int, c_double_p]
