"""axialdeform: thousands of individually different shapes from one base mesh.

The data flow, one module each::

    mesh.py -> axis.py -> params.py (+ variation.py) -> buffers.py -> shaders.py
    -> renderer.py -> image.py

``deform.py`` is the CPU reference of the same maths; ``bake.py`` writes
deformed instances out; ``cli.py`` is the ``axialdeform`` command.
"""

from importlib.metadata import PackageNotFoundError, version as _version

from .axis import ControlAxis
from .bake import bake
from .camera import Camera, frame_instances, instance_bounds
from .context import Offscreen, create_context
from .deform import deform, rotation_matrices
from .ground import GroundPlane
from .errors import (
    AxialDeformError,
    ContextError,
    GltfError,
    MeshError,
    MeshMismatchError,
    ParamError,
    ParamFileError,
    ResidualError,
    ShaderError,
    TopologyError,
)
from .image import render_image, save_png
from .mesh import BUNDLED_MESHES, BaseMesh, bundled_mesh_path, load_mesh
from .params import FIELDS, as_params, make_params, read_param_file, read_params, write_params
from .renderer import MODES, AxialRenderer
from .shaders import assemble, assemble_text, build_program, deformation_glsl
from .variation import random_params

try:
    __version__ = _version("axialdeform")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = [
    "AxialDeformError", "AxialRenderer", "BaseMesh", "BUNDLED_MESHES", "Camera", "ContextError", "ControlAxis",
    "FIELDS", "GroundPlane", "MODES", "MeshError", "MeshMismatchError", "Offscreen", "ParamError", "ParamFileError", "ShaderError", "GltfError", "ResidualError", "TopologyError",
    "as_params", "assemble", "assemble_text", "bake", "build_program", "bundled_mesh_path", "create_context", "deform",
    "deformation_glsl", "frame_instances", "instance_bounds", "load_mesh", "make_params", "random_params",
    "read_param_file", "read_params", "render_image", "rotation_matrices", "save_png", "write_params",
]
