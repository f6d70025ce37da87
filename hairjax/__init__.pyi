"""hairjax: differentiable hair shading in JAX (the public names; `__init__.py` loads them lazily).

Strands are drawn as antialiased, alpha-blended ribbons in a bin-sorted visibility order,
self-shadowed with opacity shadow maps and shaded with Kajiya-Kay or Scheuermann's two
shifted highlights. The model is written down once, in docs/model.md; how the package is
laid out, and how to add a shading model, shadow method or ordering, in
docs/architecture.md.
"""

from . import experimental as experimental
from . import extend as extend
from ._animate import load_animation as load_animation
from ._animate import write_frames as write_frames
from ._distill import Distillation as Distillation
from ._distill import distill as distill
from ._errors import EmptyViewWarning as EmptyViewWarning
from ._errors import HairFormatError as HairFormatError
from ._errors import MissingDependency as MissingDependency
from ._errors import SceneError as SceneError
from ._errors import SceneTooLarge as SceneTooLarge
from ._explore import Explorer as Explorer
from ._explore import explore as explore
from ._fit import BFGS as BFGS
from ._fit import FitError as FitError
from ._fit import FitNotConverged as FitNotConverged
from ._fit import FitResult as FitResult
from ._fit import FitStop as FitStop
from ._fit import FitTargets as FitTargets
from ._fit import FitVariables as FitVariables
from ._fit import GaussNewton as GaussNewton
from ._fit import fit as fit
from ._fit import fit_solvers as fit_solvers
from ._fit import fitted_image as fitted_image
from ._geometry._ordering import Ordering as Ordering
from ._geometry._shadows import Shadows as Shadows
from ._geometry_stage._stage import geometry_stage as geometry_stage
from ._io import hair_info as hair_info
from ._io import load_hair as load_hair
from ._io import save_hair as save_hair
from ._io._image import read_image as read_image
from ._io._image import write_image as write_image
from ._reference import reference_image as reference_image
from ._render import render as render
from ._render import render_profiled as render_profiled
from ._scene._file import default_scene_path as default_scene_path
from ._scene._file import load_scene as load_scene
from ._scene._file import scene_for_hair as scene_for_hair
from ._scene._occluder import Occluder as Occluder
from ._scene._procedural import combed as combed
from ._scene._procedural import furball as furball
from ._scene._procedural import scalp as scalp
from ._scene._reference import ReferenceSettings as ReferenceSettings
from ._scene._save import save_scene as save_scene
from ._scene._scene import PatchGeometry as PatchGeometry
from ._scene._scene import Scene as Scene
from ._shading import KajiyaKay as KajiyaKay
from ._shading import KajiyaKayLookup as KajiyaKayLookup
from ._shading import KajiyaKayMirror as KajiyaKayMirror
from ._shading import LightParams as LightParams
from ._shading import Marschner as Marschner
from ._shading import MarschnerParams as MarschnerParams
from ._shading import Scheuermann as Scheuermann
from ._shading import ScheuermannMaps as ScheuermannMaps
from ._shading import ScheuermannParams as ScheuermannParams
from ._shading import ShadingParams as ShadingParams
from ._shading import Streaks as Streaks
from ._shading import shading_stage as shading_stage
from ._supersample import supersample as supersample
from ._values._camera import Camera as Camera
from ._values._light import Light as Light
from ._values._strands import Strands as Strands
from ._views import render_views as render_views

__version__: str
