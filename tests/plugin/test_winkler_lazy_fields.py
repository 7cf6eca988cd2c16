"""The Winkler fast path's lazily written traction arrays (contact/winkler.cc:
WriteWinklerSlipTraction writes the float pressure, and pressure_pa only for
the `pressure` output; MaterializeTraction writes the shear arrays for the
stress paths that read them). Every consumer must see the field the eager
path wrote: the stress paths that read the shear arrays (fft, tree) against
the folded direct sum, which reads the pressure alone."""

import mujoco
import numpy as np
from conftest import pad_scene

from mjtouch.scene.sensor import SkinLayout


def _run(skin: dict[str, str], steps: int = 120) -> dict[str, np.ndarray]:
    model = mujoco.MjModel.from_xml_string(
        pad_scene({"pressure": "winkler", "nx": "64", "outputs": "stress force pressure", **skin})
    )
    data = mujoco.MjData(model)
    # pushed sideways: a tangential contact force, so the shear is nonzero
    data.xfrc_applied[model.body("finger").id, 0] = 0.2
    layout = SkinLayout.from_model(model)
    out = {"stress": [], "force": [], "pressure": []}
    for _ in range(steps):
        mujoco.mj_step(model, data)
        for k in out:
            out[k].append(layout.block(data.sensordata, k).copy())
    return {k: np.array(v) for k, v in out.items()}


def rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2) / np.mean(b**2)))


def test_shear_reading_stress_paths_see_the_lazy_shear():
    direct = _run({"stress_method": "direct"})
    fft = _run({"stress_method": "fft"})
    no_shear = _run({"stress_method": "fft", "shear": "false"})
    # the same contact: MuJoCo's force and the pressure output (pressure_pa)
    assert direct["force"].tobytes() == fft["force"].tobytes()
    assert direct["pressure"].tobytes() == fft["pressure"].tobytes()
    touching = direct["force"][:, 0] > 0
    assert touching.sum() > 50
    # the pressure output carries MuJoCo's normal force (sum p A = F)
    h = 1.5e-4  # pad_spec's pitch
    sums = direct["pressure"][touching].sum(axis=1) * h * h
    np.testing.assert_allclose(sums, direct["force"][touching, 0], rtol=1e-9)
    # FFT and direct sums of the same tables agree to float round-off; the
    # shear's share of the stress is far above that (so zero shear arrays
    # would fail the first assertion)
    s_direct, s_fft = direct["stress"][touching], fft["stress"][touching]
    assert np.abs(s_direct).max() > 0
    assert rel_rms(s_fft, s_direct) < 1e-4
    assert rel_rms(no_shear["stress"][touching], s_direct) > 1e-2
