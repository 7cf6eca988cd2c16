"""The viewer: the skin's drawing in MuJoCo's scene, rendered frames, and the
session logic behind the keys, sliders and figures.

Rendering needs an offscreen OpenGL backend, fixed when mujoco is imported,
so frames are rendered by this file run as a script in a subprocess with
MUJOCO_GL=egl (or osmesa, whichever works here). A machine with neither
fails the render tests with what to install; it does not skip them.

The drawing (plugin/mujoco/visualize.cc): pressure tiles (boxes, a heat ramp
from dark red to white at the frame's peak, tiles under 2% of the peak left
out) and receptor sites (spheres, grey; lit in the class colour, larger, for
30 ms after a spike), on the pad and again 2 mm above it.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import subprocess
import sys

import mujoco
import numpy as np

FLASH_S = 0.03  # visualize.cc kFlashS
MIN_REL_PRESSURE = 0.02  # visualize.cc kMinRelPressure
MAX_TILES_PER_SIDE = 32  # visualize.cc kMaxTilesPerSide
LIT_RADIUS_M, IDLE_RADIUS_M = 1.2e-4, 4e-5  # visualize.cc: small, so the heatmap reads
CLASS_RGBA = {
    "SA1": (0.15, 0.45, 1.0, 1.0),
    "RA": (0.1, 0.9, 0.25, 1.0),
    "PC": (0.95, 0.2, 0.95, 1.0),
}
# Frames: half a grating period apart at V/D = 25 Hz, so the pattern moves.
FRAME_TIMES_S = (0.30, 0.32)
INSTALL_HINT = (
    "no offscreen OpenGL backend works on this machine (tried MUJOCO_GL=egl, then "
    "osmesa). Install one: EGL with `apt-get install libegl1 libegl-mesa0 "
    "libgl1-mesa-dri` (Debian/Ubuntu), or OSMesa with `apt-get install libosmesa6`; "
    'then check with `MUJOCO_GL=egl python -c "import mujoco; '
    "mujoco.Renderer(mujoco.MjModel.from_xml_string('<mujoco/>'), 8, 8)\"`"
)


def heat_color(u: float) -> np.ndarray:
    """visualize.cc HeatColor: the tile colour at pressure u x the peak."""
    v = 0.2 + 0.8 * min(max(u, 0.0), 1.0)
    return np.array(
        [
            min(max(3 * v, 0.0), 1.0),
            min(max(3 * v - 1, 0.0), 1.0),
            min(max(3 * v - 2, 0.0), 1.0),
            1.0,
        ]
    )


def skin_geoms(scn: mujoco.MjvScene, sensor_id: int) -> list[int]:
    """Indices of the geoms the skin plugin added to the scene."""
    return [
        i
        for i in range(scn.ngeom)
        if scn.geoms[i].objtype == mujoco.mjtObj.mjOBJ_UNKNOWN
        and scn.geoms[i].objid == sensor_id
        and scn.geoms[i].category == mujoco.mjtCatBit.mjCAT_DECOR
    ]


# ----- the render worker (this file as a script) ----------------------------


def _worker(out: pathlib.Path) -> None:
    """Render frames of the sliding scene and of the environments; write
    arrays (frames.npz), PNGs and check results (worker.json) into out."""
    import warnings

    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env
    from PIL import Image

    import mjtouch.envs  # noqa: F401
    from mjtouch import viewer

    warnings.simplefilter("error")  # as under pytest
    out.mkdir(parents=True, exist_ok=True)
    session = viewer.SlideSession()
    renderer = mujoco.Renderer(session.model, 480, 640)
    arrays, report = {}, {"backend": os.environ.get("MUJOCO_GL")}
    pad = session.layout_pad_geom()
    for k, t in enumerate(FRAME_TIMES_S):
        session.advance(int(round(t / session.dt)) - session._count)
        renderer.update_scene(session.data, session.camera())
        drawn = skin_geoms(renderer.scene, session.layout.sensor_id)
        report[f"skin_geoms_{k}"] = len(drawn)
        arrays[f"with_{k}"] = renderer.render().copy()
        for i in drawn:  # the same frame without the skin's drawing
            renderer.scene.geoms[i].pos[:] = (0.0, 0.0, -100.0)
        arrays[f"without_{k}"] = renderer.render().copy()
        renderer.enable_segmentation_rendering()
        renderer.update_scene(session.data, session.camera())
        seg = renderer.render()
        renderer.disable_segmentation_rendering()
        arrays[f"pad_{k}"] = (seg[..., 0] == pad) & (seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM))
        Image.fromarray(arrays[f"with_{k}"]).save(out / f"slide_{t:.2f}s.png")
    Image.fromarray(arrays["without_0"]).save(out / "slide_no_skin_drawing.png")
    arrays["session"] = session.render(960, 600)
    # the colour scale's top against the tile means of the pressure output,
    # tiled here as visualize.cc does (independently of viewer.py's helper)
    lay = session.layout
    p = lay.block(session.data.sensordata, "pressure").reshape(lay.nx, lay.nx)
    b = -(-lay.nx // MAX_TILES_PER_SIDE)
    tiles = [
        p[j : j + b, i : i + b].mean() for j in range(0, lay.nx, b) for i in range(0, lay.nx, b)
    ]
    report["peak_tile_kpa"] = float(max(tiles)) / 1e3
    report["scale_top_kpa"] = float(session.scale_figure().range[0][1])
    Image.fromarray(arrays["session"]).save(out / "viewer_session.png")
    report["expected_hz"] = session.expected_hz()
    session.close()
    renderer.close()
    # Gymnasium's render checks (rgb_array) for both environments
    for env_id in mjtouch.envs.ENV_IDS:
        env = gym.make(env_id)
        check_env(env.unwrapped)  # with its render check
        env.close()
        env = gym.make(env_id, render_mode="rgb_array")
        env.reset(seed=0)
        for _ in range(5):
            env.step(env.action_space.sample() * 0)
        frame = env.render()
        name = env_id.split("/")[1]
        arrays[f"env_{name}"] = frame
        Image.fromarray(frame).save(out / f"env_{name}.png")
        env.close()
    np.savez_compressed(out / "frames.npz", **arrays)
    (out / "worker.json").write_text(json.dumps(report))


if __name__ == "__main__":
    _worker(pathlib.Path(sys.argv[1]))
    raise SystemExit(0)


# ----- tests ------------------------------------------------------------------

import pytest  # noqa: E402

from mjtouch import viewer  # noqa: E402
from mjtouch.scene import scenes  # noqa: E402
from mjtouch.viewer import (  # noqa: E402
    KEY_DELETE,
    KEY_END,
    KEY_F9,
    KEY_HOME,
    KEY_INSERT,
    KEY_PAGE_DOWN,
    TEXTURES,
    SlideSession,
    ViewSettings,
)


@pytest.fixture(scope="module")
def gl_env():
    """The environment for a subprocess that renders offscreen."""
    backend = viewer.offscreen_backend()
    if backend is None:
        pytest.fail(INSTALL_HINT, pytrace=False)
    return {**os.environ, "MUJOCO_GL": backend, "PYOPENGL_PLATFORM": backend}


@pytest.fixture(scope="module")
def rendered(tmp_path_factory, gl_env):
    out = tmp_path_factory.mktemp("viewer_frames")
    env = gl_env
    proc = subprocess.run(
        [sys.executable, __file__, str(out)], env=env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, f"render worker failed:\n{proc.stdout}\n{proc.stderr}"
    frames = dict(np.load(out / "frames.npz"))
    report = json.loads((out / "worker.json").read_text())
    return frames, report, out


def classify(img: np.ndarray) -> dict[str, np.ndarray]:
    """Pixel masks of the drawing's colours, lit and shaded: the heat ramp
    (red >= green >= blue, reddish, not grey) and the class colours (one or
    two channels well above the rest)."""
    r, g, b = (img[..., c].astype(int) for c in range(3))
    margin = 60  # of 255: far from the grey plate (channels within 25) and shading
    return {
        "heat": (r > 100) & (r >= g) & (g >= b - 10) & (r - b > margin),
        "SA1": (b > r + margin) & (b > g + 30),
        "RA": (g > r + margin) & (g > b + margin),
        "PC": (r > g + margin) & (b > g + margin),
    }


def test_rendered_frames_show_heatmap_and_spikes_over_the_pad(rendered):
    frames, report, out = rendered
    for k in range(len(FRAME_TIMES_S)):
        drawn = (
            np.abs(frames[f"with_{k}"].astype(int) - frames[f"without_{k}"].astype(int)).max(axis=2)
            > 30
        )
        colours = {name: m & drawn for name, m in classify(frames[f"with_{k}"]).items()}
        counts = {name: int(m.sum()) for name, m in colours.items()}
        # the heatmap: a 9.6 mm square 5 cm from a 640 x 480 camera covers
        # ~100 x 60 pixels, the contact (~5 mm across) a good part of it
        assert counts["heat"] > 500, counts
        # spike markers: lit spheres of 0.24 mm, a few pixels each; SA1 and
        # PC fire steadily while sliding (RA: see the report on RA)
        assert counts["SA1"] > 10 and counts["PC"] > 3, counts
        # over the pad: the drawing's centre is within the pad's columns
        pad_cols = np.nonzero(frames[f"pad_{k}"].any(axis=0))[0]
        cols = np.nonzero(drawn)[1]
        assert pad_cols.min() <= cols.mean() <= pad_cols.max()
        assert report[f"skin_geoms_{k}"] > 300

    # while sliding (the camera tracks the finger, so the pad stays put) the
    # drawing changes: the grating moved half a period under the pad
    def differ(a, b):
        return np.abs(frames[a].astype(int) - frames[b].astype(int)).max(axis=2) > 30

    drawing = differ("with_0", "without_0") | differ("with_1", "without_1")
    changed = differ("with_0", "with_1") & drawing
    scene_changed = differ("without_0", "without_1") & drawing
    # a good share of the drawing changes (measured ~30%), and not because
    # the scene behind it moved
    assert changed.sum() > 0.1 * drawing.sum(), (changed.sum(), drawing.sum())
    assert scene_changed.sum() < 0.1 * changed.sum()
    assert sorted(p.name for p in out.glob("*.png"))  # PNGs for a look


def test_rendered_viewer_frame_has_raster_spectrum_and_marks(rendered):
    frames, report, _ = rendered
    img = frames["session"]
    h, w, _ = img.shape
    raster = img[: h // 2, 2 * w // 3 :]
    spectrum = img[h // 2 :, 2 * w // 3 :]
    rc = {name: int(m.sum()) for name, m in classify(raster).items()}
    assert rc["SA1"] > 50 and rc["PC"] > 20 and rc["RA"] > 5, rc  # ticks of each class
    r, g, b = (spectrum[..., c].astype(int) for c in range(3))
    vd_mark = (r > 200) & (g > 50) & (g < 110) & (b < 90)  # V/D line, rgb (1, .3, .2)
    vl_mark = (g > 200) & (r < 90) & (b > 70) & (b < 140)  # V/lambda line, rgb (.2, 1, .4)
    assert vd_mark.sum() > 50 and vl_mark.sum() > 50
    assert report["expected_hz"]["V/D"] == pytest.approx(0.025 / 1e-3)


def test_rendered_viewer_frame_has_a_colour_scale(rendered):
    """Top left of the viewer frame: the heatmap's scale, bands of the heat
    ramp from dark red (0) to near white (the peak), left to right."""
    frames, report, _ = rendered
    img = frames["session"].astype(int)
    h, w, _ = img.shape
    corner = img[: h // 5, : w // 3]
    ramp = np.array([heat_color(u)[:3] * 255 for u in np.linspace(0, 1, 9)])
    # a row of the bar: the row whose pixels match the most ramp colours
    near = np.abs(corner[:, :, None, :] - ramp[None, None]).max(axis=3) < 40
    row = int(np.argmax(near.any(axis=2).sum(axis=1)))
    matched = np.nonzero(near[row].any(axis=1))[0]
    assert len(matched) > 0.6 * (w // 3 - 20), (row, len(matched))
    # along the bar the colour follows the ramp: brightness rises left to right
    bright = corner[row, matched].sum(axis=1)[2:-2]  # the bar's anti-aliased ends left out
    assert bright[: len(bright) // 4].mean() + 150 < bright[-len(bright) // 4 :].mean()
    assert np.all(np.diff(bright) >= 0), bright  # band by band, never darker
    # MjvFigure.range is float32
    assert report["scale_top_kpa"] == pytest.approx(report["peak_tile_kpa"], rel=1e-6)
    assert report["scale_top_kpa"] > 1  # kPa under a 0.5 N press, not the unitless fallback


def test_environments_render_rgb_arrays(rendered):
    frames, _, _ = rendered
    for name in ("TextureExplore-v0", "SlipHold-v0"):
        frame = frames[f"env_{name}"]
        assert frame.shape == (480, 640, 3) and frame.dtype == np.uint8
        assert frame.std() > 10  # a scene, not a blank frame


def test_view_command_offscreen_writes_a_png(tmp_path, gl_env):
    """`mjtouch view --offscreen` (Pillow writes the PNG)."""
    from PIL import Image

    png = tmp_path / "view.png"
    proc = subprocess.run(
        [sys.executable, "-m", "mjtouch", "view", "--offscreen", str(png), "--duration", "0.3"],
        env=gl_env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "wrote" in proc.stdout and "F = 0.50 N" in proc.stdout
    img = np.asarray(Image.open(png).convert("RGB"))
    assert img.shape == (600, 960, 3)  # SlideSession.render's default size
    scene = img[:, : 2 * img.shape[1] // 3]  # left of the figures
    r, g, b = (scene[..., c].astype(int) for c in range(3))
    yellow = (r > 180) & (g > 160) & (b < 80)  # mid heat ramp; the pad is (.93, .72, .62)
    assert yellow.sum() > 200 and classify(scene)["SA1"].sum() > 10  # heatmap, lit SA1 sites


# ----- the drawing in the scene, checked exactly (no OpenGL needed) ---------


@pytest.fixture(scope="module")
def pressure_session(tmp_path_factory):
    """The viewer's sliding scene with the skin's pressure output on."""
    s = ViewSettings()
    tip = scenes.Fingertip(
        nx=s.nx, pitch_m=s.pitch_m, skin={"outputs": "spikes stress force pressure"}
    )
    xml = scenes.scene_xml(
        tip,
        scenes.Texture(period_m=1e-3),
        scenes.Protocol(force_n=s.force_n, speed_m_s=s.speed_m_s, timestep_s=s.timestep_s),
    )
    path = tmp_path_factory.mktemp("scene") / "slide_pressure.xml"
    path.write_text(xml)
    return path


def scene_drawing(session: SlideSession):
    m, d = session.model, session.data
    scn = mujoco.MjvScene(m, maxgeom=5000)
    mujoco.mjv_updateScene(
        m,
        d,
        mujoco.MjvOption(),
        mujoco.MjvPerturb(),
        session.camera(),
        mujoco.mjtCatBit.mjCAT_ALL,
        scn,
    )
    idx = skin_geoms(scn, session.layout.sensor_id)
    boxes = [scn.geoms[i] for i in idx if scn.geoms[i].type == mujoco.mjtGeom.mjGEOM_BOX]
    spheres = [scn.geoms[i] for i in idx if scn.geoms[i].type == mujoco.mjtGeom.mjGEOM_SPHERE]
    return boxes, spheres


def expected_tiles(session: SlideSession) -> np.ndarray:
    """Tile colours from the pressure output, as visualize.cc draws them."""
    lay = session.layout
    p = lay.block(session.data.sensordata, "pressure").reshape(lay.nx, lay.nx)
    b = -(-lay.nx // MAX_TILES_PER_SIDE)
    nt = -(-lay.nx // b)
    padded = np.full((nt * b, nt * b), np.nan)
    padded[: lay.nx, : lay.nx] = p
    tiles = np.nanmean(padded.reshape(nt, b, nt, b), axis=(1, 3)).ravel()
    peak = tiles.max()
    return np.array([heat_color(t / peak) for t in tiles if t >= MIN_REL_PRESSURE * peak])


def test_scene_heatmap_and_flashing_receptors_match_the_skin(pressure_session):
    session = SlideSession(scene=pressure_session, window_s=0.2)
    lay = session.layout
    nrec = len(lay.classes)
    boxes, spheres = scene_drawing(session)
    # before any contact: the backing square only, every receptor idle
    assert len(boxes) == 1 and len(spheres) == 2 * nrec  # on the pad and above it
    assert all(g.size[0] == pytest.approx(IDLE_RADIUS_M) for g in spheres)
    previous = None
    for t in FRAME_TIMES_S:
        session.advance(int(round(t / session.dt)) - session._count)
        boxes, spheres = scene_drawing(session)
        # heatmap: pad and above copies of every tile over 2% of the peak,
        # coloured by the heat ramp at the tile's pressure over the peak
        want = expected_tiles(session)
        got = np.array([g.rgba for g in boxes[1:]])  # [0]: the backing square
        assert len(got) == 2 * len(want) > 100
        assert np.array_equal(got[0::2], got[1::2])  # each tile on the pad and above
        # row-major tiles in both; float32 colours from float pressures
        assert np.allclose(got[0::2], want, atol=1e-6)
        # receptors: lit (larger, class colour) exactly when they spiked in
        # the last 30 ms; the spike time is the step's start (mj_step's
        # sensor stage), the record's time its end: bracket by half a step
        times, spikes, _ = session.window()
        age = session.data.time - (times - session.dt)
        must = spikes[age < FLASH_S - session.dt / 2].sum(axis=0) > 0
        may = spikes[age < FLASH_S + session.dt / 2].sum(axis=0) > 0
        lit = np.array([g.size[0] > IDLE_RADIUS_M for g in spheres[0::2]])
        assert np.all(lit[must]) and not np.any(lit & ~may)
        assert must.sum() > 10
        for r in np.nonzero(lit)[0]:
            assert np.allclose(spheres[2 * r].rgba, CLASS_RGBA[lay.classes[r]], atol=1e-6)
            assert IDLE_RADIUS_M < spheres[2 * r].size[0] <= LIT_RADIUS_M
        if previous is not None:  # sliding changes both
            assert not np.array_equal(np.sort(want, axis=0), np.sort(previous[0], axis=0))
            assert not np.array_equal(lit, previous[1])
        previous = (want, lit)


# ----- session logic: keys, sliders, figures (no window) -----------------


def test_keys_change_force_speed_texture_and_ridges():
    session = SlideSession()
    s = session.settings
    press, slide = session._act["press"], session._act["slide"]
    session.key(KEY_HOME)
    assert s.force_n == pytest.approx(0.6) and session.data.ctrl[press] == pytest.approx(-0.6)
    session.key(KEY_END)
    session.key(KEY_END)
    assert s.force_n == pytest.approx(0.4) and session.data.ctrl[press] == pytest.approx(-0.4)
    session.key(KEY_INSERT)
    assert s.speed_m_s == pytest.approx(0.030) and session.data.ctrl[slide] == pytest.approx(0.03)
    session.key(KEY_DELETE)
    session.key(KEY_DELETE)
    assert s.speed_m_s == pytest.approx(0.020)
    for _ in range(30):  # clamped to the valid ranges
        session.key(KEY_HOME)
        session.key(KEY_DELETE)
    assert (s.force_n, s.speed_m_s) == (viewer.FORCE_RANGE_N[1], viewer.SPEED_RANGE_M_S[0])
    assert session.key(KEY_INSERT) is False  # force and speed do not rebuild
    # texture: Page Down cycles and rebuilds the scene, V/D follows
    model = session.model
    assert session.key(KEY_PAGE_DOWN) is True and session.model is not model
    assert s.texture == 1 and session.texture_name == TEXTURES[1][0]
    assert session.expected_hz()["V/D"] == pytest.approx(s.speed_m_s / TEXTURES[1][1].period_m)
    for _ in range(len(TEXTURES) - 1):
        session.key(KEY_PAGE_DOWN)
    assert s.texture == 0
    # ridges: F9 toggles, V/lambda only with ridges
    assert session.expected_hz()["V/lambda"] is not None
    session.key(KEY_F9)
    assert s.ridges is False and session.expected_hz()["V/lambda"] is None
    assert plugin_attribute(session.model, "ridges") == "false"
    session.key(KEY_F9)
    assert s.ridges is True and plugin_attribute(session.model, "ridges") == "true"
    # the rebuilt scene keeps force and speed
    assert session.data.ctrl[session._act["press"]] == pytest.approx(-s.force_n)
    assert session.key(12345) is False  # other keys: MuJoCo's


# The first of the skin's attributes, in the order MuJoCo stores their values
# (plugin/core/pipeline/attributes.cc SkinAttributeKeys).
FIRST_ATTRIBUTES = ("texture", "texture_group", "nx", "pitch", "ridges")


def plugin_attribute(model: mujoco.MjModel, key: str) -> str:
    """A config attribute of the first plugin instance, as compiled."""
    values = bytes(model.plugin_attr).split(b"\0")
    attrs = dict(zip(FIRST_ATTRIBUTES, (v.decode() for v in values)))
    assert attrs["nx"] == "48" and attrs["texture_group"] == "3"  # the order holds
    return attrs[key]


def test_scene_file_keeps_its_texture_and_ridges(pressure_session):
    session = SlideSession(scene=pressure_session)
    assert session.key(KEY_PAGE_DOWN) is False and session.key(KEY_F9) is False
    assert "fixed by the scene file" in session.status()
    session.key(KEY_HOME)  # force still drives the `press` actuator
    assert session.data.ctrl[session._act["press"]] == pytest.approx(-session.settings.force_n)


def test_sliders_drive_the_session_and_the_skin_feels_it():
    """The viewer's Control sliders write ctrl; the session takes them over,
    and the skin's normal force follows the new press."""
    session = SlideSession()
    d = session.data
    d.ctrl[session._act["press"]] = -1.2
    d.ctrl[session._act["slide"]] = -0.03
    session.advance(1)
    s = session.settings
    assert s.force_n == pytest.approx(1.2) and s.speed_m_s == pytest.approx(0.03)
    assert session._direction == -1.0
    session.advance(300)
    normal = session.layout.block(d.sensordata, "force")[0]
    # steady sliding: the README measures the normal force steady to
    # < 1e-4 relative; 1e-3 leaves room for the 0.3 s settling
    assert normal == pytest.approx(1.2, rel=1e-3)


