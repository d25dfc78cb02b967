"""axialdeform: thousands of individually different shapes from one base mesh.

The data flow -- mesh -> axis -> record -> buffers -> shader -> image -- in
three layers, one folder each (an upper layer may import a lower one, never
the reverse; ``tests/app/test_layers.py`` reads the imports and enforces it):

* ``core/`` -- pure numpy, no GL: meshes, the control axis, the instance
  record, parameters and their files, the CPU reference, scenes, the look;
* ``gl/``   -- moderngl: context, shaders (``glsl/``), buffers, renderer,
  camera, pictures;
* the application -- ``cli/`` (the ``axialdeform`` command), ``bench/``,
  ``viewer.py``, ``web/`` (the WebGL page) and ``widget.py`` (the notebook widget).

This top level is the product, 25 names; every other public name has one
home in :mod:`axialdeform.core` or :mod:`axialdeform.gl`, whose ``__all__``
lists it.  Names that used to be here still work for one release, with a
DeprecationWarning naming their new home.
"""

from .core.errors import AxialDeformError  # noqa: F401 - the error base, a top-level name (__all__)
from .core.lazy import attach

# every other name is imported on first use (PEP 562): ``import axialdeform`` loads
# no GL, mesh or image library.  (bake, deform and scatter share their names with
# modules of core/ and gl/, not of this package: importing those never rebinds them.)
_NAMES = {
    "bake": "gl.bake", "deform": "core.deform", "scatter": "core.scatter",
    # mesh -> axis
    "load_mesh": "core.io.mesh", "BaseMesh": "core.mesh",
    # the record and its variation
    "Instances": "core.record", "random_params": "core.variation", "Variation": "core.variation",
    # files
    "read_params": "core.io.params", "write_params": "core.io.params",
    # scene, look, camera, wind
    "Scene": "core.scene", "Look": "core.look", "Wind": "core.wind", "RenderOptions": "core.options",
    "Camera": "core.camera", "frame_instances": "core.camera",
    # drawing
    "create_context": "gl.context", "Offscreen": "gl.context", "AxialRenderer": "gl.renderer",
    "render_image": "gl.image", "save_png": "core.io.image", "deformation_glsl": "gl.shaders",
    # out again
    "export_glb": "core.io.gltf", "fit_params": "core.fit",
    # scenery by example
    "learn_layer": "core.io.example",
}

#: the old top-level names and their homes now
_DEPRECATED = {name: f"axialdeform.{home}.{name}" for home, names in {
    "core": ("ArgumentError", "ContextError", "GltfError", "MeshError", "MeshMismatchError", "ParamError",
             "ParamFileError", "ResidualError", "SceneError", "ScatterError", "ShaderError", "TooFewError",
             "TopologyError", "ControlAxis", "Material", "Part", "AssetWarning", "BUNDLED_MESHES",
             "bundled_mesh_path", "FIELDS", "EXTENDED_FIELDS", "as_params", "make_params", "read_param_file",
             "extend_params", "is_extended", "instance_bounds", "scene_box", "load_surface", "load_scene",
             "wind_offsets", "apply_wind", "rotation_matrices", "OrbitCamera"),
    "gl": ("GroundPlane", "ShadowMap", "read_pixels", "MODES", "assemble", "assemble_text",
           "build_program", "SceneRenderer"),
}.items() for name in names}

_getattr, __dir__, _lazy_all = attach(__name__, _NAMES, _DEPRECATED)

__all__ = sorted(["AxialDeformError", *_lazy_all])


def __getattr__(name: str):
    if name == "__version__":  # read on first use: importlib.metadata is not cheap
        from importlib.metadata import PackageNotFoundError, version

        try:
            value = version("axialdeform")
        except PackageNotFoundError:  # a source tree that was never installed
            value = "0+unknown"
        globals()[name] = value
        return value
    return _getattr(name)
