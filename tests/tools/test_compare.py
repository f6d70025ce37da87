"""`hairjax compare`'s measures (hairjax/tools/_compare.py): the image statistics on
hand-made images whose maximum, RMSE, PSNR and share of pixels over 1e-4 follow by hand,
the report's text, the median timing, and `compare` itself on a tiny scene with both
renderers. (The CLI's `compare` command end to end: tests/gl/test_plumbing.py.)"""

from __future__ import annotations

import math
import re
import types
import weakref

import numpy as np
import pytest
from helpers import PIXEL_TOL, small_furball_scene

import hairjax as hj
from hairjax.tools import _compare, compare, format_report, image_stats, median_time, timed_calls

# The keys `hairjax compare` prints (format_report) and writes to --json.
REPORT_KEYS = {
    "scene",
    "size",
    "max_abs",
    "rmse",
    "psnr_db",
    "share_over_1e-4",
    "band_share",
    "differing",
    "outside_band",
    "tau_max_abs",
    "jax_s",
    "gl_s",
    "repeats",
}


# --------------------------------------------------------------------------- image_stats


def test_image_stats_by_hand():
    """Ten RGB pixels, four differing in one channel each: by 0.5, by 2e-4 (over the
    tolerance), by exactly 1e-4 (not over it: the test is >) and by 5e-5."""
    assert PIXEL_TOL == 1e-4
    a = np.zeros((2, 5, 3))
    b = a.copy()
    b[0, 0, 1] = 0.5
    b[1, 3, 0] = 2e-4
    b[1, 2, 2] = 1e-4
    b[1, 4, 2] = -5e-5
    mse = (0.5**2 + 2e-4**2 + 1e-4**2 + 5e-5**2) / 30  # over all 30 values
    stats = image_stats(a, b)
    assert set(stats) == {"max_abs", "rmse", "psnr_db", "share_over_1e-4"}
    assert stats["max_abs"] == 0.5
    assert stats["rmse"] == pytest.approx(math.sqrt(mse), rel=1e-14)
    assert stats["psnr_db"] == pytest.approx(10 * math.log10(1 / mse), rel=1e-14)  # peak 1
    assert stats["share_over_1e-4"] == 2 / 10  # pixels, not values: (0, 0) and (1, 3)
    assert image_stats(b, a) == stats  # symmetric
    assert all(type(v) is float for v in stats.values())


def test_image_stats_of_a_uniform_difference_and_of_equal_images():
    a = np.full((3, 4, 4), 0.25, np.float32)  # float32 in, as GL's images are
    stats = image_stats(a, a + np.float32(0.1))
    assert stats["max_abs"] == pytest.approx(0.1, rel=1e-6)
    assert stats["rmse"] == pytest.approx(0.1, rel=1e-6)
    assert stats["psnr_db"] == pytest.approx(20.0, rel=1e-5)  # −10·log10(0.01)
    assert stats["share_over_1e-4"] == 1.0
    same = image_stats(a, a.copy())
    assert same == {"max_abs": 0.0, "rmse": 0.0, "psnr_db": math.inf, "share_over_1e-4": 0.0}


# --------------------------------------------------------------------------- the report


def report_of(**changes) -> dict:
    r = {
        "scene": "tiny",
        "size": [16, 12],
        "max_abs": 0.5,
        "rmse": 0.0913,
        "psnr_db": 20.79,
        "share_over_1e-4": 0.2,
        "band_share": 0.0125,
        "differing": 38,
        "outside_band": 0,
        "tau_max_abs": 3.25e-5,
        "jax_s": 0.5,
        "gl_s": 0.25,
        "repeats": 3,
    }
    return {**r, **changes}


