"""axialdeform-three/webgpu in Chromium: three's WebGPURenderer, its WebGPU backend (SwiftShader's
Vulkan here) and its WebGL 2 fallback, with the oldest three the entry supports (r184: r171 to r181
place every instance wrong and r182 to r183 lose the shadows of updated instances, three bugs
fixed since) and the latest release the tests pin (r187).

The bend there is glsl/axial.glsl and glsl/wind.glsl as three's node functions, generated at build
(js/src/webgpu/glsl_nodes.js by js/build.mjs): these tests hold it to ``axialdeform.deform`` on every feature, draw
what ``render`` draws, cast bent shadows, bake and raycast, and refuse in words what they cannot bend."""

from __future__ import annotations

import base64
import json
import subprocess
import sys
from io import BytesIO
from urllib.parse import quote

import numpy as np
import pytest
from PIL import Image

import axialdeform as ad
from axialdeform.core.generate import Generate, children_table, generate_tiles, recipe_json, recipe_uniforms, tile_size, tiles_around
from axialdeform.core.generate_ground import GroundMaps
from axialdeform.core.io.gltf import bend_extension
from axialdeform.core.wind import apply_wind

from helpers.generated_scenes import GLTF_SCENE, HILLS, LANDSCAPE, TREES, close
from helpers.models import blended
from helpers.three_site import JS, MORE, ROOT, SIZE, Server, iou, make_site, mask, render_reference

pytestmark = pytest.mark.slow

VERSIONS = ["three-r184", "three-r187"]  # js/package.json's devDependencies (npm aliases)
BACKENDS = {"webgl2": True, "webgpu": False}  # forceWebGL
WIND = {"direction": [1, 0, 0.3], "strength": 0.35, "gustiness": 0.6, "frequency": 0.5, "wavelength": 4.0}


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    folder = make_site(tmp_path_factory.mktemp("webgpu") / "site")
    (folder / "favicon.ico").write_bytes(b"")  # Chromium asks for one: not a missing file of the checks
    page = (ROOT / "tests" / "web" / "three" / "webgpu.html").read_text()
    for v in VERSIONS:
        three = JS / "node_modules" / v
        assert (three / "build" / "three.webgpu.js").is_file(), \
            f"js/node_modules/{v} is missing: the README's test command runs `npm ci --prefix js`"
        (folder / "node_modules" / v).symlink_to(three)
        (folder / f"webgpu-{v}.html").write_text(page.replace("THREEDIR", v))
    s = Server(folder)
    yield folder, s.url
    s.close()


def run(browser, url: str, version: str, call: str, arg: dict, timeout=240_000):
    """``window.checks[call](arg)`` on the page of ``version``, and the page's errors."""
    page = browser.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    try:
        page.goto(f"{url}webgpu-{version}.html")
        page.wait_for_function("window.checksReady === true", timeout=timeout)
        return page.evaluate(f"(arg) => window.checks.{call}(arg)", arg), errors
    finally:
        page.close()


def png(data_url: str) -> np.ndarray:
    return np.asarray(Image.open(BytesIO(base64.b64decode(data_url.split(",", 1)[1]))).convert("RGB"))


# ---- the maths: every feature against axialdeform.deform ----

def _case(name, mesh, params, wind=None, time=0.0):
    ext = bend_extension(mesh, params.shape[1])
    tree = getattr(mesh, "tree", None)
    return {"name": name, "positions": mesh.positions.ravel().tolist(), "normals": mesh.normals.ravel().tolist(),
            "vertexAxis": tree.vertex_code.tolist() if tree is not None else None,  # a blend's code: b + 64 b1 + 4096 q
            "axis": {"axis": ext["axis"], "axes": ext.get("axes")}, "count": len(params),
            "numbersPerInstance": params.shape[1], "axes": tree.count if tree is not None else 1,
            "data": np.asarray(params, np.float32).ravel().tolist(), "wind": wind, "time": time}


