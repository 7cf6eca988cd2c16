"""Stress in a layered elastic skin under surface tractions: an oracle for the
layered kernel (plugin/core/substrate/layered.*), computed independently of it.

The problem is Burmister's layered system (D. M. Burmister, J. Appl. Phys.
16:89, 1945) in the Fourier-transform form of Johnson, *Contact Mechanics*
(1985, sec. 3.3 for the homogeneous limits it is checked against). A second
computation of what the C++ does, written separately:

* per wavenumber k, the Navier equations in displacement form (Lame lambda,
  mu; so nu < 0.5 only) with the general solution
  u_xi = i (A + B s) e^-s, u_z = -(A + kappa B + B s) e^-s (s = k z',
  kappa = 3 - 4 nu) and its mirror decaying from a layer's bottom face,
  complex arithmetic, stresses from Hooke's law, a global matrix per k solved
  by numpy (batched over k);
* the stress in real space by direct numerical inverse 2D Fourier
  integration: composite Gauss-Legendre in k, trapezoid in the wavevector
  angle (no Bessel-function identities, no hand-rotated formulas: the tensor
  is rotated numerically);
* for an axisymmetric disc of pressure also the classical Hankel integrals
  with scipy.special.j0 / j1 (a third route, for the oracle's own checks).

Frame and signs as the C++: z into the skin, tension positive, `pressure`
pushes into the skin, shear tractions along +x / +y; components in Voigt
order (xx, yy, zz, xy, xz, yz). Layers are (thickness_m, young_pa, poisson);
base is None for a rigid base (bone) or (young_pa, poisson) for a half-space.

Run `python -m mjtouch.analysis.reference_solutions.layered` for the
self-checks, or add `DUMP.json` to compare with values written by
`test_layered --dump DUMP.json` (the C++ standalone test).
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np
from scipy import special

LOADS = ("pressure", "shear_x", "shear_y")


def _lame(young, poisson):
    mu = young / (2.0 * (1.0 + poisson))
    lam = 2.0 * mu * poisson / (1.0 - 2.0 * poisson)
    return lam, mu


def _inplane_basis(k, zeta, h, lam, mu, mu_ref):
    """Basis fields of one layer at local depth zeta, shape (nk, 4, 6).

    Columns: A, B (decaying from the top face), C, D (from the bottom face;
    absent, i.e. zero, for a half-space h = inf). Entries: mu_ref k u_xi,
    mu_ref k u_z, and stresses s_xixi, s_etaeta, s_zz, s_xiz divided by
    mu_ref, for the factor exp(i k xi).
    """
    kappa = (lam + 3 * mu) / (lam + mu)
    s = k * zeta
    e = np.exp(-s)
    out = np.zeros((k.size, 4, 6), dtype=complex)
    # (u_xi, u_z) and d/ds of them, per unit coefficient.
    cols = []
    # A: u_xi = i e, u_z = -e.
    cols.append((1j * e, -e, -1j * e, e))
    # B: u_xi = i s e, u_z = -(kappa + s) e.
    cols.append((1j * s * e, -(kappa + s) * e, 1j * (1 - s) * e, (kappa + s - 1) * e))
    if np.isfinite(h):
        sp = k * (zeta - h)  # <= 0
        ep = np.exp(sp)
        # C: u_xi = i e', u_z = e'.
        cols.append((1j * ep, ep, 1j * ep, ep))
        # D: u_xi = -i s' e', u_z = (kappa - s') e'.
        cols.append((-1j * sp * ep, (kappa - sp) * ep, -1j * (1 + sp) * ep, (kappa - 1 - sp) * ep))
    else:
        z0 = np.zeros_like(e)
        cols += [(z0, z0, z0, z0)] * 2
    for c, (ux, uz, dux, duz) in enumerate(cols):
        div = 1j * ux + duz  # (i k u_xi + u_z') mu_ref / k... per unit k
        out[:, c, 0] = ux
        out[:, c, 1] = uz
        out[:, c, 2] = (lam * div + 2 * mu * 1j * ux) / mu_ref  # s_xixi
        out[:, c, 3] = lam * div / mu_ref  # s_etaeta
        out[:, c, 4] = (lam * div + 2 * mu * duz) / mu_ref  # s_zz
        out[:, c, 5] = mu * (dux + 1j * uz) / mu_ref  # s_xiz
    return out


def _antiplane_basis(k, zeta, h, mu, mu_ref):
    """(nk, 2, 3): mu_ref k u_eta, s_etaz / mu_ref, s_xieta / mu_ref."""
    s = k * zeta
    e = np.exp(-s)
    out = np.zeros((k.size, 2, 3), dtype=complex)
    out[:, 0, 0] = e
    out[:, 0, 1] = -mu / mu_ref * e
    out[:, 0, 2] = 1j * mu / mu_ref * e
    if np.isfinite(h):
        ep = np.exp(k * (zeta - h))
        out[:, 1, 0] = ep
        out[:, 1, 1] = mu / mu_ref * ep
        out[:, 1, 2] = 1j * mu / mu_ref * ep
    return out


def _materials(layers, base):
    mats = []
    for t, young, nu in layers:
        lam, mu = _lame(young, nu)
        mats.append((float(t), lam, mu))
    if base is not None:
        lam, mu = _lame(*base)
        mats.append((math.inf, lam, mu))
    return mats


def solve(k, layers, base):
    """Coefficients per k for unit pressure, unit shear q_xi, unit q_eta."""
    k = np.atleast_1d(np.asarray(k, dtype=float))
    mats = _materials(layers, base)
    nl = len(mats)
    mu_ref = mats[0][2]
    ncol = [4 if np.isfinite(m[0]) else 2 for m in mats]
    offs = np.concatenate([[0], np.cumsum(ncol)])
    n = int(offs[-1])
    M = np.zeros((k.size, n, n), dtype=complex)
    rhs = np.zeros((k.size, n, 2), dtype=complex)
    na_col = [2 if np.isfinite(m[0]) else 1 for m in mats]
    oa = np.concatenate([[0], np.cumsum(na_col)])
    na = int(oa[-1])
    Ma = np.zeros((k.size, na, na), dtype=complex)
    ra = np.zeros((k.size, na, 1), dtype=complex)

    def bi(j, zeta):
        t, lam, mu = mats[j]
        return _inplane_basis(k, zeta, t, lam, mu, mu_ref)[:, : ncol[j], :]

    def ba(j, zeta):
        t, lam, mu = mats[j]
        return _antiplane_basis(k, zeta, t, mu, mu_ref)[:, : na_col[j], :]

    # Surface: s_zz = -p, s_xiz = -q_xi, s_etaz = -q_eta (traction on z = 0).
    b = bi(0, 0.0)
    M[:, 0, offs[0] : offs[1]] = b[:, :, 4]
    M[:, 1, offs[0] : offs[1]] = b[:, :, 5]
    rhs[:, 0, 0] = -1.0 / mu_ref
    rhs[:, 1, 1] = -1.0 / mu_ref
    a = ba(0, 0.0)
    Ma[:, 0, oa[0] : oa[1]] = a[:, :, 1]
    ra[:, 0, 0] = -1.0 / mu_ref
    row, rowa = 2, 1
    for j in range(nl - 1):
        top = bi(j, mats[j][0])
        bot = bi(j + 1, 0.0)
        for comp in (0, 1, 4, 5):  # u_xi, u_z, s_zz, s_xiz
            M[:, row, offs[j] : offs[j + 1]] = top[:, :, comp]
            M[:, row, offs[j + 1] : offs[j + 2]] = -bot[:, :, comp]
            row += 1
        ta = ba(j, mats[j][0])
        bb = ba(j + 1, 0.0)
        for comp in (0, 1):
            Ma[:, rowa, oa[j] : oa[j + 1]] = ta[:, :, comp]
            Ma[:, rowa, oa[j + 1] : oa[j + 2]] = -bb[:, :, comp]
            rowa += 1
    if base is None:  # rigid: u = 0 at the bottom of the last layer
        last = bi(nl - 1, mats[-1][0])
        M[:, row, offs[-2] : offs[-1]] = last[:, :, 0]
        M[:, row + 1, offs[-2] : offs[-1]] = last[:, :, 1]
        la = ba(nl - 1, mats[-1][0])
        Ma[:, rowa, oa[-2] : oa[-1]] = la[:, :, 0]
    x = np.linalg.solve(M, rhs)
    xa = np.linalg.solve(Ma, ra)
    return {
        "k": k,
        "mats": mats,
        "offs": offs,
        "oa": oa,
        "ncol": ncol,
        "na_col": na_col,
        "x": x,
        "xa": xa,
        "mu_ref": mu_ref,
    }


def _locate(z, layers, base, upper):
    tops = np.concatenate([[0.0], np.cumsum([layer[0] for layer in layers])])
    tol = 1e-9 * tops[-1]
    for j in range(len(layers)):
        if abs(z - tops[j + 1]) <= tol:
            if upper:
                return j, layers[j][0]
            if j + 1 == len(layers) and base is None:
                raise ValueError("depth on the rigid base")
            return j + 1, 0.0
        if z < tops[j + 1]:
            return j, z - tops[j]
    if base is None:
        raise ValueError("depth inside the rigid base")
    return len(layers), z - tops[-1]


def stress_xieta(k, z, layers, base, upper=True):
    """Complex stress tensors (nk, 3 loads, 3, 3) in the (xi, eta, z) frame
    for unit pressure, unit q_xi and unit q_eta, factor exp(i k xi)."""
    sol = solve(k, layers, base)
    j, zeta = _locate(z, layers, base, upper)
    t, lam, mu = sol["mats"][j]
    mu_ref = sol["mu_ref"]
    b = _inplane_basis(sol["k"], zeta, t, lam, mu, mu_ref)[:, : sol["ncol"][j], :]
    c = sol["x"][:, sol["offs"][j] : sol["offs"][j + 1], :]  # (nk, ncol, 2)
    f = np.einsum("kcq,kcl->klq", b, c) * mu_ref  # (nk, 2 loads, 6)
    ab = _antiplane_basis(sol["k"], zeta, t, mu, mu_ref)[:, : sol["na_col"][j], :]
    ca = sol["xa"][:, sol["oa"][j] : sol["oa"][j + 1], 0]
    fa = np.einsum("kcq,kc->kq", ab, ca) * mu_ref
    S = np.zeros((sol["k"].size, 3, 3, 3), dtype=complex)
    for load in (0, 1):
        S[:, load, 0, 0] = f[:, load, 2]
        S[:, load, 1, 1] = f[:, load, 3]
        S[:, load, 2, 2] = f[:, load, 4]
        S[:, load, 0, 2] = S[:, load, 2, 0] = f[:, load, 5]
    S[:, 2, 1, 2] = S[:, 2, 2, 1] = fa[:, 1]
    S[:, 2, 0, 1] = S[:, 2, 1, 0] = fa[:, 2]
    return S


def transfer(k, z, layers, base, upper=True):
    """The C++ LayerTransfer functions (see layered.h) at wavenumbers k."""
    S = stress_xieta(k, z, layers, base, upper)
    return {
        "p_xixi": S[:, 0, 0, 0].real,
        "p_etaeta": S[:, 0, 1, 1].real,
        "p_zz": S[:, 0, 2, 2].real,
        "p_xiz": (S[:, 0, 0, 2] / 1j).real,
        "q_xixi": (S[:, 1, 0, 0] / 1j).real,
        "q_etaeta": (S[:, 1, 1, 1] / 1j).real,
        "q_zz": (S[:, 1, 2, 2] / 1j).real,
        "q_xiz": (-S[:, 1, 0, 2]).real,
        "a_etaz": S[:, 2, 1, 2].real,
        "a_xieta": (S[:, 2, 0, 1] / 1j).real,
    }


def surface_compliance(k, layers, base):
    """u_z / p (m/Pa) at the surface, wavenumber k > 0."""
    sol = solve(k, layers, base)
    t, lam, mu = sol["mats"][0]
    b = _inplane_basis(sol["k"], 0.0, t, lam, mu, sol["mu_ref"])
    uz = np.einsum("kc,kc->k", b[:, : sol["ncol"][0], 1], sol["x"][:, : sol["ncol"][0], 0])
    return (uz * sol["mu_ref"] / (sol["mu_ref"] * sol["k"])).real


def _k_nodes(r_scale, z, kmax_factor=45.0, order=16):
    """Composite Gauss-Legendre nodes/weights on [0, kmax_factor / z]:
    geometric panels at small k, then panels no wider than a half period of
    the oscillation (pi / r_scale) or 1 / z."""
    kmax = kmax_factor / z
    edges = [0.0]
    k = 1e-6 / max(z, r_scale)
    edges.append(k)
    while k < kmax:
        w = max(0.2 * k, 1e-6 / max(z, r_scale))
        w = min(w, math.pi / r_scale if r_scale > 0 else math.inf, 1.0 / z)
        k = min(k + w, kmax)
        edges.append(k)
    edges = np.array(edges)
    xg, wg = special.roots_legendre(order)
    a, b = edges[:-1, None], edges[1:, None]
    nodes = (0.5 * (b - a) * xg + 0.5 * (a + b)).ravel()
    weights = (0.5 * (b - a) * wg).ravel()
    return nodes, weights


def disc_stress(load, x, y, z, radius, layers, base, upper=True):
    """Stress (Pa, Voigt) at (x, y, z) from a unit uniform traction on a disc
    of radius `radius` at the origin: direct inverse 2D Fourier integral,
    Gauss-Legendre in k, trapezoid in the wavevector angle."""
    return _window_stress(load, x, y, z, ("disc", radius), layers, base, upper)


def cell_stress(load, x, y, z, pitch, layers, base, upper=True):
    """As disc_stress for a unit traction on a square cell of side `pitch`
    centred at the origin (FT pitch^2 sinc(kx pitch/2) sinc(ky pitch/2)): the
    C++ CellStress and LatticeTable entries (receptor offset = -(di, dj)
    pitch)."""
    return _window_stress(load, x, y, z, ("cell", pitch), layers, base, upper)


def _window_stress(load, x, y, z, window, layers, base, upper):
    li = LOADS.index(load)
    r = math.hypot(x, y)
    kind, size = window
    reach = r + (size if kind == "disc" else size / math.sqrt(2))
    k, wk = _k_nodes(reach, z)
    S = stress_xieta(k, z, layers, base, upper)  # (nk, 3, 3, 3)
    disc = 2 * math.pi * size * special.j1(k * size) / k
    total = np.zeros((3, 3), dtype=complex)
    for i in range(k.size):
        m = int(1.3 * k[i] * reach) + 48
        phi = 2 * math.pi * np.arange(m) / m
        c, s = np.cos(phi), np.sin(phi)
        if kind == "disc":
            win = np.full(m, disc[i])
        else:
            win = (
                size
                * size
                * np.sinc(k[i] * c * size / (2 * math.pi))
                * np.sinc(k[i] * s * size / (2 * math.pi))
            )
        # Rotation from (xi, eta, z) to (x, y, z): columns xi, eta, z.
        R = np.zeros((m, 3, 3))
        R[:, 0, 0], R[:, 0, 1] = c, -s
        R[:, 1, 0], R[:, 1, 1] = s, c
        R[:, 2, 2] = 1.0
        if li == 0:
            Sx = np.broadcast_to(S[i, 0], (m, 3, 3))
        else:
            qx, qy = (1.0, 0.0) if li == 1 else (0.0, 1.0)
            q_xi = c * qx + s * qy
            q_eta = -s * qx + c * qy
            Sx = q_xi[:, None, None] * S[i, 1] + q_eta[:, None, None] * S[i, 2]
        cart = np.einsum("mab,mbc,mdc->mad", R, Sx, R)
        phase = np.exp(1j * k[i] * (x * c + y * s))
        total += np.einsum("m,mab->ab", phase * win, cart) * (2 * math.pi / m) * wk[i] * k[i]
    total /= 4 * math.pi**2
    out = total.real
    return np.array([out[0, 0], out[1, 1], out[2, 2], out[0, 1], out[0, 2], out[1, 2]])


def disc_pressure_axisym(r, z, radius, layers, base, upper=True):
    """Unit pressure on a disc, classical Hankel route with j0 / j1:
    returns (s_rr, s_tt, s_zz, s_rz)."""
    k, wk = _k_nodes(r + radius, z)
    T = transfer(k, z, layers, base, upper)
    w = wk * radius * special.j1(k * radius)  # k * 2 pi a J1(ka)/k / (2 pi)
    j0, j1 = special.j0(k * r), special.j1(k * r)
    szz = np.sum(w * T["p_zz"] * j0)
    ssum = np.sum(w * (T["p_xixi"] + T["p_etaeta"]) * j0)
    # s_rr - s_tt = -H2[p_xixi - p_etaeta]; J2 = 2 J1 / x - J0.
    x = k * r
    j2 = np.where(x > 1e-8, 2 * j1 / np.where(x > 0, x, 1) - j0, x * x / 8)
    sdif = -np.sum(w * (T["p_xixi"] - T["p_etaeta"]) * j2)
    srz = -np.sum(w * T["p_xiz"] * j1)
    return 0.5 * (ssum + sdif), 0.5 * (ssum - sdif), szz, srz


def _self_check():
    ok = True
    # Homogeneous half-space as layers: disc on the axis (REFERENCE.md sec 3).
    nu, E, a = 0.45, 50e3, 1e-3
    layers = [(0.3e-3, E, nu), (0.9e-3, E, nu)]
    base = (E, nu)
    for z in (0.2e-3, 0.3e-3, 1.5e-3):
        ref = -(1 - z**3 / (a * a + z * z) ** 1.5)
        s = disc_stress("pressure", 0.0, 0.0, z, a, layers, base)
        h = disc_pressure_axisym(0.0, z, a, layers, base)
        err = max(abs(s[2] - ref), abs(h[2] - ref))
        print(
            f"disc axis z={z * 1e3:.2f} mm: s_zz {s[2]:.10f} hankel {h[2]:.10f}"
            f" closed {ref:.10f} err {err:.1e}"
        )
        ok &= err < 1e-8
    # Two routes agree off the axis on a real stack (s_xx at y = 0 is s_rr).
    shao = [(0.7e-3, 80e3, 0.48), (0.8e-3, 50e3, 0.48), (2.5e-3, 24e3, 0.4)]
    s = disc_stress("pressure", 0.8e-3, 0.0, 0.7e-3, a, shao, None)
    h = disc_pressure_axisym(0.8e-3, 0.7e-3, a, shao, None)
    err = max(abs(s[0] - h[0]), abs(s[1] - h[1]), abs(s[2] - h[2]), abs(s[4] - h[3]))
    print(f"shao off-axis, angular vs hankel: max diff {err:.1e}")
    ok &= err < 1e-8
    # Layer on bone: closed-form compliance.
    for nu in (0.3, 0.49):
        H = 1.5e-3
        kh = np.array([0.1, 1.0, 5.0, 20.0])
        k3 = 3 - 4 * nu
        ref = (
            2
            * (1 - nu * nu)
            / (E * kh / H)
            * (k3 * np.sinh(2 * kh) - 2 * kh)
            / (k3 * np.cosh(2 * kh) + 2 * kh**2 + 5 - 12 * nu + 8 * nu * nu)
        )
        c = surface_compliance(kh / H, [(H, E, nu)], None)
        err = np.max(np.abs(c / ref - 1))
        print(f"layer on bone nu={nu}: compliance rel err {err:.1e}")
        ok &= err < 1e-10
    print("PASS" if ok else "FAIL")
    return ok


def compare_dump(path):
    """Compare values written by `test_layered --dump` with this oracle."""
    with open(path) as f:
        dump = json.load(f)
    worst = 0.0
    for case in dump["cases"]:
        layers = [tuple(layer) for layer in case["layers"]]
        base = None if case["base"] is None else tuple(case["base"])
        for pt in case["disc"]:
            ref = disc_stress(
                pt["load"], pt["x"], pt["y"], pt["z"], pt["radius"], layers, base, pt["upper"]
            )
            got = np.array(pt["stress"])
            err = np.max(np.abs(got - ref)) / max(np.max(np.abs(ref)), 1e-30)
            worst = max(worst, err)
            print(
                f"{case['name']} {pt['load']} z={pt['z'] * 1e3:.2f} mm "
                f"x={pt['x'] * 1e3:.2f} y={pt['y'] * 1e3:.2f}: rel err {err:.1e}"
            )
        for pt in case.get("cell", []):
            ref = cell_stress(
                pt["load"], pt["x"], pt["y"], pt["z"], pt["pitch"], layers, base, pt["upper"]
            )
            got = np.array(pt["stress"])
            err = np.max(np.abs(got - ref)) / max(np.max(np.abs(ref)), 1e-30)
            worst = max(worst, err)
            print(
                f"{case['name']} cell {pt['load']} z={pt['z'] * 1e3:.2f} mm "
                f"x={pt['x'] * 1e3:.2f} y={pt['y'] * 1e3:.2f}: rel err {err:.1e}"
            )
        for tr in case.get("transfer", []):
            ref = transfer(np.array([tr["k"]]), tr["z"], layers, base, tr["upper"])
            got = tr["values"]
            scale = max(abs(ref[name][0]) for name in got) or 1.0
            err = max(abs(got[name] - ref[name][0]) for name in got) / scale
            worst = max(worst, err)
    print(f"max relative error (of the largest component): {worst:.2e}")
    return worst


if __name__ == "__main__":
    if len(sys.argv) > 1:
        sys.exit(0 if compare_dump(sys.argv[1]) < 1e-5 else 1)
    sys.exit(0 if _self_check() else 1)
