"""Real assets: UVs, vertex colours, materials, multi-part meshes,
from the file to the picture to glTF/OBJ and back."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import axialdeform as ad
from axialdeform.core.deform import deform_tangents
from axialdeform.core.errors import ContextError, MeshError
from axialdeform.core.material import AssetWarning, compute_tangents

from conftest import ALPHA_TEST, data_mesh
from conftest import validate_gltf as _validate


def _textured_card(folder: Path, *, mtl="card.mtl", texture="tex.png", cut=True) -> Path:
    """A 1 x 2 card with UVs and an .mtl/.png: the texture's left half is red, the right
    half blue; with ``cut`` the left half's alpha is 0 (a cut-out)."""
    from PIL import Image

    img = np.zeros((8, 8, 4), np.uint8)
    img[..., 3] = 255
    img[:, :4, 0] = 255
    img[:, 4:, 2] = 255
    if cut:
        img[:, :4, 3] = 0
    Image.fromarray(img, "RGBA").save(folder / "tex.png")
    (folder / "card.mtl").write_text(f"newmtl Leafy\nKd 1 1 1\nmap_Kd {texture}\n")
    obj = folder / "card.obj"
    obj.write_text(f"mtllib {mtl}\no card\nv 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\n"
                   "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\n"
                   "usemtl Leafy\nf 1/1/1 2/2/2 3/3/3\nf 1/1/1 3/3/3 4/4/4\n")
    return obj


# ------------------------------------------------------------------ loading


def test_alpha_blend_mode_test_loads_nine_parts_one_axis():
    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    assert len(mesh.parts) == 9
    assert sum(p.count for p in mesh.parts) == len(mesh.faces)
    modes = {p.name: (p.material.alpha_mode, p.material.alpha_cutoff) for p in mesh.parts}
    assert modes["TestCutoff25"] == ("MASK", 0.25) and modes["TestCutoff75"] == ("MASK", 0.75)
    assert modes["TestCutoffDefault"] == ("MASK", 0.5)
    assert modes["TestBlend"][0] == "BLEND" and modes["TestOpaque"][0] == "OPAQUE"
    assert all(p.material.texture is not None for p in mesh.parts)
    assert mesh.uvs.shape == (mesh.vertex_count, 2)
    bed = mesh.part("Bed").material
    assert bed.normal_texture is not None and mesh.tangents is not None  # tangents computed for the normal map
    # ONE control axis over every vertex of every part
    extent = mesh.positions.max(axis=0) - mesh.positions.min(axis=0)
    assert mesh.axis.index == int(np.argmax(extent)) and np.isclose(mesh.axis.length, extent.max())
    with pytest.raises(MeshError, match="no part 'Nope'; expected one of 'TestCutoff25'"):
        mesh.part("Nope")


def test_obj_objects_become_parts_in_the_file_vertex_order():
    path = data_mesh("edge_cases/two_objects.obj")
    mesh = ad.load_mesh(path)
    assert [p.name for p in mesh.parts] == ["cube", "tetra"]
    merged = trimesh.load(path, process=False)  # what the file held before parts existed
    assert np.array_equal(mesh.positions, np.asarray(merged.vertices, np.float32))
    assert np.array_equal(mesh.faces, merged.faces)  # same fingerprint as before


def test_several_meshes_in_one_file_are_parts():
    for rel, parts in (("edge_cases/multibody.stl", 2), ("gltf/simple_pole.glb", 11)):
        mesh = ad.load_mesh(data_mesh(rel))
        assert len(mesh.parts) == parts, rel


def test_vertex_colours_and_textures():
    vc = ad.load_mesh(data_mesh("gltf/cubevc.glb"))
    assert vc.colors.shape == (vc.vertex_count, 4)
    assert np.allclose(vc.colors, [1, 0, 1, 1])  # the file's COLOR_0 is magenta throughout
    quads = ad.load_mesh(data_mesh("edge_cases/box_vertex_colors_quads_moderngl.obj"))
    assert quads.colors is not None and np.allclose(quads.colors[0], [1, 0, 0, 1])
    assert len(np.unique(quads.colors.round(3), axis=0)) > 1
    box = ad.load_mesh(data_mesh("gltf/BoxTextured.glb"))
    assert box.uvs.shape == (24, 2) and box.parts[0].material.texture.shape[2] == 4


def test_obj_with_mtl_and_png(tmp_path):
    mesh = ad.load_mesh(_textured_card(tmp_path))
    m = mesh.parts[0].material
    assert m.name == "Leafy" and m.alpha_mode == "MASK"  # the texture has holes: a cut-out
    assert m.texture.shape == (8, 8, 4)
    assert np.allclose(mesh.uvs, [[0, 0], [1, 0], [1, 1], [0, 1]])