def bend_cases():
    """(case for the page, expected positions, normals, L): one aligned axis; a chosen frame with scale,
    twist and taper; tinted leaves in the wind; a tree of ten anchored axes with twist, in the wind; the same
    tree with half its vertices blending two chains (AxisTree.blend), in the wind."""
    stone = ad.load_mesh("stone")
    framed = ad.load_mesh("stone", axis="oriented")
    leaf = ad.load_mesh("leafcard", axis="auto")
    tree = ad.load_mesh("tree", axes=str(ROOT / "examples" / "forest" / "tree-axes.toml"))
    wind = ad.Wind(direction=tuple(WIND["direction"]), strength=WIND["strength"], gustiness=WIND["gustiness"],
                   frequency=WIND["frequency"], wavelength=WIND["wavelength"])
    out = []
    for name, mesh, params, windy, t in [
        ("stones", stone, ad.random_params(stone, 40, seed=3, variation=ad.Variation(bend=0.15)), False, 0.0),
        ("framed", framed, ad.random_params(framed, 30, seed=4, variation=ad.Variation(bend=0.15, twist=0.8, taper=0.3, scale=(0.7, 1.3))),
         False, 0.0),
        ("leaves", leaf, ad.random_params(leaf, 40, seed=5, variation=ad.Variation(bend=0.15, tint=0.3)), True, 1.3),
        ("trees", tree, ad.random_params(tree, 9, seed=2, variation=ad.Variation(bend=0.1, twist=0.3), spacing=3), True, 0.7),
        ("blended trees", blended(tree), ad.random_params(tree, 6, seed=7, variation=ad.Variation(bend=0.2, twist=0.3), spacing=3),
         True, 0.9),
    ]:
        moved = apply_wind(wind, getattr(mesh, "tree", None) or mesh.axis, params, t) if windy else params
        pos, nrm = ad.deform(mesh, moved)
        still = ad.deform(mesh, params)[0] if windy else None
        out.append((_case(name, mesh, params, WIND if windy else None, t), pos, nrm, mesh.axis.length, still))
    return out


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("backend", list(BACKENDS))
def test_the_node_bend_equals_the_cpu_reference(webgpu_browser, site, version, backend):
    """World positions and normals bent by the node functions (bendAsync's compute pass: WebGPU compute,
    or transform feedback under the WebGL 2 backend) against axialdeform.deform, wind included: positions
    to 1e-6 L (times the positions' reach in units of L where instances stand far out), normals to 1e-5."""
    _folder, url = site
    cases = bend_cases()
    out, errors = run(webgpu_browser, url, version, "bend", {"gl": BACKENDS[backend], "cases": [c[0] for c in cases]})
    if (version, backend) == ("three-r184", "webgl2"):  # three's compute under the fallback mixes passes up there
        assert out["error"].startswith("AxialError: bendAsync: three r184's WebGL 2 fallback"), out
        assert errors == []
        return
    assert out["backend"] == backend and out["version"] == version.split("-r")[1], out.get("backend")
    for (case, pos, nrm, L, still), got in zip(cases, out["cases"]):
        assert (got["n"], got["V"]) == pos.shape[:2], case["name"]
        gpos = np.array(got["positions"]).reshape(*pos.shape[:2], 4)[..., :3]
        gnrm = np.array(got["normals"]).reshape(*pos.shape[:2], 4)[..., :3]
        reach = max(1.0, float(np.abs(pos).max()) / L)
        assert np.abs(gpos - pos).max() <= 1e-6 * L * reach, (case["name"], np.abs(gpos - pos).max() / L)
        assert np.abs(gnrm - nrm).max() <= 1e-5, (case["name"], np.abs(gnrm - nrm).max())
        if still is not None:  # the wind moved them: the comparison can fail
            assert np.abs(still - pos).max() > 0.05 * L, case["name"]
    assert errors == []


# ---- the pictures: what render draws ----

