"""A grating exported as STL slides like the generated grating (issue 16)."""

import json

import pytest
import trimesh
from conftest import fast_tip
from test_mesh_texture import W_PLATEAU, D, H, grating_points

from mjtouch import analysis, cli
from mjtouch.experiments import rollout
from mjtouch.scene import meshes, scenes

SPEED = 0.04  # m/s: V/D = 40 Hz


@pytest.fixture(scope="module")
def grating_stl(tmp_path_factory):
    path = tmp_path_factory.mktemp("slide") / "grating.stl"
    meshes.profile_mesh(*grating_points(0.0401), width_m=0.004).export(path)
    return path


def strongest_peak(tex, duration_s=0.35):
    res = rollout.run_slide(fast_tip(), tex, scenes.Protocol(speed_m_s=SPEED), duration_s)
    f, p = analysis.stress_spectrum(res.stress[res.window()], res.dt)
    return analysis.spectral_peaks(f, p, n=1, fmin_hz=5.0, fmax_hz=1000.0)[0], f[1] - f[0]


def test_stl_grating_gives_the_generated_gratings_VD_line(grating_stl):
    # a 2 mm wide crop of the profile, widened to the generated plate's width
    mt = meshes.from_mesh(grating_stl, resolution_m=2e-5, width_m=0.002)
    generated = scenes.Texture(
        kind="grating",
        period_m=D,
        plateau_m=W_PLATEAU,
        height_m=H,
        edge_m=0.0,
        length_m=mt.length_m,
    )
    f_mesh, bin_hz = strongest_peak(mt.texture(width_m=generated.width_m))
    f_gen, _ = strongest_peak(generated)
    assert abs(f_mesh - f_gen) <= bin_hz
    assert abs(f_mesh - SPEED / D) <= bin_hz


def test_concatenated_parts_stl_grating_slides_with_its_VD_line(tmp_path):
    # the way trimesh users build one: plateau boxes dropped onto a base slab
    # (the slab's top face runs on, hidden, under every plateau)
    length, width = 0.0401, 0.004
    slab = trimesh.creation.box([length, width, 1e-3])
    slab.apply_translation([0, 0, -5e-4])
    parts = [slab]
    for k in range(-19, 20):
        box = trimesh.creation.box([W_PLATEAU, width, H + 2e-4])
        box.apply_translation([k * D, 0, (H - 2e-4) / 2])  # 0.2 mm into the slab
        parts.append(box)
    path = tmp_path / "parts.stl"
    trimesh.util.concatenate(parts).export(path)
    mt = meshes.from_mesh(path, resolution_m=2e-5, width_m=0.002)
    assert mt.relief_m == pytest.approx(H, rel=1e-6)
    f_mesh, bin_hz = strongest_peak(mt.texture(width_m=0.02))
    assert abs(f_mesh - SPEED / D) <= bin_hz


def test_cli_texture_mesh_reports_peaks_against_VD(grating_stl, capsys):
    rc = cli.main(
        [
            "slide",
            "--texture-mesh",
            str(grating_stl),
            "--period",
            str(D),
            "--speed",
            str(SPEED / 2),
            "--duration",
            "0.25",
            "--nx",
            "48",
            "--pitch",
            "2e-4",
            "--json",
        ]
    )
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    assert out["texture"] == "mesh"
    assert out["expected_hz"]["texture"] == pytest.approx(SPEED / 2 / D)
    assert min(abs(f - SPEED / 2 / D) for f in out["peaks_hz"]) <= out["fft_bin_hz"]
    # a file in mm read as metres is refused with the fix
    assert cli.main(["slide", "--texture-mesh", str(grating_stl), "--mesh-scale", "1000"]) == 2
    assert "scale = 1e-3" in capsys.readouterr().err
