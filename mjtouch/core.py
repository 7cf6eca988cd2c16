"""The C++ pipeline stages called directly, without a MuJoCo scene.

Thin wrappers over the compiled extension ``mjtouch._core`` (nanobind, built
from plugin/python/ with the stage libraries of plugin/core): array
arguments go to C++ whole (no per-point Python loops), and every error a
stage reports, naming the argument and its valid range, is raised as
``ValueError`` with the stage's message. Configuration dictionaries use the
same keys as the plugin's MJCF attributes (see plugin/README.md).
"""

from __future__ import annotations

import math

import numpy as np

from mjtouch._loader import PluginNotBuiltError

try:
    from mjtouch import _core
except ImportError as e:  # the compiled part is missing or stale
    raise PluginNotBuiltError(
        f"mjtouch's compiled module mjtouch._core could not be imported ({e}). Was the package "
        "built? Run `pip install .` (or `pip install -e .`) from the mjtouch source tree."
    ) from e

LOADS = {"pressure": 0, "shear_x": 1, "shear_y": 2}
CLASS_INDEX = {"SA1": 0, "RA": 1, "PC": 2}
STRESS_COMPONENTS = ("xx", "yy", "zz", "xy", "xz", "yz")


def _config(config: dict | None) -> dict[str, str]:
    """Plugin attributes as strings, as MJCF gives them to the plugin."""
    out = {}
    for k, v in (config or {}).items():
        if not isinstance(k, str):
            raise ValueError(f"config entry {k!r}: {v!r} is not a valid attribute value")
        out[k] = str(v).strip()
    return out


def _points(x_m, y_m, z_m) -> tuple[tuple[int, ...], np.ndarray]:
    """Broadcast coordinates to (npoint, 3) points and the broadcast shape."""
    x, y, z = np.broadcast_arrays(
        np.asarray(x_m, float), np.asarray(y_m, float), np.asarray(z_m, float)
    )
    return x.shape, np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


def _square(a: np.ndarray, name: str) -> None:
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a square (n x n) array, got shape {a.shape}")


def _shear_pair(p: np.ndarray, shear_x_pa, shear_y_pa):
    """Both shear fields (float32; a missing one is zero) or (None, None)."""
    if shear_x_pa is None and shear_y_pa is None:
        return None, None
    sx = np.zeros_like(p) if shear_x_pa is None else np.ascontiguousarray(shear_x_pa, np.float32)
    sy = np.zeros_like(p) if shear_y_pa is None else np.ascontiguousarray(shear_y_pa, np.float32)
    if sx.shape != p.shape or sy.shape != p.shape:
        raise ValueError("shear fields must have the pressure field's shape")
    return sx, sy


def halfspace_stress(
    x_m, y_m, z_m, load: str = "pressure", poisson: float = 0.5, cell_m: float = 0.0
) -> np.ndarray:
    """Stress (Pa, Voigt order xx yy zz xy xz yz; z into the solid, tension
    positive) in a homogeneous half-space at points (x, y, z > 0) for a 1 N
    point force (cell_m = 0) or a uniform 1 Pa traction on a square cell of
    side cell_m centred at the origin. Broadcasts over the point arrays."""
    shape, pts = _points(x_m, y_m, z_m)
    return _core.halfspace_stress(pts, load, float(poisson), float(cell_m)).reshape(shape + (6,))


def field_stress(
    pressure_pa: np.ndarray,
    pitch_m: float,
    depth_m: float,
    receptors_ij,
    shear_x_pa: np.ndarray | None = None,
    shear_y_pa: np.ndarray | None = None,
    poisson: float = 0.5,
) -> np.ndarray:
    """Stress (nrec x 6, Pa) at depth under taxel cells receptors_ij (nrec x 2:
    i along x, j along y) from traction fields on an n x n grid (indexed
    [j, i]) of square cells of side pitch_m, homogeneous half-space."""
    p = np.ascontiguousarray(pressure_pa, dtype=np.float32)
    _square(p, "pressure_pa")
    ij = np.ascontiguousarray(receptors_ij, dtype=np.int32).reshape(-1, 2)
    sx, sy = _shear_pair(p, shear_x_pa, shear_y_pa)
    return _core.field_stress(p, float(pitch_m), float(depth_m), ij, sx, sy, float(poisson))


