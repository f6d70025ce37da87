"""Ribbon coverage and fragments (docs/model.md §5)."""

import numpy as np
import pytest

from hairjax._geometry._raster import rasterize, ribbon_coverage


def image(frags, w, h, weights=None):
    weights = frags.coverage if weights is None else weights
    return np.bincount(frags.pixel, weights, minlength=w * h).reshape(h, w)


def test_coverage_by_hand():
    # Width 1: box [d − ½, d + ½] ∩ [−½, ½] has length 1 − d for 0 ≤ d ≤ 1.
    np.testing.assert_allclose(
        ribbon_coverage(np.array([0.0, 0.25, 0.5, 1.0, 1.5]), np.ones(5)), [1.0, 0.75, 0.5, 0.0, 0.0]
    )
    # Width 0.25: fully inside the box up to d = 0.375, then shrinking to 0 at 0.625.
    np.testing.assert_allclose(
        ribbon_coverage(np.array([0.0, 0.375, 0.5, 0.625]), np.full(4, 0.25)), [0.25, 0.25, 0.125, 0.0]
    )
    # Width 3: the box is inside the ribbon for d ≤ 1.
    np.testing.assert_allclose(
        ribbon_coverage(np.array([0.0, 1.0, 1.5, 2.0]), np.full(4, 3.0)), [1.0, 1.0, 0.5, 0.0]
    )


def test_horizontal_line_through_pixel_centres():
    # y = 3.5 runs through row 3's centres; x ∈ [2.2, 7.9) contains centres 2.5 … 7.5.
    f = rasterize(
        np.array([[2.2, 3.5]]), np.array([[7.9, 3.5]]), np.ones(1), np.ones(1), np.ones(1), 10, 8, False
    )
    img = image(f, 10, 8)
    expected = np.zeros((8, 10))
    expected[3, 2:8] = 1.0
    np.testing.assert_allclose(img, expected, atol=1e-12)
    # t = s/L at the centres.
    np.testing.assert_allclose(np.sort(f.t), (np.arange(2, 8) + 0.5 - 2.2) / 5.7, rtol=1e-12)


def test_line_between_rows_splits_coverage():
    # y = 4.0: centres of rows 3 and 4 are ½ away, each covered ½.
    f = rasterize(
        np.array([[0.0, 4.0]]), np.array([[6.0, 4.0]]), np.ones(1), np.ones(1), np.ones(1), 6, 8, False
    )
    img = image(f, 6, 8)
    np.testing.assert_allclose(img[3], 0.5)
    np.testing.assert_allclose(img[4], 0.5)
    assert img.sum() == pytest.approx(6.0)


@pytest.mark.parametrize("direction", [(27.4, 21.1), (-5.3, 30.2), (12.0, -12.0), (-30.0, -2.0)])
def test_straight_strand_as_one_or_eight_segments(direction):
    """Same fragments for 1 and 8 collinear segments: no double-covered joints, no gaps."""
    p0 = np.array([32.3, 31.1])
    p1 = p0 + np.array(direction)
    pts = p0 + np.linspace(0, 1, 9)[:, None] * (p1 - p0)
    w, h = 64, 64
    one = rasterize(p0[None], p1[None], np.ones(1), np.ones(1), np.ones(1), w, h, True)
    eight = rasterize(pts[:-1], pts[1:], np.ones(8), np.ones(8), np.ones(8), w, h, True)
    # Each pixel appears once per drawing (no pixel drawn by two neighbouring segments).
    assert np.bincount(eight.pixel).max() == 1
    assert np.array_equal(np.sort(one.pixel), np.sort(eight.pixel))
    # Coverage equal up to the rounding of each segment's own direction (float64).
    np.testing.assert_allclose(image(eight, w, h), image(one, w, h), atol=1e-12)
    assert image(one, w, h).sum() > 0.9 * np.hypot(*direction)


def test_zero_length_and_offscreen_segments_draw_nothing():
    xy = np.array([[5.0, 5.0], [-50.0, -50.0]])
    xy1 = np.array([[5.0, 5.0], [-40.0, -45.0]])
    f = rasterize(xy, xy1, np.ones(2), np.ones(2), np.ones(2), 16, 16, True)
    assert f.size == 0


def test_fragments_stay_inside_the_image_and_cover_positive():
    rng = np.random.default_rng(1)
    a = rng.uniform(-10, 40, (200, 2))
    b = a + rng.normal(0, 8, (200, 2))
    w = rng.uniform(0.25, 8, 200)
    f = rasterize(a, b, np.ones(200), np.ones(200), w, 30, 20, True)
    assert f.pixel.min() >= 0 and f.pixel.max() < 600
    assert np.all((f.coverage > 0) & (f.coverage <= 1))
    assert np.all((f.t >= 0) & (f.t < 1))


