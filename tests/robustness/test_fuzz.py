"""Property-based: random attributes and geometry give a clear error or a
finite result, never a crash; load/unload loops do not grow memory."""

import gc
import resource

import mujoco
import numpy as np
from conftest import add_geom, pad_scene, pad_spec, registered_attributes
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

# Ranges drawn for the numeric attributes, inside their valid ranges
# (plugin/core/pipeline/attributes.cc; test_fuzz_ranges_are_valid). Draws inside
# a range are log-uniform where the range is positive; the nx and depth
# ranges are narrowed to keep kernel builds fast (tests/robustness/test_hard_cases.py
# covers 10 um and 20 mm); out-of-range and malformed values come from
# `anything` below.
LOG_RANGES = {
    "pitch": (5e-5, 1e-2),
    "ridge_pitch": (1e-4, 1e-2),
    "ridge_height": (1e-6, 1e-3),
    "young": (1e2, 1e10),
    "tolerance": (1e-6, 0.1),
    "stiffness": (1e5, 1e12),
    "radius": (1e-4, 0.1),
    "sa1_k0": (1e-20, 1e-6),
    "sa1_k1": (1e-20, 1e-6),
    "sa1_c": (1e-14, 1),
    "sa1_r": (1e3, 1e15),
    "sa1_vth": (1e-4, 10),
    "ra_gain": (1e-8, 1),
    "ra_tau": (1e-5, 10),
    "pc_gain": (1e-8, 1),
    "pc_tau": (1e-5, 10),
    "pc_highpass": (1, 1e5),
    "refractory": (1e-5, 1),
    "ra_lowpass": (1, 1e4),
    "pc_lowpass": (1, 1e5),
    "noise_tau": (1e-5, 10),
    "rate_tau": (1e-4, 100),
    "stress_theta": (0.05, 2),
    "sa1_lowpass": (1, 1e4),
    "ra_saturation": (1e-3, 1e6),
    "ra_sustained": (1e-3, 1e6),
    "ra_sustained_tau": (1e-4, 10),
    "pc_saturation": (1e-3, 1e6),
    "pc_refractory": (1e-5, 1),
    "sa1_saturation": (1e-3, 1e12),
}
LINEAR_RANGES = {"ridge_angle": (-180, 180), "poisson": (-0.99, 0.5), "sa1_i0": (-1e-6, 1e-6)}
INTEGER_RANGES = {"nx": (4, 40), "texture_group": (0, 5), "threads": (1, 3), "grid_cycle": (1, 4)}
CHOICES = {
    "ridges": ["true", "false", "1", "0"],
    "shear": ["true", "false"],
    "ridge_profile": ["sine", "triangle", "square"],
    "pressure": ["contacts", "winkler", "elastic"],
    "contact_solver": ["pcg", "pk"],
    "elastic_precision": ["float", "double"],
    "grid_shift": ["true", "false"],
    "substep": ["full", "receptors"],
    "visual": ["none", "pad", "above", "both"],
    "skin": ["layered", "halfspace"],
    "interface_side": ["upper", "lower"],
    "stress_method": ["auto", "direct", "fft", "tree"],
    "oversample": ["auto", "1", "2", "3"],
    "texture": ["", "texture", "plate", "texture plate"],
    "sa1_model": ["filtered", "wang2016"],
    "population": ["uniform", "varied"],
    "facing": ["0 0 -1", "1 0 0", "0 -1 1", "0 0 1"],
    "pad_geom": ["", "pad"],
}
CLASSES = ["SA1", "RA", "PC"]
QUANTITIES = ["szz", "maxcomp", "vonmises", "maxshear", "sed", "strain"]
OUTPUTS = ["spikes", "stress", "voltage", "force", "pressure", "rate", "coverage"]

anything = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64).map(repr),
    st.integers(-(10**20), 10**20).map(str),
    st.sampled_from(
        [
            "0",
            "-1",
            "1e-300",
            "1e300",
            "0.5",
            "4",
            "512",
            "513",
            "1e-4",
            "3e-3",
            "nan",
            "inf",
            "-inf",
            "1 2",
            ";",
            "",
            "true",
            "pad",
            "SA1 0 0 1e-3 RA",
            "1e-3 5e4 0.45; 1e-3",
            "rigid 0.3",
            "spikes rate rate",
            "sed sed",
        ]
    ),
    st.text(alphabet="abcdefSAPCR1 .-e;,", max_size=12),
)


