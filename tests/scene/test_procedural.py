"""Procedural sources (docs/model.md §1, wenzel-2002)."""

import numpy as np
import pytest

import hairjax as hj


def test_furball_follows_the_joint_rule():
    g, inertia = np.array([0.0, -0.3, 0.0]), np.array([0.05, 0.0, 0.0])
    hair = hj.furball(strands=5, points=6, seed=7, length=1.0, gravity=g, inertia=inertia)
    pts = hair.points.reshape(5, 6, 3)
    np.testing.assert_array_equal(pts[:, 0], 0.0)  # every hair starts at the origin
    for h in range(5):
        steps = np.diff(pts[h], axis=0)
        lengths = np.linalg.norm(steps, axis=1)
        np.testing.assert_allclose(lengths, lengths[0], rtol=1e-12)  # per-hair length
        assert 0.8 / 5 <= lengths[0] <= 1.2 / 5
        dirs = steps / lengths[:, None]
        for j in range(1, 5):
            expected = dirs[j - 1] + g + inertia
            np.testing.assert_allclose(dirs[j], expected / np.linalg.norm(expected), rtol=1e-12)
        # The first step bends the random unit direction d₀: d₀ ∝ dirs[0]·|d₀ + g + i| − g − i
        d0 = dirs[0] * np.linalg.norm(dirs[0]) - g - inertia
        assert np.linalg.norm(d0) > 0


def test_furball_is_deterministic_per_seed():
    a, b, c = hj.furball(50, 4, seed=1), hj.furball(50, 4, seed=1), hj.furball(50, 4, seed=2)
    np.testing.assert_array_equal(a.points, b.points)
    assert not np.array_equal(a.points, c.points)


def test_scalp_roots_on_the_sphere_growing_outward():
    hair = hj.scalp(strands=200, points=5, seed=0, radius=0.5, coverage=0.5, gravity=(0, 0, 0))
    pts = hair.points.reshape(200, 5, 3)
    np.testing.assert_allclose(np.linalg.norm(pts[:, 0], axis=1), 0.5, rtol=1e-12)
    assert pts[:, 0, 1].min() >= -1e-12  # coverage ½: the upper hemisphere
    # Without gravity a strand is straight along its root normal.
    np.testing.assert_allclose(
        np.linalg.norm(pts[:, -1], axis=1), 0.5 + np.linalg.norm(pts[:, -1] - pts[:, 0], axis=1), rtol=1e-12
    )


def test_combed_hair_lies_on_its_layers():
    """`combed` (docs/scenes.md): each strand on its layer's sphere down to the equator, then
    straight down; points evenly spaced along it; the face left open."""
    radius, gap, layers = 0.8, 0.06, 3
    hair = hj.combed(strands=60, points=24, seed=5, length=2.0, radius=radius, layers=layers)
    pts = hair.points.reshape(60, 24, 3)
    shell = radius * (1 + gap * (np.arange(60) % layers + 1))  # layer i mod 3, innermost 0
    upper = pts[..., 1] >= 0
    dist = np.linalg.norm(pts, axis=2)
    np.testing.assert_allclose(dist[upper], np.broadcast_to(shell[:, None], dist.shape)[upper], rtol=1e-12)
    # Below the equator: straight down at the layer's radius in x, z.
    below = ~upper
    np.testing.assert_allclose(
        np.linalg.norm(pts[..., [0, 2]], axis=2)[below], np.broadcast_to(shell[:, None], dist.shape)[below]
    )
    # Roots near the crown: polar angle in [0.1, 0.2] rad.
    polar = np.arccos(pts[:, 0, 1] / shell)
    assert polar.min() >= 0.1 - 1e-12 and polar.max() <= 0.2 + 1e-12
    # Evenly spaced points along each strand (a chord of an arc of at most 2/23 of the
    # length is within 0.1 % of the arc).
    steps = np.linalg.norm(np.diff(pts, axis=1), axis=2)
    np.testing.assert_allclose(steps, steps[:, :1] * np.ones_like(steps), rtol=1e-3)
    # The face (azimuth within 0.9 rad of +z) is open: those strands end at polar angle 1.
    azimuth = np.arctan2(pts[:, 0, 0], pts[:, 0, 2])
    over_face = np.abs(azimuth) < 0.9
    assert over_face.any() and (~over_face).any()
    tip_polar = np.arccos(np.clip(pts[:, -1, 1] / shell, -1, 1))
    assert np.all(tip_polar[over_face] <= 1.0 + 1e-9)
    assert np.all(pts[~over_face, -1, 1] < 0)  # the others hang below the equator
    np.testing.assert_array_equal(hj.combed(10, 4, seed=1).points, hj.combed(10, 4, seed=1).points)


@pytest.mark.parametrize("kwargs", [dict(strands=0), dict(points=1)])
def test_bad_arguments(kwargs):
    with pytest.raises(ValueError):
        hj.furball(**kwargs)