def test_format_report_names_every_number():
    text = format_report(report_of())
    lines = text.splitlines()
    assert lines[0] == "tiny (16x12): GL vs JAX"
    for line in (
        "  max abs difference   0.5",
        "  RMSE                 0.0913",
        "  PSNR                 20.8 dB",
        "  pixels > 1e-4        20.0000 %",
        "  max |Δτ| per point   3.25e-05  (largest JAX−GL difference in τ, the share of light "
        "reaching a strand point through the hair, 0 to 1; docs/model.md §7)",
        "  time, JAX (full)     0.500 s  (median of 3)",
        "  time, GL             0.250 s  (ratio JAX/GL 2.00)",
        "  verdict              within band (all 38 pixels differing by > 1e-4 lie in it; "
        "the band holds 1.25 % of pixels, docs/model.md §11)",
    ):
        assert line in lines, (line, lines)
    assert len(lines) == 9


@pytest.mark.parametrize(
    "differing, outside, text",
    [
        (
            0,
            0,
            "within band (no pixel differs by > 1e-4; the band holds 1.25 % of pixels, docs/model.md §11)",
        ),
        (
            5,
            2,
            "2 pixels (0.6944 %) differ by > 1e-4 outside the explained band "
            "(the band holds 1.25 % of pixels, docs/model.md §11)",
        ),
    ],
)
def test_verdict_text(differing, outside, text):
    report = report_of(differing=differing, outside_band=outside, size=[16, 18])  # 288 pixels
    assert _compare.verdict_text(report) == text
    assert f"  verdict              {text}" in format_report(report).splitlines()


def test_format_report_without_omega_from_gl():
    text = format_report(report_of(tau_max_abs=None, psnr_db=math.inf))
    assert "max |Δτ| per point   n/a (no Ω from GL)" in text
    assert "PSNR                 inf dB" in text


def test_median_time_skips_a_warm_up_call_and_takes_the_median(monkeypatch):
    clock = types.SimpleNamespace(now=0.0)
    durations = iter([100.0, 5.0, 1.0, 3.0])  # the warm-up (compilation) is slow

    def fn():
        clock.now += next(durations)

    monkeypatch.setattr(_compare, "time", types.SimpleNamespace(perf_counter=lambda: clock.now))
    assert median_time(fn, 3) == 3.0
    with pytest.raises(StopIteration):
        fn()  # exactly 1 + 3 calls were made


def test_median_time_reports_each_call_outside_the_timed_span(monkeypatch):
    clock = types.SimpleNamespace(now=0.0)
    monkeypatch.setattr(_compare, "time", types.SimpleNamespace(perf_counter=lambda: clock.now))

    def fn():
        clock.now += 1.0

    def after(k):
        calls.append(k)
        clock.now += 50.0  # a slow report must not enter the timings

    calls: list[int] = []
    assert median_time(fn, 2, after) == 1.0
    assert calls == [0, 1, 2]  # 0: the warm-up


class _Pending:
    """A result whose work finishes only when waited for, as a JAX array's after
    asynchronous dispatch: `block_until_ready` advances the clock by `wait`."""

    def __init__(self, clock, wait: float):
        self.clock, self.wait, self.waited = clock, wait, False

    def block_until_ready(self):
        self.clock.now += self.wait
        self.waited = True
        return self


def test_median_time_waits_for_each_result(monkeypatch):
    clock = types.SimpleNamespace(now=0.0)
    monkeypatch.setattr(_compare, "time", types.SimpleNamespace(perf_counter=lambda: clock.now))
    made: list[_Pending] = []

    def fn():  # dispatch takes 1 s, the work 10 s more
        clock.now += 1.0
        made.append(_Pending(clock, 10.0))
        return made[-1]

    assert median_time(fn, 3) == 11.0  # without the wait: 1.0
    assert len(made) == 4 and all(p.waited for p in made)  # the warm-up's result too


def test_median_time_blocks_through_jax(monkeypatch):
    blocked = []
    monkeypatch.setattr(_compare.jax, "block_until_ready", lambda x: blocked.append(x) or x)
    results = iter(range(3))
    median_time(lambda: next(results), 2)
    assert blocked == [0, 1, 2]