def skin_surface(semi_axes_m=(0.008, 0.007, 0.007), config: dict | None = None) -> np.ndarray:
    """Cell-averaged skin height (pad frame z, m; +inf outside the pad) on the
    nx x nx taxel grid, indexed [j, i], for the ridge attributes in config."""
    return _core.skin_surface(tuple(float(v) for v in semi_axes_m), _config(config))


def hfield_box_mean(
    samples: np.ndarray,
    half_x_m: float,
    half_y_m: float,
    elevation_m: float,
    x0: float,
    x1: float,
    y0: float,
    y1: float,
) -> float:
    """Exact mean of MuJoCo's bilinear height field over [x0,x1] x [y0,y1]."""
    s = np.ascontiguousarray(samples, dtype=np.float32)
    if s.ndim != 2:
        raise ValueError(f"samples must be (nrow >= 2, ncol >= 2), got {s.shape}")
    box = np.array([[x0, x1, y0, y1]], dtype=np.float64)
    return float(_core.hfield_box_mean(s, half_x_m, half_y_m, elevation_m, box)[0])


def winkler_pressure(
    gap_m: np.ndarray,
    pitch_m: float,
    stiffness_pa_per_m: float,
    force_n: float,
    coverage: np.ndarray | None = None,
    approach_guess_m: float = math.nan,
    reference: bool = False,
):
    """Winkler pressure (Pa, n x n) whose integral equals force_n, and the
    solved approach (m). approach_guess_m warm-starts the solve as the plugin
    does from its last step; reference=True runs the unoptimised solve (the
    fast one must match it bit for bit)."""
    g = np.ascontiguousarray(gap_m, dtype=np.float64)
    _square(g, "gap_m")
    cov = np.ones_like(g) if coverage is None else np.ascontiguousarray(coverage, np.float64)
    p, approach = _core.winkler_pressure(
        g,
        cov,
        float(pitch_m),
        float(stiffness_pa_per_m),
        float(force_n),
        float(approach_guess_m),
        bool(reference),
    )
    return p.astype(np.float64), approach


def receptor_run(
    cls: str,
    quantity_pa: np.ndarray,
    dt_s: float,
    config: dict | None = None,
    stream: int = 0,
    return_rate: bool = False,
):
    """Drive one receptor of class cls with the quantity trace (Pa for the
    stress quantities; one value per step of dt_s), exactly as the plugin
    does: the first value primes the receptor at rest (no output), each
    further value ends a step of dt_s over which q is linear. Afferent
    parameters come from ``config`` (the plugin's attribute names); ``stream``
    is the receptor index that selects its noise sequence (a plugin
    instance's receptor r uses stream r). Returns (spikes per step,
    membrane over threshold), plus the smoothed rate (Hz) if return_rate."""
    if not (isinstance(stream, (int, np.integer)) and 0 <= stream < 2**64):
        raise ValueError(f"stream = {stream!r} must be an integer in [0, 2**64)")
    q = np.ascontiguousarray(quantity_pa, dtype=np.float64).ravel()
    spikes, volt, rate = _core.receptor_run(cls, q, float(dt_s), _config(config), int(stream))
    return (spikes, volt, rate) if return_rate else (spikes, volt)


def surface_compliance(n: int, pitch_m: float, young_pa: float, poisson: float) -> np.ndarray:
    """Homogeneous half-space surface compliance (m/Pa), (2n-1) x (2n-1),
    indexed [dj + n - 1, di + n - 1]: normal displacement at a cell's centre
    per Pa of uniform pressure on the cell offset by (di, dj)."""
    return _core.surface_compliance(int(n), float(pitch_m), float(young_pa), float(poisson)).astype(
        np.float64
    )


