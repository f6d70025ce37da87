"""Scene files: the default scene, the example scenes, every kind of error, hair paths,
and the [hair] transforms."""

from __future__ import annotations

import math
import os
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from helpers import DATA, EXAMPLES, REPO

import hairjax as hj
from hairjax import Camera, Light, Occluder, Ordering, Shadows
from hairjax._errors import HairFormatError, SceneError
from hairjax._scene._file import default_scene_path, load_scene, scene_from_dict
from hairjax._scene._procedural import combed, furball, scalp
from hairjax._values._strands import Strands

PONYTAIL_TAIL = DATA / "tressfx" / "ponytail_tail.tfx"  # read in place (shared/data/README.md)

# A valid [hair] table small enough to generate in microseconds.
HAIR = '[hair]\nsource = "furball"\nstrands = 50\n'


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def real_load_hair():
    """The real reader, for tests that read shared/data; skip where the data is not beside
    the checkout (CI has it; a clone elsewhere may not)."""
    from hairjax._io import load_hair

    if not DATA.is_dir():
        pytest.skip(f"{DATA} is not beside the checkout")
    return load_hair


@pytest.fixture
def fake_io(monkeypatch):
    """Replace `hairjax._io` with a recorder returning two hand-made strands, so path
    resolution and the [hair] transforms are tested independently of the file readers."""
    calls = []

    def load_hair(path, alpha=1.0, width=1.0):
        calls.append({"path": Path(path), "alpha": alpha, "width": width})
        return Strands.from_list([[[0, 0, 0], [1, 0, 0]], [[0, 1, 0], [0, 1, 2]]], alpha=alpha, width=width)

    module = types.ModuleType("hairjax._io")
    module.load_hair = load_hair
    monkeypatch.setitem(sys.modules, "hairjax._io", module)
    return calls


# --------------------------------------------------------------------------- default


def test_default_scene_path_is_packaged():
    path = default_scene_path()
    assert path.is_file()
    assert path.parent.name == "scenes" and path.parent.parent.name == "hairjax"


def test_default_scene_values():
    scene = load_scene(default_scene_path())
    assert scene.name == "default"

    hair = scene.strands
    assert hair.num_strands == 20000 and hair.num_points == 20000 * 16
    np.testing.assert_array_equal(np.diff(hair.offsets), 16)
    np.testing.assert_array_equal(hair.alpha, 0.5)
    np.testing.assert_array_equal(hair.width, 1.0)
    assert hair.color is None
    # The same generator call, so seed, length and gravity all match.
    expected = furball(strands=20000, points=16, seed=0, length=1.0, gravity=(0.0, -0.08, 0.0))
    np.testing.assert_array_equal(hair.points, expected.points)

    assert scene.camera == Camera(
        eye=(0.0, 0.3, 4.2), target=(0.0, -0.1, 0.0), up=(0.0, 1.0, 0.0), fov=40.0, width=512, height=512
    )
    assert scene.light == Light(kind="directional", direction=(-0.6, -0.8, -0.5), color=(1.0, 1.0, 1.0))
    assert isinstance(scene.shading, hj.KajiyaKay) and type(scene.shading).name == "kajiya-kay"
    p = scene.params
    np.testing.assert_allclose(p.kd, [0.55, 0.35, 0.2], rtol=1e-6)
    np.testing.assert_allclose(p.ks, [0.35] * 3, rtol=1e-6)
    np.testing.assert_allclose(p.shininess, 30.0)
    np.testing.assert_allclose(p.kappa, 1.0)
    np.testing.assert_allclose(p.ambient, [0.05] * 3, rtol=1e-6)
    assert scene.shadows == Shadows(method="opacity-maps", maps=64, resolution=256)
    assert scene.ordering == Ordering(method="bins", bins=256)
    assert scene.occluder is None
    assert scene.background == (0.02, 0.02, 0.03)


# --------------------------------------------------------------------------- examples

EXAMPLE_NAMES = [
    "point_light",
    "grazing",
    "dense_opaque",
    "occluder",
    "tressfx_ponytail",
    "sintel",
    "furball_animated",
    "scheuermann",
    "patches",
    "deep",
]


def test_every_example_is_listed():
    assert sorted(p.stem for p in EXAMPLES.glob("*.toml")) == sorted(EXAMPLE_NAMES)


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_example_scene_loads(name):
    if name in ("tressfx_ponytail", "sintel"):
        real_load_hair()
    scene = load_scene(EXAMPLES / f"{name}.toml")
    assert scene.name == name
    assert (scene.camera.width, scene.camera.height) in {(256, 256), (320, 320)}
    assert scene.strands.num_strands > 0


