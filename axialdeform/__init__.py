"""axialdeform: thousands of individually different shapes from one base mesh.

Three layers, one folder each (an upper layer may import a lower one, never
the reverse; ``tests/test_layers.py`` reads the imports and enforces it):

* ``core/`` -- pure numpy, no GL: mesh -> axis -> params (+ variation) ->
  deform (the CPU reference), fit, bake, export;
* ``gl/``   -- moderngl: context, shaders (``glsl/``), buffers, renderer,
  ground, camera, image;
* the application -- ``cli/`` (the ``axialdeform`` command), ``bench/``,
  ``viewer.py``, ``web/`` (the WebGL page) and ``widget.py`` (the notebook widget).
"""

from .core.errors import (
    ArgumentError,
    AxialDeformError,
    ContextError,
    GltfError,
    MeshError,
    MeshMismatchError,
    ParamError,
    ParamFileError,
    ResidualError,
    SceneError,
    ScatterError,
    ShaderError,
    TooFewError,
    TopologyError,
)

# These two share their names with their modules (axialdeform.gl.bake,
# axialdeform.core.deform), so they are bound now: importing the submodule later
# must not replace the function.
from .gl.bake import bake
from .core.deform import deform
from .core.transforms import rotation_matrices

# The other public names and the module each lives in.  They are imported on first
# use (PEP 562), so ``import axialdeform`` -- and every CLI start and every
# benchmark child -- pays only for what it touches.
_LAZY = {
    "ControlAxis": "core.axis", "Look": "core.look", "Instances": "core.record",
    "Camera": "gl.camera", "OrbitCamera": "gl.camera", "frame_instances": "gl.camera", "instance_bounds": "core.bounds", "scene_box": "core.bounds",
    "Offscreen": "gl.context", "create_context": "gl.context", "read_pixels": "gl.context",
    "GroundPlane": "gl.ground", "ShadowMap": "gl.shadow",
    "Material": "core.material", "Part": "core.material", "AssetWarning": "core.material",
    "render_image": "gl.image", "save_png": "gl.image",
    "BUNDLED_MESHES": "core.mesh", "BaseMesh": "core.mesh", "bundled_mesh_path": "core.mesh", "load_mesh": "core.mesh",
    "FIELDS": "core.params", "as_params": "core.params", "make_params": "core.params", "read_param_file": "core.params",
    "read_params": "core.params", "write_params": "core.params",
    "MODES": "gl.renderer", "AxialRenderer": "gl.renderer",
    "assemble": "gl.shaders", "assemble_text": "gl.shaders", "build_program": "gl.shaders", "deformation_glsl": "gl.shaders",
    "random_params": "core.variation",
    "scatter": "core.scatter", "load_surface": "core.scatter",
    "load_scene": "core.scene", "SceneRenderer": "gl.scene", "render_scene": "gl.scene",
    "EXTENDED_FIELDS": "core.params", "extend_params": "core.params", "is_extended": "core.params",
    "Wind": "core.wind", "wind_offsets": "core.wind", "apply_wind": "core.wind",
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
        value = import_module(f".{name}", __name__)  # a submodule: axialdeform.core.params, ...
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY) | {"__version__"})


__all__ = [
    "ArgumentError", "AxialDeformError", "AxialRenderer", "BaseMesh", "BUNDLED_MESHES", "Camera", "ContextError", "ControlAxis",
    "FIELDS", "GroundPlane", "ShadowMap", "Material", "Part", "AssetWarning", "MODES", "OrbitCamera", "MeshError", "MeshMismatchError", "Offscreen", "ParamError", "ParamFileError", "ScatterError", "SceneError", "ShaderError", "TooFewError", "GltfError", "ResidualError", "TopologyError",
    "as_params", "assemble", "assemble_text", "bake", "build_program", "bundled_mesh_path", "create_context", "deform",
    "deformation_glsl", "frame_instances", "instance_bounds",
    "scene_box", "load_mesh", "make_params", "random_params",
    "read_param_file", "read_params", "read_pixels", "render_image", "rotation_matrices", "save_png", "scatter", "load_surface", "load_scene", "SceneRenderer", "render_scene", "write_params",
    "EXTENDED_FIELDS", "extend_params", "is_extended", "Wind", "wind_offsets", "apply_wind",
]