DRAWN = [("stones", ["stone", "stones.adp"])] + [(name, [mesh, f"{name}.adp", *opts[:2]]) for name, mesh, opts in MORE
                                                 if name in ("trees", "framed", "leaves")]


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("backend", list(BACKENDS))
def test_webgpu_renderer_draws_what_render_draws(webgpu_browser, site, version, backend):
    """The plugin's meshes under WebGPURenderer against render_image (silhouette IoU >= 0.97), and the
    stones unbent would not match (IoU < 0.9)."""
    folder, url = site
    for name, what in DRAWN:
        out, errors = run(webgpu_browser, url, version, "draw", {"gl": BACKENDS[backend], "glb": f"{name}.glb"})
        assert out["backend"] == backend and out["meshes"] >= 1, out
        assert all("NodeMaterial" in t for t in out["types"]), out["types"]
        shot = png(out["png"])
        what = [w if i != 1 else folder / w for i, w in enumerate(what)]
        ref = render_reference(folder, what)
        Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / f"webgpu-{version}-{backend}-{name}.png")
        assert iou(shot, ref) >= 0.97, (name, iou(shot, ref))
        assert errors == []
    # the same stones, all offsets zero, are far from render's bent picture: the comparison can fail
    flat = ad.read_params(folder / "stones.adp", mesh=ad.load_mesh("stone"))
    flat[:, :10] = 0
    ad.write_params(folder / "flat.adp", flat, ad.load_mesh("stone"))
    out, _ = run(webgpu_browser, url, version, "draw", {"gl": BACKENDS[backend], "glb": "stones.glb"})
    ref = render_reference(folder, ["stone", folder / "stones.adp"])
    unbent = render_reference(folder, ["stone", folder / "flat.adp"])
    assert iou(unbent, ref) < 0.9 and iou(png(out["png"]), ref) >= 0.97


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_the_tint_colours_each_instance_under_webgpu(webgpu_browser, site, backend):
    """Tinted leaves (22 numbers) drawn as they are and with every tint 1, 1, 1: the same silhouette,
    other colours (the node path sets the varying three's materials multiply their colour by)."""
    _folder, url = site
    shots = []
    for untint in (False, True):
        out, errors = run(webgpu_browser, url, VERSIONS[-1], "draw", {"gl": BACKENDS[backend], "glb": "leaves.glb",
                                                                     "untint": untint})
        assert errors == []
        shots.append(png(out["png"]))
    tinted, plain = shots
    assert iou(tinted, plain) > 0.99
    both = mask(tinted) & mask(plain)
    diff = np.abs(tinted.astype(np.float64) - plain)[both].mean()
    assert diff > 2, diff  # measured 3.9 (mean over the leaves; 0 where the tint were lost)


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_webgpu_wind_sways_trees_as_render_draws_them(webgpu_browser, site, backend):
    folder, url = site
    name, mesh, opts = next(m for m in MORE if m[0] == "trees")
    out, errors = run(webgpu_browser, url, VERSIONS[-1], "draw",
                      {"gl": BACKENDS[backend], "glb": "trees.glb", "wind": WIND, "time": 1.3})
    wind = ad.Wind(direction=tuple(WIND["direction"]), strength=WIND["strength"], gustiness=WIND["gustiness"],
                   frequency=WIND["frequency"], wavelength=WIND["wavelength"])
    ref = render_reference(folder, [mesh, folder / "trees.adp", *opts[:2]], wind=wind, time=1.3)
    still = render_reference(folder, [mesh, folder / "trees.adp", *opts[:2]])
    shot = png(out["png"])
    Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / f"webgpu-wind-{backend}.png")
    assert iou(shot, ref) >= 0.95, iou(shot, ref)
    assert iou(still, ref) < 0.93  # the wind moved them visibly
    assert errors == []


@pytest.mark.parametrize("version", VERSIONS)
def test_the_bent_instance_casts_a_bent_shadow_under_webgpu(webgpu_browser, site, version):
    _folder, url = site
    (bent, flat), errors = run(webgpu_browser, url, version, "shadows", {"gl": False})
    bent, flat = np.array(bent), np.array(flat)
    assert bent.sum() > 200 and flat.sum() > 200  # both shadows are there
    assert (bent ^ flat).sum() > 0.15 * (bent | flat).sum()  # and they differ: the shadow pass bends
    assert errors == []


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_bake_and_raycast_under_webgpu(webgpu_browser, site, backend):
    """bakeAsync (the compute pass, read back once) draws what bending draws; raycastAsync finds the
    instance under a ray, and so does raycast() once baked; unbaked raycast() warns once (the GPU reads
    back asynchronously) and bake() names bakeAsync."""
    _folder, url = site
    out, errors = run(webgpu_browser, url, VERSIONS[-1], "baking", {"gl": BACKENDS[backend]})
    n = out["N"]
    bent, baked = (np.array(out[k], dtype=np.float64).reshape(n, n, 4)[..., :3] for k in ("bentPx", "bakedPx"))
    assert out["baked"] is True
    assert (bent.max(axis=2) > 0).sum() > 2000
    assert np.abs(bent - baked).mean() < 0.5 and np.abs(bent - baked).max() <= 24
    assert out["asyncId"] == 0 and out["hitId"] == 0
    assert abs(out["asyncDistance"] - out["syncDistance"]) < 1e-4
    assert out["unbakedSync"] == 0 and len(out["warnings"]) == 1 and "raycastAsync" in out["warnings"][0]
    assert out["bakeSync"].startswith("AxialError: bake:") and "bakeAsync" in out["bakeSync"]
    assert out["after"] == {"baked": False, "children": 0}
    assert errors == []


