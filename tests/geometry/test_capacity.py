"""The fragment arrays' buckets (hairjax/_geometry/_capacity.py, docs/model.md §6): few
sizes, little padding, and a moved camera that reuses the compiled stages."""

import dataclasses

import numpy as np
from helpers import real_fragments, small_furball_scene

import hairjax as hj
from hairjax._geometry._capacity import MIN_BUCKET, fragment_bucket
from hairjax._geometry_stage._setup import prepare


def test_buckets_are_eight_to_an_octave_and_pad_by_at_most_an_eighth():
    assert fragment_bucket(0) == fragment_bucket(1) == fragment_bucket(MIN_BUCKET) == MIN_BUCKET
    assert fragment_bucket(MIN_BUCKET + 1) == MIN_BUCKET * 9 // 8
    n = np.unique(np.r_[np.arange(1, 5000), np.geomspace(5000, 1e9, 4000).astype(np.int64)])
    b = np.array([fragment_bucket(int(k)) for k in n])
    assert np.all(b >= n) and np.all(np.diff(b) >= 0)
    assert np.all(b[n >= MIN_BUCKET] <= n[n >= MIN_BUCKET] * 9 / 8)
    # Eight sizes in every octave above the minimum: n in (2^20, 2^21] takes 2^17 · (9 … 16).
    octave = np.unique([fragment_bucket(k) for k in range((1 << 20) + 1, (1 << 21) + 1)])
    np.testing.assert_array_equal(octave, (1 << 17) * np.arange(9, 17))


def test_the_geometry_is_padded_to_its_bucket_and_the_set_up_is_not():
    scene = small_furball_scene(strands=200, size=32)
    setup, geometry = prepare(scene), hj.geometry_stage(scene, cutoff=0.0)
    n = setup.frag_pixel.size
    assert n > 100 and all(x.shape == (n,) for x in (setup.frag_i0, setup.frag_t, setup.frag_coverage))
    assert geometry.frag_pixel.shape == (fragment_bucket(n),)
    real = real_fragments(geometry)  # pixel H·W and weight 0 after the real ones
    np.testing.assert_array_equal(real["frag_pixel"], setup.frag_pixel)
    assert np.all(np.asarray(geometry.frag_weight)[n:] == 0)
    for padded, exact in zip(setup.padded_fragments, (setup.frag_pixel, setup.frag_i0, setup.frag_coverage)):
        np.testing.assert_array_equal(np.asarray(padded)[:n], exact)


def test_a_camera_moved_a_little_keeps_the_bucket():
    """Fewer or more fragments, the same bucket: the composite and the shading stage run
    the programs compiled for the first view (3–4 s a view saved on the default scene,
    BENCHMARKS.md)."""
    scene = small_furball_scene(strands=400, size=48)
    eye = np.asarray(scene.camera.eye)
    moved = scene.replace(camera=dataclasses.replace(scene.camera, eye=tuple(eye * 1.01)))
    counts = [prepare(s).frag_pixel.size for s in (scene, moved)]
    assert counts[0] != counts[1]
    shapes = {hj.geometry_stage(s).frag_pixel.shape for s in (scene, moved)}
    assert len(shapes) == 1
