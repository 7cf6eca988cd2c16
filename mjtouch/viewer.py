"""Interactive viewer: ``python -m mjtouch view [scene]``.

Opens MuJoCo's viewer (``mujoco.viewer.launch_passive``) on a sliding scene:
the fingertip scans back and forth over a plate. The skin plugin draws the
live pressure heatmap and flashes receptor sites when they spike (its own
visualize callback, so plain ``python -m mujoco.viewer`` shows those too);
this module adds live figures (the heatmap's colour scale in kPa, a spike
raster of a few receptors per class and the receptor-stress spectrum with V/D
and V/lambda marked), a status line, and keys:

| key | action |
|---|---|
| Home / End | normal force +0.1 N / -0.1 N |
| Insert / Delete | sliding speed +5 mm/s / -5 mm/s |
| Page Down | next texture (gratings D = 1, 0.6, 2.5 mm, flat) |
| F9 | fingerprint ridges on / off |

The right panel's Control sliders (``slide`` speed, ``press`` = -force) work
as well. Texture and ridges rebuild the scene.

:class:`SlideSession` holds the scene, the rolling records and the figures
without any window; :meth:`SlideSession.render` draws what the viewer shows
(scene, figures, status) offscreen, for tests and pictures
(``MUJOCO_GL=egl`` or ``osmesa``).
"""

from __future__ import annotations

import dataclasses
import pathlib
import queue
import time

import mujoco
import numpy as np

from mjtouch.analysis import signals
from mjtouch.scene import scenes
from mjtouch.scene.sensor import CLASSES, SkinLayout

# GLFW key codes (MuJoCo's mjKEY_*) that MuJoCo's viewer leaves unbound.
KEY_HOME, KEY_END, KEY_INSERT, KEY_DELETE, KEY_PAGE_DOWN, KEY_F9 = 268, 269, 260, 261, 267, 298
KEY_HELP = "Home/End force +-0.1 N   Ins/Del speed +-5 mm/s   PgDn texture   F9 ridges"

TEXTURES: tuple[tuple[str, scenes.Texture], ...] = (
    ("grating D = 1 mm", scenes.Texture(period_m=1.0e-3)),
    ("grating D = 0.6 mm", scenes.Texture(period_m=0.6e-3)),
    ("grating D = 2.5 mm", scenes.Texture(period_m=2.5e-3)),
    ("flat", scenes.Texture(kind="flat")),
)
CLASS_RGB = {"SA1": (0.15, 0.45, 1.0), "RA": (0.1, 0.9, 0.25), "PC": (0.95, 0.2, 0.95)}
# The skin's heatmap (plugin/mujoco/visualize.cc): pressure averaged over
# tiles of at most this many per side, coloured by heat_rgb(tile / peak tile).
HEATMAP_TILES_PER_SIDE = 32
SCALE_STEPS = 24  # colour bands of the scale figure
FORCE_RANGE_N = (0.1, 2.0)
SPEED_RANGE_M_S = (0.0, 0.1)
SCAN_HALF_M = 0.025  # the finger turns round this far from the plate's centre


def heat_rgb(u: np.ndarray | float) -> np.ndarray:
    """The heatmap's colour at pressure u x the frame's peak (visualize.cc
    HeatColor): dark red, red, orange, yellow, near white."""
    v = 0.2 + 0.8 * np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return np.stack(
        [np.clip(3 * v, 0, 1), np.clip(3 * v - 1, 0, 1), np.clip(3 * v - 2, 0, 1)], axis=-1
    )


