"""The C++ pipeline stages called directly, without a MuJoCo scene.

Each function validates its arguments and raises ``ValueError`` naming the
argument and its valid range. Configuration dictionaries use the same keys as
the plugin's MJCF attributes (see plugin/README.md).
"""

from __future__ import annotations

import ctypes
import math
import weakref

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
                 config: dict | None = None, stream: int = 0,
                 return_rate: bool = False):
    """Drive one receptor of class cls with the quantity trace (Pa for the
    stress quantities; one value per step of dt_s), exactly as the plugin
    does: the first value primes the receptor at rest (no output), each
    further value ends a step of dt_s over which q is linear. Afferent
    parameters come from ``config`` (the plugin's attribute names); ``stream``
    is the receptor index that selects its noise sequence (a plugin
    instance's receptor r uses stream r). Returns (spikes per step,
    membrane over threshold), plus the smoothed rate (Hz) if return_rate."""
    if cls not in CLASS_INDEX:
        raise ValueError(f"receptor class {cls!r} is not one of {sorted(CLASS_INDEX)}")
    if not dt_s > 0:
        raise ValueError(f"dt_s = {dt_s} must be > 0")
    if not (isinstance(stream, (int, np.integer)) and 0 <= stream < 2**64):
        raise ValueError(f"stream = {stream!r} must be an integer in [0, 2**64)")
    q = np.ascontiguousarray(quantity_pa, dtype=np.float64).ravel()
    if q.size == 0 or not np.all(np.isfinite(q)):
        raise ValueError("quantity_pa must be a non-empty finite array")
    spikes = np.empty_like(q)
    volt = np.empty_like(q)
    rate = np.empty_like(q)
    err = ctypes.create_string_buffer(512)
    rc = _lib().mjtouch_receptor_run(_config_text(config), CLASS_INDEX[cls], _ptr(q, ctypes.c_double),
                                     q.size, dt_s, _ptr(spikes, ctypes.c_double),
                                     _ptr(volt, ctypes.c_double), _ptr(rate, ctypes.c_double),
                                     int(stream), err, 512)
    if rc:
        raise ValueError(err.value.decode())
    return (spikes, volt, rate) if return_rate else (spikes, volt)


def surface_compliance(n: int, pitch_m: float, young_pa: float, poisson: float) -> np.ndarray:
    """Homogeneous half-space surface compliance (m/Pa), (2n-1) x (2n-1),
    indexed [dj + n - 1, di + n - 1]: normal displacement at a cell's centre
    per Pa of uniform pressure on the cell offset by (di, dj)."""
    if not (young_pa > 0 and -1 < poisson <= 0.5 and pitch_m > 0 and n >= 1):
        raise ValueError("need young_pa > 0, poisson in (-1, 0.5], pitch_m > 0, n >= 1")
    out = np.empty((2 * n - 1) ** 2, np.float32)
    _lib().mjtouch_surface_compliance(young_pa, poisson, pitch_m, int(n), _ptr(out, ctypes.c_float))
    return out.reshape(2 * n - 1, 2 * n - 1).astype(np.float64)