def test_spectrum_figure_peaks_at_the_marked_v_over_d():
    """0.5 s of sliding at 25 mm/s over D = 1 mm: the figure's stress
    spectrum peaks at the V/D line it marks (within one FFT bin)."""
    session = SlideSession(window_s=0.5)
    session.advance(int(round(1.0 / session.dt)))  # press, then a window of steady sliding
    fig = session.spectrum_figure()
    n = fig.linepnt[0]
    f, logp = fig.linedata[0, 0 : 2 * n : 2], fig.linedata[0, 1 : 2 * n : 2]
    v_over_d = session.expected_hz()["V/D"]
    assert v_over_d == pytest.approx(25.0)
    assert fig.linedata[1, 0] == pytest.approx(v_over_d) == fig.linedata[1, 2]
    assert bytes(fig.linename[1]).startswith(b"V/D")
    bin_hz = 1 / session.window_s
    band = f > 10  # above the press transient's low-frequency tail
    assert abs(f[band][np.argmax(logp[band])] - v_over_d) <= bin_hz
    # the raster shows the chosen receptors' spikes: ticks at their times
    raster = session.raster_figure()
    times, spikes, _ = session.window()
    maxpnt = (mujoco.mjMAXLINEPNT - 1) // 3
    for line, r in enumerate(session._raster_rows):
        want = (times[spikes[:, r] > 0] - times[0])[-maxpnt:]
        assert np.allclose(fig_ticks(raster, line), want, atol=1e-6)  # float32 figure data


def fig_ticks(fig: mujoco.MjvFigure, line: int) -> np.ndarray:
    n = fig.linepnt[line]
    pts = fig.linedata[line, : 2 * n].reshape(-1, 2)
    return pts[1::3, 0] if n >= 3 else np.zeros(0)


def test_settings_are_validated():
    with pytest.raises(ValueError, match="force_n = 3 is out of range"):
        SlideSession(ViewSettings(force_n=3))
    with pytest.raises(ValueError, match="texture = 9 is out of range"):
        SlideSession(ViewSettings(texture=9))
    with pytest.raises(FileNotFoundError, match="is not a file"):
        SlideSession(scene="/nonexistent/scene.xml")
    assert dataclasses.asdict(ViewSettings())["nx"] == 48
