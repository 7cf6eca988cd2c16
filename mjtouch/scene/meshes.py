"""Plate textures from mesh files (trimesh): the top surface of a mesh as a
height field of exact cell means, and meshes of profiles and height maps to
export (3D-printable gratings, dot plates, knurls).

:func:`from_mesh` places the mesh (scale, which axis is up, rotation about
up), keeps the triangles that face up, and integrates their heights exactly
over each height-field cell (each triangle clipped to each cell it touches;
the integral of a linear height over the clipped polygon is its area times
the height at its centroid). A sample is therefore the mean height of the
surface over the cell centred on it, as a box filter of the mesh: no aliasing
of features finer than a cell, and a faceted mesh gives the same samples as
its exact geometry.

The skin touches a mesh's upper envelope. Where one upward triangle layer
covers a cell, its sample is that exact cell mean. Meshes made by
concatenating parts (boxes or dots on a base slab, overlapping shells,
overhangs) cover some cells more than once, with hidden faces under the
upper ones; such a cell's sample is the mean of the upper envelope (the
highest upward triangle) at ENVELOPE_SAMPLES x ENVELOPE_SAMPLES points of
the cell (a box filter to within 1 / ENVELOPE_SAMPLES of the cell per edge
crossing it). A cell no upward triangle covers whole is a hole and refused
with its position.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib

import numpy as np

from mjtouch.scene.textures import Texture

UP_AXES = ("+z", "-z", "+x", "-x", "+y", "-y")
# The skin's scale: a fingertip pad is ~20 mm across and feels reliefs from
# ~1 um (Skedung 2013) to a few mm.
FOOTPRINT_RANGE_M = (2e-3, 0.5)
RELIEF_RANGE_M = (1e-7, 5e-3)
MAX_SAMPLES = 8_000_000  # as textures.Texture
ENVELOPE_SAMPLES = 8  # points per cell side where parts overlap


@dataclasses.dataclass(frozen=True)
class MeshTexture:
    """Height map (m, >= 0) of a mesh's top surface: ``heights[r, c]`` is the
    mean height over the cell of side ``resolution_m`` centred on
    x = -length/2 + c res, y = -width/2 + r res (MuJoCo's height-field order);
    two identical rows (y = -+width/2) when the surface does not vary along y."""

    heights: np.ndarray
    length_m: float
    width_m: float
    resolution_m: float
    source: str = ""

    @property
    def relief_m(self) -> float:
        return float(self.heights.max() - self.heights.min())

    @property
    def is_profile(self) -> bool:
        return self.heights.shape[0] == 2

    def texture(self, width_m: float | None = None):
        """A :class:`mjtouch.scene.textures.Texture` of kind "mesh" over a flat proxy.
        ``width_m`` widens a profile (its rows are all equal) to any plate
        width, so a narrow crop of a long grating serves a whole pad."""
        if width_m is not None and not self.is_profile:
            raise ValueError(
                f"width_m = {width_m}: only a profile (a surface that does not "
                "vary along y) can be widened; crop the mesh instead"
            )
        return Texture(
            kind="mesh",
            mesh=self,
            length_m=self.length_m,
            width_m=width_m or self.width_m,
            resolution_m=self.resolution_m,
            height_m=self.relief_m,
        )


def _up_rotation(up: str) -> np.ndarray:
    """Rotation taking the mesh axis ``up`` to +z (right-handed)."""
    if up not in UP_AXES:
        raise ValueError(f"up = {up!r} is not one of {UP_AXES}")
    sign = 1.0 if up[0] == "+" else -1.0
    a = "xyz".index(up[1])
    if a == 2:
        return np.diag([1.0, sign, sign])  # -z: a half turn about x
    R = np.zeros((3, 3))
    R[2, a] = sign  # new z = sign * old axis a
    b = (a + 1) % 3  # new x = the next axis, new y = z cross x
    R[0, b] = 1.0
    R[1] = np.cross(R[2], R[0])
    return R


def _load(mesh) -> tuple[object, str]:
    import trimesh

    if isinstance(mesh, trimesh.Trimesh):
        return mesh, "trimesh.Trimesh"
    path = pathlib.Path(mesh)
    if not path.is_file():
        raise FileNotFoundError(f"mesh file {str(path)!r} does not exist")
    try:
        loaded = trimesh.load(str(path), force="mesh")
    except Exception as e:  # trimesh raises many types for unreadable files
        raise ValueError(f"mesh file {str(path)!r} could not be read by trimesh: {e}") from e
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"mesh file {str(path)!r} holds no triangles")
    return loaded, str(path)


def from_mesh(
    mesh,
    *,
    scale: float = 1.0,
    up: str = "+z",
    rotate_deg: float = 0.0,
    resolution_m: float = 2e-5,
    length_m: float | None = None,
    width_m: float | None = None,
) -> MeshTexture:
    """The top surface of ``mesh`` (a file trimesh reads: STL, OBJ, PLY, GLB,
    ...; or a ``trimesh.Trimesh``) as a height map of exact cell means.

    Placement: vertices times ``scale`` (1e-3 for files in mm), the mesh
    axis ``up`` turned to +z (the face the skin touches), then
    ``rotate_deg`` about z (e.g. 90 to slide along a grating's other axis).
    The map is centred on the top surface's footprint; ``length_m`` x
    ``width_m`` (default: the largest whole number of cells inside the
    footprint) crops a centred window. Heights start at 0 (the lowest point
    of the window)."""
    for k, v in (("scale", scale), ("resolution_m", resolution_m)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{k} = {v!r} must be a positive finite number")
    if not math.isfinite(rotate_deg):
        raise ValueError(f"rotate_deg = {rotate_deg!r} must be finite")
    tm, source = _load(mesh)
    v = np.asarray(tm.vertices, float)
    bad = ~np.isfinite(v).all(axis=1)
    if bad.any():
        raise ValueError(
            f"mesh {source!r} has {int(bad.sum())} non-finite vertices "
            f"(first: index {int(np.argmax(bad))}, {v[np.argmax(bad)].tolist()})"
        )
    c, s = math.cos(math.radians(rotate_deg)), math.sin(math.radians(rotate_deg))
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]) @ _up_rotation(up)
    v = scale * v @ R.T
    tri = v[np.asarray(tm.faces)]  # (nf, 3, 3)
    n_z = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2]  # 2 x projected area
    area_scale = float(np.ptp(v[:, :2], axis=0).prod()) or 1.0
    top = tri[n_z > 1e-12 * area_scale]
    if len(top) == 0:
        raise ValueError(
            f"mesh {source!r} has no top surface: no triangle faces +z after "
            f"placement (up = {up!r}); pick the axis that points out of the "
            f"textured face (one of {UP_AXES})"
        )
    lo, hi = top[:, :, :2].reshape(-1, 2).min(0), top[:, :, :2].reshape(-1, 2).max(0)
    extent = hi - lo
    relief_all = float(np.ptp(top[:, :, 2]))
    lo_f, hi_f = FOOTPRINT_RANGE_M
    if not (lo_f <= extent.min() and extent.max() <= hi_f):
        raise ValueError(
            f"mesh {source!r} top surface is {extent[0]:.3g} x {extent[1]:.3g} m after scale = "
            f"{scale:g}; valid footprint [{lo_f:g}, {hi_f:g}] m per side (a fingertip is ~0.02 m; "
            "a file in mm needs scale = 1e-3)"
        )
    if relief_all > RELIEF_RANGE_M[1]:
        raise ValueError(
            f"mesh {source!r} top surface relief is {relief_all:.3g} m after "
            f"scale = {scale:g}; valid up to {RELIEF_RANGE_M[1]:g} m (a texture, not "
            "an object: collide with objects as mesh geoms instead)"
        )
    # Whole cells inside the footprint (a cell is centred on each sample).
    ncol_max = int(math.floor(extent[0] / resolution_m + 1e-9))
    nrow_max = int(math.floor(extent[1] / resolution_m + 1e-9))
    ncol = ncol_max if length_m is None else int(round(length_m / resolution_m)) + 1
    nrow = nrow_max if width_m is None else int(round(width_m / resolution_m)) + 1
    if not (2 <= ncol <= ncol_max and 2 <= nrow <= nrow_max):
        raise ValueError(
            f"length_m x width_m = {length_m} x {width_m} m needs {ncol} x {nrow} cells of "
            f"resolution_m = {resolution_m:g}; valid: 2 to {ncol_max} x {nrow_max} (the top "
            f"surface's footprint, {extent[0]:.4g} x {extent[1]:.4g} m)"
        )
    if ncol * nrow > MAX_SAMPLES:
        raise ValueError(
            f"the height map needs {nrow} x {ncol} samples; valid up to "
            f"{MAX_SAMPLES:g} (coarsen resolution_m = {resolution_m:g} or crop)"
        )
    L, W = (ncol - 1) * resolution_m, (nrow - 1) * resolution_m
    centre = 0.5 * (lo + hi)
    # Grid units: cell (r, c) is [c, c + 1] x [r, r + 1].
    uv = (
        top[:, :, :2] - centre + [0.5 * L + 0.5 * resolution_m, 0.5 * W + 0.5 * resolution_m]
    ) / resolution_m
    integral, cover = cell_integrals(uv, top[:, :, 2], nrow, ncol)
    h = integral / np.maximum(cover, 1e-300)
    layered = cover > 1.0 + 1e-6  # hidden faces under the upper envelope
    hole = cover < 1.0 - 1e-6
    if layered.any():
        env = envelope_means(uv, top[:, :, 2], np.flatnonzero(layered), nrow, ncol)
        hole[layered] = ~np.isfinite(env)
        h[layered] = env
    if hole.any():
        r, col = np.argwhere(hole)[0]
        x, y = -L / 2 + col * resolution_m, -W / 2 + r * resolution_m
        raise ValueError(
            f"mesh {source!r} top surface has a hole: {int(hole.sum())} cells no "
            f"upward triangle covers whole, the first at x = {x:.4g}, y = {y:.4g} m "
            f"(coverage {cover[r, col]:.4g}; outside a non-rectangular top? crop "
            "with length_m / width_m)"
        )
    h -= h.min()
    relief = float(h.max())
    if relief < RELIEF_RANGE_M[0]:
        raise ValueError(
            f"mesh {source!r} top surface is flat (relief {relief:.3g} m after "
            f"scale = {scale:g}; valid from {RELIEF_RANGE_M[0]:g} m): use a flat "
            "texture"
        )
    if np.abs(h - h[0]).max() <= 1e-9 * relief:  # a profile along x: 2 rows
        h = np.stack([h.mean(0)] * 2)
    return MeshTexture(heights=h, length_m=L, width_m=W, resolution_m=resolution_m, source=source)


def _clip(
    poly: np.ndarray, count: np.ndarray, axis: int, bound: np.ndarray, keep_below: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Sutherland-Hodgman clip of each convex polygon (n, M, 2; ``count``
    vertices used) by the half-plane coordinate[axis] <= bound (or >=)."""
    n, M, _ = poly.shape
    k = np.arange(M)
    valid = k[None, :] < count[:, None]
    nxt = np.where(k[None, :] + 1 < count[:, None], k[None, :] + 1, 0)
    q = np.take_along_axis(poly, nxt[:, :, None].repeat(2, 2), axis=1)
    d0 = poly[:, :, axis] - bound[:, None]
    d1 = q[:, :, axis] - bound[:, None]
    if not keep_below:
        d0, d1 = -d0, -d1
    in0, in1 = d0 <= 0, d1 <= 0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(in0 != in1, d0 / (d0 - d1), 0.0)
    cross = poly + t[:, :, None] * (q - poly)
    emit = np.stack([in0 & valid, (in0 != in1) & valid], axis=2).reshape(n, 2 * M)
    pts = np.stack([poly, cross], axis=2).reshape(n, 2 * M, 2)
    pos = np.cumsum(emit, axis=1) - 1
    out = np.zeros((n, 2 * M, 2))
    rows = np.nonzero(emit)
    out[rows[0], pos[rows]] = pts[rows]
    return out[:, : M + 1], emit.sum(1)


def cell_integrals(
    uv: np.ndarray, z: np.ndarray, nrow: int, ncol: int, chunk: int = 400_000
) -> tuple[np.ndarray, np.ndarray]:
    """Exact integrals over each unit cell [c, c+1] x [r, r+1] of the linear
    heights of triangles (uv: (nt, 3, 2) grid units, z: (nt, 3)), and each
    cell's covered area. Cells a triangle contains whole are the plane at the
    cell centre; the others are clipped."""
    integral = np.zeros(nrow * ncol)
    cover = np.zeros(nrow * ncol)
    # plane z = a u + b v + c per triangle
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    dz1, dz2 = z[:, 1] - z[:, 0], z[:, 2] - z[:, 0]
    a = (dz1 * e2[:, 1] - dz2 * e1[:, 1]) / det
    b = (dz2 * e1[:, 0] - dz1 * e2[:, 0]) / det
    c0 = z[:, 0] - a * uv[:, 0, 0] - b * uv[:, 0, 1]
    c_lo = np.clip(np.floor(uv[:, :, 0].min(1)), 0, ncol).astype(np.int64)
    c_hi = np.clip(np.ceil(uv[:, :, 0].max(1)), 0, ncol).astype(np.int64)
    r_lo = np.clip(np.floor(uv[:, :, 1].min(1)), 0, nrow).astype(np.int64)
    r_hi = np.clip(np.ceil(uv[:, :, 1].max(1)), 0, nrow).astype(np.int64)
    nc, nr = np.maximum(c_hi - c_lo, 0), np.maximum(r_hi - r_lo, 0)
    npair = nc * nr
    # Triangles in chunks of about `chunk` (triangle, cell) pairs.
    bounds = np.searchsorted(np.cumsum(npair), np.arange(chunk, npair.sum() + chunk, chunk))
    start = 0
    for stop in np.unique(np.minimum(bounds + 1, len(uv))):
        sl = slice(start, stop)
        start = stop
        cnt = npair[sl]
        if cnt.sum() == 0:
            continue
        t = np.repeat(np.arange(sl.start, sl.stop), cnt)
        k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        col = c_lo[t] + k % nc[t]
        row = r_lo[t] + k // nc[t]
        # whole cells: the four corners inside all three edges; cells out of
        # the triangle: the four corners outside one edge (no clipping)
        inside = np.ones(len(t), bool)
        outside = np.zeros(len(t), bool)
        for i in range(3):
            A, B = uv[t, i], uv[t, (i + 1) % 3]
            out_all = np.ones(len(t), bool)
            for du, dv in ((0, 0), (1, 0), (0, 1), (1, 1)):
                side = (
                    (B[:, 0] - A[:, 0]) * (row + dv - A[:, 1])
                    - (B[:, 1] - A[:, 1]) * (col + du - A[:, 0])
                ) * det[t]
                inside &= side >= 0
                out_all &= side < 0
            outside |= out_all
        cell = row * ncol + col
        w = inside
        N = nrow * ncol
        integral += np.bincount(
            cell[w], a[t[w]] * (col[w] + 0.5) + b[t[w]] * (row[w] + 0.5) + c0[t[w]], minlength=N
        )
        cover += np.bincount(cell[w], minlength=N)
        e = ~inside & ~outside
        if not e.any():
            continue
        te, ce, re = t[e], col[e].astype(float), row[e].astype(float)
        poly = np.zeros((len(te), 8, 2))
        poly[:, :3] = uv[te]
        count = np.full(len(te), 3)
        for axis, bound, below in (
            (0, ce, False),
            (0, ce + 1, True),
            (1, re, False),
            (1, re + 1, True),
        ):
            poly, count = _clip(poly, count, axis, bound, below)
            poly = poly[:, :8]
        # shoelace area and centroid of each clipped polygon
        k8 = np.arange(8)
        nxt = np.where(k8[None, :] + 1 < count[:, None], k8[None, :] + 1, 0)
        q = np.take_along_axis(poly, nxt[:, :, None].repeat(2, 2), axis=1)
        used = k8[None, :] < count[:, None]
        cr = np.where(used, poly[:, :, 0] * q[:, :, 1] - q[:, :, 0] * poly[:, :, 1], 0.0)
        area2 = cr.sum(1)
        with np.errstate(divide="ignore", invalid="ignore"):
            cx = np.where(area2 != 0, ((poly[:, :, 0] + q[:, :, 0]) * cr).sum(1) / (3 * area2), 0)
            cy = np.where(area2 != 0, ((poly[:, :, 1] + q[:, :, 1]) * cr).sum(1) / (3 * area2), 0)
        area = np.abs(0.5 * area2)
        cell_e = cell[e]
        integral += np.bincount(cell_e, area * (a[te] * cx + b[te] * cy + c0[te]), minlength=N)
        cover += np.bincount(cell_e, area, minlength=N)
    return integral.reshape(nrow, ncol), cover.reshape(nrow, ncol)


def envelope_means(
    uv: np.ndarray,
    z: np.ndarray,
    cells: np.ndarray,
    nrow: int,
    ncol: int,
    n: int = ENVELOPE_SAMPLES,
    chunk: int = 20_000,
) -> np.ndarray:
    """Mean over each unit cell in ``cells`` (flat indices r * ncol + c) of the
    upper envelope of the triangles (uv: (nt, 3, 2) grid units, z: (nt, 3)),
    sampled at n x n points; inf where some point lies under no triangle."""
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    c_lo = np.clip(np.floor(uv[:, :, 0].min(1)), 0, ncol).astype(np.int64)
    c_hi = np.clip(np.ceil(uv[:, :, 0].max(1)), 0, ncol).astype(np.int64)
    r_lo = np.clip(np.floor(uv[:, :, 1].min(1)), 0, nrow).astype(np.int64)
    r_hi = np.clip(np.ceil(uv[:, :, 1].max(1)), 0, nrow).astype(np.int64)
    nc, nr = np.maximum(c_hi - c_lo, 0), np.maximum(r_hi - r_lo, 0)
    npair = nc * nr
    slot = np.full(nrow * ncol, -1)  # cell -> its row in `env`
    slot[cells] = np.arange(len(cells))
    env = np.full((len(cells), n * n), -np.inf)
    off = (np.arange(n) + 0.5) / n
    pu, pv = (g.ravel() for g in np.meshgrid(off, off))
    # triangles in runs of about `chunk` (triangle, cell) pairs of their boxes
    ends = np.searchsorted(np.cumsum(npair), np.arange(chunk, npair.sum() + chunk, chunk))
    start = 0
    for stop in np.unique(np.minimum(ends + 1, len(uv))):
        cnt = npair[start:stop]
        t = np.repeat(np.arange(start, stop), cnt)
        start = stop
        j = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        col = c_lo[t] + j % np.maximum(nc[t], 1)
        row = r_lo[t] + j // np.maximum(nc[t], 1)
        k = slot[row * ncol + col]
        keep = k >= 0
        t, k, col, row = t[keep], k[keep], col[keep], row[keep]
        if len(t) == 0:
            continue
        u = col[:, None] + pu[None, :] - uv[t, 0, 0, None]
        v = row[:, None] + pv[None, :] - uv[t, 0, 1, None]
        b1 = (u * e2[t, 1, None] - v * e2[t, 0, None]) / det[t, None]
        b2 = (v * e1[t, 0, None] - u * e1[t, 1, None]) / det[t, None]
        eps = 1e-9  # points on a shared edge belong to both triangles
        inside = (b1 >= -eps) & (b2 >= -eps) & (b1 + b2 <= 1 + eps)
        zz = z[t, 0, None] + b1 * (z[t, 1] - z[t, 0])[:, None] + b2 * (z[t, 2] - z[t, 0])[:, None]
        np.maximum.at(env, k, np.where(inside, zz, -np.inf))
    out = env.mean(1)
    out[~np.isfinite(env).all(1)] = np.inf
    return out


def _orient(verts: np.ndarray, faces: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """Faces flipped where their normal points against ``outward`` (per face)."""
    t = verts[faces]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    flip = (n * outward).sum(1) < 0
    faces = faces.copy()
    faces[flip] = faces[flip][:, ::-1]
    return faces


def profile_mesh(x_m: np.ndarray, z_m: np.ndarray, width_m: float, base_m: float = 1e-3):
    """A closed prism (``trimesh.Trimesh``) whose top is the polyline
    (x_m, z_m) extruded across y in [-width/2, width/2], on a base
    ``base_m`` below z = 0: a grating to export as STL. Vertical steps are
    repeated x values."""
    import trimesh

    x, z = np.asarray(x_m, float), np.asarray(z_m, float)
    hw = width_m / 2
    # the cross-section polygon: the profile, then down and back along the base
    px = np.concatenate([x, [x[-1], x[0]]])
    pz = np.concatenate([z, [-base_m, -base_m]])
    m = len(px)
    verts = np.concatenate(
        [np.stack([px, np.full(m, -hw), pz], 1), np.stack([px, np.full(m, hw), pz], 1)]
    )
    i = np.arange(m)
    j = (i + 1) % m
    faces = np.concatenate([np.stack([i, j, m + j], 1), np.stack([i, m + j, m + i], 1)])
    # outward normal of each polygon edge (the polygon's orientation from its area)
    area2 = np.sum(px * np.roll(pz, -1) - np.roll(px, -1) * pz)
    dx, dz = px[j] - px[i], pz[j] - pz[i]
    out = np.sign(area2) * np.stack([dz, np.zeros(m), -dx], 1)
    faces = _orient(verts, faces, np.concatenate([out, out]))
    # end caps: a trapezoid under each profile segment, at y = -hw and +hw
    cv, cf, co = [], [], []
    for y in (-hw, hw):
        for k in range(len(x) - 1):
            if x[k + 1] == x[k]:
                continue
            b = len(cv)
            cv += [
                [x[k], y, -base_m],
                [x[k + 1], y, -base_m],
                [x[k + 1], y, z[k + 1]],
                [x[k], y, z[k]],
            ]
            cf += [[b, b + 1, b + 2], [b, b + 2, b + 3]]
            co += [[0, np.sign(y), 0]] * 2
    cv, cf = np.array(cv), np.array(cf)
    cf = _orient(cv, cf, np.array(co, float)) + len(verts)
    return trimesh.Trimesh(np.concatenate([verts, cv]), np.concatenate([faces, cf]), process=False)


def heightmap_mesh(x_m: np.ndarray, y_m: np.ndarray, h_m: np.ndarray, base_m: float = 1e-3):
    """A closed solid (``trimesh.Trimesh``) whose top is the height map
    h_m[row(y), col(x)] (two triangles per grid square), on a base
    ``base_m`` below z = 0: dot plates, knurls or scans to export."""
    import trimesh

    x, y, h = np.asarray(x_m, float), np.asarray(y_m, float), np.asarray(h_m, float)
    ny, nx = h.shape
    X, Y = np.meshgrid(x, y)
    top = np.stack([X.ravel(), Y.ravel(), h.ravel()], 1)
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    faces = [np.stack([a, b, c], 1), np.stack([a, c, d], 1)]
    bottom = top.copy()
    bottom[:, 2] = -base_m
    off = nx * ny
    faces += [np.stack([a, c, b], 1) + off, np.stack([a, d, c], 1) + off]
    # side walls along the border
    ring = np.concatenate([idx[0, :], idx[1:, -1], idx[-1, -2::-1], idx[-2:0:-1, 0]])
    r2 = np.roll(ring, -1)
    faces += [np.stack([ring, r2 + off, r2], 1), np.stack([ring, ring + off, r2 + off], 1)]
    verts, faces = np.concatenate([top, bottom]), np.concatenate(faces)
    centre = np.array([x.mean(), y.mean(), 0.0])
    walls = len(faces) - 2 * len(ring)  # the walls point away from the centre in xy
    out = np.zeros((len(faces), 3))
    out[:walls, 2] = np.where(np.arange(walls) < 2 * len(a), 1.0, -1.0)
    out[walls:, :2] = (verts[faces[walls:]].mean(1) - centre)[:, :2]
    return trimesh.Trimesh(verts, _orient(verts, faces, out), process=False)