def elastic_pressure(gap_m: np.ndarray, pitch_m: float, force_n: float,
                     young_pa: float | None = None, poisson: float | None = None,
                     periodic: bool = False, tolerance: float = 1e-8,
                     max_iterations: int = 2000, initial_pa: np.ndarray | None = None,
                     compliance_m_per_pa: np.ndarray | None = None):
    """Boundary-element contact of the skin against the rigid gap field
    (ny x nx, m; inf: cannot touch), total load force_n: a homogeneous
    half-space (young_pa, poisson), or any skin given by its surface
    compliance table ((2n - 1) x (2n - 1), m/Pa, e.g.
    LayeredSkin.compliance_table(pitch_m, n)). Non-periodic grids must be
    square; periodic sizes products of 2, 3, 5 (half-space only).
    Returns (pressure Pa, stats dict: iterations, converged, change,
    approach_m, contact_cells, max_contact_gap_m)."""
    g = np.ascontiguousarray(gap_m, dtype=np.float64)
    if g.ndim != 2:
        raise ValueError(f"gap_m must be 2D, got shape {g.shape}")
    ny, nx = g.shape
    if not periodic and nx != ny:
        raise ValueError(f"non-periodic grids must be square, got {g.shape}")
    p = (np.zeros_like(g) if initial_pa is None
         else np.ascontiguousarray(initial_pa, dtype=np.float64).copy())
    if p.shape != g.shape:
        raise ValueError("initial_pa must have gap_m's shape")
    stats = np.zeros(6)
    if compliance_m_per_pa is not None:
        if young_pa is not None or poisson is not None or periodic:
            raise ValueError("give either compliance_m_per_pa or young_pa and poisson (the "
                             "table's solver is non-periodic)")
        t = np.ascontiguousarray(compliance_m_per_pa, dtype=np.float32)
        if t.shape != (2 * nx - 1, 2 * nx - 1) or not np.all(np.isfinite(t)):
            raise ValueError(f"compliance_m_per_pa must be a finite ({2 * nx - 1}, {2 * nx - 1}) "
                             f"table for a {nx} x {nx} grid, got shape {t.shape}")
        rc = _lib().mjtouch_elastic_pressure_table(nx, pitch_m, _ptr(g, ctypes.c_double),
                                                   _ptr(t, ctypes.c_float), force_n, tolerance,
                                                   int(max_iterations), _ptr(p, ctypes.c_double),
                                                   _ptr(stats, ctypes.c_double))
    else:
        if young_pa is None or poisson is None:
            raise ValueError("give young_pa and poisson (a half-space), or compliance_m_per_pa")
        rc = _lib().mjtouch_elastic_pressure(nx, ny, pitch_m, _ptr(g, ctypes.c_double), young_pa,
                                             poisson, force_n, int(bool(periodic)), tolerance,
                                             int(max_iterations), _ptr(p, ctypes.c_double),
                                             _ptr(stats, ctypes.c_double))
    if rc == 1:
        raise ValueError("elastic_pressure: invalid arguments (pitch, young, poisson, tolerance; "
                         "periodic sizes must be products of 2, 3 and 5)")
    if rc == 2:
        raise ValueError("no cell can carry the load (all gaps infinite or force <= 0)")
    names = ("iterations", "converged", "change", "approach_m", "contact_cells",
             "max_contact_gap_m")
    info = dict(zip(names, stats))
    info["iterations"] = int(info["iterations"])
    info["converged"] = bool(info["converged"])
    info["contact_cells"] = int(info["contact_cells"])
    return p, info


# ---------------------------------------------------------------------------
# Layered elastic skin (plugin/core/substrate/layered.*) and the stress stage
# (plugin/core/stress/stress_field.*), without a MuJoCo scene.

SIDES = {None: -1, "upper": 0, "lower": 1}
STRESS_METHODS = {"auto": 0, "direct": 1, "fft": 2, "tree": 3}
TRANSFER_NAMES = ("p_xixi", "p_etaeta", "p_zz", "p_xiz", "q_xixi", "q_etaeta", "q_zz", "q_xiz",
                  "a_etaz", "a_xieta")
_layered_declared = False


