"""Every reader and writer of the core, in one package (in the manner of
trimesh's ``exchange/``): bytes in and out go through here, reads through the
bounded reader (:mod:`.safeio`), writes atomically (:mod:`.atomic`).

* :mod:`.mesh` -- mesh files (OBJ, PLY, STL, OFF, glTF/GLB) via trimesh;
* :mod:`.resolver` -- what a mesh file references (textures, buffers);
* :mod:`.gltf` -- glTF accessors and the GLBs this library writes;
* :mod:`.params` -- text and binary parameter files, quantization;
* :mod:`.scene` -- scene files (TOML);
* :mod:`.bake` -- baked instances as ``.npz`` and mesh folders;
* :mod:`.image` -- PNG pictures;
* :mod:`.safeio`, :mod:`.atomic` -- bounded reads, safe outputs, atomic writes.
"""

from ..lazy import attach

_NAMES = {
    "load_mesh": "mesh", "bundled_mesh_path": "mesh", "BUNDLED_MESHES": "mesh", "MESH_SUFFIXES": "mesh",
    "read_params": "params", "write_params": "params", "read_param_file": "params", "ParamFile": "params",
    "parse_text": "params", "format_text": "params", "encode_binary": "params", "decode_binary": "params",
    "quantize_params": "params", "dequantize_params": "params",
    "export_glb": "gltf", "export_instanced": "gltf", "export_baked": "gltf", "export_scene": "gltf",
    "read_instanced_glb": "gltf", "parse_scene": "scene", "write_mesh_folder": "bake", "write_npz": "bake",
    "save_png": "image", "read_regular": "safeio", "atomic_path": "atomic",
}

__getattr__, __dir__, __all__ = attach(__name__, _NAMES)
