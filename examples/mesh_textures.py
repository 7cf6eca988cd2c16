"""Textures from mesh files: a Braille-like dot plate and a diamond knurl are
built as meshes with trimesh, exported (STL and PLY, as a CAD tool or a
3D scan would give them), read back with mjtouch.scene.meshes.from_mesh and
slid under the fingertip; a figure shows each surface, the receptor stress
and the spikes.

    python examples/mesh_textures.py [--out DIR] [--plot FILE] [--json]

Braille (Marburg Medium, the common print standard): dots of 1.6 mm base
diameter and 0.5 mm height, 2.5 mm apart within a cell, cells 6 mm apart,
lines 10 mm apart. The knurl: a diamond (45 deg) knurl of 1.0 mm pitch and
0.25 mm depth, pyramids with flat-topped crests cut at 80 % height (worn).
The knurl's pitch along x (1.0 mm / cos 45 deg = 1.41 mm) sets its stress
line V/D; Braille text is not periodic (no V/D).
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import tempfile

import numpy as np

from mjtouch import analysis
from mjtouch.experiments import rollout
from mjtouch.scene import meshes, scenes

LENGTH_M, WIDTH_M = 0.04, 0.016  # plate: the slide and the pad both fit
MESH_GRID_M = 5e-5  # the exported meshes' vertex spacing

# Braille: six-dot cells; the text "mjtouch" in Grade 1 Braille (dots 1-6).
BRAILLE = {
    "m": (1, 3, 4),
    "j": (2, 4, 5),
    "t": (2, 3, 4, 5),
    "o": (1, 3, 5),
    "u": (1, 3, 6),
    "c": (1, 4),
    "h": (1, 2, 5),
}
DOT_BASE_M, DOT_HEIGHT_M, DOT_SPACING_M, CELL_M = 1.6e-3, 0.5e-3, 2.5e-3, 6e-3
KNURL_PITCH_M, KNURL_DEPTH_M = 1.0e-3, 0.25e-3


def braille_heights(x, y, text="mjtouch"):
    """Spherical-cap dots of the text's cells, one line centred on y = 0."""
    X, Y = np.meshgrid(x, y)
    a, h = DOT_BASE_M / 2, DOT_HEIGHT_M
    R = (a * a + h * h) / (2 * h)
    z = np.zeros_like(X)
    x0 = -(len(text) - 1) * CELL_M / 2
    for k, ch in enumerate(text):
        for dot in BRAILLE[ch]:
            col, row = (dot - 1) // 3, (dot - 1) % 3
            cx = x0 + k * CELL_M + (col - 0.5) * DOT_SPACING_M
            cy = (1 - row) * DOT_SPACING_M
            r2 = (X - cx) ** 2 + (Y - cy) ** 2
            z = np.maximum(z, np.sqrt(np.maximum(R * R - r2, 0)) - (R - h))
    return z


def knurl_heights(x, y):
    """Diamond knurl: pyramids between two grooves crossing at +-45 deg."""
    X, Y = np.meshgrid(x, y)
    p = KNURL_PITCH_M

    def tri(s):  # 1 on the crest, 0 in the groove, period p
        return 1 - 2 * np.abs(s / p - np.round(s / p))

    u, v = (X + Y) / math.sqrt(2), (X - Y) / math.sqrt(2)
    return KNURL_DEPTH_M * np.minimum(np.minimum(tri(u), tri(v)), 0.8) / 0.8


SURFACES = {
    "braille": (braille_heights, "stl", None),
    "knurl": (knurl_heights, "ply", KNURL_PITCH_M * math.sqrt(2)),
}


def export_meshes(out: pathlib.Path, grid_m: float = MESH_GRID_M) -> dict[str, pathlib.Path]:
    """Each surface as a closed trimesh solid in a mesh file (in mm, as CAD
    tools write them), vertices every grid_m."""
    x = np.arange(-LENGTH_M / 2, LENGTH_M / 2 + grid_m / 2, grid_m)
    y = np.arange(-WIDTH_M / 2, WIDTH_M / 2 + grid_m / 2, grid_m)
    paths = {}
    for name, (heights, ext, _) in SURFACES.items():
        mesh = meshes.heightmap_mesh(x, y, heights(x, y))
        mesh.apply_scale(1e3)
        paths[name] = out / f"{name}.{ext}"
        mesh.export(paths[name])
    return paths