def log_uniform(lo, hi):
    return st.floats(np.log10(lo), np.log10(hi)).map(lambda e: repr(float(10.0**e)))


def words(vocabulary, n=None):
    """n (or 1 to all) space-separated words of `vocabulary`."""
    size = dict(min_size=n, max_size=n) if n else dict(min_size=1, max_size=len(vocabulary))
    return st.lists(st.sampled_from(vocabulary), **size).map(" ".join)


def numbers(lo, hi, n_min, n_max=None):
    return st.lists(log_uniform(lo, hi), min_size=n_min, max_size=n_max or n_min).map(" ".join)


layer = st.tuples(
    log_uniform(1e-5, 3e-2), log_uniform(1e2, 1e7), st.floats(-0.99, 0.5).map(repr)
).map(" ".join)


@st.composite
def sites(draw):
    """1-6 entries 'CLASS x y depth', one depth per class (the rule)."""
    depth = {c: draw(log_uniform(1e-5, 2e-2)) for c in CLASSES}
    entries = draw(
        st.lists(
            st.tuples(st.sampled_from(CLASSES), st.floats(-2e-3, 2e-3), st.floats(-2e-3, 2e-3)),
            min_size=1,
            max_size=6,
        )
    )
    return "; ".join(f"{c} {x!r} {y!r} {depth[c]}" for c, x, y in entries)


LIST_VALUES = {
    "classes": words(CLASSES),
    "quantity": words(QUANTITIES, 3),
    "outputs": words(OUTPUTS),
    "density": numbers(1, 1e4, 3),
    "depth": numbers(1e-5, 2e-2, 3),
    "noise": numbers(1e-3, 100, 3),
    "adapt": numbers(1e-3, 100, 3),
    "adapt_tau": numbers(1e-5, 10, 3),
    "sa1_merkel": numbers(1, 1000, 1, 4),
    "seed": st.integers(0, 2**64 - 1).map(str),
    "layers": st.lists(layer, min_size=1, max_size=4).map("; ".join),
    "base": st.one_of(
        st.just("rigid"),
        st.tuples(log_uniform(1e2, 1e7), st.floats(-0.99, 0.5).map(repr)).map(" ".join),
    ),
    "sites": sites(),
}


def valid_values(key):
    """Values in the attribute's own valid range (combinations may still be
    invalid: ridge_pitch vs pitch, depth vs layers, radius vs the grid)."""
    if key in LOG_RANGES:
        good = log_uniform(*LOG_RANGES[key])
    elif key in LINEAR_RANGES:
        good = st.floats(*LINEAR_RANGES[key]).map(repr)
    elif key in INTEGER_RANGES:
        good = st.integers(*INTEGER_RANGES[key]).map(str)
    elif key in CHOICES:
        good = st.sampled_from(CHOICES[key])
    else:
        good = LIST_VALUES[key]
    return good


def test_every_registered_attribute_is_fuzzed():
    strategies = (
        set(LOG_RANGES) | set(LINEAR_RANGES) | set(INTEGER_RANGES) | set(CHOICES) | set(LIST_VALUES)
    )
    assert set(registered_attributes()) == strategies


@st.composite
def attribute_sets(draw):
    keys = draw(
        st.lists(st.sampled_from(registered_attributes()), min_size=1, max_size=8, unique=True)
    )
    # at most one attribute gets an arbitrary (usually bad) value: most sets
    # compile and run, and each error has one culprit
    # (hypothesis favours small integers: i < 4, no bad value, is common)
    i = draw(st.integers(0, len(keys) + 3))
    bad = keys[i - 4] if i >= 4 else None
    cfg = {"nx": "24", "pitch": "2e-4", "texture": ""}
    for k in keys:
        cfg[k] = draw(anything if k == bad else valid_values(k))
    return cfg


size = st.floats(1e-4, 0.03)
pad_size = st.one_of(st.floats(2.5e-3, 0.03), st.floats(2.5e-3, 0.03), size)  # mostly fits the skin
pads = st.one_of(
    st.tuples(st.just("sphere"), pad_size),
    # cylinder: not a pad shape (an error naming the geom)
    st.tuples(
        st.sampled_from(["cylinder", "ellipsoid", "box", "capsule"]), pad_size, pad_size, pad_size
    ),
)
obstacles = st.lists(
    st.tuples(
        st.sampled_from(["sphere", "box", "capsule", "cylinder", "ellipsoid"]),
        st.tuples(size, size, size),
        st.tuples(st.floats(-0.01, 0.01), st.floats(-0.01, 0.01), st.floats(-0.005, 0.01)),
    ),
    max_size=3,
)
angles = st.tuples(st.floats(-180, 180), st.floats(-180, 180), st.floats(-180, 180))


