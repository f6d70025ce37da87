"""The hidden fragments left out as the camera's fragments are made (hairjax/_geometry/_seen.py,
docs/model.md §6): on the host exactly those seen through less than the cutoff, in any
number of pieces; on the device a superset of those; and the images the same as without
the cut, bit for bit, since the weights of a concrete opacity are multiplied in order
(`_weights`)."""

import jax.numpy as jnp
import numpy as np
import pytest
from helpers import FRAGMENT_FIELDS, real_fragments, small_furball_scene

import hairjax as hj
from hairjax._geometry._raster import rasterize
from hairjax._geometry._raster_plan import RibbonRaster
from hairjax._geometry._seen import Seen, rasterize_seen, seen_on_device
from hairjax._geometry_stage._setup import prepare, render_cutoff
from hairjax._geometry_stage._stage import geometry_stage


def _raster(seed=3, n=400, size=24):
    """Ribbons crossing a small raster many times over: long runs per pixel."""
    rng = np.random.default_rng(seed)
    xy0 = rng.uniform(-2, size + 2, (n, 2))
    xy1 = xy0 + rng.normal(0, 6, (n, 2))
    z0, z1 = rng.uniform(1, 5, n), rng.uniform(1, 5, n)
    width = rng.uniform(0.5, 3, (n, 2))
    return (xy0, xy1, z0, z1, width, size, size, True)


def _exact_cut(everything, opacity, cutoff, hit=None):
    """Which of `everything`'s fragments (draw order) are seen through T ≥ cutoff, T
    carried in float64 front to back per pixel; and each pixel's product of the hidden
    ones' (1 − α). The occluder's test first: a fragment behind it neither passes nor dims."""
    transmittance, hidden = {}, {}
    keep = np.zeros(everything.size, bool)
    for k in range(everything.size):
        p = int(everything.pixel[k])
        if hit is not None and not everything.depth[k] < hit[p]:
            continue
        through = 1.0 - opacity[everything.segment[k]] * float(everything.coverage[k])
        if transmittance.get(p, 1.0) < cutoff:
            hidden[p] = hidden.get(p, 1.0) * through
            continue
        transmittance[p] = transmittance.get(p, 1.0) * through
        keep[k] = True
    return keep, hidden


@pytest.mark.parametrize("parts", [1, 2, 3])
@pytest.mark.parametrize("occluded", [False, True])
def test_the_host_leaves_out_exactly_the_hidden_fragments_in_any_number_of_pieces(parts, occluded):
    args = _raster()
    n_segments, size = args[0].shape[0], args[5]
    everything = rasterize(*args)  # every covered fragment, with depth, segment after segment
    opacity = np.random.default_rng(4).uniform(0.3, 0.95, n_segments)
    hit = np.random.default_rng(5).uniform(1.5, 6, size * size) if occluded else None
    cutoff = 1e-3
    want, want_hidden = _exact_cut(everything, opacity, cutoff, hit)
    assert 100 < want.sum() < everything.size - 100  # the cut does leave out fragments
    raster = RibbonRaster(*args)
    pieces, hidden = rasterize_seen(
        raster, np.arange(n_segments, dtype=np.int32), Seen(hit, opacity, cutoff), parts=parts
    )
    assert len(pieces) == parts
    for name in ("pixel", "segment", "coverage", "t"):
        got = np.concatenate([getattr(piece, name) for piece in pieces])
        np.testing.assert_array_equal(got, getattr(everything, name)[want], err_msg=name)
    expected = np.ones(size * size)
    for p, product in want_hidden.items():
        expected[p] = product
    # The same factors, multiplied piece by piece: rounding of a product of at most
    # `n_segments` factors, half an epsilon each.
    np.testing.assert_allclose(hidden, expected, rtol=n_segments * np.finfo(float).eps, atol=0)


def test_without_a_cut_the_host_keeps_every_fragment_in_front_of_the_occluder():
    args = _raster(seed=8)
    everything = rasterize(*args)
    hit = np.full(args[5] * args[6], 3.0)

    pieces, hidden = rasterize_seen(
        RibbonRaster(*args), np.arange(args[0].shape[0], dtype=np.int32), Seen(hit, None, 0.0), parts=2
    )
    assert hidden is None
    front = everything.depth < hit[everything.pixel]
    np.testing.assert_array_equal(np.concatenate([p.pixel for p in pieces]), everything.pixel[front])