def run(
    name: str,
    path: pathlib.Path,
    duration_s: float,
    nx: int,
    pitch_m: float,
    speed_m_s: float,
    resolution_m: float = 2.5e-5,
) -> dict:
    mt = meshes.from_mesh(path, scale=1e-3, resolution_m=resolution_m)
    tip = scenes.Fingertip(nx=nx, pitch_m=pitch_m)
    protocol = scenes.Protocol(force_n=0.5, speed_m_s=speed_m_s)
    res = rollout.run_slide(tip, mt.texture(), protocol, duration_s=duration_s)
    w = res.window()
    f, p = analysis.stress_spectrum(res.stress[w], res.dt)
    return {
        "mesh": mt,
        "result": res,
        "window": w,
        "rates_hz": analysis.rates_hz(res.spikes[w], res.dt, res.layout.classes),
        "peaks_hz": analysis.spectral_peaks(f, p, n=3, fmin_hz=3.0, fmax_hz=500.0),
        "expected_hz": speed_m_s / SURFACES[name][2] if SURFACES[name][2] else None,
        "relief_m": mt.relief_m,
        "cells": list(mt.heights.shape),
        "fft_bin_hz": float(f[1] - f[0]),
    }


def plot(path, runs: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, len(runs), figsize=(6 * len(runs), 9), squeeze=False)
    colors = {"SA1": "tab:blue", "RA": "tab:orange", "PC": "tab:green"}
    for k, (name, r) in enumerate(runs.items()):
        mt, res, w = r["mesh"], r["result"], r["window"]
        ext = [
            -mt.length_m / 2 * 1e3,
            mt.length_m / 2 * 1e3,
            -mt.width_m / 2 * 1e3,
            mt.width_m / 2 * 1e3,
        ]
        im = axes[0, k].imshow(mt.heights * 1e3, origin="lower", extent=ext, cmap="gray")
        fig.colorbar(im, ax=axes[0, k], label="height (mm)")
        axes[0, k].set(
            title=f"{name} (from {pathlib.Path(mt.source).name})", xlabel="x (mm)", ylabel="y (mm)"
        )
        t = res.time_s[w]
        stress = res.stress[w]
        for c in ("SA1", "RA", "PC"):  # the most modulated receptor of each class
            idx = np.nonzero(res.layout.classes == c)[0]
            if len(idx):
                i = idx[np.argmax(stress[:, idx].std(0))]
                axes[1, k].plot(
                    t, stress[:, i] / 1e3, c=colors[c], lw=0.8, label=f"{c} receptor {i}"
                )
        axes[1, k].set(xlabel="time (s)", ylabel="receptor stress (kPa)")
        axes[1, k].legend(fontsize=8)
        sp = res.spikes[w]
        for rec in range(sp.shape[1]):
            ts = t[sp[:, rec] > 0]
            axes[2, k].plot(ts, np.full_like(ts, rec), "|", ms=2, c=colors[res.layout.classes[rec]])
        axes[2, k].set(xlabel="time (s)", ylabel="receptor (SA1, RA, PC)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", help="where to write the mesh files (default: a temp dir)")
    ap.add_argument("--duration", type=float, default=0.6, help="sliding time (s)")
    ap.add_argument("--speed", type=float, default=0.025, help="sliding speed (m/s)")
    ap.add_argument("--nx", type=int, default=96)
    ap.add_argument("--pitch", type=float, default=1.25e-4)
    ap.add_argument(
        "--mesh-grid",
        type=float,
        default=MESH_GRID_M,
        help="vertex spacing of the exported meshes (m)",
    )
    ap.add_argument(
        "--resolution",
        type=float,
        default=2.5e-5,
        help="height-field cell of the textures read back (m)",
    )
    ap.add_argument("--plot", metavar="FILE", help="PNG of the surfaces, stress and spikes")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(args.out or tmp)
        out.mkdir(parents=True, exist_ok=True)
        paths = export_meshes(out, args.mesh_grid)
        runs = {
            name: run(name, p, args.duration, args.nx, args.pitch, args.speed, args.resolution)
            for name, p in paths.items()
        }
        if args.plot:
            plot(args.plot, runs)
    summary = {
        name: {k: v for k, v in r.items() if k not in ("mesh", "result", "window")}
        for name, r in runs.items()
    }
    if args.json:
        print(json.dumps(summary))
        return 0
    for name, r in summary.items():
        vd = f"{r['expected_hz']:.1f} Hz" if r["expected_hz"] else "-"
        print(
            f"{name:8s} relief {r['relief_m'] * 1e3:.3f} mm on {r['cells']} cells; V/D = "
            f"{vd}, stress peaks "
            + ", ".join(f"{x:.1f}" for x in r["peaks_hz"])
            + " Hz; rates "
            + "  ".join(f"{c} {v:.1f}" for c, v in r["rates_hz"].items())
            + " Hz"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