def test_timed_calls_records_warm_up_runs_and_the_last_result(monkeypatch):
    clock = types.SimpleNamespace(now=0.0)
    monkeypatch.setattr(_compare, "time", types.SimpleNamespace(perf_counter=lambda: clock.now))
    durations = iter([100.0, 5.0, 1.0, 3.0])
    calls = iter(range(4))

    def fn():
        clock.now += next(durations)
        return next(calls)

    seen = []
    timed = timed_calls(fn, 3, lambda k, result, seconds: seen.append((k, result, seconds)))
    assert (timed.warm_up_s, timed.runs_s, timed.median_s, timed.last) == (100.0, [5.0, 1.0, 3.0], 3.0, 3)
    assert seen == [(0, 0, 100.0), (1, 1, 5.0), (2, 2, 1.0), (3, 3, 3.0)]


def test_timed_calls_drops_each_result_before_the_next_call():
    """Two calls' results never coexist (a render's arrays can fill the memory)."""

    class Result:
        pass

    made: list[weakref.ref] = []
    alive_at_call: list[int] = []

    def fn():
        alive_at_call.append(sum(ref() is not None for ref in made))
        result = Result()
        made.append(weakref.ref(result))
        return result

    timed = timed_calls(fn, 3)
    assert alive_at_call == [0, 0, 0, 0]
    assert made[-1]() is timed.last


@pytest.mark.parametrize("repeats", [0, -1, 1.5, True, "3"])
def test_check_repeats(repeats):
    with pytest.raises(
        ValueError, match="^" + re.escape(f"repeats must be a positive integer, got {repeats!r}")
    ):
        _compare.check_repeats(repeats)
    assert _compare.check_repeats(np.int64(2)) == 2 and type(_compare.check_repeats(np.int64(2))) is int


@pytest.mark.parametrize("repeats", [0, -1])  # non-integers are beartype's to refuse under pytest
def test_compare_refuses_bad_repeats_before_rendering(monkeypatch, repeats):
    def no_render(*args, **kwargs):
        raise AssertionError("rendered before checking repeats")

    monkeypatch.setattr(_compare, "render", no_render)
    with pytest.raises(
        ValueError, match="^" + re.escape(f"repeats must be a positive integer, got {repeats!r}") + "$"
    ):
        compare(small_furball_scene(strands=4, size=8), repeats=repeats)


# --------------------------------------------------------------------------- compare


@pytest.mark.parametrize("shadows", ["opacity-maps", "none"])
def test_compare_on_a_tiny_scene(gl, shadows):
    from hairjax._geometry_stage._stage import geometry_stage
    from hairjax.gl import render_gl

    scene = small_furball_scene(strands=40, size=24, shadows=shadows).replace(name="tiny")
    report = compare(scene, repeats=1)
    assert set(report) == REPORT_KEYS
    assert report["scene"] == "tiny" and report["size"] == [24, 24] and report["repeats"] == 1
    assert report["jax_s"] > 0 and report["gl_s"] > 0
    # The statistics are those of GL's image against JAX's.
    gl_result = render_gl(scene)
    expected = image_stats(gl_result.image, np.asarray(hj.render(scene)))
    for key, value in expected.items():
        assert report[key] == pytest.approx(value, rel=1e-6, abs=1e-12), key
    assert 0 < report["rmse"] < 1e-3 and report["max_abs"] > 0  # they agree, not bit for bit
    if shadows == "none":
        assert report["tau_max_abs"] is None  # GL reports no Ω without shadows
        assert "n/a (no Ω from GL)" in format_report(report)
    else:
        kappa = float(scene.params.kappa)
        jax_omega = np.asarray(geometry_stage(scene).omega, np.float64)
        tau = np.abs(np.exp(-kappa * jax_omega) - np.exp(-kappa * gl_result.omega.astype(np.float64)))
        assert report["tau_max_abs"] == pytest.approx(tau.max(), rel=1e-6, abs=1e-12)
        assert f"{report['tau_max_abs']:.3g}" in format_report(report)
    text = format_report(report)
    assert f"{report['rmse']:.3g}" in text and f"{report['psnr_db']:.1f} dB" in text