def _llib():
    """The library with the layered-skin entry points declared (once)."""
    global _layered_declared
    lib = _lib()
    if not _layered_declared:
        d, f, i = ctypes.c_double, ctypes.c_float, ctypes.c_int
        dp, fp, ip = ctypes.POINTER(d), ctypes.POINTER(f), ctypes.POINTER(i)
        vp, cp = ctypes.c_void_p, ctypes.c_char_p
        lib.mjtouch_shao_fingertip.argtypes = [dp, i, ip]
        lib.mjtouch_layered_create.restype = vp
        lib.mjtouch_layered_create.argtypes = [i, dp, i, d, d, i, cp, i]
        lib.mjtouch_layered_free.argtypes = [vp]
        lib.mjtouch_layered_describe.argtypes = [vp, cp, i]
        lib.mjtouch_layered_check_depth.argtypes = [vp, d, i, cp, i]
        lib.mjtouch_layered_material.argtypes = [vp, d, i, dp]
        lib.mjtouch_layered_transfer.argtypes = [vp, d, d, i, dp]
        lib.mjtouch_layered_compliance.restype = d
        lib.mjtouch_layered_compliance.argtypes = [vp, d]
        lib.mjtouch_layered_compliance_table.argtypes = [vp, d, i, fp]
        lib.mjtouch_layered_stress.argtypes = [vp, i, i, d, d, d, d, i, dp]
        lib.mjtouch_layered_lattice_table.argtypes = [vp, d, d, i, i, fp]
        lib.mjtouch_stress_engine_create.restype = vp
        lib.mjtouch_stress_engine_create.argtypes = [vp, d, i, d, i, dp, i, ip, ip, ip, ip, i, d, cp, i]
        lib.mjtouch_stress_engine_free.argtypes = [vp]
        lib.mjtouch_stress_engine_info.argtypes = [vp, dp]
        lib.mjtouch_stress_engine_cost.argtypes = [vp, i, i, dp]
        lib.mjtouch_stress_engine_eval.argtypes = [vp, fp, fp, fp, i, i, dp, dp, ip, ip]
        _layered_declared = True
    return lib


def shao_fingertip() -> tuple[list[tuple[float, float, float]], str]:
    """The default skin (Shao et al. 2010 fingertip): layers as (thickness m,
    E Pa, nu) from the surface down, and the base ("rigid": bone)."""
    buf = np.zeros(3 * 16)
    rigid = ctypes.c_int(0)
    m = _llib().mjtouch_shao_fingertip(_ptr(buf, ctypes.c_double), 16, ctypes.byref(rigid))
    layers = [tuple(float(v) for v in buf[3 * k:3 * k + 3]) for k in range(m)]
    return layers, "rigid" if rigid.value else "halfspace"


def _side(side) -> int:
    if side not in SIDES:
        raise ValueError(f"side {side!r} is not one of None, 'upper', 'lower'")
    return SIDES[side]


