"""Files to layers and layers to files, through the axialdeform library (its readers and writers:
one reading of every format, the library's checks and errors).

``layers_from_file`` reads a GLB (each ``EXT_mesh_gpu_instancing`` node, with ``AXIALDEFORM_bend``), a
mesh with a parameter file, or a scene file (each layer; a generated layer's instances made by the
library's generator); ``write_glb`` writes instance objects back as the library's instanced GLB.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .layers import UP_TO_Z_UP, LayerData

__all__ = ["layers_from_file", "layer_data", "terrain_from_file", "base_mesh", "write_glb"]



def layer_data(name: str, mesh, params, color=None, up: str = "y") -> LayerData:
    """A :class:`LayerData` of an axialdeform ``BaseMesh`` and its records."""
    tree = getattr(mesh, "tree", None)
    if tree is not None:
        axes = tree.axes
        parents, anchors, names = tuple(tree.parents), tuple(tree.anchors), tuple(tree.names)
        vertex_axis, blend = np.asarray(tree.vertex_axis, dtype=int), tree.blend
    else:
        axes, parents, anchors, names = [mesh.axis], (-1,), (0.0,), ()
        vertex_axis, blend = np.zeros(mesh.vertex_count, dtype=int), None
    if color is not None:  # a scene layer's colour: its mesh's default material takes it
        color = tuple(float(c) for c in color) + (1.0,) * (4 - len(color))
    from axialdeform.core.axes import sag_weights
    from axialdeform.core.wind import wind_phase

    axis0 = axes[0]
    return LayerData(
        name=name, positions=np.asarray(mesh.positions, np.float32), normals=np.asarray(mesh.normals, np.float32),
        faces=np.asarray(mesh.faces, np.int64), frames=np.stack([a.matrix for a in axes]),
        lo=np.array([a.lo for a in axes]), length=np.array([a.length for a in axes]), parents=parents,
        anchors=anchors, line=tuple(axis0.line), vertex_axis=vertex_axis, blend=blend, params=np.asarray(params, np.float32),
        uvs=None if mesh.uvs is None else np.asarray(mesh.uvs, np.float32), color=color, names=names,
        extra={"up": up, "axis_kind": "frame" if axis0.framed else "xyz"[axis0.index]},
        wind_weights=sag_weights(np.asarray(anchors, dtype=np.float64)),
        phases=wind_phase(np.arange(len(params))).astype(np.float32),
        colors=None if mesh.colors is None else np.asarray(mesh.colors, np.float32),
        parts=[{"name": p.name, "start": int(p.start), "count": int(p.count),
                "color": tuple(float(c) for c in p.material.base_color), "texture": p.material.texture,
                "alpha_mode": p.material.alpha_mode, "alpha_cutoff": float(p.material.alpha_cutoff),
                "default": bool(p.material.is_default)} for p in mesh.parts])


def layers_from_file(path, mesh_path=None) -> list:
    """Every layer of ``path`` as a :class:`LayerData`: a ``.glb`` (each instanced node), a scene file
    (``.toml``: each layer), or a parameter file (``.adp``/text, with ``mesh_path``)."""
    from axialdeform.core.io.glb import BEND_EXTENSION, INSTANCING, load_glb
    from axialdeform.core.io.gltf_read import read_instanced_glb
    from axialdeform.core.scene import is_scene_file, load_scene

    path = Path(path)
    if path.suffix.lower() in (".glb", ".gltf"):
        gltf = load_glb(path)
        up = ((gltf.scenes[gltf.scene or 0].extras or {}).get("axialdeform", {}) or {}).get("up", "y") \
            if gltf.scenes else "y"
        nodes = [nd for nd in gltf.nodes if (nd.extensions or {}).get(INSTANCING) and nd.mesh is not None]
        out = []
        for nd in nodes:
            generated = isinstance((nd.extensions or {}).get(BEND_EXTENSION), dict) and \
                "generate" in nd.extensions[BEND_EXTENSION]
            mesh, params = read_instanced_glb(path, nd.name if len(nodes) > 1 else None, fallback=generated)
            data = layer_data(nd.name or path.stem, mesh, params, up=up if up in UP_TO_Z_UP else "y")
            if generated:  # its instances are a recipe's: the file holds a small sample of them
                data.extra["note"] = (f"{data.name}: a generated layer (its recipe); imported its fallback, "
                                      f"{len(params)} instances -- import the scene file for all of them")
            out.append(data)
        return out
    if is_scene_file(path):
        scene = load_scene(path)
        out = [layer_data(layer.name, layer.mesh, layer.params, layer.color, scene.up)
               for layer in scene.layers if len(layer.params)]
        if scene.wind is not None:  # the scene's wind drives the layers that sway in it
            for data, layer in zip(out, [x for x in scene.layers if len(x.params)]):
                if layer.wind:
                    w = scene.wind
                    data.extra["wind"] = {"direction": list(w.unit_direction), "strength": w.strength,
                                          "gustiness": w.gustiness, "frequency": w.frequency,
                                          "wavelength": w.wavelength}
        return out
    from axialdeform.core.io.mesh import load_mesh
    from axialdeform.core.io.params import read_params

    if mesh_path is None:
        raise ValueError(f"{path}: a parameter file needs its base mesh (mesh_path)")
    mesh = load_mesh(mesh_path)
    return [layer_data(path.stem, mesh, read_params(path, mesh))]


def terrain_from_file(path):
    """A scene file's terrain as ``(positions, faces, colour, up)``, or None (no terrain, not a scene file)."""
    from axialdeform.core.scene import is_scene_file, load_scene

    if not is_scene_file(path):
        return None
    scene = load_scene(path)
    if scene.terrain is None:
        return None
    return (np.asarray(scene.terrain.positions, np.float32), np.asarray(scene.terrain.faces, np.int64),
            tuple(scene.terrain_color), scene.up)


