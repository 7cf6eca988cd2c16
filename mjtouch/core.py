"""The C++ pipeline stages called directly, without a MuJoCo scene.

Each function validates its arguments and raises ``ValueError`` naming the
argument and its valid range. Configuration dictionaries use the same keys as
the plugin's MJCF attributes (see plugin/README.md).
"""

from __future__ import annotations

import ctypes

import numpy as np

from mjtouch import _loader

LOADS = {"pressure": 0, "shear_x": 1, "shear_y": 2}
CLASS_INDEX = {"SA1": 0, "RA": 1, "PC": 2}
STRESS_COMPONENTS = ("xx", "yy", "zz", "xy", "xz", "yz")


def _lib():
    return _loader.load()


def _ptr(a: np.ndarray, ctype):
    return a.ctypes.data_as(ctypes.POINTER(ctype))


def _config_text(config: dict | None) -> bytes:
    if not config:
        return b""
    for k, v in config.items():
        if not isinstance(k, str) or any(c in str(v) for c in ";\n="):
            raise ValueError(f"config entry {k!r}: {v!r} is not a valid attribute value")
    return ";".join(f"{k}={v}" for k, v in config.items()).encode()


def halfspace_stress(x_m, y_m, z_m, load: str = "pressure", poisson: float = 0.5,
                     cell_m: float = 0.0) -> np.ndarray:
    """Stress (Pa, Voigt order xx yy zz xy xz yz; z into the solid, tension
    positive) in a homogeneous half-space at points (x, y, z > 0) for a 1 N
    point force (cell_m = 0) or a uniform 1 Pa traction on a square cell of
    side cell_m centred at the origin. Broadcasts over the point arrays."""
    if load not in LOADS:
        raise ValueError(f"load {load!r} is not one of {sorted(LOADS)}")
    if not -1 < poisson <= 0.5:
        raise ValueError(f"poisson = {poisson} is out of range; valid range (-1, 0.5]")
    if cell_m < 0:
        raise ValueError(f"cell_m = {cell_m} must be >= 0")
    x, y, z = np.broadcast_arrays(np.asarray(x_m, float), np.asarray(y_m, float),
                                  np.asarray(z_m, float))
    if np.any(~(z > 0)):
        raise ValueError("z_m must be > 0 (points strictly below the surface)")
    out = np.empty(x.shape + (6,))
    buf = np.empty(6)
    lib = _lib()
    for idx in np.ndindex(x.shape):
        lib.mjtouch_halfspace_stress(poisson, LOADS[load], x[idx], y[idx], z[idx], cell_m,
                                     _ptr(buf, ctypes.c_double))
        out[idx] = buf
    return out


def field_stress(pressure_pa: np.ndarray, pitch_m: float, depth_m: float, receptors_ij,
                 shear_x_pa: np.ndarray | None = None, shear_y_pa: np.ndarray | None = None,
                 poisson: float = 0.5) -> np.ndarray:
    """Stress (nrec x 6, Pa) at depth under taxel cells receptors_ij (nrec x 2:
    i along x, j along y) from traction fields on an n x n grid (indexed
    [j, i]) of square cells of side pitch_m, homogeneous half-space."""
    p = np.ascontiguousarray(pressure_pa, dtype=np.float32)
    if p.ndim != 2 or p.shape[0] != p.shape[1]:
        raise ValueError(f"pressure_pa must be a square (n x n) array, got shape {p.shape}")
    n = p.shape[0]
    if not pitch_m > 0 or not depth_m > 0:
        raise ValueError("pitch_m and depth_m must be > 0")
    ij = np.ascontiguousarray(receptors_ij, dtype=np.int32).reshape(-1, 2)
    if ij.size and (ij.min() < 0 or ij.max() >= n):
        raise ValueError(f"receptor cell indices must be in [0, {n - 1}]")
    sx = sy = None
    if shear_x_pa is not None or shear_y_pa is not None:
        sx = np.ascontiguousarray(np.zeros_like(p) if shear_x_pa is None else shear_x_pa,
                                  dtype=np.float32)
        sy = np.ascontiguousarray(np.zeros_like(p) if shear_y_pa is None else shear_y_pa,
                                  dtype=np.float32)
        if sx.shape != p.shape or sy.shape != p.shape:
            raise ValueError("shear fields must have the pressure field's shape")
    ri = np.ascontiguousarray(ij[:, 0])
    rj = np.ascontiguousarray(ij[:, 1])
    out = np.empty((len(ij), 6))
    null = ctypes.POINTER(ctypes.c_float)()
    rc = _lib().mjtouch_halfspace_field_stress(
        poisson, n, pitch_m, depth_m, _ptr(p, ctypes.c_float),
        _ptr(sx, ctypes.c_float) if sx is not None else null,
        _ptr(sy, ctypes.c_float) if sy is not None else null, len(ij),
        _ptr(ri, ctypes.c_int), _ptr(rj, ctypes.c_int), _ptr(out, ctypes.c_double))
    if rc:
        raise ValueError("field_stress: invalid arguments")
    return out