class LayeredSkin:
    """A stack of welded elastic layers over a rigid base (bone) or an
    elastic half-space: the C++ ``LayeredSubstrate`` (plugin/core/substrate/layered.h).

    ``layers``: rows (thickness m, E Pa, nu) from the surface down (default:
    the Shao et al. 2010 fingertip); ``base``: ``"rigid"`` or (E Pa, nu);
    ``interface_side``: which side's stress a depth exactly on an interface
    gets (``"upper"``: the layer above). Frame and signs as
    :func:`halfspace_stress` (z into the skin, tension positive, pressure
    pushes into the skin); stresses in Voigt order xx yy zz xy xz yz. Every
    ``side`` argument defaults to ``interface_side``.
    """

    def __init__(self, layers=None, base="rigid", interface_side: str = "upper"):
        if layers is None:
            layers, _ = shao_fingertip()
        arr = np.ascontiguousarray(layers, dtype=np.float64)
        if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0:
            raise ValueError("layers must be a non-empty sequence of (thickness_m, young_pa, "
                             f"poisson) rows, got shape {arr.shape}")
        if isinstance(base, str):
            if base != "rigid":
                raise ValueError(f"base {base!r}: valid 'rigid' or (young_pa, poisson)")
            rigid, eb, nub = 1, 0.0, 0.0
        else:
            eb, nub = (float(v) for v in base)
            rigid = 0
        if interface_side not in ("upper", "lower"):
            raise ValueError(f"interface_side {interface_side!r} is not one of 'upper', 'lower'")
        err = ctypes.create_string_buffer(512)
        lib = _llib()
        h = lib.mjtouch_layered_create(arr.shape[0], _ptr(arr, ctypes.c_double), rigid, eb, nub,
                                       SIDES[interface_side], err, 512)
        if not h:
            raise ValueError(err.value.decode())
        self._h = ctypes.c_void_p(h)
        self._finalizer = weakref.finalize(self, lib.mjtouch_layered_free, self._h)
        self.layers = [tuple(float(v) for v in row) for row in arr]
        self.base = "rigid" if rigid else (eb, nub)
        self.interface_side = interface_side

    def describe(self) -> str:
        buf = ctypes.create_string_buffer(1024)
        need = _llib().mjtouch_layered_describe(self._h, buf, 1024)
        if need:
            buf = ctypes.create_string_buffer(need)
            _llib().mjtouch_layered_describe(self._h, buf, need)
        return buf.value.decode()

    def check_depth(self, z_m: float, side=None) -> None:
        """Raise ValueError if z_m is not a valid receptor depth."""
        err = ctypes.create_string_buffer(512)
        if _llib().mjtouch_layered_check_depth(self._h, float(z_m), _side(side), err, 512):
            raise ValueError(err.value.decode())

    def material(self, z_m: float, side=None) -> tuple[float, float]:
        """(E Pa, nu) of the layer at depth z_m."""
        out = np.zeros(2)
        _llib().mjtouch_layered_material(self._h, float(z_m), _side(side),
                                         _ptr(out, ctypes.c_double))
        return float(out[0]), float(out[1])

    def transfer(self, k_per_m, z_m: float, side=None) -> dict[str, np.ndarray]:
        """Point-force transfer functions at wavenumbers k >= 0 and depth z_m
        (layered.h LayerTransfer; names as there), each an array like k."""
        self.check_depth(z_m, side)
        k = np.atleast_1d(np.asarray(k_per_m, dtype=float))
        if np.any(~(k >= 0)):
            raise ValueError("k_per_m must be >= 0")
        out = np.empty((k.size, 10))
        buf = np.empty(10)
        lib = _llib()
        for i, kk in enumerate(k):
            lib.mjtouch_layered_transfer(self._h, kk, float(z_m), _side(side),
                                         _ptr(buf, ctypes.c_double))
            out[i] = buf
        return {name: out[:, c].reshape(np.shape(k_per_m)) for c, name in enumerate(TRANSFER_NAMES)}

    def compliance(self, k_per_m) -> np.ndarray:
        """Fourier surface compliance u_z / p (m/Pa) at wavenumbers k > 0
        (k = 0: the finite part, layered.h SurfaceCompliance)."""
        k = np.asarray(k_per_m, dtype=float)
        if np.any(~(k >= 0)):
            raise ValueError("k_per_m must be >= 0")
        f = np.vectorize(lambda kk: _llib().mjtouch_layered_compliance(self._h, float(kk)))
        return f(k).astype(float)

    def compliance_table(self, pitch_m: float, n: int) -> np.ndarray:
        """Surface normal displacement (m per Pa) at the centre of a cell from
        unit pressure on a cell (di, dj) away, as a (2n-1, 2n-1) array indexed
        [dj + n - 1, di + n - 1]."""
        if not pitch_m > 0 or not 1 <= n <= 1024:
            raise ValueError("need pitch_m > 0 and 1 <= n <= 1024")
        L = 2 * n - 1
        out = np.empty(L * L, np.float32)
        _llib().mjtouch_layered_compliance_table(self._h, pitch_m, n, _ptr(out, ctypes.c_float))
        return out.reshape(L, L).astype(np.float64)

    def _stress(self, kind, load, x_m, y_m, z_m, size_m, side):
        if load not in LOADS:
            raise ValueError(f"load {load!r} is not one of {sorted(LOADS)}")
        x, y, z = np.broadcast_arrays(np.asarray(x_m, float), np.asarray(y_m, float),
                                      np.asarray(z_m, float))
        out = np.empty(x.shape + (6,))
        buf = np.empty(6)
        lib = _llib()
        for idx in np.ndindex(x.shape):
            self.check_depth(z[idx], side)
            rc = lib.mjtouch_layered_stress(self._h, kind, LOADS[load], x[idx], y[idx], z[idx],
                                            size_m, _side(side), _ptr(buf, ctypes.c_double))
            if rc:
                raise ValueError("invalid arguments (size_m must be > 0)")
            out[idx] = buf
        return out

    def point_stress(self, x_m, y_m, z_m, load: str = "pressure", side=None) -> np.ndarray:
        """Stress (Pa) at points from a 1 N point force at the origin."""
        return self._stress(0, load, x_m, y_m, z_m, 0.0, side)

    def cell_stress(self, x_m, y_m, z_m, pitch_m: float, load: str = "pressure",
                    side=None) -> np.ndarray:
        """Stress (Pa) at points from a unit (1 Pa) traction on a square cell
        of side pitch_m centred at the origin."""
        return self._stress(1, load, x_m, y_m, z_m, float(pitch_m), side)

    def disc_stress(self, x_m, y_m, z_m, radius_m: float, load: str = "pressure",
                    side=None) -> np.ndarray:
        """Stress (Pa) at points from a unit traction on a disc at the origin."""
        return self._stress(2, load, x_m, y_m, z_m, float(radius_m), side)

    def lattice_table(self, z_m: float, pitch_m: float, n: int, side=None) -> np.ndarray:
        """The plugin's kernel table at depth z_m: (3 loads, 6 components,
        2n-1, 2n-1), entry [load, comp, dj + n - 1, di + n - 1] = stress under
        the centre of cell (i, j) from unit traction on cell (i + di, j + dj)."""
        self.check_depth(z_m, side)
        if not pitch_m > 0 or not 1 <= n <= 512:
            raise ValueError("need pitch_m > 0 and 1 <= n <= 512")
        L = 2 * n - 1
        out = np.empty(3 * 6 * L * L, np.float32)
        rc = _llib().mjtouch_layered_lattice_table(self._h, z_m, pitch_m, n, _side(side),
                                                   _ptr(out, ctypes.c_float))
        if rc:
            raise ValueError("lattice_table: invalid arguments")
        return out.reshape(3, 6, L, L).astype(np.float64)

    def field_stress(self, pressure_pa: np.ndarray, pitch_m: float, depth_m: float,
                     receptors_ij, shear_x_pa: np.ndarray | None = None,
                     shear_y_pa: np.ndarray | None = None, method: str = "auto") -> np.ndarray:
        """Stress (nrec x 6, Pa) at depth_m under taxel cells receptors_ij
        (nrec x 2: i along x, j along y) from traction fields on an n x n grid
        ([j, i]) of square cells of side pitch_m: the plugin's stress stage
        (direct summation or FFT convolution, ``method``)."""
        engine = StressEngine(self, np.shape(pressure_pa)[0], pitch_m, [depth_m], receptors_ij,
                              method="fft" if method == "fft" else "auto")
        return engine.stress(pressure_pa, shear_x_pa, shear_y_pa, method=method)