def test_what_cannot_be_bent_is_refused_in_words(webgpu_browser, site):
    _folder, url = site
    out, errors = run(webgpu_browser, url, VERSIONS[-1], "refusals", {"gl": False})
    assert out["shaderMaterial"].startswith("AxialError: AxialInstancedMesh: ShaderMaterial cannot be bent"), out
    assert out["lineMaterial"].startswith("AxialError: AxialInstancedMesh: LineBasicMaterial cannot be bent"), out
    assert "positionNode of its own" in out["ownPosition"], out
    assert out["classicMeshUnderWebGPU"].startswith("AxialError: AxialInstancedMesh: three's WebGPURenderer"), out
    assert "axialdeform-three/webgpu" in out["classicMeshUnderWebGPU"]
    assert "axialdeform-three/webgpu" in out["nodeMaterialToClassic"], out
    assert "only three's WebGPURenderer" in out["webgpuMeshUnderOtherRenderer"], out
    for kind, k in out["kinds"].items():  # every kind becomes a node material that bends, keeping its settings
        assert k == {"node": True, "bends": True, "color": None if kind == "MeshNormalMaterial" else 0x3366cc}, (kind, k)
    assert errors == []


def test_the_webgpu_entry_is_exported_and_typed():
    pkg = json.loads((JS / "package.json").read_text())
    assert pkg["exports"]["./webgpu"] == {"types": "./src/webgpu.d.ts", "import": "./src/webgpu.js"}
    assert (JS / "src" / "webgpu.d.ts").is_file()
    for v in VERSIONS:
        assert pkg["devDependencies"][v] == f"npm:three@0.{v.split('-r')[1]}.0"


@pytest.mark.parametrize("version", VERSIONS)
def test_gpu_culling_draws_the_same_picture_with_fewer_instances(webgpu_browser, site, version):
    """setGPUCulling: the compute pass keeps the instances whose bend-aware spheres meet the frustum and
    the indirect draw draws just those: the same picture as drawing all 60, from fewer than 60 (and no pass while
    the camera rests); in a field of
    4 000 (blocks outside, wholly inside and cut) exactly the ids whose spheres three's Frustum finds inside;
    with two levels by distance, each level draws some and those beyond the last none."""
    _folder, url = site
    out, errors = run(webgpu_browser, url, version, "culling", {"gl": False})
    n = out["count"]
    assert 0 < out["args"][1] < n, out["args"]  # the camera sees a corner of the field
    assert out["args"][0] == 336  # the stone's indices a draw
    all_px, culled = (np.array(out[k]).reshape(-1, 4)[:, :3] for k in ("all", "culledPx"))
    assert (all_px.max(1) > 0).sum() > 5000
    assert np.abs(all_px.astype(int) - culled).max() <= 2  # the same picture
    rest = np.array(out["rest"]).reshape(-1, 4)[:, :3]
    assert out["restPasses"] == 0 and np.array_equal(rest, culled)  # a camera at rest: no pass, the same picture
    assert out["movedPasses"] == 2  # moved, and back: a pass each
    assert out["after"] == {"children": 0, "culled": False}
    assert "ids" in out, out.get("error")
    ids = out["ids"]  # a field of 4 000 in blocks of 64: the pass keeps exactly what three's Frustum finds inside
    assert ids["blocks"] == 63 and ids["inside"] > 0 and ids["cut"] > 0, {k: ids[k] for k in ("blocks", "inside", "cut")}
    assert 0 < len(ids["want"]) < 4000 and ids["got"] == ids["want"], (len(ids["got"]), len(ids["want"]))
    lod, _ = run(webgpu_browser, url, version, "culling", {"gl": False, "levels": [5, 7]})
    near, far = lod["args"][1], lod["args"][6]
    assert near > 0 and far > 0 and near + far < out["args"][1], lod["args"]
    assert errors == []


