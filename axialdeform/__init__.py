"""axialdeform: thousands of individually different shapes from one base mesh.

The data flow, one module each::

    mesh.py -> axis.py -> params.py (+ variation.py) -> buffers.py -> shaders.py
    -> renderer.py -> image.py

``deform.py`` is the CPU reference of the same maths; ``bake.py`` writes
deformed instances out; ``cli.py`` is the ``axialdeform`` command.
"""

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

# These two share their names with their modules (axialdeform.bake,
# axialdeform.deform), so they are bound now: importing the submodule later
# must not replace the function.
from .bake import bake
from .deform import deform, rotation_matrices

# The other public names and the module each lives in.  They are imported on first
# use (PEP 562), so ``import axialdeform`` -- and every CLI start and every
# benchmark child -- pays only for what it touches.
_LAZY = {
    "ControlAxis": "axis",
    "Camera": "camera", "frame_instances": "camera", "instance_bounds": "camera",
    "Offscreen": "context", "create_context": "context",
    "GroundPlane": "ground",
    "render_image": "image", "save_png": "image",
    "BUNDLED_MESHES": "mesh", "BaseMesh": "mesh", "bundled_mesh_path": "mesh", "load_mesh": "mesh",
    "FIELDS": "params", "as_params": "params", "make_params": "params", "read_param_file": "params",
    "read_params": "params", "write_params": "params",
    "MODES": "renderer", "AxialRenderer": "renderer",
    "assemble": "shaders", "assemble_text": "shaders", "build_program": "shaders", "deformation_glsl": "shaders",
    "random_params": "variation",
}


def __getattr__(name: str):
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            value = version("axialdeform")
        except PackageNotFoundError:  # running from a source tree that was never installed
            value = "0+unknown"
    elif name in _LAZY:
        from importlib import import_module

        value = getattr(import_module(f".{_LAZY[name]}", __name__), name)
    else:
        from importlib import import_module
        from importlib.util import find_spec

        if name.startswith("_") or find_spec(f"{__name__}.{name}") is None:
            raise AttributeError(f"module 'axialdeform' has no attribute {name!r}")
        value = import_module(f".{name}", __name__)  # a submodule: axialdeform.params, ...
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | {"__version__"})


__all__ = [
    "AxialDeformError", "AxialRenderer", "BaseMesh", "BUNDLED_MESHES", "Camera", "ContextError", "ControlAxis",
    "FIELDS", "GroundPlane", "MODES", "MeshError", "MeshMismatchError", "Offscreen", "ParamError", "ParamFileError", "ShaderError", "GltfError", "ResidualError", "TopologyError",
    "as_params", "assemble", "assemble_text", "bake", "build_program", "bundled_mesh_path", "create_context", "deform",
    "deformation_glsl", "frame_instances", "instance_bounds", "load_mesh", "make_params", "random_params",
    "read_param_file", "read_params", "render_image", "rotation_matrices", "save_png", "write_params",
]
