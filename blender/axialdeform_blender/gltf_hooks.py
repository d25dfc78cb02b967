"""Blender's glTF exporter writes ``AXIALDEFORM_bend`` for an instance object (its user-extension hooks).

An instance object is not exported as the bent geometry Geometry Nodes make of it (every vertex of
every instance) but as what it is: the base mesh once, on a node with ``EXT_mesh_gpu_instancing``
(each instance's numbers) and ``AXIALDEFORM_bend`` (the axes).  The node's contents are the library's
own writer's (``axialdeform.core.io.gltf``), carried into the exporter's document accessor by
accessor, so a file from File > Export > glTF 2.0 reads in axialdeform and the npm plugin exactly as
one from ``axialdeform export --instanced``.  The base colour travels as the layer's material
(textures do not).
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from .layers import BASE_KEY, LAYER_KEY, UP_TO_Z_UP, is_layer

__all__ = ["glTF2ExportUserExtension"]

#: glTF component type -> the numpy type of its bytes
_DTYPES = {5121: "u1", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}


def _library_node(obj):
    """The library's GLB of this one layer, loaded: (gltf, blob, node)."""
    from axialdeform.core.io.glb import load_glb

    from . import export_layers
    from .read import write_glb

    info = json.loads(obj[LAYER_KEY])
    with tempfile.TemporaryDirectory() as tmp:
        path = write_glb(Path(tmp) / "layer.glb", export_layers([obj]), up=info.get("up", "y"))
        gltf = load_glb(path)
    node = next(nd for nd in gltf.nodes if nd.mesh is not None and (nd.extensions or {}).get("EXT_mesh_gpu_instancing"))
    return gltf, gltf.binary_blob() or b"", node


class glTF2ExportUserExtension:
    """The hooks Blender's glTF exporter calls (it finds this class on an enabled add-on's module)."""

    def __init__(self):
        from io_scene_gltf2.io.com import gltf2_io, gltf2_io_extensions
        from io_scene_gltf2.io.com.constants import ComponentType, DataType
        from io_scene_gltf2.io.exp import binary_data

        self.io, self.ext, self.binary = gltf2_io, gltf2_io_extensions, binary_data
        self.types = {"SCALAR": DataType.Scalar, "VEC2": DataType.Vec2, "VEC3": DataType.Vec3, "VEC4": DataType.Vec4}
        self.components = {5121: ComponentType.UnsignedByte, 5123: ComponentType.UnsignedShort,
                           5125: ComponentType.UnsignedInt, 5126: ComponentType.Float}

    def gather_tree_filter_tag_hook(self, vtree, export_settings):
        for vnode in vtree.nodes.values():  # a layer's base mesh travels inside its layer's node
            if vnode.blender_object is not None and BASE_KEY in vnode.blender_object.keys():
                vnode.keep_tag = False

    def gather_node_mesh_hook(self, hook, blender_object, export_settings):
        if is_layer(blender_object):  # not the bent geometry: the base mesh, once (gather_node_hook)
            hook.export_mesh = False

    def gather_node_hook(self, node, blender_object, export_settings):
        if not is_layer(blender_object):
            return
        from axialdeform.core.io.glb import read_accessor

        gltf, blob, src = _library_node(blender_object)
        where = f"{blender_object.name} (the library's encoding)"

        carried = {}  # one exporter accessor per accessor of the file: the parts' primitives share POSITION

        def carry(index, target=None):
            if index in carried:
                return carried[index]
            acc = gltf.accessors[index]
            data = read_accessor(gltf, blob, index, str(index), where)
            kind = acc.componentType
            arr = np.ascontiguousarray(data, dtype=_DTYPES[kind])
            view = self.binary.BinaryData(arr.tobytes(), bufferViewTarget=target)
            carried[index] = self.io.Accessor(
                buffer_view=view, byte_offset=None, component_type=self.components[kind], count=int(acc.count),
                extensions=None, extras=None, max=acc.max, min=acc.min, name=None, normalized=None, sparse=None,
                type=self.types[acc.type])
            return carried[index]

        mesh = gltf.meshes[src.mesh]
        primitives = []
        for prim in mesh.primitives:  # a part each, over the same vertices
            attrs = {name: carry(index, 34962) for name, index in vars(prim.attributes).items()
                     if isinstance(index, int)}
            primitives.append(self.io.MeshPrimitive(attributes=attrs, extensions=None, extras=None,
                                                    indices=carry(prim.indices, 34963),
                                                    material=self._material(gltf, prim.material), mode=4, targets=None))
        node.mesh = self.io.Mesh(extensions=None, extras=None, name=f"{blender_object.name} base",
                                 primitives=primitives, weights=None)
        instancing = {"attributes": {name: carry(index) for name, index in
                                     src.extensions["EXT_mesh_gpu_instancing"]["attributes"].items()}}
        node.extensions = dict(node.extensions or {})
        node.extensions["EXT_mesh_gpu_instancing"] = self.ext.Extension("EXT_mesh_gpu_instancing", instancing, False)
        node.extensions["AXIALDEFORM_bend"] = self.ext.Extension("AXIALDEFORM_bend",
                                                                 src.extensions["AXIALDEFORM_bend"], False)
        node.extras = src.extras
        self._place(node, blender_object, export_settings)

    def _material(self, gltf, index):
        if index is None:
            return None
        pbr = gltf.materials[index].pbrMetallicRoughness
        return self.io.Material(
            alpha_cutoff=None, alpha_mode=None, double_sided=None, emissive_factor=None, emissive_texture=None,
            extensions=None, extras=None, name=gltf.materials[index].name, normal_texture=None,
            occlusion_texture=None, pbr_metallic_roughness=self.io.MaterialPBRMetallicRoughness(
                base_color_factor=list(pbr.baseColorFactor or [1, 1, 1, 1]), base_color_texture=None, extensions=None,
                extras=None, metallic_factor=pbr.metallicFactor, metallic_roughness_texture=None,
                roughness_factor=pbr.roughnessFactor))

    @staticmethod
    def _place(node, obj, export_settings):
        """The node's transform: the object's, less the turn that stands the file's +Y up in Blender
        (the instances' numbers are in the file's coordinates)."""
        from mathutils import Matrix

        local = obj.matrix_world if obj.parent is None else obj.parent.matrix_world.inverted() @ obj.matrix_world
        turn = Matrix(UP_TO_Z_UP["y"]) if export_settings.get("gltf_yup", True) else Matrix.Identity(4)
        t, q, s = (turn.inverted() @ local).decompose()
        node.matrix = None
        node.translation = None if t.length == 0 else [t.x, t.y, t.z]
        node.rotation = None if abs(q.w) >= 1.0 else [q.x, q.y, q.z, q.w]
        node.scale = None if all(abs(c - 1.0) < 1e-7 for c in s) else [s.x, s.y, s.z]
