"""The scene's values (hairjax/_scene/_scene.py, _camera.py, _occluder.py): what `Scene`,
`Camera` and `Occluder` refuse at construction (a SceneError naming the field), what
`Scene.replace(params=...)` swaps, and the camera's default near plane.

Scene files reach the same checks through hairjax/_scene/_file.py (tests/scene/test_file.py);
these build the values in Python, as a script or notebook does.

A value of the wrong *type* meets two checks: the constructor's own (SceneError naming the
field), and, where pytest checks hairjax's annotations at run time (jaxtyping's import hook,
`--jaxtyping-packages`), the annotation's, which comes first and names the parameter;
`refused` accepts either. Wrong values of the right type always reach the SceneError."""

from __future__ import annotations

import re

import numpy as np
import pytest
from helpers import refused

import hairjax as hj
from hairjax._constants import NEAR_FRACTION

HAIR = hj.furball(strands=3, points=4, seed=0)
QUAD = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
QUAD_TRIANGLES = [[0, 1, 2], [0, 2, 3]]


def assert_same_params(a, b):
    assert type(a) is type(b)
    for field in ("kd", "ks", "shininess", "kappa", "ambient"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)


# --------------------------------------------------------------------------- Scene


@pytest.mark.parametrize(
    "field, value, kind, got",
    [
        ("strands", QUAD, "Strands", "ndarray"),
        ("camera", dict(eye=(0.0, 0.0, 4.0)), "Camera", "dict"),
        ("light", None, "Light", "NoneType"),
        # The parameters where the model belongs: the model wraps them (KajiyaKay(params)).
        ("shading", hj.ShadingParams(), "AbstractShadingModel", "ShadingParams"),
        # A method's name where its object belongs (hj.Shadows("exact"), hj.Ordering("bins")).
        ("shadows", "exact", "AbstractShadowMethod", "str"),
        ("ordering", "bins", "AbstractOrdering", "str"),
    ],
)
def test_a_value_of_the_wrong_type_is_refused_naming_the_field(field, value, kind, got):
    kwargs = {"strands": HAIR, field: value}
    with refused(field, f"^scene\\.{field} must be a {kind}, got {got}$"):
        hj.Scene(**kwargs)


def test_optional_parts_of_the_wrong_type_are_refused():
    with refused("streaks", r"^scene\.streaks must be a Streaks or None$"):
        hj.Scene(HAIR, streaks=0.5)
    with refused("patches", r"^scene\.patches must be a PatchGeometry or None$"):
        hj.Scene(HAIR, patches=0.04)
    with pytest.raises(hj.SceneError, match=r"^background\.color must be a non-negative number"):
        hj.Scene(HAIR, background=(0.1, -0.2, 0.3))
    # Patches take an occluder: the head, drawn first (docs/model.md §18).
    assert hj.Scene(HAIR, patches=hj.PatchGeometry(width=0.04), occluder=hj.Occluder()).occluder is not None
    for key, value, name in [
        ("strands", 0, "patch_strands"),
        ("strand_alpha", -0.1, "patch_strand_alpha"),
        ("tips", 2.0, "patch_strand_tips"),
    ]:
        with pytest.raises(hj.SceneError, match=rf"^hair\.{name} must be"):
            hj.PatchGeometry(width=0.04, **{key: value})


def test_defaults_and_the_background():
    assert hj.Scene(HAIR).background == (0.0, 0.0, 0.0)
    scene = hj.Scene(HAIR, background=(0.25, 0.5, 1.0))
    assert scene.background == (0.25, 0.5, 1.0)
    assert all(type(c) is float for c in scene.background)
    assert isinstance(scene.shading, hj.KajiyaKay) and scene.params is scene.shading.params
    assert scene.occluder is None and scene.streaks is None and scene.patches is None


