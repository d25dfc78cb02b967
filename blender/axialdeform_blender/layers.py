"""One layer of instances as Blender data: a base mesh object, a point cloud of instances whose
points carry each instance's numbers as named attributes, and the Geometry Nodes modifier that
bends them (:mod:`.nodes`).  And back: the records of such an object, exactly as stored.

A layer is described by plain arrays (:class:`LayerData`); reading files is :mod:`.read`'s.  The rest
shape's Bernstein weights are the library's (``axialdeform.core.deform``).  Coordinates stay the file's (glTF: +Y
up); the instance object turns them upright for Blender (+Z up) by its own transform, the turn
Blender's glTF importer makes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import bpy
import numpy as np
from mathutils import Matrix

from axialdeform.core.blend import join_vertex_code
from axialdeform.core.deform import T_SLACK, bernstein

from .nodes import GROUP_PREFIX, build_group

__all__ = ["LayerData", "add_layer", "add_terrain", "layer_records", "set_records", "is_layer", "base_arrays",
           "LAYER_KEY", "BASE_KEY", "UP_TO_Z_UP"]

#: the custom property that marks an instance object and holds its axes (JSON)
LAYER_KEY = "axialdeform"
#: the custom property that marks a layer's (hidden) base mesh object
BASE_KEY = "axialdeform_base"
#: a scene's up to Blender's +Z, the instance object's transform (y: glTF's, the turn Blender's glTF importer makes)
UP_TO_Z_UP = {
    "y": ((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, -1.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    "z": ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    "x": ((0.0, 0.0, -1.0, 0.0), (0.0, 1.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
}
#: the viewport bends a layer of up to this many vertices in all (instances x base-mesh vertices); a larger
#: one shows its instances rigid until "Bend in Viewport" is ticked (renders and exports always bend)
VIEWPORT_BEND_LIMIT = 2_000_000


@dataclass
class LayerData:
    """What one layer is, as plain arrays.

    positions, normals : (v, 3) float32 — the base mesh (file coordinates).
    faces : (f, 3) int.
    frames : (K, 3, 3) float — each axis's rows ``e_a, e_u, e_v``; lo, length : (K,) float.
    parents : (K,) int (-1 for the root); anchors : (K,) float; line : (2,) axis 0's axis line.
    vertex_axis : (v,) int — each vertex's axis; blend : (v, 2) float or None — a second axis and its weight
    (``AxisTree.blend``: the vertex moves by ``1 - w`` of its own chain's bend and ``w`` of the second's).
    params : (n, 10·K + 6 [+3 [+3]]) float32 — the records.
    uvs : (v, 2) float32 or None (``v = 0`` at the image's bottom, as Blender's); color : RGBA or None.
    colors : (v, 4) float32 or None — linear RGBA vertex colours.
    parts : list of dict — ``name``, ``start``, ``count`` (faces), ``color`` (linear RGBA), ``texture``
    ((h, w, 4) uint8 sRGB, first row at the top, or None), ``alpha_mode``, ``alpha_cutoff``, ``default``
    (the default material: the layer's ``color`` replaces its colour).
    wind_weights : (K, 5) float — the control polygon each axis is pushed along by the wind
    (``sag_weights`` of its anchor); phases : (n,) float32 — each instance's wind phase.
    """

    name: str
    positions: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    frames: np.ndarray
    lo: np.ndarray
    length: np.ndarray
    parents: tuple
    anchors: tuple
    line: tuple
    vertex_axis: np.ndarray
    params: np.ndarray
    uvs: np.ndarray | None = None
    color: tuple | None = None
    names: tuple = ()
    extra: dict = field(default_factory=dict)
    wind_weights: np.ndarray | None = None
    phases: np.ndarray | None = None
    colors: np.ndarray | None = None
    parts: list = field(default_factory=list)
    blend: np.ndarray | None = None

    @property
    def count(self) -> int:
        return len(self.frames)

    @property
    def level(self) -> int:
        """0: 16-number records, 1: + scale, twist, taper, 2: + tint."""
        return (self.params.shape[1] - 10 * self.count - 6) // 3

    def axes_json(self) -> dict:
        return {"count": self.count, "names": list(self.names) or [f"axis{k}" for k in range(self.count)],
                "parents": [int(p) for p in self.parents], "frames": np.asarray(self.frames, float).tolist(),
                "lo": [float(x) for x in self.lo], "length": [float(x) for x in self.length],
                "anchors": [float(a) for a in self.anchors], "line": [float(x) for x in self.line],
                "width": int(self.params.shape[1]), "color": None if self.color is None else list(self.color),
                **self.extra}


def _depths(parents) -> np.ndarray:
    d = np.zeros(len(parents), dtype=int)
    for k in range(1, len(parents)):
        d[k] = d[parents[k]] + 1
    return d


def _levels(data: LayerData):
    """Each level's axes and, per vertex, the weights of the axis of its chain at that level: a level a depth of
    the tree, then (a tree whose vertices blend two chains) a level a depth for the axes of the second chain
    that are not on the first, each level's weights times the vertex's weight on that axis."""
    p = np.asarray(data.positions, dtype=np.float64)
    depth = _depths(data.parents)
    chain = np.eye(data.count, dtype=bool)
    for k in range(1, data.count):
        chain[k] |= chain[data.parents[k]]
    own = chain[np.asarray(data.vertex_axis, dtype=int)]  # (v, K)
    weight = own.astype(np.float64)
    levels = [(m, own) for m in range(int(depth.max()) + 1)]
    if data.blend is not None:  # AxisTree.weights: 1 - w on the own chain, w on the second's, 1 on both
        w = np.asarray(data.blend[:, 1], dtype=np.float64)[:, None]
        second = chain[np.asarray(data.blend[:, 0], dtype=int)] & (w > 0)
        weight = (1.0 - w) * own + w * second
        only = second & ~own
        levels += [(m, only) for m in range(1, int(depth.max()) + 1) if np.any(only[:, depth == m])]
    level_axes = [[int(k) for k in np.flatnonzero(depth == m)] for m, _ in levels]
    attrs = {}
    for m, (_, on) in enumerate(levels):
        axes = level_axes[m]
        pick = np.full(len(p), -1)
        omega = np.zeros(len(p))
        for item, k in enumerate(axes):
            pick[on[:, k]] = item
            omega[on[:, k]] = weight[on[:, k], k]
        b4, s3 = np.zeros((len(p), 5)), np.zeros((len(p), 4))
        eas, eus, evs = (np.zeros((len(p), 3)) for _ in range(3))
        for item, k in enumerate(axes):
            sel = pick == item
            f = np.asarray(data.frames[k], dtype=np.float64)
            raw = (p[sel] @ f[0] - data.lo[k]) / data.length[k]
            t = np.clip(raw, 0.0, 1.0)
            inside = ((raw >= -T_SLACK) & (raw <= 1 + T_SLACK)) if data.count > 1 else np.ones(len(raw), bool)
            b4[sel] = bernstein(t, 4)  # (T_SLACK: beyond it an ancestor's t is clamped and its slope drops out)
            s3[sel] = 4.0 * bernstein(t, 3) * (inside / data.length[k])[:, None]
            eas[sel], eus[sel], evs[sel] = f[0], f[1], f[2]
        b4 *= omega[:, None]  # the vertex's weight on the axis (1 unless it blends two chains): the bend is linear
        s3 *= omega[:, None]
        wb, ws = np.zeros(len(p)), np.zeros(len(p))
        if data.wind_weights is not None:  # the wind's push on each axis, a multiple of its part across the axis
            for item, k in enumerate(axes):
                sel = pick == item
                c = np.asarray(data.wind_weights[k], dtype=np.float64) * data.length[k]
                wb[sel] = b4[sel] @ c
                ws[sel] = s3[sel] @ (c[1:] - c[:-1])
        attrs[f"axial_m{m}_wb"] = ("FLOAT", wb)
        attrs[f"axial_m{m}_ws"] = ("FLOAT", ws)
        for i in range(5):
            attrs[f"axial_m{m}_b{i}"] = ("FLOAT", b4[:, i])
        for i in range(4):
            attrs[f"axial_m{m}_s{i}"] = ("FLOAT", s3[:, i])
        if m > 0:
            attrs[f"axial_m{m}_item"] = ("INT", np.maximum(pick, 0))
            attrs[f"axial_m{m}_ea"] = ("FLOAT_VECTOR", eas)
            attrs[f"axial_m{m}_eu"] = ("FLOAT_VECTOR", eus)
            attrs[f"axial_m{m}_ev"] = ("FLOAT_VECTOR", evs)
    f0 = np.asarray(data.frames[0], dtype=np.float64)
    local = p @ f0.T
    raw = (local[:, 0] - data.lo[0]) / data.length[0]
    inside = ((raw >= -T_SLACK) & (raw <= 1 + T_SLACK)) if data.count > 1 else np.ones(len(raw), bool)
    w = np.zeros((len(p), 3))
    w[:, :2] = local[:, 1:] - np.asarray(data.line, dtype=np.float64)
    attrs["axial_turn_t"] = ("FLOAT", np.clip(raw, 0.0, 1.0))
    attrs["axial_turn_w"] = ("FLOAT_VECTOR", w)
    attrs["axial_turn_in"] = ("FLOAT", inside / data.length[0])
    attrs["axial_rest_normal"] = ("FLOAT_VECTOR", np.asarray(data.normals, dtype=np.float64))
    attrs["axial_axis"] = ("INT", join_vertex_code(data.vertex_axis, data.blend))  # b + 64 b1 + 4096 q (blends)
    return level_axes, attrs


_FOREACH = {"FLOAT": ("value", 1), "INT": ("value", 1), "FLOAT_VECTOR": ("vector", 3), "FLOAT2": ("vector", 2),
            "FLOAT_COLOR": ("color", 4)}


def _store(mesh, name: str, kind: str, values) -> None:
    attr = mesh.attributes.new(name, kind, "POINT")
    key, width = _FOREACH[kind]
    arr = np.ascontiguousarray(values, dtype=np.int32 if kind == "INT" else np.float32)
    attr.data.foreach_set(key, arr.reshape(-1) if width > 1 or arr.ndim == 1 else arr[:, 0])


def _read(mesh, name: str, kind: str, count: int) -> np.ndarray:
    key, width = _FOREACH[kind]
    out = np.empty(count * width, dtype=np.int32 if kind == "INT" else np.float32)
    mesh.attributes[name].data.foreach_get(key, out)
    return out.reshape(count, width) if width > 1 else out


def instance_attributes(params: np.ndarray, count: int) -> dict:
    """The point attributes of a layer's records: (name, kind, values)."""
    v = np.asarray(params, dtype=np.float32)
    n, k = len(v), count
    out = {}
    for j in range(k):
        for i in range(5):
            name = f"axial_d{i + 1}" if j == 0 else f"axial_a{j}_d{i + 1}"
            out[name] = ("FLOAT2", v[:, 10 * j + 2 * i:10 * j + 2 * i + 2])
    rest = v[:, 10 * k:]
    out["axial_angles"] = ("FLOAT_VECTOR", rest[:, 3:6])
    if rest.shape[1] >= 9:
        out["axial_scale"] = ("FLOAT", rest[:, 6])
        out["axial_twist"] = ("FLOAT", rest[:, 7])
        out["axial_taper"] = ("FLOAT", rest[:, 8])
    if rest.shape[1] >= 12:
        out["axial_tint"] = ("FLOAT_COLOR", np.concatenate([rest[:, 9:12], np.ones((n, 1), np.float32)], axis=1))
    return out


def _base_object(data: LayerData, collection):
    mesh = bpy.data.meshes.new(f"{data.name} base")
    pos = np.asarray(data.positions, dtype=np.float32)
    faces = np.asarray(data.faces, dtype=np.int32)
    mesh.vertices.add(len(pos))
    mesh.vertices.foreach_set("co", pos.reshape(-1))
    mesh.loops.add(faces.size)
    mesh.loops.foreach_set("vertex_index", faces.reshape(-1))
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    mesh.polygons.foreach_set("use_smooth", np.ones(len(faces), dtype=bool))
    if data.uvs is not None:
        uv = np.asarray(data.uvs, dtype=np.float32)[faces.reshape(-1)]  # v = 0 at the bottom, as Blender's
        mesh.uv_layers.new(name="UVMap").data.foreach_set("uv", uv.reshape(-1))
    if data.colors is not None:
        _store(mesh, "Col", "FLOAT_COLOR", np.asarray(data.colors, dtype=np.float32))
    parts = data.parts or [{"name": "surface", "start": 0, "count": len(faces), "color": (1.0, 1.0, 1.0, 1.0),
                            "texture": None, "alpha_mode": "OPAQUE", "alpha_cutoff": 0.5, "default": True}]
    index = np.zeros(len(faces), dtype=np.int32)
    for i, part in enumerate(parts):
        index[part["start"]:part["start"] + part["count"]] = i
        mesh.materials.append(_material(data, part))
    mesh.polygons.foreach_set("material_index", index)
    level_axes, attrs = _levels(data)
    if data.uvs is not None:  # as the library had them, whatever is done to the UV layer
        attrs["axial_uv"] = ("FLOAT2", np.asarray(data.uvs, dtype=np.float32))
    for name, (kind, values) in attrs.items():
        _store(mesh, name, kind, values)
    obj = bpy.data.objects.new(f"{data.name} base", mesh)
    collection.objects.link(obj)
    obj.hide_render = True
    obj.hide_viewport = True
    obj[BASE_KEY] = data.name
    return obj, level_axes


def _multiply(tree, a, b):
    """A node multiplying two colour sockets (or a socket and a constant); its output."""
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type, mix.blend_type = "RGBA", "MULTIPLY"
    mix.inputs["Factor"].default_value = 1.0
    for socket, value in ((mix.inputs[6], a), (mix.inputs[7], b)):
        if isinstance(value, tuple):
            socket.default_value = value
        else:
            tree.links.new(value, socket)
    return mix.outputs[2]


def _texture(data: LayerData, part: dict):
    tex = np.asarray(part["texture"], dtype=np.uint8)
    h, w = tex.shape[:2]
    image = bpy.data.images.new(f"{data.name} {part['name']}", w, h, alpha=True)
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :tex.shape[2]] = tex[::-1] / 255.0  # Blender's rows run bottom-up
    image.pixels.foreach_set(rgba.reshape(-1))
    image.pack()
    return image