def heatmap_peak_pa(pressure: np.ndarray) -> float:
    """The peak the heatmap is scaled to: the largest tile mean of the nx x nx
    pressure field (Pa), tiled as the skin draws it."""
    n = pressure.shape[0]
    b = -(-n // HEATMAP_TILES_PER_SIDE)
    nt = -(-n // b)
    padded = np.full((nt * b, nt * b), np.nan)
    padded[:n, :n] = pressure
    return float(np.nanmax(np.nanmean(padded.reshape(nt, b, nt, b), axis=(1, 3))))


@dataclasses.dataclass
class ViewSettings:
    force_n: float = 0.5
    speed_m_s: float = 0.025
    texture: int = 0  # index into TEXTURES
    ridges: bool = True
    nx: int = 48
    pitch_m: float = 2e-4
    timestep_s: float = 1e-3

    def validate(self) -> None:
        if not FORCE_RANGE_N[0] <= self.force_n <= FORCE_RANGE_N[1]:
            raise ValueError(f"force_n = {self.force_n} is out of range; valid {FORCE_RANGE_N} N")
        if not SPEED_RANGE_M_S[0] <= self.speed_m_s <= SPEED_RANGE_M_S[1]:
            raise ValueError(
                f"speed_m_s = {self.speed_m_s} is out of range; valid {SPEED_RANGE_M_S} m/s"
            )
        if not 0 <= self.texture < len(TEXTURES):
            raise ValueError(
                f"texture = {self.texture} is out of range; valid 0 to {len(TEXTURES) - 1}"
            )
        if not 1e-4 <= self.timestep_s <= 2e-3:
            raise ValueError(
                f"timestep_s = {self.timestep_s} is out of range; valid [1e-4, 2e-3] s"
            )


class SlideSession:
    """A sliding scene with rolling records of spikes and stress.

    ``scene``: None for the built-in scene (settings apply), or an MJCF file
    with an ``mjtouch.skin`` sensor (its own texture and ridges; the force and
    speed keys drive actuators named ``press`` and ``slide`` if present).
    """

    def __init__(
        self,
        settings: ViewSettings | None = None,
        scene: str | pathlib.Path | None = None,
        window_s: float = 0.5,
        raster_per_class: int = 5,
    ):
        self.settings = settings or ViewSettings()
        self.settings.validate()
        self.scene_path = pathlib.Path(scene) if scene is not None else None
        if self.scene_path is not None and not self.scene_path.is_file():
            raise FileNotFoundError(f"scene {str(self.scene_path)!r} is not a file")
        if not 0.05 <= window_s <= 5:
            raise ValueError(f"window_s = {window_s} is out of range; valid [0.05, 5] s")
        self.window_s = window_s
        self.raster_per_class = raster_per_class
        self.message = ""
        self.build()

    # ----- scene -----------------------------------------------------------
    def build(self) -> None:
        s = self.settings
        if self.scene_path is None:
            # interactive preset: exact (folded) stress, as cheap as the tree
            # the pressure output gives the colour scale its units
            tip = scenes.Fingertip(
                nx=s.nx,
                pitch_m=s.pitch_m,
                ridges=s.ridges,
                skin={"outputs": "spikes stress force pressure"},
            )
            texture = dataclasses.replace(TEXTURES[s.texture][1])
            protocol = scenes.Protocol(
                force_n=s.force_n, speed_m_s=s.speed_m_s, timestep_s=s.timestep_s
            )
            self.model = scenes.scene_spec(
                tip, texture, protocol, model_name="mjtouch_view"
            ).compile()
        else:
            self.model = mujoco.MjModel.from_xml_path(str(self.scene_path))
        self.data = mujoco.MjData(self.model)
        self.layout = SkinLayout.from_model(self.model)
        m = self.model
        self._act = {
            name: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
            for name in ("slide", "press")
        }
        self._pad = self.layout_pad_geom()
        self._direction = 1.0
        self.dt = m.opt.timestep
        n = max(8, int(round(self.window_s / self.dt)))
        nrec = len(self.layout.classes)
        self._spikes = np.zeros((n, nrec), np.float32)
        self._stress = np.zeros((n, nrec), np.float32)
        self._time = np.full(n, np.nan)
        self._count = 0
        # A few receptors per class, spread from the pole (first) to the rim.
        rows = []
        for c in CLASSES:
            members = np.nonzero(self.layout.classes == c)[0]
            k = min(self.raster_per_class, len(members))
            rows.append(
                members[np.unique(np.linspace(0, len(members) - 1, k).round().astype(int))]
                if k
                else members
            )
        self._raster_rows = np.concatenate(rows)
        self._apply_ctrl()

    def _apply_ctrl(self) -> None:
        d = self.data
        if self._act["press"] >= 0:
            d.ctrl[self._act["press"]] = -self.settings.force_n
        if self._act["slide"] >= 0:
            d.ctrl[self._act["slide"]] = self._direction * self.settings.speed_m_s

    def _read_ctrl(self) -> None:
        """Take over values set with the viewer's Control sliders."""
        d, s = self.data, self.settings
        if self._act["press"] >= 0:
            s.force_n = float(np.clip(-d.ctrl[self._act["press"]], *FORCE_RANGE_N))
        if self._act["slide"] >= 0:
            v = float(d.ctrl[self._act["slide"]])
            if v != 0:
                self._direction = 1.0 if v > 0 else -1.0
            s.speed_m_s = float(np.clip(abs(v), *SPEED_RANGE_M_S))

    @property
    def is_builtin(self) -> bool:
        return self.scene_path is None

    @property
    def texture_name(self) -> str:
        return TEXTURES[self.settings.texture][0] if self.is_builtin else self.scene_path.name

    def expected_hz(self) -> dict[str, float | None]:
        """Expected stress lines: V/D of the grating and V/lambda of the ridges."""
        s = self.settings
        v = s.speed_m_s
        out: dict[str, float | None] = {"V/D": None, "V/lambda": None}
        if self.is_builtin:
            tex = TEXTURES[s.texture][1]
            if tex.kind == "grating" and v > 0:
                out["V/D"] = v / tex.period_m
            if s.ridges and v > 0:
                out["V/lambda"] = v / scenes.Fingertip().ridge_pitch_m
        return out

    # ----- keys ------------------------------------------------------------
    def key(self, keycode: int) -> bool:
        """Apply a key; returns True if the scene was rebuilt."""
        s = self.settings
        if keycode in (KEY_HOME, KEY_END):
            step = 0.1 if keycode == KEY_HOME else -0.1
            s.force_n = float(np.clip(round(s.force_n + step, 3), *FORCE_RANGE_N))
            self._apply_ctrl()
        elif keycode in (KEY_INSERT, KEY_DELETE):
            step = 0.005 if keycode == KEY_INSERT else -0.005
            s.speed_m_s = float(np.clip(round(s.speed_m_s + step, 4), *SPEED_RANGE_M_S))
            self._apply_ctrl()
        elif keycode in (KEY_PAGE_DOWN, KEY_F9):
            if not self.is_builtin:
                self.message = "texture and ridges are fixed by the scene file"
                return False
            if keycode == KEY_PAGE_DOWN:
                s.texture = (s.texture + 1) % len(TEXTURES)
            else:
                s.ridges = not s.ridges
            self.build()
            return True
        return False

    # ----- simulation ------------------------------------------------------
    def advance(self, nstep: int) -> None:
        """Step the physics nstep times, scanning back and forth, recording."""
        m, d, lay = self.model, self.data, self.layout
        self._read_ctrl()
        sp = lay.blocks["spikes"] if "spikes" in lay.blocks else None
        st = lay.blocks["stress"] if "stress" in lay.blocks else None
        adr = lay.sensor_adr
        n = len(self._time)
        for _ in range(nstep):
            if self.is_builtin:
                x = d.geom_xpos[self._pad, 0]
                if x > SCAN_HALF_M and self._direction > 0:
                    self._direction = -1.0
                elif x < -SCAN_HALF_M and self._direction < 0:
                    self._direction = 1.0
                self._apply_ctrl()
            mujoco.mj_step(m, d)
            k = self._count % n
            self._time[k] = d.time
            if sp is not None:
                self._spikes[k] = d.sensordata[adr + sp.start : adr + sp.stop]
            if st is not None:
                self._stress[k] = d.sensordata[adr + st.start : adr + st.stop]
            self._count += 1

    def window(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The recorded window, oldest first: time, spikes, stress."""
        n = len(self._time)
        if self._count < n:
            sl = slice(0, self._count)
            return self._time[sl], self._spikes[sl], self._stress[sl]
        order = np.roll(np.arange(n), -(self._count % n))
        return self._time[order], self._spikes[order], self._stress[order]

    def spectrum(self) -> tuple[np.ndarray, np.ndarray]:
        """Stress power spectrum over the window (all receptors, incoherent)."""
        _, _, stress = self.window()
        if len(stress) < 8:
            return np.zeros(1), np.zeros(1)
        return signals.stress_spectrum(stress.astype(np.float64), self.dt)

    def rates_hz(self) -> dict[str, float]:
        _, spikes, _ = self.window()
        if len(spikes) == 0:
            return {c: 0.0 for c in CLASSES}
        return signals.rates_hz(spikes, self.dt, self.layout.classes)

    # ----- figures ---------------------------------------------------------
    def raster_figure(self, fig: mujoco.MjvFigure | None = None) -> mujoco.MjvFigure:
        """Spike raster: one row per receptor (a few per class, in class
        colours), a tick per spike over the window."""
        fig = fig or mujoco.MjvFigure()
        mujoco.mjv_defaultFigure(fig)
        fig.title = "spike raster"
        fig.xlabel = "time (s)"
        fig.flg_extend = 0
        fig.gridsize = [6, 2]
        fig.flg_ticklabel = [1, 0]
        fig.xformat = "%.2f"
        fig.linewidth = 1.5
        fig.figurergba = fig.panergba = (0.0, 0.0, 0.0, 0.85)
        t, spikes, _ = self.window()
        t0 = t[0] if len(t) else 0.0
        # head room above the rows for the legend
        fig.range = [[0.0, self.window_s], [-0.5, len(self._raster_rows) + 7.5]]
        maxpnt = (mujoco.mjMAXLINEPNT - 1) // 3
        for line, r in enumerate(self._raster_rows[: mujoco.mjMAXLINE]):
            ts = (t[spikes[:, r] > 0] - t0)[-maxpnt:]
            y = float(line)
            pts = np.zeros((max(1, 3 * len(ts)), 2))
            if len(ts):
                pts[0::3, 0] = ts
                pts[1::3, 0] = ts
                pts[2::3, 0] = ts
                pts[0::3, 1] = y
                pts[1::3, 1] = y + 0.6
                pts[2::3, 1] = y
            else:
                pts[0] = [0.0, y]
            fig.linedata[line, : 2 * len(pts)] = pts.ravel()
            fig.linepnt[line] = len(pts)
            cls = self.layout.classes[r]
            fig.linergb[line] = CLASS_RGB[cls]
            # the legend names each class once, on its first row
            first = line == 0 or self.layout.classes[self._raster_rows[line - 1]] != cls
            fig.linename[line] = cls if first else ""
        fig.flg_legend = 1
        return fig

    def peak_pressure_pa(self) -> float | None:
        """The pressure at the top of the heatmap's colour scale (Pa), or None
        if the skin does not output its pressure field."""
        lay = self.layout
        if "pressure" not in lay.blocks:
            return None
        p = lay.block(self.data.sensordata, "pressure").reshape(lay.nx, lay.nx)
        return heatmap_peak_pa(p)

    def scale_figure(self, fig: mujoco.MjvFigure | None = None) -> mujoco.MjvFigure:
        """The heatmap's colour scale: bands of the heat ramp along the x axis,
        from 0 to the frame's peak tile pressure in kPa (or to 1 = the peak
        when the pressure output is off). Tiles under 2% of the peak are not
        drawn."""
        fig = fig or mujoco.MjvFigure()
        mujoco.mjv_defaultFigure(fig)
        peak = self.peak_pressure_pa()
        top = peak / 1e3 if peak else 1.0
        fig.title = "pressure (kPa)" if peak else "pressure / frame peak"
        fig.flg_extend = 0
        fig.flg_ticklabel = [1, 0]
        fig.gridsize = [5, 2]
        fig.xformat = "%.0f" if top >= 10 else "%.1f"
        fig.figurergba = fig.panergba = (0.0, 0.0, 0.0, 0.85)
        fig.range = [[0.0, top], [0.0, 1.0]]
        fig.linewidth = 24.0
        for k in range(SCALE_STEPS):
            x0, x1 = top * k / SCALE_STEPS, top * (k + 1) / SCALE_STEPS
            fig.linedata[k, :4] = [x0, 0.5, x1, 0.5]
            fig.linepnt[k] = 2
            fig.linergb[k] = heat_rgb((k + 0.5) / SCALE_STEPS)
        return fig

    def spectrum_figure(
        self, fig: mujoco.MjvFigure | None = None, fmax_hz: float = 300.0
    ) -> mujoco.MjvFigure:
        """log10 stress power vs frequency, with V/D and V/lambda marked."""
        fig = fig or mujoco.MjvFigure()
        mujoco.mjv_defaultFigure(fig)
        fig.title = "receptor stress spectrum, log10 Pa^2"
        fig.xlabel = "frequency (Hz)"
        fig.flg_legend = 1
        fig.figurergba = fig.panergba = (0.0, 0.0, 0.0, 0.85)
        f, p = self.spectrum()
        sel = (f > 0) & (f <= fmax_hz)
        f, logp = f[sel], np.log10(np.maximum(p[sel], 1e-12))
        if len(f) > mujoco.mjMAXLINEPNT:
            f, logp = f[: mujoco.mjMAXLINEPNT], logp[: mujoco.mjMAXLINEPNT]
        lo, hi = (float(logp.min()), float(logp.max())) if len(f) else (0.0, 1.0)
        if hi <= lo:
            hi = lo + 1.0
        fig.range = [[0.0, fmax_hz], [lo, hi]]
        fig.flg_extend = 0
        fig.linedata[0, : 2 * len(f)] = np.column_stack([f, logp]).ravel()
        fig.linepnt[0] = len(f)
        fig.linergb[0] = (1.0, 1.0, 1.0)
        fig.linename[0] = "stress"
        marks = [("V/D", (1.0, 0.3, 0.2)), ("V/lambda", (0.2, 1.0, 0.4))]
        expected = self.expected_hz()
        line = 1
        for name, rgb in marks:
            v = expected[name]
            if v is None or v > fmax_hz:
                continue
            fig.linedata[line, :4] = [v, lo, v, hi]
            fig.linepnt[line] = 2
            fig.linergb[line] = rgb
            fig.linename[line] = f"{name} {v:.1f} Hz"
            line += 1
        return fig

    def status(self) -> str:
        s = self.settings
        r = self.rates_hz()
        return (
            f"F = {s.force_n:.2f} N   V = {s.speed_m_s * 1e3:.0f} mm/s   "
            f"{self.texture_name}   ridges {'on' if s.ridges else 'off'}   "
            + "   ".join(f"{c} {r[c]:.0f} Hz" for c in CLASSES)
            + (f"   ({self.message})" if self.message else "")
        )

    # ----- offscreen -------------------------------------------------------
    def camera(self) -> mujoco.MjvCamera:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        cam.trackbodyid = max(0, self.model.geom_bodyid[self.layout_pad_geom()])
        cam.distance, cam.elevation, cam.azimuth = 0.04, -50.0, 120.0
        return cam

    def layout_pad_geom(self) -> int:
        return int(self.model.sensor_objid[self.layout.sensor_id])

    def render(
        self,
        width: int = 960,
        height: int = 600,
        figures: bool = True,
        option: mujoco.MjvOption | None = None,
    ) -> np.ndarray:
        """What the viewer shows (scene with the skin's drawing, figures on the
        right, status line), rendered offscreen: (height, width, 3) uint8."""
        if self._gl is None or self._gl_size != (width, height):
            self.close()
            from mujoco.gl_context import GLContext

            self._gl = GLContext(width, height)
            self._gl.make_current()
            self.model.vis.global_.offwidth = max(self.model.vis.global_.offwidth, width)
            self.model.vis.global_.offheight = max(self.model.vis.global_.offheight, height)
            self._con = mujoco.MjrContext(self.model, mujoco.mjtFontScale.mjFONTSCALE_100)
            self._scn = mujoco.MjvScene(self.model, maxgeom=20000)
            self._gl_size = (width, height)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        self._gl.make_current()
        opt = option or mujoco.MjvOption()
        mujoco.mjv_updateScene(
            self.model,
            self.data,
            opt,
            mujoco.MjvPerturb(),
            self.camera(),
            mujoco.mjtCatBit.mjCAT_ALL,
            self._scn,
        )
        full = mujoco.MjrRect(0, 0, width, height)
        mujoco.mjr_render(full, self._scn, self._con)
        if figures:
            # inside the frame with a margin, so titles and labels are not cut
            margin = 8
            fw, fh = width // 3 - margin, height // 2 - 20 - margin
            x = width - fw - margin
            mujoco.mjr_figure(
                mujoco.MjrRect(x, fh + 20 + margin, fw, fh), self.raster_figure(), self._con
            )
            mujoco.mjr_figure(mujoco.MjrRect(x, 20, fw, fh), self.spectrum_figure(), self._con)
            sw, sh = width // 3, 90
            mujoco.mjr_figure(
                mujoco.MjrRect(margin, height - sh - margin, sw, sh), self.scale_figure(), self._con
            )
            mujoco.mjr_overlay(
                mujoco.mjtFont.mjFONT_NORMAL,
                mujoco.mjtGridPos.mjGRID_BOTTOMLEFT,
                full,
                self.status(),
                "",
                self._con,
            )
        rgb = np.empty((height, width, 3), np.uint8)
        mujoco.mjr_readPixels(rgb, None, full, self._con)
        return np.flipud(rgb).copy()

    _gl = None
    _gl_size = None

    def close(self) -> None:
        if self._gl is not None:
            self._con.free()
            self._gl.free()
            self._gl = None


def launch(scene: str | None = None, settings: ViewSettings | None = None) -> None:
    """Open MuJoCo's viewer on the session and run it in real time until closed."""
    import mujoco.viewer

    session = SlideSession(settings, scene)
    keys: queue.Queue[int] = queue.Queue()
    handle = mujoco.viewer.launch_passive(session.model, session.data, key_callback=keys.put)
    _set_camera(handle.cam, session)
    raster, spectrum, scale = mujoco.MjvFigure(), mujoco.MjvFigure(), mujoco.MjvFigure()
    last_figure = 0.0
    frame_s = 1 / 60
    try:
        while handle.is_running():
            t_frame = time.perf_counter()
            rebuilt = False
            while not keys.empty():
                rebuilt |= session.key(keys.get())
            if rebuilt:
                sim = handle._get_sim()  # mujoco 4.0 passive viewer: swap in the new model
                if sim is None:
                    break
                sim.load(session.model, session.data, "")
                _set_camera(handle.cam, session)
            with handle.lock():
                session.advance(max(1, int(round(frame_s / session.dt))))
            handle.sync()
            if t_frame - last_figure > 0.2:
                last_figure = t_frame
                vp = handle.viewport
                if vp is not None and vp.width > 0:
                    fw, fh = vp.width // 3, vp.height // 3
                    handle.set_figures(
                        [
                            (
                                mujoco.MjrRect(vp.left + vp.width - fw, vp.bottom + fh, fw, fh),
                                session.raster_figure(raster),
                            ),
                            (
                                mujoco.MjrRect(vp.left + vp.width - fw, vp.bottom, fw, fh),
                                session.spectrum_figure(spectrum),
                            ),
                            (
                                mujoco.MjrRect(
                                    vp.left + vp.width - fw, vp.bottom + 2 * fh, fw, fh // 2
                                ),
                                session.scale_figure(scale),
                            ),
                        ]
                    )
                handle.set_texts(
                    [
                        (None, mujoco.mjtGridPos.mjGRID_BOTTOMLEFT, session.status(), ""),
                        (None, mujoco.mjtGridPos.mjGRID_TOPRIGHT, KEY_HELP, ""),
                    ]
                )
            slack = frame_s - (time.perf_counter() - t_frame)
            if slack > 0:
                time.sleep(slack)
    finally:
        handle.close()


def _set_camera(cam: mujoco.MjvCamera, session: SlideSession) -> None:
    ref = session.camera()
    cam.type, cam.trackbodyid = ref.type, ref.trackbodyid
    cam.distance, cam.elevation, cam.azimuth = ref.distance, ref.elevation, ref.azimuth


def offscreen_backend() -> str | None:
    """The first offscreen OpenGL backend (``MUJOCO_GL``) that works here:
    egl, then osmesa; None if neither does. Probed in subprocesses, since
    the backend is fixed when mujoco is imported."""
    import os
    import subprocess
    import sys

    probe = (
        "import mujoco; m = mujoco.MjModel.from_xml_string('<mujoco/>'); "
        "r = mujoco.Renderer(m, 8, 8); r.render(); print('ok')"
    )
    for backend in ("egl", "osmesa"):
        env = {**os.environ, "MUJOCO_GL": backend, "PYOPENGL_PLATFORM": backend}
        try:
            out = subprocess.run(
                [sys.executable, "-c", probe], env=env, capture_output=True, text=True, timeout=120
            )
        except subprocess.TimeoutExpired:
            continue
        if out.returncode == 0 and out.stdout.strip().endswith("ok"):
            return backend
    return None