def test_example_specifics():
    point = load_scene(EXAMPLES / "point_light.toml")
    assert point.light.kind == "point" and point.strands.num_strands == 2000
    # The light is outside every hair (furball hairs are at most 1.2 long).
    assert np.linalg.norm(point.light.position) > 1.2 * 1.0 + 0.5

    grazing = load_scene(EXAMPLES / "grazing.toml")
    seg = grazing.strands.segments()
    t = grazing.strands.points[seg[:, 1]] - grazing.strands.points[seg[:, 0]]
    mean = t.sum(axis=0) / np.linalg.norm(t.sum(axis=0))
    light = np.asarray(grazing.light.direction) / np.linalg.norm(grazing.light.direction)
    assert abs(mean @ light) > 0.99  # within ~8° of the mean hair direction

    dense = load_scene(EXAMPLES / "dense_opaque.toml")
    np.testing.assert_array_equal(dense.strands.alpha, 1.0)
    assert dense.strands.num_strands >= 10000

    occ = load_scene(EXAMPLES / "occluder.toml")
    assert occ.occluder == Occluder(center=(0.0, 0.0, 0.0), radius=0.68, color=(0.6, 0.5, 0.45))
    roots = occ.strands.points[occ.strands.offsets[:-1]]
    assert np.all(np.linalg.norm(roots, axis=1) > occ.occluder.radius)


def assert_framed(scene):
    """Every hair point lies in front of the camera and inside 95% of its view cone."""
    cam = scene.camera
    forward = np.subtract(cam.target, cam.eye)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, cam.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = scene.strands.points - np.asarray(cam.eye)
    depth = rel @ forward
    tan_y = math.tan(math.radians(cam.fov) / 2)
    tan_x = tan_y * cam.width / cam.height
    assert np.all(depth > 0)
    assert np.all(np.abs(rel @ right) / depth < 0.95 * tan_x)
    assert np.all(np.abs(rel @ up) / depth < 0.95 * tan_y)


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_example_scene_is_framed(name):
    if name in ("tressfx_ponytail", "sintel"):
        real_load_hair()
    assert_framed(load_scene(EXAMPLES / f"{name}.toml"))


def test_a_directory_as_hair_source_says_it_is_one(tmp_path):
    (tmp_path / "adir.hair").mkdir()
    path = write(tmp_path, '[hair]\nsource = "adir.hair"\n')
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert str(err.value) == f"{path}: hair.source {tmp_path / 'adir.hair'}: is a directory, not a hair file"


def test_frame_auto_places_the_camera_from_the_hair(tmp_path):
    # A fur ball 10 times the default size, 100 units off the origin: the default camera
    # misses it, frame = "auto" shows all of it.
    hair = HAIR + "scale = 10.0\ntranslate = [100.0, -50.0, 20.0]\n"
    unframed = load_scene(write(tmp_path, hair, "plain.toml"))
    rel = unframed.strands.points - np.asarray(unframed.camera.eye)
    assert np.all(rel @ [0.0, 0.0, -1.0] < 0)  # all behind the default eye's view direction
    text = hair + '[camera]\nframe = "auto"\nfov = 30\nwidth = 64\nheight = 48\nnear = 0.25\n'
    scene = load_scene(write(tmp_path, text))
    assert_framed(scene)
    assert (scene.camera.fov, scene.camera.width, scene.camera.height, scene.camera.near) == (
        30.0,
        64,
        48,
        0.25,
    )
    centre = 0.5 * (scene.strands.points.min(axis=0) + scene.strands.points.max(axis=0))
    np.testing.assert_allclose(scene.camera.target, centre, atol=1e-9)  # float64 rounding at ~100
    assert scene.camera.up == (0.0, 1.0, 0.0)


def test_frame_auto_frames_a_real_file(tmp_path):
    real_load_hair()
    text = f'[hair]\nsource = "{PONYTAIL_TAIL}"\n[camera]\nframe = "auto"\nwidth = 32\nheight = 32\n'
    scene = load_scene(write(tmp_path, text))
    assert_framed(scene)
    # Without frame the file (in its own units, above the origin) is not in view.
    with pytest.raises(AssertionError):
        assert_framed(load_scene(write(tmp_path, f'[hair]\nsource = "{PONYTAIL_TAIL}"\n', "plain.toml")))


def test_tressfx_example_is_scaled():
    real_load_hair()
    scene = load_scene(EXAMPLES / "tressfx_ponytail.toml")
    assert scene.strands.num_strands == 3066 and scene.strands.num_points == 3066 * 16
    pts = scene.strands.points
    # scale/translate bring the ~107-unit model to about ±1.1 around the origin.
    assert np.all(np.abs(pts) < 1.2) and np.ptp(pts[:, 1]) > 2.0


# --------------------------------------------------------------------------- defaults