class StressEngine:
    """The plugin's per-step stress stage for an n x n grid: lattice tables
    (and FFT spectra) at the given depths, and receptor sites (cell i, j;
    depth index; wanted components). ``skin``: a :class:`LayeredSkin`, or a
    float Poisson's ratio for a homogeneous half-space. ``method`` at creation:
    ``"auto"`` builds FFT spectra where the FFT path can win (as the plugin
    with stress_method="auto"), ``"direct"`` never, ``"fft"`` always,
    ``"tree"`` builds the hierarchical path with opening angle ``theta``
    (the plugin's default, stress_method="tree")."""

    def __init__(self, skin, n: int, pitch_m: float, depths_m, receptors_ij, depth_index=None,
                 components=None, method: str = "auto", theta: float = 0.5):
        if method not in STRESS_METHODS:
            raise ValueError(f"method {method!r} is not one of {sorted(STRESS_METHODS)}")
        if isinstance(skin, LayeredSkin):
            handle, poisson = skin._h, 0.0
        else:
            handle, poisson = None, float(skin)
        depths = np.ascontiguousarray(np.atleast_1d(depths_m), dtype=np.float64)
        ij = np.ascontiguousarray(receptors_ij, dtype=np.int32).reshape(-1, 2)
        nrec = len(ij)
        di = np.zeros(nrec, np.int32) if depth_index is None else np.ascontiguousarray(
            depth_index, dtype=np.int32)
        if di.shape != (nrec,):
            raise ValueError("depth_index must have one entry per receptor")
        # components: None (all six), one list for every site, or one list per site.
        comps = [range(6)] * nrec if components is None else list(components)
        if not comps or np.ndim(comps[0]) == 0:
            comps = [comps] * nrec
        if len(comps) != nrec or any(not 0 <= int(c) < 6 for cc in comps for c in cc):
            raise ValueError("components: indices in [0, 6), for all sites or one list per site")
        mask = np.array([sum(1 << int(c) for c in set(cc)) for cc in comps], np.int32)
        ri, rj = np.ascontiguousarray(ij[:, 0]), np.ascontiguousarray(ij[:, 1])
        err = ctypes.create_string_buffer(512)
        lib = _llib()
        h = lib.mjtouch_stress_engine_create(
            handle, poisson, int(n), float(pitch_m), depths.size, _ptr(depths, ctypes.c_double),
            nrec, _ptr(ri, ctypes.c_int), _ptr(rj, ctypes.c_int), _ptr(di, ctypes.c_int),
            _ptr(mask, ctypes.c_int), STRESS_METHODS[method], float(theta), err, 512)
        if not h:
            raise ValueError(err.value.decode())
        self._skin = skin  # keeps the substrate alive
        self._h = ctypes.c_void_p(h)
        self._finalizer = weakref.finalize(self, lib.mjtouch_stress_engine_free, self._h)
        self.n = int(n)
        self.nrec = nrec
        info = np.zeros(6)
        lib.mjtouch_stress_engine_info(self._h, _ptr(info, ctypes.c_double))
        self.table_build_s, self.spectra_build_s = float(info[0]), float(info[1])
        self.fft_n = int(info[2])
        self.table_bytes_per_depth = int(info[3])
        self.tree_build_s, self.tree_terms_per_site = float(info[4]), float(info[5])

    def estimated_cost(self, active_cells: int, shear: bool = True) -> tuple[float, float]:
        """The cost model's (direct, fft) seconds per call."""
        out = np.zeros(2)
        _llib().mjtouch_stress_engine_cost(self._h, int(active_cells), int(shear),
                                           _ptr(out, ctypes.c_double))
        return float(out[0]), float(out[1])

    def stress(self, pressure_pa, shear_x_pa=None, shear_y_pa=None, method: str = "auto",
               repeats: int = 1, timing: bool = False):
        """Stress (nrec x 6, Pa). With timing=True also returns (seconds per
        call, method used, active cells)."""
        if method not in STRESS_METHODS:
            raise ValueError(f"method {method!r} is not one of {sorted(STRESS_METHODS)}")
        p = np.ascontiguousarray(pressure_pa, dtype=np.float32)
        if p.shape != (self.n, self.n):
            raise ValueError(f"pressure_pa must have shape ({self.n}, {self.n}), got {p.shape}")
        fp = ctypes.POINTER(ctypes.c_float)
        sx = sy = None
        if shear_x_pa is not None or shear_y_pa is not None:
            sx = np.ascontiguousarray(np.zeros_like(p) if shear_x_pa is None else shear_x_pa,
                                      dtype=np.float32)
            sy = np.ascontiguousarray(np.zeros_like(p) if shear_y_pa is None else shear_y_pa,
                                      dtype=np.float32)
            if sx.shape != p.shape or sy.shape != p.shape:
                raise ValueError("shear fields must have the pressure field's shape")
        out = np.empty((self.nrec, 6))
        sec = ctypes.c_double(0)
        used = ctypes.c_int(0)
        active = ctypes.c_int(0)
        rc = _llib().mjtouch_stress_engine_eval(
            self._h, _ptr(p, ctypes.c_float), _ptr(sx, ctypes.c_float) if sx is not None else fp(),
            _ptr(sy, ctypes.c_float) if sy is not None else fp(), STRESS_METHODS[method],
            int(repeats), _ptr(out, ctypes.c_double), ctypes.byref(sec), ctypes.byref(used),
            ctypes.byref(active))
        if rc == 2:
            raise ValueError("method 'fft' needs FFT spectra: create the engine with method='fft'")
        if rc == 3:
            raise ValueError("method 'tree' needs the tree: create the engine with method='tree'")
        if rc:
            raise ValueError("stress: invalid arguments")
        if timing:
            name = {1: "direct", 2: "fft", 3: "tree"}[used.value]
            return out, sec.value, name, active.value
        return out


