"""axialdeform for Blender: instanced scenes as ONE object per layer, bent by Geometry Nodes.

File > Import > axialdeform (``bpy.ops.import_scene.axialdeform``) reads a GLB with
``AXIALDEFORM_bend``, a scene file, or a mesh with a parameter file; each layer becomes a point cloud
whose points carry the instances' numbers, a hidden base mesh and a Geometry Nodes group that bends
every instance as the library does.  File > Export > axialdeform (``export_scene.axialdeform``) writes
them back as the library's instanced GLB, and Blender's own glTF exporter writes ``AXIALDEFORM_bend``
for them too (:mod:`.gltf_hooks`).  Object > axialdeform: Vary (``object.axialdeform_vary``) draws a
layer's bends again with a seed and a bend per level; Rotate Instances (``object.axialdeform_rotate``) turns
the selected instances about an axis through each one's position.  The numbers: docs/blender.md.
"""

from __future__ import annotations

import json
import time

import bpy
from bpy.props import BoolProperty, FloatVectorProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from .gltf_hooks import glTF2ExportUserExtension  # noqa: F401  (Blender's glTF exporter looks for it here)
from .layers import LAYER_KEY, add_layer, add_terrain, base_arrays, is_layer, layer_records, set_records

bl_info = {  # for Blender before extensions (the manifest is the extension's)
    "name": "axialdeform", "author": "axialdeform developers", "version": (0, 1, 0), "blender": (4, 2, 0),
    "location": "File > Import/Export > axialdeform", "category": "Import-Export",
    "description": "Instanced, individually bent shapes (AXIALDEFORM_bend) as one Geometry Nodes object per layer",
}


def _library_error(exc) -> str:
    return f"{exc}" if exc.__class__.__module__.startswith("axialdeform") else f"{type(exc).__name__}: {exc}"


class IMPORT_SCENE_OT_axialdeform(bpy.types.Operator, ImportHelper):
    """Import instanced, bent shapes (GLB with AXIALDEFORM_bend, scene file, or mesh + parameter file)"""

    bl_idname = "import_scene.axialdeform"
    bl_label = "Import axialdeform"
    bl_options = {"REGISTER", "UNDO"}
    filter_glob: StringProperty(default="*.glb;*.gltf;*.toml;*.adp;*.txt", options={"HIDDEN"})
    mesh_path: StringProperty(name="Base mesh", description="The base mesh of a parameter file (.adp, .txt)",
                              default="", subtype="FILE_PATH")

    def execute(self, context):
        from .read import layers_from_file, terrain_from_file

        start = time.perf_counter()
        try:
            layers = layers_from_file(self.filepath, self.mesh_path or None)
            terrain = terrain_from_file(self.filepath)
        except Exception as exc:  # the library's errors name the file and the field
            self.report({"ERROR"}, _library_error(exc))
            return {"CANCELLED"}
        objects = [add_layer(data) for data in layers]
        for data in layers:
            if data.extra.get("note"):
                self.report({"WARNING"}, data.extra["note"])
        if terrain is not None:
            add_terrain(*terrain)
        for obj in context.selected_objects:
            obj.select_set(False)
        for obj in objects:
            obj.select_set(True)
        if objects:
            context.view_layer.objects.active = objects[0]
        count = sum(len(obj.data.vertices) for obj in objects)
        self.report({"INFO"}, f"{len(objects)} layer(s), {count} instances in {time.perf_counter() - start:.1f} s")
        return {"FINISHED"}


def layer_objects(context, selected_only: bool):
    pool = context.selected_objects if selected_only else context.scene.objects
    return [obj for obj in pool if is_layer(obj)]


def export_layers(objects):
    """``[(name, BaseMesh, params, color)]`` of instance objects (the library's types)."""
    from .read import base_mesh

    out = []
    for obj in objects:
        info = json.loads(obj[LAYER_KEY])
        arrays = base_arrays(obj)
        mesh = base_mesh(info, arrays["positions"], arrays["normals"], arrays["faces"], arrays["uvs"],
                         arrays["vertex_axis"], arrays["colors"], arrays["parts"])
        out.append((obj.name, mesh, layer_records(obj), tuple(info.get("color") or (0.6, 0.6, 0.6))[:3]))
    return out