def test_absent_tables_take_dataclass_defaults(tmp_path):
    scene = load_scene(write(tmp_path, HAIR, "minimal.toml"))
    assert scene.name == "minimal"
    assert scene.camera == Camera()
    assert scene.light == Light()
    assert scene.shadows == Shadows() and scene.ordering == Ordering()
    assert scene.occluder is None
    assert scene.background == (0.0, 0.0, 0.0)
    assert isinstance(scene.shading, hj.KajiyaKay) and type(scene.shading).name == "kajiya-kay"
    np.testing.assert_allclose(scene.params.kd, [0.6] * 3, rtol=1e-6)
    np.testing.assert_allclose(scene.params.shininess, 40.0)
    np.testing.assert_array_equal(scene.strands.alpha, 0.5)
    np.testing.assert_array_equal(scene.strands.width, 1.0)
    np.testing.assert_array_equal(scene.strands.points, furball(strands=50).points)


@pytest.mark.parametrize(
    "table, message",
    [
        ('[shadows]\nmethod = "exact"\nmaps = 8\n', r"shadows\.maps is not a key of method = 'exact'"),
        (
            '[shadows]\nmethod = "none"\nresolution = 8\n',
            r"shadows\.resolution is not a key of method = 'none'",
        ),
        ('[ordering]\nmethod = "none"\nbins = 3\n', r"ordering\.bins is not a key of method = 'none'"),
    ],
)
def test_keys_another_method_would_ignore_are_refused(tmp_path, table, message):
    with pytest.raises(SceneError, match=message):
        load_scene(write(tmp_path, HAIR + table))


def test_deep_shadows_are_read(tmp_path):
    text = HAIR + '[shadows]\nmethod = "deep"\nlayers = 6\nresolution = 64\nlayer_spacing = 0.05\n'
    scene = load_scene(write(tmp_path, text))
    assert scene.shadows == Shadows("deep", layers=6, resolution=64, layer_spacing=0.05)
    for lookup in ("layer", "depth"):
        read = load_scene(write(tmp_path, text + f'lookup = "{lookup}"\n')).shadows
        assert read == Shadows("deep", layers=6, resolution=64, layer_spacing=0.05, lookup=lookup)
    assert (scene.shadows.layers, scene.shadows.resolution, scene.shadows.layer_spacing) == (6, 64, 0.05)
    # Absent keys take the defaults: 4 layers, 256², spacing 0 (the depth extent over K);
    # an integer spacing is a number.
    default = load_scene(write(tmp_path, HAIR + '[shadows]\nmethod = "deep"\nlayer_spacing = 1\n')).shadows
    assert (default.layers, default.resolution, default.layer_spacing) == (4, 256, 1.0)


def test_name_must_come_before_the_tables(tmp_path):
    # In TOML a key after [hair] belongs to [hair]; the error says where it landed.
    with pytest.raises(SceneError, match=r"unknown key hair\.name"):
        load_scene(write(tmp_path, HAIR + 'name = "x"\n'))


def test_values_are_read(tmp_path):
    text = (
        'name = "custom"\n'
        + HAIR
        + """
[camera]
fov = 30          # a TOML integer is fine where a float is expected
width = 64
height = 48
near = 0.5
[light]
kind = "point"
position = [1, 2, 3]
color = [0.5, 0.25, 0]
[shading]
model = "kajiya-kay-mirror"
kd = 0.25         # one number is grey
ks = [0, 0.5, 1]
shininess = 7
kappa = 0
ambient = [0.1, 0.2, 0.3]
[shadows]
method = "exact"
resolution = 4
[ordering]
method = "none"
[occluder]
[background]
color = [0.25, 0.5, 0.75]
"""
    )
    scene = load_scene(write(tmp_path, text))
    assert scene.name == "custom"
    assert scene.camera == Camera(fov=30.0, width=64, height=48, near=0.5)
    assert scene.light == Light(kind="point", position=(1.0, 2.0, 3.0), color=(0.5, 0.25, 0.0))
    assert isinstance(scene.shading, hj.KajiyaKayMirror)
    np.testing.assert_allclose(scene.params.kd, [0.25] * 3)
    np.testing.assert_allclose(scene.params.ks, [0, 0.5, 1])
    np.testing.assert_allclose(scene.params.shininess, 7.0)
    np.testing.assert_allclose(scene.params.kappa, 0.0)
    np.testing.assert_allclose(scene.params.ambient, [0.1, 0.2, 0.3], rtol=1e-6)
    assert scene.shadows == Shadows(method="exact", resolution=4)
    assert scene.ordering == Ordering(method="none")
    assert scene.occluder == Occluder()  # an empty [occluder] is the default sphere
    assert scene.background == (0.25, 0.5, 0.75)