def test_perspective_correct_depth():
    # 1/z is linear in t: at t = ½ between z = 1 and z = 3, z = 1/(½ + 1/6) = 1.5.
    f = rasterize(
        np.array([[0.0, 0.5]]),
        np.array([[2.0, 0.5]]),
        np.array([1.0]),
        np.array([3.0]),
        np.ones(1),
        2,
        1,
        True,
    )
    # Centres at x = 0.5, 1.5: t = ¼, ¾.
    np.testing.assert_allclose(np.sort(f.depth), [1 / (0.75 + 0.25 / 3), 1 / (0.25 + 0.75 / 3)])


# --- ribbons of world-space width (kim-2003 Fig. 2; docs/model.md §5) ---


def test_ribbon_widths_by_hand():
    from hairjax._geometry._raster import ribbon_widths

    w = np.array([0.1, 0.3])
    d0, d1 = np.array([2.0, 5.0]), np.array([4.0, 5.0])
    # Perspective, f = 100: 0.1·100/2 = 5, 0.1·100/4 = 2.5; 0.3·100/5 = 6 at both ends.
    np.testing.assert_allclose(ribbon_widths(w, "world", d0, d1, 100.0, True), [[5, 2.5], [6, 6]])
    # Orthographic, f = 10 texels per world unit: 1 and 3, whatever the depth.
    np.testing.assert_allclose(ribbon_widths(w, "world", d0, d1, 10.0, False), [[1, 1], [3, 3]])
    np.testing.assert_array_equal(ribbon_widths(w, "pixels", d0, d1, 100.0, True), [[0.1, 0.1], [0.3, 0.3]])
    with pytest.raises(ValueError, match="'pixels' or 'world'"):
        ribbon_widths(w, "metres", d0, d1, 1.0, True)


def test_tapered_ribbon_coverage_by_hand():
    # y = 16.0, x from 0 to 10, width 1 at x = 0 growing to 3 at x = 10: w = 1 + 2t, t = x/10.
    # Row 16 (centre 16.5, d = ½): min(1, w/2) − max(0, −w/2) = min(1, w/2): x = 0.5 → 0.55, x = 4.5 → 0.95.
    # Row 17 (centre 17.5, d = 1.5): w/2 − 1 where w > 2, i.e. x > 5: x = 5.5 → w = 2.1, 0.05;
    # x = 7.5 → 0.25; x = 9.5 → 0.45. Rows 15 and 14 mirror 16 and 17.
    f = rasterize(
        np.array([[0.0, 16.0]]),
        np.array([[10.0, 16.0]]),
        np.ones(1),
        np.ones(1),
        np.array([[1.0, 3.0]]),
        32,
        32,
        False,
    )
    img = image(f, 32, 32)
    x = np.arange(10) + 0.5
    w = 1 + 2 * x / 10
    outer = np.clip(w / 2 - 1, 0, 1)
    expected = np.zeros((32, 32))
    expected[15, :10] = expected[16, :10] = np.minimum(1.0, w / 2)
    expected[14, :10] = expected[17, :10] = outer
    np.testing.assert_allclose(img, expected, atol=1e-12)
    np.testing.assert_allclose(img[17, [5, 7, 9]], [0.05, 0.25, 0.45], atol=1e-12)
    np.testing.assert_allclose(img[16, [0, 4, 5]], [0.55, 0.95, 1.0], atol=1e-12)


