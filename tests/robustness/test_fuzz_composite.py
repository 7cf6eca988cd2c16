"""Property-based: composite attribute values (lists, entries, separators,
extreme numbers), any `layers` value and structural edits of the scene each
give a clear error or a sane run (fuzz_cases.classify), in a worker process
with a time limit: a hang fails the test instead of stalling the suite."""

import numpy as np
import pytest
from fuzz_cases import STRUCTURAL, Runner, classify, scene_xml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from test_fuzz import LIST_VALUES

# Generous next to the bounded kernel build (~1-2 s at its bound on one
# core): the limit catches hangs (a 1e-30 m layer never returned), not speed.
TIMEOUT_S = 60.0

COMPOSITE = [
    "layers",
    "sites",
    "noise",
    "density",
    "depth",
    "adapt",
    "adapt_tau",
    "outputs",
    "classes",
    "quantity",
    "sa1_merkel",
    "base",
    "seed",
    "oversample",
]

token = st.one_of(
    st.sampled_from(
        [
            "SA1",
            "RA",
            "PC",
            "XX",
            "szz",
            "sed",
            "maxcomp",
            "spikes",
            "force",
            "stress",
            "rate",
            "rigid",
            "auto",
            "nan",
            "inf",
            "-inf",
            "0",
            "-1",
            "1e-30",
            "1e30",
            "1e-300",
            "7e-4",
            "8e4",
            "0.48",
            "1e-3",
            "2e-3",
            "5e4",
            "abc",
            "",
        ]
    ),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-(10**20), 10**20).map(str),
)
separator = st.sampled_from([" ", " ", " ", "  ", ";", "; ", ",", ";;", "\t"])
jumble = st.lists(st.tuples(token, separator), max_size=12).map(
    lambda parts: "".join(t + s for t, s in parts)
)


@st.composite
def composite_case(draw):
    key = draw(st.sampled_from(COMPOSITE))
    valid = LIST_VALUES.get(key, st.sampled_from(["auto", "1", "2"]))
    value = draw(st.one_of(jumble, valid, valid.map(lambda v: v.replace(" ", ","))))
    return {key: value}


@pytest.fixture(scope="module")
def runner():
    r = Runner(timeout_s=TIMEOUT_S)
    yield r
    r.close()


def assert_clear_or_sane(runner, attrs, edit=None, steps=40):
    result = runner.run(scene_xml(attrs, edit), steps=steps)
    outcome, why = classify(result, attrs)
    assert outcome in ("error", "ran"), (outcome, why, attrs)
    return outcome


# Deterministic (derandomize, no example database) and bounded: ~1 min.
@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(attrs=composite_case())
def test_composite_attribute_gives_clear_error_or_sane_run(runner, attrs):
    event(assert_clear_or_sane(runner, attrs))


thickness = st.one_of(
    st.floats(-300, 3).map(lambda e: repr(10.0**e)),
    st.sampled_from(["0", "-1e-3", "nan", "inf", "1e-6", "4e-6"]),
)
modulus = st.floats(-3, 15).map(lambda e: repr(10.0**e))
poisson = st.floats(-2, 1).map(repr)
layers_value = st.lists(st.tuples(thickness, modulus, poisson), min_size=1, max_size=6).map(
    lambda ls: "; ".join(" ".join(layer) for layer in ls)
)


@settings(
    max_examples=30,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(layers=layers_value)
def test_any_layers_value_compiles_or_fails_within_the_time_limit(runner, layers):
    # compile and a few steps; the worker is killed past TIMEOUT_S (a hang)
    event(assert_clear_or_sane(runner, {"layers": layers}, steps=5))


@pytest.mark.parametrize("label", list(STRUCTURAL))
def test_structural_case_gives_clear_error_or_sane_run(runner, label):
    assert_clear_or_sane(runner, {}, STRUCTURAL[label], steps=100)


def test_the_hang_of_a_1e_30_layer_is_a_prompt_error(runner):
    # the case: compile never returned; now a message naming the layer
    for t in ("1e-30", "1e-300"):
        attrs = {"layers": f"{t} 8e4 0.48; 8e-4 5e4 0.48; 2.5e-3 2.4e4 0.4"}
        result = runner.run(scene_xml(attrs), steps=1)
        outcome, why = classify(result, attrs)
        assert outcome == "error" and "layer 1 thickness" in why, (outcome, why)


def test_classify_rejects_the_failures_it_is_for():
    # the classifier itself: each failure form is caught
    twice = (
        "Error: engine error: plugin->init failed for plugin id 0\n"
        + "mjtouch.skin: attribute `nx` = 3 is out of range\n" * 2
    )
    assert classify({"kind": "error", "message": twice})[0] == "silent"
    vague = "Error: engine error: plugin->init failed for plugin id 0"
    assert classify({"kind": "error", "message": vague})[0] == "silent"
    assert classify({"kind": "hang"})[0] == "hang"
    assert classify({"kind": "crash", "returncode": -11})[0] == "crash"
    empty = {"kind": "ran", "finite": True, "blocks": [{"spikes": 0, "force": 5}], "classes": [[]]}
    assert classify(empty)[0] == "silent"
    nan = {"kind": "ran", "finite": False, "blocks": [], "classes": []}
    assert classify(nan)[0] == "silent"
    ok = "Error: engine error: \nmjtouch.skin: attribute `nx` = 3 is out of range; valid [4, 512]"
    assert classify({"kind": "error", "message": ok})[0] == "error"
    assert np.isfinite(TIMEOUT_S)
