"""`grid_shift` (plugin/core/pipeline/grid_shift.h): the `elastic` contact
solved again on the taxel grid shifted by half a cell, deposited back and
averaged. Against Hertz (the averaged field is still the elastic solution:
same oracle, same tolerance as test_contact_hertz.py) and against the
default (no shift) on the sliding scene, where it must cancel the line at
V / pitch that edges sharper than a cell put in the PC stress
(examples/pc_grid_line_static.py, examples/pc_grid_shift.py)."""

import mujoco
import numpy as np
import pytest
from conftest import fast_tip, hertz_sphere_press

from mjtouch import analysis
from mjtouch.analysis import reference_solutions
from mjtouch.bench.configs import lattice_sites
from mjtouch.experiments import rollout
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

E, NU = 80e3, 0.48
SPEED = 0.025


def test_grid_shift_sphere_pad_matches_hertz():
    # as test_elastic_sphere_pad_matches_hertz (32 cells per contact radius,
    # errors below 1e-3 there); the deposit widens each shifted cell's load
    # by half a cell, which moves the second-moment radius by ~(h/a)^2 / 6 =
    # 1.6e-4 and the peak by ~(h/a)^2 / 8
    h = reference_solutions.Hertz(load_n=0.5, radius_m=0.2, young_pa=E, poisson=NU)
    force, p, pitch = hertz_sphere_press(h, E, NU, grid_shift="true")
    n = p.shape[0]
    assert force[0] == pytest.approx(h.load_n, rel=1e-6)
    assert p.sum() * pitch**2 == pytest.approx(force[0], rel=1e-6)
    err = reference_solutions.hertz_errors(h, p, pitch, force[3])
    assert all(abs(v) < 1e-3 for v in err.values()), err
    # symmetric about the pole like the load (the shifted grid's cells
    # straddle it): the centroid stays on it to well under a cell
    x = (np.arange(n) - (n - 1) / 2) * pitch
    assert abs((p.sum(0) * x).sum() / p.sum()) < 1e-3 * pitch
    assert abs((p.sum(1) * x).sum() / p.sum()) < 1e-3 * pitch


def _slide(grid_shift: str, nx: int = 65, pitch: float = 2e-4):
    tip = scenes.Fingertip(
        nx=nx,
        pitch_m=pitch,
        skin={
            "noise": "0 0 0",
            "sites": lattice_sites([(nx, pitch)]),
            "grid_shift": grid_shift,
            "grid_cycle": "1",  # against the taxel grid alone (grid_shift turns the cycle off)
        },
    )
    r = rollout.run_slide(
        tip, scenes.Texture(), scenes.Protocol(speed_m_s=SPEED, force_n=0.5), duration_s=0.25
    )
    w, m = r.window(), r.layout.mask("PC")
    f, p = analysis.stress_spectrum(r.stress[w][:, m], r.dt)
    hw = max(3.0, 1.5 * (f[1] - f[0]))
    band = lambda fc: float(p[np.abs(f - fc) <= hw].max())  # noqa: E731
    return (
        r,
        band(SPEED / pitch),
        band(SPEED / 1e-3),
        analysis.rates_hz(r.spikes[w], r.dt, r.layout.classes)["PC"],
    )


def test_grid_shift_cancels_the_v_over_pitch_line():
    # 65 x 0.2 mm, 25 mm/s over the 1 mm grating: the grid's line at V/pitch
    # = 125 Hz (measured 38 Pa^2 without the shift, 0.30 with it); the
    # grating's own line at V/D = 25 Hz stays (measured 93 -> 81 Pa^2: the
    # two grids sample the ridges differently); the PC rate the grid line
    # drove falls (143 -> 116 Hz; 184 -> 101 before the PC's 2.5 ms
    # refractory period capped its bursts at 400 Hz)
    r0, line0, vd0, pc0 = _slide("false")
    r1, line1, vd1, pc1 = _slide("true")
    assert line1 * 30 < line0
    assert vd1 == pytest.approx(vd0, rel=0.25)
    assert pc1 < 0.9 * pc0
    # the sliding itself is MuJoCo's and the same; the shift is deterministic
    assert np.array_equal(r0.finger_x_m, r1.finger_x_m)
    r2, *_ = _slide("true")
    assert np.array_equal(r1.stress, r2.stress) and np.array_equal(r1.spikes, r2.spikes)


def test_grid_shift_warm_start_from_its_history_reaches_the_cold_solution():
    # the shifted solve starts from its own history in plugin_state
    # (extrapolated 2 p(n-1) - p(n-2), its K p by linearity from the stored
    # displacements); that may change where the CG starts, never the
    # solution: one step from a sliding state must give the pressure of the
    # same step with the plugin state cleared (both solves cold, uniform
    # start). Tolerance 1e-9: what is left is the float history's rounding
    # (K p stored as floats), measured 3e-6 relative L1 without grid_shift
    # and 2e-6 with it; a stale or mis-placed history, or a wrong K p0,
    # converges elsewhere
    proto = scenes.Protocol(timestep_s=2e-4, press_s=0.05)
    tip = fast_tip(
        skin={
            "pressure": "elastic",
            "grid_shift": "true",
            "tolerance": "1e-9",
            "outputs": "force pressure",
            "noise": "0 0 0",
        }
    )
    m = scenes.build_model(tip, scenes.Texture(period_m=0.6e-3), proto)
    layout = SkinLayout.from_model(m)
    d = mujoco.MjData(m)
    for _ in range(320):  # pressed at 0.05 s, then sliding at 30 mm/s
        d.ctrl[:] = [0.03 if d.time > 0.05 else 0.0, -0.5]
        mujoco.mj_step(m, d)
    cold = mujoco.MjData(m)
    mujoco.mj_copyData(cold, m, d)
    cold.plugin_state[:] = 0.0
    for data in (d, cold):
        mujoco.mj_step(m, data)
    warm_p = layout.block(d.sensordata, "pressure")
    cold_p = layout.block(cold.sensordata, "pressure")
    assert warm_p.sum() > 0
    assert np.abs(warm_p - cold_p).sum() < 1e-5 * np.abs(cold_p).sum()