def elastic_pressure(
    gap_m: np.ndarray,
    pitch_m: float,
    force_n: float,
    young_pa: float | None = None,
    poisson: float | None = None,
    periodic: bool = False,
    tolerance: float = 1e-8,
    max_iterations: int = 2000,
    initial_pa: np.ndarray | None = None,
    compliance_m_per_pa: np.ndarray | None = None,
    method: str = "pcg",
    precision: str = "double",
):
    """Boundary-element contact of the skin against the rigid gap field
    (ny x nx, m; inf: cannot touch), total load force_n: a homogeneous
    half-space (young_pa, poisson), or any skin given by its surface
    compliance table ((2n - 1) x (2n - 1), m/Pa, e.g.
    LayeredSkin.compliance_table(pitch_m, n)). Non-periodic grids must be
    square; periodic sizes products of 2, 3, 5 (half-space only).
    ``method``: ``"pcg"`` (preconditioned CG, the plugin's) or ``"pk"``
    (Polonsky & Keer's plain CG, the reference path). ``precision``: of the
    operator's FFTs, ``"double"`` (the reference) or ``"float"`` (the
    plugin's default, attribute ``elastic_precision``). Returns (pressure Pa,
    stats dict: iterations, converged, change, approach_m, contact_cells,
    max_contact_gap_m, fft_applies: operator applications by FFT, the cost)."""
    g = np.ascontiguousarray(gap_m, dtype=np.float64)
    if g.ndim != 2:
        raise ValueError(f"gap_m must be 2D, got shape {g.shape}")
    p0 = np.zeros_like(g) if initial_pa is None else np.ascontiguousarray(initial_pa, np.float64)
    if compliance_m_per_pa is not None:
        if young_pa is not None or poisson is not None or periodic:
            raise ValueError(
                "give either compliance_m_per_pa or young_pa and poisson (the "
                "table's solver is non-periodic)"
            )
        t = np.ascontiguousarray(compliance_m_per_pa, dtype=np.float32)
        return _core.elastic_pressure_table(
            g,
            p0,
            float(pitch_m),
            float(force_n),
            t,
            float(tolerance),
            int(max_iterations),
            method,
            precision,
        )
    if young_pa is None or poisson is None:
        raise ValueError("give young_pa and poisson (a half-space), or compliance_m_per_pa")
    return _core.elastic_pressure(
        g,
        p0,
        float(pitch_m),
        float(force_n),
        float(young_pa),
        float(poisson),
        bool(periodic),
        float(tolerance),
        int(max_iterations),
        method,
        precision,
    )


# ---------------------------------------------------------------------------
# Layered elastic skin (plugin/core/substrate/layered.*) and the stress stage
# (plugin/core/stress/stress_field.*), without a MuJoCo scene.

SIDES = {None: -1, "upper": 0, "lower": 1}
STRESS_METHODS = {"auto": 0, "direct": 1, "fft": 2, "tree": 3}
TRANSFER_NAMES = (
    "p_xixi",
    "p_etaeta",
    "p_zz",
    "p_xiz",
    "q_xixi",
    "q_etaeta",
    "q_zz",
    "q_xiz",
    "a_etaz",
    "a_xieta",
)