@pytest.mark.parametrize("cull", [False, True], ids=["all", "gpu-culled"])
def test_unbent_instances_draw_without_the_bend_as_with_it_under_webgpu(webgpu_browser, site, cull):
    """While no instance has an offset (and no wind blows) the positionNode leaves the bend out (core/variant.js):
    the same picture as the whole bend's, all drawn and GPU-culled; bent again, the bend comes back, and with 16
    numbers the generated functions are built with the turn switched off: the same picture as with it."""
    _folder, url = site
    out, errors = run(webgpu_browser, url, VERSIONS[-1], "variant", {"gl": False, "cull": cull})
    assert out["defines"] == ["AXIAL_NO_BEND", "AXIAL_NO_TURN"], out["defines"]
    assert out["bentDefines"] == ["AXIAL_NO_TURN"], out["bentDefines"]
    variant, full, bent, bent_full = (np.array(out[k]).reshape(-1, 4)[:, :3].astype(int)
                                      for k in ("variant", "full", "bent", "bentFull"))
    assert (full.max(1) > 0).sum() > 5000
    assert np.abs(variant - full).max() <= 2, np.abs(variant - full).max()
    assert np.abs(bent - bent_full).max() <= 2, np.abs(bent - bent_full).max()  # the turn switched off (16 numbers)
    if not cull:  # and it is gone from the vertex shader: one call of axial_cos_sin fewer
        assert out["bentFullCalls"] > out["bentCalls"], (out["bentCalls"], out["bentFullCalls"])
    assert (np.abs(bent - full).max(1) > 40).sum() > 500  # the bent stones are elsewhere: the check can fail
    assert errors == []


def test_gpu_culling_under_the_webgl2_fallback_is_refused_in_words(webgpu_browser, site):
    _folder, url = site
    out, errors = run(webgpu_browser, url, VERSIONS[-1], "culling", {"gl": True})
    assert out["error"].startswith("AxialError: setGPUCulling: GPU culling reads storage buffers"), out.get("error")
    assert errors == []


def example_picture_webgpu(browser, folder, url, name: str, query: str, ready: str, extra: str):
    """examples/web/NAME with three r187, drawn once on render's background without its ground and fog:
    ``{png, backend, ...}`` (``extra``: more fields, a JS object's entries over window.app's names) and
    the page's errors.  ``ready``: what the page must have done first (a JS expression)."""
    text = (ROOT / "examples" / "web" / name).read_text()
    (folder / name).write_text(text.replace("./node_modules/three/", f"./node_modules/{VERSIONS[-1]}/"))
    page = browser.new_page(viewport={"width": SIZE[0], "height": SIZE[1]})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    try:
        page.goto(url + name + query)
        page.wait_for_function(ready, timeout=240_000)
        out = page.evaluate("""async () => {
            const app = window.app, { THREE, renderer, scene, camera, ground } = app;
            renderer.setAnimationLoop(null);
            ground.visible = false;
            scene.fog = null;
            scene.background = new THREE.Color().setRGB(0.93, 0.94, 0.96, THREE.SRGBColorSpace);
            await renderer.compileAsync(scene, camera);
            renderer.render(scene, camera);
            const c = document.createElement('canvas');
            c.width = renderer.domElement.width; c.height = renderer.domElement.height;
            c.getContext('2d').drawImage(renderer.domElement, 0, 0);
            return { png: c.toDataURL(), backend: renderer.backend.isWebGPUBackend ? 'webgpu' : 'webgl2', EXTRA };
        }""".replace("EXTRA", extra))
    finally:
        page.close()
    return out, errors


@pytest.mark.parametrize("backend", list(BACKENDS))
def test_the_webgpu_example_draws_what_render_draws(webgpu_browser, site, backend):
    """examples/web/webgpu.html (WebGPURenderer, the plugin of axialdeform-three/webgpu, GPU culling on
    the WebGPU backend) as render draws stones.adp, on render's background without its ground and fog."""
    folder, url = site
    out, errors = example_picture_webgpu(webgpu_browser, folder, url, "webgpu.html", "?webgl=1" if BACKENDS[backend] else "",
                                         "window.app !== undefined", "culled: app.bent.map((m) => m.gpuCulled)")
    shot = png(out["png"])
    ref = render_reference(folder, ["stone", folder / "stones.adp"])
    Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / f"webgpu-example-{backend}.png")
    assert out["backend"] == backend
    assert out["culled"] == [backend == "webgpu"]  # GPU culling where the backend has it
    assert iou(shot, ref) >= 0.97, iou(shot, ref)
    assert errors == []


# ---- generated layers: glsl/generate.glsl as node functions, by a compute pass (generate_nodes.js) ----

GEN_STONES = {"rate": 1.0, "tile": 4.0, "min_distance": 0.4, "seed": 5, "bend": 0.15, "scale": [0.6, 1.2],
              "twist": 0.5, "tint": 0.3}


