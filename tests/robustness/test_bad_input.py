"""Bad input at the MuJoCo adapter (plugin/mujoco/): non-finite height-field
samples, one plugin instance shared by two sensors; and copying / pickling an
MjData that carries the plugin (README "Copying and pickling MjData")."""

import copy
import os
import pickle
import subprocess
import sys
import textwrap

import mujoco
import numpy as np
import pytest
from conftest import REPO, pad_spec

from mjtouch.scene import scenes

NAN_SAMPLES = [0, 1, 0, np.nan, 0, 0, 1, 0, 1, 0]


def _compile_error(spec: mujoco.MjSpec) -> str:
    with pytest.raises(ValueError) as e:
        spec.compile()
    ours = [line for line in str(e.value).splitlines() if line.startswith("mjtouch.skin: ")]
    assert ours, str(e.value)
    return ours[0]


# -- non-finite height-field samples --------------------------------------


def test_nan_in_texture_hfield_fails_at_compile():
    # userdata is stored as given (row-major): sample 3 is row 0, col 3.
    spec = pad_spec()
    spec.hfield("h").userdata = NAN_SAMPLES
    msg = _compile_error(spec)
    assert "height field 'h' (geom 'texture')" in msg, msg
    assert "sample nan at row 0, col 3 of 2 x 5" in msg, msg
    assert "valid: finite" in msg, msg


def test_inf_in_colliding_hfield_fails_at_mjdata(capfd):
    # a colliding height field (no `texture`): the pad may touch it. Samples
    # edited after compiling are checked when the plugin starts (MjData):
    # MuJoCo raises its generic init error, our message is its warning.
    spec = pad_spec(texture=False)
    spec.add_hfield(
        name="ground", nrow=3, ncol=3, size=[0.02, 0.02, 0.001, 0.001], userdata=[0.0] * 9
    )
    spec.worldbody.add_geom(
        name="bumps", type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname="ground", pos=[0, 0, -0.01]
    )
    m = spec.compile()
    mujoco.MjData(m)  # finite: fine
    m.hfield_data[4] = np.inf
    capfd.readouterr()
    with pytest.raises(mujoco.FatalError, match="plugin->init failed"):
        mujoco.MjData(m)
    out = "".join(capfd.readouterr())
    assert "field 'ground' (geom 'bumps') has sample inf at row 1, col 1 of 3 x 3" in out, out


def test_nan_in_hfield_the_skin_never_renders_is_accepted():
    # non-colliding and not a texture: the skin never reads it
    spec = pad_spec(texture=False)
    spec.add_hfield(
        name="h", nrow=2, ncol=5, size=[0.01, 0.01, 0.0001, 0.001], userdata=NAN_SAMPLES
    )
    spec.worldbody.add_geom(
        name="decor",
        type=mujoco.mjtGeom.mjGEOM_HFIELD,
        hfieldname="h",
        contype=0,
        conaffinity=0,
        group=4,
        pos=[0.05, 0, 0],
    )
    m = spec.compile()
    assert np.isnan(m.hfield_data).sum() == 1
    mujoco.MjData(m)


def test_nan_set_after_compile_fails_at_mjdata(capfd):
    m = pad_spec().compile()
    m.hfield_data[7] = np.nan
    capfd.readouterr()
    with pytest.raises(mujoco.FatalError, match="plugin->init failed"):
        mujoco.MjData(m)
    out = "".join(capfd.readouterr())
    assert "height field 'h' (geom 'texture') has sample nan at row 1, col 2 of 2 x 5" in out, out


# -- one instance, two sensors ----------------------------------------------


def test_two_sensors_sharing_an_instance_fail_at_compile():
    # MuJoCo accepts it (the second sensor would stay all zero)
    spec = pad_spec()
    plugin = scenes.skin_plugins(spec)[0]
    plugin.name = "x"
    left = spec.sensor("skin")
    left.name = "left"
    left.plugin = plugin  # the sensor holds a copy of the reference: renew it
    right = spec.add_sensor(
        name="right",
        type=mujoco.mjtSensor.mjSENS_PLUGIN,
        objtype=mujoco.mjtObj.mjOBJ_GEOM,
        objname="pad",
    )
    right.plugin = plugin
    msg = _compile_error(spec)
    assert "plugin instance 'x' is used by two sensors, 'left' and 'right'" in msg, msg
    assert "valid: one sensor per instance" in msg, msg


