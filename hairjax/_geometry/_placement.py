"""Where the geometry set-up's raster and grouping run: a value passed down, not global
state (docs/model.md §5, docs/architecture.md "One set-up, two kernels").

There is one set-up, with two kernels for the raster and the grouping by pixel:

- `"host"`: loops compiled by numba (`_raster`, `_group`). On the CPU they beat XLA's
  programs by 1.2–6× (BENCHMARKS.md, "The device-resident set-up on this CPU");
- `"device"`: XLA programs on JAX's default device (`_device_raster`), the primitives an
  accelerator is fast at.

Tests hold both to the same fragments. Every function of the set-up takes the placement as
an argument and the per-scene cache keys on it, so a scene set up on one is never handed
back for the other. `HAIRJAX_SETUP` (auto, host or device) gives only the default: what a
call that names no placement gets, read at that call; nothing here writes it.
"""

from __future__ import annotations

import os
from typing import Literal, cast

import jax

__all__ = ["Placement", "PLACEMENTS", "PLACEMENT_VARIABLE", "default_placement", "placement_of"]

Placement = Literal["host", "device"]
PLACEMENTS: tuple[Placement, ...] = ("host", "device")
PLACEMENT_VARIABLE = "HAIRJAX_SETUP"  # the environment variable of the default: auto, host or device


def default_placement() -> Placement:
    """The placement of a call that names none: `HAIRJAX_SETUP`'s, and for `auto` (or
    unset) the device unless JAX's default device is the CPU."""
    choice = os.environ.get(PLACEMENT_VARIABLE, "auto")
    if choice == "auto":
        return "host" if jax.default_backend() == "cpu" else "device"
    if choice not in PLACEMENTS:
        raise ValueError(f"{PLACEMENT_VARIABLE} must be auto, host or device, got {choice!r}")
    return cast(Placement, choice)


def placement_of(placement: str | None) -> Placement:
    """`placement` checked ("host" or "device"), or the default for None."""
    if placement is None:
        return default_placement()
    if placement not in PLACEMENTS:
        raise ValueError(f"the set-up's placement must be 'host' or 'device', got {placement!r}")
    return cast(Placement, placement)
