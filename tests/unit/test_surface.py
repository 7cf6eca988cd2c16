"""Stage 1's fast path (surface.cc RenderAlignedFace: planes, rectangles and
height fields whose axes are the pad's; gratings rendered per column) against
the general per-cell code (render_gap fast_paths=False), which it must match
bit for bit, in every case the dispatch meets: aligned and rotated pads, 1D
and 2D textures, texture edges inside the grid, and mixed with the analytic
bodies that always take the general path."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from mjtouch import _core, core
from mjtouch.scene import textures

N, PITCH = 48, 1e-4
SEMI = (8e-3, 7e-3, 7e-3)
HALF = (2.0e-3, 1.5e-3)  # texture half sizes: edges fall inside a 4.8 mm grid
RES = 2.5e-5  # texture sample spacing


def _rot(yaw_deg=0.0, tilt_deg=0.0):
    a, b = math.radians(yaw_deg), math.radians(tilt_deg)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    ry = np.array([[math.cos(b), 0, math.sin(b)], [0, 1, 0], [-math.sin(b), 0, math.cos(b)]])
    return rz @ ry


def _samples(kind):
    x, y = textures.grid(2 * HALF[0], 2 * HALF[1], RES)
    if kind == "grating":
        row = textures.grating(x, 1e-3, 0.5e-3, 1.0, edge_m=0.1e-3)
        return np.tile(row, (len(y), 1)).astype(np.float32)
    if kind == "dots":
        h = textures.dots(x, y, 0.6e-3, 0.25e-3, 0.1e-3)
    else:
        h = textures.random_rough(len(y), len(x), RES, 1e-5, corr_length_m=1e-4, seed=3)
    return ((h - h.min()) / (h.max() - h.min())).astype(np.float32)


def _render(surfaces, samples, pad_pos, pad_mat, ridges=True):
    z = core.pad_surface("ellipsoid", SEMI, N, PITCH, ridge_height_m=5e-5 if ridges else 0.0)
    kw = dict(pad_pos=pad_pos, pad_mat=pad_mat, hfield=samples)
    fast = core.render_gap(z, PITCH, surfaces, **kw)
    ref = core.render_gap(z, PITCH, surfaces, fast_paths=False, **kw)
    return fast, ref


def _assert_bit_identical(fast, ref, what):
    for a, b, name in zip(fast, ref, ("gap", "coverage")):
        assert a.tobytes() == b.tobytes(), (
            f"{what}: {name} differs from the general path in {np.sum(a != b)} cells, "
            f"max {np.nanmax(np.abs(np.where(a == b, 0, a - b)))}"
        )


def _texture(elevation=1e-4):
    return dict(type="hfield", half=HALF, elevation=elevation)


PLATE = dict(type="rectangle", half=(4e-3, 3e-3))  # the plate's top face under the texture

POSES = {
    "aligned": (0.0, 0.0),
    "aligned, yaw 180 deg": (180.0, 0.0),  # R = diag(-1, -1, 1): still the fast path
    "yaw 30 deg": (30.0, 0.0),
    "tilt 4 deg": (0.0, 4.0),
}


@pytest.mark.parametrize("pose", POSES)
@pytest.mark.parametrize("kind", ["grating", "dots", "random"])
@pytest.mark.parametrize("x_m", [0.0, 1.1e-3, -1.9e-3])  # texture edge off / inside the grid
def test_face_fast_path_matches_general(kind, pose, x_m):
    samples = _samples(kind)
    mat = _rot(*POSES[pose])
    if pose == "aligned, yaw 180 deg":
        mat = np.diag([-1.0, -1.0, 1.0])  # exact, as MuJoCo gives for a half turn
    pos = (x_m, 0.3e-3, SEMI[2] + 2e-5)  # pole 20 um below the texture's top
    fast, ref = _render([PLATE, _texture()], samples, pos, mat)
    _assert_bit_identical(fast, ref, f"{kind}, {pose}, x = {x_m}")
    gap, cov = fast
    touched = (cov > 0) & np.isfinite(gap)
    assert touched.sum() > 100, "the pad must face the surfaces for the comparison to bite"
    # The texture is seen: its relief makes the gap of covered cells vary by
    # more than the smooth pad shape alone would near the pole.
    assert np.ptp(gap[touched]) > 1e-5


def test_aligned_plane_and_rectangle_edges():
    # A plane and a rectangle whose edge cuts through the grid (partial coverage).
    for surfaces in ([dict(type="plane")], [dict(type="rectangle", half=(1.0e-3, 0.6e-3))]):
        fast, ref = _render(surfaces, None, (0.35e-3, 0.0, SEMI[2] + 1e-5), np.eye(3))
        _assert_bit_identical(fast, ref, surfaces[0]["type"])
        cov = fast[1]
        if surfaces[0]["type"] == "rectangle":
            assert np.any((cov > 0) & (cov < 1)), "the rectangle's edge must cut some cells"


@pytest.mark.parametrize(
    "body",
    [
        dict(type="sphere", pos=(0.4e-3, 0, -3e-3 + 5e-5), size=(3e-3, 0, 0)),
        dict(type="capsule", pos=(0, 0, -1e-3 + 4e-5), size=(1e-3, 2e-3, 0), mat=_rot(0, 90)),
        dict(type="rectangle", pos=(0, 0, 3e-5), half=(0.5e-3, 0.5e-3)),  # a box's top face
    ],
)
def test_bodies_mixed_with_a_grating(body):
    # Analytic bodies take the general path, the grating the fast one; the
    # nearest surface per cell (first one on ties) must be the same.
    fast, ref = _render(
        [PLATE, _texture(), body], _samples("grating"), (0.0, 0.0, SEMI[2] + 2e-5), np.eye(3)
    )
    _assert_bit_identical(fast, ref, body["type"])


def test_grating_column_means_are_the_exact_cell_integrals():
    # A flat skin at height z0 over a grating: every covered cell's gap is
    # z0 minus the exact mean of the bilinear texture over the cell
    # (hfield_box_mean, computed independently per cell).
    samples = _samples("grating")
    z0 = 2e-5
    z = np.full((N, N), z0)
    gap, cov = core.render_gap(z, PITCH, [_texture()], hfield=samples)
    c = (np.arange(N) - 0.5 * (N - 1)) * PITCH
    X, Y = np.meshgrid(c, c)
    x0 = np.maximum(X - PITCH / 2, -HALF[0])
    x1 = np.minimum(X + PITCH / 2, HALF[0])
    y0 = np.maximum(Y - PITCH / 2, -HALF[1])
    y1 = np.minimum(Y + PITCH / 2, HALF[1])
    inside = cov > 0
    boxes = np.stack([x0[inside], x1[inside], y0[inside], y1[inside]], axis=1)
    mean = _core.hfield_box_mean(samples, HALF[0], HALF[1], 1e-4, boxes)
    np.testing.assert_allclose(gap[inside], z0 - mean, rtol=0, atol=1e-15)
    assert np.ptp(mean) > 5e-5  # crests and grooves both under the grid


def _plate_and_texture_rows(n: int) -> np.ndarray:
    """n rows of ComputeTraction's surface table: the plate's 8 x 6 mm top
    face (type 1, kRectangle) and the texture's height field on it (type 2,
    kHeightField, 0.1 mm samples); rows from 2 on are the caller's."""
    surfaces = np.zeros((n, 20))
    surfaces[0, 0], surfaces[0, 4:13], surfaces[0, 16:18] = 1, np.eye(3).ravel(), (4e-3, 3e-3)
    surfaces[1, 0], surfaces[1, 4:13], surfaces[1, 16:18] = 2, np.eye(3).ravel(), HALF
    surfaces[1, 18] = surfaces[1, 19] = 1e-4
    return surfaces


