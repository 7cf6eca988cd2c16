"""The folded direct stress path (plugin/core/stress/stress_fold.h) against
the reference direct sum, on the default skin's real lattice tables and a real
contact field, and the stage's thread pool (bit-identical for any count)."""

import math

import mujoco
import numpy as np
import pytest

from mjtouch import core
from mjtouch.scene import scenes
from mjtouch.scene.sensor import SkinLayout

# Stated tolerance of the folded path (issue 13): relative RMS over every
# site and component. Folding rounds each table entry once more in float
# (~6e-8 relative) and widens the float lanes to double every 8 rows.
REL_RMS_TOL = 1e-5


def _rel_rms(a, ref):
    return math.sqrt(float(((a - ref) ** 2).sum()) / float((ref**2).sum()))


@pytest.fixture(scope="module")
def sliding_contact():
    """The default fingertip (128 x 0.1 mm, ridged) pressed with 0.5 N onto
    the default grating and slid for 20 ms: the plugin's pressure field and
    MuJoCo's friction ratio (F_t / F_n) of the last step."""
    tip = scenes.Fingertip(skin={"outputs": "force pressure"})
    proto = scenes.Protocol(force_n=0.5)
    model = scenes.build_model(tip, scenes.Texture(), proto)
    data = mujoco.MjData(model)
    layout = SkinLayout.from_model(model)
    for row in scenes.controls(proto, 0.02):
        data.ctrl[:] = row
        mujoco.mj_step(model, data)
    n = layout.nx
    p = layout.block(data.sensordata, "pressure").reshape(n, n).astype(np.float32)
    f = layout.block(data.sensordata, "force")
    assert f[0] > 0.1 and (p > 0).sum() > 500, "the pad must press on the grating"
    return tip, p, (f[1] / f[0], f[2] / f[0])


def _spiral_sites(n, h):
    """(cells, classes) of 120 sites on a spiral over the contact and beyond;
    class 0: SA1 (six components), 1: RA, 2: PC (s_zz)."""
    golden = math.pi * (3 - math.sqrt(5))
    ij, cls = [], []
    for s in range(120):
        r = 5e-3 * math.sqrt((s + 0.5) / 120)
        ij.append(
            (
                int(np.clip(round(r * math.cos(s * golden) / h + n / 2), 0, n - 1)),
                int(np.clip(round(r * math.sin(s * golden) / h + n / 2), 0, n - 1)),
            )
        )
        cls.append(s % 3)
    return ij, np.array(cls)


def _stage_engine(n, h, ij, cls):
    comps = [range(6) if c == 0 else (2,) for c in cls]
    return core.StressEngine(
        core.LayeredSkin(),
        n,
        h,
        [0.75e-3, 2e-3],
        ij,
        depth_index=np.where(cls == 2, 1, 0),
        components=comps,
        method="direct",
    )


@pytest.fixture(scope="module")
def engine(sliding_contact):
    """The plugin's stress stage for the default skin: SA1 (all six
    components) and RA (s_zz) at 0.75 mm, PC (s_zz) at 2 mm, on a spiral of
    sites over the contact and beyond."""
    tip, _, _ = sliding_contact
    return _stage_engine(tip.nx, tip.pitch_m, *_spiral_sites(tip.nx, tip.pitch_m))


def test_folded_matches_reference_on_sliding_contact(sliding_contact, engine):
    _, p, ratio = sliding_contact
    assert abs(ratio[0]) > 0.1, "the pad must slide (friction shear present)"
    assert engine.mirror_symmetric  # the folded path's condition holds for the skin
    ref = engine.stress(p, slip=ratio, method="direct", fold=False)
    got = engine.stress(p, slip=ratio, method="direct")
    assert not np.array_equal(got, ref)  # another summation (folded) ran
    assert np.abs(ref).max() > 1e3  # kPa-scale stresses were compared
    assert _rel_rms(got, ref) <= REL_RMS_TOL
    # every component, not only the large ones
    for c in range(6):
        scale = np.abs(ref[:, c]).max()
        if scale > 0:
            assert np.abs(got[:, c] - ref[:, c]).max() <= REL_RMS_TOL * scale
    # the shear matters: without it the stress differs far beyond the tolerance
    no_shear = engine.stress(p, method="direct", fold=False)
    assert _rel_rms(no_shear, ref) > 100 * REL_RMS_TOL


def test_folded_pressure_only_matches_reference(sliding_contact, engine):
    _, p, _ = sliding_contact
    ref = engine.stress(p, method="direct", fold=False)
    got = engine.stress(p, method="direct")
    assert _rel_rms(got, ref) <= REL_RMS_TOL