SURFACE_TYPES = ("plane", "rectangle", "hfield", "sphere", "ellipsoid", "capsule", "cylinder")
PAD_SHAPES = ("sphere", "ellipsoid", "capsule", "box")
RIDGE_PROFILES = ("sine", "triangle", "square")


def render_gap(skin_z_m: np.ndarray, pitch_m: float, surfaces: list[dict],
               pad_pos=(0.0, 0.0, 0.0), pad_mat=np.eye(3), hfield: np.ndarray | None = None,
               area_average: bool = True):
    """Stage 1: gap (m; inf where no surface) and coverage of each taxel cell
    of a skin (skin_z_m: n x n pad-frame heights) at the pad pose, against
    counter-surfaces given as dicts: type (one of SURFACE_TYPES), pos (3),
    mat (3 x 3, local -> world), size (3, MuJoCo geom size), half (2: face
    half sizes of a rectangle / height field), elevation (height field, m).
    Height-field surfaces read `hfield` (nrow x ncol samples in [0, 1]).
    area_average=False samples cell centres (point sampling)."""
    z = np.ascontiguousarray(skin_z_m, dtype=np.float64)
    if z.ndim != 2 or z.shape[0] != z.shape[1]:
        raise ValueError(f"skin_z_m must be square (n x n), got {z.shape}")
    desc = np.zeros((len(surfaces), 20))
    for k, s in enumerate(surfaces):
        if s.get("type") not in SURFACE_TYPES:
            raise ValueError(f"surface {k}: type {s.get('type')!r} is not one of {SURFACE_TYPES}")
        desc[k, 0] = SURFACE_TYPES.index(s["type"])
        desc[k, 1:4] = s.get("pos", (0, 0, 0))
        desc[k, 4:13] = np.asarray(s.get("mat", np.eye(3)), float).ravel()
        desc[k, 13:16] = s.get("size", (0, 0, 0))
        desc[k, 16:18] = s.get("half", (0, 0))
        desc[k, 18] = s.get("elevation", 0.0)
        desc[k, 19] = s.get("elevation", 0.0) * (1.0 if hfield is None else float(np.max(hfield)))
    hf = np.ascontiguousarray(np.zeros((2, 2)) if hfield is None else hfield, dtype=np.float32)
    n = z.shape[0]
    gap = np.empty_like(z)
    cov = np.empty_like(z)
    pos = np.ascontiguousarray(pad_pos, dtype=np.float64)
    mat = np.ascontiguousarray(pad_mat, dtype=np.float64).ravel()
    rc = _lib().mjtouch_render_gap(n, pitch_m, _ptr(z, ctypes.c_double), _ptr(pos, ctypes.c_double),
                                   _ptr(mat, ctypes.c_double), len(surfaces),
                                   _ptr(desc, ctypes.c_double), hf.shape[0], hf.shape[1],
                                   _ptr(hf, ctypes.c_float), int(bool(area_average)),
                                   _ptr(gap, ctypes.c_double), _ptr(cov, ctypes.c_double))
    if rc:
        raise ValueError("render_gap: invalid arguments (pitch_m > 0; height fields need "
                         "hfield with at least 2 x 2 samples)")
    return gap, cov


