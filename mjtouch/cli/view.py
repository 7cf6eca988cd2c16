"""``mjtouch view``: MuJoCo's viewer on a sliding scene, or an offscreen PNG."""

from __future__ import annotations

import argparse
import sys
import textwrap

from mjtouch.cli.types import positive_float

EXAMPLE = """example:
  mjtouch view --texture 1 --speed 0.04
  MUJOCO_GL=egl mjtouch view --offscreen view.png --duration 0.5"""


def add_parser(sub) -> argparse.ArgumentParser:
    from mjtouch.viewer import KEY_HELP, TEXTURES

    p = sub.add_parser(
        "view",
        help="MuJoCo's viewer on a sliding scene: live pressure heatmap, "
        "flashing receptors, raster and stress spectrum",
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=textwrap.fill(
            "Keys: " + KEY_HELP + ". MJCF scenes also "
            "open in plain `python -m mujoco.viewer "
            "--mjcf=FILE`."
        ),
    )
    p.add_argument(
        "scene",
        nargs="?",
        default=None,
        help="an MJCF file with an mjtouch.skin sensor (default: the built-in "
        "sliding scene, whose texture and ridges the keys change)",
    )
    p.add_argument(
        "--force", type=positive_float("--force"), default=0.5, help="normal force (N), default 0.5"
    )
    p.add_argument(
        "--speed",
        type=positive_float("--speed"),
        default=0.025,
        help="sliding speed (m/s), default 0.025",
    )
    p.add_argument(
        "--texture",
        type=int,
        default=0,
        choices=range(len(TEXTURES)),
        help="; ".join(f"{i}: {name}" for i, (name, _) in enumerate(TEXTURES)),
    )
    p.add_argument("--ridges", action=argparse.BooleanOptionalAction, default=True)
    p.add_argument("--nx", type=int, default=48, help="taxels per side, default 48")
    p.add_argument(
        "--dt",
        type=positive_float("--dt"),
        default=1e-3,
        help="simulation timestep (s), default 1e-3",
    )
    p.add_argument(
        "--offscreen",
        metavar="PNG",
        help="no window: simulate --duration seconds and write what the viewer "
        "would show to PNG (needs MUJOCO_GL=egl or osmesa)",
    )
    p.add_argument(
        "--duration",
        type=positive_float("--duration"),
        default=1.0,
        help="simulated seconds before --offscreen renders, default 1",
    )
    return p


def main(args: argparse.Namespace) -> int:
    from mjtouch import viewer

    try:
        settings = viewer.ViewSettings(
            force_n=args.force,
            speed_m_s=args.speed,
            texture=args.texture,
            ridges=args.ridges,
            nx=args.nx,
            timestep_s=args.dt,
        )
        if args.offscreen:
            session = viewer.SlideSession(settings, args.scene)
            session.advance(int(round(args.duration / session.dt)))
            from PIL import Image

            Image.fromarray(session.render()).save(args.offscreen)
            session.close()
            print(f"mjtouch view: wrote {args.offscreen} ({session.status()})")
        else:
            viewer.launch(args.scene, settings)
    except (ValueError, FileNotFoundError) as e:
        print(f"mjtouch: error: {e}", file=sys.stderr)
        return 2
    return 0
