"""The bend as a Geometry Nodes group: every instance of a layer bent as axialdeform bends it.

The group reads what :mod:`.layers` stores: on the base mesh, per vertex, the rest normal and the
Bernstein weights of each axis of its chain (they depend on the rest shape only); on the instance
points, each instance's numbers (``axial_d1`` .. ``axial_d5`` and ``axial_a{j}_d{i}``: the control
offsets, ``axial_angles``, ``axial_scale``, ``axial_twist``, ``axial_taper``, ``axial_tint``).  It
realizes the instances (each instance's points keep its numbers as point attributes) and sets every
vertex to

    V'' = V + F0ᵀ (0, k Rot(tw t0) w - w) + Σ_j F_jᵀ (0, D_j(t_j)),   W = R (s V'') + p,

and its normal to ``R normalize(cof(J) n)`` (``docs/method.md``; ``glsl/axial.glsl``'s
``axial_tree_world`` operation for operation, in the node tree's float32).  A switch keeps the
instances rigid (placed, not bent) in the viewport when there are many.

Nothing here reads a file: the maths of the method, written once more as nodes.
"""

from __future__ import annotations

import bpy

__all__ = ["build_group", "GROUP_PREFIX"]

GROUP_PREFIX = "AxialDeform"


class Field:
    """One output socket of the tree being built, with arithmetic that adds nodes."""

    def __init__(self, graph, socket, vector: bool):
        self.g, self.socket, self.vector = graph, socket, vector

    def __add__(self, other):
        return self.g.op("ADD", self, other)

    def __radd__(self, other):
        return self.g.op("ADD", other, self)

    def __sub__(self, other):
        return self.g.op("SUBTRACT", self, other)

    def __rsub__(self, other):
        return self.g.op("SUBTRACT", other, self)

    def __mul__(self, other):
        return self.g.op("MULTIPLY", self, other)

    def __rmul__(self, other):
        return self.g.op("MULTIPLY", other, self)

    def __neg__(self):
        return self.g.op("MULTIPLY", self, -1.0)

    def xyz(self):
        """The three components of a vector field."""
        node = self.g.node("ShaderNodeSeparateXYZ")
        self.g.link(node.inputs[0], self)
        return tuple(Field(self.g, node.outputs[i], False) for i in range(3))