def test_procedural_keys_are_passed_to_the_generators(tmp_path):
    text = """[hair]
source = "scalp"
strands = 20
points = 5
seed = 9
length = 0.5
gravity = [0, -0.3, 0.1]
radius = 2
coverage = 0.25
alpha = 0.75
width = 2.5
"""
    got = load_scene(write(tmp_path, text)).strands
    want = scalp(strands=20, points=5, seed=9, length=0.5, gravity=(0, -0.3, 0.1), radius=2.0, coverage=0.25)
    np.testing.assert_array_equal(got.points, want.points)
    np.testing.assert_array_equal(got.offsets, want.offsets)
    np.testing.assert_array_equal(got.alpha, 0.75)
    np.testing.assert_array_equal(got.width, 2.5)

    text = HAIR + "inertia = [0.1, 0, 0]\npoints = 4\n"
    got = load_scene(write(tmp_path, text)).strands
    want = furball(strands=50, points=4, inertia=(0.1, 0, 0))
    np.testing.assert_array_equal(got.points, want.points)

    text = '[hair]\nsource = "combed"\nstrands = 12\npoints = 6\nseed = 3\nlength = 1.5\n'
    text += "radius = 0.8\nlayers = 2\n"
    got = load_scene(write(tmp_path, text)).strands
    want = combed(strands=12, points=6, seed=3, length=1.5, radius=0.8, layers=2)
    np.testing.assert_array_equal(got.points, want.points)
    np.testing.assert_array_equal(got.offsets, want.offsets)


# --------------------------------------------------------------------------- transforms


def test_scale_translate_color_on_procedural_hair(tmp_path):
    text = HAIR + "seed = 7\nscale = 2\ntranslate = [1, 2, 3]\ncolor = [0.1, 0.2, 0.3]\n"
    hair = load_scene(write(tmp_path, text)).strands
    # Fur-ball roots are at the origin: scaled about the origin, then moved to (1, 2, 3).
    np.testing.assert_array_equal(hair.points[hair.offsets[:-1]], [[1.0, 2.0, 3.0]] * 50)
    raw = furball(strands=50, seed=7).points
    np.testing.assert_allclose(hair.points, 2 * raw + [1, 2, 3], rtol=0, atol=1e-15)
    assert hair.color.shape == (50 * 16, 3)
    np.testing.assert_array_equal(hair.color, [[0.1, 0.2, 0.3]] * (50 * 16))


def test_scale_translate_color_on_file_hair(tmp_path, fake_io):
    (tmp_path / "h.tfx").touch()
    text = """[hair]
source = "h.tfx"
alpha = 0.25
width = 2
scale = 2
translate = [1, 2, 3]
color = [1, 0, 0.5]
"""
    hair = load_scene(write(tmp_path, text)).strands
    assert fake_io == [{"path": tmp_path / "h.tfx", "alpha": 0.25, "width": 2.0}]
    # By hand: (0,0,0) (1,0,0) | (0,1,0) (0,1,2), × 2, + (1,2,3).
    np.testing.assert_array_equal(hair.points, [[1, 2, 3], [3, 2, 3], [1, 4, 3], [1, 4, 7]])
    np.testing.assert_array_equal(hair.offsets, [0, 2, 4])
    np.testing.assert_array_equal(hair.color, [[1, 0, 0.5]] * 4)
    np.testing.assert_array_equal(hair.alpha, 0.25)
    np.testing.assert_array_equal(hair.width, 2.0)


def test_file_hair_defaults(tmp_path, fake_io):
    (tmp_path / "h.hair").touch()
    hair = load_scene(write(tmp_path, '[hair]\nsource = "h.hair"\n')).strands
    assert fake_io[0]["alpha"] == 0.5 and fake_io[0]["width"] == 1.0
    np.testing.assert_array_equal(hair.points, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 2]])
    assert hair.color is None


# --------------------------------------------------------------------------- hair paths


def test_relative_hair_path_resolves_against_scene_dir(tmp_path, fake_io, monkeypatch):
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "h.ply").touch()
    scene_path = write(tmp_path, '[hair]\nsource = "../assets/h.ply"\n', "scenes/s.toml")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # the working directory must not matter
    load_scene(scene_path)
    assert fake_io[0]["path"].resolve() == (tmp_path / "assets" / "h.ply").resolve()

    # A relative scene path works too: the scene directory is resolved at load time.
    monkeypatch.chdir(tmp_path)
    load_scene(Path("scenes/s.toml"))
    assert fake_io[1]["path"].resolve() == (tmp_path / "assets" / "h.ply").resolve()


def test_absolute_hair_path(tmp_path, fake_io):
    (tmp_path / "h.tfx").touch()
    elsewhere = tmp_path / "deep" / "er"
    load_scene(write(elsewhere, f'[hair]\nsource = "{(tmp_path / "h.tfx").as_posix()}"\n'))
    assert fake_io[0]["path"] == tmp_path / "h.tfx"


