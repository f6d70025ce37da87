"""The geometry stage (docs/model.md §2–§7, §13; docs/architecture.md): projection, the
visibility orderings (`_ordering/`, one module each), the ribbons' fragments, the shadow
methods (`_shadows/`, one module each), the occluder's tests, the set-up (`_setup.py`:
NumPy, and two loops compiled by numba in `_raster.py` and `_group.py`, or on an
accelerator the same raster and grouping as XLA programs in `_device_raster.py`; the
fragment arrays' buckets in `_capacity.py`) and the JAX stage (`_stage.py`). Geometry,
camera and light only: no shading parameter enters here."""
