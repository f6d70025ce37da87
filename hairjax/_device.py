"""What a render ran on: JAX's devices and where the geometry set-up ran, as strings for
the records that `hairjax render` (its sidecar) and `hairjax bench` (its header) keep.

On a machine with a GPU and JAX's CUDA build (`pip install -e '.[cuda]'`, README "On a
GPU"), JAX's default device is the GPU, and the set-up's raster and grouping run there
too by default (`default_placement`: unless `HAIRJAX_SETUP=host`; docs/architecture.md,
"Batched views and devices").
"""

from __future__ import annotations

import jax

from ._geometry._placement import default_placement

__all__ = ["device_record"]


def device_record() -> dict[str, str]:
    """JAX's default platform (`cpu`, `gpu`, `tpu`), its first device's kind (e.g. `cpu`,
    `NVIDIA H100 80GB HBM3`), every device's name, and where the set-up runs (`host` or
    `device`, docs/model.md §5: the default placement, `default_placement`). Every value is
    a string."""
    devices = jax.devices()
    return {
        "jax_platform": str(jax.default_backend()),
        "jax_device_kind": str(devices[0].device_kind),
        "jax_devices": ", ".join(str(d) for d in devices),
        "setup": default_placement(),
    }