def _material(data: LayerData, part: dict):
    """A part's look: its base colour (the layer's for the default material) times its texture, the vertex
    colours and each instance's tint (the library's shading multiplies the same)."""
    mat = bpy.data.materials.new(f"{data.name} {part['name']}")
    mat["axial_part"] = {"name": str(part["name"]), "color": [float(c) for c in part["color"]],
                         "alpha_mode": str(part.get("alpha_mode", "OPAQUE")),
                         "alpha_cutoff": float(part.get("alpha_cutoff", 0.5)), "default": bool(part.get("default"))}
    mat.use_nodes = True
    tree = mat.node_tree
    bsdf = next(nd for nd in tree.nodes if nd.type == "BSDF_PRINCIPLED")
    color = tuple(data.color) if part.get("default") and data.color is not None else tuple(part["color"])
    color = (color + (1.0,) * 4)[:4]
    out = None
    alpha = None
    if part.get("texture") is not None and data.uvs is not None:
        node = tree.nodes.new("ShaderNodeTexImage")
        node.image = _texture(data, part)
        mat["axial_texture"] = node.image.name
        out, alpha = _multiply(tree, node.outputs["Color"], color), node.outputs["Alpha"]
    if data.colors is not None:
        vc = tree.nodes.new("ShaderNodeVertexColor")
        vc.layer_name = "Col"
        out = _multiply(tree, vc.outputs["Color"], color if out is None else out)
    if data.level >= 2:  # the tint multiplies the base colour
        tint = tree.nodes.new("ShaderNodeAttribute")
        tint.attribute_name = "axial_tint"
        out = _multiply(tree, tint.outputs["Color"], color if out is None else out)
    if out is None:
        bsdf.inputs["Base Color"].default_value = color
    else:
        tree.links.new(out, bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.9
    if part.get("alpha_mode", "OPAQUE") != "OPAQUE" and alpha is not None:
        tree.links.new(alpha, bsdf.inputs["Alpha"])
    return mat


def add_layer(data: LayerData, collection=None, base_collection=None):
    """Make one layer's objects and return its instance object (one object, however many instances).

    The base mesh goes to ``base_collection`` (hidden; made if None), the instance object to
    ``collection`` (the scene's if None).
    """
    scene = bpy.context.scene
    collection = collection or scene.collection
    if base_collection is None:
        base_collection = bpy.data.collections.get("axialdeform bases") or bpy.data.collections.new("axialdeform bases")
        if base_collection.name not in scene.collection.children:
            scene.collection.children.link(base_collection)
        base_collection.hide_render = True
    base, level_axes = _base_object(data, base_collection)
    params = np.asarray(data.params, dtype=np.float32)
    points = bpy.data.meshes.new(f"{data.name} instances")
    points.vertices.add(len(params))
    points.vertices.foreach_set("co", params[:, 10 * data.count:10 * data.count + 3].reshape(-1))
    for name, (kind, values) in instance_attributes(params, data.count).items():
        _store(points, name, kind, values)
    phases = np.zeros(len(params)) if data.phases is None else data.phases
    _store(points, "axial_wind_phase", "FLOAT", phases)
    obj = bpy.data.objects.new(data.name, points)
    collection.objects.link(obj)
    obj[LAYER_KEY] = json.dumps(data.axes_json())
    obj.matrix_world = Matrix(UP_TO_Z_UP[data.extra.get("up", "y")])  # rows
    plan = {"frames": np.asarray(data.frames, float).tolist(), "levels": len(level_axes), "level_axes": level_axes,
            "extended": data.level >= 1, "tinted": data.level >= 2}
    group = build_group(f"{GROUP_PREFIX} {data.name}", plan)
    mod = obj.modifiers.new("axialdeform", "NODES")
    mod.node_group = group
    ident = {item.name: item.identifier for item in group.interface.items_tree if getattr(item, "in_out", "") == "INPUT"}
    mod[ident["Base"]] = base
    mod[ident["Bend in Viewport"]] = len(params) * len(data.positions) <= VIEWPORT_BEND_LIMIT
    wind = data.extra.get("wind")
    if wind:  # the scene's wind; the scene's time is its clock
        for name, key in (("Wind Direction", "direction"), ("Wind Strength", "strength"), ("Gustiness", "gustiness"),
                          ("Frequency", "frequency"), ("Wavelength", "wavelength")):
            mod[ident[name]] = wind[key]
    return obj


def add_terrain(positions, faces, color, up: str = "y", collection=None):
    """A scene's terrain as a plain mesh object (stood up as the layers are)."""
    mesh = bpy.data.meshes.new("terrain")
    mesh.from_pydata(np.asarray(positions, np.float64).tolist(), [], np.asarray(faces).tolist())
    mesh.update()
    mat = bpy.data.materials.new("terrain")
    mat.use_nodes = True
    bsdf = next(nd for nd in mat.node_tree.nodes if nd.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = tuple(color)[:3] + (1.0,)
    mesh.materials.append(mat)
    obj = bpy.data.objects.new("terrain", mesh)
    (collection or bpy.context.scene.collection).objects.link(obj)
    obj.matrix_world = Matrix(UP_TO_Z_UP[up])
    return obj


def is_layer(obj) -> bool:
    return obj is not None and obj.type == "MESH" and LAYER_KEY in obj.keys()


def layer_records(obj) -> np.ndarray:
    """The records of an instance object, float32 exactly as its attributes hold them:
    ``(n, 10·K + 6 [+3 [+3]])`` (instances moved, deleted or edited in the spreadsheet included)."""
    info = json.loads(obj[LAYER_KEY])
    mesh = obj.data
    n, k, width = len(mesh.vertices), int(info["count"]), int(info["width"])
    out = np.zeros((n, width), dtype=np.float32)
    pos = np.empty(n * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", pos)
    for j in range(k):
        for i in range(5):
            name = f"axial_d{i + 1}" if j == 0 else f"axial_a{j}_d{i + 1}"
            out[:, 10 * j + 2 * i:10 * j + 2 * i + 2] = _read(mesh, name, "FLOAT2", n)
    r = 10 * k
    out[:, r:r + 3] = pos.reshape(n, 3)
    out[:, r + 3:r + 6] = _read(mesh, "axial_angles", "FLOAT_VECTOR", n)
    if width >= r + 9:
        out[:, r + 6] = _read(mesh, "axial_scale", "FLOAT", n)
        out[:, r + 7] = _read(mesh, "axial_twist", "FLOAT", n)
        out[:, r + 8] = _read(mesh, "axial_taper", "FLOAT", n)
    if width >= r + 12:
        out[:, r + 9:r + 12] = _read(mesh, "axial_tint", "FLOAT_COLOR", n)[:, :3]
    return out


def base_arrays(obj) -> dict:
    """The base mesh of an instance object as the file gave it: positions, normals, faces, uvs, vertex_axis."""
    mod = next(m for m in obj.modifiers if m.type == "NODES" and m.node_group is not None)
    ident = {item.name: item.identifier for item in mod.node_group.interface.items_tree
             if getattr(item, "in_out", "") == "INPUT"}
    mesh = mod[ident["Base"]].data
    v, f = len(mesh.vertices), len(mesh.polygons)
    pos = np.empty(v * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", pos)
    loops = np.empty(f * 3, dtype=np.int32)
    mesh.polygons.foreach_get("vertices", loops)
    index = np.empty(f, dtype=np.int32)
    mesh.polygons.foreach_get("material_index", index)
    parts = []
    for i, mat in enumerate(mesh.materials):  # each part as the library had it: its faces, its material
        faces = np.flatnonzero(index == i)
        info = dict(mat["axial_part"]) if mat is not None and "axial_part" in mat else {"name": f"part{i}"}
        texture = None
        if mat is not None and "axial_texture" in mat:
            image = bpy.data.images[mat["axial_texture"]]
            w, h = image.size
            px = np.empty(w * h * 4, dtype=np.float32)
            image.pixels.foreach_get(px)
            texture = np.round(px.reshape(h, w, 4)[::-1] * 255.0).astype(np.uint8)
        parts.append({**info, "start": int(faces[0]) if len(faces) else 0, "count": len(faces), "texture": texture})
    return {"positions": pos.reshape(v, 3), "normals": _read(mesh, "axial_rest_normal", "FLOAT_VECTOR", v),
            "colors": _read(mesh, "Col", "FLOAT_COLOR", v) if "Col" in mesh.attributes else None, "parts": parts,
            "faces": loops.reshape(f, 3), "vertex_axis": _read(mesh, "axial_axis", "INT", v),
            "uvs": _read(mesh, "axial_uv", "FLOAT2", v) if "axial_uv" in mesh.attributes else None}


def set_records(obj, params) -> None:
    """Replace an instance object's records (same number of axes and width; the count may change)."""
    info = json.loads(obj[LAYER_KEY])
    params = np.asarray(params, dtype=np.float32)
    k, width = int(info["count"]), int(info["width"])
    if params.ndim != 2 or params.shape[1] != width:
        raise ValueError(f"{obj.name}: expected records of {width} numbers, found shape {params.shape}")
    mesh = obj.data
    if len(mesh.vertices) != len(params):
        mesh.clear_geometry()
        mesh.vertices.add(len(params))
    mesh.vertices.foreach_set("co", params[:, 10 * k:10 * k + 3].reshape(-1))
    for name, (kind, values) in instance_attributes(params, k).items():
        if name in mesh.attributes and len(mesh.vertices) == len(params):
            key, w = _FOREACH[kind]
            arr = np.ascontiguousarray(values, dtype=np.float32)
            mesh.attributes[name].data.foreach_set(key, arr.reshape(-1))
        else:
            _store(mesh, name, kind, values)
    if "axial_wind_phase" not in mesh.attributes:
        _store(mesh, "axial_wind_phase", "FLOAT", np.zeros(len(params)))
    mesh.update()