# -- copying and pickling MjData --------------------------------------------


def _model():
    return pad_spec().compile()


def _rollout(m, d, n):
    out = np.empty((n, m.nsensordata))
    for i in range(n):
        d.qfrc_applied[0] = 0.05 if d.time > 0.01 else 0.0  # slide along x
        d.qfrc_applied[2] = -0.5  # press
        mujoco.mj_step(m, d)
        out[i] = d.sensordata
    return out


def _copy_deepcopy(m, d):
    return copy.deepcopy(d)


def _copy_copy(m, d):
    return copy.copy(d)


def _copy_mj_copydata(m, d):
    dst = mujoco.MjData(m)
    mujoco.mj_copyData(dst, m, d)
    return dst


def _copy_pickle(m, d):
    return pickle.loads(pickle.dumps(d))


@pytest.mark.parametrize(
    "make_copy",
    [_copy_deepcopy, _copy_copy, _copy_mj_copydata, _copy_pickle],
    ids=["deepcopy", "copy", "mj_copyData", "pickle"],
)
def test_copy_continues_bit_identically(make_copy):
    m = _model()
    d = mujoco.MjData(m)
    _rollout(m, d, 150)
    twin = make_copy(m, d)
    ref = _rollout(m, d, 150)
    assert np.abs(ref).sum() > 0  # the pad touches: a real comparison
    got = _rollout(m, twin, 150)
    np.testing.assert_array_equal(got, ref)
    del twin  # frees only what the twin owns; d keeps stepping
    _rollout(m, d, 5)


def _python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        cwd=REPO / "tests" / "robustness",
        env={**os.environ, "PYTHONPATH": str(REPO / "tests")},
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_pickle_round_trip_does_not_crash_the_process():
    # The round trip of the issue: before, both MjData freed one plugin
    # (double free at exit); an unpickled copy stepped another's scratch.
    run = _python("""
        import pickle, mujoco, mjtouch
        m = mujoco.MjModel.from_xml_path("../../models/slide_flat.xml")
        d = mujoco.MjData(m)
        mujoco.mj_step(m, d)
        d2 = pickle.loads(pickle.dumps(d))
        mujoco.mj_step(m, d2)
        mujoco.mj_resetData(m, d2)
        del d2
        mujoco.mj_step(m, d)
        del d
        print("done")
        """)
    assert run.returncode == 0 and "done" in run.stdout, run.stderr[-2000:]


def test_pickle_into_another_process_continues_bit_identically(tmp_path):
    # There the copied plugin pointer is garbage: the plugin rebuilds itself
    # from the model and the pickled plugin_state.
    m = _model()
    d = mujoco.MjData(m)
    _rollout(m, d, 150)
    (tmp_path / "data.pkl").write_bytes(pickle.dumps(d))
    ref = _rollout(m, d, 150)
    fresh = _rollout(m, mujoco.MjData(m), 100)
    run = _python(f"""
        import pickle, mujoco, numpy as np, mjtouch
        from conftest import pad_spec
        from test_bad_input import _rollout
        m = pad_spec().compile()
        d = pickle.loads(open({str(tmp_path / "data.pkl")!r}, "rb").read())
        np.save({str(tmp_path / "cont.npy")!r}, _rollout(m, d, 150))
        d = pickle.loads(open({str(tmp_path / "data.pkl")!r}, "rb").read())
        mujoco.mj_resetData(m, d)  # before any step: reset from the model
        np.save({str(tmp_path / "reset.npy")!r}, _rollout(m, d, 100))
        """)
    assert run.returncode == 0, run.stderr[-2000:]
    np.testing.assert_array_equal(np.load(tmp_path / "cont.npy"), ref)
    np.testing.assert_array_equal(np.load(tmp_path / "reset.npy"), fresh)
