"""How far each pressure model is from Hertz (a sphere pad on a flat plate).

    python examples/pressure_ladder.py [--radius 0.02] [--force 0.5]

For each `pressure` model (contacts, winkler, elastic) the skin is a
homogeneous half-space (E = 80 kPa, nu = 0.48), 96 x 96 taxels at 32 per
Hertz contact radius; MuJoCo presses the sphere with the set force until it
settles. Prints the relative errors of peak pressure, contact radius (second
moment of the pressure) and indentation against mjtouch.analysis.reference_solutions.Hertz.
"""

from __future__ import annotations

import argparse

import mujoco

from mjtouch.analysis import reference_solutions
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout


def ladder(radius_m: float = 0.02, force_n: float = 0.5, steps: int = 1500) -> dict:
    h = reference_solutions.Hertz(load_n=force_n, radius_m=radius_m, young_pa=80e3, poisson=0.48)
    pitch, n = h.contact_radius_m / 32, 96
    out = {}
    for model in ("contacts", "winkler", "elastic"):
        skin = dict(
            nx=n,
            pitch=pitch,
            ridges="false",
            pressure=model,
            skin="halfspace",
            poisson=h.poisson,
            outputs="force pressure",
        )
        if model == "elastic":
            skin.update(young=h.young_pa, tolerance=1e-8)
        m = scenes.sphere_press_spec(radius_m, skin).compile()
        d = mujoco.MjData(m)
        layout = SkinLayout.from_model(m)
        d.ctrl[0] = force_n
        for _ in range(steps):
            mujoco.mj_step(m, d)
        force = layout.block(d.sensordata, "force")
        p = layout.block(d.sensordata, "pressure").reshape(n, n)
        out[model] = reference_solutions.hertz_errors(h, p, pitch, force[3])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--radius", type=float, default=0.02, help="sphere radius (m)")
    ap.add_argument("--force", type=float, default=0.5, help="load (N)")
    args = ap.parse_args()
    print(f"{'model':9s} {'peak':>10s} {'radius':>10s} {'indentation':>12s}  (relative to Hertz)")
    for model, e in ladder(args.radius, args.force).items():
        print(f"{model:9s} {e['peak']:+10.2e} {e['radius']:+10.2e} {e['indentation']:+12.2e}")


if __name__ == "__main__":
    main()