def test_replace_params_swaps_the_models_parameters_only():
    scene = hj.Scene(
        HAIR,
        shading=hj.KajiyaKayMirror(hj.ShadingParams(kd=0.6, ks=0.4)),
        background=(0.1, 0.1, 0.1),
        name="s",
    )
    new = hj.ShadingParams(kd=(0.1, 0.2, 0.3), ks=0.05, shininess=7.0, kappa=0.2, ambient=0.0)
    swapped = scene.replace(params=new)
    # The same model (not the default KajiyaKay) holding the new parameters …
    assert type(swapped.shading) is hj.KajiyaKayMirror
    assert_same_params(swapped.params, new)
    assert swapped.params is swapped.shading.params
    # … and every other field as it was; the original scene untouched.
    for field in ("strands", "camera", "light", "shadows", "ordering"):
        assert getattr(swapped, field) is getattr(scene, field), field
    assert (swapped.background, swapped.name) == ((0.1, 0.1, 0.1), "s")
    np.testing.assert_array_equal(scene.params.kd, 0.6)
    # With shading= as well, the parameters go into the given model.
    both = scene.replace(shading=hj.KajiyaKay(), params=new)
    assert type(both.shading) is hj.KajiyaKay
    assert_same_params(both.params, new)
    # The image is the one of those parameters.
    small = scene.replace(camera=hj.Camera(width=12, height=10), shadows=hj.Shadows("none"))
    np.testing.assert_array_equal(
        np.asarray(hj.render(small.replace(params=new))), np.asarray(hj.render(small, new))
    )


def test_replace_params_refuses_another_models_parameters():
    scene = hj.Scene(HAIR)
    message = "shading model 'kajiya-kay' takes ShadingParams, got ScheuermannParams"
    with pytest.raises(TypeError, match=f"^{re.escape(message)}$"):
        scene.replace(params=hj.ScheuermannParams())
    with pytest.raises(TypeError, match="takes ShadingParams, got dict"):
        scene.replace(params={"kd": 0.5})
    assert isinstance(scene.params, hj.ShadingParams)  # the scene is unchanged


# --------------------------------------------------------------------------- Camera


def test_camera_near_defaults_to_a_fraction_of_the_distance_to_the_target():
    assert NEAR_FRACTION == 1e-3  # the value Camera's docstring states
    # |target − eye| = 3 (not |eye|, which is 3 too here: the second camera tells them apart).
    assert hj.Camera(eye=(1.0, 2.0, 2.0), target=(0.0, 0.0, 0.0)).near == NEAR_FRACTION * 3.0
    assert hj.Camera(eye=(5.0, 0.0, 0.0), target=(1.0, 0.0, 0.0)).near == NEAR_FRACTION * 4.0
    cam = hj.Camera(eye=(0.0, 0.0, 400.0), target=(0.0, 0.0, 0.0))
    assert cam.near == pytest.approx(0.4, rel=1e-15)
    # A given near is kept, as a float.
    given = hj.Camera(near=2)
    assert given.near == 2.0 and type(given.near) is float


@pytest.mark.parametrize("near", [0.0, -1.0, float("nan"), float("inf")])
def test_camera_refuses_a_near_plane_that_is_not_positive_and_finite(near):
    with pytest.raises(hj.SceneError, match=r"^camera\.near must be positive"):
        hj.Camera(near=near)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(eye=(0.0, 0.0, 0.0)), "camera.eye and camera.target must differ"),
        (dict(up=(0.0, 0.0, 1.0)), "camera.up must not be parallel to the view direction"),
        (dict(up=(0.0, 0.0, 0.0)), "camera.up must not have length 0"),
        (dict(eye=(0.0, 0.0)), "camera.eye must be 3 finite numbers"),
        (dict(fov=180.0), "camera.fov must be in (0, 180) degrees"),
        (dict(width=0), "camera.width must be an integer in [1, 16384]"),
        (dict(width=True), "camera.width must be an integer"),
        (dict(offset=(0.6, 0.0)), "camera.offset must be two numbers in [-0.5, 0.5]"),
    ],
)
def test_camera_refuses_each_bad_value_naming_it(kwargs, message):
    with pytest.raises(hj.SceneError, match="^" + re.escape(message)):
        hj.Camera(**kwargs)


# --------------------------------------------------------------------------- Occluder