def _gen_case(name, mesh, recipe, reach, maps=None, point=(0.0, 0.0), uniforms=True, picture=False, wind=None):
    """A generated layer for the page's ``generate`` check: the base mesh, the recipe, the Python library's
    numbers (or none: the module computes them), the ground maps and child-axis table, the point."""
    ext = bend_extension(mesh, recipe.width)
    tree = getattr(mesh, "tree", None)
    grids = {"heights": getattr(maps, "heights", None), "density": getattr(maps, "density", None),
             "children": None if tree is None else children_table(recipe, mesh)}
    case = {"name": name, "positions": mesh.positions.ravel().tolist(), "normals": mesh.normals.ravel().tolist(),
            "index": mesh.faces.ravel().tolist(), "vertexAxis": tree.vertex_axis.tolist() if tree is not None else None,
            "axis": {"axis": ext["axis"], "axes": ext.get("axes")}, "recipe": recipe_json(recipe, reach),
            "maps": {k: {"data": np.asarray(g, np.float32).ravel().tolist(), "cols": int(g.shape[1]), "rows": int(g.shape[0])}
                     for k, g in grids.items() if g is not None},
            "point": list(point), "picture": picture, "side": tree is not None, "wind": wind, "time": 1.3}
    if uniforms:
        case["uniforms"] = json.loads(json.dumps(recipe_uniforms(recipe, mesh, maps)))
    return case


def generated_cases(tmp_path):
    """(case, mesh, recipe, maps): stones on the flat ground (the module's own numbers), tinted and twisted, and
    in clumps with a core;
    stones and grass on a height map (density map, altitude and slope bands, leaning with the ground); a
    tree of ten axes (every level its bend, the joints closed)."""
    stone = ad.load_mesh("stone")
    flat = Generate(**{**GEN_STONES, "yaw": [-1.0, 0.5]})  # the module's own numbers: yaw among them
    sparse = Generate(**{**GEN_STONES, "rate": 0.25, "scale": [1.0, 1.4]})  # each its own silhouette
    clumps = Generate(**{**GEN_STONES, "rate": 4.0, "min_distance": 0.0, "clump_cells": 3, "clump_radius": 0.8,
                         "clump_core": 0.4, "clump_core_radius": 0.2})
    out = [(_gen_case("stones", stone, flat, 5.0, uniforms=False, picture=True), stone, flat, None),
           (_gen_case("stones in the wind", stone, sparse, 8.0, uniforms=False, picture=True, wind=WIND), stone, sparse,
            None),
           (_gen_case("stones in clumps", stone, clumps, 5.0, uniforms=False), stone, clumps, None)]
    for f in ("terrain.png", "stone_density.png", "grass.obj"):
        (tmp_path / f).write_bytes((LANDSCAPE / f).read_bytes())
    (tmp_path / "tree-axes.toml").write_bytes((ROOT / "examples" / "forest" / "tree-axes.toml").read_bytes())
    for name, text, point in (("hills", HILLS, (3.0, -2.0)), ("trees", TREES, (0.0, 0.0))):
        (tmp_path / f"{name}.toml").write_text(text, encoding="utf-8")
        for layer in ad.Scene.load(tmp_path / f"{name}.toml").layers[:2 if name == "hills" else 1]:
            g = layer.generate
            reach = 9.0 if name == "hills" else 20.0  # a few tiles
            out.append((_gen_case(f"{name}-{layer.name}", layer.mesh, g.generate, reach, g.maps, point),
                        layer.mesh, g.generate, g.maps))
    return out


