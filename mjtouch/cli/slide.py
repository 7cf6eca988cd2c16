"""``mjtouch slide``: its options are the fields of
:class:`mjtouch.experiments.slide.SlideParams`."""

from __future__ import annotations

import argparse
import json
import sys

from mjtouch import progress
from mjtouch.experiments import slide

EXAMPLE = """example:
  mjtouch slide --texture random --speed 0.05 --force 0.5 --duration 0.5 --nx 64
  mjtouch slide --json --no-ridges --period 0.6e-3   (one JSON object)"""


def field_type(name: str, label: str):
    """An argparse type parsing and checking one SlideParams field (argparse
    names the option before the message)."""

    def parse(token: str):
        try:
            return slide.parse(name, token, label)
        except ValueError as e:
            msg = str(e).removeprefix(f"{label} = ").removeprefix(f"{label} ")
            raise argparse.ArgumentTypeError(msg) from None

    return parse


def add_field_options(p: argparse.ArgumentParser) -> None:
    """One option per SlideParams field (dest: the field name)."""
    for f in slide.fields():
        m, opt = f.metadata, slide.flag(f)
        kw = {"dest": f.name, "default": f.default, "help": slide.describe(f)}
        if m["kind"] == "bool":
            p.add_argument(opt, action=argparse.BooleanOptionalAction, **kw)
        elif m["choices"] is not None:
            p.add_argument(opt, choices=m["choices"], **kw)
        else:
            metavar = m["metavar"] or opt[2:].replace("-", "_").upper()
            p.add_argument(opt, type=field_type(f.name, opt), metavar=metavar, **kw)


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "slide",
        help="ridged fingertip pressed on a plate and slid; prints "
        "spike rates and stress spectral peaks vs V/D and V/lambda",
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_field_options(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="FILE", help="write a PNG of the spectrum and raster")
    progress.add_argument(p)
    return p


def params(args: argparse.Namespace) -> slide.SlideParams:
    return slide.SlideParams(**{f.name: getattr(args, f.name) for f in slide.fields()})


def main(args: argparse.Namespace) -> int:
    try:
        out = slide.run(params(args), progress_bar=progress.wanted(args.progress, args.json))
        if args.plot:
            slide.plot(args.plot, out)
    except (ValueError, FileNotFoundError, ImportError) as e:
        print(f"mjtouch: error: {e}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(out.summary))
    else:
        print_human(out.summary)
    return 0


PRESSURE_MODELS = {
    "elastic": "elastic contact on the layered skin's compliance",
    "winkler": "Winkler foundation",
    "contacts": "MuJoCo's contact points",
}


def print_human(o: dict) -> None:
    period = f"{o['period_m'] * 1e3:.3g} mm" if o["period_m"] else "-"
    print(
        f"mjtouch slide: {o['texture']} texture, D = {period}, "
        f"V = {o['speed_m_s'] * 1e3:.3g} mm/s, F = {o['force_n']:.3g} N, "
        f"ridges {'on' if o['ridges'] else 'off'} (lambda = {o['ridge_pitch_m'] * 1e3:.3g} mm), "
        f"{o['duration_s']:.3g} s sliding (wall {o['wall_s']:.1f} s)"
    )
    shift = ", grid shift average" if o["grid_shift"] else ""
    if o.get("grids_cycled", 0) > 1:
        shift = f", {o['grids_cycled']} sub-cell offset grids in turn"
    print(f"pressure model: {o['pressure']} ({PRESSURE_MODELS[o['pressure']]}{shift})")
    print(
        "firing rates (Hz):  "
        + "  ".join(f"{k} {v:.1f}" for k, v in o["rates_hz"].items())
        + "   receptors: "
        + " ".join(f"{k} {v}" for k, v in o["receptors"].items())
    )
    e = o["expected_hz"]
    print(
        "expected:  V/D = "
        + (f"{e['texture']:.2f} Hz" if e["texture"] else "-")
        + "   V/lambda = "
        + (f"{e['ridges']:.2f} Hz" if e["ridges"] else "-")
        + f"   (FFT bin {o['fft_bin_hz']:.2f} Hz)"
    )
    print(
        "stress spectral peaks (Hz, strongest first): "
        + ", ".join(f"{x:.2f}" for x in o["peaks_hz"])
    )
    for key, name in (("texture", "V/D"), ("ridges", "V/lambda")):
        if not e[key]:
            continue
        if key == "ridges" and not o["ridge_line_expected"]:
            print(
                f"{name}: no line expected on a periodic texture (its stress repeats every "
                "D/V, so its lines are V/D harmonics); ridges band-pass broadband textures: "
                "--texture random"
            )
            continue
        line = o["lines"][key]
        if line is None:
            print(f"{name}: above the spectrum's top frequency")
            continue
        peak = (
            f"peak {line['peak_hz']:.2f} Hz ({round(100 * (line['peak_hz'] / e[key] - 1)) + 0:+d}%)"
            if line["peak_hz"] is not None
            else "no bin"
        )
        print(
            f"{name} band {line['lo_hz']:.1f}-{line['hi_hz']:.1f} Hz: {peak}, "
            f"{100 * line['share']:.1f}% of the stress power, {line['contrast']:.1f}x its flanks"
        )
    if o.get("grid_line_hz"):
        print(
            f"note: the elastic contact adds a grid line at V/pitch = {o['grid_line_hz']:.0f} Hz "
            "to the stress; PC rates include it (--grid-cycle 4 or --grid-shift cancel it; docs: "
            "Performance, "
            '"What accuracy costs")'
        )