def ridge_cell_mean(s_m, profile: str = "sine", pitch_m: float = 0.45e-3,
                    height_m: float = 0.05e-3, angle_deg: float = 0.0,
                    cell_m: float = 0.0) -> np.ndarray:
    """Ridge relief (m, protrusion positive) at distance s_m along the ridge
    normal, averaged exactly over a square taxel cell of side cell_m (0: the
    point value)."""
    if profile not in RIDGE_PROFILES:
        raise ValueError(f"profile {profile!r} is not one of {RIDGE_PROFILES}")
    lib = _lib()
    s = np.asarray(s_m, float)
    out = np.array([lib.mjtouch_ridge_cell_mean(RIDGE_PROFILES.index(profile), pitch_m, height_m,
                                                math.radians(angle_deg), v, cell_m)
                    for v in s.ravel()])
    return out.reshape(s.shape)


def pad_surface(shape: str, half_extents_m, n: int, pitch_m: float, profile: str = "sine",
                ridge_pitch_m: float = 0.45e-3, ridge_height_m: float = 0.0,
                ridge_angle_deg: float = 0.0) -> np.ndarray:
    """Cell-averaged skin height (pad frame z, m; inf outside the pad), n x n
    indexed [j, i], for a pad shape in PAD_SHAPES with half extents (x, y, z)
    (capsule: r, r, r + half length); ridge_height_m = 0: smooth skin."""
    if shape not in PAD_SHAPES:
        raise ValueError(f"shape {shape!r} is not one of {PAD_SHAPES}")
    if profile not in RIDGE_PROFILES:
        raise ValueError(f"profile {profile!r} is not one of {RIDGE_PROFILES}")
    a, b, c = (float(v) for v in half_extents_m)
    out = np.empty(n * n)
    rc = _lib().mjtouch_pad_surface(int(n), pitch_m, PAD_SHAPES.index(shape), a, b, c,
                                    RIDGE_PROFILES.index(profile), ridge_pitch_m, ridge_height_m,
                                    math.radians(ridge_angle_deg), _ptr(out, ctypes.c_double))
    if rc:
        raise ValueError("pad_surface: need n >= 1, pitch_m > 0 and positive half extents")
    return out.reshape(n, n)