def _reference_and_fast_fields(pressure, pos, mat, forces, surfaces, samples):
    """Stages 1-2 over the steps by the reference and the fast paths (ridged
    skin, all fields): (reference, fast) traction_steps outputs."""
    config = {
        "nx": str(N),
        "pitch": str(PITCH),
        "ridges": "true",
        "ridge_height": "5e-05",
        "pressure": pressure,
    }
    ref = _core.traction_steps(
        list(SEMI), config, pos, mat, forces, surfaces, samples, reference=True, fields=True
    )
    fast = _core.traction_steps(
        list(SEMI), config, pos, mat, forces, surfaces, samples, fields=True
    )
    return ref, fast


@pytest.mark.parametrize("yaw_deg", [0.0, 20.0])
def test_stages_1_2_fast_paths_match_reference_over_a_slide(yaw_deg):
    # The plugin's stages 1-2 (ComputeTraction: culled render, warm-started
    # Winkler solve, re-render when the cull was too tight, shear) over a
    # pad sliding 0.6 mm across a grating on a plate, with a varying force.
    # Fast and reference paths must give the same pressure and approach at
    # every step, and the pressure must carry the force (sum p A = F).
    T = 40
    samples = _samples("grating")
    surfaces = _plate_and_texture_rows(2)
    pos = np.zeros((T, 3))
    pos[:, 0] = np.linspace(0.0, 0.6e-3, T)
    pos[:, 2] = SEMI[2] + 5e-5
    mat = np.tile(_rot(yaw_deg).ravel(), (T, 1))
    forces = np.zeros((T, 3))
    forces[:, 0] = 0.3 + 0.2 * np.sin(np.linspace(0, 3, T))
    forces[:, 1] = 0.1
    config = {"nx": str(N), "pitch": str(PITCH), "ridges": "true", "ridge_height": "5e-05"}
    ref = _core.traction_steps(
        list(SEMI), config, pos, mat, forces, surfaces, samples, reference=True, fields=True
    )
    fast = _core.traction_steps(
        list(SEMI), config, pos, mat, forces, surfaces, samples, fields=True
    )
    approach_ref, approach_fast = ref[2], fast[2]
    assert np.all(np.isfinite(approach_ref)), "the pad must touch at every step"
    assert approach_fast.tobytes() == approach_ref.tobytes()
    # every field stage 3 reads: pressure, shear (double and float), active cells
    assert fast[3].tobytes() == ref[3].tobytes()
    p_ref = ref[3][:, 0]
    assert_allclose(p_ref.sum(axis=(1, 2)) * PITCH**2, forces[:, 0], rtol=1e-9)
    assert_allclose(ref[3][:, 1].sum(axis=(1, 2)) * PITCH**2, forces[:, 1], rtol=1e-9)
    assert np.array_equal(ref[3][:, 6] > 0, p_ref != 0)  # active cells: the loaded ones


