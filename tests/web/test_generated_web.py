"""Generated layers in the browser (docs/generate.md): the page of ``axialdeform web SCENE.toml`` and the
npm module's generated AxialInstancedMesh make the Python library's records from the recipe on the GPU
(glsl/generate.glsl by WebGL 2 transform feedback), in the tiles around the camera; no per-instance
file travels.  Debian's chromium, WebGL 2 on SwiftShader; nothing here skips."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from urllib.parse import quote

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.generate import Generate, generate_tiles, recipe_uniforms, tile_size, tiles_around

from helpers.browser import SIZE, SKY, Visit, iou, widget_page, widget_state
from helpers.generated_scenes import GLTF_SCENE, HILLS, LANDSCAPE, TREES, close, learned_clumps
from helpers.three_site import Server, example_picture, make_site
from helpers.three_site import iou as three_iou
from helpers.three_site import mask as three_mask

ROOT = Path(__file__).resolve().parents[2]
GRASS = LANDSCAPE / "grass.obj"

SCENE = """
background = [0.80, 0.87, 0.95]
[camera]
elevation = {elevation}
azimuth = 35
[light]
direction = [0.4, 0.9, 0.3]
ambient = 0.4
[[layer]]
name = "stones"
mesh = "stone"
color = [0.58, 0.55, 0.5]
[layer.generate]
rate = {rate}
tile = 8.0
min_distance = 0.4
seed = 11
bend = 0.15
scale = [0.5, 1.0]
extent = {extent}
reach = {reach}
[[layer]]
name = "grass"
mesh = "grass.obj"
color = [0.33, 0.5, 0.2]
[layer.generate]
rate = 2.0
tile = 8.0
min_distance = 0.2
seed = 2
bend = 0.25
twist = 0.6
yaw = [-0.5, 0.5]
extent = {extent}
reach = {reach}
"""


def _scene(folder: Path, name: str, rate=0.3, extent="[-12, -12, 12, 12]", reach=20.0, elevation=18) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "grass.obj").write_bytes(GRASS.read_bytes())
    path = folder / f"{name}.toml"
    path.write_text(SCENE.format(rate=rate, extent=extent, reach=reach, elevation=elevation), encoding="utf-8")
    return path


def _web(scene: Path, out: Path):
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", str(scene), "-o", str(out), "--size",
                        f"{SIZE[0]}x{SIZE[1]}"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


def test_a_generated_page_carries_the_recipe_and_no_instance_file(tmp_path):
    """The page's files do not grow with the rate: only the recipe's numbers in scene.json change."""
    sizes = {}
    for rate in (0.3, 3.0):
        scene = _scene(tmp_path / f"r{rate}", "s", rate=rate, extent="[-40, -40, 40, 40]")
        _web(scene, tmp_path / f"page{rate}")
        files = {p.relative_to(tmp_path / f"page{rate}").as_posix(): p.stat().st_size
                 for p in (tmp_path / f"page{rate}").rglob("*") if p.is_file()}
        assert not [f for f in files if f.endswith(".adp")], files
        sizes[rate] = files
        config = json.loads((tmp_path / f"page{rate}" / "scene.json").read_text())
        loaded = ad.Scene.load(scene)
        for entry, layer in zip(config["layers"], loaded.layers):
            assert "params_file" not in entry
            assert entry["generate"]["uniforms"] == json.loads(json.dumps(recipe_uniforms(layer.generate.generate,
                                                                                          layer.mesh)))
    assert sizes[0.3].keys() == sizes[3.0].keys()
    for name, size in sizes[0.3].items():
        assert abs(size - sizes[3.0][name]) <= (64 if name == "scene.json" else 0), name


@pytest.fixture(scope="module")
def generated_site(tmp_path_factory):
    """Two scene files as pages: a walk through many tiles, and one tile (its extent) for the picture."""
    base = tmp_path_factory.mktemp("generated") / "gen site"
    walk = _scene(base, "walk")
    for f in ("terrain.png", "stone_density.png"):
        (base / f).write_bytes((LANDSCAPE / f).read_bytes())
    (base / "tree-axes.toml").write_bytes((ROOT / "examples" / "forest" / "tree-axes.toml").read_bytes())
    trees = base / "trees.toml"
    trees.write_text(TREES, encoding="utf-8")
    _web(trees, base / "trees")
    hills = base / "hills.toml"
    hills.write_text(HILLS, encoding="utf-8")
    _web(hills, base / "hills")
    learned = learned_clumps(base, hills)
    _web(learned, base / "learned")
    one = _scene(base, "one", rate=0.5, extent="[0, 0, 8, 8]", reach=2.0, elevation=30)
    _web(walk, base / "walk")
    _web(one, base / "one")
    _web(one, base / "one.html")
    server = Server(base)
    yield {"base": base, "url": server.url, "walk": walk, "one": one, "hills": hills, "trees": trees, "learned": learned}
    server.close()


def _check_records(layers: list, scene: Path) -> int:
    """Every generated layer's tiles are the ones within reach of the page's target, and its records the
    Python library's for them (hash exact: positions and angles to float32 rounding).  Returns the count."""
    loaded = {layer.name: layer for layer in ad.Scene.load(scene).layers}
    total = 0
    for g in layers:
        layer = loaded[g["name"]]
        recipe = layer.generate
        x, _, z = g["target"]
        want_tiles = tiles_around(recipe.generate, x, z, recipe.reach)
        # the set (its order: nearest first when it was made, the target since then moved within it)
        assert sorted(g["tiles"]) == sorted(want_tiles.tolist()), g["name"]
        want = generate_tiles(recipe.generate, layer.mesh, g["tiles"], recipe.maps)
        got = np.asarray(g["data"], np.float32).reshape(-1, g["width"])
        if recipe.maps.heights is None and recipe.maps.density is None and recipe.generate.choice == (0, 1):  # all kept
            assert got.shape[0] == len(want_tiles) * tile_size(recipe.generate)[0] ** 2
        assert close(got, want) <= 1e-6, (g["name"], close(got, want))
        total += got.shape[0]
    return total