def test_missing_or_special_texture_warns_and_loads(tmp_path):
    obj = _textured_card(tmp_path, texture="gone.png")
    with pytest.warns(AssetWarning, match=r"card.obj: 'gone.png' .* material 'Leafy' drawn with its base colour"):
        mesh = ad.load_mesh(obj)
    assert mesh.parts[0].material.texture is None
    # a FIFO as texture is never opened: the load finishes (in a child, so a hang fails by timeout)
    fifo = tmp_path / "pipe.png"
    import os

    os.mkfifo(fifo)
    _textured_card(tmp_path, texture="pipe.png")
    code = ("import warnings, axialdeform as ad\n"
            "with warnings.catch_warnings(record=True) as w:\n"
            "    warnings.simplefilter('always')\n"
            f"    m = ad.load_mesh({str(obj)!r})\n"
            "print(m.parts[0].material.texture is None, [str(x.message) for x in w])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("True") and "pipe.png" in out.stdout and "not a regular file" in out.stdout


def test_uv_and_colour_count_mismatch_is_a_mesh_error():
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    nrm = np.tile([0.0, 0, 1], (3, 1))
    faces = np.array([[0, 1, 2]])
    with pytest.raises(MeshError, match=r"tri.obj: 2 texture coordinates for 3 vertices"):
        ad.BaseMesh(pos, nrm, faces, name="tri.obj", uvs=np.zeros((2, 2)))
    with pytest.raises(MeshError, match=r"tri.obj: 4 vertex colours for 3 vertices"):
        ad.BaseMesh(pos, nrm, faces, name="tri.obj", colors=np.ones((4, 4)))


def test_tangents_follow_the_uv_frame():
    # a flat card in z = 0 whose u runs along +x: tangent +x, handedness +1; mirrored u: -x
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    nrm = np.tile([0.0, 0, 1], (4, 1))
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    uv = pos[:, :2]
    t = compute_tangents(pos, nrm, uv, faces)
    assert np.allclose(t, [[1, 0, 0, 1]] * 4, atol=1e-6)
    t = compute_tangents(pos, nrm, np.column_stack([1 - uv[:, 0], uv[:, 1]]), faces)
    assert np.allclose(t, [[-1, 0, 0, -1]] * 4, atol=1e-6)


# ------------------------------------------------------------------ GPU


def test_gpu_capture_equals_cpu_for_every_part(ctx):
    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    params = ad.random_params(mesh, 40, seed=3, variation=ad.Variation(bend=0.2))
    cpu_pos, cpu_nrm = ad.deform(mesh.axis, mesh.positions, mesh.normals, params)
    with ad.AxialRenderer(ctx, mesh, params) as r:
        pos, nrm = r.capture()
    tol = 1e-5 * mesh.axis.length
    for part in mesh.parts:
        used = np.unique(mesh.faces[part.start:part.start + part.count])
        assert np.abs(pos[:, used] - cpu_pos[:, used]).max() <= tol, part.name
        assert np.abs(nrm[:, used] - cpu_nrm[:, used]).max() <= 1e-4, part.name


@pytest.mark.parametrize("form", ["16", "extended", "extended+wind"])
def test_gpu_tangents_bend_by_the_jacobian(ctx, form):
    """axial_world_tangent (glsl/axial.glsl) against deform_tangents, and both
    stay orthogonal to the bent normal (a tangent by J, a normal by cof(J)),
    for 16-number instances and for extended ones (scale, twist, taper), also
    in the wind (which moves control points: the CPU side takes the moved ones)."""
    from axialdeform.core.wind import Wind, apply_wind
    from axialdeform.gl.buffers import InstanceBuffer, MeshBuffers
    from axialdeform.gl.material import AppearanceBuffer
    from axialdeform.gl.shaders import build_program
    from axialdeform.gl.uniforms import set_uniforms

    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    extended = form != "16"
    extra = dict(scale=(0.7, 1.3), twist=0.8, taper=0.5) if extended else {}
    params = ad.random_params(mesh, 16, seed=5, variation=ad.Variation(bend=0.3, **extra))
    assert params.shape[1] == (19 if extended else 16)
    defines = {"AXIAL_MATERIAL": 1, **({"AXIAL_EXTENDED": 1} if extended else {}),
               **({"AXIAL_WIND": 1} if "wind" in form else {})}  # the windy build (still builds leave it out)
    prog = build_program(ctx, "scene.vert", defines=defines, varyings=("v_tangent",))
    buffers, look = MeshBuffers(ctx, mesh), AppearanceBuffer(ctx, mesh)
    inst = InstanceBuffer(ctx, params, extended=extended)
    i, j = mesh.axis.perpendicular
    set_uniforms(prog, {"u_axis": mesh.axis.index, "u_lo": mesh.axis.lo, "u_len": mesh.axis.length,
                        "u_center": (mesh.axis.center[i], mesh.axis.center[j]), "u_instance_base": 0,
                        "u_wind_strength": 0.0})
    wind, time = (Wind(direction=(1.0, 0.0, 0.5), strength=0.3, gustiness=0.5), 1.7) if "wind" in form else (None, 0.0)
    if wind is not None:  # the uniforms AxialRenderer sets for a wind
        prog["u_wind_strength"].value = wind.strength
        prog["u_wind_dir"].value = tuple(wind.unit_direction)
        prog["u_wind_gust"].value = wind.gustiness
        prog["u_wind_cycles"].value = tuple(wind.cycles(time))
        prog["u_wind_wavenumber"].value = wind.wavenumber
    vao = ctx.vertex_array(prog, [buffers.content(prog), inst.content(prog), look.content(prog)])
    out = ctx.buffer(reserve=len(params) * mesh.vertex_count * 16)
    color = ctx.renderbuffer((1, 1))
    fbo = ctx.framebuffer(color)
    previous = ctx.fbo
    fbo.use()
    import moderngl

    from axialdeform.gl.context import bind_framebuffer, release_framebuffer

    vao.transform(out, mode=moderngl.POINTS, vertices=mesh.vertex_count, instances=len(params))
    gpu = np.frombuffer(out.read(), "f4").reshape(len(params), mesh.vertex_count, 4)
    bind_framebuffer(ctx, previous)
    release_framebuffer(ctx, fbo)
    for obj in (vao, out, prog, color):
        obj.release()
    for obj in (buffers, inst, look):
        obj.release()
    moved = apply_wind(wind, mesh.axis, params, time)
    assert (wind is None) == np.array_equal(moved, params)
    cpu = deform_tangents(mesh.axis, mesh.positions, mesh.tangents, moved)
    assert np.abs(gpu[..., :3] - cpu).max() < 1e-4
    assert np.array_equal(gpu[..., 3], np.broadcast_to(mesh.tangents[:, 3], gpu.shape[:2]))
    _, normals = ad.deform(mesh.axis, mesh.positions, mesh.normals, moved)
    base_dot = np.einsum("vi,vi->v", mesh.tangents[:, :3], mesh.normals)
    bent_dot = np.einsum("nvi,nvi->nv", cpu, normals)
    assert np.abs(bent_dot - base_dot).max() < 1e-3  # J t . cof(J) n / |..| keeps t.n = 0


def _front_camera(mesh, params):
    return ad.frame_instances(mesh, params, 1.0, elevation=0.0, azimuth=90.0, margin=0.05)


def test_texture_and_cutout_drawn(ctx, tmp_path):
    mesh = ad.load_mesh(_textured_card(tmp_path))
    params = np.zeros((1, 16), np.float32)
    bg = (0.0, 0.0, 0.0)
    img = ad.render_image(mesh, params, (64, 64), "solid", ctx=ctx, camera=_front_camera(mesh, params),
                          look=ad.Look(background=bg, fast=True, ambient=1.0)).astype(int)
    # the card's red half (u < 0.5) is cut out: only the blue half is drawn
    def columns(image):
        return int((image.sum(axis=2) > 30).any(axis=0).sum())

    def red(image):
        return int(((image[..., 0] > 2 * image[..., 2]) & (image[..., 0] > 60)).sum())

    def blue(image):
        return int(((image[..., 2] > 2 * image[..., 0]) & (image[..., 2] > 60)).sum())

    assert red(img) == 0 and blue(img) > 100
    # without the cut (an opaque texture) the red half shows too, and the card is twice as wide
    opaque = ad.load_mesh(_textured_card(tmp_path, cut=False))
    img2 = ad.render_image(opaque, params, (64, 64), "solid", ctx=ctx, camera=_front_camera(opaque, params),
                           look=ad.Look(background=bg, fast=True, ambient=1.0)).astype(int)
    assert red(img2) > 100 and blue(img2) > 100
    assert 1.6 < columns(img2) / columns(img) < 2.4


def test_missing_texture_part_drawn_with_base_colour(ctx, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AssetWarning)
        mesh = ad.load_mesh(_textured_card(tmp_path, texture="gone.png"))
    params = np.zeros((1, 16), np.float32)
    img = ad.render_image(mesh, params, (48, 48), "solid", ctx=ctx, camera=_front_camera(mesh, params),
                          look=ad.Look(background=(0, 0, 0), fast=True))
    drawn = img[img.sum(axis=2) > 0]
    assert len(drawn) > 200  # the whole card, in its (white) base colour
    assert (np.abs(drawn[:, 0].astype(int) - drawn[:, 2]) < 40).all()


def test_texture_too_large_is_a_clear_error(tmp_path):
    from axialdeform.gl.material import GpuMaterials

    class SmallContext:  # a context whose limit is 4 pixels: refused before any GL call
        info = {"GL_MAX_TEXTURE_SIZE": 4}
        max_anisotropy = 1.0

    mesh = ad.load_mesh(_textured_card(tmp_path))
    with pytest.raises(ContextError, match=r"card.obj: the base colour texture of material 'Leafy' is 8x8 pixels; "
                                           r"this GL context allows at most 4x4"):
        GpuMaterials(SmallContext(), mesh)


def test_one_instanced_draw_per_part_and_part_choice(ctx, monkeypatch):
    import moderngl

    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    params = ad.random_params(mesh, 30, seed=2)
    calls = []
    original = moderngl.VertexArray.render

    def spy(self, *args, **kwargs):
        calls.append((kwargs.get("instances"), kwargs.get("vertices")))
        return original(self, *args, **kwargs)

    original_indirect = moderngl.VertexArray.render_indirect

    def spy_indirect(self, buffer, mode=None, count=-1, first=0):  # the culled draw on GL >= 4.3: the GPU's command
        command = np.frombuffer(buffer.read(size=20, offset=20 * first), "<u4")
        calls.append((int(command[1]), int(command[0])))
        return original_indirect(self, buffer, mode, count, first)

    monkeypatch.setattr(moderngl.VertexArray, "render", spy)
    monkeypatch.setattr(moderngl.VertexArray, "render_indirect", spy_indirect)
    full = ad.render_image(mesh, params, (96, 72), "solid", ctx=ctx, look=ad.Look(fast=True))
    assert sorted(v for _, v in calls) == sorted(p.count * 3 for p in mesh.parts)
    assert all(n == 30 for n, _ in calls)
    calls.clear()
    bed = ad.render_image(mesh, params, (96, 72), "solid", ctx=ctx, options=ad.RenderOptions(parts=["Bed"]), look=ad.Look(fast=True))
    assert calls == [(30, mesh.part("Bed").count * 3)]
    assert not np.array_equal(full, bed)
    with pytest.raises(MeshError, match="no part 'Nope'"):
        ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(parts=["Nope"]))