def test_a_mesh_occluder_holds_read_only_arrays_and_compares_by_them():
    occ = hj.Occluder(kind="mesh", vertices=QUAD.tolist(), triangles=QUAD_TRIANGLES)
    assert occ.vertices.dtype == np.float64 and occ.triangles.dtype == np.int32
    assert occ.vertices.shape == (4, 3) and occ.triangles.shape == (2, 3)
    assert not occ.vertices.flags.writeable and not occ.triangles.flags.writeable
    assert occ == hj.Occluder(kind="mesh", vertices=QUAD, triangles=np.array(QUAD_TRIANGLES))
    assert occ != hj.Occluder(kind="mesh", vertices=QUAD * 2, triangles=QUAD_TRIANGLES)
    assert occ != hj.Occluder(kind="mesh", vertices=QUAD, triangles=[[0, 1, 2]])
    # The arrays are copies: changing the caller's array later changes nothing.
    vertices = QUAD.copy()
    kept = hj.Occluder(kind="mesh", vertices=vertices, triangles=QUAD_TRIANGLES)
    vertices[0] = 9.0
    np.testing.assert_array_equal(kept.vertices, QUAD)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(kind="mesh"), "occluder kind 'mesh' needs path, or vertices and triangles"),
        (dict(kind="mesh", vertices=QUAD), "occluder kind 'mesh' needs path, or vertices and triangles"),
        (
            dict(kind="mesh", vertices=QUAD, triangles=QUAD_TRIANGLES, path="head.obj"),
            "occluder: give either path or vertices and triangles, not both",
        ),
        (
            dict(kind="sphere", vertices=QUAD, triangles=QUAD_TRIANGLES),
            "occluder.path, vertices and triangles are for kind 'mesh' only",
        ),
        (
            dict(kind="mesh", vertices=QUAD[:, :2], triangles=QUAD_TRIANGLES),
            "occluder.vertices must be finite [V, 3], got shape (4, 2)",
        ),
        (
            dict(kind="mesh", vertices=np.where(QUAD == 1.0, np.nan, QUAD), triangles=QUAD_TRIANGLES),
            "occluder.vertices must be finite [V, 3]",
        ),
        (
            dict(kind="mesh", vertices=QUAD, triangles=np.array(QUAD_TRIANGLES, float)),
            "occluder.triangles must be integer [F, 3] with F ≥ 1, got shape (2, 3) and dtype float64",
        ),
        (
            dict(kind="mesh", vertices=QUAD, triangles=np.zeros((0, 3), int)),
            "occluder.triangles must be integer [F, 3] with F ≥ 1, got shape (0, 3)",
        ),
        (
            dict(kind="mesh", vertices=QUAD, triangles=[[0, 1, 2, 3]]),
            "occluder.triangles must be integer [F, 3] with F ≥ 1, got shape (1, 4)",
        ),
        (dict(kind="mesh", vertices=QUAD, triangles=[[0, 1, 4]]), "occluder.triangles index outside [0, 4)"),
        (dict(kind="mesh", vertices=QUAD, triangles=[[0, -1, 2]]), "occluder.triangles index outside [0, 4)"),
        (dict(radius=0.0), "occluder.radius must be positive"),
        (dict(center=(0.0, np.inf, 0.0)), "occluder.center must be 3 finite numbers"),
        (dict(color=(0.5, -0.5, 0.5)), "occluder.color must be a non-negative number or 3 of them"),
    ],
)
def test_occluder_refuses_each_bad_value_naming_it(kwargs, message):
    with pytest.raises(hj.SceneError, match="^" + re.escape(message)):
        hj.Occluder(**kwargs)


def test_camera_and_occluder_refuse_values_of_the_wrong_type():
    with refused("height", r"^camera\.height must be an integer in \[1, 16384\], got 2\.5$"):
        hj.Camera(height=2.5)
    with refused("kind", r"^occluder\.kind must be one of \('sphere', 'mesh'\), got 'cube'$"):
        hj.Occluder(kind="cube")
    with refused("kind", r"^light\.kind must be 'directional' or 'point', got 'spot'$"):
        hj.Light(kind="spot")


def test_a_mesh_occluder_from_an_obj_file(tmp_path):
    good = tmp_path / "quad.obj"
    good.write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n")
    occ = hj.Occluder(kind="mesh", path=str(good))
    np.testing.assert_array_equal(occ.vertices, QUAD)
    np.testing.assert_array_equal(occ.triangles, QUAD_TRIANGLES)  # the quad fanned, 0-based
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(hj.SceneError, match=r"^occluder\.path could not be loaded: .*bad\.obj:3"):
        hj.Occluder(kind="mesh", path=str(bad))
