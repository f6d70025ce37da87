"""hairjax: differentiable hair shading in JAX.

Strands are drawn as antialiased, alpha-blended ribbons in a bin-sorted visibility order,
self-shadowed with opacity shadow maps and shaded with Kajiya-Kay. The model is written
down once, in docs/model.md.
"""

from importlib.metadata import PackageNotFoundError, version

from ._animate import load_animation as load_animation
from ._animate import write_frames as write_frames
from ._band import renderer_band as renderer_band
from ._errors import HairFormatError as HairFormatError
from ._errors import SceneError as SceneError
from ._fit import FitError as FitError
from ._fit import FitResult as FitResult
from ._fit import fit as fit
from ._image import read_image as read_image
from ._image import write_image as write_image
from ._io import hair_info as hair_info
from ._io import load_hair as load_hair
from ._render import (
    Geometry as Geometry,
)
from ._render import (
    geometry_stage as geometry_stage,
)
from ._render import (
    prepare as prepare,
)
from ._render import (
    render as render,
)
from ._render import (
    render_profiled as render_profiled,
)
from ._render import (
    shading_stage as shading_stage,
)
from ._scene import (
    Camera as Camera,
)
from ._scene import (
    Light as Light,
)
from ._scene import (
    Occluder as Occluder,
)
from ._scene import (
    Ordering as Ordering,
)
from ._scene import (
    Scene as Scene,
)
from ._scene import (
    Shadows as Shadows,
)
from ._scene_file import default_scene_path as default_scene_path
from ._scene_file import load_scene as load_scene
from ._scheuermann import ScheuermannMaps as ScheuermannMaps
from ._scheuermann import ScheuermannParams as ScheuermannParams
from ._shading import ShadingParams as ShadingParams
from ._shading import kajiya_kay as kajiya_kay
from ._sources import furball as furball
from ._sources import scalp as scalp
from ._strands import Strands as Strands
from ._streaks import Streaks as Streaks
from ._supersample import supersample as supersample

# isort: split
# Used by experiments/ and notebooks/
from ._ordering import draw_order as draw_order
from ._ordering import hair_centre as hair_centre
from ._ordering import segment_depth as segment_depth
from ._ordering import static_order as static_order
from ._projection import camera_view as camera_view
from ._render import forget as forget
from ._render import visibility_order as visibility_order

try:
    __version__ = version("hairjax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"