def test_shadows_darken_the_ground_and_hidden_lines_hide(ctx, stone):
    params = ad.random_params(stone, 60, seed=4, variation=ad.Variation(bend=0.1), spacing=2.0 * stone.axis.length)
    with_shadow = ad.render_image(stone, params, (160, 120), "solid", ctx=ctx, look=ad.Look(samples=0))
    # the ground without shadows
    no_shadow = ad.render_image(stone, params, (160, 120), "solid", ctx=ctx, look=ad.Look(samples=0, shadow=False))
    darker = (with_shadow.astype(int).sum(axis=2) < no_shadow.astype(int).sum(axis=2) - 30).mean()
    assert darker > 0.01, f"{darker:.1%} of the pixels darker with shadows"
    lines = ad.Look(background=(0, 0, 0), line_color=(1, 1, 1), samples=0, ground=False, shadow=False)
    few = params[:4]  # big on the screen: the back edges are apart from the front ones
    hidden = ad.render_image(stone, few, (320, 240), "wireframe", ctx=ctx, look=lines.replace(hidden_line=True))
    every = ad.render_image(stone, few, (320, 240), "wireframe", ctx=ctx, look=lines.replace(fast=True))
    on_hidden, on_every = (hidden.sum(axis=2) > 100).sum(), (every.sum(axis=2) > 100).sum()
    assert 0 < on_hidden < 0.8 * on_every, (on_hidden, on_every)  # back lines removed
    assert ((hidden.sum(axis=2) > 100) & ~(every.sum(axis=2) > 100)).sum() <= 0.02 * on_hidden
    # the default fills the faces (washed out) under the front lines, with the dark line colour
    filled = ad.render_image(stone, few, (320, 240), "wireframe", ctx=ctx,
                             look=ad.Look(samples=0, ground=False, background=(0, 0, 0), line_color=(0, 0, 0)))
    solid = ad.render_image(stone, few, (320, 240), "solid", ctx=ctx, look=ad.Look(fast=True, background=(0, 0, 0)))
    covered, silhouette = (filled.astype(int).sum(axis=2) > 30), (solid.astype(int).sum(axis=2) > 30)
    assert (covered & silhouette).sum() >= 0.95 * silhouette.sum()  # the faces, not just lines
    assert ((hidden.astype(int).sum(axis=2) > 30) & silhouette).sum() < 0.9 * silhouette.sum()


