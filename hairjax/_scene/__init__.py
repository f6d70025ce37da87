"""The scene (docs/architecture.md, "Layers"): `Scene`, procedural hair, the occluder, and
the TOML reader and writer. Plain immutable values, validated at construction; the public
names are re-exported by `hairjax/__init__.py`. Strands, camera and light are in
`hairjax._values`."""
