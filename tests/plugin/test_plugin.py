"""Plugin registration, the committed models, and the sensordata layout."""

import subprocess
import sys
import tempfile

import mujoco
import numpy as np
import pytest
from conftest import MODELS, assert_no_warnings, pad_scene

import mjtouch
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

SCENES = sorted(p.name for p in MODELS.glob("slide_*.xml"))
ALL_MODELS = sorted(p.name for p in MODELS.glob("*.xml"))


def test_plain_import_mujoco_registers_plugin():
    # A fresh interpreter that imports only mujoco: the `mujoco.plugins`
    # entry point must register mjtouch.skin.
    code = (
        f"import mujoco; m = mujoco.MjModel.from_xml_path({str(MODELS / 'slide_flat.xml')!r}); "
        "print(m.nplugin, m.nsensordata)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=tempfile.gettempdir(),
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    nplugin, nsensordata = map(int, out.stdout.split())
    assert nplugin == 1 and nsensordata > 0


def test_library_found_and_version_pinned():
    assert mjtouch.library_path().is_file()
    assert mujoco.__version__ == mjtouch.MUJOCO_VERSION
    lib = mjtouch._loader.load()
    assert lib.mjtouch_built_mujoco_version() == mujoco.mj_version()


def test_committed_models_match_builders():
    with tempfile.TemporaryDirectory() as tmp:
        written = scenes.write_models(tmp)
        for p in written:
            committed = MODELS / p.name
            assert committed.is_file(), f"models/{p.name} missing; run scenes.write_models"
            assert committed.read_text() == p.read_text(), (
                f"models/{p.name} is out of date; regenerate with "
                "python -c 'import mjtouch.scenes as s; s.write_models(\"models\")'"
            )


def _arrays(m: mujoco.MjModel) -> dict:
    return {
        k: getattr(m, k)
        for k in dir(m)
        if not k.startswith("_") and isinstance(getattr(m, k, None), np.ndarray)
    }


def test_scene_spec_compiles_to_the_committed_scene():
    # the Python builder and the committed file give the same model, bit for bit
    built = _arrays(
        scenes.scene_spec(
            scenes.Fingertip(ridges=False), model_name="slide_grating_smooth"
        ).compile()
    )
    read = _arrays(mujoco.MjModel.from_xml_path(str(MODELS / "slide_grating_smooth.xml")))
    differ = [k for k in read if not np.array_equal(read[k], built[k])]
    assert differ == []


def test_scene_spec_edits():
    spec = scenes.scene_spec(scenes.Fingertip(nx=16, pitch_m=4e-4, ridges=False))
    scenes.set_skin(spec, outputs="force pressure", ridge_angle=None)
    layout = SkinLayout.from_model(spec.compile())
    assert set(layout.blocks) == {"force", "pressure"}
    assert "ridge_angle" not in scenes.skin_plugins(spec)[0].config
    bare = scenes.remove_skin(spec).compile()
    assert bare.nplugin == 0 and bare.nsensor == 0 and bare.ngeom == 3


@pytest.mark.parametrize("name", ALL_MODELS)
def test_every_model_compiles(name):
    if name.startswith(("plate_",)):
        # parts without the fingertip compile on their own
        mujoco.MjModel.from_xml_path(str(MODELS / name))
        return
    m = mujoco.MjModel.from_xml_path(str(MODELS / name))
    assert m.nplugin >= 1


@pytest.mark.parametrize("name", SCENES)
def test_scene_steps_one_second_pressed_without_warnings(name):
    m = mujoco.MjModel.from_xml_path(str(MODELS / name))
    d = mujoco.MjData(m)
    layout = SkinLayout.from_model(m)
    d.ctrl[m.actuator("press").id] = -0.5
    steps = int(round(1.0 / m.opt.timestep))
    fn = np.empty(steps)
    for k in range(steps):
        mujoco.mj_step(m, d)
        fn[k] = layout.block(d.sensordata, "force")[0]
    assert_no_warnings(d)
    assert np.all(np.isfinite(d.sensordata))
    # quasi-static press: the plugin's normal force settles at the command
    # (gravity compensated); 1% allows the contact's residual settling.
    assert abs(fn[-1000:].mean() - 0.5) < 5e-3


def test_layout_blocks_and_receptors():
    m = mujoco.MjModel.from_xml_string(
        pad_scene({"outputs": "spikes stress voltage force pressure"})
    )
    layout = SkinLayout.from_model(m)
    nrec = len(layout.classes)
    assert nrec > 0 and set(layout.classes) == {"SA1", "RA", "PC"}
    sizes = {k: s.stop - s.start for k, s in layout.blocks.items()}
    assert sizes == {
        "spikes": nrec,
        "stress": nrec,
        "voltage": nrec,
        "force": 5,
        "pressure": layout.nx**2,
    }
    assert layout.size == m.nsensordata
    # densities (per cm^2) times the population disc's area
    r = np.hypot(layout.positions_m[:, 0], layout.positions_m[:, 1])
    radius = 48 * 1.5e-4 / 2 - 1.5e-4
    assert r.max() <= radius + 1.5e-4
    area_cm2 = np.pi * radius**2 * 1e4
    for cls, density in (("SA1", 70), ("RA", 140), ("PC", 21)):
        assert (layout.classes == cls).sum() == round(density * area_cm2)


def test_force_on_pad_is_weight_at_rest():
    m = mujoco.MjModel.from_xml_string(pad_scene({"outputs": "force pressure"}))
    d = mujoco.MjData(m)
    layout = SkinLayout.from_model(m)
    for _ in range(2500):
        mujoco.mj_step(m, d)
    f = layout.block(d.sensordata, "force")
    weight = 0.05 * 9.81
    assert abs(f[0] - weight) < 1e-3 * weight
    # sum of p * A equals the normal force to round-off (float32 pressures)
    p = layout.block(d.sensordata, "pressure")
    assert abs(p.sum() * layout.pitch_m**2 - f[0]) < 1e-6 * f[0]


def test_missing_plugin_library_gives_clear_error(monkeypatch, tmp_path):
    monkeypatch.setattr(mjtouch._loader, "_candidates", lambda: [tmp_path / "libmjtouch.so"])
    with pytest.raises(mjtouch.PluginNotBuiltError, match="was not found.*pip install"):
        mjtouch._loader.library_path()


def test_shipped_scene_spec_sets_the_skin_attributes():
    # The shipped file with the given attributes on its inline <sensor><plugin>:
    # the same model as the file edited by set_skin, the rest untouched.
    spec = scenes.shipped_scene_spec("slide_flat", pressure="elastic", nx=40)
    layout = SkinLayout.from_model(spec.compile())
    assert layout.nx == 40
    cfg = dict(
        next(s for s in spec.sensors if s.type == mujoco.mjtSensor.mjSENS_PLUGIN).plugin.config
    )
    assert cfg["pressure"] == "elastic"
    ref = mujoco.MjSpec.from_file(str(MODELS / "slide_flat.xml"))
    ref_cfg = dict(
        next(s for s in ref.sensors if s.type == mujoco.mjtSensor.mjSENS_PLUGIN).plugin.config
    )
    assert {k: v for k, v in cfg.items() if k not in ("pressure", "nx")} == {
        k: v for k, v in ref_cfg.items() if k not in ("pressure", "nx")
    }
    plain = scenes.shipped_scene_spec("slide_grating").compile()
    assert (
        SkinLayout.from_model(plain).nx
        == SkinLayout.from_model(mujoco.MjModel.from_xml_path(str(MODELS / "slide_grating.xml"))).nx
    )
    with pytest.raises(ValueError, match="slide_cork.*must be one of"):
        scenes.shipped_scene_spec("slide_cork")


def test_set_skin_edits_the_shipped_scenes_inline_instance():
    # models/*.xml define the instance inline in <sensor><plugin>; set_skin
    # must reach it (it once did nothing there) and reject a spec without skin.
    spec = mujoco.MjSpec.from_file(str(MODELS / "slide_flat.xml"))
    scenes.set_skin(spec, pressure="elastic", nx="40")
    layout = SkinLayout.from_model(spec.compile())
    assert layout.nx == 40
    bare = scenes.remove_skin(
        scenes.scene_spec(scenes.Fingertip(), scenes.Texture(), scenes.Protocol())
    )
    with pytest.raises(ValueError, match="no mjtouch.skin"):
        scenes.set_skin(bare, nx="40")