def shao_fingertip() -> tuple[list[tuple[float, float, float]], str]:
    """The default skin (Shao et al. 2010 fingertip): layers as (thickness m,
    E Pa, nu) from the surface down, and the base ("rigid": bone)."""
    layers, rigid = _core.shao_fingertip()
    return list(layers), "rigid" if rigid else "halfspace"


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
        if arr.ndim != 2:
            raise ValueError(
                "layers must be a non-empty sequence of (thickness_m, young_pa, "
                f"poisson) rows, got shape {arr.shape}"
            )
        if isinstance(base, str):
            if base != "rigid":
                raise ValueError(f"base {base!r}: valid 'rigid' or (young_pa, poisson)")
            rigid, eb, nub = True, 0.0, 0.0
        else:
            eb, nub = (float(v) for v in base)
            rigid = False
        self._s = _core.LayeredSubstrate.create(arr, rigid, eb, nub, interface_side)
        self.layers = [tuple(float(v) for v in row) for row in arr]
        self.base = "rigid" if rigid else (eb, nub)
        self.interface_side = interface_side

    def describe(self) -> str:
        return self._s.describe()

    def check_depth(self, z_m: float, side=None) -> None:
        """Raise ValueError if z_m is not a valid receptor depth."""
        self._s.check_depth(float(z_m), side)

    def material(self, z_m: float, side=None) -> tuple[float, float]:
        """(E Pa, nu) of the layer at depth z_m."""
        return self._s.material(float(z_m), side)

    def transfer(self, k_per_m, z_m: float, side=None) -> dict[str, np.ndarray]:
        """Point-force transfer functions at wavenumbers k >= 0 and depth z_m
        (layered.h LayerTransfer; names as there), each an array like k."""
        k = np.asarray(k_per_m, dtype=float)
        out = self._s.transfer(np.ascontiguousarray(k.ravel()), float(z_m), side)
        return {name: out[:, c].reshape(k.shape) for c, name in enumerate(TRANSFER_NAMES)}

    def compliance(self, k_per_m) -> np.ndarray:
        """Fourier surface compliance u_z / p (m/Pa) at wavenumbers k > 0
        (k = 0: the finite part, layered.h SurfaceCompliance)."""
        k = np.asarray(k_per_m, dtype=float)
        return self._s.compliance(np.ascontiguousarray(k.ravel())).reshape(k.shape)

    def compliance_table(self, pitch_m: float, n: int) -> np.ndarray:
        """Surface normal displacement (m per Pa) at the centre of a cell from
        unit pressure on a cell (di, dj) away, as a (2n-1, 2n-1) array indexed
        [dj + n - 1, di + n - 1]."""
        return self._s.compliance_table(float(pitch_m), int(n)).astype(np.float64)

    def _stress(self, kind, load, x_m, y_m, z_m, size_m, side):
        shape, pts = _points(x_m, y_m, z_m)
        return self._s.stress(kind, load, pts, size_m, side).reshape(shape + (6,))

    def point_stress(self, x_m, y_m, z_m, load: str = "pressure", side=None) -> np.ndarray:
        """Stress (Pa) at points from a 1 N point force at the origin."""
        return self._stress("point", load, x_m, y_m, z_m, 0.0, side)

    def cell_stress(
        self, x_m, y_m, z_m, pitch_m: float, load: str = "pressure", side=None
    ) -> np.ndarray:
        """Stress (Pa) at points from a unit (1 Pa) traction on a square cell
        of side pitch_m centred at the origin."""
        return self._stress("cell", load, x_m, y_m, z_m, float(pitch_m), side)

    def disc_stress(
        self, x_m, y_m, z_m, radius_m: float, load: str = "pressure", side=None
    ) -> np.ndarray:
        """Stress (Pa) at points from a unit traction on a disc at the origin."""
        return self._stress("disc", load, x_m, y_m, z_m, float(radius_m), side)

    def lattice_table(self, z_m: float, pitch_m: float, n: int, side=None) -> np.ndarray:
        """The plugin's kernel table at depth z_m: (3 loads, 6 components,
        2n-1, 2n-1), entry [load, comp, dj + n - 1, di + n - 1] = stress under
        the centre of cell (i, j) from unit traction on cell (i + di, j + dj)."""
        return self._s.lattice_table(float(z_m), float(pitch_m), int(n), side).astype(np.float64)

    def field_stress(
        self,
        pressure_pa: np.ndarray,
        pitch_m: float,
        depth_m: float,
        receptors_ij,
        shear_x_pa: np.ndarray | None = None,
        shear_y_pa: np.ndarray | None = None,
        method: str = "auto",
    ) -> np.ndarray:
        """Stress (nrec x 6, Pa) at depth_m under taxel cells receptors_ij
        (nrec x 2: i along x, j along y) from traction fields on an n x n grid
        ([j, i]) of square cells of side pitch_m: the plugin's stress stage
        (direct summation or FFT convolution, ``method``)."""
        engine = StressEngine(
            self,
            np.shape(pressure_pa)[0],
            pitch_m,
            [depth_m],
            receptors_ij,
            method="fft" if method == "fft" else "auto",
        )
        return engine.stress(pressure_pa, shear_x_pa, shear_y_pa, method=method)