class EXPORT_SCENE_OT_axialdeform(bpy.types.Operator, ExportHelper):
    """Export axialdeform layers as an instanced GLB (EXT_mesh_gpu_instancing + AXIALDEFORM_bend)"""

    bl_idname = "export_scene.axialdeform"
    bl_label = "Export axialdeform"
    filename_ext = ".glb"
    filter_glob: StringProperty(default="*.glb", options={"HIDDEN"})
    use_selection: BoolProperty(name="Selected only", default=False)

    def execute(self, context):
        from .read import write_glb

        objects = layer_objects(context, self.use_selection)
        if not objects:
            self.report({"ERROR"}, "no axialdeform layer to export (import one first)")
            return {"CANCELLED"}
        ups = {json.loads(obj[LAYER_KEY]).get("up", "y") for obj in objects}
        try:
            write_glb(self.filepath, export_layers(objects), up=ups.pop() if len(ups) == 1 else "y")
        except Exception as exc:
            self.report({"ERROR"}, _library_error(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"{len(objects)} layer(s) written to {self.filepath}")
        return {"FINISHED"}


class OBJECT_OT_axialdeform_vary(bpy.types.Operator):
    """Draw the active layer's bends again (the library's random variation), keeping where each instance stands"""

    bl_idname = "object.axialdeform_vary"
    bl_label = "axialdeform: Vary"
    bl_options = {"REGISTER", "UNDO"}
    seed: IntProperty(name="Seed", default=0, min=0)
    bend: FloatVectorProperty(name="Bend per level", size=4, default=(0.08, 0.08, 0.08, 0.08), min=0.0, max=1.0,
                              description="Offsets uniform in ±bend·L of each axis, the trunk's first")
    droop: bpy.props.FloatProperty(name="Droop", default=0.0, min=0.0, max=1.0)

    @classmethod
    def poll(cls, context):
        return is_layer(context.active_object)

    def execute(self, context):
        obj = context.active_object
        try:
            [(_, mesh, params, _)] = export_layers([obj])
            set_records(obj, vary(mesh, params, self.seed, tuple(self.bend), self.droop))
        except Exception as exc:
            self.report({"ERROR"}, _library_error(exc))
            return {"CANCELLED"}
        return {"FINISHED"}


class OBJECT_OT_axialdeform_rotate(bpy.types.Operator):
    """Turn the selected instances of the active layer (all of them outside Edit Mode) about an axis through each
    one's own position: its rotation angles become those of the turn after its rotation"""

    bl_idname = "object.axialdeform_rotate"
    bl_label = "axialdeform: Rotate Instances"
    bl_options = {"REGISTER", "UNDO"}
    angle: bpy.props.FloatProperty(name="Angle", default=0.0, subtype="ANGLE")
    axis: bpy.props.EnumProperty(name="Axis", items=[("X", "X", ""), ("Y", "Y", "up in the file"), ("Z", "Z", "")],
                                 default="Y", description="In the file's coordinates (glTF: Y is up)")

    @classmethod
    def poll(cls, context):
        return is_layer(context.active_object)

    def execute(self, context):
        obj = context.active_object
        editing = obj.mode == "EDIT"
        if editing:
            bpy.ops.object.mode_set(mode="OBJECT")  # the selection and the attributes as Edit Mode left them
        rotate_instances(obj, self.angle, self.axis)
        if editing:
            bpy.ops.object.mode_set(mode="EDIT")
        return {"FINISHED"}


def rotate_instances(obj, angle: float, axis: str) -> int:
    """Turn ``obj``'s selected instances (every one when none is selected) by ``angle`` about the file's
    ``axis``: ``R' = R_axis(angle)·R``, written back as rx, ry, rz (``R = Rz·Ry·Rx``); how many turned."""
    import numpy as np

    from axialdeform.core.transforms import angles_from_matrices, rotation_matrices

    mesh = obj.data
    n = len(mesh.vertices)
    chosen = np.zeros(n, dtype=bool)
    mesh.vertices.foreach_get("select", chosen)
    if not chosen.any():
        chosen[:] = True
    angles = np.empty(n * 3, dtype=np.float32)
    mesh.attributes["axial_angles"].data.foreach_get("vector", angles)
    angles = angles.reshape(n, 3)
    turn = rotation_matrices(np.eye(3)[["X", "Y", "Z"].index(axis)][None] * angle)[0]
    angles[chosen] = angles_from_matrices(turn @ rotation_matrices(angles[chosen].astype(np.float64)))
    mesh.attributes["axial_angles"].data.foreach_set("vector", angles.reshape(-1))
    mesh.update()
    return int(chosen.sum())


def vary(mesh, params, seed: int, bend, droop: float = 0.0):
    """``params`` with every axis's offsets drawn again by the library's rules (``random_params``), each
    instance's position, rotation, scale, twist, taper and tint kept."""
    import numpy as np

    from axialdeform.core.variation import Variation, random_params

    k = getattr(mesh, "axis_count", 1)
    fresh = random_params(mesh, len(params), seed=seed, variation=Variation(bend=tuple(bend)[:max(k, 1)], droop=droop))
    out = np.array(params, dtype=np.float32, copy=True)
    out[:, :10 * k] = np.asarray(fresh)[:, :10 * k]
    return out


def _menu_import(self, context):
    self.layout.operator(IMPORT_SCENE_OT_axialdeform.bl_idname, text="axialdeform (.glb, .toml, .adp)")


def _menu_export(self, context):
    self.layout.operator(EXPORT_SCENE_OT_axialdeform.bl_idname, text="axialdeform (.glb)")


def _menu_object(self, context):
    self.layout.operator(OBJECT_OT_axialdeform_vary.bl_idname)
    self.layout.operator(OBJECT_OT_axialdeform_rotate.bl_idname)


_CLASSES = (IMPORT_SCENE_OT_axialdeform, EXPORT_SCENE_OT_axialdeform, OBJECT_OT_axialdeform_vary,
            OBJECT_OT_axialdeform_rotate)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)
    bpy.types.TOPBAR_MT_file_export.append(_menu_export)
    bpy.types.VIEW3D_MT_object.append(_menu_object)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(_menu_object)
    bpy.types.TOPBAR_MT_file_export.remove(_menu_export)
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
