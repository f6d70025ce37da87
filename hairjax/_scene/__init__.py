"""The scene (docs/architecture.md): strands and their tangents, procedural hair, camera,
light, occluder, `Scene`, and the TOML reader. Plain immutable values, validated at
construction; the public names are re-exported by `hairjax/__init__.py`."""
