"""Progress reports (hairjax/_progress.py): the plain lines off a terminal, silence when
quiet, the live bar on one, and the calls `compare`, `run_sweep`, `write_frames` and
`render_profiled` make (tiny scenes: a few seconds in all)."""

from __future__ import annotations

import io
import re

import numpy as np
import pytest
from helpers import small_furball_scene

from hairjax._animate import load_animation, write_frames
from hairjax._progress import Progress, progress_of, reporter
from hairjax._render import render_profiled
from hairjax.tools import compare, load_points, run_sweep


# One tiny scene for every renderer-driven test: each compiles the JAX stages for its
# shapes once, and the next test reuses the compilation.
def tiny_scene():
    return small_furball_scene(strands=20, size=12, maps=2, resolution=8)


LINE = re.compile(r"^demo: (\d+)/(\d+) (.*) \((\d+\.\d) s\)$")


class Recorder:
    """A `Progress` that keeps its calls."""

    def __init__(self):
        self.calls: list[tuple[int, int, str]] = []

    def __call__(self, done: int, total: int, message: str = "") -> None:
        self.calls.append((done, total, message))


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def test_off_a_terminal_one_flushed_line_per_step():
    stream = io.StringIO()  # no terminal: isatty() is False
    with reporter("demo", stream=stream) as progress:
        assert isinstance(progress, Progress)
        for k in range(1, 4):
            progress(k, 3, f"step {k}")
            # Written at once (a log shows each step as it ends), not at the block's end.
            assert stream.getvalue().count("\n") == k
    lines = stream.getvalue().splitlines()
    assert [LINE.match(line).group(1, 2, 3) for line in lines] == [
        ("1", "3", "step 1"),
        ("2", "3", "step 2"),
        ("3", "3", "step 3"),
    ]


def test_a_line_without_a_message():
    stream = io.StringIO()
    with reporter("demo", stream=stream) as progress:
        progress(0, 2)
    assert re.fullmatch(r"demo: 0/2 \(\d+\.\d s\)\n", stream.getvalue())


@pytest.mark.parametrize("stream", [io.StringIO(), FakeTerminal()])
def test_quiet_writes_nothing(stream):
    with reporter("demo", quiet=True, stream=stream) as progress:
        progress(1, 1, "done")
    assert stream.getvalue() == ""


def test_on_a_terminal_a_bar_not_lines():
    stream = FakeTerminal()
    with reporter("demo", stream=stream) as progress:
        progress(1, 3, "first")
        progress(3, 3, "last")
    text = stream.getvalue()
    assert "demo: last" in text and "3/3" in text  # the bar's final state
    assert not any(LINE.match(line) for line in text.splitlines())


def test_progress_of_maps_the_old_flags(capsys):
    recorder = Recorder()
    for silent in (None, False):
        with progress_of(silent, "demo") as progress:
            progress(1, 1, "x")
    assert capsys.readouterr().err == ""
    with progress_of(recorder, "demo") as progress:
        progress(1, 2, "x")
    assert recorder.calls == [(1, 2, "x")]
    with progress_of(True, "demo") as progress:  # pytest's stderr is no terminal: lines
        progress(1, 2, "x")
    assert LINE.match(capsys.readouterr().err.strip()).group(1, 2, 3) == ("1", "2", "x")


def test_compare_reports_every_render(gl):
    recorder = Recorder()
    compare(tiny_scene(), repeats=2, progress=recorder)
    total = 2 + 2 * (1 + 2)  # the two compared renders, then warm-up + 2 timed runs each
    assert [c[:2] for c in recorder.calls] == [(k, total) for k in range(1, total + 1)]
    assert [c[2] for c in recorder.calls] == [
        "jax render",
        "gl render",
        "jax warm-up",
        "jax timed run 1/2",
        "jax timed run 2/2",
        "gl warm-up",
        "gl timed run 1/2",
        "gl timed run 2/2",
    ]


ANIMATION = """
[hair]
source = "furball"
strands = 12
points = 4
[camera]
width = 12
height = 10
[shadows]
method = "none"
[animation]
frames = 3
"""


def test_write_frames_reports_each_frame(tmp_path):
    path = tmp_path / "anim.toml"
    path.write_text(ANIMATION)
    recorder = Recorder()
    write_frames(load_animation(path), tmp_path / "frames", frames=2, progress=recorder)
    assert recorder.calls == [(1, 2, "frame 0"), (2, 2, "frame 1")]


def test_a_resumed_sweep_counts_the_points_already_done(tmp_path):
    scene = tiny_scene()
    knobs = {"bins": (1, 4, 16)}

    def interrupt_after_one(done, total, message=""):
        calls.append((done, total, message))
        if done == 1:
            raise KeyboardInterrupt  # as a Ctrl-C right after the first point is stored

    calls: list[tuple[int, int, str]] = []
    with pytest.raises(KeyboardInterrupt):
        run_sweep(scene, tmp_path, knobs=knobs, paths=("jax",), repeats=1, progress=interrupt_after_one)
    assert calls == [(0, 3, "jax reference"), (1, 3, "jax bins = 1")]
    assert len(load_points(tmp_path)) == 1

    recorder = Recorder()
    run_sweep(scene, tmp_path, knobs=knobs, paths=("jax",), repeats=1, progress=recorder)
    assert recorder.calls == [
        (1, 3, "resuming: 1 of 3 points already done"),
        (1, 3, "jax reference"),
        (2, 3, "jax bins = 4"),
        (3, 3, "jax bins = 16"),
    ]


def test_render_profiled_reports_its_stages():
    recorder = Recorder()
    scene = tiny_scene()
    image, timings = render_profiled(scene, progress=recorder)
    assert recorder.calls == [
        (1, 3, "geometry set-up"),
        (2, 3, "geometry opacity (JAX)"),
        (3, 3, "shading"),
    ]
    stages = ("geometry set-up", "geometry opacity (JAX)", "shading")
    # The total is the stages' sum (float addition in another order: a few ulps).
    assert timings["total"] == pytest.approx(sum(timings[k] for k in stages), rel=1e-9)
    assert np.asarray(image).shape == (12, 12, 4)
