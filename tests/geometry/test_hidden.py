"""Fragments hidden below a transmittance cutoff are left out (hairjax/_geometry/_hidden.py,
docs/model.md §6): exactly those, and the image moves by less than the bound."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import FRAGMENT_FIELDS, real_fragments, small_furball_scene

from hairjax._geometry._hidden import drawn_cutoff, keep_on_device, keep_on_host, keep_visible
from hairjax._geometry._host import ALIGNMENT
from hairjax._geometry_stage._setup import prepare
from hairjax._geometry_stage._stage import geometry_stage
from hairjax._shading._stage import point_colors, shading_stage

cpu_only = pytest.mark.skipif(jax.default_backend() != "cpu", reason="the CPU backend aliases host arrays")
# The tests run in float64 (conftest): the default cutoff is 2⁻⁵³ there.
WORKING = jnp.result_type(float)


def _dense_scene():
    """Opaque-ish strands, many to a pixel: runs of dozens of fragments, so that T falls
    below the working precision's cutoff at some pixels and below 1e-3 at many."""
    return small_furball_scene(strands=600, size=24, shadows="none", alpha=0.9)


def _front_transmittance(scene) -> np.ndarray:
    """T_k = Π_{j nearer} (1 − α_j) of every fragment, in float64 from the set-up's own
    α·coverage (docs/model.md §6), independently of the JAX composite."""
    setup = prepare(scene)
    alpha = np.asarray(scene.strands.alpha, np.float64)[setup.strand_of_point[setup.frag_i0]]
    alpha = alpha * np.asarray(setup.frag_coverage, np.float64)
    t = np.empty_like(alpha)
    pixel = np.asarray(setup.frag_pixel)
    for start, stop in _runs(pixel):
        run = 1.0 - alpha[start:stop]
        t[start:stop] = np.concatenate([[1.0], np.cumprod(run)[:-1]])
    return t


def _runs(pixel: np.ndarray):
    edges = np.flatnonzero(np.diff(pixel)) + 1
    bounds = np.concatenate([[0], edges, [pixel.size]])
    return zip(bounds[:-1], bounds[1:])


def _kept_mask(everything, kept) -> np.ndarray:
    """Which of `everything`'s fragments are in `kept`, by their (pixel, segment) key."""
    key = lambda f: f["frag_pixel"].astype(np.int64) << 32 | f["frag_i0"].astype(np.int64)  # noqa: E731
    everything, kept = real_fragments(everything), real_fragments(kept)
    all_keys = key(everything)
    assert np.unique(all_keys).size == all_keys.size  # one fragment per segment and pixel
    return np.isin(all_keys, key(kept))


def _stages(cutoff):
    """The dense scene, its geometry stage with every fragment and at `cutoff` (None: the
    default), and the cutoff in effect."""
    scene = _dense_scene()
    everything, kept = geometry_stage(scene, cutoff=0.0), geometry_stage(scene, cutoff=cutoff)
    return scene, everything, kept, drawn_cutoff(WORKING) if cutoff is None else cutoff


@pytest.mark.parametrize("cutoff", [None, 1e-3])
def test_the_kept_fragments_are_those_seen_through_the_cutoff(cutoff):
    scene, everything, kept, c = _stages(cutoff)
    t = _front_transmittance(scene)
    # The composite's T_k is a product of up to `longest` factors, each rounding by half an
    # epsilon of the working precision: fragments that near the cutoff may fall either way.
    longest = max(stop - start for start, stop in _runs(real_fragments(everything)["frag_pixel"]))
    slack = longest * float(np.finfo(WORKING).eps)
    mask = _kept_mask(everything, kept)
    assert np.all(mask[t >= c * (1 + slack)]) and not np.any(mask[t < c * (1 - slack)])
    assert (t < c * (1 - slack)).sum() >= 10  # the scene does hide fragments at this cutoff
    # The kept fragments are the full stage's, in order, with their own weights.
    kept_fragments, all_fragments = real_fragments(kept), real_fragments(everything)
    for name in FRAGMENT_FIELDS:
        np.testing.assert_array_equal(kept_fragments[name], all_fragments[name][mask])
    # Each pixel's T keeps the hidden fragments' factors, multiplied apart from the seen
    # ones' (`GeometrySetup.hidden`): the same product of up to `longest` factors, each
    # rounding by half an epsilon, grouped otherwise.
    np.testing.assert_allclose(
        np.asarray(kept.transmittance), np.asarray(everything.transmittance), rtol=slack, atol=0
    )


@pytest.mark.parametrize("cutoff", [None, 1e-3])
def test_the_image_moves_by_less_than_the_cutoff_times_the_brightest_colour(cutoff):
    scene, everything, kept, c = _stages(cutoff)
    full, cut = (np.asarray(shading_stage(g, scene.params)) for g in (everything, kept))
    brightest = np.asarray(point_colors(everything, scene.params)).max(axis=0)  # fragments interpolate these
    # Bound (module docstring of _hidden): the left-out weights sum to at most c per pixel;
    # plus the rounding of a colour of order one, summed in another order (8 ulps).
    ulp = float(np.finfo(WORKING).eps)
    bound = c * brightest + 8 * ulp
    assert np.all(np.abs(full[..., :3] - cut[..., :3]) <= bound)
    np.testing.assert_array_equal(full[..., 3], cut[..., 3])  # the alpha channel is T's
    if cutoff is not None:
        assert np.abs(full - cut).max() > 8 * ulp  # the cut did move the image


def test_drawn_cutoff_is_half_an_ulp_of_one():
    assert drawn_cutoff(np.float32) == 2.0**-24 and drawn_cutoff(np.float64) == 2.0**-53


def test_a_given_alpha_keeps_every_fragment_and_takes_no_cutoff():
    scene = small_furball_scene(strands=30, size=16, shadows="none")
    with pytest.raises(ValueError, match="cutoff"):
        geometry_stage(scene, jnp.asarray(scene.strands.alpha), cutoff=1e-3)


@pytest.mark.parametrize("keep", [keep_visible, keep_on_host, keep_on_device])
def test_keep_visible_keeps_the_set_entries_in_order(keep):
    visible = jnp.asarray([True, False, True, True, False, True])
    a, b = jnp.arange(6, dtype=jnp.int32), jnp.linspace(0.0, 1.0, 6, dtype=jnp.float32)
    ka, kb = keep(visible, a, b)
    np.testing.assert_array_equal(np.asarray(ka), [0, 2, 3, 5])
    np.testing.assert_array_equal(np.asarray(kb), np.asarray(b)[[0, 2, 3, 5]])
    assert ka.dtype == jnp.int32 and kb.dtype == jnp.float32


@cpu_only
def test_the_host_cut_is_shared_with_jax():
    """On the CPU the kept fragments are written into aligned buffers that JAX shares
    (`_host`), as the set-up's are: no second copy."""
    visible = jnp.asarray(np.arange(4096) % 3 != 0)
    (kept,) = keep_on_host(visible, jnp.arange(4096, dtype=jnp.int32))
    assert kept.unsafe_buffer_pointer() % ALIGNMENT == 0
