"""The core layer: pure numpy, no GL.  The public names below have their home
here; each lives in the module named beside it (imported on first use).

Modules, in the order of the data flow: ``mesh`` (load, parts, materials),
``axis`` (the control axis), ``record`` (THE instance record), ``params``
(parameter arrays and files), ``variation``, ``scatter`` and ``wind`` (making
instances), ``deform`` and ``transforms`` (the CPU reference), ``bounds``,
``lod``, ``look``, ``options``, ``scene``, ``bake``, ``fit``; plumbing: ``errors``,
``arrays``, ``lazy``.  Every file read and written: the :mod:`.io` package.
"""

from .lazy import attach

_NAMES = {
    # errors: one family
    **{n: "errors" for n in ("AxialDeformError", "ArgumentError", "ContextError", "GltfError", "MeshError",
                             "MeshMismatchError", "ParamError", "ParamFileError", "ResidualError", "SceneError",
                             "ScatterError", "ShaderError", "TooFewError", "TopologyError")},
    # mesh, axis, appearance
    "BaseMesh": "mesh", "load_mesh": "io.mesh", "BUNDLED_MESHES": "io.mesh", "bundled_mesh_path": "io.mesh",
    "ControlAxis": "axis", "Material": "material", "Part": "material", "AssetWarning": "material",
    # the record and parameters
    "RECORD": "record", "Field": "record", "Instances": "record",
    "FIELDS": "record", "EXTENDED_FIELDS": "record",
    "as_params": "params", "make_params": "params", "extend_params": "params", "is_extended": "params",
    "tint_params": "params", "is_tinted": "params",
    "read_params": "io.params", "read_param_file": "io.params", "write_params": "io.params", "ParamFile": "io.params",
    "random_params": "variation", "Variation": "variation", "load_surface": "surface",
    "Placement": "scatter",
    "Wind": "wind", "wind_offsets": "wind", "apply_wind": "wind",
    # the CPU reference, bounds
    "rotation_matrices": "transforms", "instance_bounds": "bounds", "scene_box": "bounds",
    # scene and look
    "Scene": "scene", "Layer": "scene", "load_scene": "scene", "Look": "look", "DEFAULT_LOOK": "look",
    "RenderOptions": "options", "Camera": "camera", "CameraSpec": "camera", "OrbitCamera": "camera",
    "frame_instances": "camera",
    # out again
    "export_glb": "io.gltf", "export_instanced": "io.gltf", "export_baked": "io.gltf", "fit_params": "fit",
    "save_png": "io.image",
}

__getattr__, __dir__, __all__ = attach(__name__, _NAMES)
