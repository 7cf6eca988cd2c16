"""Wang et al. 2016 (seed 002): SA1 static firing across six mouse skin specimens,
force control against displacement control.

    python examples/wang2016_specimens.py                      # ~10 s
    python examples/wang2016_specimens.py --json
    python examples/wang2016_specimens.py --plot wang2016.png
    python examples/wang2016_specimens.py --pitch 6.25e-6      # convergence check
    python examples/wang2016_specimens.py --modulus relaxed    # skin modulus at the hold window

The C++ stages are called from Python (mjtouch.core), quasi-statically: MuJoCo's
soft-contact stiffness does not derive from the skin's layers, so the tip's
load-indentation relation must come from the skin itself.

- Skin stack per specimen (Wang 2016 Methods, Table 2), welded on a rigid base:
  skin (thickness l0, Ogden initial shear modulus mu, nu = 0.475: the paper's
  D1 = 1/(10 mu), bulk modulus 20 mu), nylon wick 339 um (Ogden mu1 = 42.37 kPa,
  nu = 0.475 assumed: the paper gives no D1 for it), Sylgard 10.13 mm
  (Neo-Hookean C10 = 105.2 kPa: shear modulus 2 C10, nu = 0.49). Small-strain
  Young's modulus E = 2 mu (1 + nu) (about 3 mu: the shear modulus is kept).
  ``--modulus relaxed`` scales the skin's mu by its Prony relaxation
  g_inf + g1 exp(-t/tau1) + g2 exp(-t/tau2) at the middle of the rate window
  (3.25 s after the ramp), an approximation of the viscoelastic hold.
- Tip: rigid cylinder, radius 0.5 mm, flat face with a 0.1 mm edge fillet:
  gap 0 for r <= 0.4 mm, the fillet circle for 0.4 < r <= 0.5 mm, no contact
  beyond (the side wall). Point-sampled at the centres of an odd n x n grid.
- Contact: core.elastic_pressure on the stack's compliance table (load
  controlled; its approach is the indentation). Force control: the paper's
  forces 2.6-7.8 mN. Displacement control: the force whose approach equals the
  prescribed indentation (brentq; approach rises monotonically with force).
  The paper pairs its levels one to one (0.34 mm .. 0.73 mm with 0 .. 7.8 mN),
  so our five displacement levels are the indentations at which the average
  skin (specimen 1) carries the five forces: the two protocols coincide for
  specimen 1 and differ for the others.
- Stress at the Merkel depth, 22.5 um, on a row of sites from the tip's centre
  outwards; q = most compressive principal stress (compressive positive), as
  Wang's stress model. Reported: the centre site, and the row's most excited
  site under the edge (0.4 mm <= r <= 0.6 mm).
- Pressure control (the paper's pressure-to-stress transformation, its
  Figs. 8-10): specimen 1's contact pressure at each force prescribed on every
  stack, isolating what force control with a rigid tip adds: the contact
  pressure's redistribution from skin to skin.
- SA1: core.receptor_run("SA1", ...) on a 0.2 s linear ramp and 4.5 s hold of
  q (quasi-static linear elasticity: stress follows the load), static rate =
  spikes 2-4.5 s after the ramp / 2.5 s. Gains: Wang's Table 1 (stress model)
  as printed, and (``--calibrate-hz``) with k0 and k1 scaled by one factor so
  that specimen 1's centre site fires at 6.5 mN at the rate Table 3 implies
  (3.79 Hz / 12% = 31.6 Hz): with the printed gains our centre stresses stay
  below the SA1's rheobase (13.4 kPa).
- Mean response range (MRR) as the paper: mean over the five levels of the
  max - min static rate across specimens; relative = absolute / the rate of
  specimen 1 at the fourth level (6.5 mN; 0.66 mm in the paper).
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
from scipy.optimize import brentq

from mjtouch import core

TIP_RADIUS_M = 0.5e-3
FILLET_RADIUS_M = 0.1e-3
MERKEL_DEPTH_M = 22.5e-6
EDGE_SITES_M = (0.4e-3, 0.6e-3)  # radii searched for the edge's most excited site
GRID_MARGIN_M = 0.1e-3  # stress sites beyond the rim (the edge's tail)

FORCES_N = (2.6e-3, 3.9e-3, 5.2e-3, 6.5e-3, 7.8e-3)  # the paper's five upper levels
PAPER_DISPLACEMENTS_M = (0.47e-3, 0.53e-3, 0.60e-3, 0.66e-3, 0.73e-3)
PAPER_ZERO_FORCE_DISPLACEMENT_M = 0.34e-3  # the paper's lowest level, paired with 0 mN
REFERENCE_LEVEL = 3  # the fourth level: 6.5 mN / 0.66 mm, the relative MRR's denominator
PAPER_TABLE3 = {
    "displacement": {"absolute_hz": 14.66, "relative": 0.77},
    "force": {"absolute_hz": 3.79, "relative": 0.12},
}
PAPER_FORCE_RANGE_AT_060_N = (2.8e-3, 5.0e-3)  # Fig. 6, at 0.60 mm (the third level)
PAPER_RATE_AT_7_8_MN_HZ = (22.0, 26.0)  # text on Fig. 7F, across the six specimens
# Table 3's force row implies specimen 1's rate at 6.5 mN: absolute / relative MRR
PAPER_REFERENCE_RATE_HZ = PAPER_TABLE3["force"]["absolute_hz"] / PAPER_TABLE3["force"]["relative"]

# Table 2: l0 (m), Ogden mu (Pa), alpha, tau1, tau2 (s), g1, g2, g_inf.
SPECIMENS = (
    (379.81e-6, 1306.06, 7.90, 0.08, 1.21, 0.59, 0.10, 0.31),
    (267.71e-6, 1153.32, 9.37, 0.03, 0.41, 0.73, 0.15, 0.12),
    (388.58e-6, 1510.12, 7.35, 0.13, 2.30, 0.64, 0.08, 0.28),
    (524.84e-6, 1653.94, 9.25, 0.18, 2.07, 0.47, 0.10, 0.43),
    (435.53e-6, 1916.31, 7.38, 0.09, 1.31, 0.37, 0.07, 0.56),
    (384.11e-6, 1554.02, 9.35, 0.03, 0.31, 0.52, 0.21, 0.27),
)
SKIN_POISSON = 0.475  # Wang's D1 = 1/(10 mu): K = 20 mu
NYLON = (339e-6, 42.37e3, 0.475)  # thickness, Ogden mu1, nu (assumed as the skin's)
SYLGARD = (10.13e-3, 2 * 105.2e3, 0.49)  # thickness, Neo-Hookean 2 C10, nu

RAMP_S = 0.2
HOLD_S = 4.5
WINDOW_S = (2.0, 4.5)  # after the ramp (the paper's static window)
MODES = ("force", "displacement", "pressure")
DT_S = 1e-3  # the SA1 stage integrates exactly within a step: dt only samples q


def young_pa(shear_pa: float, poisson: float) -> float:
    return 2.0 * shear_pa * (1.0 + poisson)


def relaxation(specimen, t_s: float) -> float:
    """Table 2's Prony series, G(t) / G(0)."""
    _, _, _, tau1, tau2, g1, g2, g_inf = specimen
    return g_inf + g1 * math.exp(-t_s / tau1) + g2 * math.exp(-t_s / tau2)


