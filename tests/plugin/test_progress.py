"""mjtouch.progress and the progress of slide: shown on a terminal, quiet with
--json or when not a TTY, and counting exactly the work done."""

import io
import re
import subprocess
import sys

import mujoco
import mujoco.rollout
import numpy as np
import pytest

from mjtouch import progress
from mjtouch.experiments import rollout
from mjtouch.scene import scenes

# a small slide: 300 press + 300 sliding steps, well under a second
SMALL = ["--duration", "0.15", "--dt", "5e-4", "--nx", "24", "--pitch", "2e-4"]
SMALL_STEPS = round(0.15 / 5e-4) + round(scenes.Protocol().press_s / 5e-4)


class Stream(io.StringIO):
    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


def counts(stderr: str) -> list[tuple[int, int]]:
    """(done, total) of every state a tqdm bar drew ("12/40 [")."""
    return [(int(a), int(b)) for a, b in re.findall(r"(\d+)/(\d+) \[", stderr)]


@pytest.mark.parametrize(
    "mode,json_output,tty,shown",
    [
        ("auto", False, True, True),  # a terminal
        ("auto", True, True, False),  # --json: machine-read output, no bar
        ("auto", False, False, False),  # a pipe, a CI log
        ("on", True, False, True),
        ("off", False, True, False),
    ],
)
def test_wanted(mode, json_output, tty, shown):
    assert progress.wanted(mode, json_output, Stream(tty)) is shown


def test_wanted_rejects_unknown_mode():
    with pytest.raises(ValueError, match="progress mode 'sometimes' is not one of auto, on, off"):
        progress.wanted("sometimes")


def test_bar_counts_and_disabled_bar_writes_nothing():
    out = Stream(tty=True)
    with progress.Progress(5, enabled=True, stream=out, desc="t", initial=2) as bar:
        bar.step("a")
        bar.update(2, "b")
    assert bar.done == 5 and counts(out.getvalue())[-1] == (5, 5)
    quiet = Stream(tty=True)
    with progress.Progress(5, enabled=False, stream=quiet) as bar:
        bar.update(5)
    assert bar.done == 5 and quiet.getvalue() == ""


def test_chunked_rollout_is_the_one_call_rollout_bit_for_bit():
    tip = scenes.Fingertip(nx=24, pitch_m=2e-4)
    protocol = scenes.Protocol(timestep_s=5e-4)
    reported = []
    chunked = rollout.run_slide(
        tip, scenes.Texture(), protocol, duration_s=0.15, progress=reported.append
    )
    assert len(reported) > 3 and sum(reported) == SMALL_STEPS == len(chunked.time_s)
    # the same slide in one mujoco.rollout call
    m = scenes.build_model(tip, scenes.Texture(), protocol)
    d = mujoco.MjData(m)
    full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.empty(mujoco.mj_stateSize(m, full))
    mujoco.mj_getState(m, d, s0, full)
    state, sd = mujoco.rollout.rollout(m, d, s0[None], scenes.controls(protocol, 0.15)[None])
    layout = chunked.layout
    np.testing.assert_array_equal(chunked.time_s, state[0, :, 0])
    np.testing.assert_array_equal(chunked.finger_x_m, state[0, :, 1])
    np.testing.assert_array_equal(chunked.spikes, layout.block(sd[0], "spikes"))
    np.testing.assert_array_equal(chunked.stress, layout.block(sd[0], "stress"))
    np.testing.assert_array_equal(chunked.force, layout.block(sd[0], "force"))
    assert chunked.spikes.sum() > 0  # the comparison covers spiking, not a silent run


def run_slide_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "mjtouch", "slide", *SMALL, *args],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_slide_is_quiet_with_json_and_off_a_terminal():
    for args in (["--json"], []):  # subprocess stderr is a pipe, not a TTY
        out = run_slide_cli(*args)
        assert out.returncode == 0, out.stderr
        assert out.stderr == "", args


def test_slide_progress_counts_every_step():
    out = run_slide_cli("--json", "--progress", "on")
    assert out.returncode == 0, out.stderr
    seen = counts(out.stderr)
    assert seen and all(total == SMALL_STEPS for _, total in seen)
    done = [d for d, _ in seen]
    assert done == sorted(done) and done[-1] == SMALL_STEPS
    assert "step/s" in out.stderr or "s/step" in out.stderr  # a rate, hence an ETA
