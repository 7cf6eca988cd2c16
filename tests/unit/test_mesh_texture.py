"""meshes.from_mesh: a mesh's top surface as exact cell means (issue 16)."""

import numpy as np
import pytest
import trimesh

from mjtouch.scene import meshes

D, W_PLATEAU, H = 1e-3, 0.5e-3, 1e-4  # a square-wave grating


def grating_points(length_m):
    """Polyline of a sharp-edged grating: plateaux centred on x = k D."""
    xs, zs = [-length_m / 2], [0.0]
    for k in range(-100, 101):
        a, b = k * D - W_PLATEAU / 2, k * D + W_PLATEAU / 2
        if a > -length_m / 2 and b < length_m / 2:
            xs += [a, a, b, b]
            zs += [0, H, H, 0]
    return np.array(xs + [length_m / 2]), np.array(zs + [0.0])


def square_wave_cell_means(x, r):
    """Analytic mean of the square wave over [x - r/2, x + r/2]."""

    def F(s):  # integral of the unit square wave from a period start
        k = np.floor((s + D / 2) / D)
        return k * W_PLATEAU + np.clip(s - k * D, -W_PLATEAU / 2, W_PLATEAU / 2)

    return H * (F(x + r / 2) - F(x - r / 2)) / r


@pytest.fixture(scope="module")
def grating_stl(tmp_path_factory):
    path = tmp_path_factory.mktemp("mesh") / "grating.stl"
    meshes.profile_mesh(*grating_points(0.0121), width_m=0.004).export(path)
    return path


def test_stl_grating_heights_are_the_profiles_cell_means(grating_stl):
    r = 2e-5
    mt = meshes.from_mesh(grating_stl, resolution_m=r)
    assert mt.is_profile  # no variation along y: two rows, as the generated gratings
    x = np.linspace(-mt.length_m / 2, mt.length_m / 2, mt.heights.shape[1])
    inner = np.abs(x) < 5.5e-3  # the plateaux the mesh holds (|k| <= 5)
    ref = square_wave_cell_means(x, r)
    # STL stores float32: edges move by <= eps32 * 6 mm = 7e-10 m, which
    # moves a cell mean by <= H * 7e-10 / r = 3.6e-9 m.
    tol = H * np.finfo(np.float32).eps * 6e-3 / r
    assert np.abs(mt.heights[0] - ref)[inner].max() < tol
    # cells that straddle an edge are partial (anti-aliased), not 0 or H
    partial = (ref > 0.01 * H) & (ref < 0.99 * H) & inner
    assert partial.sum() >= 10


def test_exact_for_a_tilted_plane_on_an_irregular_triangulation():
    # The mean of a linear height over a cell is its value at the centre,
    # whatever triangles (and cell-crossing diagonals) carry it.
    rng = np.random.default_rng(3)
    x = np.sort(np.concatenate([[-4e-3, 4e-3], rng.uniform(-4e-3, 4e-3, 9)]))
    y = np.sort(np.concatenate([[-3e-3, 3e-3], rng.uniform(-3e-3, 3e-3, 7)]))
    X, Y = np.meshgrid(x, y)
    mt = meshes.from_mesh(
        meshes.heightmap_mesh(x, y, 0.02 * X + 0.01 * Y + 1e-4), resolution_m=5e-5
    )
    xc = np.linspace(-mt.length_m / 2, mt.length_m / 2, mt.heights.shape[1])
    yc = np.linspace(-mt.width_m / 2, mt.width_m / 2, mt.heights.shape[0])
    Xc, Yc = np.meshgrid(xc, yc)
    ref = 0.02 * Xc + 0.01 * Yc
    ref -= ref.min()
    assert np.abs(mt.heights - ref).max() < 1e-12


def test_placement_scale_up_axis_and_rotation(grating_stl, tmp_path):
    base = meshes.from_mesh(grating_stl, resolution_m=4e-5)
    # the same grating in mm with its textured face along +y: up = +y puts
    # the file's z along x (from_mesh: new x = the axis after up), so the
    # profile (file x) lies along y until turned 90 degrees about up
    m = trimesh.load(grating_stl)
    m.apply_scale(1e3)
    m.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
    path = tmp_path / "turned.ply"
    m.export(path)
    turned = meshes.from_mesh(path, scale=1e-3, up="+y", rotate_deg=90, resolution_m=4e-5)
    assert turned.heights.shape == base.heights.shape
    assert np.abs(turned.heights - base.heights).max() < 1e-8


def test_mesh_texture_in_a_scene_compiles_with_its_heights(grating_stl):
    from mjtouch.scene import scenes

    mt = meshes.from_mesh(grating_stl, resolution_m=4e-5, width_m=0.002)
    tex = mt.texture(width_m=0.02)
    model = scenes.plate_spec(tex).compile()
    h = model.hfield_data.reshape(2, -1) * model.hfield_size[0, 2]
    assert np.abs(h - mt.heights).max() < 1e-6 * H
    assert model.hfield_size[0, 1] == pytest.approx(0.01)
    with pytest.raises(ValueError, match="only a profile"):
        meshes.from_mesh(
            meshes.heightmap_mesh([-2e-3, 0, 2e-3], [-2e-3, 2e-3], [[0, 1e-4, 0], [0, 2e-4, 0]])
        ).texture(width_m=0.1)


