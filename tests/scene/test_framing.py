"""Automatic framing (hairjax/_scene/_framing.py): every shared asset fills the view, the
camera follows the strands' position and scale, and the key light comes from the upper
left front."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import DATA

import hairjax as hj
from hairjax._errors import SceneError
from hairjax._geometry._projection import camera_view
from hairjax._scene._file import scene_for_hair
from hairjax._scene._framing import frame_camera, key_light
from hairjax._values._strands import Strands

ASSETS = (
    sorted(DATA.glob("hair/*.hair")) + sorted(DATA.glob("hair/*.ply")) + sorted(DATA.glob("tressfx/*.tfx"))
)

# The acceptance threshold for a framed asset: its hair covers at least 5 % of the image, a
# low bar for a camera that fits the hair's bounding sphere to the narrower field of view
# with a 10 % margin (docs/scenes.md, `[camera]`, `frame = "auto"`).
MIN_COVERAGE = 0.05


def cloud(seed: int = 0, n: int = 200) -> Strands:
    """Ten strands of random points, off the origin, in a box of unequal sides."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-1, 1, (n, 3)) * [3.0, 1.0, 2.0] + [40.0, -7.0, 12.0]
    return Strands(points, np.linspace(0, n, 11).astype(int), 1.0, 1.0)


@pytest.mark.skipif(not ASSETS, reason=f"no hair assets in {DATA}")
@pytest.mark.slow
@pytest.mark.parametrize("path", ASSETS, ids=lambda p: p.name)
def test_every_asset_is_framed(path):
    scene = scene_for_hair(path, width=96, height=96)
    # Coverage is alpha, which the shadow maps do not change (they darken colour only):
    # rendered without them, for time.
    alpha = np.asarray(hj.render(scene.replace(shadows=hj.Shadows("none"))))[..., 3]
    assert np.mean(alpha > 0) >= MIN_COVERAGE
    # The bounding sphere stays inside: no hair on the image's outer rows and columns...
    assert not alpha[[0, -1], :].any() and not alpha[:, [0, -1]].any()
    # ...and every point projects inside the image, in front of the camera.
    xy, depth = camera_view(scene.camera).project(scene.strands.points)
    assert np.all(depth > scene.camera.near)
    assert np.all((xy > 0) & (xy < 96))


