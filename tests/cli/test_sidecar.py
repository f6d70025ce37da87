"""`render`'s sidecar records the device it ran on: JAX's platform and device kind, where
the set-up ran, and for `--backend gl` the GL renderer string. There is no GPU here, so
the test checks that the fields are there, are strings, and say what JAX and GL say."""

from __future__ import annotations

import json

import jax

from hairjax.cli import main

SMALL_SCENE = """
[hair]
source = "furball"
strands = 40
points = 4
[camera]
width = 24
height = 16
[shadows]
maps = 4
resolution = 16
"""


def _record(tmp_path, *options) -> dict:
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL_SCENE)
    assert main(["render", str(scene), "-o", str(tmp_path / "r.exr"), "-q", *options]) == 0
    return json.loads((tmp_path / "r.json").read_text())


def test_the_jax_device_is_recorded(tmp_path):
    device = _record(tmp_path)["device"]
    # No GL fields: the JAX renderer opens no GL context just to name it.
    assert set(device) == {"jax_platform", "jax_device_kind", "jax_devices", "setup"}
    assert all(isinstance(value, str) and value for value in device.values()), device
    assert device["jax_platform"] == jax.default_backend()
    assert device["jax_device_kind"] == jax.devices()[0].device_kind
    assert device["jax_devices"].split(", ") == [str(d) for d in jax.devices()]
    # On a CPU the set-up runs on the host unless HAIRJAX_SETUP says otherwise (docs/model.md §5).
    assert device["setup"] == ("host" if jax.default_backend() == "cpu" else "device")


def test_the_setup_placement_follows_hairjax_setup(tmp_path, monkeypatch):
    monkeypatch.setenv("HAIRJAX_SETUP", "device")  # the XLA set-up, which runs on any machine
    assert _record(tmp_path)["device"]["setup"] == "device"


def test_the_gl_renderer_is_recorded(tmp_path, gl):
    device = _record(tmp_path, "--backend", "gl")["device"]
    assert device["gl_renderer"] == gl.info["GL_RENDERER"] and isinstance(device["gl_renderer"], str)
    assert device["gl_version"] == gl.info["GL_VERSION"]
    assert device["jax_platform"] == jax.default_backend()  # JAX is still the host's numerics
