"""The npm module axialdeform-three (js/) in Chromium: the examples in
examples/web draw what ``axialdeform render`` draws, shadows and raycasting
follow the bent shape, and ``npm pack`` makes a tarball a fresh folder installs
and runs.  The parsers' own tests run with node's test runner (test_node_tests)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import axialdeform as ad

from helpers.three_site import JS, MORE, ROOT, SIZE, Server, cli, example_picture, iou, make_site, mask, render_reference


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    folder = make_site(tmp_path_factory.mktemp("three") / "site")
    s = Server(folder)
    yield folder, s.url
    s.close()


def test_node_tests_pass():
    """js/test with node's own runner, and src/glsl.js is what glsl/axial.glsl gives."""
    node = shutil.which("node")
    assert node, "Node.js is required (the README's test command)"
    r = subprocess.run([node, "build.mjs", "--check"], cwd=JS, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([node, "--test", "test/"], cwd=JS, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    assert "# fail 0" in r.stdout and "# pass " in r.stdout


@pytest.mark.slow
def test_node_tests_pass_with_the_latest_three_too(tmp_path):
    """The peer range is ">=0.160.0": js/test runs with 0.160 (the devDependency, above) and here with
    the latest three on npm, the module's sources and tests copied into a folder of their own."""
    npm, node = shutil.which("npm"), shutil.which("node")
    assert npm and node, "Node.js and npm are required (the README's test command)"
    app = tmp_path / "latest"
    shutil.copytree(JS / "src", app / "src")
    shutil.copytree(JS / "test", app / "test")
    (app / "package.json").write_text(json.dumps({"name": "latest-three-check", "type": "module", "private": True}))
    r = subprocess.run([npm, "install", "--no-audit", "--no-fund", "three@latest"], cwd=app, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    version = json.loads((app / "node_modules" / "three" / "package.json").read_text())["version"]
    assert int(version.split(".")[1]) > 160, version  # a newer release than the devDependency
    r = subprocess.run([node, "--test", "test/"], cwd=app, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"three {version}: " + r.stdout[-3000:] + r.stderr[-2000:]
    assert "# fail 0" in r.stdout


def test_the_module_has_no_second_copy_of_the_maths():
    """The shader text the module injects is glsl/axial.glsl and wind.glsl verbatim (no GLSL of its own bends).
    The one other copy is js/src/nodes.js, the node-function port WebGPURenderer needs (its WGSL cannot
    include GLSL), held to axialdeform.deform on every feature by test_webgpu.py."""
    glsl = (ROOT / "glsl" / "axial.glsl").read_text()
    built = (JS / "src" / "glsl.js").read_text()
    import json

    consts = {m.group(1): json.loads(m.group(2)) for m in re.finditer(r"^export const (\w+) = (\".*\");$", built, re.M)}
    assert consts["AXIAL_GLSL"] == glsl
    assert consts["WIND_GLSL"] == (ROOT / "glsl" / "wind.glsl").read_text()
    # the generator: generate.glsl as it is, generate.vert less its includes (the module puts those before it)
    assert consts["GENERATE_GLSL"] == (ROOT / "glsl" / "generate.glsl").read_text()
    vert = (ROOT / "glsl" / "generate.vert").read_text()
    assert consts["GENERATE_VERT"] == re.sub(r"^\s*#include[^\n]*\n", "", vert, flags=re.M)
    assert consts["GENERATE_VERT"] in vert.replace('#include "axial.glsl"\n#include "wind.glsl"\n#include "generate.glsl"\n', "")
    shader_js = (JS / "src" / "shader.js").read_text()
    for maths in ("Bernstein", "s * s * s * s", "cos(", "sin(", "6.28"):  # the formulas live in glsl/ only
        assert maths not in shader_js.split("const BEND", 1)[1].split("`;", 1)[0]
    for f in (JS / "src").glob("*.js"):  # nor on the CPU: drawing, baking and raycasting bend on the GPU
        if f.name != "glsl.js":
            text = f.read_text().lower()
            assert "bernstein" not in text and "s * s * s * s" not in text and "* t * t * t" not in text, f.name


def test_the_modules_record_columns_are_the_record_tables():
    """js/src/adp.js recordLayout against core/record.py, for every level and a tree of ten axes."""
    import json

    from axialdeform.core import record as R

    script = ("import { recordLayout } from '" + (JS / "src" / "adp.js").as_uri() + "';\n"
              "const out = [];\n"
              "for (const k of [1, 10]) for (const w of " + json.dumps(list(R.WIDTHS)) + ")"
              " out.push(recordLayout(w + 10 * (k - 1), k));\n"
              "console.log(JSON.stringify(out));")
    r = subprocess.run([shutil.which("node"), "--input-type=module", "-e", script], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    got = iter(json.loads(r.stdout))
    for k in (1, 10):
        for level, _width in enumerate(R.WIDTHS):
            lay, shift = next(got), 10 * (k - 1)
            assert lay["position"] == R.POSITION.start + shift and lay["angles"] == R.ANGLES.start + shift
            assert (lay["scale"], lay["twist"], lay["taper"]) == (
                (R.SCALE + shift, R.TWIST + shift, R.TAPER + shift) if level >= 1 else (None, None, None))
            assert lay["tint"] == (R.TINT.start + shift if level == 2 else None)
            assert R.OFFSETS == slice(0, 10)  # axis 0's offsets first; child axis j's at 10 j


def test_the_modules_record_is_what_the_python_record_generates(tmp_path):
    """js/src/record.js (the record's fields, the instanced attributes, the wind's defaults) is what
    tools/make_js_record.py writes from core/record.py and core/wind.py."""
    out = tmp_path / "record.js"
    subprocess.run([sys.executable, str(ROOT / "tools" / "make_js_record.py"), str(out)], check=True,
                   capture_output=True)
    assert out.read_text() == (JS / "src" / "record.js").read_text(), "rerun tools/make_js_record.py"


def test_fixtures_are_what_the_library_writes(tmp_path):
    cmd = [sys.executable, str(ROOT / "tools" / "make_js_fixtures.py"), str(tmp_path)]
    subprocess.run(cmd, check=True, capture_output=True)
    for f in sorted((JS / "test" / "fixtures").iterdir()):
        hint = f"{f.name}: rerun tools/make_js_fixtures.py"
        if f.suffix == ".json":  # floats from numpy/scipy/trimesh arithmetic: equal to rounding, not to the bit
            _assert_same_json(json.loads((tmp_path / f.name).read_text()), json.loads(f.read_text()), hint)
        else:  # .adp files: the format's bytes, but lo and L (the header's float64s, computed by numpy/scipy) to 1e-9
            _assert_same_adp((tmp_path / f.name).read_bytes(), f.read_bytes(), hint)


def _assert_same_adp(got: bytes, want: bytes, where: str) -> None:
    """Two parameter files equal field for field: every byte but the header's ``lo`` and ``L`` (float64s an
    axis frame's arithmetic computes, a last bit differently with other versions of numpy, scipy or BLAS),
    which agree to 1e-9 relative; the CRC-32 trailer covers them, so it is left out too."""
    from axialdeform.core.io.adp import _HEADER, HEADER_SIZE

    assert len(got) == len(want), f"{where}: {len(got)} bytes != {len(want)}"
    g, w = _HEADER.unpack_from(got), _HEADER.unpack_from(want)
    for i, (a, b) in enumerate(zip(g, w)):
        if isinstance(b, float):
            assert a == pytest.approx(b, rel=1e-9, abs=1e-12), f"{where}: header field {i}: {a} != {b}"
        else:
            assert a == b, f"{where}: header field {i}: {a!r} != {b!r}"
    assert got[HEADER_SIZE:-4] == want[HEADER_SIZE:-4], f"{where}: the numbers differ"


def _assert_same_json(got, want, where: str) -> None:
    """The same JSON tree; numbers equal to 1e-9 relative (1e-12 absolute): a last-bit change of a
    library's arithmetic passes, a changed method or file format does not."""
    if isinstance(want, dict):
        assert isinstance(got, dict) and sorted(got) == sorted(want), f"{where}: keys {sorted(got)} != {sorted(want)}"
        for key in want:
            _assert_same_json(got[key], want[key], f"{where}.{key}")
    elif isinstance(want, list):
        assert isinstance(got, list) and len(got) == len(want), f"{where}: a list of {len(want)} expected"
        for i, (g, w) in enumerate(zip(got, want)):
            _assert_same_json(g, w, f"{where}[{i}]")
    elif isinstance(want, (int, float)) and not isinstance(want, bool):
        assert isinstance(got, (int, float)) and not isinstance(got, bool), f"{where}: a number expected"
        assert got == pytest.approx(want, rel=1e-9, abs=1e-12), f"{where}: {got} != {want}"
    else:
        assert got == want, f"{where}: {got!r} != {want!r}"


@pytest.mark.slow
@pytest.mark.parametrize("example", ["gltf.html", "adp.html"])
def test_the_examples_draw_what_render_draws(browser, site, example):
    """The GLB that `export --instanced` wrote of stones.adp, and stones.adp itself, as render draws stones.adp."""
    folder, url = site
    shot, errors = example_picture(browser, url + example)
    ref = render_reference(folder, ["stone", folder / "stones.adp"])
    assert errors == []
    assert mask(ref).sum() > 0.05 * ref.shape[0] * ref.shape[1]  # stones in view
    assert iou(shot, ref) >= 0.97, iou(shot, ref)
    # the look too: the exported GLB carries render's stone colour as a dielectric material (glTF's own
    # default is white and metallic 1, which three.js draws black where no environment is reflected)
    both = mask(shot) & mask(ref)
    lum = lambda img: img[..., :3].astype(np.float64).mean(axis=-1)[both]  # noqa: E731
    dark = float((lum(shot) < 12).mean())
    assert dark < 0.05 and 0.6 < lum(shot).mean() / lum(ref).mean() < 1.6, (dark, lum(shot).mean(), lum(ref).mean())


@pytest.mark.slow
@pytest.mark.parametrize("name,mesh,opts", MORE, ids=[m[0] for m in MORE])
def test_the_plugin_draws_trees_frames_and_textured_parts_as_render(browser, site, name, mesh, opts):
    folder, url = site
    shot, errors = example_picture(browser, url + f"gltf.html?file={name}.glb")
    ref = render_reference(folder, [mesh, folder / f"{name}.adp", *opts[:2]])
    assert errors == []
    assert mask(ref).sum() > 0.03 * ref.shape[0] * ref.shape[1]
    Image.fromarray(shot).save(folder / f"{name}-three.png")
    Image.fromarray(ref).save(folder / f"{name}-render.png")
    assert iou(shot, ref) >= 0.97, iou(shot, ref)


WIND = {"direction": [1, 0, 0.3], "strength": 0.35, "gustiness": 0.6, "frequency": 0.5, "wavelength": 4.0}


@pytest.mark.slow
@pytest.mark.parametrize("name,mesh,opts", [("stones", "stone", []), MORE[0]], ids=["stones", "trees"])
def test_the_wind_at_a_time_sways_as_render_draws_it(browser, site, name, mesh, opts):
    """setWind + setTime (glsl/wind.glsl in three's materials) against render_image(wind=, time=)."""
    import json

    folder, url = site
    sway = ("window.app.gltf.scene.traverse((o) => { if (o.isAxialInstancedMesh) o.setWind(" + json.dumps(WIND) +
            ").setTime(1.3); });")
    shot, errors = example_picture(browser, url + f"gltf.html?file={name}.glb", sway)
    wind = ad.Wind(direction=tuple(WIND["direction"]), strength=WIND["strength"], gustiness=WIND["gustiness"],
                   frequency=WIND["frequency"], wavelength=WIND["wavelength"])
    ref = render_reference(folder, [mesh, folder / f"{name}.adp", *opts[:2]], wind=wind, time=1.3)
    still = render_reference(folder, [mesh, folder / f"{name}.adp", *opts[:2]])
    Image.fromarray(np.concatenate([shot, ref, still], 1)).save(folder / f"wind-{name}.png")
    assert errors == []
    assert iou(shot, ref) >= 0.97, iou(shot, ref)
    assert iou(still, ref) < 0.93  # the wind moved them visibly: the test can fail


@pytest.mark.slow
def test_a_palm_whose_fronds_cross_the_crown_sways_in_three_as_render_draws_it(browser, site):
    """Anchored child axes (the fronds' joints mid-axis, at the crown) through the exported GLB
    (AXIALDEFORM_bend axes.anchors) and the module's shader, in the wind, against render_image."""
    import json

    sys.path.insert(0, str(ROOT / "tests" / "core"))
    from helpers.models import PALM, palm_file

    folder, url = site
    palm = palm_file(folder / "palm.glb")
    pick = {"parts": PALM, "axes": "parts", "axis": "oriented"}
    mesh = ad.load_mesh(palm, **pick)
    assert min(mesh.tree.anchors[1:]) > 0.2  # the joints are where the fronds cross the crown
    params = ad.random_params(mesh, 9, seed=2, bend=(0.05, 0.3), placement="disc", spacing=1.6)
    params[:, 10 * mesh.axis_count + 1] -= 2.5  # the crowns in the examples' view (the camera looks at the origin)
    ad.write_params(folder / "palms.adp", params, mesh)
    ad.export_glb(folder / "palms.glb", mesh, params, "instanced")
    sway = ("window.app.gltf.scene.traverse((o) => { if (o.isAxialInstancedMesh) o.setWind(" + json.dumps(WIND) +
            ").setTime(1.3); });")
    shot, errors = example_picture(browser, url + "gltf.html?file=palms.glb", sway)
    wind = ad.Wind(direction=tuple(WIND["direction"]), strength=WIND["strength"], gustiness=WIND["gustiness"],
                   frequency=WIND["frequency"], wavelength=WIND["wavelength"])
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    ref = ad.render_image(mesh, params, size=SIZE, look=look, camera=camera, wind=wind, time=1.3)
    still = ad.render_image(mesh, params, size=SIZE, look=look, camera=camera)
    Image.fromarray(np.concatenate([shot, ref, still], 1)).save(folder / "wind-palms.png")
    assert errors == []
    assert iou(shot, ref) >= 0.95, iou(shot, ref)
    assert iou(still, ref) < 0.93  # the wind moved the fronds visibly: the test can fail


@pytest.mark.slow
@pytest.mark.parametrize("name,mesh,opts", MORE[:3], ids=[m[0] for m in MORE[:3]])
def test_baked_trees_frames_and_tinted_leaves_draw_as_render(browser, site, name, mesh, opts):
    """bake(): ten axes (the offsets texture in the transform feedback), a chosen frame with twist and
    taper, a tint (a colour a vertex) -- drawn as plain geometry, as render draws them."""
    folder, url = site
    bake = ("let baked = 0; window.app.gltf.scene.traverse((o) => { if (o.isAxialInstancedMesh && o.bake(renderer))"
            " baked += 1; }); if (baked < 1) throw new Error('nothing baked');")
    shot, errors = example_picture(browser, url + f"gltf.html?file={name}.glb", bake)
    ref = render_reference(folder, [mesh, folder / f"{name}.adp", *opts[:2]])
    bent, _errors = example_picture(browser, url + f"gltf.html?file={name}.glb")  # the same, bent every frame
    Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / f"baked-{name}.png")
    assert errors == []
    assert iou(shot, ref) >= 0.97, iou(shot, ref)
    diff = np.abs(shot.astype(np.float64) - bent)
    assert diff.mean() < 0.5 and np.percentile(diff.max(axis=2), 99.5) < 40, (diff.mean(), diff.max())


@pytest.mark.slow
def test_a_scene_file_glb_loads_every_layer_bent(browser, site, tmp_path):
    """`export SCENE.toml --instanced` (the forest: a terrain and 2 000 ten-axis trees, 18 % of them
    here) through the plugin, with the scene's camera, against render_image of the same scene
    without its wind (a GLB holds no wind)."""
    import dataclasses
    import json

    from axialdeform.gl.scene import scene_camera

    folder, url = site
    toml = (ROOT / "examples" / "forest" / "forest.toml").read_text()
    small = tmp_path / "forest.toml"  # fewer trees: a test in software rendering
    small.write_text(toml.replace('"tree-axes.toml"', f'"{ROOT / "examples" / "forest" / "tree-axes.toml"}"')
                     .replace('"../landscape/', f'"{ROOT / "examples" / "landscape"}/').replace("count = 2000", "count = 360"))
    scene = ad.Scene.load(small)
    scene = dataclasses.replace(scene, wind=None)
    cli("export", small, "--instanced", "-o", folder / "forest.glb")
    cam = scene_camera(scene, SIZE[0] / SIZE[1])
    place = ("camera.position.fromArray(" + json.dumps(list(map(float, cam.eye))) +
             "); camera.up.fromArray(" + json.dumps(list(map(float, cam.up))) + "); camera.fov = " + str(cam.fovy) +
             "; camera.near = " + str(cam.near) + "; camera.far = " + str(cam.far) + "; camera.updateProjectionMatrix();"
             " camera.lookAt(...(" + json.dumps(list(map(float, cam.target))) + ")); camera.updateMatrixWorld();"
             " let bent = 0; window.app.gltf.scene.traverse((o) => { if (o.isAxialInstancedMesh) bent += 1; });"
             " if (bent < 1) throw new Error('no AxialInstancedMesh');")
    shot, errors = example_picture(browser, url + "gltf.html?file=forest.glb", place)
    look = ad.Look(ground=False, shadow=False)
    ref = ad.render_image(scene, size=SIZE, look=look, camera=ad.Camera(cam.eye, cam.target, cam.up, cam.fovy,
                                                                          cam.near, cam.far))
    Image.fromarray(np.concatenate([shot, ref], 1)).save(folder / "forest-three-render.png")
    assert errors == []
    assert iou(shot, ref) >= 0.97, iou(shot, ref)


@pytest.mark.slow
def test_unbent_would_not_match(browser, site):
    """The IoU test can fail: the same GLB drawn by plain GLTFLoader (no plugin: unbent) is off."""
    folder, url = site
    page = (folder / "gltf.html").read_text()
    plain = page.replace("new GLTFLoader().register((parser) => new AxialGLTFPlugin(parser))", "new GLTFLoader()")
    assert plain != page
    (folder / "plain.html").write_text(plain)
    shot, errors = example_picture(browser, url + "plain.html")
    ref = render_reference(folder, ["stone", folder / "stones.adp"])
    assert errors == []
    assert iou(shot, ref) < 0.9
    assert mask(shot).sum() > 0.6 * mask(ref).sum()  # but every instance is there, placed and sized


@pytest.fixture(scope="module")
def checks(browser, site):
    _folder, url = site
    page = browser.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)  # shader errors
    page.goto(url + "checks.html")
    page.wait_for_function("window.checksReady === true", timeout=120_000)
    yield page, errors
    page.close()


@pytest.mark.slow
def test_the_bent_instance_casts_a_bent_shadow(checks):
    page, errors = checks
    bent, flat = (np.array(m) for m in page.evaluate("window.checks.shadows(true)"))
    assert bent.sum() > 200 and flat.sum() > 200  # both shadows are there
    assert (bent ^ flat).sum() > 0.15 * (bent | flat).sum()  # and they differ
    # without the module's depth material the shadow would be the unbent one's
    plain_bent, plain_flat = (np.array(m) for m in page.evaluate("window.checks.shadows(false)"))
    assert (plain_bent ^ plain_flat).sum() < 0.02 * (plain_bent | plain_flat).sum()
    assert errors == []


@pytest.mark.slow
def test_standard_physical_lambert_basic_keep_maps_lights_fog_and_tone_mapping(checks):
    page, errors = checks
    out = page.evaluate("window.checks.materials()")
    ref = np.array(out["basic"]["plain"]["mask"])
    assert ref.sum() > 500
    for kind, v in out.items():
        for variant, r in v.items():  # every material and variant draws the same bent silhouette
            m = np.array(r["mask"])
            assert (m & ref).sum() / (m | ref).sum() > 0.97, (kind, variant)
        assert v["map"]["colours"] >= v["plain"]["colours"] + (1 if kind == "basic" else 10), kind  # the checker shows
        fog, plain = np.array(v["fog"]["mean"]), np.array(v["map"]["mean"])
        assert fog[0] - fog[1] > plain[0] - plain[1] + 20, kind  # red fog
        assert np.abs(np.array(v["tone"]["mean"]) - plain).max() > 3, kind  # ACES changes the colours
        if kind != "basic":  # lit: shading varies over the bent surface
            assert v["plain"]["colours"] > 8, kind
    assert out["basic"]["plain"]["colours"] <= 2  # unlit white
    assert errors == []


@pytest.mark.slow
def test_a_bake_draws_what_bending_draws(checks):
    """bake(): the instances bent once by transform feedback and drawn as plain geometry look as
    when bent every frame; raycasting still answers with instanceId; setParams bends again."""
    page, errors = checks
    out = page.evaluate("window.checks.baking()")
    assert out["baked"] is True and out["calls"] == 1
    bent, baked = (np.array(out[k], dtype=np.float64).reshape(128, 128, 4)[..., :3] for k in ("bentPx", "bakedPx"))
    assert (bent.max(axis=2) > 0).sum() > 2000
    assert np.abs(bent - baked).mean() < 0.5 and np.abs(bent - baked).max() <= 24
    assert out["hitId"] is not None
    assert out["after"] == {"baked": False, "children": 0}
    assert errors == []


@pytest.mark.slow
def test_dispose_gives_back_what_the_mesh_made(checks):
    page, errors = checks
    out = page.evaluate("window.checks.disposing()")
    assert out["during"]["geometries"] > out["before"]["geometries"]  # the mesh and its bake were on the GPU
    assert out["after"] == out["before"], out
    assert errors == []


@pytest.mark.slow
def test_the_gpu_bend_in_three_equals_the_cpu_reference(checks, site):
    """World positions and normals of 60 stones as the module's shader bends them on the GPU (read back
    from bake()'s transform feedback: the same BEND as the materials' vertex shaders) against
    axialdeform.deform: positions to 2e-6 L (measured 4.7e-7 L), normals exact (cof(J) n) to 1e-5
    (measured 3.2e-7)."""
    page, errors = checks
    folder, _url = site
    out = page.evaluate("window.checks.gpuBend()")
    stone = ad.load_mesh("stone")
    params = ad.read_params(folder / "stones.adp", mesh=stone)
    pos, nrm = ad.deform(stone, params)
    assert (out["n"], out["V"]) == (len(params), stone.vertex_count)
    gpu_pos = np.array(out["positions"]).reshape(pos.shape)
    gpu_nrm = np.array(out["normals"]).reshape(nrm.shape)
    assert np.abs(gpu_pos - pos).max() < 2e-6 * stone.axis.length, np.abs(gpu_pos - pos).max()
    assert np.abs(gpu_nrm - nrm).max() < 1e-5, np.abs(gpu_nrm - nrm).max()
    assert errors == []


@pytest.mark.slow
def test_raycasting_hits_the_bent_surface(checks):
    page, errors = checks
    bent = page.evaluate("window.checks.raycasts(window.checks.bent)")
    flat = page.evaluate("window.checks.raycasts(window.checks.flat)")
    assert bent["ids"] and bent["drawn"] > 100
    assert bent["agreement"] >= 0.98, bent["agreement"]
    assert flat["agreement"] >= 0.98, flat["agreement"]
    differ = np.array(bent["mask"]) ^ np.array(flat["mask"])
    assert differ.sum() > 0.2 * bent["drawn"]  # the bend moved the surface the rays find
    windy = page.evaluate("window.checks.raycasts(window.checks.bent, "
                          "{direction: [0, 0, 1], strength: 0.5, gustiness: 0, frequency: 0.5})")
    assert windy["agreement"] >= 0.98 and windy["ids"], windy["agreement"]
    assert (np.array(windy["mask"]) ^ np.array(bent["mask"])).sum() > 0.1 * bent["drawn"]  # the wind moved it
    assert errors == []


@pytest.mark.slow
def test_npm_pack_installs_in_a_fresh_folder_and_runs_the_example(browser, tmp_path):
    npm = shutil.which("npm")
    assert npm, "npm is required (the README's test command)"
    r = subprocess.run([npm, "pack", "--pack-destination", str(tmp_path)], cwd=JS, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    tarball = next(tmp_path.glob("axialdeform-three-*.tgz"))
    app = make_site(tmp_path / "app", modules=False)
    r = subprocess.run([npm, "install", "--no-audit", "--no-fund", str(tarball), "three"], cwd=app,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    installed = app / "node_modules" / "axialdeform-three"
    assert (installed / "src" / "glsl.js").is_file() and (installed / "src" / "index.d.ts").is_file()
    assert not (installed / "test").exists()  # the tarball carries the module, not its tests
    s = Server(app)
    try:
        shot, errors = example_picture(browser, s.url + "gltf.html")
        webgpu = _under_webgpu_renderer(browser, app, s.url)
    finally:
        s.close()
    ref = render_reference(app, ["stone", app / "stones.adp"])
    assert errors == []
    assert iou(shot, ref) >= 0.97, iou(shot, ref)
    # never a silent unbent picture: the latest three's WebGPURenderer (its WebGL 2 backend,
    # what headless Chromium runs) and its node materials are refused in words, not drawn unbent
    assert webgpu["version"] >= "170", webgpu
    assert webgpu["node"].startswith("AxialError: AxialInstancedMesh: MeshStandardNodeMaterial is a node material"), webgpu
    assert webgpu["render"].startswith("AxialError: AxialInstancedMesh: three's WebGPURenderer"), webgpu
    assert "WebGLRenderer" in webgpu["render"], webgpu  # what to do instead (gltf.html above: it draws right)
    assert webgpu["webgpuEntry"]["material"] == "MeshStandardNodeMaterial", webgpu  # or axialdeform-three/webgpu
    assert webgpu["webgpuEntry"]["moved"] > 0.5, webgpu  # instance 0 read back placed far from the origin


def _under_webgpu_renderer(browser, app: Path, url: str) -> dict:
    """AxialInstancedMesh with three/webgpu (the installed three): a node material, then a classic one
    drawn by WebGPURenderer (forceWebGL: its WebGL 2 backend)."""
    (app / "webgpu.html").write_text("""<!doctype html><html><body><script type="importmap">
{"imports": {"three": "./node_modules/three/build/three.webgpu.js",
             "three/webgpu": "./node_modules/three/build/three.webgpu.js",
             "three/tsl": "./node_modules/three/build/three.tsl.js",
             "axialdeform-three": "./node_modules/axialdeform-three/src/index.js",
             "axialdeform-three/webgpu": "./node_modules/axialdeform-three/src/webgpu.js"}}</script>
<script type="module">
import * as THREE from 'three';
import { AxialInstancedMesh, parseADP } from 'axialdeform-three';
const out = { version: THREE.REVISION };
const said = (e) => `${e.name}: ${e.message}`;
const record = parseADP(await (await fetch('stones.adp')).arrayBuffer(), 'stones.adp');
const geometry = new THREE.IcosahedronGeometry(0.5, 2);
try { new AxialInstancedMesh(geometry, new THREE.MeshStandardNodeMaterial(), record); out.node = 'accepted'; }
catch (e) { out.node = said(e); }
const scene = new THREE.Scene();
scene.add(new AxialInstancedMesh(geometry, new THREE.MeshStandardMaterial(), record));
const camera = new THREE.PerspectiveCamera(40, 4 / 3, 0.1, 100);
camera.position.set(7, 5, 7);
camera.lookAt(0, 0, 0);
const renderer = new THREE.WebGPURenderer({ forceWebGL: true });
renderer.setSize(160, 120);
await renderer.init();
try { await renderer.renderAsync(scene, camera); out.render = 'drawn'; } catch (e) { out.render = said(e); }
// and the entry made for it draws them bent, and reads them back bent (the installed tarball's webgpu.js)
try {
  const webgpu = await import('axialdeform-three/webgpu');
  const bent = new webgpu.AxialInstancedMesh(geometry, new THREE.MeshStandardMaterial(), record);
  const s2 = new THREE.Scene();
  s2.add(bent);
  renderer.render(s2, camera);
  const r = await bent.bendAsync(renderer, [0]);
  out.webgpuEntry = { material: bent.material.type, moved: Math.abs(r.positions[0] - geometry.getAttribute('position').getX(0)) };
} catch (e) { out.webgpuEntry = said(e); }
window.result = out;
</script></body></html>""")
    return page_result(browser, url + "webgpu.html", "result")[0]


def page_result(browser, url: str, name: str) -> tuple[dict, list]:
    """``window[name]`` of the page at ``url`` once it is set, and the page's errors."""
    page = browser.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    try:
        page.goto(url)
        page.wait_for_function(f"window.{name} !== undefined", timeout=120_000)
        return page.evaluate(f"window.{name}"), errors
    finally:
        page.close()


def test_the_type_declarations_compile():
    """src/index.d.ts against three's own types (@types/three), for the README's usage."""
    node = shutil.which("node")
    tsc = JS / "node_modules" / "typescript" / "bin" / "tsc"
    assert tsc.is_file(), "js/node_modules/typescript is missing: the README's test command runs `npm ci --prefix js`"
    r = subprocess.run([node, str(tsc), "-p", "test/types"], cwd=JS, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr


README_JS = re.findall(r"^```js\n(.*?)^```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S | re.M)


@pytest.mark.slow
def test_the_readme_js_block_runs(browser, site):
    """The README's three.js usage, verbatim, in a page that gives it `scene` and `geometry`."""
    assert len(README_JS) == 1
    folder, url = site
    page_text = (ROOT / "tests" / "web" / "three" / "checks.html").read_text()
    head = page_text.split("<script type=\"module\">", 1)[0]
    (folder / "readme.html").write_text(head + """<script type="module">
import * as THREE from 'three';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { mergeVertices } from 'three/addons/utils/BufferGeometryUtils.js';
const scene = new THREE.Scene();
const obj = (await new OBJLoader().loadAsync('stone.obj')).children[0].geometry;
obj.deleteAttribute('normal');
const geometry = mergeVertices(obj);
geometry.computeVertexNormals();
// ---- the README's block
""" + README_JS[0] + """
// ----
const bent = [];
scene.traverse((o) => { if (o.isAxialInstancedMesh) bent.push(o.count); });
const renderer = new THREE.WebGLRenderer();
renderer.setSize(200, 150);
const camera = new THREE.PerspectiveCamera(40, 4 / 3, 0.1, 100);
camera.position.set(7, 5, 7);
camera.lookAt(0, 0, 0);
scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 2));
renderer.render(scene, camera);
window.readme = { bent, programs: renderer.info.programs.length };
</script></body></html>
""")
    out, errors = page_result(browser, url + "readme.html", "readme")
    assert errors == []
    assert out["bent"] == [60, 60]  # the GLB's node and the .adp's mesh, 60 stones each