@pytest.mark.parametrize("version", VERSIONS)
def test_the_generated_mesh_makes_the_python_records_under_webgpu(webgpu_browser, site, version, tmp_path):
    """axialdeform-three/webgpu's generated AxialInstancedMesh: its compute pass (the generated axial_generate, WebGPU backend)
    makes the Python library's records for the tiles around a point -- flat ground, a height map with
    density, bands and leaning, a tree of ten axes --, counts the kept ones on the GPU, draws them as
    render does (silhouette IoU >= 0.95), and a ray straight down hits the first one."""
    folder, url = site
    cases = generated_cases(tmp_path)
    out, errors = run(webgpu_browser, url, version, "generate", {"gl": False, "cases": [c[0] for c in cases]})
    assert out["backend"] == "webgpu" and errors == [], (out.get("backend"), errors)
    for (case, mesh, recipe, maps), got in zip(cases, out["cases"]):
        name = case["name"]
        assert "error" not in got, (name, got.get("error"))
        reach = case["recipe"]["reach"]
        tiles = tiles_around(recipe, *case["point"], reach)
        assert got["tiles"] == tiles.tolist(), name
        assert got["made"] is True and got["again"] is False and got["keptBefore"] is None, name
        want = generate_tiles(recipe, mesh, tiles, maps)
        records = np.asarray(got["data"], np.float32).reshape(-1, got["width"])
        assert got["slots"] == len(tiles) * tile_size(recipe)[0] ** 2 and got["kept"] == got["counted"] == len(want), name
        assert len(want) > 10 and close(records, want) <= 1e-6, (name, close(records, want))
        assert got["cpu"] == got["width"]  # drawing needed no CPU copy of the records: one row
        # the ray hits the instance it was aimed at (across a tree's trunk: that tree or one in front of it)
        assert got["hit"] is not None, name
        at = 10 * (getattr(mesh, "tree", None).count if case["side"] else 1)  # the position: after the offsets
        hit = np.abs(records[:, at:at + 3] - got["hit"]["at"]).max(axis=1) <= 1e-5
        # (in clumps, instances overlap: the one above it)
        assert (hit[0] if not (case["side"] or recipe.clumped) else hit.any()), (name, got["hit"])
        if case["picture"]:
            shot = png(got["png"])
            look = ad.Look(ground=False, shadow=False)
            camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
            wind = ad.Wind(direction=tuple(WIND["direction"]), strength=WIND["strength"], gustiness=WIND["gustiness"],
                           frequency=WIND["frequency"], wavelength=WIND["wavelength"]) if case["wind"] else None
            # a generated layer's instances, as render draws them: their wind phases hash where they stand
            ref = ad.render_image(mesh, want, size=SIZE, look=look, camera=camera, options=ad.RenderOptions(wind=wind, time=case["time"],
                                                                                                            position_ids=True))
            Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / f"webgpu-generated-{version}-{name}.png")
            assert mask(ref).sum() > 0.05 * ref.size / 3
            assert iou(shot, ref) >= 0.95, (name, iou(shot, ref))
            if wind is not None:  # the wind moved them visibly, by those phases: the comparison can fail
                still = ad.render_image(mesh, want, size=SIZE, look=look, camera=camera)
                by_index = ad.render_image(mesh, want, size=SIZE, look=look, camera=camera, options=ad.RenderOptions(wind=wind,
                                                                                                                     time=case["time"]))
                assert iou(still, ref) < 0.93 and iou(shot, by_index) < iou(shot, ref) - 0.02, \
                    (iou(still, ref), iou(shot, by_index), iou(shot, ref))


def test_the_brush_paints_a_generated_mesh_under_webgpu(webgpu_browser, site):
    """This entry's AxialBrush on its generated AxialInstancedMesh (setDensity): the compute passes are made again from the
    painted mask and the tiles give the Python library's records for the same strokes (core/brush.py), fewer
    than before."""
    from axialdeform.core.brush import Stroke, fold, new_mask, paint

    stone = ad.load_mesh("stone")
    recipe = Generate(**GEN_STONES)
    area = (-8.0, -8.0, 8.0, 8.0)
    strokes = [(-2.0, 0.5, 4.0, True), (2.0, -1.0, 1.5, True), (-2.5, 0.0, 1.0, False)]
    mask = new_mask()
    for x, z, radius, erase in strokes:
        paint(mask, area, Stroke("stones", x, z, radius, erase))
    maps = GroundMaps.of(density=fold(None, mask), extent=area)
    case = _gen_case("stones, painted", stone, recipe, 5.0, uniforms=False)
    case["paint"] = {"area": list(area), "wrap": bool(maps.d_wrap), "strokes": strokes}
    out, errors = run(webgpu_browser, site[1], VERSIONS[-1], "generate", {"gl": False, "cases": [case]})
    got = out["cases"][0]
    assert "error" not in got and errors == [], (got.get("error"), errors)
    tiles = tiles_around(recipe, *case["point"], 5.0)
    want = generate_tiles(recipe, stone, tiles, maps)
    records = np.asarray(got["paintedData"], np.float32).reshape(-1, got["width"])
    assert got["painted"] is True and got["paintedCount"] == len(want) < 0.8 * got["kept"], (got["paintedCount"], got["kept"])
    assert len(want) > 10 and close(records, want) <= 1e-6, close(records, want)