@pytest.mark.slow
def test_the_page_makes_the_python_records_and_walks(browser, generated_site):
    url = generated_site["url"] + quote("walk") + "/index.html"
    v = Visit(browser, url)
    try:
        assert v.state["ready"] is True, v.state
        layers = v.page.evaluate("window.axialdeformView.generated()")
        assert [g["name"] for g in layers] == ["stones", "grass"]
        held = _check_records(layers, generated_site["walk"])
        assert held == v.state["instances"] > 1000
        assert f"{held:,} instances" in v.page.locator(".axd-status").inner_text()
        assert v.errors == []
    finally:
        v.close()
    # walking: the camera and its target move 0.8, 0.4 a frame; the tiles follow, the count stays bounded
    v = Visit(browser, url + "?walk=0.8,0.4")
    try:
        v.page.wait_for_function("window.axialdeformView.frames >= 40", timeout=240_000)
        layers = v.page.evaluate("window.axialdeformView.generated()")
        x, _, z = layers[0]["target"]
        start = json.loads((generated_site["base"] / "walk" / "scene.json").read_text())["camera"]["target"]
        assert x - start[0] >= 30 and z - start[2] >= 15, (x, z, start)
        moved = _check_records(layers, generated_site["walk"])
        assert abs(moved - held) <= 0.25 * held  # bounded: the tiles within reach, wherever the camera is
        assert v.errors == []
    finally:
        v.close()


# counts what the page's WebGL 2 context reads back and uploads (bytes), from the page's first script on
_GL_TRAFFIC = """(() => {
  const t = window.__glTraffic = { reads: 0, readBytes: 0, pixels: 0, uploads: 0 };
  const P = WebGL2RenderingContext.prototype;
  const getBuffer = P.getBufferSubData, readPixels = P.readPixels, data = P.bufferData, sub = P.bufferSubData;
  P.getBufferSubData = function (...a) { t.reads += 1; t.readBytes += a[2].byteLength; return getBuffer.apply(this, a); };
  P.readPixels = function (...a) { t.pixels += a[2] * a[3]; return readPixels.apply(this, a); };
  P.bufferData = function (...a) { if (typeof a[1] !== 'number' && a[1]) t.uploads += a[1].byteLength; return data.apply(this, a); };
  P.bufferSubData = function (...a) { t.uploads += a[2].byteLength; return sub.apply(this, a); };
})();"""


@pytest.mark.slow
def test_the_page_draws_the_gpus_records_and_reads_none_back(browser, generated_site):
    """Walking, the page makes tile sets again and again, and neither reads a record back nor uploads one:
    the GPU writes the attributes three draws from (js/src/webgl/tiles.js); what comes back is one pixel a
    tile set (the count kept) and the page's own first-frame pixel.  Asked for its records, it reads them."""
    page = browser.new_page(viewport={"width": SIZE[0], "height": SIZE[1] + 40})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.add_init_script(_GL_TRAFFIC)
    try:
        page.goto(generated_site["url"] + "walk/index.html?walk=1.6,0.8")
        page.wait_for_function("window.axialdeform && window.axialdeform.ready === true", timeout=120_000)
        page.wait_for_function("window.axialdeformView.frames >= 3", timeout=120_000)
        before = page.evaluate("({...window.__glTraffic})")
        sets = page.evaluate("""async () => { const v = window.axialdeformView, seen = new Set();
            const key = () => JSON.stringify(v.generated({records: false}).map((g) => g.tiles));
            seen.add(key());
            for (let k = 0; k < 400 && seen.size < 4; k++) { await new Promise(requestAnimationFrame); seen.add(key()); }
            return seen.size; }""")
        after = page.evaluate("({...window.__glTraffic})")
        assert sets >= 4, sets  # three tile sets made while walking
        assert after["reads"] == before["reads"] and after["readBytes"] == before["readBytes"], (before, after)
        assert after["pixels"] - before["pixels"] <= 2 * 2 * sets  # the count kept: a pixel a layer a set
        # no upload of the instances (a stone's record is 76 bytes; 2 layers hold thousands): a few uniforms' worth
        assert after["uploads"] - before["uploads"] < 4096, (before, after)
        counts = page.evaluate("window.axialdeformView.generated()")
        assert page.evaluate("window.__glTraffic.reads") > after["reads"]  # records() reads them back, when asked
        assert _check_records(counts, generated_site["walk"]) > 1000
        assert errors == []
    finally:
        page.close()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["folder", "single file"])