@pytest.mark.parametrize("pressure", ["winkler", "elastic"])
@pytest.mark.parametrize("yaw_deg", [0.0, 20.0])
def test_stages_1_2_fields_over_lost_and_regained_contact(yaw_deg, pressure):
    # The fast Winkler + shear path writes each step's field over the last
    # one, clearing only what the new contact leaves, and the render writes
    # over the last gap where one surface reaches (both models): over load
    # jumps (the
    # warm start left of the root, the cull too tight), steps without force
    # and steps with the pad moved off the plate, every field stage 3
    # reads must still equal the reference path's (which clears the grid
    # first), and where no cell is over a surface the step reports no contact.
    T = 40
    samples = _samples("grating")
    surfaces = _plate_and_texture_rows(2)
    pos = np.zeros((T, 3))
    pos[:, 0] = np.linspace(-0.3e-3, 0.6e-3, T)
    pos[:, 2] = SEMI[2] + 5e-5
    pos[30:35, 0] = 20e-3  # off the plate: no cell over a surface
    mat = np.tile(_rot(yaw_deg).ravel(), (T, 1))
    forces = np.zeros((T, 3))
    forces[:, 0] = np.where(np.arange(T) % 7 < 3, 0.15, 0.6)  # jumps both ways
    forces[10:15, 0] = 0.0  # no contact force
    forces[:, 1], forces[:, 2] = -0.08, 0.05
    ref, fast = _reference_and_fast_fields(pressure, pos, mat, forces, surfaces, samples)
    touching = np.isfinite(ref[2])
    assert not touching[10:15].any() and not touching[30:35].any()
    assert touching[:10].all() and touching[15:30].all() and touching[35:].all()
    assert fast[2].tobytes() == ref[2].tobytes()
    assert fast[3].tobytes() == ref[3].tobytes()
    p_ref = ref[3][:, 0]
    assert_allclose(p_ref[touching].sum(axis=(1, 2)) * PITCH**2, forces[touching, 0], rtol=1e-9)