def skin_layers(specimen, modulus: str = "initial") -> list[tuple[float, float, float]]:
    """(thickness m, E Pa, nu) rows from the surface down, over a rigid base."""
    if modulus not in ("initial", "relaxed"):
        raise ValueError(f"modulus {modulus!r} is not one of 'initial', 'relaxed'")
    thickness, mu = specimen[0], specimen[1]
    if modulus == "relaxed":
        mu *= relaxation(specimen, 0.5 * sum(WINDOW_S))
    return [
        (thickness, young_pa(mu, SKIN_POISSON), SKIN_POISSON),
        (NYLON[0], young_pa(NYLON[1], NYLON[2]), NYLON[2]),
        (SYLGARD[0], young_pa(SYLGARD[1], SYLGARD[2]), SYLGARD[2]),
    ]


def grid_size(pitch_m: float) -> int:
    """Odd n: a cell centred on the axis, sites out to the rim + margin."""
    if not 0 < pitch_m <= FILLET_RADIUS_M / 4:
        raise ValueError(
            f"pitch_m = {pitch_m} must be in (0, {FILLET_RADIUS_M / 4}] "
            "(at least 4 cells across the fillet)"
        )
    return 2 * math.ceil((TIP_RADIUS_M + GRID_MARGIN_M) / pitch_m) + 1