def test_bad_meshes_get_clear_errors(tmp_path, grating_stl):
    down = trimesh.Trimesh([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0]], [[0, 2, 1]], process=False)
    with pytest.raises(ValueError, match="no top surface"):
        meshes.from_mesh(down)
    bad = trimesh.Trimesh([[0, 0, 0], [0.01, 0, np.nan], [0, 0.01, 0]], [[0, 1, 2]], process=False)
    with pytest.raises(ValueError, match="non-finite vertices"):
        meshes.from_mesh(bad)
    with pytest.raises(ValueError, match=r"scale = 1000.*scale = 1e-3"):
        meshes.from_mesh(grating_stl, scale=1000)
    with pytest.raises(ValueError, match="valid footprint"):
        meshes.from_mesh(grating_stl, scale=0.01)
    plate = trimesh.creation.box([0.01, 0.01, 0.001])
    with pytest.raises(ValueError, match="flat"):
        meshes.from_mesh(plate, resolution_m=1e-4)
    with pytest.raises(ValueError, match="up = '\\+w'"):
        meshes.from_mesh(plate, up="+w")
    with pytest.raises(FileNotFoundError, match="does not exist"):
        meshes.from_mesh(tmp_path / "missing.stl")
    junk = tmp_path / "junk.stl"
    junk.write_text("not a mesh")
    with pytest.raises(ValueError, match="junk.stl"):
        meshes.from_mesh(junk)
    with pytest.raises(ValueError, match="length_m x width_m"):
        meshes.from_mesh(grating_stl, length_m=1.0)


@pytest.mark.parametrize("ext", ["obj", "ply", "glb"])
def test_every_format_trimesh_reads_gives_the_same_heights(grating_stl, tmp_path, ext):
    stl = meshes.from_mesh(grating_stl, resolution_m=4e-5)
    path = tmp_path / f"grating.{ext}"
    trimesh.load(grating_stl).export(path)
    other = meshes.from_mesh(path, resolution_m=4e-5)
    assert other.heights.shape == stl.heights.shape
    # the vertices as the STL's float32 values (OBJ writes them as decimal
    # text): the same heights to a float32 step of the 6 mm coordinates
    assert np.abs(other.heights - stl.heights).max() < H * 1e-4


def test_concatenated_parts_are_read_as_their_upper_envelope():
    # a 2 x 2 mm box sunk into a 10 x 10 mm plate (tops 0.8 mm apart): the
    # plate's top face runs on under the box, hidden; edges fall mid-cell
    plate = trimesh.creation.box([0.01, 0.01, 0.001])  # top at z = 0.5 mm
    bump = trimesh.creation.box([0.002, 0.002, 0.001])
    x0 = 3.3e-5  # edges 1/3 of a cell off the cell boundaries
    bump.apply_translation([x0, 0, 0.0008])  # top at 1.3 mm
    r = 1e-4
    mt = meshes.from_mesh(trimesh.util.concatenate([plate, bump]), resolution_m=r)
    ny, nx = mt.heights.shape
    x = -mt.length_m / 2 + np.arange(nx) * r
    y = -mt.width_m / 2 + np.arange(ny) * r

    # analytic cell means of the envelope: the box's covered share of each cell
    def share(c, half, lo_edge):  # overlap of [c - r/2, c + r/2] with [lo, lo + 2 half]
        return (
            np.clip(
                np.minimum(c + r / 2, lo_edge + 2 * half) - np.maximum(c - r / 2, lo_edge), 0, r
            )
            / r
        )

    ref = 8e-4 * np.outer(share(y, 1e-3, -1e-3), share(x, 1e-3, x0 - 1e-3))
    # at most 1/ENVELOPE_SAMPLES of a cell off per edge crossing a cell
    err = np.abs(mt.heights - ref)
    assert err.max() <= 8e-4 * 2 / meshes.ENVELOPE_SAMPLES + 1e-12
    assert mt.heights.max() == pytest.approx(8e-4, rel=1e-9)  # the box's top, whole cells
    assert err[ref == 0].max() < 1e-12  # the plate around it: exact
    # a hole (one of the plate's two top triangles gone) is still refused
    top = [f for f in range(len(plate.faces)) if plate.face_normals[f][2] > 0.5]
    holed = trimesh.Trimesh(plate.vertices, np.delete(plate.faces, top[:1], axis=0), process=False)
    with pytest.raises(ValueError, match="has a hole"):
        meshes.from_mesh(trimesh.util.concatenate([holed, bump]), resolution_m=r)
