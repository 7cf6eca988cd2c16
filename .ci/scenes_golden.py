"""Record the shipped scenes' sensordata (0.3 s each) to compare two builds
bit for bit across refactors:
    python .ci/scenes_golden.py record before.npz   # on the old build
    python .ci/scenes_golden.py record after.npz    # on the new build
    python .ci/scenes_golden.py compare before.npz after.npz
(a rounding-level change: compare prints, per sensordata block, the largest
difference over each channel's largest value, and the spike totals).
Press 0.5 N from t = 0, slide at 40 mm/s from t = 0.1 s."""

import pathlib
import sys

import numpy as np

SCENES = ("slide_flat", "slide_grating", "slide_grating_smooth")


def record(out):
    import mujoco

    import mjtouch  # noqa: F401  (registers the plugin)

    models = pathlib.Path(__file__).resolve().parents[1] / "models"
    arrays = {}
    for name in SCENES:
        m = mujoco.MjModel.from_xml_path(str(models / f"{name}.xml"))
        d = mujoco.MjData(m)
        n = int(round(0.3 / m.opt.timestep))
        sd = np.empty((n, m.nsensordata))
        for i in range(n):
            d.ctrl[:] = (0.04 if d.time >= 0.1 else 0.0, 0.5)  # slide (m/s), press (N)
            d.ctrl[1] = -0.5
            mujoco.mj_step(m, d)
            sd[i] = d.sensordata
        arrays[name] = sd
        print(f"{name}: {n} steps x {m.nsensordata} sensordata, sum {sd.sum():.17g}")
    np.savez(out, **arrays)


def compare(a, b):
    A, B = np.load(a), np.load(b)
    ok = True
    for name in SCENES:
        same = A[name].shape == B[name].shape and np.array_equal(A[name], B[name])
        ok &= same
        print(f"{name}: {'bit-identical' if same else 'DIFFERENT'}")
        if not same and A[name].shape == B[name].shape:
            print("  " + "; ".join(_block_differences(name, A[name], B[name])))
    sys.exit(0 if ok else 1)


def _block_differences(name, x, y):
    import mujoco

    from mjtouch.sensor import SkinLayout

    models = pathlib.Path(__file__).resolve().parents[1] / "models"
    layout = SkinLayout.from_model(mujoco.MjModel.from_xml_path(str(models / f"{name}.xml")))
    out = []
    for block in layout.blocks:
        a = np.stack([layout.block(r, block) for r in x])
        b = np.stack([layout.block(r, block) for r in y])
        if block == "spikes":
            out.append(
                f"spikes {a.sum():.0f} -> {b.sum():.0f} ({int((a != b).sum())} entries differ)"
            )
            continue
        scale = np.abs(a).max(axis=0)
        scale[scale == 0] = 1.0
        rel = (np.abs(a - b) / scale).max(axis=0)
        out.append(
            f"{block}: max {rel.max():.1e}, median {np.median(rel):.1e} of each channel's largest"
        )
    return out


if __name__ == "__main__":
    {"record": record, "compare": compare}[sys.argv[1]](*sys.argv[2:])