def base_mesh(info: dict, positions, normals, faces, uvs=None, vertex_axis=None, colors=None, parts=()):
    """The axialdeform ``BaseMesh`` an instance object was made from: its axes as recorded (``vertex_axis``: each
    vertex's code, ``AxisTree.vertex_code``: its axis, or the two it blends), its appearance (``parts``:
    :class:`LayerData`'s dicts, the texture's pixels as Blender holds them) as imported."""
    from axialdeform.core.axes import tree_from_vertices
    from axialdeform.core.blend import split_vertex_code
    from axialdeform.core.material import Material, Part
    from axialdeform.core.mesh import BaseMesh

    looks = tuple(Part(p["name"], p["start"], p["count"], Material(
        name=p["name"], base_color=p.get("color", (1.0, 1.0, 1.0, 1.0)), texture=p.get("texture"),
        texture_name=None if p.get("texture") is None else "blender", alpha_mode=p.get("alpha_mode", "OPAQUE"),
        alpha_cutoff=p.get("alpha_cutoff", 0.5))) for p in parts if p["count"])
    mesh = BaseMesh(np.asarray(positions, np.float32), np.asarray(normals, np.float32), np.asarray(faces),
                    name=info.get("name", "blender"), uvs=uvs, colors=colors, parts=looks)
    kind = info.get("axis_kind", "frame")
    if int(info["count"]) == 1:
        return mesh.with_axis(kind if kind in ("x", "y", "z") else np.asarray(info["frames"][0]))
    axis, blend = split_vertex_code(vertex_axis)
    tree = tree_from_vertices(mesh, axis.astype(np.int64), list(info["parents"]),
                              frames=[np.asarray(f) for f in info["frames"]], names=list(info["names"]),
                              root_children=False, anchors=info.get("anchors"), blend=blend)
    return mesh.with_axes(tree)


def write_glb(path, layers, up: str = "y"):
    """Write ``[(name, BaseMesh, params, color)]`` as the library's instanced GLB (one node a layer,
    ``AXIALDEFORM_bend``), atomically."""
    from axialdeform.core.io.gltf import export_scene
    from axialdeform.core.scene import Layer, Scene

    scene = Scene(path=None, up=up, layers=[Layer(name, mesh, params, color=color) for name, mesh, params, color
                                            in layers])
    return export_scene(path, scene, layout="instanced")