def test_folded_path_handles_oblique_slip_and_edge_contact(engine):
    # A contact at the grid's corner (table offsets beyond the window's
    # edge) with slip along both axes; reference from explicit shear fields.
    n = engine.n
    p = np.zeros((n, n), np.float32)
    yy, xx = np.mgrid[0:n, 0:n]
    p[(xx - 3) ** 2 + (yy - n + 5) ** 2 < 60] = 2e3
    p[n // 2, n // 2 + 7] = 5e2  # a lone cell
    rx, ry = 0.3, -0.45
    qx = (rx * p.astype(np.float64)).astype(np.float32)
    qy = (ry * p.astype(np.float64)).astype(np.float32)
    ref = engine.stress(p, qx, qy, method="direct", fold=False)
    got = engine.stress(p, qx, qy, method="direct", slip=(rx, ry))
    assert _rel_rms(got, ref) <= REL_RMS_TOL


def test_split_path_matches_reference_for_partial_slip_shear(sliding_contact, engine):
    # Partial slip's path (stress_fold.h FoldedSplitStresses): the pressure
    # folded at the full-slip ratio plus a coarse correction of the rest.
    # Shear of Cattaneo's shape on the real contact: mu p, less mu p scaled
    # down inside a central stick disk, direction fixed; the ratio r is its
    # total over the total pressure, so q - r p carries no net force.
    _, p, _ = sliding_contact
    n = engine.n
    yy, xx = np.mgrid[0:n, 0:n]
    loaded = p > 0
    cy, cx = (float(np.mean(v[loaded])) for v in (yy, xx))
    r_cells = np.sqrt(loaded.sum() / np.pi)
    stick = np.hypot(xx - cx, yy - cy) < 0.6 * r_cells
    mu = 0.8
    q = mu * p.astype(np.float64) * np.where(stick, 0.5, 1.0)
    e = np.array([0.8, -0.6])
    qx, qy = (q * e[0]).astype(np.float32), (q * e[1]).astype(np.float32)
    ratio = (float(qx.sum(dtype=np.float64) / p.sum()), float(qy.sum(dtype=np.float64) / p.sum()))
    ref = engine.stress(p, qx, qy, method="direct", fold=False)
    got = engine.stress(p, qx, qy, method="direct", slip=ratio, split=True)
    full = engine.stress(p, slip=ratio, method="direct")
    effect = _rel_rms(full, ref)  # what the correction carries
    assert effect > 100 * REL_RMS_TOL
    # the correction's error: the kernels' interpolation over the node
    # spacing (0.4 mm here, over sites 0.75 mm deep), a small part of it
    assert _rel_rms(got, ref) < 0.05 * effect, (_rel_rms(got, ref), effect)
    # with no correction to make (q = r p) the split path is the folded one
    fx = (ratio[0] * p.astype(np.float64)).astype(np.float32)
    fy = (ratio[1] * p.astype(np.float64)).astype(np.float32)
    uniform = engine.stress(p, fx, fy, method="direct", slip=ratio, split=True)
    assert _rel_rms(uniform, full) <= REL_RMS_TOL


def test_split_needs_slip_and_shear(sliding_contact, engine):
    _, p, _ = sliding_contact
    with pytest.raises(ValueError, match="split=True needs slip"):
        engine.stress(p, split=True)


@pytest.mark.parametrize("fold", [True, False])
def test_stress_bit_identical_for_any_thread_count(sliding_contact, engine, fold):
    _, p, ratio = sliding_contact
    one = engine.stress(p, slip=ratio, method="direct", fold=fold, threads=1)
    for threads in (2, 3, 8):
        assert np.array_equal(
            engine.stress(p, slip=ratio, method="direct", fold=fold, threads=threads), one
        )


# The stage in a fresh process (MJTOUCH_SUM_LANES is read once per process).
_STAGE_SCRIPT = """
import sys
import numpy as np
sys.path.insert(0, sys.argv[3])
from test_stress_fold import _spiral_sites, _stage_engine
d = np.load(sys.argv[1])
n, h = int(d["n"]), float(d["h"])
e = _stage_engine(n, h, *_spiral_sites(n, h))
np.save(sys.argv[2], e.stress(d["p"], slip=tuple(d["ratio"]), method="direct", fold=True))
"""


@pytest.mark.parametrize("lanes", ["8", "4"])
def test_every_vector_width_gives_the_same_bits(sliding_contact, engine, lanes, tmp_path):
    # The sums run in the widest vectors the CPU has (AVX-512: 16 floats,
    # AVX2: 8, else SSE2 / NEON: 4; stress_fold.cc SumBand); a 16-lane chunk
    # is 16 / width vectors doing the same elementwise operations, so every
    # width gives the same bits. MJTOUCH_SUM_LANES runs a narrower copy on
    # this CPU (8 where it has AVX2).
    import os
    import pathlib
    import subprocess
    import sys

    tip, p, ratio = sliding_contact
    np.savez(tmp_path / "in.npz", n=tip.nx, h=tip.pitch_m, p=p, ratio=np.array(ratio))
    widest = engine.stress(p, slip=ratio, method="direct", fold=True)
    env = {**os.environ, "MJTOUCH_SUM_LANES": lanes}
    subprocess.run(
        [
            sys.executable,
            "-c",
            _STAGE_SCRIPT,
            str(tmp_path / "in.npz"),
            str(tmp_path / "out.npy"),
            str(pathlib.Path(__file__).parent),
        ],
        env=env,
        check=True,
        timeout=300,
    )
    narrow = np.load(tmp_path / "out.npy")
    assert np.abs(widest).max() > 1e3, "the contact must load the sites"
    assert np.array_equal(narrow, widest)


def test_aligned_sums_and_rx_cache_are_the_legacy_bits(sliding_contact, engine):
    # The sums' aligned layout (table loads on 64-byte boundaries at dx
    # multiples of 16; stress_fold.cc SiteBand) and the fold from the cached
    # Kp + rx Kx (from the second call with the same float rx on) must give
    # the same bits as unaligned loads without the cache (fold_legacy), for
    # sites at every column mod 16 (every lane offset), contacts at the grid's
    # edges (the padded cells are read), with and without shear, on any thread
    # count, while rx repeats and after it changes.
    tip, p, ratio = sliding_contact
    n = engine.n
    ij = [(i, j) for j in (20, 64, 100) for i in range(56, 72)]  # 16 columns: every shift
    assert {i % 16 for i, _ in ij} == set(range(16))
    comps = [range(6) if k % 3 else (2,) for k in range(len(ij))]  # 1 and 6 components
    e = core.StressEngine(
        core.LayeredSkin(), n, tip.pitch_m, [0.75e-3], ij, components=comps, method="direct"
    )
    edge = np.zeros((n, n), np.float32)
    yy, xx = np.mgrid[0:n, 0:n]
    edge[(xx - 2) ** 2 + (yy - n + 4) ** 2 < 50] = 3e3  # at column 0 and the last row
    edge[(xx - n + 3) ** 2 + (yy - 5) ** 2 < 30] = 1e3  # at the last column
    rx_next = float(np.nextafter(np.float32(0.3), np.float32(1)))  # the next float rx
    for eng in (engine, e):
        for field, slip in (
            (p, ratio),
            (p, None),
            (edge, (0.3, -0.45)),
            (edge, (rx_next, 0.2)),
            (edge, (0.3, 0.2)),
        ):
            legacy = eng.stress(field, slip=slip, method="direct", fold_legacy=True)
            assert np.abs(legacy).max() > 0
            for threads in (1, 3, 1):  # the second call on reads the rx cache
                got = eng.stress(field, slip=slip, method="direct", threads=threads)
                assert np.array_equal(got, legacy)
    # the cache is of rx, not of the result: a new ry with the same rx
    a = e.stress(edge, slip=(0.3, 0.1), method="direct")
    assert np.array_equal(a, e.stress(edge, slip=(0.3, 0.1), method="direct", fold_legacy=True))
    assert not np.array_equal(a, e.stress(edge, slip=(0.3, 0.2), method="direct"))


def test_site_stress_does_not_depend_on_other_sites(sliding_contact):
    # A site's sum is its own fixed sequence of operations (what makes the
    # output the same for any thread split, and any future sharing of loads
    # between sites of a row): each site must get the bits it gets alone,
    # whichever sites share its lattice row (one-component pairs, a triple, a
    # six-component site between them, a site alone), on 1 and 3 threads,
    # with and without shear.
    tip, p, ratio = sliding_contact
    n = tip.nx
    ij = [(50, 64), (61, 64), (77, 64), (70, 64), (40, 40), (83, 40), (66, 90), (58, 20), (59, 20)]
    comps = [(2,), (2,), (2,), range(6), (2,), (2,), (2,), (0, 2), (2,)]
    e = core.StressEngine(
        core.LayeredSkin(), n, tip.pitch_m, [0.75e-3], ij, components=comps, method="direct"
    )
    alone = [
        core.StressEngine(
            core.LayeredSkin(), n, tip.pitch_m, [0.75e-3], [s], components=[c], method="direct"
        )
        for s, c in zip(ij, comps)
    ]
    for slip in (ratio, None):
        want = np.concatenate([a.stress(p, slip=slip, method="direct") for a in alone])
        assert np.abs(want[:, 2]).min() > 0  # every site under the contact's stress
        for threads in (1, 3):
            got = e.stress(p, slip=slip, method="direct", threads=threads)
            assert np.array_equal(got, want)


def test_fold_false_is_the_reference_sum(sliding_contact, engine):
    # fold=False with explicit shear fields is the same arithmetic as the
    # shear fields without slip information (the `contacts` model's path).
    _, p, ratio = sliding_contact
    qx = (ratio[0] * p.astype(np.float64)).astype(np.float32)
    qy = (ratio[1] * p.astype(np.float64)).astype(np.float32)
    a = engine.stress(p, qx, qy, method="direct")
    b = engine.stress(p, qx, qy, method="direct", slip=ratio, fold=False)
    assert np.array_equal(a, b)


def test_bad_thread_count_names_range(sliding_contact, engine):
    _, p, _ = sliding_contact
    with pytest.raises(ValueError, match=r"threads = 0 .*\[1, 64\]"):
        engine.stress(p, threads=0)
    with pytest.raises(ValueError, match=r"threads = 65 .*\[1, 64\]"):
        engine.stress(p, threads=65)


def test_cost_model_folded_direct_is_cheaper(engine):
    direct, fft = engine.estimated_cost(3000, shear=True, folded=False)
    folded, fft2 = engine.estimated_cost(3000, shear=True, folded=True)
    assert fft == fft2 and folded < direct / 2


def test_bench_stage_table_runs(sliding_contact, engine, capsys):
    # examples/bench_kernel.py's stage table (reference / folded / threads),
    # one short round: the three paths run and agree to the tolerance.
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[2] / "examples" / "bench_kernel.py"
    spec = importlib.util.spec_from_file_location("bench_kernel", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    _, p, ratio = sliding_contact
    times = bench.folded_stage(engine, p, ratio, rounds=1, repeats=1, threads=2)
    assert set(times) == {"reference", "folded (legacy layout)", "folded", "folded+2threads"}
    assert all(len(t) == 1 and t[0] > 0 for t in times.values())
    out = capsys.readouterr().out
    assert "reference / folded" in out and "legacy layout / folded" in out
    for line in out.splitlines():
        if "rel. RMS vs reference" in line:
            assert float(line.rsplit(" ", 1)[1]) <= REL_RMS_TOL


def test_bench_scene_stage_is_the_plugins():
    # bench_kernel --scene times the stage on a shipped scene's own sites and
    # contact: its engine must give the plugin's receptor quantity (szz
    # classes: -s_zz) at that step, to the folded path's tolerance.
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[2] / "examples" / "bench_kernel.py"
    spec = importlib.util.spec_from_file_location("bench_kernel", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    e, p, ratio, desc, plugin_q, szz = bench.scene_stage("slide_grating")
    assert (p > 0).sum() > 1000 and "181 receptors" in desc
    out = e.stress(p, slip=ratio, method="direct")
    assert szz.sum() > 100
    assert _rel_rms(-out[szz, 2], plugin_q[szz]) <= REL_RMS_TOL


def test_bench_baseline_build_in_one_process(sliding_contact, engine, tmp_path, capsys):
    # bench_kernel --baseline-core: another build's _core (here a copy of this
    # one's, so the same code) loaded next to this build's in one process;
    # its engine must run on its own module and give this build's bits, and
    # the stage table must time it and report the comparison.
    import importlib.util
    import pathlib
    import shutil

    from mjtouch import _core

    path = pathlib.Path(__file__).resolve().parents[2] / "examples" / "bench_kernel.py"
    spec = importlib.util.spec_from_file_location("bench_kernel", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    copy = tmp_path / pathlib.Path(_core.__file__).name
    shutil.copy(_core.__file__, copy)
    base = bench.load_baseline_core(copy)
    assert base is not _core and base.__file__ == str(copy)
    tip, p, ratio = sliding_contact
    n, h = tip.nx, tip.pitch_m
    ij = [(40, 60), (64, 64), (70, 90), (90, 50)]
    comps = [range(6), (2,), range(6), (2,)]
    with bench.using_core(base):
        e_base = core.StressEngine(
            core.LayeredSkin(), n, h, [0.75e-3], ij, components=comps, method="direct"
        )
    assert isinstance(e_base._e, base.StressEngine)
    assert not isinstance(e_base._e, _core.StressEngine)
    e = core.StressEngine(
        core.LayeredSkin(), n, h, [0.75e-3], ij, components=comps, method="direct"
    )
    got = e_base.stress(p, slip=ratio, method="direct")
    assert np.abs(got).max() > 1e3
    assert np.array_equal(got, e.stress(p, slip=ratio, method="direct"))
    e.baseline = e_base
    times = bench.folded_stage(e, p, ratio, rounds=1, repeats=1, threads=2)
    assert len(times["folded (baseline build)"]) == 1
    assert "same bits: True" in capsys.readouterr().out