@pytest.mark.parametrize("pressure", ["winkler", "elastic"])
def test_stages_1_2_texture_shifted_on_a_plate_and_one_parked(pressure):
    # TextureExplore's scene: a plate wider than the grid, a texture on a
    # mocap body in the plate's plane but shifted along it (the grating's
    # phase), covering the contact, and a second texture parked far beside
    # the pad, in the same plane, whose blocks the render skips (no cell's
    # footprint overlaps it). Every field stage 3 reads must equal the
    # reference path's, and the pressure must carry the force.
    T = 30
    samples = _samples("grating")
    surfaces = np.zeros((3, 20))
    surfaces[0, 0], surfaces[0, 4:13], surfaces[0, 16:18] = 1, np.eye(3).ravel(), (20e-3, 10e-3)
    for k, y_m in ((1, 0.0), (2, 0.5)):
        surfaces[k, 0], surfaces[k, 4:13], surfaces[k, 16:18] = 2, np.eye(3).ravel(), (8e-3, 6e-3)
        surfaces[k, 1:4] = (0.37e-3, y_m, 0.0)
        surfaces[k, 18] = surfaces[k, 19] = 1e-4
    pos = np.zeros((T, 3))
    pos[:, 0] = np.linspace(-0.3e-3, 0.6e-3, T)
    pos[:, 2] = SEMI[2] + 5e-5
    mat = np.tile(np.eye(3).ravel(), (T, 1))
    forces = np.zeros((T, 3))
    forces[:, 0] = 0.3 + 0.2 * np.sin(np.linspace(0, 3, T))
    forces[:, 1] = 0.05
    ref, fast = _reference_and_fast_fields(pressure, pos, mat, forces, surfaces, samples)
    assert np.all(np.isfinite(ref[2])), "the pad must touch at every step"
    assert fast[2].tobytes() == ref[2].tobytes()
    assert fast[3].tobytes() == ref[3].tobytes()
    assert_allclose(ref[3][:, 0].sum(axis=(1, 2)) * PITCH**2, forces[:, 0], rtol=1e-9)


@pytest.mark.parametrize("pressure", ["winkler", "elastic"])
def test_stages_1_2_fields_when_a_second_body_comes_within_reach(pressure):
    # While the texture alone reaches the skin, the render overwrites its
    # rectangle and clears only the rest of the last result's box; when the
    # load drops that box shrinks, and when a bump then comes within reach
    # (two surfaces: the last box is cleared first and each cell keeps the
    # lower gap) no stale gap may survive: every field must equal the
    # reference path's (which clears the grid every step).
    T = 40
    samples = _samples("grating")
    surfaces = _plate_and_texture_rows(3)
    # a sphere 2.4 mm right of the texture's centre, its top 0.27 mm up: off
    # the grid while the pad is left, under the skin's flank once it is right
    surfaces[2, 0], surfaces[2, 4:13], surfaces[2, 13] = 3, np.eye(3).ravel(), 0.3e-3
    surfaces[2, 1:4] = (2.4e-3, 0.0, 0.27e-3 - 0.3e-3)
    pos = np.zeros((T, 3))
    pos[:, 0] = np.linspace(-1.0e-3, 1.0e-3, T)
    pos[:, 2] = SEMI[2] + 5e-5
    mat = np.tile(np.eye(3).ravel(), (T, 1))
    forces = np.zeros((T, 3))
    forces[:, 0] = 2.0
    forces[[5, 12, 13, 14, 27], 0] = 0.02  # the contact shrinks (the bump reaches from step 15 on)
    forces[:, 1] = 0.05
    ref, fast = _reference_and_fast_fields(pressure, pos, mat, forces, surfaces, samples)
    assert np.isfinite(ref[2]).all()
    assert fast[2].tobytes() == ref[2].tobytes()
    assert fast[3].tobytes() == ref[3].tobytes()
    # the bump carries load at the end (loaded cells right of the pad's pole)
    right = ref[3][-1, 0][:, N // 2 + 15 :]
    assert np.count_nonzero(right) > 0