class Graph:
    """A node tree and the helpers that add its nodes in reading order."""

    def __init__(self, tree):
        self.tree = tree
        self.count = 0

    def node(self, kind: str, **props):
        node = self.tree.nodes.new(kind)
        for key, value in props.items():
            setattr(node, key, value)
        node.location = (200.0 * (self.count // 40), -60.0 * (self.count % 40))
        self.count += 1
        return node

    def link(self, socket, value) -> None:
        if isinstance(value, Field):
            self.tree.links.new(value.socket, socket)
        else:
            socket.default_value = value

    @staticmethod
    def _is_vector(value) -> bool:
        return (isinstance(value, Field) and value.vector) or isinstance(value, (tuple, list))

    def op(self, operation: str, a, b):
        """a (op) b for floats and vectors (a vector times a float: SCALE)."""
        va, vb = self._is_vector(a), self._is_vector(b)
        if not va and not vb:
            node = self.node("ShaderNodeMath", operation=operation)
            self.link(node.inputs[0], a)
            self.link(node.inputs[1], b)
            return Field(self, node.outputs[0], False)
        if va != vb:
            if operation != "MULTIPLY":
                raise TypeError(f"{operation} of a vector and a float")
            vec, scalar = (a, b) if va else (b, a)
            node = self.node("ShaderNodeVectorMath", operation="SCALE")
            self.link(node.inputs[0], vec)
            self.link(node.inputs[3], scalar)
            return Field(self, node.outputs[0], True)
        node = self.node("ShaderNodeVectorMath", operation=operation)
        self.link(node.inputs[0], a)
        self.link(node.inputs[1], b)
        return Field(self, node.outputs[0], True)

    def math(self, operation: str, a):
        node = self.node("ShaderNodeMath", operation=operation)
        self.link(node.inputs[0], a)
        return Field(self, node.outputs[0], False)

    def vector(self, operation: str, a, b=None):
        node = self.node("ShaderNodeVectorMath", operation=operation)
        self.link(node.inputs[0], a)
        if b is not None:
            self.link(node.inputs[1], b)
        out = node.outputs[1] if operation in ("DOT_PRODUCT", "LENGTH") else node.outputs[0]
        return Field(self, out, operation not in ("DOT_PRODUCT", "LENGTH"))

    def combine(self, x, y, z):
        node = self.node("ShaderNodeCombineXYZ")
        for i, value in enumerate((x, y, z)):
            self.link(node.inputs[i], value)
        return Field(self, node.outputs[0], True)

    def attribute(self, name: str, kind: str = "FLOAT"):
        """A named attribute of the geometry being evaluated (FLOAT, FLOAT_VECTOR, INT, ...)."""
        node = self.node("GeometryNodeInputNamedAttribute", data_type=kind)
        node.inputs["Name"].default_value = name
        return Field(self, node.outputs["Attribute"], kind in ("FLOAT_VECTOR", "FLOAT2", "FLOAT_COLOR"))

    def switch(self, index, fields):
        """``fields[index]`` per element (an Index Switch of vectors)."""
        node = self.node("GeometryNodeIndexSwitch", data_type="VECTOR")
        while len(node.index_switch_items) < len(fields):
            node.index_switch_items.new()
        self.link(node.inputs["Index"], index)
        for i, value in enumerate(fields):
            self.link(node.inputs[i + 1], value)
        return Field(self, node.outputs[0], True)


def _sum(terms):
    total = terms[0]
    for term in terms[1:]:
        total = total + term
    return total


def _wind_push(g: Graph, group_in):
    """The wind's push per unit of axis length in each instance's model frame at the scene's time
    (``glsl/wind.glsl``'s ``axial_wind_push`` with ``len`` 1): ``strength (1 + gust wave) Rᵀ dir``."""
    direction = g.vector("NORMALIZE", Field(g, group_in.outputs["Wind Direction"], True))
    seconds = Field(g, g.node("GeometryNodeInputSceneTime").outputs["Seconds"], False)
    cycles = Field(g, group_in.outputs["Frequency"], False) * seconds
    c1 = g.math("FRACT", cycles)
    c2 = g.math("FRACT", cycles * 2.31)
    wavenumber = g.op("DIVIDE", 1.0, Field(g, group_in.outputs["Wavelength"], False))  # 0 for 0: no fronts
    ph = g.attribute("axial_wind_phase") - g.vector("DOT_PRODUCT", g.attribute("axial_position", "FLOAT_VECTOR"),
                                                    direction) * wavenumber
    tau = 6.283185307179586
    wave = 0.6 * g.math("SINE", (c1 + ph) * tau) + 0.4 * g.math("SINE", (c2 + ph * 1.7) * tau)
    amp = Field(g, group_in.outputs["Wind Strength"], False) * (
        1.0 + Field(g, group_in.outputs["Gustiness"], False) * wave)
    return _rotate(g, direction, g.attribute("axial_angles", "FLOAT_VECTOR"), invert=True) * amp


def _bend(g: Graph, plan: dict, push):
    """Model-space ``s·V''`` and the unit normal ``normalize(cof(J)·n)`` of every realized vertex
    (``push``: the wind's, :func:`_wind_push`)."""
    v = g.attribute("axial_rest_position", "FLOAT_VECTOR")
    n = g.attribute("axial_rest_normal", "FLOAT_VECTOR")
    f0 = plan["frames"][0]
    ea0, eu0, ev0 = (tuple(float(c) for c in row) for row in f0)
    moved = v
    if plan["extended"]:  # twist and taper about axis 0's axis line, before the displacements
        t0 = g.attribute("axial_turn_t")
        wx, wy, _ = g.attribute("axial_turn_w", "FLOAT_VECTOR").xyz()
        gin = g.attribute("axial_turn_in")
        tw, tp = g.attribute("axial_twist"), g.attribute("axial_taper")
        k = 1.0 - tp * t0
        theta = tw * t0
        c, s = g.math("COSINE", theta), g.math("SINE", theta)
        rwx, rwy = c * wx - s * wy, s * wx + c * wy
        moved = moved + g.op("MULTIPLY", eu0, k * rwx - wx) + g.op("MULTIPLY", ev0, k * rwy - wy)
        ktw = k * tw
        gx = gin * (ktw * (-rwy) - tp * rwx)
        gy = gin * (ktw * rwx - tp * rwy)
        kc, ks = k * c, k * s
        cols = []
        for m in range(3):  # column m of J = F0ᵀ Jl F0
            alpha = gx * ea0[m] + kc * eu0[m] - ks * ev0[m]
            beta = gy * ea0[m] + ks * eu0[m] + kc * ev0[m]
            cols.append(g.op("ADD", tuple(x * ea0[m] for x in ea0), g.op("MULTIPLY", eu0, alpha))
                        + g.op("MULTIPLY", ev0, beta))
    else:
        cols = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    disp = []
    for level in range(plan["levels"]):
        axes = plan["level_axes"][level]  # the axes at this depth
        if level == 0:
            ea, eu, ev = ea0, eu0, ev0
        else:
            ea = g.attribute(f"axial_m{level}_ea", "FLOAT_VECTOR")
            eu = g.attribute(f"axial_m{level}_eu", "FLOAT_VECTOR")
            ev = g.attribute(f"axial_m{level}_ev", "FLOAT_VECTOR")
        offsets = []
        for i in range(1, 6):
            names = [f"axial_d{i}" if j == 0 else f"axial_a{j}_d{i}" for j in axes]
            fields = [g.attribute(name, "FLOAT_VECTOR") for name in names]
            offsets.append(fields[0] if len(fields) == 1 else g.switch(g.attribute(f"axial_m{level}_item", "INT"), fields))
        weights = [g.attribute(f"axial_m{level}_b{i}") for i in range(5)]
        slopes = [g.attribute(f"axial_m{level}_s{i}") for i in range(4)]
        d = _sum([offsets[i] * weights[i] for i in range(5)])
        sl = _sum([(offsets[i + 1] - offsets[i]) * slopes[i] for i in range(4)])
        dx, dy, _ = d.xyz()
        sx, sy, _ = sl.xyz()
        # the wind: the push's part across this axis, on the axis's control polygon of its anchor
        ea_vec = ea if isinstance(ea, Field) else tuple(ea)
        cross = push - g.op("MULTIPLY", ea_vec, g.vector("DOT_PRODUCT", push, ea_vec))
        disp.append(g.op("MULTIPLY", eu, dx) + g.op("MULTIPLY", ev, dy)
                    + cross * g.attribute(f"axial_m{level}_wb"))
        across = (g.op("MULTIPLY", eu, sx) + g.op("MULTIPLY", ev, sy)
                  + cross * g.attribute(f"axial_m{level}_ws"))
        ea_xyz = ea if isinstance(ea, tuple) else ea.xyz()
        cols = [cols[m] + across * ea_xyz[m] for m in range(3)]
    moved = moved + _sum(disp)
    nx, ny, nz = n.xyz()
    cof = (g.vector("CROSS_PRODUCT", cols[1], cols[2]) * nx + g.vector("CROSS_PRODUCT", cols[2], cols[0]) * ny
           + g.vector("CROSS_PRODUCT", cols[0], cols[1]) * nz)
    normal = g.vector("NORMALIZE", cof)
    if plan["extended"]:
        moved = moved * g.attribute("axial_scale")
    return moved, normal


def _rotate(g: Graph, vec, euler, invert: bool = False):
    """``R·vec`` with ``R = Rz(rz)·Ry(ry)·Rx(rx)`` (Blender's Euler XYZ); ``invert``: ``Rᵀ·vec``."""
    node = g.node("ShaderNodeVectorRotate", rotation_type="EULER_XYZ", invert=invert)
    g.link(node.inputs["Vector"], vec)
    g.link(node.inputs["Rotation"], euler)
    return Field(g, node.outputs[0], True)


def build_group(name: str, plan: dict):
    """A new Geometry Nodes group ``name`` for one layer's base mesh.

    plan : dict
        ``frames`` (K, 3, 3) rows ``e_a, e_u, e_v`` of every axis; ``levels`` the depth of the axis tree + 1;
        ``level_axes`` the axes at each depth (their order is ``axial_m{m}_item``'s); ``extended`` whether the
        records have scale, twist and taper; ``tinted`` whether they carry a tint.
    Inputs: Geometry (the instance points), Base (the base mesh's object), Bend in Viewport (bool), and the
    wind (``docs/wind.md``; the scene's time in seconds is its clock): Wind Direction (the file's
    coordinates), Wind Strength (tip displacement in axis lengths; 0: still), Gustiness, Frequency (Hz),
    Wavelength (of the gust fronts; 0: none).
    """
    tree = bpy.data.node_groups.new(name, "GeometryNodeTree")
    face = tree.interface
    face.new_socket("Geometry", in_out="INPUT", socket_type="NodeSocketGeometry")
    face.new_socket("Base", in_out="INPUT", socket_type="NodeSocketObject")
    bend_socket = face.new_socket("Bend in Viewport", in_out="INPUT", socket_type="NodeSocketBool")
    bend_socket.default_value = True
    for name, kind, value in (("Wind Direction", "NodeSocketVector", (1.0, 0.0, 0.0)),
                              ("Wind Strength", "NodeSocketFloat", 0.0), ("Gustiness", "NodeSocketFloat", 0.6),
                              ("Frequency", "NodeSocketFloat", 0.5), ("Wavelength", "NodeSocketFloat", 0.0)):
        face.new_socket(name, in_out="INPUT", socket_type=kind).default_value = value
    face.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    g = Graph(tree)
    group_in = g.node("NodeGroupInput")
    group_out = g.node("NodeGroupOutput")
    base = g.node("GeometryNodeObjectInfo", transform_space="ORIGINAL")
    tree.links.new(group_in.outputs["Base"], base.inputs["Object"])
    angles = g.attribute("axial_angles", "FLOAT_VECTOR")
    scale = g.attribute("axial_scale") if plan["extended"] else 1.0
    # the rigid instances (the viewport's quick form): placed and sized, not bent
    rigid = g.node("GeometryNodeInstanceOnPoints")
    tree.links.new(group_in.outputs["Geometry"], rigid.inputs["Points"])
    tree.links.new(base.outputs["Geometry"], rigid.inputs["Instance"])
    to_rot = g.node("FunctionNodeEulerToRotation")
    g.link(to_rot.inputs[0], angles)
    tree.links.new(to_rot.outputs[0], rigid.inputs["Rotation"])
    g.link(rigid.inputs["Scale"], g.combine(scale, scale, scale) if plan["extended"] else (1.0, 1.0, 1.0))
    # the bent instances: the points' own positions kept, each copy realized at the origin
    keep = g.node("GeometryNodeStoreNamedAttribute", data_type="FLOAT_VECTOR", domain="POINT")
    tree.links.new(group_in.outputs["Geometry"], keep.inputs["Geometry"])
    keep.inputs["Name"].default_value = "axial_position"
    pos = g.node("GeometryNodeInputPosition")
    tree.links.new(pos.outputs[0], keep.inputs["Value"])
    origin = g.node("GeometryNodeSetPosition")
    tree.links.new(keep.outputs[0], origin.inputs["Geometry"])
    origin.inputs["Position"].default_value = (0.0, 0.0, 0.0)
    rest = g.node("GeometryNodeStoreNamedAttribute", data_type="FLOAT_VECTOR", domain="POINT")
    tree.links.new(base.outputs["Geometry"], rest.inputs["Geometry"])
    rest.inputs["Name"].default_value = "axial_rest_position"
    tree.links.new(g.node("GeometryNodeInputPosition").outputs[0], rest.inputs["Value"])
    copies = g.node("GeometryNodeInstanceOnPoints")
    tree.links.new(origin.outputs[0], copies.inputs["Points"])
    tree.links.new(rest.outputs[0], copies.inputs["Instance"])
    real = g.node("GeometryNodeRealizeInstances")
    tree.links.new(copies.outputs[0], real.inputs["Geometry"])
    moved, normal = _bend(g, plan, _wind_push(g, group_in))
    world = _rotate(g, moved, angles) + g.attribute("axial_position", "FLOAT_VECTOR")
    place = g.node("GeometryNodeSetPosition")
    tree.links.new(real.outputs[0], place.inputs["Geometry"])
    g.link(place.inputs["Position"], world)
    bent = place
    if hasattr(bpy.types, "GeometryNodeSetMeshNormal"):  # Blender 4.5 and later: the exact normals as custom normals (earlier: its own)
        normals = g.node("GeometryNodeSetMeshNormal", mode="FREE", domain="POINT")
        tree.links.new(place.outputs[0], normals.inputs["Mesh"])
        g.link(normals.inputs["Custom Normal"], _rotate(g, normal, angles))
        bent = normals
    # Is Viewport and not Bend in Viewport: the rigid instances
    viewport = g.node("GeometryNodeIsViewport")
    quick = g.node("FunctionNodeBooleanMath", operation="NIMPLY")
    tree.links.new(viewport.outputs[0], quick.inputs[0])
    tree.links.new(group_in.outputs["Bend in Viewport"], quick.inputs[1])
    choose = g.node("GeometryNodeSwitch", input_type="GEOMETRY")
    tree.links.new(quick.outputs[0], choose.inputs["Switch"])
    tree.links.new(bent.outputs[0], choose.inputs["False"])
    tree.links.new(rigid.outputs[0], choose.inputs["True"])
    tree.links.new(choose.outputs[0], group_out.inputs[0])
    return tree