def test_relative_hair_path_with_real_file(tmp_path, monkeypatch):
    real_load_hair()
    scene_dir = tmp_path / "scenes"
    rel = Path(os.path.relpath(PONYTAIL_TAIL, scene_dir)).as_posix()
    assert not Path(rel).is_absolute()
    scene_path = write(scene_dir, f'[hair]\nsource = "{rel}"\nscale = 0.5\n')
    monkeypatch.chdir(REPO)
    hair = load_scene(scene_path).strands
    assert hair.num_strands == 255 and hair.num_points == 255 * 16
    np.testing.assert_array_equal(hair.alpha, 0.5)


def test_missing_hair_file_names_resolved_path(tmp_path):
    path = write(tmp_path, '[hair]\nsource = "sub/missing.hair"\n')
    with pytest.raises(SceneError) as err:
        load_scene(path)
    msg = str(err.value)
    assert msg.startswith(str(path)) and "hair.source" in msg
    assert str(tmp_path / "sub" / "missing.hair") in msg


def test_hair_format_error_is_wrapped(tmp_path, monkeypatch):
    def broken(path, alpha=1.0, width=1.0):
        raise HairFormatError(path, "bad magic bytes")

    module = types.ModuleType("hairjax._io")
    module.load_hair = broken
    monkeypatch.setitem(sys.modules, "hairjax._io", module)
    (tmp_path / "h.hair").touch()
    path = write(tmp_path, '[hair]\nsource = "h.hair"\n')
    with pytest.raises(SceneError) as err:
        load_scene(path)
    msg = str(err.value)
    assert msg.startswith(str(path)) and "hair.source" in msg
    assert "bad magic bytes" in msg and str(tmp_path / "h.hair") in msg
    assert isinstance(err.value.__cause__, HairFormatError)


# --------------------------------------------------------------------------- errors