def scene(cfg, pad, euler, obstacles, drop):
    """pad_spec with the drawn pad (kind, sizes...), its orientation (degrees),
    the obstacles (kind, size, pos) and the pad dropped from drop m higher."""
    spec = pad_spec(cfg, pad={"kind": pad[0], "size": pad[1:], "euler_deg": euler})
    for kind, size, pos in obstacles:
        add_geom(spec.worldbody, kind, size, pos=list(pos))
    spec.body("finger").pos = [0, 0, 0.0071 + drop]
    return spec


def named_in(msg: str, cfg: dict) -> bool:
    """The plugin's message names (in backticks) an attribute that was set,
    or one it says is at its default, or the pad geom."""
    ours = [line for line in msg.splitlines() if line.startswith("mjtouch.skin: ")]
    return bool(ours) and (
        any(f"`{k}`" in ours[0] for k in cfg) or "(default)" in ours[0] or "pad geom" in ours[0]
    )


# Deterministic (derandomize: the same examples every run, no example
# database) and bounded: about half the sets compile and run 30 steps;
# 500 examples take ~13 s here.
@settings(
    max_examples=500,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(
    cfg=attribute_sets(), pad=pads, euler=angles, obstacles=obstacles, drop=st.floats(-0.002, 0.01)
)
def test_random_attributes_and_geometry_error_or_finite(cfg, pad, euler, obstacles, drop):
    spec = scene(cfg, pad, euler, obstacles, drop)  # with a height-field texture
    try:
        m = spec.compile()
    except ValueError as e:
        # a clear error: the plugin's message names the attribute or geom
        assert named_in(str(e), cfg), (str(e), cfg)
        return
    d = mujoco.MjData(m)
    for _ in range(30):
        mujoco.mj_step(m, d)
    assert np.all(np.isfinite(d.sensordata)), cfg
    assert np.all(np.isfinite(d.plugin_state)), cfg


def _rss_kib() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def test_model_load_unload_does_not_grow_memory():
    # Each model holds a shared kernel table (~2 MB at nx 64); after warm-up,
    # 150 more load/step/free cycles must not grow the resident set by more
    # than a few table sizes (allocator slack), i.e. nothing leaks per cycle.
    xml = pad_scene({"nx": "64"})

    def cycle():
        m = mujoco.MjModel.from_xml_string(xml)
        d = mujoco.MjData(m)
        for _ in range(20):
            mujoco.mj_step(m, d)
        d2 = mujoco.MjData(m)
        mujoco.mj_copyData(d2, m, d)
        del d, d2, m

    for _ in range(20):
        cycle()
    gc.collect()
    before = _rss_kib()
    for _ in range(150):
        cycle()
    gc.collect()
    growth_kib = _rss_kib() - before
    assert growth_kib < 8 * 1024, f"resident memory grew by {growth_kib} KiB over 150 cycles"


def _table_ranges():
    """The plugin's own valid ranges (plugin/core/pipeline/attributes.cc)."""
    from mjtouch import _core

    return {r["key"]: r for r in _core.attribute_ranges()}


def test_fuzz_ranges_are_valid():
    # every range drawn above lies inside the attribute's valid range, so a
    # "valid" draw that fails names a real cross-attribute problem
    table = _table_ranges()
    for key, (lo, hi) in {**LOG_RANGES, **LINEAR_RANGES, **INTEGER_RANGES}.items():
        r = table[key]
        assert (lo > r["lo"]) if r["lo_open"] else (lo >= r["lo"]), (key, lo, r)
        assert (hi < r["hi"]) if r["hi_open"] else (hi <= r["hi"]), (key, hi, r)
    for key, (lo, hi) in {"density": (1, 1e4), "depth": (1e-5, 2e-2), "noise": (1e-3, 100)}.items():
        r = table[key]
        assert r["kind"] == "per_class" and lo >= r["lo"] and hi <= r["hi"], (key, r)