def tip_gap(n: int, pitch_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Gap (m; inf: the tip cannot touch) between the undeformed skin and the
    tip's face at first contact, and each cell's radius (m)."""
    c = (np.arange(n) - (n - 1) / 2) * pitch_m
    r = np.hypot(*np.meshgrid(c, c))
    flat = TIP_RADIUS_M - FILLET_RADIUS_M
    gap = np.full((n, n), np.inf)
    gap[r <= flat] = 0.0
    fil = (r > flat) & (r <= TIP_RADIUS_M)
    gap[fil] = FILLET_RADIUS_M - np.sqrt(FILLET_RADIUS_M**2 - (r[fil] - flat) ** 2)
    return gap, r


def max_compressive_pa(stress: np.ndarray) -> np.ndarray:
    """Most compressive principal stress, compressive positive (rows: Voigt
    xx yy zz xy xz yz, tension positive), clipped at 0 as the plugin's
    `maxcomp`."""
    s = np.asarray(stress, float)
    t = np.empty(s.shape[:-1] + (3, 3))
    t[..., 0, 0], t[..., 1, 1], t[..., 2, 2] = s[..., 0], s[..., 1], s[..., 2]
    t[..., 0, 1] = t[..., 1, 0] = s[..., 3]
    t[..., 0, 2] = t[..., 2, 0] = s[..., 4]
    t[..., 1, 2] = t[..., 2, 1] = s[..., 5]
    return np.maximum(0.0, -np.linalg.eigvalsh(t)[..., 0])


class SpecimenContact:
    """One specimen's stack under the tip: the compliance table, the gap and
    the stress stage at the Merkel depth on the row j = centre, i >= centre."""

    def __init__(self, layers, pitch_m: float):
        self.pitch_m = pitch_m
        self.n = grid_size(pitch_m)
        self.skin = core.LayeredSkin(layers, "rigid")
        self.table = self.skin.compliance_table(pitch_m, self.n)
        self.gap, r = tip_gap(self.n, pitch_m)
        c = self.n // 2
        self.site_ij = [(i, c) for i in range(c, self.n)]
        self.site_r_m = r[c, c:]
        self.engine = core.StressEngine(self.skin, self.n, pitch_m, [MERKEL_DEPTH_M], self.site_ij)
        self.edge = (self.site_r_m >= EDGE_SITES_M[0]) & (self.site_r_m <= EDGE_SITES_M[1])

    def sample(self, pressure_pa: np.ndarray) -> dict:
        """q at the Merkel sites under a surface pressure field (n x n, Pa)."""
        q = max_compressive_pa(self.engine.stress(pressure_pa))
        c = self.n // 2
        k = int(np.argmax(np.where(self.edge, q, -1.0)))
        return {
            "force_n": float(pressure_pa.sum()) * self.pitch_m**2,
            "pressure_pa": pressure_pa,
            "pressure_centre_pa": float(pressure_pa[c, c]),
            "pressure_row_pa": pressure_pa[c, c:],
            "q_row_pa": q,
            "q_centre_pa": float(q[0]),
            "q_edge_pa": float(q[k]),
            "edge_site_r_m": float(self.site_r_m[k]),
        }

    def press(self, force_n: float) -> dict:
        """Force control: the rigid tip pressed with force_n."""
        p, info = core.elastic_pressure(
            self.gap, self.pitch_m, force_n, compliance_m_per_pa=self.table
        )
        if not info["converged"]:
            raise RuntimeError(f"contact solve did not converge at {force_n} N: {info}")
        return {**self.sample(p), "force_n": force_n, "approach_m": info["approach_m"]}

    def press_to(self, approach_m: float, guess_n: float) -> dict:
        """Displacement control: the force whose approach is approach_m."""

        def miss(f):
            info = core.elastic_pressure(self.gap, self.pitch_m, f, compliance_m_per_pa=self.table)[
                1
            ]
            return info["approach_m"] - approach_m

        lo, hi = 0.5 * guess_n, 2.0 * guess_n
        while miss(lo) > 0:
            lo *= 0.5
        while miss(hi) < 0:
            hi *= 2.0
        return self.press(brentq(miss, lo, hi, xtol=1e-9 * guess_n, rtol=1e-10))


def sa1_config(gain_scale: float) -> dict:
    """Wang 2016's SA1 (`sa1_model` wang2016: |dq/dt|, no adaptation) with
    its Table 1 gains k0 and k1 scaled (the same as scaling q)."""
    return {
        "sa1_model": "wang2016",
        "sa1_k0": 1.40e-16 * gain_scale,
        "sa1_k1": 1.68e-16 * gain_scale,
    }


def q_trace(q_static_pa: float) -> np.ndarray:
    t = np.arange(round((RAMP_S + HOLD_S) / DT_S) + 1) * DT_S
    return q_static_pa * np.minimum(t / RAMP_S, 1.0)


def static_rate_hz(q_static_pa: float, gain_scale: float = 1.0) -> float:
    """Spikes over 2-4.5 s of the hold / 2.5 s, for a ramp-and-hold of q."""
    spikes, _ = core.receptor_run("SA1", q_trace(q_static_pa), DT_S, sa1_config(gain_scale))
    t_end = np.arange(spikes.size) * DT_S  # spikes[k]: the step ending at t_end[k]
    lo, hi = RAMP_S + WINDOW_S[0], RAMP_S + WINDOW_S[1]
    window = (t_end > lo + 0.5 * DT_S) & (t_end < hi + 0.5 * DT_S)
    return float(spikes[window].sum()) / (WINDOW_S[1] - WINDOW_S[0])


def lif_rate_hz(q_pa: float, gain_scale: float = 1.0) -> float:
    """Constant-q SA1 rate of the most excited heminode (M = 8): period
    t_ref + R C ln(I R / (I R - U_th)) (README, "Afferent models")."""
    i = 8 * 1.40e-16 * gain_scale * q_pa + 4.94e-12
    u = i * 1.5e9
    return 0.0 if u <= 0.03 else 1.0 / (1e-3 + 15e-3 * math.log(u / (u - 0.03)))


def calibrate_gain(q_pa: float, target_hz: float) -> float:
    """The gain scale at which a constant q fires at target_hz (LIF formula)."""
    period = 1.0 / target_hz - 1e-3
    u = 0.03 / (1.0 - math.exp(-period / 15e-3))  # I R at that period
    return (u / 1.5e9 - 4.94e-12) / (8 * 1.40e-16 * q_pa)


def mrr(rates_hz: np.ndarray) -> dict:
    """rates_hz: (specimens, levels); specimen 0 is the average skin."""
    r = np.asarray(rates_hz, float)
    absolute = float(np.mean(r.max(axis=0) - r.min(axis=0)))
    ref = float(r[0, REFERENCE_LEVEL])
    return {
        "absolute_hz": absolute,
        "relative": absolute / ref if ref > 0 else None,
        "reference_rate_hz": ref,
    }


def stress_range(q_pa: np.ndarray) -> float:
    """The MRR's recipe on the stress itself: mean max - min across
    specimens over the levels, relative to specimen 1 at the fourth level."""
    q = np.asarray(q_pa, float)
    return float(np.mean(q.max(axis=0) - q.min(axis=0)) / q[0, REFERENCE_LEVEL])


def run(
    pitch_m: float = 12.5e-6,
    modulus: str = "initial",
    calibrate_hz: float = PAPER_REFERENCE_RATE_HZ,
    specimens=SPECIMENS,
    forces_n=FORCES_N,
) -> dict:
    if not calibrate_hz >= 0:
        raise ValueError(f"calibrate_hz = {calibrate_hz} must be >= 0 (0: Table 1 gains only)")
    contacts = [SpecimenContact(skin_layers(s, modulus), pitch_m) for s in specimens]
    force = [[c.press(f) for f in forces_n] for c in contacts]
    levels_m = [r["approach_m"] for r in force[0]]
    disp = [force[0]] + [
        [
            c.press_to(d, guess_n=f * fr["approach_m"] / d)
            for d, f, fr in zip(levels_m, forces_n, force[k + 1])
        ]
        for k, c in enumerate(contacts[1:])
    ]
    # pressure control (the paper's pressure-to-stress transformation): specimen
    # 1's contact pressure at each force, prescribed on every stack
    pres = [[c.sample(r["pressure_pa"]) for r in force[0]] for c in contacts]

    def field(results, key):
        return np.array([[r[key] for r in row] for row in results])

    out = {
        "pitch_m": pitch_m,
        "grid_n": contacts[0].n,
        "modulus": modulus,
        "layers": [skin_layers(s, modulus) for s in specimens],
        "forces_n": list(forces_n),
        "displacements_m": levels_m,
        "paper_displacements_m": list(PAPER_DISPLACEMENTS_M),
        "paper_indentations_m": [
            d - PAPER_ZERO_FORCE_DISPLACEMENT_M for d in PAPER_DISPLACEMENTS_M
        ],
        "site_r_m": contacts[0].site_r_m.tolist(),
        "modes": {},
    }
    q_ref = field(force, "q_centre_pa")[0, REFERENCE_LEVEL]  # specimen 1, centre, 6.5 mN
    gains = {"table1": 1.0}
    if calibrate_hz > 0:
        gains["calibrated"] = calibrate_gain(q_ref, calibrate_hz)
    out["gain_scale"] = gains
    out["calibrate_hz"] = calibrate_hz
    for mode, res in (("force", force), ("displacement", disp), ("pressure", pres)):
        m = {
            "force_n": field(res, "force_n").tolist(),
            "pressure_centre_pa": field(res, "pressure_centre_pa").tolist(),
            "edge_site_r_m": field(res, "edge_site_r_m").tolist(),
            "q_row_pa": [[r["q_row_pa"].tolist() for r in row] for row in res],
            "pressure_row_pa": [[r["pressure_row_pa"].tolist() for r in row] for row in res],
            "sites": {},
        }
        if mode != "pressure":
            m["approach_m"] = field(res, "approach_m").tolist()
        for site in ("centre", "edge"):
            q = field(res, f"q_{site}_pa")
            entry = {"q_pa": q.tolist(), "stress_range_relative": stress_range(q), "rates": {}}
            for name, scale in gains.items():
                rates = np.array([[static_rate_hz(v, scale) for v in row] for row in q])
                entry["rates"][name] = {"rates_hz": rates.tolist(), "mrr": mrr(rates)}
            m["sites"][site] = entry
        out["modes"][mode] = m
    f_mid = np.array(out["modes"]["displacement"]["force_n"])[:, 2]
    out["force_range_at_level3_n"] = [float(f_mid.min()), float(f_mid.max())]
    out["paper"] = {
        "table3_stress": PAPER_TABLE3,
        "force_range_at_060mm_n": list(PAPER_FORCE_RANGE_AT_060_N),
        "rate_at_7_8mN_hz": list(PAPER_RATE_AT_7_8_MN_HZ),
    }
    return out


def _fmt_mrr(m: dict) -> str:
    rel = "  n/a" if m["relative"] is None else f"{100 * m['relative']:4.0f}%"
    return f"{m['absolute_hz']:6.2f} Hz {rel}"


def report(r: dict) -> str:
    lines = [
        f"Wang et al. 2016, six specimens: pitch {r['pitch_m'] * 1e6:.3g} um, "
        f"{r['grid_n']} x {r['grid_n']} cells, skin modulus {r['modulus']}",
        "levels (force mN / our displacement mm / paper's displacement mm, minus 0.34):",
    ]
    for f, d, pd, pi in zip(
        r["forces_n"], r["displacements_m"], r["paper_displacements_m"], r["paper_indentations_m"]
    ):
        lines.append(
            f"  {f * 1e3:4.1f} mN   {d * 1e3:6.3f} mm   {pd * 1e3:.2f} ({pi * 1e3:.2f}) mm"
        )
    fd = np.array(r["modes"]["displacement"]["force_n"]) * 1e3
    lines.append("reaction force (mN) under displacement control, specimen x level:")
    for k, row in enumerate(fd):
        lines.append(f"  {k + 1}: " + " ".join(f"{v:6.2f}" for v in row))
    lo, hi = r["force_range_at_level3_n"]
    lines.append(
        f"  at the third level: {lo * 1e3:.2f}-{hi * 1e3:.2f} mN (max/min {hi / lo:.2f}); "
        "paper at 0.60 mm: 2.8-5.0 mN (1.79)"
    )
    for site in ("centre", "edge"):
        lines.append(
            f"{site} site (22.5 um deep), q = max compressive stress (kPa), specimen x level:"
        )
        for mode in MODES:
            q = np.array(r["modes"][mode]["sites"][site]["q_pa"]) / 1e3
            lines.append(f"  {mode}:")
            for k, row in enumerate(q):
                lines.append(f"    {k + 1}: " + " ".join(f"{v:6.2f}" for v in row))
    gains = r["gain_scale"]
    lines.append(
        "static SA1 rate (Hz) and mean response ranges (paper, Table 3 stress row: "
        "displacement 14.66 Hz 77%, force 3.79 Hz 12%):"
    )
    for name, scale in gains.items():
        label = (
            "Table 1 gains"
            if name == "table1"
            else (
                f"gains x {scale:.3f} (specimen 1 centre at 6.5 mN -> {r['calibrate_hz']:.1f} Hz)"
            )
        )
        lines.append(f"  {label}:")
        for site in ("centre", "edge"):
            for mode in MODES:
                e = r["modes"][mode]["sites"][site]
                rates = np.array(e["rates"][name]["rates_hz"])
                lines.append(
                    f"    {site:6s} {mode:12s} MRR {_fmt_mrr(e['rates'][name]['mrr'])}   "
                    f"rates min-max per level: "
                    + " ".join(f"{a:.1f}-{b:.1f}" for a, b in zip(rates.min(0), rates.max(0)))
                )
    lines.append("stress range (MRR recipe on q, relative to specimen 1 at the fourth level):")
    for site in ("centre", "edge"):
        lines.append(
            f"  {site:6s} "
            + "   ".join(
                f"{mode} {100 * r['modes'][mode]['sites'][site]['stress_range_relative']:5.1f}%"
                for mode in MODES
            )
        )
    return "\n".join(lines)


def plot(r: dict, path: str) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("--plot needs matplotlib: pip install 'mjtouch[plot]'") from None
    name = "calibrated" if "calibrated" in r["gain_scale"] else "table1"
    fig, ax = plt.subplots(2, 3, figsize=(15, 8))
    f_mn = np.array(r["forces_n"]) * 1e3
    d_mm = np.array(r["displacements_m"]) * 1e3
    fd = np.array(r["modes"]["displacement"]["force_n"]) * 1e3
    for k, row in enumerate(fd):
        ax[0, 0].plot(d_mm, row, "o-", label=f"specimen {k + 1}", lw=2.5 if k == 0 else 1)
    ax[0, 0].set(
        xlabel="indentation (mm)",
        ylabel="reaction force (mN)",
        title="displacement control: reaction force",
    )
    ax[0, 0].legend(fontsize=8)
    for a, mode, x, xl in (
        (ax[0, 1], "force", f_mn, "force (mN)"),
        (ax[1, 1], "displacement", d_mm, "indentation (mm)"),
        (ax[0, 2], "pressure", f_mn, "force of specimen 1's pressure (mN)"),
    ):
        rates = np.array(r["modes"][mode]["sites"]["centre"]["rates"][name]["rates_hz"])
        a.fill_between(x, rates.min(0), rates.max(0), color="0.8", label="6 specimens")
        a.plot(x, rates[0], "k-o", label="specimen 1")
        m = r["modes"][mode]["sites"]["centre"]["rates"][name]["mrr"]
        rel = "n/a" if m["relative"] is None else f"{100 * m['relative']:.0f}%"
        a.set(
            xlabel=xl,
            ylabel="SA1 static rate (Hz)",
            title=f"{mode} control, centre: MRR {m['absolute_hz']:.1f} Hz, {rel}",
        )
        a.legend(fontsize=8)
    rr = np.array(r["site_r_m"]) * 1e3
    for j, f in enumerate(f_mn):
        q = np.array(r["modes"]["force"]["q_row_pa"][0][j]) / 1e3
        p = np.array(r["modes"]["force"]["pressure_row_pa"][0][j]) / 1e3
        (line,) = ax[1, 0].plot(rr, q, label=f"{f:.1f} mN")
        ax[1, 0].plot(rr, p, ":", color=line.get_color())
    ax[1, 0].set(
        xlabel="r (mm)", ylabel="kPa", title="specimen 1: q at 22.5 um (solid), pressure (dotted)"
    )
    ax[1, 0].legend(fontsize=8)
    labels, ours, paper = [], [], []
    for mode in MODES:
        for site in ("centre", "edge"):
            rel = r["modes"][mode]["sites"][site]["rates"][name]["mrr"]["relative"]
            labels.append(f"{'displ.' if mode == 'displacement' else mode}\n{site}")
            ours.append(np.nan if rel is None else 100 * rel)
            paper.append(100 * PAPER_TABLE3[mode]["relative"] if mode in PAPER_TABLE3 else np.nan)
    x = np.arange(len(labels))
    ax[1, 2].bar(x - 0.2, ours, 0.4, label="mjtouch")
    ax[1, 2].bar(x + 0.2, paper, 0.4, label="Wang 2016, Table 3 (stress)")
    ax[1, 2].set_xticks(x, labels, fontsize=8)
    ax[1, 2].set(ylabel="relative MRR (%)", title="relative mean response range")
    ax[1, 2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _jsonable(r: dict) -> dict:
    return json.loads(json.dumps(r, default=float))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--pitch",
        type=float,
        default=12.5e-6,
        help="taxel pitch (m); 8 cells across the 0.1 mm fillet by default",
    )
    p.add_argument(
        "--modulus",
        choices=("initial", "relaxed"),
        default="initial",
        help="skin shear modulus: Ogden mu, or mu x its Prony relaxation at 3.25 s",
    )
    p.add_argument(
        "--calibrate-hz",
        type=float,
        default=PAPER_REFERENCE_RATE_HZ,
        help="also scale the SA1 gains so that specimen 1's centre site fires at "
        "this rate at 6.5 mN (default: Table 3's 3.79 Hz / 12%%); 0: Table 1 "
        "gains only",
    )
    p.add_argument("--plot", metavar="FILE", help="write a PNG (forces, rates, stress profile)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    r = run(args.pitch, args.modulus, args.calibrate_hz)
    if args.plot:
        plot(r, args.plot)
    if args.json:
        print(json.dumps(_jsonable(r)))
    else:
        print(report(r))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
