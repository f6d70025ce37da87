"""hairjax: differentiable hair shading in JAX.

Strands are drawn as antialiased, alpha-blended ribbons in a bin-sorted visibility order,
self-shadowed with opacity shadow maps and shaded with Kajiya-Kay. The model is written
down once, in docs/model.md.
"""

from importlib.metadata import PackageNotFoundError, version

from ._errors import HairFormatError as HairFormatError, SceneError as SceneError
from ._fit import FitError as FitError, FitResult as FitResult, fit as fit
from ._image import read_image as read_image, write_image as write_image
from ._io import hair_info as hair_info, load_hair as load_hair
from ._render import (
    Geometry as Geometry,
    geometry_stage as geometry_stage,
    prepare as prepare,
    render as render,
    render_profiled as render_profiled,
    shading_stage as shading_stage,
)
from ._scene import (
    Camera as Camera,
    Light as Light,
    Occluder as Occluder,
    Ordering as Ordering,
    Scene as Scene,
    Shadows as Shadows,
)
from ._scene_file import default_scene_path as default_scene_path, load_scene as load_scene
from ._shading import ShadingParams as ShadingParams, kajiya_kay as kajiya_kay
from ._sources import furball as furball, scalp as scalp
from ._strands import Strands as Strands

try:
    __version__ = version("hairjax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"