class StressEngine:
    """The plugin's per-step stress stage for an n x n grid: lattice tables
    (and FFT spectra) at the given depths, and receptor sites (cell i, j;
    depth index; wanted components). ``skin``: a :class:`LayeredSkin`, or a
    float Poisson's ratio for a homogeneous half-space. ``method`` at creation:
    ``"auto"`` builds FFT spectra where the FFT path can win (as the plugin
    with stress_method="auto"), ``"direct"`` never, ``"fft"`` always,
    ``"tree"`` builds the hierarchical path with opening angle ``theta``
    (the plugin with stress_method="tree")."""

    def __init__(
        self,
        skin,
        n: int,
        pitch_m: float,
        depths_m,
        receptors_ij,
        depth_index=None,
        components=None,
        method: str = "auto",
        theta: float = 0.5,
    ):
        layered, poisson = (skin._s, 0.0) if isinstance(skin, LayeredSkin) else (None, float(skin))
        depths = np.ascontiguousarray(np.atleast_1d(depths_m), dtype=np.float64)
        ij = np.ascontiguousarray(receptors_ij, dtype=np.int32).reshape(-1, 2)
        nrec = len(ij)
        di = (
            np.zeros(nrec, np.int32)
            if depth_index is None
            else np.ascontiguousarray(depth_index, dtype=np.int32)
        )
        if di.shape != (nrec,):
            raise ValueError("depth_index must have one entry per receptor")
        # components: None (all six), one list for every site, or one list per site.
        comps = [range(6)] * nrec if components is None else list(components)
        if not comps or np.ndim(comps[0]) == 0:
            comps = [comps] * nrec
        if len(comps) != nrec or any(not 0 <= int(c) < 6 for cc in comps for c in cc):
            raise ValueError("components: indices in [0, 6), for all sites or one list per site")
        mask = np.array([sum(1 << int(c) for c in set(cc)) for cc in comps], np.int32)
        self._skin = skin
        self._e = _core.StressEngine(
            layered, poisson, int(n), float(pitch_m), depths, ij, di, mask, method, float(theta)
        )
        self.n = self._e.n
        self.nrec = self._e.nrec
        self.mirror_symmetric = self._e.mirror_symmetric
        self.table_build_s, self.spectra_build_s = self._e.table_build_s, self._e.spectra_build_s
        self.fft_n = self._e.fft_n
        self.table_bytes_per_depth = self._e.table_bytes_per_depth
        self.tree_build_s, self.tree_terms_per_site = (
            self._e.tree_build_s,
            self._e.tree_terms_per_site,
        )

    def estimated_cost(
        self, active_cells: int, shear: bool = True, folded: bool | None = None
    ) -> tuple[float, float]:
        """The cost model's (direct, fft) seconds per call. folded: whether the
        direct path is the folded one (default: as stress() without slip, i.e.
        folded when there is no shear)."""
        folded = (not shear) if folded is None else bool(folded)
        return self._e.estimated_cost(int(active_cells), bool(shear), folded)

    def stress(
        self,
        pressure_pa,
        shear_x_pa=None,
        shear_y_pa=None,
        method: str = "auto",
        repeats: int = 1,
        timing: bool = False,
        slip=None,
        fold: bool = True,
        threads: int = 1,
        fold_legacy: bool = False,
        split: bool = False,
    ):
        """Stress (nrec x 6, Pa). With timing=True also returns (seconds per
        call, method used, active cells). slip = (rx, ry): the shear is
        (rx, ry) x pressure (full slip, as the plugin's winkler and elastic
        models), so the direct path folds its tables (shear fields default to
        float32(r x pressure)); fold=False: the reference direct sum.
        threads: the stage's thread count (the same bits for any count).
        fold_legacy: the folded path's memory layout before #13 (unaligned
        table loads; the same bits), for benchmarks. split=True (with slip
        and any shear fields): partial slip's path, the pressure folded at
        slip plus the coarse correction of shear - slip x pressure."""
        p = np.ascontiguousarray(pressure_pa, dtype=np.float32)
        if split and (slip is None or shear_x_pa is None or shear_y_pa is None):
            raise ValueError("split=True needs slip and both shear fields")
        if p.shape != (self.n, self.n):
            raise ValueError(f"pressure_pa must have shape ({self.n}, {self.n}), got {p.shape}")
        if slip is not None:
            rx, ry = (float(v) for v in slip)
            slip = (rx, ry)
            if shear_x_pa is None and shear_y_pa is None:
                shear_x_pa = (rx * p.astype(np.float64)).astype(np.float32)
                shear_y_pa = (ry * p.astype(np.float64)).astype(np.float32)
        sx, sy = _shear_pair(p, shear_x_pa, shear_y_pa)
        out, seconds, used, active = self._e.stress(
            p,
            sx,
            sy,
            method,
            int(repeats),
            slip,
            bool(fold),
            int(threads),
            bool(fold_legacy),
            bool(split),
        )
        return (out, seconds, used, active) if timing else out


