"""What the reference can render: Mitsuba itself, and the scene features it refuses.

Mitsuba is an optional extra (`pip install 'hairjax[reference]'`); `import_mitsuba` says so
in one line when it is missing. `check_supported` refuses, one line each, what a scene can
hold but a fibre cannot show (docs/reference.md, "What is refused").
"""

from __future__ import annotations

from types import ModuleType

from .._errors import MissingDependency, SceneError
from .._scene._scene import Scene

__all__ = ["import_mitsuba", "check_supported", "MITSUBA_VARIANT", "INSTALL_HINT"]

# No derivative is needed from Mitsuba, and `scalar_rgb` needs no LLVM (the `llvm_*`
# variants abort with some system LLVMs); at the image sizes of a fit it is as fast.
MITSUBA_VARIANT = "scalar_rgb"
INSTALL_HINT = "pip install 'hairjax[reference]'"


def import_mitsuba() -> ModuleType:
    """`mitsuba`, with its `scalar_rgb` variant available; `MissingDependency` otherwise."""
    try:
        import mitsuba
    except ImportError as err:
        raise MissingDependency(
            f"the physically based reference needs Mitsuba 3, which is not installed ({err.msg}): "
            f"{INSTALL_HINT}"
        ) from err
    if MITSUBA_VARIANT not in mitsuba.variants():
        raise MissingDependency(
            f"this Mitsuba has no {MITSUBA_VARIANT!r} variant (it has {', '.join(mitsuba.variants())}): "
            f"{INSTALL_HINT}"
        )
    return mitsuba


def check_supported(scene: Scene) -> None:
    """`SceneError` naming the first feature of `scene` that the reference cannot show."""
    if scene.patches is not None:
        raise SceneError(
            f"scene {scene.name!r}: hair.geometry = 'patches' (polygon cards with an alpha texture, "
            "docs/model.md §18) has no fibre counterpart; the reference needs geometry = 'strands'"
        )
    if scene.streaks is not None:
        raise SceneError(
            f"scene {scene.name!r}: [streaks] (wenzel-2002's streak texture, docs/model.md §16) has no "
            "counterpart on a fibre; remove [streaks] to render the reference"
        )
    if scene.camera.offset != (0.0, 0.0):
        raise SceneError(
            f"scene {scene.name!r}: camera.offset {scene.camera.offset} (a sub-pixel shift for "
            "supersampling, docs/model.md §12) is not taken: the reference samples the whole pixel; "
            "use offset (0, 0)"
        )