def slip_shear(pressure_pa: np.ndarray, pitch_m: float, normal_n: float, tangential_n):
    """Full-slip shear traction (qx, qy in Pa) for a pressure field and the
    contact's normal and tangential (x, y) force."""
    p = np.ascontiguousarray(pressure_pa, dtype=np.float64)
    qx, qy = np.empty_like(p), np.empty_like(p)
    _lib().mjtouch_slip_shear(p.shape[0], pitch_m, _ptr(p, ctypes.c_double), normal_n,
                              float(tangential_n[0]), float(tangential_n[1]),
                              _ptr(qx, ctypes.c_double), _ptr(qy, ctypes.c_double))
    return qx, qy


def splat_contacts(contacts, n: int, pitch_m: float):
    """`contacts` model: rows (x, y, fx, fy, fz) in the pad frame (m, N)
    spread onto the n x n grid. Returns (pressure, qx, qy) in Pa."""
    c = np.ascontiguousarray(contacts, dtype=np.float64).reshape(-1, 5)
    p, qx, qy = (np.empty((n, n)) for _ in range(3))
    rc = _lib().mjtouch_splat_contacts(int(n), pitch_m, len(c), _ptr(c, ctypes.c_double),
                                       _ptr(p, ctypes.c_double), _ptr(qx, ctypes.c_double),
                                       _ptr(qy, ctypes.c_double))
    if rc == 1:
        raise ValueError("splat_contacts: need n >= 2 and pitch_m > 0")
    return p, qx, qy