def skin_surface(semi_axes_m=(0.008, 0.007, 0.007), config: dict | None = None) -> np.ndarray:
    """Cell-averaged skin height (pad frame z, m; +inf outside the pad) on the
    nx x nx taxel grid, indexed [j, i], for the ridge attributes in config."""
    a, b, c = (float(v) for v in semi_axes_m)
    lib = _lib()
    err = ctypes.create_string_buffer(512)
    text = _config_text(config)
    if lib.mjtouch_check_config(text, err, 512):
        raise ValueError(err.value.decode())
    n = int((config or {}).get("nx", 128))
    out = np.empty(n * n)
    if lib.mjtouch_skin_surface(text, a, b, c, _ptr(out, ctypes.c_double), err, 512):
        raise ValueError(err.value.decode())
    return out.reshape(n, n)


def hfield_box_mean(samples: np.ndarray, half_x_m: float, half_y_m: float, elevation_m: float,
                    x0: float, x1: float, y0: float, y1: float) -> float:
    """Exact mean of MuJoCo's bilinear height field over [x0,x1] x [y0,y1]."""
    s = np.ascontiguousarray(samples, dtype=np.float32)
    if s.ndim != 2 or min(s.shape) < 2:
        raise ValueError(f"samples must be (nrow >= 2, ncol >= 2), got {s.shape}")
    return _lib().mjtouch_hfield_box_mean(s.shape[0], s.shape[1], _ptr(s, ctypes.c_float),
                                          half_x_m, half_y_m, elevation_m, x0, x1, y0, y1)


def winkler_pressure(gap_m: np.ndarray, pitch_m: float, stiffness_pa_per_m: float,
                     force_n: float, coverage: np.ndarray | None = None):
    """Winkler pressure (Pa, n x n) whose integral equals force_n, and the
    solved approach (m)."""
    g = np.ascontiguousarray(gap_m, dtype=np.float64)
    if g.ndim != 2 or g.shape[0] != g.shape[1]:
        raise ValueError(f"gap_m must be square (n x n), got {g.shape}")
    cov = np.ones_like(g) if coverage is None else np.ascontiguousarray(coverage, np.float64)
    out = np.zeros(g.shape, np.float32)
    approach = ctypes.c_double(0)
    rc = _lib().mjtouch_winkler_pressure(g.shape[0], pitch_m, _ptr(g, ctypes.c_double),
                                         _ptr(cov, ctypes.c_double), stiffness_pa_per_m, force_n,
                                         _ptr(out, ctypes.c_float), ctypes.byref(approach))
    if rc == 2:
        raise ValueError("no cell can carry the load (all gaps infinite or force <= 0)")
    return out.astype(np.float64), approach.value


def receptor_run(cls: str, quantity_pa: np.ndarray, dt_s: float,
                 config: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Drive one receptor of class cls with the quantity trace (Pa, one value
    per step of dt_s). Returns (spikes per step, normalised voltage)."""
    if cls not in CLASS_INDEX:
        raise ValueError(f"receptor class {cls!r} is not one of {sorted(CLASS_INDEX)}")
    if not dt_s > 0:
        raise ValueError(f"dt_s = {dt_s} must be > 0")
    q = np.ascontiguousarray(quantity_pa, dtype=np.float64).ravel()
    if q.size == 0 or not np.all(np.isfinite(q)):
        raise ValueError("quantity_pa must be a non-empty finite array")
    spikes = np.empty_like(q)
    volt = np.empty_like(q)
    err = ctypes.create_string_buffer(512)
    rc = _lib().mjtouch_receptor_run(_config_text(config), CLASS_INDEX[cls], _ptr(q, ctypes.c_double),
                                     q.size, dt_s, _ptr(spikes, ctypes.c_double),
                                     _ptr(volt, ctypes.c_double), err, 512)
    if rc:
        raise ValueError(err.value.decode())
    return spikes, volt
