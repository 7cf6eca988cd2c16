"""Quick start: the README's Python snippet as a script.

    python examples/quickstart.py                      # README defaults (a few seconds)
    python examples/quickstart.py --nx 48 --pitch 2e-4 --dt 5e-4 --duration 0.3   # fast

Builds the default scene (a ridged fingertip pressed with 0.5 N onto a
grating of period D = 1 mm), slides it at V = 25 mm/s, and prints the SA1 /
RA / PC firing rates and the strongest spectral peaks of the receptor
stress, next to the expected lines V/D (the grating) and V/lambda (the
fingerprint ridges). The strongest peak is expected at V/D, within one FFT
bin (the spectrum covers the steady sliding after settle_s).
"""

from __future__ import annotations

import argparse
import json

from mjtouch import analysis
from mjtouch.experiments import rollout
from mjtouch.scene import scenes


def run(
    duration_s: float = 1.0,
    nx: int = 128,
    pitch_m: float = 1e-4,
    dt_s: float = 1e-4,
    speed_m_s: float = 0.025,
    period_m: float = 1e-3,
    force_n: float = 0.5,
) -> dict:
    tip = scenes.Fingertip(nx=nx, pitch_m=pitch_m)
    res = rollout.run_slide(
        tip,
        scenes.Texture(period_m=period_m),
        scenes.Protocol(force_n=force_n, speed_m_s=speed_m_s, timestep_s=dt_s),
        duration_s=duration_s,
    )
    w = res.window()  # steady sliding: from slide start + 0.1 s
    f, p = analysis.stress_spectrum(res.stress[w], res.dt)
    peaks = analysis.spectral_peaks(f, p)
    bin_hz = float(f[1] - f[0])
    v_over_d = speed_m_s / period_m
    return {
        "rates_hz": analysis.rates_hz(res.spikes[w], res.dt, res.layout.classes),
        "peaks_hz": [float(x) for x in peaks],
        "v_over_d_hz": v_over_d,
        "v_over_lambda_hz": speed_m_s / tip.ridge_pitch_m,
        "fft_bin_hz": bin_hz,
        "peak_at_v_over_d": bool(peaks) and abs(peaks[0] - v_over_d) <= bin_hz,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--duration", type=float, default=1.0, help="sliding time (s), default 1")
    p.add_argument("--nx", type=int, default=128, help="taxels per side, default 128")
    p.add_argument("--pitch", type=float, default=1e-4, help="taxel pitch (m), default 1e-4")
    p.add_argument("--dt", type=float, default=1e-4, help="timestep (s), default 1e-4")
    p.add_argument("--speed", type=float, default=0.025, help="sliding speed V (m/s)")
    p.add_argument("--period", type=float, default=1e-3, help="grating period D (m)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    if not 0.15 <= args.duration <= 10:
        p.error(
            f"--duration {args.duration} is out of range; valid [0.15, 10] s (0.1 s "
            "settles before the spectrum window)"
        )
    try:
        r = run(args.duration, args.nx, args.pitch, args.dt, args.speed, args.period)
    except ValueError as e:
        p.error(str(e))
    if args.json:
        print(json.dumps(r))
        return 0
    print("firing rates (Hz): " + "  ".join(f"{c} {v:.1f}" for c, v in r["rates_hz"].items()))
    print(
        f"expected lines: V/D = {r['v_over_d_hz']:.2f} Hz, V/lambda = "
        f"{r['v_over_lambda_hz']:.2f} Hz (FFT bin {r['fft_bin_hz']:.2f} Hz)"
    )
    print(
        "stress spectral peaks (Hz, strongest first): "
        + ", ".join(f"{x:.2f}" for x in r["peaks_hz"])
    )
    print(f"strongest peak at V/D within one bin: {'yes' if r['peak_at_v_over_d'] else 'NO'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
