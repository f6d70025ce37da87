"""The geometry stage of a scene (docs/model.md §2–§7; docs/architecture.md, "Layers"):
the capacity estimate (`_estimate.py`), the set-up (`_setup.py`: projection, fragments
and their grouping in `_fragments.py`, occluder and shadows in `_lighting.py`, from the
kernels and methods of `hairjax._geometry`) and the JAX
stage (`_stage.py`). It reads a `Scene`, so it sits above the scene package, which itself
reads the orderings, shadow methods and shading models it is configured with."""