SURFACE_TYPES = ("plane", "rectangle", "hfield", "sphere", "ellipsoid", "capsule", "cylinder")
PAD_SHAPES = ("sphere", "ellipsoid", "capsule", "box")
RIDGE_PROFILES = ("sine", "triangle", "square")


def render_gap(
    skin_z_m: np.ndarray,
    pitch_m: float,
    surfaces: list[dict],
    pad_pos=(0.0, 0.0, 0.0),
    pad_mat=None,
    hfield: np.ndarray | None = None,
    area_average: bool = True,
    fast_paths: bool = True,
):
    """Stage 1: gap (m; inf where no surface) and coverage of each taxel cell
    of a skin (skin_z_m: n x n pad-frame heights) at the pad pose, against
    counter-surfaces given as dicts: type (one of SURFACE_TYPES), pos (3),
    mat (3 x 3, local -> world), size (3, MuJoCo geom size), half (2: face
    half sizes of a rectangle / height field), elevation (height field, m).
    Height-field surfaces read `hfield` (nrow x ncol samples in [0, 1]).
    area_average=False samples cell centres (point sampling). fast_paths=False
    renders with the general per-cell code only (the fast paths must match it
    bit for bit)."""
    z = np.ascontiguousarray(skin_z_m, dtype=np.float64)
    _square(z, "skin_z_m")
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
    pos = tuple(float(v) for v in np.ravel(pad_pos))
    mat = tuple(float(v) for v in np.ravel(np.eye(3) if pad_mat is None else pad_mat))
    return _core.render_gap(
        z, float(pitch_m), desc, pos, mat, hf, bool(area_average), bool(fast_paths)
    )


def ridge_cell_mean(
    s_m,
    profile: str = "sine",
    pitch_m: float = 0.45e-3,
    height_m: float = 0.05e-3,
    angle_deg: float = 0.0,
    cell_m: float = 0.0,
) -> np.ndarray:
    """Ridge relief (m, protrusion positive) at distance s_m along the ridge
    normal, averaged exactly over a square taxel cell of side cell_m (0: the
    point value)."""
    s = np.asarray(s_m, float)
    out = _core.ridge_cell_mean(
        np.ascontiguousarray(s.ravel()),
        profile,
        float(pitch_m),
        float(height_m),
        math.radians(angle_deg),
        float(cell_m),
    )
    return out.reshape(s.shape)


def pad_surface(
    shape: str,
    half_extents_m,
    n: int,
    pitch_m: float,
    profile: str = "sine",
    ridge_pitch_m: float = 0.45e-3,
    ridge_height_m: float = 0.0,
    ridge_angle_deg: float = 0.0,
) -> np.ndarray:
    """Cell-averaged skin height (pad frame z, m; inf outside the pad), n x n
    indexed [j, i], for a pad shape in PAD_SHAPES with half extents (x, y, z)
    (capsule: r, r, r + half length); ridge_height_m = 0: smooth skin."""
    return _core.pad_surface(
        shape,
        tuple(float(v) for v in half_extents_m),
        int(n),
        float(pitch_m),
        profile,
        float(ridge_pitch_m),
        float(ridge_height_m),
        math.radians(ridge_angle_deg),
    )


def slip_shear(pressure_pa: np.ndarray, pitch_m: float, normal_n: float, tangential_n):
    """Full-slip shear traction (qx, qy in Pa) for a pressure field and the
    contact's normal and tangential (x, y) force."""
    p = np.ascontiguousarray(pressure_pa, dtype=np.float64)
    _square(p, "pressure_pa")
    return _core.slip_shear(
        p, float(pitch_m), float(normal_n), float(tangential_n[0]), float(tangential_n[1])
    )


def splat_contacts(contacts, n: int, pitch_m: float):
    """`contacts` model: rows (x, y, fx, fy, fz) in the pad frame (m, N)
    spread onto the n x n grid. Returns (pressure, qx, qy) in Pa."""
    c = np.ascontiguousarray(contacts, dtype=np.float64).reshape(-1, 5)
    return _core.splat_contacts(c, int(n), float(pitch_m))