def test_equal_end_widths_are_the_pixel_width_ribbon():
    """[E, 2] widths with equal ends give bit-identical fragments to [E] widths."""
    rng = np.random.default_rng(5)
    xy0, xy1 = rng.uniform(-2, 30, (40, 2)), rng.uniform(-2, 30, (40, 2))
    z0, z1, w = rng.uniform(1, 3, 40), rng.uniform(1, 3, 40), rng.uniform(0.5, 3, 40)
    a = rasterize(xy0, xy1, z0, z1, w, 28, 28, True)
    b = rasterize(xy0, xy1, z0, z1, np.stack([w, w], axis=1), 28, 28, True)
    for field in ("pixel", "segment", "coverage", "t", "depth"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def _world_segment_scene(width, units, depth=5.0):
    import hairjax as hj

    # A camera at z = depth looking at the origin, fov 90° on 32 rows: f = 16 pixels. The
    # segment x ∈ [−0.5, 0.5] at y = 0, depth `depth`, lands on row boundary y = 16.
    hair = hj.Strands.from_list([[[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]], alpha=1.0, width=width)
    return hj.Scene(
        hair.replace(width_units=units),
        camera=hj.Camera(eye=(0.0, 0.0, depth), target=(0.0, 0.0, 0.0), fov=90.0, width=32, height=32),
        shadows=hj.Shadows("none"),
    )


def test_world_width_segment_covers_the_expected_pixels():
    import hairjax as hj

    # 0.625 world units at depth 5 with f = 16: 0.625·16/5 = 2 pixels, centred on y = 16:
    # rows 15 and 16 (centres ½ away) fully covered, row 14 and 17 (1½ away) not at all.
    # Along x: 16 ± 0.5·16/5 = [14.4, 17.6) holds the centres of columns 14 … 17.
    alpha = np.asarray(hj.render(_world_segment_scene(0.625, "world")))[..., 3]
    expected = np.zeros((32, 32))
    expected[15:17, 14:18] = 1.0
    np.testing.assert_allclose(alpha, expected, atol=1e-6)  # float32 composite rounding
    # Twice as far: half the length and half the width, 1 pixel: ½ on rows 15 and 16,
    # over 16 ± 0.8 → centres 15.5 and 16.5 (columns 15, 16).
    alpha = np.asarray(hj.render(_world_segment_scene(0.625, "world", depth=10.0)))[..., 3]
    expected = np.zeros((32, 32))
    expected[15:17, 15:17] = 0.5
    np.testing.assert_allclose(alpha, expected, atol=1e-6)
    # The same width in pixels is 0.625 pixels at any depth: 0.3125 on rows 15 and 16.
    alpha = np.asarray(hj.render(_world_segment_scene(0.625, "pixels")))[..., 3]
    expected = np.zeros((32, 32))
    expected[15:17, 14:18] = 0.3125
    np.testing.assert_allclose(alpha, expected, atol=1e-6)


def test_world_width_too_wide_for_the_light_view_is_a_clear_error():
    import hairjax as hj

    scene = _world_segment_scene(5.0, "world").replace(shadows=hj.Shadows("exact", resolution=16))
    with pytest.raises(ValueError, match="too wide for its border"):
        hj.render(scene)


def test_a_raster_without_depth_has_the_same_fragments():
    """`depth=False` (the camera's raster without an occluder) skips depth and only depth:
    the same pixels, segments, coverage and t, in the same order, bit for bit."""
    rng = np.random.default_rng(4)
    a = rng.uniform(-10, 40, (300, 2))
    b = a + rng.normal(0, 8, (300, 2))
    z0, z1 = rng.uniform(1, 5, 300), rng.uniform(1, 5, 300)
    w = rng.uniform(0.25, 8, (300, 2))
    with_depth = rasterize(a, b, z0, z1, w, 30, 20, True)
    without = rasterize(a, b, z0, z1, w, 30, 20, True, depth=False)
    assert without.depth is None and with_depth.depth is not None and with_depth.size > 1000
    for name in ("pixel", "segment", "coverage", "t"):
        np.testing.assert_array_equal(getattr(without, name), getattr(with_depth, name))
    assert without.take(np.arange(5)).depth is None


# --- the capacity policy (docs/model.md §5): count first when the bound does not fit ---


def _segments():
    """Three ribbons across a 32 × 32 raster, two pixels wide: a few hundred fragments
    among a few times as many candidates."""
    xy0 = np.array([[1.0, 2.0], [3.5, 30.0], [16.0, 1.0]])
    xy1 = np.array([[30.0, 9.0], [28.0, 4.5], [17.0, 31.0]])
    return xy0, xy1, np.ones(3), np.ones(3), np.full(3, 2.0), 32, 32, False


@pytest.fixture
def raster_calls(monkeypatch):
    """The count_only flag of every call of the raster loop."""
    from hairjax._geometry import _raster

    calls = []
    loop = _raster.raster_loop("float32")

    def spy(*args):
        calls.append(args[12])  # count_only, after the segment range (`raster_loop`)
        return loop(*args)

    monkeypatch.setattr(_raster, "raster_loop", lambda name: spy)
    return calls


def test_a_bound_beyond_memory_counts_first_and_renders_the_same(monkeypatch, raster_calls):
    from hairjax._geometry import _capacity

    plain = rasterize(*_segments())
    assert raster_calls == [False]  # memory for every candidate: no count
    per_fragment = _capacity.fragment_bytes(plain.coverage.itemsize, True)
    # Exactly enough for the fragments, not for the candidates' bound.
    monkeypatch.setattr(_capacity, "available_memory", lambda: plain.size * per_fragment)
    counted = rasterize(*_segments())
    assert raster_calls == [False, True, False]
    for name in ("pixel", "segment", "coverage", "t", "depth"):
        np.testing.assert_array_equal(getattr(counted, name), getattr(plain, name))


def test_fragments_beyond_memory_are_refused_before_the_fields_exist(monkeypatch, raster_calls):
    import hairjax as hj
    from hairjax._geometry import _capacity

    plain = rasterize(*_segments())
    per_fragment = _capacity.fragment_bytes(plain.coverage.itemsize, True)
    monkeypatch.setattr(_capacity, "available_memory", lambda: plain.size * per_fragment - 1)
    with pytest.raises(hj.SceneTooLarge, match=f"32x32 raster of this scene holds {plain.size:,} fragments"):
        rasterize(*_segments())
    assert raster_calls == [False, True]  # counted, never written
    assert issubclass(hj.SceneTooLarge, MemoryError) and issubclass(hj.SceneTooLarge, hj.SceneError)


def test_fragment_bytes_by_hand():
    from hairjax._geometry._capacity import fragment_bytes

    # Raster: pixel, segment (int32), coverage, t, depth; grouped: pixel, first point, coverage, t.
    assert fragment_bytes(4, True) == 4 + 4 + 3 * 4 + 4 + 4 + 2 * 4 == 36
    assert fragment_bytes(4, False) == 32 and fragment_bytes(8, False) == 48


@pytest.mark.parametrize("parts", [1, 2, 3, 8])
def test_pieces_in_order_are_the_raster(parts):
    """rasterize_parts: each piece holds a run of segments (about equal in candidates),
    rasterised on its own thread; in order they are rasterize's fragments."""
    from hairjax._geometry._raster import rasterize_parts

    whole = rasterize(*_segments())
    pieces = rasterize_parts(*_segments(), parts=parts)
    assert (len(pieces) == 1) == (parts == 1) and len(pieces) <= min(parts, 3)
    for name in ("pixel", "segment", "coverage", "t", "depth"):
        joined = np.concatenate([getattr(piece, name) for piece in pieces])
        np.testing.assert_array_equal(joined, getattr(whole, name))


def test_pieces_grouped_where_they_are_equal_the_whole_grouped():
    from hairjax._geometry._group import group_by_pixel, group_parts
    from hairjax._geometry._raster import rasterize_parts

    whole = rasterize(*_segments())
    pieces = rasterize_parts(*_segments(), parts=3)
    expected = group_by_pixel(whole.pixel, 32 * 32, whole.segment, whole.coverage)
    got = group_parts([(p.pixel, p.segment, p.coverage) for p in pieces], 32 * 32)
    np.testing.assert_array_equal(got[0], expected[0])
    for g, e in zip(got[1], expected[1]):
        np.testing.assert_array_equal(g, e)


def test_labels_name_the_segments():
    """`labels`: what each fragment's `segment` holds instead of its segment's index."""
    plain = rasterize(*_segments())
    labels = np.array([70, 50, 60], np.int32)
    labelled = rasterize(*_segments(), labels=labels)
    np.testing.assert_array_equal(labelled.segment, labels[plain.segment])
    for name in ("pixel", "coverage", "t", "depth"):
        np.testing.assert_array_equal(getattr(labelled, name), getattr(plain, name))
    with pytest.raises(ValueError, match="one entry per segment"):
        rasterize(*_segments(), labels=labels[:2])


@pytest.mark.parametrize("threads", [2, 3])
@pytest.mark.parametrize("depth", [True, False])
def test_the_raster_on_several_cores_moves_its_pieces_together(monkeypatch, threads, depth):
    """rasterize from PARALLEL_MIN candidates on: pieces on every core, each shifted down
    in place to follow the one before; lowered here so that three segments take it."""
    from hairjax._geometry import _raster

    one_piece = _raster.rasterize_parts(*_segments(), depth=depth, parts=1)[0]
    monkeypatch.setattr(_raster, "PARALLEL_MIN", 1)
    monkeypatch.setattr(_raster, "host_threads", lambda: threads)
    assert len(_raster.rasterize_parts(*_segments(), depth=depth)) > 1  # the path taken
    joined = rasterize(*_segments(), depth=depth)
    for name in ("pixel", "segment", "coverage", "t") + (("depth",) if depth else ()):
        np.testing.assert_array_equal(getattr(joined, name), getattr(one_piece, name))
    assert joined.depth is None if not depth else joined.depth.size == one_piece.size
