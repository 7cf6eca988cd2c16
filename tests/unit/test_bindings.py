"""The Python <-> C++ boundary (mjtouch._core, plugin/python/): arrays of the
wrong dtype or rank are refused with the expected signature, wrong shapes and
stage errors raise ValueError with the stage's own message, point arrays give
what single points give, and a missing extension says how to build it."""

import gc
import subprocess
import sys

import mujoco
import numpy as np
import pytest
from conftest import pad_scene
from numpy.testing import assert_array_equal

from mjtouch import _loader, core
from mjtouch.core import _core


def test_wrong_dtype_is_a_type_error_naming_the_expected_dtype():
    gap = np.zeros((8, 8), np.float32)  # the stage takes float64 gaps
    with pytest.raises(TypeError, match=r"gap_m: ndarray\[dtype=float64"):
        _core.winkler_pressure(gap, np.ones((8, 8)), 1e-4, 1e6, 1.0)
    ij = np.zeros((1, 2), np.int64)  # cell indices are int32
    with pytest.raises(TypeError, match=r"receptors_ij: ndarray\[dtype=int32"):
        _core.field_stress(np.zeros((4, 4), np.float32), 1e-4, 1e-3, ij)


def test_wrong_rank_or_layout_is_a_type_error():
    with pytest.raises(TypeError, match=r"points_m: ndarray\[dtype=float64, shape=\(\*, \*\)"):
        _core.halfspace_stress(np.ones(3))
    strided = np.ones((4, 6))[:, ::2]  # not C-contiguous
    with pytest.raises(TypeError, match="order='C'"):
        _core.halfspace_stress(strided)


def test_wrong_shape_is_a_value_error_naming_the_argument_and_shape():
    with pytest.raises(
        ValueError,
        match=r"points_m must have shape \(npoint, 3\), got shape "
        r"\(4, 2\)",
    ):
        _core.halfspace_stress(np.ones((4, 2)))
    with pytest.raises(
        ValueError,
        match=r"gap_m must be a non-empty square \(n x n\) array, got "
        r"shape \(8, 6\)",
    ):
        _core.winkler_pressure(np.zeros((8, 6)), np.ones((8, 6)), 1e-4, 1e6, 1.0)
    with pytest.raises(ValueError, match=r"coverage must have shape \(8, 8\)"):
        _core.winkler_pressure(np.zeros((8, 8)), np.ones((8, 7)), 1e-4, 1e6, 1.0)
    with pytest.raises(ValueError, match=r"contacts must have shape \(ncontact, 5\)"):
        _core.splat_contacts(np.zeros((2, 4)), 8, 1e-4)


def test_stage_error_reaches_python_with_the_plugins_message():
    # The same attribute error through MuJoCo's compiler (the plugin) and
    # through _core (ParseSkinConfig): one message.
    with pytest.raises(ValueError) as from_core:
        _core.check_config({"sa1_c": "-1e-12"})
    with pytest.raises(ValueError) as from_plugin:
        mujoco.MjModel.from_xml_string(pad_scene({"sa1_c": "-1e-12"}))
    message = str(from_core.value)
    assert "`sa1_c`" in message and "(0, 1]" in message
    assert message in str(from_plugin.value)


def test_layered_substrate_error_is_the_stages_message():
    with pytest.raises(ValueError, match=r"base poisson.*\(-1, 0\.5\]"):
        _core.LayeredSubstrate.create(np.array([[1e-3, 1e3, 0.3]]), False, 1e3, 0.7, "upper")
    shao = core.LayeredSkin()
    with pytest.raises(ValueError, match="rigid base"):  # LayeredSubstrate::CheckDepth
        shao.point_stress([0.0, 0.0], 0.0, [1e-3, 5e-3])


def test_unknown_attribute_and_enum_arguments_are_value_errors():
    with pytest.raises(ValueError, match="unknown attribute `no_such_key`"):
        _core.check_config({"no_such_key": "1"})
    with pytest.raises(ValueError, match=r"load 'twist' is not one of"):
        core.halfspace_stress(0.0, 0.0, 1e-3, "twist")
    with pytest.raises(ValueError, match=r"method 'fastest' is not one of"):
        core.StressEngine(0.5, 8, 1e-4, [1e-3], [[1, 1]], method="fastest")


def test_point_arrays_match_single_points_exactly():
    rng = np.random.default_rng(3)
    pts = rng.uniform([-2e-3, -2e-3, 0.2e-3], [2e-3, 2e-3, 3e-3], size=(7, 3))
    many = core.halfspace_stress(pts[:, 0], pts[:, 1], pts[:, 2], "shear_x", 0.45)
    for k, (x, y, z) in enumerate(pts):
        assert_array_equal(many[k], core.halfspace_stress(x, y, z, "shear_x", 0.45))
    skin = core.LayeredSkin()
    k = np.array([[0.0, 100.0], [2e3, 5e4]])
    c = skin.compliance(k)
    assert c.shape == (2, 2)
    assert_array_equal(c[1, 0], skin.compliance(2e3))


def test_stress_engine_keeps_its_substrate_alive():
    skin = core.LayeredSkin()
    engine = core.StressEngine(skin, 8, 2e-4, [1e-3], [[4, 4]], method="direct")
    ref = engine.stress(np.ones((8, 8)))
    raw = _core.StressEngine(
        skin._s,
        0.0,
        8,
        2e-4,
        np.array([1e-3]),
        np.array([[4, 4]], np.int32),
        np.zeros(1, np.int32),
        np.full(1, 63, np.int32),
        "direct",
        0.5,
    )
    del skin, engine
    gc.collect()
    out, _, used, active = raw.stress(np.ones((8, 8), np.float32))
    assert used == "direct" and active == 64
    assert_array_equal(out, ref)


def test_instance_reader_refuses_a_library_that_is_not_loaded(tmp_path):
    with pytest.raises(ValueError, match="is not loaded"):
        _core.describe_instance(str(tmp_path / "libmjtouch.so"), 0, 0)
    # the loaded plugin library speaks the same instance interface version
    assert _core.INSTANCE_ABI_VERSION == _loader.load().mjtouch_instance_abi_version()


def test_missing_extension_says_how_to_build():
    code = (
        "import sys; sys.modules['mjtouch._core'] = None\n"
        "try:\n    import mjtouch.core\n"
        "except ImportError as e:\n    print(type(e).__name__, e)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.startswith("PluginNotBuiltError")
    assert "Was the package built? Run `pip install .`" in out