# (id, TOML text, fragments the message must contain besides the file path)
ERROR_CASES = [
    # structure
    ("unknown-table", HAIR + "[hairs]\nx = 1\n", ["'hairs'", "allowed tables"]),
    ("unknown-top-key", "foo = 1\n" + HAIR, ["'foo'", "allowed tables"]),
    ("unknown-key", HAIR + "[camera]\nfox = 40\n", ["camera.fox", "allowed keys", "fov"]),
    ("unknown-hair-key", HAIR + "length_jitter = 0.1\n", ["hair.length_jitter"]),
    ("table-not-table", "camera = 3\n" + HAIR, ["camera must be a table ([camera]), got 3"]),
    ("name-type", "name = 3\n" + HAIR, ["name must be a non-empty string", "3"]),
    ("missing-hair", "[camera]\nfov = 40\n", ["hair.source is required", "'furball'"]),
    ("missing-source", "[hair]\nstrands = 5\n", ["hair.source is required"]),
    # [hair]
    ("source-type", "[hair]\nsource = 3\n", ["hair.source must be a non-empty string"]),
    (
        "source-unknown",
        '[hair]\nsource = "furbal"\n',
        [
            "hair.source must be 'furball', 'scalp', 'combed', or a path to a "
            ".hair/.tfx/.ply/.data/.usd/.usda/.usdc/.usdz file",
            "'furbal'",
        ],
    ),
    ("source-suffix", '[hair]\nsource = "head.obj"\n', ["hair.source must be", ".tfx"]),
    ("missing-file", '[hair]\nsource = "nope.tfx"\n', ["hair.source file not found", "nope.tfx"]),
    (
        "strands-string",
        '[hair]\nsource = "furball"\nstrands = "many"\n',
        ["hair.strands must be an integer", "'many' (string)"],
    ),
    (
        "strands-bool",
        '[hair]\nsource = "furball"\nstrands = true\n',
        ["hair.strands must be an integer", "true (boolean)"],
    ),
    (
        "strands-float",
        '[hair]\nsource = "furball"\nstrands = 50.0\n',
        ["hair.strands must be an integer", "50.0"],
    ),
    (
        "strands-zero",
        '[hair]\nsource = "furball"\nstrands = 0\n',
        ["hair.strands must be an integer >= 1, got 0"],
    ),
    ("points-one", HAIR + "points = 1\n", ["hair.points must be an integer >= 2, got 1"]),
    ("seed-negative", HAIR + "seed = -1\n", ["hair.seed must be an integer >= 0, got -1"]),
    ("length-zero", HAIR + "length = 0\n", ["hair.length must be > 0, got 0"]),
    ("width-negative", HAIR + "width = -1\n", ["hair.width must be > 0, got -1"]),
    ("width-string", HAIR + 'width = "wide"\n', ["hair.width must be a finite number", "'wide' (string)"]),
    ("width-nan", HAIR + "width = nan\n", ["hair.width must be a finite number"]),
    ("width-inf", HAIR + "width = inf\n", ["hair.width must be a finite number"]),
    ("alpha-zero", HAIR + "alpha = 0\n", ["hair.alpha must be in (0, 1], got 0"]),
    ("alpha-big", HAIR + "alpha = 1.5\n", ["hair.alpha must be in (0, 1], got 1.5"]),
    ("scale-zero", HAIR + "scale = 0\n", ["hair.scale must be > 0, got 0"]),
    (
        "translate-short",
        HAIR + "translate = [1, 2]\n",
        ["hair.translate must be an array of 3 finite numbers", "[1, 2] (array)"],
    ),
    (
        "gravity-string",
        HAIR + 'gravity = [0, "down", 0]\n',
        ["hair.gravity must be an array of 3 finite numbers"],
    ),
    ("gravity-bool", HAIR + "gravity = [0, true, 0]\n", ["hair.gravity", "true"]),
    ("color-negative", HAIR + "color = [-0.1, 0, 0]\n", ["hair.color must be an array of 3 numbers >= 0"]),
    ("color-scalar", HAIR + "color = 0.5\n", ["hair.color must be an array of 3 numbers"]),
    (
        "inertia-scalp",
        '[hair]\nsource = "scalp"\ninertia = [0, 0, 0]\n',
        ["hair.inertia applies only to source = 'furball'", "'scalp'"],
    ),
    ("radius-furball", HAIR + "radius = 1\n", ["hair.radius applies only to source = 'scalp'"]),
    ("coverage-furball", HAIR + "coverage = 0.5\n", ["hair.coverage applies only to"]),
    (
        "layers-scalp",
        '[hair]\nsource = "scalp"\nlayers = 2\n',
        ["hair.layers applies only to source = 'combed'"],
    ),
    (
        "gravity-combed",
        '[hair]\nsource = "combed"\ngravity = [0, -1, 0]\n',
        ["hair.gravity applies only to source = 'furball' or 'scalp'", "'combed'"],
    ),
    (
        "layers-zero",
        '[hair]\nsource = "combed"\nlayers = 0\n',
        ["hair.layers must be an integer >= 1, got 0"],
    ),
    (
        "coverage-zero",
        '[hair]\nsource = "scalp"\nstrands = 5\ncoverage = 0\n',
        ["hair.coverage must be in (0, 1], got 0"],
    ),
    (
        "radius-negative",
        '[hair]\nsource = "scalp"\nstrands = 5\nradius = -1\n',
        ["hair.radius must be > 0, got -1"],
    ),
    (
        "procedural-key-on-file",
        '[hair]\nsource = "x.tfx"\nstrands = 5\n',
        ["hair.strands applies only to procedural sources", "'x.tfx'"],
    ),
    # [camera] (ranges are Camera's own checks, wrapped with the path)
    (
        "camera-width-negative",
        HAIR + "[camera]\nwidth = -1\n",
        ["camera.width must be an integer in [1, 16384], got -1"],
    ),
    ("camera-width-float", HAIR + "[camera]\nwidth = 512.0\n", ["camera.width must be an integer", "512.0"]),
    (
        "camera-height-bool",
        HAIR + "[camera]\nheight = true\n",
        ["camera.height must be an integer", "true (boolean)"],
    ),
    ("camera-fov-zero", HAIR + "[camera]\nfov = 0\n", ["camera.fov must be in (0, 180)"]),
    ("camera-fov-string", HAIR + '[camera]\nfov = "wide"\n', ["camera.fov must be a finite number"]),
    (
        "camera-eye-short",
        HAIR + "[camera]\neye = [0, 0]\n",
        ["camera.eye must be an array of 3 finite numbers"],
    ),
    ("camera-eye-target", HAIR + "[camera]\neye = [0, 0, 0]\n", ["camera.eye and camera.target must differ"]),
    ("camera-up-parallel", HAIR + "[camera]\nup = [0, 0, 1]\n", ["camera.up must not be parallel"]),
    ("camera-near-negative", HAIR + "[camera]\nnear = -1\n", ["camera.near must be positive"]),
    (
        "camera-frame-value",
        HAIR + '[camera]\nframe = "manual"\n',
        ["camera.frame must be one of 'auto'", "'manual'"],
    ),
    *(
        (
            f"camera-frame-{key}",
            HAIR + f'[camera]\nframe = "auto"\n{key} = [0, 1, 5]\n',
            [f"camera.frame = 'auto' and camera.{key} exclude each other"],
        )
        for key in ("eye", "target", "up")
    ),
    # [light]
    (
        "light-kind",
        HAIR + '[light]\nkind = "spot"\n',
        ["light.kind must be one of 'directional', 'point'", "'spot'"],
    ),
    (
        "light-direction-zero",
        HAIR + "[light]\ndirection = [0, 0, 0]\n",
        ["light.direction must not have length 0"],
    ),
    (
        "light-position-directional",
        HAIR + "[light]\nposition = [1, 1, 1]\n",
        ["light.position is not allowed for kind = 'directional'", "light.direction"],
    ),
    (
        "light-direction-point",
        HAIR + '[light]\nkind = "point"\nposition = [1, 1, 1]\ndirection = [0, -1, 0]\n',
        ["light.direction is not allowed for kind = 'point'"],
    ),
    (
        "light-point-no-position",
        HAIR + '[light]\nkind = "point"\n',
        ["light.position is required for a point light"],
    ),
    (
        "light-color-short",
        HAIR + "[light]\ncolor = [1, 1]\n",
        ["light.color must be an array of 3 numbers >= 0"],
    ),
    ("light-color-negative", HAIR + "[light]\ncolor = [1, -1, 1]\n", ["light.color"]),
    # [shading]
    (
        "shading-model",
        HAIR + '[shading]\nmodel = "phong"\n',
        [
            "shading.model must be one of 'kajiya-kay', 'kajiya-kay-lookup', 'marschner', "
            "'kajiya-kay-mirror'",
            "'phong'",
        ],
    ),
    (
        "kd-negative",
        HAIR + "[shading]\nkd = -0.1\n",
        ["shading.kd must be a number >= 0 or an array of 3 numbers >= 0, got -0.1"],
    ),
    ("kd-bool", HAIR + "[shading]\nkd = true\n", ["shading.kd", "true (boolean)"]),
    ("ks-short", HAIR + "[shading]\nks = [1, 2]\n", ["shading.ks must be a number >= 0"]),
    ("ks-negative-channel", HAIR + "[shading]\nks = [0.1, -0.2, 0.1]\n", ["shading.ks"]),
    ("shininess-zero", HAIR + "[shading]\nshininess = 0\n", ["shading.shininess must be > 0, got 0"]),
    ("kappa-negative", HAIR + "[shading]\nkappa = -1\n", ["shading.kappa must be >= 0, got -1"]),
    ("ambient-negative", HAIR + "[shading]\nambient = -0.5\n", ["shading.ambient", "-0.5"]),
    # [shadows], [ordering]
    (
        "shadows-method",
        HAIR + '[shadows]\nmethod = "pcf"\n',
        ["shadows.method must be one of 'opacity-maps', 'deep', 'exact', 'none'"],
    ),
    (
        "shadows-resolution-zero",
        HAIR + "[shadows]\nresolution = 0\n",
        ["shadows.resolution must be an integer in [4, 16384], got 0"],
    ),
    ("shadows-maps-zero", HAIR + "[shadows]\nmaps = 0\n", ["shadows.maps must be an integer in"]),
    ("shadows-maps-float", HAIR + "[shadows]\nmaps = 1.5\n", ["shadows.maps must be an integer"]),
    (
        "deep-layers-zero",
        HAIR + '[shadows]\nmethod = "deep"\nlayers = 0\n',
        ["shadows.layers must be an integer in [1, 65536], got 0"],
    ),
    ("deep-layers-float", HAIR + '[shadows]\nmethod = "deep"\nlayers = 2.5\n', ["shadows.layers", "2.5"]),
    (
        "deep-spacing-negative",
        HAIR + '[shadows]\nmethod = "deep"\nlayer_spacing = -0.1\n',
        ["shadows.layer_spacing must be ≥ 0", "got -0.1"],
    ),
    (
        "deep-spacing-string",
        HAIR + '[shadows]\nmethod = "deep"\nlayer_spacing = "a"\n',
        ["shadows.layer_spacing"],
    ),
    (
        "deep-lookup",
        HAIR + '[shadows]\nmethod = "deep"\nlookup = "nearest"\n',
        ["shadows.lookup must be one of 'layer', 'depth', got 'nearest'"],
    ),
    ("deep-lookup-number", HAIR + '[shadows]\nmethod = "deep"\nlookup = 2\n', ["shadows.lookup"]),
    (
        "maps-lookup",
        HAIR + '[shadows]\nmethod = "opacity-maps"\nlookup = "depth"\n',
        ["shadows.lookup is not a key of method = 'opacity-maps'"],
    ),
    (
        "deep-maps",
        HAIR + '[shadows]\nmethod = "deep"\nmaps = 8\n',
        ["shadows.maps is not a key of method = 'deep'"],
    ),
    (
        "maps-layers",
        HAIR + '[shadows]\nmethod = "opacity-maps"\nlayers = 8\n',
        ["shadows.layers is not a key of method = 'opacity-maps'"],
    ),
    ("width-units", HAIR + 'width_units = "mm"\n', ["hair.width_units must be one of 'pixels', 'world'"]),
    (
        "ordering-method",
        HAIR + '[ordering]\nmethod = "sorted"\n',
        ["ordering.method must be one of 'bins', 'exact', 'none'"],
    ),
    ("ordering-bins-zero", HAIR + "[ordering]\nbins = 0\n", ["ordering.bins must be an integer"]),
    ("ordering-bins-bool", HAIR + "[ordering]\nbins = false\n", ["ordering.bins", "false"]),
    # [occluder], [background]
    ("occluder-kind", HAIR + '[occluder]\nkind = "cube"\n', ["occluder.kind must be one of 'sphere'"]),
    ("occluder-radius", HAIR + "[occluder]\nradius = 0\n", ["occluder.radius must be > 0, got 0"]),
    ("occluder-center", HAIR + "[occluder]\ncenter = [0, 0]\n", ["occluder.center"]),
    (
        "occluder-color",
        HAIR + '[occluder]\ncolor = "red"\n',
        ["occluder.color must be an array of 3 numbers >= 0", "'red' (string)"],
    ),
    ("background-long", HAIR + "[background]\ncolor = [0, 0, 0, 1]\n", ["background.color"]),
    ("background-key", HAIR + "[background]\nalpha = 1\n", ["background.alpha", "color"]),
]