def test_sphere_fills_the_narrower_field_of_view():
    # Two points at ±1 on x: the sphere is centred at the origin with radius 1; the eye
    # lies at 1.1 / sin(half the narrower field of view) from it (the docstring's rule).
    two = Strands([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [0, 2], 1.0, 1.0)
    for width, height, half in (
        (100, 100, math.radians(20.0)),  # square: the vertical fov
        (200, 100, math.radians(20.0)),  # wide: still the vertical fov
        (100, 200, math.atan(math.tan(math.radians(20.0)) / 2)),  # tall: the horizontal one
    ):
        cam = frame_camera(two, width=width, height=height, fov=40.0)
        assert cam.target == (0.0, 0.0, 0.0)
        assert np.linalg.norm(cam.eye) == pytest.approx(1.1 / math.sin(half), rel=1e-12)  # float64 rounding
        assert (cam.width, cam.height, cam.fov) == (width, height, 40.0)


def test_three_quarter_view_from_front_right_above():
    cam = frame_camera(cloud())
    d = np.subtract(cam.eye, cam.target)
    # 35° from the front (+z) towards +x, 20° up (the docstring's view).
    assert math.degrees(math.atan2(d[0], d[2])) == pytest.approx(35.0, abs=1e-9)  # float64 rounding
    assert math.degrees(math.asin(d[1] / np.linalg.norm(d))) == pytest.approx(20.0, abs=1e-9)
    assert cam.up == (0.0, 1.0, 0.0)


def test_translation_moves_the_eye_by_the_translation():
    strands = cloud()
    shift = np.array([-123.0, 45.0, 6.5])
    a = frame_camera(strands)
    b = frame_camera(strands.transformed(1.0, shift))
    # Tolerance: float64 rounding of coordinates of size ~150.
    np.testing.assert_allclose(np.subtract(b.eye, a.eye), shift, atol=1e-9)
    np.testing.assert_allclose(np.subtract(b.target, a.target), shift, atol=1e-9)


def test_doubling_the_scale_doubles_the_eye_distance():
    strands = cloud(1)
    a = frame_camera(strands)
    b = frame_camera(strands.transformed(2.0))
    dist_a = np.linalg.norm(np.subtract(a.eye, a.target))
    dist_b = np.linalg.norm(np.subtract(b.eye, b.target))
    assert dist_b == pytest.approx(2 * dist_a, rel=1e-12)  # float64 rounding
    # The view direction is the same: only the distance changes.
    np.testing.assert_allclose(
        np.subtract(b.eye, b.target) / dist_b, np.subtract(a.eye, a.target) / dist_a, atol=1e-12
    )


def test_random_clouds_project_inside_wide_and_tall_images():
    for seed, (width, height) in enumerate([(64, 64), (160, 48), (48, 160)]):
        cam = frame_camera(cloud(seed), width=width, height=height, fov=30.0)
        xy, depth = camera_view(cam).project(cloud(seed).points)
        assert np.all(depth > cam.near)
        assert np.all((xy[:, 0] > 0) & (xy[:, 0] < width) & (xy[:, 1] > 0) & (xy[:, 1] < height))


def test_a_single_point_is_framed():
    cam = frame_camera(Strands([[5.0, 5.0, 5.0]], [0, 1], 1.0, 1.0))
    assert cam.target == (5.0, 5.0, 5.0)
    # The zero-radius guard frames one world unit.
    assert np.linalg.norm(np.subtract(cam.eye, cam.target)) == pytest.approx(
        1.1 / math.sin(math.radians(20.0)), rel=1e-12
    )


def test_no_points_and_bad_sizes_are_scene_errors():
    with pytest.raises(SceneError, match="without points"):
        frame_camera(Strands(np.zeros((0, 3)), [0], 1.0, 1.0))
    with pytest.raises(SceneError, match="camera.fov"):
        frame_camera(cloud(), fov=180.0)
    with pytest.raises(SceneError, match="camera.width"):
        frame_camera(cloud(), width=0)


def test_key_light_comes_from_upper_left_front():
    cam = frame_camera(cloud())
    light = key_light(cam)
    view = camera_view(cam)
    towards_light = -np.asarray(light.direction)  # direction: the way the light travels
    assert light.kind == "directional"
    assert towards_light @ view.up > 0  # above
    assert towards_light @ view.right < 0  # left
    assert towards_light @ view.forward < 0  # in front of the hair, on the eye's side


@pytest.mark.skipif(not (DATA / "tressfx/ponytail_tail.tfx").is_file(), reason=f"no {DATA}")
def test_scene_for_hair_widths_follow_the_asset():
    path = DATA / "tressfx/ponytail_tail.tfx"
    scene = scene_for_hair(path, width=80, height=60)
    points = scene.strands.points
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    radius = np.linalg.norm(points - centre, axis=1).max()
    assert scene.strands.width_units == "world"
    np.testing.assert_allclose(scene.strands.width, radius / 128, rtol=1e-12)  # the 1/128 of the docstring
    assert np.all(scene.strands.alpha == 0.5)  # as a scene file's hair
    assert (scene.camera.width, scene.camera.height) == (80, 60)
    assert scene.name == "ponytail_tail"


def test_azimuth_elevation_and_zoom_place_the_eye():
    """From the front (azimuth 0, elevation 0) the eye lies on +z from the centre; zoom 2
    halves the distance."""
    base = frame_camera(cloud())
    cam = frame_camera(cloud(), azimuth=0.0, elevation=0.0, zoom=2.0)
    d = np.subtract(cam.eye, cam.target)
    assert cam.target == base.target
    assert abs(d[0]) < 1e-12 and abs(d[1]) < 1e-12 and d[2] > 0  # float64 rounding of cos/sin
    dist = np.linalg.norm(np.subtract(base.eye, base.target))
    assert np.linalg.norm(d) == pytest.approx(dist / 2, rel=1e-12)
    cam = frame_camera(cloud(), azimuth=180.0, elevation=-30.0)
    d = np.subtract(cam.eye, cam.target)
    assert d[2] < 0 and math.degrees(math.asin(d[1] / np.linalg.norm(d))) == pytest.approx(-30.0, abs=1e-9)


def test_framing_keys_in_a_scene_file(tmp_path):
    hair = tmp_path / "s.toml"
    hair.write_text(
        '[hair]\nsource = "furball"\nstrands = 20\npoints = 4\n'
        '[camera]\nframe = "auto"\nazimuth = 0.0\nelevation = 0.0\nzoom = 1.5\nwidth = 32\nheight = 32\n'
    )
    scene = hj.load_scene(hair)
    expected = frame_camera(scene.strands, width=32, height=32, azimuth=0.0, elevation=0.0, zoom=1.5)
    assert scene.camera.eye == expected.eye
    for text, message in (
        ("elevation = 90.0", r"camera\.elevation must be in \(-90, 90\)"),
        ("zoom = 0", r"camera\.zoom must be > 0"),
    ):
        hair.write_text(f'[hair]\nsource = "furball"\n[camera]\nframe = "auto"\n{text}\n')
        with pytest.raises(SceneError, match=message):
            hj.load_scene(hair)
    hair.write_text('[hair]\nsource = "furball"\n[camera]\nazimuth = 10.0\n')
    with pytest.raises(SceneError, match=r"camera\.azimuth applies only to frame = 'auto'"):
        hj.load_scene(hair)


@pytest.mark.skipif(not ASSETS, reason=f"no hair assets in {DATA}")
def test_a_hair_file_is_framed_from_the_front_with_set():
    scene = scene_for_hair(
        ASSETS[0], width=32, height=32, overrides={"camera.azimuth": 0, "camera.elevation": 0}
    )
    d = np.subtract(scene.camera.eye, scene.camera.target)
    assert abs(d[0]) < 1e-9 * np.linalg.norm(d) and d[2] > 0  # on +z: the front