# ------------------------------------------------------------------ out again


def test_exported_glbs_keep_the_material_and_pass_the_validator(tmp_path):
    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    params = ad.random_params(mesh, 3, seed=1)
    from axialdeform.core.io.gltf import export_baked, export_instanced, read_instanced_glb

    baked, inst = export_baked(tmp_path / "b.glb", mesh, params), export_instanced(tmp_path / "i.glb", mesh, params)
    for report in _validate(baked, inst):
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    for path in (baked, inst):
        scene = trimesh.load(path)
        textured = [g for g in scene.geometry.values() if getattr(g.visual.material, "baseColorTexture", None) is not None]
        assert textured and textured[0].visual.uv is not None
        modes = {g.visual.material.alphaMode for g in scene.geometry.values()}
        assert {"MASK", "BLEND"} <= modes
    back, p = read_instanced_glb(inst)
    assert back.fingerprint == mesh.fingerprint and np.array_equal(p, params)


def test_vertex_colour_glb_passes_the_validator(tmp_path):
    from axialdeform.core.io.gltf import export_baked

    mesh = ad.load_mesh(data_mesh("gltf/cubevc.glb"))
    path = export_baked(tmp_path / "vc.glb", mesh, ad.random_params(mesh, 2, seed=1))
    assert _validate(path)[0]["issues"]["numErrors"] == 0
    _assert_vertex_colours(path, mesh)


def test_bake_obj_writes_vt_mtllib_and_the_texture(tmp_path):
    from axialdeform.cli import main

    obj = _textured_card(tmp_path)
    assert main(["random", str(obj), "-n", "3", "-o", str(tmp_path / "p.adp")]) == 0
    out = tmp_path / "baked"
    assert main(["bake", str(obj), str(tmp_path / "p.adp"), "-o", str(out), "--format", "obj"]) == 0
    text = (out / "instance_000000.obj").read_text()
    assert "mtllib material.mtl" in text and "\nvt " in text
    back = trimesh.load(out / "instance_000002.obj", process=False)
    assert back.visual.uv.shape == (4, 2)
    assert np.asarray(back.visual.material.image).shape[:2] == (8, 8)
    for fmt in ("glb", "ply"):
        folder = tmp_path / fmt
        assert main(["bake", str(obj), str(tmp_path / "p.adp"), "-o", str(folder), "--format", fmt]) == 0
        g = trimesh.load(folder / f"instance_000001.{fmt}", force="mesh", process=False)
        assert g.visual.uv is not None and len(g.visual.uv) == 4