@pytest.mark.parametrize("text, fragments", [c[1:] for c in ERROR_CASES], ids=[c[0] for c in ERROR_CASES])
def test_error_names_key_and_file(tmp_path, text, fragments):
    path = write(tmp_path, text)
    with pytest.raises(SceneError) as err:
        load_scene(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: ") and "\n" not in msg, msg
    for fragment in fragments:
        assert fragment in msg, (fragment, msg)


@pytest.mark.parametrize(
    "content, fragment",
    [
        (b"[hair\nsource = 'furball'\n", "invalid TOML"),
        (b"[hair]\nsource = 'furball'\nsource = 'scalp'\n", "invalid TOML"),
        (b"[hair]\nsource = \xff\n", "not valid UTF-8"),
    ],
    ids=["syntax", "duplicate-key", "not-utf8"],
)
def test_unparsable_file(tmp_path, content, fragment):
    path = tmp_path / "broken.toml"
    path.write_bytes(content)
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert str(err.value).startswith(f"{path}: ") and fragment in str(err.value)


def test_unreadable_file(tmp_path):
    for path in (tmp_path / "absent.toml", tmp_path):  # missing; a directory
        with pytest.raises(SceneError) as err:
            load_scene(path)
        assert str(err.value).startswith(f"{path}: cannot read scene file")


def test_scene_from_dict_without_a_file(tmp_path):
    data = {"hair": {"source": "furball", "strands": 3}, "camera": {"width": 32, "height": 32}}
    scene = scene_from_dict(data, tmp_path, "inline")
    assert scene.name == "inline" and scene.strands.num_strands == 3
    assert (scene.camera.width, scene.camera.height) == (32, 32)
    with pytest.raises(SceneError, match=r"^inline: hair\.strands must be an integer >= 1"):
        scene_from_dict({"hair": {"source": "furball", "strands": 0}}, tmp_path, "inline")


# --------------------------------------------------------------------------- docs

DOCS = REPO / "docs" / "scenes.md"


def test_docs_list_exactly_the_keys_of_each_table():
    from hairjax._scene._file import TOP_LEVEL_KEYS, scene_tables

    sections = {}
    for chunk in DOCS.read_text(encoding="utf-8").split("\n## ")[1:]:
        heading, _, body = chunk.partition("\n")
        keys = [line.split("|")[1].strip().strip("`") for line in body.splitlines() if line.startswith("| `")]
        sections[heading.strip()] = keys
    for table, keys in scene_tables().items():
        documented = sections[f"`[{table}]`"]
        assert len(documented) == len(set(documented)), table  # each key documented once
        assert set(documented) == set(keys), table
    assert sections["Top level"] == list(TOP_LEVEL_KEYS)


def test_docs_show_the_packaged_default_scene():
    text = DOCS.read_text(encoding="utf-8")
    start = text.index("```toml\n# The built-in default scene") + len("```toml\n")
    block = text[start : text.index("```", start)]
    assert block == default_scene_path().read_text(encoding="utf-8")


def test_width_units_load(tmp_path):
    scene = load_scene(write(tmp_path, HAIR + 'width = 0.01\nwidth_units = "world"\n'))
    assert scene.strands.width_units == "world"
    np.testing.assert_array_equal(scene.strands.width, 0.01)
    assert load_scene(write(tmp_path, HAIR)).strands.width_units == "pixels"  # the default