def test_the_generated_page_shows_what_render_shows(browser, generated_site, kind):
    """One tile, and the scene's extent that tile: the page's picture is render's, its ground plane too (a scene
    without a terrain stands on render's ground, not over the sky colour)."""
    url = (generated_site["url"] + "one/index.html" if kind == "folder"
           else (generated_site["base"] / "one.html").as_uri())
    scene = ad.Scene.load(generated_site["one"])
    render = ad.render_image(scene, size=SIZE, look=scene.look.replace(shadow=False))
    sky = np.asarray(SKY) * 255
    assert np.abs(render[-SIZE[1] // 4:].astype(np.float64) - sky).max(axis=2).min() > 12  # render's ground, not the sky
    v = Visit(browser, url)
    try:
        assert v.state["ready"] is True, v.state
        assert v.state["instances"] == sum(len(layer.params) for layer in scene.layers), v.state
        shot = v.silhouette()
        assert iou(shot, render, SKY) >= 0.95, iou(shot, render, SKY)
        assert np.abs(shot.astype(np.float64) - render).mean() < 3.0
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_the_notebook_widget_generates_a_scene_files_layers(browser, generated_site, tmp_path):
    """SceneWidget(SCENE.toml) of generated layers: no parameter file travels; the widget's front end
    (the page's code) makes the tiles within reach of the camera's target."""
    import base64

    from axialdeform.widget import SceneWidget

    w = SceneWidget(ad.Scene.load(generated_site["walk"]), size=SIZE)
    assert w.params_adp == b"" and not [n for n in w.files if n.endswith(".adp")]
    state = widget_state(w)
    state["files"] = {n: {"b64": base64.b64encode(b).decode()} for n, b in w.files.items()}
    page, errors = widget_page(browser, tmp_path, state, w._esm)
    try:
        status = page.evaluate("window.widgetStatus")
        assert status == {"ready": True, "instances": w.config["instances"]} and status["instances"] > 1000, status
        assert errors == []
    finally:
        page.close()


@pytest.mark.slow
def test_a_generated_page_on_a_height_map_keeps_and_tints_as_python_and_render(browser, generated_site):
    """Stones where the density map says and below an altitude, leaning with the ground, half sunk; grass on
    gentle slopes above it, tinted:
    the page's records are the Python library's, its picture render's, and no per-instance file travels."""
    assert [f.name for f in (generated_site["base"] / "hills").glob("*.adp")] == ["terrain.adp"]
    v = Visit(browser, generated_site["url"] + "hills/index.html")
    scene = ad.Scene.load(generated_site["hills"])
    try:
        assert v.state["ready"] is True, v.state
        layers = v.page.evaluate("window.axialdeformView.generated()")
        held = _check_records(layers, generated_site["hills"])
        assert held == v.state["instances"] == sum(len(x.params) for x in scene.layers)
        grass = np.asarray(layers[1]["data"], np.float32).reshape(-1, 22)
        assert grass.shape[0] > 500 and np.ptp(grass[:, 19]) > 0.1  # tinted, each its own
        shot = v.silhouette()
        render = ad.render_image(scene, size=SIZE, look=scene.look.replace(ground=False, shadow=False))
        # the terrain fills most of both pictures: compare where they differ from the bare terrain
        bare = ad.render_image(type(scene)(
            path=scene.path, up=scene.up, camera=scene.camera, look=scene.look, terrain=scene.terrain,
            terrain_color=scene.terrain_color), size=SIZE, look=scene.look.replace(ground=False, shadow=False))
        on = lambda img: np.abs(img.astype(np.float64) - bare).max(axis=2) > 24  # noqa: E731
        a, b = on(shot), on(render)
        assert iou(shot, render, SKY) >= 0.95, iou(shot, render, SKY)  # the silhouette, as every page test
        # and the instances alone (thin blades: their edges' antialiasing differs)
        assert b.mean() > 0.03 and (a & b).sum() / (a | b).sum() >= 0.85, (b.mean(), (a & b).sum() / (a | b).sum())
        assert np.abs(shot.astype(np.float64) - render).mean() < 3.0
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_a_learned_layer_in_clumps_is_the_python_records_on_the_page(browser, generated_site):
    """A layer learned from a clumped survey (clump_cells, clump_radius, its density map) with a clearing painted
    into its mask: the page makes the Python library's records, and none in the clearing."""
    v = Visit(browser, generated_site["url"] + "learned/index.html")
    try:
        assert v.state["ready"] is True, v.state
        layers = v.page.evaluate("window.axialdeformView.generated()")
        scene = ad.Scene.load(generated_site["learned"])
        assert scene.layers[0].generate.generate.clumped and scene.layers[0].generate.mask is not None
        assert _check_records(layers, generated_site["learned"]) > 100
        p = np.concatenate([np.asarray(g["data"], np.float32).reshape(-1, g["width"]) for g in layers])[:, [10, 12]]
        assert not (np.hypot(p[:, 0], p[:, 1]) < 3.9).any()  # the painted clearing
        assert v.errors == []
    finally:
        v.close()


PAINT = """(async ([name, strokes]) => {
  const v = window.axialdeformView;
  const changed = strokes.map(([x, z, r, erase]) => v.paint(name, x, z, r, erase));
  const frames = v.frames;  // the tiles are made again on the next frames
  await new Promise((ok) => { const wait = () => (v.frames >= frames + 2 ? ok() : requestAnimationFrame(wait)); wait(); });
  return { changed, png: Array.from(await v.mask(name)) };
})"""


def _painted(base: Path, stem: str, png: bytes) -> Path:
    """A copy of the hills scene file named ``stem`` beside it, with ``png`` as its stones' mask."""
    from axialdeform.core.brush import mask_path

    from helpers.generated_scenes import HILLS as hills_text

    scene = base / f"{stem}.toml"
    scene.write_text(hills_text, encoding="utf-8")
    mask_path(scene, "stones").write_bytes(png)
    return scene


@pytest.mark.slow
def test_the_page_brush_paints_where_a_layer_grows_and_its_mask_reloads(browser, generated_site):
    """Scripted strokes on the page (the brush a drag paints with B): a clearing erased in the stones, part of
    it painted back; the tiles are made again at once, and the page's records are the Python library's for the
    scene with the page's saved mask (SCENE-LAYER-mask.png, 8-bit grey) beside it; none in what stays erased."""
    from axialdeform.core.surface import load_mask

    v = Visit(browser, generated_site["url"] + "hills/index.html")
    try:
        assert v.state["ready"] is True, v.state
        x, _, z = v.page.evaluate("window.axialdeformView.generated({records: false})")[0]["target"]
        before = v.page.evaluate("window.axialdeformView.generated()")
        got = v.page.evaluate(PAINT, ["stones", [[x, z, 6.0, True], [x + 4.0, z, 1.5, False], [x, z, 6.0, True]]])
        assert got["changed"] == [True, True, True]
        layers = v.page.evaluate("window.axialdeformView.generated()")
        png = bytes(got["png"])
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        scene = _painted(generated_site["base"], "hills_painted", png)
        mask = load_mask(scene.with_name("hills_painted-stones-mask.png"))
        assert mask.shape == (512, 512) and set(np.unique(mask)) == {0.0, 1.0}
        assert _check_records(layers, scene) > 100  # the page's records: the reloaded scene's, the mask folded in
        stones = np.asarray(layers[0]["data"], np.float32).reshape(-1, layers[0]["width"])
        was = np.asarray(before[0]["data"], np.float32).reshape(-1, before[0]["width"])
        near = lambda p: np.hypot(p[:, 10] - x, p[:, 12] - z) < 5.5  # noqa: E731
        assert near(was).sum() > 10 and near(stones).sum() == 0, (near(was).sum(), near(stones).sum())
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_the_widget_brush_saves_its_mask_beside_the_scene_file(browser, generated_site, tmp_path):
    """The notebook widget's brush: a painted mask saved (M) comes back to Python, which writes it beside the
    scene file, where the scene reads it again; a bad one is refused in words and replaces nothing."""
    import base64

    from axialdeform.widget import SceneWidget

    scene = _painted(generated_site["base"], "hills_widget", b"")
    scene.with_name("hills_widget-stones-mask.png").unlink()
    w = SceneWidget(ad.Scene.load(scene), size=SIZE)
    state = widget_state(w)
    state["files"] = {n: {"b64": base64.b64encode(b).decode()} for n, b in w.files.items()}
    page, errors = widget_page(browser, tmp_path, state, w._esm)
    try:
        sent = page.evaluate("""(async () => {
          const view = document.getElementById('out').axialdeformView;
          await view.ready;
          const t = view.generated({records: false})[0].target;
          view.paint('stones', t[0], t[2], 5.0, true);
          const sent = [];
          window.widgetModel.send = (content, callbacks, buffers) => sent.push([content, Array.from(new Uint8Array(buffers[0]))]);
          await view.saveMasks();
          return sent;
        })()""")
        assert len(sent) == 1 and sent[0][0] == {"type": "mask", "layer": "stones", "file": "hills_widget-stones-mask.png"}
        w._on_mask(w, sent[0][0], [bytes(sent[0][1])])
        assert w.masks_saved == [str(scene.with_name("hills_widget-stones-mask.png"))]
        assert ad.Scene.load(scene).layers[0].generate.mask is not None  # read again with the scene
        w._on_mask(w, {"type": "mask", "layer": "stones"}, [b"not a png"])
        assert "mask" in w.status.get("mask_error", "") and len(w.masks_saved) == 1
        assert scene.with_name("hills_widget-stones-mask.png").read_bytes() == bytes(sent[0][1])  # nothing replaced
        assert errors == []
    finally:
        page.close()


@pytest.mark.slow
def test_a_generated_page_of_trees_bends_every_level_as_python(browser, generated_site):
    """A mesh of ten axes: the page makes axis 0's numbers and every child axis's (each level its bend, the
    joints closed) on the GPU; the records are the Python library's.  Beside them a layer of two meshes by
    weights: two layers on one grid, each its share."""
    v = Visit(browser, generated_site["url"] + "trees/index.html")
    try:
        assert v.state["ready"] is True, v.state
        layers = v.page.evaluate("window.axialdeformView.generated()")
        assert [g["name"] for g in layers] == ["trees", "ground-1", "ground-2"] and layers[0]["width"] == 19 + 90
        held = _check_records(layers, generated_site["trees"])
        assert held == v.state["instances"] > 40
        n = [len(g["data"]) // g["width"] for g in layers]
        assert 2 * n[1] < n[2] < 5 * n[1]  # weights 1 : 3
        children = np.asarray(layers[0]["data"], np.float32).reshape(n[0], -1)[:, 10:100]
        assert np.abs(children).max() > 0.01
        assert v.errors == []
    finally:
        v.close()


RECIPE = {"rate": 1.0, "tile": 4.0, "min_distance": 0.4, "seed": 5, "bend": 0.15, "scale": [0.6, 1.2], "yaw": [0.5, 2.0],
          "reach": 5.0}


@pytest.fixture(scope="module")
def three_site(tmp_path_factory):
    folder = make_site(tmp_path_factory.mktemp("gen-three") / "site")
    s = Server(folder)
    yield folder, s.url
    s.close()


def _generated_app(browser, page_url):
    """examples/web/generated.html at ``page_url`` with its first frames drawn: (page, its errors)."""
    page = browser.new_page(viewport={"width": 480, "height": 360})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(page_url)
    page.wait_for_function("window.app !== undefined && window.app.frames >= 2", timeout=120_000)
    return page, errors


@pytest.mark.slow
def test_the_modules_generated_mesh_makes_the_python_records_in_a_three_app(browser, three_site):
    """examples/web/generated.html: a generated AxialInstancedMesh with three's own MeshStandardMaterial, its generator's
    numbers computed by the module from the geometry (recipeUniforms), against the Python library."""
    folder, url = three_site
    page_url = url + "generated.html?recipe=" + quote(json.dumps(RECIPE))
    page, errors = _generated_app(browser, page_url)
    try:
        got = page.evaluate("""() => { const s = window.app.stones;
            return { tiles: s.tiles, width: s.layout.numbersPerInstance, count: s.count,
                     uniforms: s.generatorUniforms, slots: s.count, kept: s.kept, cpu: s.data.length,
                     sphere: [...s.boundingSphere.center.toArray(), s.boundingSphere.radius],  // the recipe's bound
                     data: Array.from(s.records()) }; }""")
        # picking: a ray straight down onto the first kept instance hits that instance (raycasting reads the
        # tile set back, once, when first asked), its instanceId the slot the GPU drew it in
        f = got["width"]
        hit = page.evaluate("""([x, z]) => { const { THREE, stones } = window.app;
            const ray = new THREE.Raycaster(new THREE.Vector3(x, 50, z), new THREE.Vector3(0, -1, 0));
            const hits = ray.intersectObject(stones);
            if (!hits.length) return null;
            const f = stones.layout.numbersPerInstance, id = hits[0].instanceId;
            return { id, slots: stones.count, cpu: stones.data.length, at: Array.from(stones.data.subarray(id * f + 10, id * f + 13)),
                     point: hits[0].point.toArray() }; }""", [got["data"][10], got["data"][12]])
    finally:
        page.close()
    assert hit is not None and 0 <= hit["id"] < hit["slots"], hit
    # drawing needs no CPU copy of the records: one row until the raycast asked, then one a slot
    assert got["cpu"] == f and hit["cpu"] == hit["slots"] * f
    assert np.allclose(hit["at"], got["data"][10:13], atol=1e-5), (hit, got["data"][:f])
    assert errors == []
    mesh = ad.load_mesh(folder / "stone.obj")
    recipe = Generate(**{k: v for k, v in RECIPE.items() if k != "reach"})
    want_u = recipe_uniforms(recipe, mesh)
    for k, v in want_u.items():
        assert np.allclose(got["uniforms"][k], v, rtol=1e-6, atol=0), (k, got["uniforms"][k], v)
    tiles = tiles_around(recipe, 0.0, 0.0, RECIPE["reach"])
    assert got["tiles"] == tiles.tolist()
    want = generate_tiles(recipe, mesh, tiles)
    records = np.asarray(got["data"], np.float32).reshape(-1, got["width"])
    assert close(records, want) <= 1e-6, close(records, want)
    # every slot of the tiles drawn, the kept ones counted on the GPU; the bound three sorts by (found from
    # the recipe before any record is read back) holds every instance
    assert got["slots"] == len(tiles) * tile_size(recipe)[0] ** 2 and got["kept"] == len(want)
    from axialdeform.core.bounds import instance_bounds

    centers, radii = instance_bounds(mesh, want)
    assert (np.linalg.norm(centers - got["sphere"][:3], axis=1) + radii <= got["sphere"][3] * (1 + 1e-6)).all()
    # and it draws them as render does (the example's camera; its ground and fog hidden)
    # (the tiles made before that picture, whether or not an animation frame ran yet)
    shot, errors = example_picture(browser, page_url, "window.app.stones.update(renderer, window.app.controls.target);")
    assert errors == []
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    ref = ad.render_image(mesh, want, size=(480, 360), look=look, camera=camera)
    assert three_mask(ref).sum() > 0.05 * ref.size / 3
    assert three_iou(shot, ref) >= 0.95, three_iou(shot, ref)


@pytest.mark.slow
def test_the_generated_mesh_draws_from_the_gpu_with_three_r187(browser, tmp_path):
    """The peer range reaches three r187 (the devDependency three-r187): the GPU-written attributes (three's
    GLBufferAttribute flagged instanced) draw there too -- the same records, the picture render's."""
    folder = make_site(tmp_path / "site")
    (folder / "node_modules" / "three").unlink()
    (folder / "node_modules" / "three").symlink_to(ROOT / "js" / "node_modules" / "three-r187")
    server = Server(folder)
    page_url = server.url + "generated.html?recipe=" + quote(json.dumps(RECIPE))
    try:
        page, errors = _generated_app(browser, page_url)
        got = page.evaluate("""() => { const s = window.app.stones;
            return { revision: window.app.THREE.REVISION, tiles: s.tiles, width: s.layout.numbersPerInstance,
                     kept: s.kept, data: Array.from(s.records()) }; }""")
        page.close()
        shot, errors2 = example_picture(browser, page_url, "window.app.stones.update(renderer, window.app.controls.target);")
    finally:
        server.close()
    assert errors == [] and errors2 == [] and got["revision"] == "187"
    mesh = ad.load_mesh(folder / "stone.obj")
    recipe = Generate(**{k: v for k, v in RECIPE.items() if k != "reach"})
    want = generate_tiles(recipe, mesh, got["tiles"])
    assert got["kept"] == len(want) and close(np.asarray(got["data"], np.float32).reshape(-1, got["width"]), want) <= 1e-6
    look, camera = ad.Look(ground=False, shadow=False), ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    ref = ad.render_image(mesh, want, size=(480, 360), look=look, camera=camera)
    assert three_iou(shot, ref) >= 0.95, three_iou(shot, ref)


@pytest.mark.slow
def test_the_modules_generated_mesh_sways_as_render_sways_a_generated_layer(browser, three_site):
    """A generated AxialInstancedMesh in the wind: its slots change as tiles come and go, so its wind phases hash where
    each instance stands (AXIAL_POSITION_IDS), as render draws a generated layer -- the same picture
    (IoU >= 0.95), closer than with phases by index, and not the still one."""
    folder, url = three_site
    recipe = {**RECIPE, "rate": 0.25, "scale": [1.0, 1.4]}
    wind = {"direction": [1, 0, 0.3], "strength": 0.35, "gustiness": 0.6, "frequency": 0.5, "wavelength": 4.0}
    page_url = url + "generated.html?recipe=" + quote(json.dumps(recipe))
    shot, errors = example_picture(browser, page_url, "window.app.stones.update(renderer, window.app.controls.target);"
                                   f"window.app.stones.setWind({json.dumps(wind)}).setTime(1.3);")
    assert errors == []
    mesh = ad.load_mesh(folder / "stone.obj")
    g = Generate(**{k: v for k, v in recipe.items() if k != "reach"})
    want = generate_tiles(g, mesh, tiles_around(g, 0.0, 0.0, recipe["reach"]))
    w = ad.Wind(direction=tuple(wind["direction"]), strength=wind["strength"], gustiness=wind["gustiness"],
                frequency=wind["frequency"], wavelength=wind["wavelength"])
    look, camera = ad.Look(ground=False, shadow=False), ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    # a generated layer's instances: their phases hash where they stand
    ref = ad.render_image(mesh, want, size=(480, 360), look=look, camera=camera, options=ad.RenderOptions(wind=w, time=1.3,
                                                                                                          position_ids=True))
    by_index = ad.render_image(mesh, want, size=(480, 360), look=look, camera=camera, options=ad.RenderOptions(wind=w, time=1.3))
    still = ad.render_image(mesh, want, size=(480, 360), look=look, camera=camera)
    assert three_iou(shot, ref) >= 0.95, three_iou(shot, ref)
    assert three_iou(shot, by_index) < three_iou(shot, ref) - 0.02 and three_iou(still, ref) < 0.93


@pytest.mark.slow
def test_the_gltf_generated_form_is_generated_by_the_plugin(browser, three_site, tmp_path):
    """export SCENE.toml --generated, loaded by a plain three.js app through AxialGLTFPlugin
    (examples/web/gltf.html): the node becomes a generated AxialInstancedMesh that makes the tiles around the camera
    before it is drawn -- the Python library's records -- and draws them as render does."""
    folder, url = three_site
    (folder / "gen.toml").write_text(GLTF_SCENE)
    r = subprocess.run([sys.executable, "-m", "axialdeform", "export", str(folder / "gen.toml"), "--generated",
                        "-o", str(folder / "gen.glb")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    # (a generated node's tiles are drawn from its second frame on: the first tells it the renderer)
    shot, errors = example_picture(browser, url + "gltf.html?file=gen.glb", "renderer.render(scene, camera);")
    assert errors == []
    page = browser.new_page(viewport={"width": 480, "height": 360})
    try:
        page.goto(url + "gltf.html?file=gen.glb")
        page.wait_for_function("window.app !== undefined", timeout=120_000)
        got = page.evaluate("""() => { const { renderer, scene, camera, gltf } = window.app;
            renderer.render(scene, camera);
            renderer.render(scene, camera);
            let s = null;
            gltf.scene.traverse((o) => { if (o.isAxialInstancedMesh && !s) s = o; });
            return { type: s.type, generated: Boolean(s.recipe), tiles: s.tiles, width: s.layout.numbersPerInstance,
                     eye: camera.position.toArray(), data: Array.from(s.records()) }; }""")
    finally:
        page.close()
    layer = ad.Scene.load(folder / "gen.toml").layers[0]
    recipe = layer.generate
    assert got["type"] == "AxialInstancedMesh" and got["generated"]
    x, _, z = got["eye"]
    assert sorted(got["tiles"]) == sorted(tiles_around(recipe.generate, x, z, recipe.reach).tolist())
    want = generate_tiles(recipe.generate, layer.mesh, got["tiles"], recipe.maps)
    records = np.asarray(got["data"], np.float32).reshape(-1, got["width"])
    assert close(records, want) <= 1e-6
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    ref = ad.render_image(layer.mesh, want, size=(480, 360), look=look, camera=camera)
    assert three_mask(ref).sum() > 0.05 * ref.size / 3
    assert three_iou(shot, ref) >= 0.95, three_iou(shot, ref)


def test_a_hostile_generated_form_is_refused_in_chromium_and_the_tab_lives(browser, three_site):
    """A few-KB GLB whose generated form asks for 10^12 a square unit, a reach of 10^9 or tiles of 10^-3
    over a reach of 24 (before: drawn as something else, the loader frozen, the tab out of memory): three's
    GLTFLoader with AxialGLTFPlugin rejects it with an AxialError naming the field, at once, and the page
    still answers (what node's verdicts in tests/app/test_generated_form_bounds.py say, in the browser)."""
    import pygltflib

    folder, url = three_site
    (folder / "host.toml").write_text(GLTF_SCENE)
    good = folder / "host.glb"
    r = subprocess.run([sys.executable, "-m", "axialdeform", "export", str(folder / "host.toml"), "--generated",
                        "-o", str(good)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for key, changes in (("rate", {"rate": 1e12, "min_distance": 0.0}), ("reach", {"reach": 1e9}),
                         ("reach", {"tile": 1e-3, "min_distance": 0.0, "reach": 24.0})):
        g = pygltflib.GLTF2().load(str(good))
        node = next(n for n in g.nodes if n.extensions and "AXIALDEFORM_bend" in n.extensions)
        gen = node.extensions["AXIALDEFORM_bend"]["generate"]
        gen["recipe"].update(changes)
        if key == "reach":  # a consistent file, but for what it asks for
            m, cell = tile_size(Generate(rate=gen["recipe"]["rate"], tile=gen["recipe"]["tile"]))
            gen["uniforms"].update(m=m, cell=cell, jitter=1.0 - gen["recipe"]["min_distance"] / cell)
        name = f"hostile-{key}-{len(changes)}.glb"
        g.save_binary(str(folder / name))
        page = browser.new_page(viewport={"width": 320, "height": 240})
        errors = []
        page.on("pageerror", lambda e, errors=errors: errors.append(str(e)))
        try:
            page.goto(url + f"gltf.html?file={name}")
            for _ in range(300):  # up to 30 s: the refusal comes at once
                if errors:
                    break
                page.wait_for_timeout(100)
            assert errors and ("generate recipe: " + key in errors[0] or "generate: " + key in errors[0]), (name, errors)
            assert page.evaluate("window.app === undefined && 1 + 1") == 2  # nothing drawn, the tab answers
        finally:
            page.close()


@pytest.mark.slow
def test_the_gltf_generated_form_of_trees_bends_every_level(browser, three_site):
    """A generated layer of ten axes in the glTF generated form (its child-axis table an accessor): the
    plugin's generated AxialInstancedMesh makes the Python library's records, child axes and all."""
    folder, url = three_site
    (folder / "gen-trees.toml").write_text(TREES.replace('axes = "tree-axes.toml"', 'axes = "{}"'.format(
        (ROOT / "examples" / "forest" / "tree-axes.toml").as_posix())).split("[[layer]]\nname = \"ground\"")[0])
    r = subprocess.run([sys.executable, "-m", "axialdeform", "export", str(folder / "gen-trees.toml"), "--generated",
                        "-o", str(folder / "gen-trees.glb")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    page = browser.new_page(viewport={"width": 480, "height": 360})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        page.goto(url + "gltf.html?file=gen-trees.glb")
        page.wait_for_function("window.app !== undefined", timeout=120_000)
        got = page.evaluate("""() => { const { renderer, scene, camera, gltf } = window.app;
            renderer.render(scene, camera);
            renderer.render(scene, camera);
            let s = null;
            gltf.scene.traverse((o) => { if (o.recipe && !s) s = o; });
            // the offsets texture the draw fetches, as the GPU drew its texels (generate_axes.vert): slot order
            const gl = renderer.getContext(), tex = s.axialUniforms.axialChildren.value;
            const fbo = gl.createFramebuffer(), texels = new Float32Array(tex.image.width * 4 * 4);
            gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
            gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D,
                                    renderer.properties.get(tex).__webglTexture, 0);
            gl.readPixels(0, 0, tex.image.width, 4, gl.RGBA, gl.FLOAT, texels);
            gl.bindFramebuffer(gl.FRAMEBUFFER, null);
            gl.deleteFramebuffer(fbo);
            renderer.resetState();
            return { tiles: s.tiles, width: s.layout.numbersPerInstance, eye: camera.position.toArray(),
                     slots: s.count, texels: Array.from(texels), data: Array.from(s.records()) }; }""")
    finally:
        page.close()
    assert errors == []
    layer = ad.Scene.load(folder / "gen-trees.toml").layers[0]
    assert got["width"] == 19 + 90
    x, _, z = got["eye"]
    assert sorted(got["tiles"]) == sorted(tiles_around(layer.generate.generate, x, z, layer.generate.reach).tolist())
    want = generate_tiles(layer.generate.generate, layer.mesh, got["tiles"], layer.generate.maps)
    assert close(np.asarray(got["data"], np.float32).reshape(-1, got["width"]), want) <= 1e-6
    # the texels the GPU drew for the draw (not read back by records()): every kept slot's child axes, the
    # Python library's, in the texture's layout (three texels an axis: d1 d2 | d3 d4 | d5 0 0)
    from axialdeform.core.generate import generate_tile

    slots = [generate_tile(layer.generate.generate, layer.mesh, tx, tz, layer.generate.maps) for tx, tz in got["tiles"]]
    records, kept = np.concatenate([p for p, _ in slots]), np.concatenate([k for _, k in slots])
    assert got["slots"] == len(kept) and kept.any()
    texels = np.asarray(got["texels"], np.float32).reshape(-1, 12)  # an axis's three texels
    first = min(len(texels) // 9, len(kept))  # the slots the rows read hold
    drawn = texels[:first * 9].reshape(first, 9, 12)[:, :, :10]
    children = records[:first, 10:100].reshape(first, 9, 10)
    assert kept[:first].sum() > 5
    assert close(drawn[kept[:first]].reshape(-1, 10), children[kept[:first]].reshape(-1, 10)) <= 1e-6
