"""The geometry's kernels and methods (docs/model.md §2–§7, §13; docs/architecture.md,
"Layers"): projection, the visibility orderings (`_ordering/`, one module each), the
ribbons' fragments, the shadow methods (`_shadows/`, one module each), the occluder's
tests, and the set-up's two kernels: NumPy and loops compiled by numba in `_raster.py`
(`_raster_loop.py`) and `_group.py`, or on an accelerator the same raster and grouping as
XLA programs in `_device_raster.py`, both covering pixels by one formula (`_coverage.py`);
the fragment arrays' buckets in `_capacity.py`. The stage that runs
them for a scene is `hairjax._geometry_stage`. Geometry, camera and light only: no shading
parameter enters here."""
