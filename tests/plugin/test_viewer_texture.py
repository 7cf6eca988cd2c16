"""What you touch is what you see (issue 16): the skin's visualize callback
draws the textures it feels, which live in a group MuJoCo hides by default,
and the ridge crests of its skin over the pressure heatmap."""

import json
import os
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from mjtouch import viewer
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout


def scene(**skin):
    tip = scenes.Fingertip(nx=48, pitch_m=2e-4, skin=skin)
    model = scenes.build_model(tip, scenes.Texture(period_m=1e-3))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def drawn(model, data, option=None):
    scn = mujoco.MjvScene(model, maxgeom=5000)
    mujoco.mjv_updateScene(
        model,
        data,
        option or mujoco.MjvOption(),
        mujoco.MjvPerturb(),
        mujoco.MjvCamera(),
        mujoco.mjtCatBit.mjCAT_ALL,
        scn,
    )
    return [scn.geoms[i] for i in range(scn.ngeom)]


def test_the_texture_the_skin_feels_is_drawn_once():
    model, data = scene()
    tex = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "texture")
    assert model.geom_group[tex] == scenes.TEXTURE_GROUP
    assert not mujoco.MjvOption().geomgroup[scenes.TEXTURE_GROUP]  # hidden by default
    copies = [
        g for g in drawn(model, data) if g.objtype == mujoco.mjtObj.mjOBJ_GEOM and g.objid == tex
    ]
    assert len(copies) == 1
    g = copies[0]
    assert g.type == mujoco.mjtGeom.mjGEOM_HFIELD and g.dataid == model.geom_dataid[tex]
    assert np.allclose(g.pos, data.geom_xpos[tex]) and np.allclose(g.rgba, model.geom_rgba[tex])
    # with the group shown MuJoCo draws it itself: no second copy
    opt = mujoco.MjvOption()
    opt.geomgroup[scenes.TEXTURE_GROUP] = 1
    assert (
        sum(
            g.objtype == mujoco.mjtObj.mjOBJ_GEOM and g.objid == tex
            for g in drawn(model, data, opt)
        )
        == 1
    )
    # visual = none: the skin draws nothing, the texture stays hidden
    model, data = scene(visual="none")
    assert not any(
        g.objtype == mujoco.mjtObj.mjOBJ_GEOM and g.objid == tex for g in drawn(model, data)
    )


@pytest.mark.parametrize("ridges,angle", [(True, 0.0), (True, 30.0), (False, 0.0)])
def test_ridge_crests_are_drawn_over_the_heatmap(ridges, angle):
    model, data = scene(ridges="true" if ridges else "false", ridge_angle=str(angle))
    lay = SkinLayout.from_model(model)
    lines = [
        g
        for g in drawn(model, data)
        if g.type == mujoco.mjtGeom.mjGEOM_LINE
        and g.objid == lay.sensor_id
        and g.objtype == mujoco.mjtObj.mjOBJ_UNKNOWN
    ]
    if not ridges:
        assert lines == []
        return
    pitch, half = scenes.Fingertip().ridge_pitch_m, 0.5 * lay.nx * lay.pitch_m
    a = np.radians(angle)
    reach = half * (abs(np.cos(a)) + abs(np.sin(a)))
    k = np.arange(np.ceil(-reach / pitch), np.floor(reach / pitch) + 1)
    # crests through the square: s = k pitch, |s| under the square's extent
    # across the ridges (the corners' lines of zero length excepted)
    assert abs(len(lines) - len(k)) <= 2 and len(lines) >= len(k) - 2 > 10
    # each crest is a segment of the square's plane, parallel to the ridges
    pad = int(model.sensor_objid[lay.sensor_id])
    R = data.geom_xmat[pad].reshape(3, 3)
    for g in lines:
        axis = R.T @ g.mat.reshape(3, 3)[:, 2]  # the line's direction, pad frame
        assert abs(axis[2]) < 1e-6
        assert abs(axis[0] * np.cos(a) + axis[1] * np.sin(a)) < 1e-6


RENDER = """
import json, sys, mujoco, numpy as np
from mjtouch import viewer
s = viewer.SlideSession()
s.advance(int(round(0.3 / s.dt)))
r = mujoco.Renderer(s.model, 240, 320)
r.enable_segmentation_rendering()
r.update_scene(s.data, s.camera())
seg = r.render()
tex = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_GEOM, "texture")
plate = mujoco.mj_name2id(s.model, mujoco.mjtObj.mjOBJ_GEOM, "plate")
is_geom = seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)
print(json.dumps({"texture": int(((seg[..., 0] == tex) & is_geom).sum()),
                  "plate": int(((seg[..., 0] == plate) & is_geom).sum()),
                  "total": seg[..., 0].size}))
"""


def test_offscreen_frames_show_the_texture_not_the_flat_proxy():
    backend = viewer.offscreen_backend()
    if backend is None:
        pytest.fail(
            "no offscreen OpenGL backend (MUJOCO_GL=egl or osmesa) works here", pytrace=False
        )
    env = {**os.environ, "MUJOCO_GL": backend, "PYOPENGL_PLATFORM": backend}
    proc = subprocess.run(
        [sys.executable, "-c", RENDER], env=env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    px = json.loads(proc.stdout.strip().splitlines()[-1])
    # the viewer's camera looks down on the plate around the pad: the
    # grating covers a good part of the frame (before, its group hidden, it
    # covered none); the flat proxy shows on the plate's sides and, as
    # z-fighting, in the grating's valleys (both at z = 0)
    assert px["texture"] > 0.2 * px["total"], px
    assert px["plate"] > 0, px
