"""Viewer demo: a fingertip sliding over a grating in MuJoCo's viewer.

    python examples/viewer_demo.py                       # a window (needs a display)
    python examples/viewer_demo.py --offscreen frames/ --frames 4 --every 0.05

With a window: MuJoCo's viewer on the sliding scene (``mjtouch.viewer``):
the pad's live pressure heatmap, receptor sites flashing in their class
colour when they spike (SA1 blue, RA green, PC magenta), a spike raster and
the receptor-stress spectrum with V/D and V/lambda marked. Keys: Home/End
force +-0.1 N, Insert/Delete speed +-5 mm/s, Page Down next texture, F9
ridges on/off; the Control sliders work too.

With ``--offscreen DIR``: no window. It presses and slides for ``--settle``
seconds, then writes ``--frames`` PNGs ``--every`` seconds apart of what the
viewer would show, and prints one line per frame. Offscreen rendering needs
EGL or OSMesa; the script picks whichever works (``MUJOCO_GL``, fixed before
mujoco is imported, so it re-runs itself with it set).
"""

from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys


def parse(argv: list[str] | None):
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--force", type=float, default=0.5, help="normal force (N), default 0.5")
    p.add_argument("--speed", type=float, default=0.025, help="sliding speed (m/s), default 0.025")
    p.add_argument(
        "--texture", type=int, default=0, help="0: grating D = 1 mm, 1: 0.6 mm, 2: 2.5 mm, 3: flat"
    )
    p.add_argument("--ridges", action=argparse.BooleanOptionalAction, default=True)
    p.add_argument("--offscreen", metavar="DIR", help="write PNG frames here instead of a window")
    p.add_argument("--frames", type=int, default=4, help="offscreen: frames to write, default 4")
    p.add_argument(
        "--every",
        type=float,
        default=0.05,
        help="offscreen: simulated seconds between frames, default 0.05",
    )
    p.add_argument(
        "--settle",
        type=float,
        default=0.3,
        help="offscreen: simulated seconds before the first frame, default 0.3",
    )
    p.add_argument(
        "--size",
        type=int,
        nargs=2,
        default=(960, 600),
        metavar=("W", "H"),
        help="offscreen: frame size in pixels, default 960 600",
    )
    args = p.parse_args(argv)
    if args.offscreen is not None:
        if not 1 <= args.frames <= 1000:
            p.error(f"--frames {args.frames} is out of range; valid 1 to 1000")
        if not (0 < args.every <= 10 and 0 <= args.settle <= 10):
            p.error("--every must be in (0, 10] s and --settle in [0, 10] s")
        if not (64 <= args.size[0] <= 4096 and 64 <= args.size[1] <= 4096):
            p.error(f"--size {args.size} is out of range; valid 64 to 4096 pixels each")
    return p, args


def offscreen(args) -> int:
    from PIL import Image

    from mjtouch import viewer

    settings = viewer.ViewSettings(
        force_n=args.force, speed_m_s=args.speed, texture=args.texture, ridges=args.ridges
    )
    session = viewer.SlideSession(settings)
    out = pathlib.Path(args.offscreen)
    out.mkdir(parents=True, exist_ok=True)
    session.advance(int(round(args.settle / session.dt)))
    width, height = args.size
    for k in range(args.frames):
        if k:
            session.advance(max(1, int(round(args.every / session.dt))))
        path = out / f"frame_{k:03d}.png"
        Image.fromarray(session.render(width, height)).save(path)
        print(f"t = {session.data.time:.3f} s  {path}  {session.status()}")
    session.close()
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    p, args = parse(argv)
    try:
        if args.offscreen is None:
            from mjtouch import viewer

            viewer.launch(
                None,
                viewer.ViewSettings(
                    force_n=args.force,
                    speed_m_s=args.speed,
                    texture=args.texture,
                    ridges=args.ridges,
                ),
            )
            return 0
        if "MUJOCO_GL" not in os.environ:
            from mjtouch.viewer import offscreen_backend

            backend = offscreen_backend()
            if backend is None:
                p.error(
                    "no offscreen OpenGL backend works here: install EGL (apt-get install "
                    "libegl1 libegl-mesa0) or OSMesa (apt-get install libosmesa6)"
                )
            env = {**os.environ, "MUJOCO_GL": backend, "PYOPENGL_PLATFORM": backend}
            return subprocess.run([sys.executable, __file__, *argv], env=env).returncode
        return offscreen(args)
    except ValueError as e:
        p.error(str(e))


if __name__ == "__main__":
    raise SystemExit(main())