# --------------------------------------------------------------------------- the band's verdict


def test_band_verdict_counts_what_lies_outside_the_band(gl):
    """GL's own image is within band on this scene; one pixel moved by 0.01 outside the
    band is counted, one moved inside it is not."""
    from hairjax.gl import render_gl

    scene = small_furball_scene(strands=40, size=24)
    jax_image = np.asarray(hj.render(scene))
    gl_image = render_gl(scene).image
    verdict, band = _compare.band_verdict(scene, gl_image, jax_image)
    peak = float(jax_image[..., :3].max())
    np.testing.assert_array_equal(band, hj.experimental.renderer_band(scene, colour_bound=peak))
    differ = np.abs(gl_image - jax_image)[..., :3].max(axis=-1) > PIXEL_TOL
    assert verdict == {
        "band_share": float(band.mean()),
        "differing": int(differ.sum()),
        "outside_band": 0,
    }
    assert 0 < band.sum() < band.size  # the scene has a band, and pixels outside it
    outside = tuple(np.argwhere(~band & ~differ)[0])
    inside = tuple(np.argwhere(band & ~differ)[0])
    moved = gl_image.copy()
    moved[outside + (1,)] += 0.01
    moved[inside + (2,)] -= 0.01
    verdict, _ = _compare.band_verdict(scene, moved, jax_image)
    assert verdict["differing"] == differ.sum() + 2 and verdict["outside_band"] == 1


def test_difference_image_by_hand():
    """Four pixels: agreeing (the JAX render's grey, dimmed), differing by 1e-2 inside the
    band (blue), by 1 outside it (orange-red, full brightness), by 1e-3 outside it."""
    jax_image = np.zeros((1, 4, 4))
    jax_image[0, 0, :3] = 1.0  # white: grey code 0.35 · 255
    gl_image = jax_image.copy()
    gl_image[0, 1, 0] += 1e-2
    gl_image[0, 2, 1] += 1.0
    gl_image[0, 3, 2] -= 1e-3
    band = np.array([[False, True, False, False]])
    codes = _compare.difference_image(gl_image, jax_image, band)
    assert codes.dtype == np.uint8 and codes.shape == (1, 4, 3)
    # Brightness 0.4 + 0.6 · log10(d / 1e-4) / 4: d = 1e-2 → 0.7, d = 1 → 1, d = 1e-3 → 0.55.
    expected = [
        [0.35 * 255] * 3,
        [0.7 * 255 * c for c in (0.25, 0.55, 1.0)],
        [1.0 * 255 * c for c in (1.0, 0.35, 0.0)],
        [0.55 * 255 * c for c in (1.0, 0.35, 0.0)],
    ]
    np.testing.assert_allclose(codes[0], np.round(expected), atol=1)  # rounding of float steps


def test_write_difference_png_and_exr(tmp_path):
    rng = np.random.default_rng(0)
    jax_image = rng.uniform(0, 1, (3, 5, 4))
    gl_image = jax_image + rng.normal(0, 1e-2, jax_image.shape)
    band = rng.uniform(size=(3, 5)) < 0.5
    png = _compare.write_difference(tmp_path / "d.png", gl_image, jax_image, band)
    back = hj.read_image(png, decode_srgb=False)  # display codes as stored
    np.testing.assert_allclose(back * 255, _compare.difference_image(gl_image, jax_image, band), atol=1e-3)
    exr = _compare.write_difference(tmp_path / "d.exr", gl_image, jax_image, band)
    np.testing.assert_array_equal(hj.read_image(exr), (gl_image - jax_image).astype(np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.exr", "d.png"]


def test_compare_writes_its_diff(gl, tmp_path):
    scene = small_furball_scene(strands=40, size=24)
    report = compare(scene, repeats=1, diff=tmp_path / "d.png")
    assert report["outside_band"] == 0 and "within band" in format_report(report)
    assert hj.read_image(tmp_path / "d.png").shape == (24, 24, 3)