def test_a_generated_mesh_under_the_webgl2_fallback_is_refused_in_words(webgpu_browser, site, tmp_path):
    """Under the WebGL 2 fallback: an AxialError naming the WebGPU backend and WebGLRenderer.  On the WebGPU
    backend, tiles whose slots need a storage buffer above the device's binding limit (128 MiB by default):
    an AxialError naming the limit and how to ask for more -- not a validation error in the console and
    nothing drawn."""
    stone = ad.load_mesh("stone")
    case = _gen_case("stones", stone, Generate(**GEN_STONES), 5.0)
    out, errors = run(webgpu_browser, site[1], VERSIONS[-1], "generate", {"gl": True, "cases": [case]})
    said = out["cases"][0]["error"]
    assert said.startswith("AxialError: AxialInstancedMesh (axialdeform-three/webgpu): a generated layer's instances"), said
    assert "WebGPU backend" in said and "WebGLRenderer" in said
    assert errors == []
    huge = _gen_case("huge", stone, Generate(rate=4.0, tile=16.0, seed=1), 290.0)  # 1 478 656 slots
    out, errors = run(webgpu_browser, site[1], VERSIONS[-1], "generate", {"gl": False, "cases": [huge]})
    said = out["cases"][0]["error"]
    assert said.startswith("AxialError: AxialInstancedMesh: 1478656 slots"), said  # by the constructor, before allocating
    assert "maxStorageBufferBindingSize 134217728" in said and "requiredLimits" in said
    # the same reach with the limit the renderer was given named: made (the device's own limit checked at the first draw)
    big = dict(huge, options={"maxStorageBufferBindingSize": 2 ** 31 - 4})
    out, errors = run(webgpu_browser, site[1], VERSIONS[-1], "generate", {"gl": False, "cases": [big]})
    said = out["cases"][0].get("error", "")
    assert "maxStorageBufferBindingSize (134217728)" in said, said  # SwiftShader's device keeps WebGPU's default
    assert errors == []


def test_the_gltf_generated_form_is_generated_under_webgpu(webgpu_browser, site):
    """export SCENE.toml --generated, loaded by this entry's AxialGLTFPlugin: the node becomes this entry's
    generated AxialInstancedMesh, which makes the tiles around the camera as it is drawn (autoUpdate) and draws
    what render draws of the Python library's records for those tiles."""
    folder, url = site
    (folder / "gen.toml").write_text(GLTF_SCENE)
    r = subprocess.run([sys.executable, "-m", "axialdeform", "export", str(folder / "gen.toml"), "--generated",
                        "-o", str(folder / "gen.glb")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out, errors = run(webgpu_browser, url, VERSIONS[-1], "draw", {"gl": False, "glb": "gen.glb"})
    assert out["meshes"] == 1 and out["generated"] == [True], out
    layer = ad.Scene.load(folder / "gen.toml").layers[0]
    g = layer.generate
    want = generate_tiles(g.generate, layer.mesh, tiles_around(g.generate, 7.0, 7.0, g.reach), g.maps)
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    ref = ad.render_image(layer.mesh, want, size=SIZE, look=look, camera=camera)
    shot = png(out["png"])
    Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / "webgpu-generated-gltf.png")
    assert mask(ref).sum() > 0.05 * ref.size / 3
    assert iou(shot, ref) >= 0.95, iou(shot, ref)
    assert errors == []


def test_the_generated_webgpu_example_draws_what_render_draws(webgpu_browser, site):
    """examples/web/generated-webgpu.html (the recipe from the address, its ground and fog hidden) draws
    what render draws of the Python library's records for the tiles around its orbit target."""
    folder, url = site
    recipe = {**GEN_STONES, "reach": 5.0}
    out, errors = example_picture_webgpu(webgpu_browser, folder, url, "generated-webgpu.html",
                                         "?recipe=" + quote(json.dumps(recipe)),
                                         "window.app !== undefined && window.app.frames >= 2",
                                         "tiles: app.stones.tiles, kept: await app.stones.counted")
    assert out["backend"] == "webgpu"
    stone = ad.load_mesh(folder / "stone.obj")
    g = Generate(**GEN_STONES)
    assert out["tiles"] == tiles_around(g, 0.0, 0.0, 5.0).tolist()
    want = generate_tiles(g, stone, out["tiles"])
    assert out["kept"] == len(want)
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    ref = ad.render_image(stone, want, size=SIZE, look=look, camera=camera)
    shot = png(out["png"])
    Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / "webgpu-generated-example.png")
    assert iou(shot, ref) >= 0.95, iou(shot, ref)
    assert errors == []