def test_cli_render_part_and_unknown_part(tmp_path, capsys):
    from axialdeform.cli import main

    mesh = str(data_mesh("edge_cases/two_objects.obj"))
    assert main(["random", mesh, "-n", "4", "-o", str(tmp_path / "p.adp")]) == 0
    assert main(["render", mesh, str(tmp_path / "p.adp"), "-o", str(tmp_path / "x.png"), "--size", "64x48",
                 "--part", "tetra", "--fast"]) == 0
    capsys.readouterr()
    assert main(["render", mesh, str(tmp_path / "p.adp"), "-o", str(tmp_path / "y.png"), "--size", "64x48",
                 "--part", "sphere"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no part 'sphere'; expected one of 'cube', 'tetra'" in err[0]


def test_bundled_leaf_card():
    mesh = ad.load_mesh("leafcard")
    m = mesh.parts[0].material
    assert m.alpha_mode == "MASK" and m.double_sided and m.texture is not None
    alpha = m.texture[..., 3]
    assert (alpha == 0).mean() > 0.2 and (alpha == 255).mean() > 0.2  # a real cut-out
    assert mesh.axis.name == "y" and mesh.uvs is not None


def test_flat_and_wireframe_work_for_textured_parts(ctx):
    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    params = ad.random_params(mesh, 6, seed=4, variation=ad.Variation(bend=0.1))
    img = ad.render_image(mesh, params, (128, 96), ("solid", "flat", "wireframe"), ctx=ctx,
                          look=ad.Look(ground=False, background=(0, 0, 0)))
    panels = [img[:, i * 128:(i + 1) * 128].astype(int).sum(axis=2) > 30 for i in range(3)]
    assert all(p.mean() > 0.02 for p in panels)
    assert not np.array_equal(img[:, :128], img[:, 128:256])  # flat shading differs from smooth


def test_normal_map_changes_the_shading(ctx):
    import dataclasses

    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    # the file's normal map is subtle; a strong one (wide stripes tilted +-40 degrees about v) shows the path works
    stripes = np.zeros((64, 64, 4), np.uint8)
    tilt = np.where((np.arange(64) // 8) % 2 == 0, 0.64, -0.64)
    stripes[..., 0] = np.round((tilt[None, :] * 0.5 + 0.5) * 255)
    stripes[..., 1] = 128
    stripes[..., 2] = np.round((np.sqrt(1 - tilt**2)[None, :] * 0.5 + 0.5) * 255)
    stripes[..., 3] = 255

    def with_normal_map(image):
        parts = tuple(dataclasses.replace(p, material=dataclasses.replace(p.material, normal_texture=image))
                      for p in mesh.parts)
        return dataclasses.replace(mesh, parts=parts, _axis=None)

    plain, bumpy = with_normal_map(None), with_normal_map(stripes)
    params = np.zeros((1, 16), np.float32)
    cam = ad.frame_instances(mesh, params, 4 / 3, elevation=10.0, azimuth=90.0, margin=-0.3)
    kw = dict(ctx=ctx, camera=cam, look=ad.Look(fast=True), options=ad.RenderOptions(parts=["Bed"]))
    a = ad.render_image(bumpy, params, (160, 120), "solid", **kw).astype(int)
    b = ad.render_image(plain, params, (160, 120), "solid", **kw).astype(int)
    differ = (np.abs(a - b).sum(axis=2) > 6).mean()
    assert differ > 0.02, f"the normal map changed {differ:.1%} of the pixels"


def test_textures_are_sampled_as_srgb(ctx, tmp_path):
    """A texture of sRGB 128 grey draws like an untextured base colour of its
    linear value (0.216), not like 0.5: the texture is decoded as sRGB."""
    import dataclasses

    from axialdeform.core.material import srgb_to_linear

    mesh = ad.load_mesh(_textured_card(tmp_path, cut=False))
    grey = np.full((16, 16, 4), 128, np.uint8)
    grey[..., 3] = 255

    def with_material(**kw):
        part = mesh.parts[0]
        return dataclasses.replace(mesh, parts=(dataclasses.replace(part, material=dataclasses.replace(part.material, **kw)),),
                                   _axis=None)

    textured = with_material(texture=grey, base_color=(1, 1, 1, 1))
    linear = float(srgb_to_linear(128 / 255))
    coloured = with_material(texture=None, base_color=(linear, linear, linear, 1))
    wrong = with_material(texture=None, base_color=(0.5, 0.5, 0.5, 1))
    params = np.zeros((1, 16), np.float32)
    kw = dict(ctx=ctx, camera=_front_camera(mesh, params), look=ad.Look(fast=True, background=(0, 0, 0)))
    a, b, c = (ad.render_image(m, params, (48, 48), "solid", **kw).astype(int) for m in (textured, coloured, wrong))
    inside = b.sum(axis=2) > 0
    assert inside.mean() > 0.05
    assert np.abs(a - b)[inside].max() <= 3
    assert np.abs(c - b)[inside].mean() > 20  # the test would see a linear upload


def test_gltf_with_a_missing_or_fifo_image_still_loads(tmp_path):
    import os

    files = trimesh.load(data_mesh("gltf/BoxTextured.glb")).export(file_type="gltf")
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    doc = json.loads((tmp_path / "model.gltf").read_text())
    for uri in ("missing.png", "pipe.png"):
        doc["images"] = [{"uri": uri}]
        (tmp_path / f"{uri}.gltf").write_text(json.dumps(doc))
    with pytest.warns(AssetWarning, match=r"missing.png.gltf: 'missing.png' .* material 'Texture' drawn with its base"):
        mesh = ad.load_mesh(tmp_path / "missing.png.gltf")
    assert mesh.parts[0].material.texture is None and mesh.uvs is not None
    os.mkfifo(tmp_path / "pipe.png")
    code = f"import axialdeform as ad; m = ad.load_mesh({str(tmp_path / 'pipe.png.gltf')!r}); print(m.parts[0].material.texture)"
    out = subprocess.run([sys.executable, "-W", "always", "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and out.stdout.strip() == "None", out.stderr
    assert "'pipe.png' (texture or material file) is not a regular file" in out.stderr


@pytest.mark.slow
@pytest.mark.parametrize("indirect", [True, False], ids=["indirect", "query"])
def test_parts_draw_from_the_culled_instances(ctx, indirect):
    """The cull pass runs once a frame and every part's instanced draw reads its
    compacted output: with shadows, multisampling and hidden-line wireframe the
    picture equals the unculled one pixel for pixel, with most instances dropped
    (indirect: one draw command per part, filled in by the compute pass)."""
    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    assert len(mesh.parts) > 1
    n, length = 40, mesh.axis.length
    params = ad.random_params(mesh, n, seed=2, variation=ad.Variation(bend=0.2))
    params[:, 10:13] = 0.0
    params[:, 10] = np.arange(n) * 2.0 * length  # a row along x
    cam = ad.Camera(eye=(2.0 * length, 0.5 * length, 6.0 * length), target=(2.0 * length, 0.5 * length, 0.0),
                    fovy=35.0, near=0.01 * length, far=100.0 * length)
    with ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(indirect=indirect)) as culled, \
            ad.AxialRenderer(ctx, mesh, params, options=ad.RenderOptions(culling=False)) as full:
        for mode in ("solid", "wireframe"):
            a = ad.render_image(mesh, params, (96, 64), mode, ctx=ctx, camera=cam, options=ad.RenderOptions(renderer=full))
            b = ad.render_image(mesh, params, (96, 64), mode, ctx=ctx, camera=cam, options=ad.RenderOptions(renderer=culled))
            assert full.stats["visible"] == n and not full.stats["culling"]
            assert culled.stats["culling"] and 0 < culled.stats["visible"] < n // 4, culled.stats
            assert culled.stats["indirect"] == indirect
            assert np.array_equal(a, b), (mode, int((a != b).any(axis=2).sum()))
            assert len(np.unique(a.reshape(-1, 3), axis=0)) > 10  # something is drawn
    assert ctx.error == "GL_NO_ERROR"


def test_lod_of_a_mesh_with_parts_is_drawn_not_refused(ctx):
    """LOD works part by part (tests/gl/test_lod_assets.py); this file's parts are
    all too small to simplify, so it keeps one level and says so."""
    mesh = ad.load_mesh(data_mesh(ALPHA_TEST))
    with pytest.warns(UserWarning, match="too few to simplify"):
        with ad.AxialRenderer(ctx, mesh, ad.random_params(mesh, 4, seed=1), options=ad.RenderOptions(lod=True)) as r:
            assert r.lod and len(r.lod_levels) == 1
    assert ctx.error == "GL_NO_ERROR"


# ------------------------------------------------------------------ the file's own tangents, PLY parts


def _gltf_tangents(path):
    """Every primitive's TANGENT of a GLB, read with pygltflib (independent of the loader)."""
    import pygltflib

    from axialdeform.core.io.glb import read_accessor

    g = pygltflib.GLTF2.load(str(path))
    blob = g.binary_blob()
    return [read_accessor(g, blob, p.attributes.TANGENT, "TANGENT", str(path))
            for m in g.meshes for p in m.primitives if p.attributes.TANGENT is not None]


def _with_tangents(src, dst, change):
    """A copy of the GLB ``src`` whose (tightly packed) TANGENT data is ``change(tangents, normals)``."""
    import pygltflib

    from axialdeform.core.io.glb import read_accessor

    g = pygltflib.GLTF2.load(str(src))
    blob = bytearray(g.binary_blob())
    a = g.meshes[0].primitives[0].attributes
    acc = g.accessors[a.TANGENT]
    view = g.bufferViews[acc.bufferView]
    assert view.byteStride in (None, 16)
    new = change(read_accessor(g, bytes(blob), a.TANGENT, "T", ""), read_accessor(g, bytes(blob), a.NORMAL, "N", ""))
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    blob[start:start + new.nbytes] = np.ascontiguousarray(new, "<f4").tobytes()
    g.set_binary_blob(bytes(blob))
    g.save_binary(str(dst))
    return dst


def test_tangents_stored_in_the_file_are_used_and_written_back(tmp_path):
    """cubevc.glb (trimesh's test model) carries TANGENT; trimesh drops it, the loader
    reads it in the file's vertex order, and export writes it back unchanged."""
    from axialdeform.core.io.gltf import export_baked, export_instanced

    src = data_mesh("gltf/cubevc.glb")
    mesh = ad.load_mesh(src)
    assert mesh.uvs is not None  # TEXCOORD_0 of a primitive without a material, also dropped by trimesh
    computed = compute_tangents(mesh.positions, mesh.normals, mesh.uvs, mesh.faces)
    assert np.array_equal(mesh.tangents, _gltf_tangents(src)[0])
    # cubevc's own tangents happen to equal the computed ones: turn them 90 degrees
    # about the normal and flip the handedness, so only the file can be their source
    path = _with_tangents(src, tmp_path / "turned.glb", lambda t, n: np.column_stack([np.cross(n, t[:, :3]), -t[:, 3]]))
    (file_tangents,) = _gltf_tangents(path)
    assert np.abs(np.einsum("ij,ij->i", file_tangents[:, :3], computed[:, :3])).max() < 1e-6
    mesh = ad.load_mesh(path)
    assert mesh.tangents is not None and np.array_equal(mesh.tangents, file_tangents)
    identity = np.zeros((2, 16), np.float32)
    baked = export_baked(tmp_path / "b.glb", mesh, identity)
    inst = export_instanced(tmp_path / "i.glb", mesh, identity)
    for report in _validate(baked, inst):
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    out = _gltf_tangents(baked)
    assert len(out) == 2
    for t in out:  # identity instances: the bend's Jacobian is I
        assert np.allclose(t[:, :3], file_tangents[:, :3], atol=1e-6) and np.array_equal(t[:, 3], file_tangents[:, 3])
    assert np.array_equal(_gltf_tangents(inst)[0], file_tangents)  # the base mesh: bit for bit


def test_bake_glb_writes_the_bent_tangents(tmp_path):
    from axialdeform.cli import main

    mesh_path = str(data_mesh("gltf/cubevc.glb"))
    assert main(["random", mesh_path, "-n", "2", "-o", str(tmp_path / "p.adp")]) == 0
    out = tmp_path / "glb"
    assert main(["bake", mesh_path, str(tmp_path / "p.adp"), "-o", str(out), "--format", "glb"]) == 0
    mesh = ad.load_mesh(mesh_path)
    params = ad.read_params(tmp_path / "p.adp", mesh)
    expected = deform_tangents(mesh.axis, mesh.positions, mesh.tangents, params)
    for i in range(2):
        path = out / f"instance_00000{i}.glb"
        assert _validate(path)[0]["issues"]["numErrors"] == 0
        (t,) = _gltf_tangents(path)
        assert np.allclose(t[:, :3], expected[i], atol=1e-6) and np.array_equal(t[:, 3], mesh.tangents[:, 3])
        _assert_vertex_colours(path, mesh)


def _assert_vertex_colours(path, mesh) -> None:
    """The colours came along (COLOR_0), under a material with render's colour for a plain part
    (render draws vertex colours times it)."""
    import pygltflib

    g = pygltflib.GLTF2().load(str(path))
    prim = g.meshes[0].primitives[0]
    assert prim.attributes.COLOR_0 is not None
    factor = g.materials[prim.material].pbrMetallicRoughness.baseColorFactor
    assert np.allclose(factor[:3], ad.core.material.default_color(mesh), atol=1e-6)


def test_gltf_tangents_under_a_mirroring_node(tmp_path):
    """A node transform turns the file's tangents by its linear part; a mirror flips w."""
    import pygltflib

    src = data_mesh("gltf/cubevc.glb")
    g = pygltflib.GLTF2.load(str(src))
    (file_tangents,) = _gltf_tangents(src)
    g.nodes[g.scenes[g.scene or 0].nodes[0]].matrix = [-2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
    path = tmp_path / "mirrored.glb"
    g.save_binary(str(path))
    mesh = ad.load_mesh(path)
    want = file_tangents.copy()
    want[:, 0] *= -1  # x scaled by -2, then normalised
    want[:, :3] /= np.linalg.norm(want[:, :3], axis=1, keepdims=True)
    want[:, 3] *= -1
    assert np.allclose(mesh.tangents, want, atol=1e-6)


def test_ply_bake_of_a_multi_part_mesh_writes_one_file_per_part(tmp_path):
    from axialdeform.cli import main

    mesh_path = str(data_mesh(ALPHA_TEST))
    mesh = ad.load_mesh(mesh_path)
    assert main(["random", mesh_path, "-n", "2", "-o", str(tmp_path / "p.adp")]) == 0
    out = tmp_path / "ply"
    assert main(["bake", mesh_path, str(tmp_path / "p.adp"), "-o", str(out), "--format", "ply"]) == 0
    names = sorted(p.name for p in out.iterdir())
    from axialdeform.core.bake import instance_name, part_file_names
    from axialdeform.core.io.bake import INSTANCE_FILE

    want = sorted(instance_name(i, 2, ".ply", part=n) for i in range(2) for n in part_file_names(mesh.parts))
    assert names == want and len(names) == 2 * len(mesh.parts)
    positions, _ = ad.bake(mesh, ad.read_params(tmp_path / "p.adp", mesh))
    for part, file_part in zip(mesh.parts, part_file_names(mesh.parts)):
        g = trimesh.load(out / instance_name(1, 2, ".ply", part=file_part), process=False)
        used = np.unique(mesh.faces[part.start:part.start + part.count])
        assert np.allclose(g.vertices, positions[1][used], atol=1e-6)  # this part's vertices only, bent
        assert np.allclose(g.visual.uv, mesh.uvs[used], atol=1e-6)  # UVs kept
        assert len(g.faces) == part.count
    assert all(INSTANCE_FILE.match(n) for n in names)
    # --overwrite with fewer instances removes the stale part files, keeps foreign ones
    (out / "notes.txt").write_text("mine")
    assert main(["random", mesh_path, "-n", "1", "-o", str(tmp_path / "q.adp")]) == 0
    assert main(["bake", mesh_path, str(tmp_path / "q.adp"), "-o", str(out), "--format", "ply", "--overwrite"]) == 0
    left = sorted(p.name for p in out.iterdir())
    assert left == sorted(["notes.txt"] + [instance_name(0, 1, ".ply", part=n) for n in part_file_names(mesh.parts)])


def test_part_file_names_are_safe_and_unique():
    from axialdeform.core.bake import part_file_names
    from axialdeform.core.material import Part

    parts = [Part("a b", 0, 1), Part("a/b", 1, 1), Part("ok-1_x", 2, 1), Part("", 3, 1)]
    assert part_file_names(parts) == ["a_b", "a_b-1", "ok-1_x", "part"]


# ------------------------------------------------------------------ BLEND: alpha-to-coverage, shadows


def _glass_card(alpha: float):
    """A 1 x 1 double-sided card in z = 0 with one BLEND material of the given alpha."""
    from axialdeform.core.material import Material, Part

    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2], [0, 2, 3]], np.uint32)
    glass = Material(name="glass", base_color=(1, 1, 1, alpha), alpha_mode="BLEND", double_sided=True)
    return ad.BaseMesh(pos, np.tile(np.float32([0, 0, 1]), (4, 1)), faces, name="glass",
                       parts=(Part("glass", 0, 2, glass),))


def _two_panes(ctx, mesh, order, coverage, samples=4):
    """A red pane in front of a blue one (overlapping), each its own renderer
    (one instance), drawn in ``order``; the picture."""
    from axialdeform.gl.context import Offscreen
    from axialdeform.gl.renderer import AxialRenderer

    params = np.zeros((2, 1, 16), np.float32)
    params[0, 0, 10:13] = (0.3, 0.2, 0.5)  # red, nearer the camera (+z)
    tint = np.float32([[[1, 0, 0]], [[0, 0, 1]]])
    cam = _front_camera(mesh, params.reshape(2, 16))
    with AxialRenderer(ctx, mesh, params[0]) as red, AxialRenderer(ctx, mesh, params[1]) as blue, \
            Offscreen(ctx, (48, 48), samples=samples) as target:
        panes = [red, blue]
        target.use((1.0, 1.0, 1.0))
        for k in order:
            panes[k].set_tint(tint[k])
            panes[k].alpha_to_coverage = coverage
            panes[k].render(cam.view(), cam.projection(1.0), "solid", look=ad.Look(ambient=1.0))
        return target.read().astype(int)


def test_blend_parts_use_alpha_to_coverage_when_multisampled(ctx):
    mesh = _glass_card(0.5)
    a2c = [_two_panes(ctx, mesh, order, True) for order in ([0, 1], [1, 0])]
    assert np.array_equal(a2c[0], a2c[1])  # order-independent: the nearer pane wins by depth
    # where both panes overlap, the red one hides the blue one behind it
    red_only = _two_panes(ctx, mesh, [0], True)
    blue_only = _two_panes(ctx, mesh, [1], True)
    overlap = (red_only.sum(axis=2) < 700) & (blue_only.sum(axis=2) < 700)
    assert overlap.sum() > 50 and np.array_equal(a2c[0][overlap], red_only[overlap])
    auto = _two_panes(ctx, mesh, [1, 0], None)  # None: a multisampled target picks alpha-to-coverage
    assert np.array_equal(auto, a2c[0])
    # plain blending (no depth writes, unsorted) depends on the order: the test can tell
    plain = [_two_panes(ctx, mesh, order, False) for order in ([0, 1], [1, 0])]
    assert not np.array_equal(plain[0], plain[1])
    # a single-sampled target cannot: None then blends
    single = _two_panes(ctx, mesh, [1, 0], None, samples=0)
    assert np.array_equal(single, _two_panes(ctx, mesh, [1, 0], False, samples=0))


@pytest.mark.parametrize("alpha, casts", [(0.3, False), (0.8, True)])
def test_blend_parts_cast_shadows_where_mostly_opaque(ctx, alpha, casts):
    from axialdeform.gl.renderer import BLEND_DEPTH_CUTOFF, AxialRenderer
    from axialdeform.gl.shadow import ShadowMap

    assert BLEND_DEPTH_CUTOFF == 0.5
    mesh = _glass_card(alpha)
    params = np.zeros((1, 16), np.float32)
    with AxialRenderer(ctx, mesh, params) as r, ShadowMap(ctx, 64) as shadow:
        shadow.fit(mesh, params, (0.0, 0.0, 1.0))
        r.render_shadow(shadow)
        depth = np.frombuffer(shadow.texture.read(), dtype=np.float32)
    assert (depth < 1.0).any() == casts


def test_gltf_text_files_give_their_tangents_too(tmp_path):
    """A .gltf with its buffer as a data URI, or as an external .bin: the same tangents as the GLB."""
    import pygltflib
    from pygltflib import BufferFormat

    src = data_mesh("gltf/cubevc.glb")
    (want,) = _gltf_tangents(src)
    g = pygltflib.GLTF2.load(str(src))
    g.convert_buffers(BufferFormat.DATAURI)
    g.save_json(str(tmp_path / "uri.gltf"))
    g = pygltflib.GLTF2.load(str(src))
    (tmp_path / "cube.bin").write_bytes(g.binary_blob())
    g.buffers[0].uri = "cube.bin"
    g.save_json(str(tmp_path / "ext.gltf"))
    for name in ("uri.gltf", "ext.gltf"):
        mesh = ad.load_mesh(tmp_path / name)
        assert mesh.tangents is not None and np.array_equal(mesh.tangents, want), name


def test_ply_part_files_keep_vertex_colours(tmp_path):
    from axialdeform.core.io.bake import write_mesh_folder
    from axialdeform.core.material import Part, linear_to_srgb

    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [3, 0, 0], [2, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2], [3, 4, 5]], np.uint32)
    colors = np.array([[1, 0, 0, 1]] * 3 + [[0, 0.2, 1, 1]] * 3, np.float32)
    mesh = ad.BaseMesh(pos, np.tile(np.float32([0, 0, 1]), (6, 1)), faces, name="two",
                       colors=colors, parts=(Part("red", 0, 1), Part("blue", 1, 1)))
    params = np.zeros((1, 16), np.float32)
    positions, normals = ad.bake(mesh, params)
    files = write_mesh_folder(tmp_path / "out", mesh, (positions, normals), "ply")
    assert [f.name for f in files] == ["instance_000000_red.ply", "instance_000000_blue.ply"]
    for f, want in zip(files, (colors[0], colors[3])):
        g = trimesh.load(f, process=False)
        srgb = np.round(255 * np.append(linear_to_srgb(want[:3]), want[3])).astype(int)
        assert len(g.vertices) == 3 and (np.abs(g.visual.vertex_colors.astype(int) - srgb) <= 1).all()


def test_textures_pass_through_export_as_the_model_ships_them(tmp_path):
    """A baked GLB carries the model's own image bytes (a JPEG stays that JPEG),
    each encoded at most once: about the size of its source plus its geometry
    (a 1.2 MB model baked to 8.6 MB a file, 45 s for 20, before)."""
    import pygltflib

    from axialdeform.core.io.bake import write_mesh_folder
    from axialdeform.core.io.glb import read_accessor  # noqa: F401 - the module under test

    source = data_mesh(ALPHA_TEST)
    mesh = ad.load_mesh(source)
    params = ad.random_params(mesh, 3, seed=2, variation=ad.Variation(bend=0.1))
    pos, nrm = ad.bake(mesh, params)
    files = write_mesh_folder(tmp_path / "out", mesh, (pos, nrm), "glb", params=params)

    def images(path):
        g = pygltflib.GLTF2.load(str(path))
        blob = g.binary_blob()
        out = []
        for im in g.images:
            view = g.bufferViews[im.bufferView]
            out.append((im.mimeType, blob[view.byteOffset or 0:(view.byteOffset or 0) + view.byteLength]))
        return out

    wanted = images(source)  # (a view of the source may hold padding after the image's end)
    for f in files:
        got = images(f)
        assert got and all(any(m == wm and wb.startswith(b) and len(wb) - len(b) < 4 for wm, wb in wanted)
                           for m, b in got), [m for m, _ in got]  # the model's own bytes and formats
        assert any(m == "image/jpeg" for m, _ in got)  # its JPEGs stay JPEGs
        assert f.stat().st_size < 1.5 * source.stat().st_size
    _validate(*files[:1])