@pytest.mark.parametrize("chunk", [7, 64, 1 << 20])
def test_the_device_keeps_a_superset_of_the_seen_fragments_and_every_one_the_host_keeps(chunk):
    args = _raster(seed=6)
    everything = rasterize(*args)
    n_segments, hw = args[0].shape[0], args[5] * args[6]
    opacity = np.random.default_rng(7).uniform(0.3, 0.95, n_segments)
    cutoff = 1e-3
    want, _ = _exact_cut(everything, opacity, cutoff)
    keep, hidden = seen_on_device(
        jnp.asarray(everything.pixel),
        jnp.ones(everything.size, bool),
        jnp.asarray(everything.segment),
        jnp.asarray(everything.coverage),
        opacity,
        cutoff,
        hw,
        chunk=chunk,
    )
    keep = np.asarray(keep)
    assert np.all(keep[want])  # never one the exact cut keeps
    if chunk < everything.size // 4:
        assert keep.sum() < everything.size  # with chunks this small, it does cut
    else:
        assert keep.all()  # one chunk: T before it is 1 everywhere
    # What it leaves out dims its pixel through `hidden`: T of all = T of the kept · hidden.
    alpha = opacity[everything.segment] * everything.coverage.astype(np.float64)
    every = np.ones(hw)
    np.multiply.at(every, everything.pixel, 1 - alpha)
    kept = np.ones(hw)
    np.multiply.at(kept, everything.pixel[keep], 1 - alpha[keep])
    # float32 products of at most `everything.size` factors each.
    np.testing.assert_allclose(kept * np.asarray(hidden, np.float64), every, rtol=1e-4, atol=1e-30)


def _dense_scene(**kwargs):
    return small_furball_scene(strands=600, size=24, alpha=0.9, **kwargs)


@pytest.mark.parametrize("shadows", ["none", "opacity-maps"])
def test_the_cut_in_the_set_up_moves_no_pixel_and_no_weight(shadows, monkeypatch):
    """A render with the set-up's cut against one whose set-up keeps every fragment (the
    geometry stage's own cut alone): the same fragments, weights and image, bit for bit."""
    from hairjax._geometry_stage import _stage

    scene = _dense_scene(shadows=shadows)
    cut_setup = prepare(scene, cutoff=render_cutoff())
    full_setup = prepare(scene)
    assert cut_setup.frag_pixel.size < 0.8 * full_setup.frag_pixel.size  # the set-up does cut
    cut_geometry, cut_image = geometry_stage(scene), np.asarray(hj.render(scene))
    uncut = _dense_scene(shadows=shadows)
    monkeypatch.setattr(_stage, "render_cutoff", lambda cutoff=None: 0.0)
    full_geometry, full_image = geometry_stage(uncut), np.asarray(hj.render(uncut))
    got, want = real_fragments(cut_geometry), real_fragments(full_geometry)
    for name in FRAGMENT_FIELDS:
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)
    np.testing.assert_array_equal(cut_image, full_image)


def test_every_positive_cutoff_shares_one_set_up_and_a_traced_opacity_the_full_one():
    scene = _dense_scene(shadows="none")
    geometry_stage(scene)
    geometry_stage(scene, cutoff=1e-5)
    assert prepare(scene, cutoff=render_cutoff()) is prepare(scene, cutoff=render_cutoff(1e-5))
    assert render_cutoff(0.0) == 0.0
    grad = hj.render(scene, alpha=jnp.asarray(scene.strands.alpha))  # every fragment: α may move
    assert np.all(np.isfinite(np.asarray(grad)))
    assert prepare(scene).frag_pixel.size > prepare(scene, cutoff=render_cutoff()).frag_pixel.size


def test_both_kernels_give_the_same_geometry_though_the_device_cuts_less(monkeypatch):
    """The set-up on the host (numba's loops) and on the device (XLA's programs, here on
    the CPU device), the device walking its candidates 64 at a time so that its bound
    does cut: it keeps more fragments than the host's exact cut, and the geometry stage's
    own cut then leaves the same fragments with the same weights, bit for bit."""
    import functools

    from hairjax._geometry_stage import _fragments

    monkeypatch.setattr(_fragments, "seen_on_device", functools.partial(seen_on_device, chunk=64))
    host_scene, device_scene = _dense_scene(shadows="none"), _dense_scene(shadows="none")
    host = prepare(host_scene, placement="host", cutoff=render_cutoff())
    device = prepare(device_scene, placement="device", cutoff=render_cutoff())
    every = prepare(host_scene, placement="host").frag_pixel.size
    assert host.frag_pixel.size < device.frag_pixel.size < every
    got = real_fragments(geometry_stage(device_scene, placement="device"))
    want = real_fragments(geometry_stage(host_scene, placement="host"))
    for name in FRAGMENT_FIELDS:
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)
