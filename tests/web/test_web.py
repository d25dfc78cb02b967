"""The web page (axialdeform web) and the notebook widget, in a REAL browser:
Debian's chromium driven by Playwright, WebGL 2 on SwiftShader.  No test
here skips: without chromium or playwright they fail (the README's test
command installs both)."""

from __future__ import annotations

import base64
import json
import re
import shutil
import socket
import subprocess
import sys
import threading
import zlib
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.io.params import encode_binary
from axialdeform.web import (
    PARAMS_FILE,
    THREE_VERSION,
    VENDOR_FILES,
    PageOptions,
    build_scene,
    embedded_file,
    make_server,
    page_shaders,
    scene_bytes,
    single_file_html,
    vendor_file,
    write_page,
)

from helpers.browser import SIZE, SKY, Visit, iou, mask, widget_page, widget_state

ROOT = Path(__file__).resolve().parents[2]


# ------------------------------------------------------------------ no browser
def test_page_shaders_hold_the_package_deformation_verbatim():
    axial = ad.deformation_glsl().rstrip("\n")
    shaders = page_shaders()
    assert set(shaders) == {f"float{lv}{m}{f}" for lv in ("", "_extended", "_tinted") for m in ("", "_material")
                            for f in ("", "_framed")}
    for stages in shaders.values():
        vs = stages["vertex"]
        assert vs.startswith("#version 300 es\nprecision highp float;\n")
        assert axial in vs, "the page's vertex shader must contain glsl/axial.glsl verbatim"
        assert "#define AXIAL_THREE 1" in vs  # the instances are the npm module's AxialInstancedMesh
        assert "axial_world(" in vs.split(axial)[1] or "axial_tree_world(" in vs.split(axial)[1]
        assert stages["fragment"].startswith("#version 300 es")
        assert "#version 330" not in vs + stages["fragment"]
    for variant in ("float_extended", "float_tinted"):
        assert "#define AXIAL_EXTENDED 1" in shaders[variant]["vertex"]


def test_exported_page_carries_the_shaders_params_and_camera(tmp_path, stone):
    params = ad.random_params(stone, 50, seed=4)
    scene = build_scene(stone, params, page=PageOptions(size=SIZE))
    index = write_page(tmp_path / "site", scene)
    config = json.loads((tmp_path / "site" / "scene.json").read_text(encoding="utf-8"))
    # the build these parameters need (a quantized file is decoded to float32 by the module's parser), and
    # render's ground plane (glsl/ground.vert, ground.frag) where the look draws one
    assert config["shaders"] == {"float": page_shaders()["float"], "ground": page_shaders(["ground"])["ground"]}
    flat = ad.Look(ground=False)
    assert build_scene(stone, params, page=PageOptions(quantize=False), look=flat).config["shaders"] == {
        "float": page_shaders()["float"]}
    assert set(build_scene(stone, params, page=PageOptions(all_shaders=True), look=flat).config["shaders"]) == {
        "float", "float_extended", "float_tinted"}
    assert set(build_scene(ad.load_mesh("leafcard"), params, page=PageOptions(all_shaders=True), look=flat).config["shaders"]) == {
        "float_material", "float_extended_material", "float_tinted_material"}
    # the ground render fits under these instances (GroundPlane.fit), drawn GroundPlane.EXTENT times as wide
    from axialdeform.core.bounds import ground_square, instance_bounds
    from axialdeform.gl.ground import GroundPlane

    center, radius = ground_square(*instance_bounds(stone, params))
    assert np.allclose(config["ground"]["center"], center) and config["ground"]["radius"] == GroundPlane.EXTENT * radius
    assert build_scene(stone, params, look=flat).config["ground"] is None
    assert ad.deformation_glsl().rstrip("\n") in config["shaders"]["float"]["vertex"]
    adp = (tmp_path / "site" / PARAMS_FILE).read_bytes()
    assert adp == encode_binary(params, axis=stone.axis, mesh_fingerprint=stone.fingerprint, quantize=True)
    cam = ad.frame_instances(stone, params, SIZE[0] / SIZE[1])
    assert np.allclose(config["camera"]["eye"], cam.eye) and np.allclose(config["camera"]["target"], cam.target)
    # near and far widened (never narrowed) to hold the ground, as render's (Camera.enclosing_square)
    assert config["camera"]["near"] <= cam.near and config["camera"]["far"] >= cam.far
    assert config["layers"][0]["mesh"]["fingerprint"] == stone.fingerprint.hex()
    assert config["fixed_size"] is True and config["wind"] is None
    assert "<script type=\"importmap\">" in index.read_text(encoding="utf-8")
    for rel in VENDOR_FILES.values():
        assert (tmp_path / "site" / "three" / rel).read_bytes() == vendor_file(rel)
    assert "MIT License" in (tmp_path / "site" / "three" / "LICENSE").read_text()
    # the single file holds the same config, mesh and params, base64
    one = single_file_html(scene)
    cfg = one.split('id="axd-config">', 1)[1].split("</script>", 1)[0]
    assert json.loads(cfg.replace("<\\/", "</")) == config
    assert embedded_file(one, PARAMS_FILE) == adp
    assert "http://" not in one.split("<body>", 1)[1] and "https://" not in one.split("<body>", 1)[1].replace(
        "https://threejs.org", "")  # nothing fetched from the network


@pytest.mark.parametrize("quantize", [False, True])
def test_the_page_parser_reads_every_record_level(tmp_path, stone, quantize):
    """``parseADP`` of the npm module (the parser web/app.js imports), run in node, reads a file of each level of
    the record table (16, 19, 22 numbers) as Python wrote it, and refuses the
    next version with the words Python uses."""
    import shutil
    import subprocess

    from axialdeform.core import record as R
    from axialdeform.core.io.params import encode_binary

    node = shutil.which("node")
    assert node, "node is needed for the page's parser tests"
    files = []
    for level, width in enumerate(R.WIDTHS):
        params = ad.random_params(stone, 5, seed=level, variation=ad.Variation(**({"scale": 1.0} if level == 1 else {}),
                                                                               **({"tint": 0.5} if level == 2 else {})))
        assert params.shape[1] == width
        path = tmp_path / f"l{level}.adp"
        path.write_bytes(encode_binary(params, quantize=quantize))
        files.append((path, width, level + 1))
    from axialdeform.core.axes import TREE_AXES

    tree = ad.load_mesh("tree", axes=TREE_AXES)  # ten axes: 106 numbers, K in the header
    path = tmp_path / "tree.adp"
    path.write_bytes(encode_binary(ad.random_params(tree, 5, seed=1), axis=tree, quantize=quantize))
    files.append((path, 106, 1))
    bad = bytearray(files[0][0].read_bytes())
    bad[8:10] = (len(R.WIDTHS) + 1).to_bytes(2, "little")
    (tmp_path / "next.adp").write_bytes(bytes(bad))
    app = (ROOT / "js" / "src" / "core" / "adp.js").as_uri()  # the page's parser: the npm module's (app.js imports it)
    script = (f"import {{ parseADP as parseAdp }} from '{app}';\nimport {{ readFileSync }} from 'node:fs';\n"
              "const out = [];\n"
              "for (const f of process.argv.slice(1)) {\n"
              "  const b = readFileSync(f); const ab = b.buffer.slice(b.byteOffset, b.byteOffset + b.length);\n"
              "  try { const p = parseAdp(ab, f); out.push([p.fields, p.version, p.count]); }\n"
              "  catch (e) { out.push(e.message); }\n"
              "}\nconsole.log(JSON.stringify(out));\n")
    proc = subprocess.run([node, "--input-type=module", "-e", script, *[str(f) for f, _, _ in files],
                           str(tmp_path / "next.adp")], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got[:-1] == [[width, version, 5] for _, width, version in files]
    assert "version: expected 1 (16 numbers), 2 (19 numbers), 3 (22 numbers), found 4" in got[-1]


def test_build_scene_refuses_bad_options(stone):
    params = ad.random_params(stone, 3, seed=1)
    for make, words in ((lambda: PageOptions(size=(0, 10)), "size"), (lambda: PageOptions(mode="hidden"), "mode"),
                        (lambda: ad.RenderOptions(up="w"), "up")):
        with pytest.raises(ad.AxialDeformError, match=words):
            value = make()
            build_scene(stone, params, **({"page": value} if isinstance(value, PageOptions) else {"options": value}))


def test_vendored_three_is_the_pinned_version():
    assert vendor_file("VERSION").decode().strip() == THREE_VERSION
    assert f"REVISION = '{THREE_VERSION.split('.')[1]}'" in vendor_file("three.module.min.js").decode()[:200000] \
        or f'"{THREE_VERSION.split(".")[1]}"' in vendor_file("three.module.min.js").decode()[:2000]
    assert f"THREE_VERSION={THREE_VERSION}" in (ROOT / "tools" / "vendor_three.sh").read_text()


@pytest.mark.slow
def test_web_cli_errors_are_one_line(tmp_path):
    cmd = [sys.executable, "-m", "axialdeform", "web"]
    r = subprocess.run(cmd + ["stone", str(tmp_path / "missing.adp"), "-o", str(tmp_path / "x.html")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1
    adp = tmp_path / "s.adp"
    ad.write_params(adp, ad.random_params(ad.load_mesh("stone"), 5, seed=1), ad.load_mesh("stone"))
    r = subprocess.run(cmd + ["leaf", str(adp), "-o", str(tmp_path / "x.html")], capture_output=True, text=True)
    assert r.returncode == 2 and "different base mesh" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = subprocess.run(cmd + ["-o", str(tmp_path / "nothing"), "--serve"], capture_output=True, text=True)
    assert r.returncode == 2 and "no exported page" in r.stderr


def test_serve_on_a_busy_port_picks_another(tmp_path):
    from urllib.request import urlopen

    (tmp_path / "index.html").write_text("<p>hi</p>")
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen(1)
    port = busy.getsockname()[1]
    try:
        proc = subprocess.Popen([sys.executable, "-m", "axialdeform", "web", "-o", str(tmp_path), "--serve",
                                 "--port", str(port)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            line = proc.stdout.readline()
            assert line.startswith("serving ") and "http://127.0.0.1:" in line, line + proc.stderr.read()
            url = re.search(r"http://127\.0\.0\.1:\d+/\S*", line).group(0)
            assert f":{port}/" not in url
            assert urlopen(url, timeout=10).read() == b"<p>hi</p>"
        finally:
            proc.terminate()
            proc.wait(timeout=10)
        assert f"port {port} is busy" in proc.stderr.read()
    finally:
        busy.close()


# ------------------------------------------------------------------ browser
def assert_page_draws(browser, url, render: np.ndarray, instances: int) -> None:
    """The page at ``url`` is ready with ``instances`` and draws what
    ``render`` drew: silhouette IoU >= 0.95 and a mean colour difference
    under 2/255, pixel by pixel; no console error."""
    v = Visit(browser, url)
    try:
        assert v.state["ready"] is True and v.state["instances"] == instances, v.state
        shot = v.silhouette()
        assert iou(shot, render, BACKGROUND) >= 0.95
        assert np.abs(shot.astype(np.float64) - render).mean() < 2.0  # colours too, pixel by pixel
        assert v.errors == []
    finally:
        v.close()


@pytest.fixture(scope="module")
def scene_files(tmp_path_factory):
    """A parameter file and both exports, in a folder whose name has spaces and non-ASCII."""
    base = tmp_path_factory.mktemp("web") / "my scènes ü"
    base.mkdir()
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 1500, seed=7, variation=ad.Variation(bend=0.12), placement="disc")
    adp = base / "stones ä.adp"
    ad.write_params(adp, params, mesh)
    for out in ("site ö", "scène.html"):
        r = subprocess.run([sys.executable, "-m", "axialdeform", "web", "--no-ground", "stone", str(adp), "-o", str(base / out),
                            "--size", f"{SIZE[0]}x{SIZE[1]}"], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
    # the page: no ground, no shadow
    render = ad.render_image(mesh, ad.read_params(adp, mesh), SIZE, look=ad.Look(ground=False, shadow=False))
    return {"base": base, "params": params, "mesh": mesh, "render": render}


@pytest.fixture(scope="module")
def served(scene_files):
    server, _ = make_server(scene_files["base"], 0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()
    server.server_close()


BACKGROUND = (0.93, 0.94, 0.96)


@pytest.mark.slow
def test_folder_page_shows_what_render_shows(browser, served, scene_files):
    from urllib.parse import quote

    v = Visit(browser, served + quote("site ö") + "/index.html")
    try:
        assert v.state == {"ready": True, "instances": 1500, "firstFrameMs": v.state["firstFrameMs"]}, v.state
        shot = v.silhouette()
        assert shot.shape == (SIZE[1], SIZE[0], 3)
        assert iou(shot, scene_files["render"], BACKGROUND) >= 0.95
        assert np.allclose(shot[0, 0], np.asarray(BACKGROUND) * 255, atol=1.5)  # render's background
        assert "1,500 instances" in v.page.locator(".axd-status").inner_text()
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_single_file_works_from_disk(browser, scene_files):
    page = scene_files["base"] / "scène.html"
    v = Visit(browser, page.as_uri())
    try:
        assert v.state["ready"] is True and v.state["instances"] == 1500, v.state
        assert iou(v.silhouette(), scene_files["render"], BACKGROUND) >= 0.95
        assert v.errors == []
    finally:
        v.close()


def _corrupt(kind: str, good: bytes) -> bytes:
    if kind == "truncated":
        return good[:-100]
    if kind == "checksum":
        bad = bytearray(good)
        bad[200] ^= 0x40
        return bytes(bad)
    leaf = ad.load_mesh("leaf")
    other = encode_binary(ad.random_params(leaf, 1500, seed=1), axis=leaf.axis, mesh_fingerprint=leaf.fingerprint,
                          quantize=True)
    assert zlib.crc32(other[:-4]) == int.from_bytes(other[-4:], "little")
    return other


@pytest.mark.slow
@pytest.mark.parametrize("kind, words", [("truncated", "truncated"), ("checksum", "checksum: stored CRC-32"),
                                         ("other mesh", "made for a different base mesh"),
                                         ("other glb", "not the base mesh this page was exported with")])
def test_bad_parameter_file_shows_why_and_draws_nothing(browser, served, scene_files, kind, words):
    from urllib.parse import quote

    site = scene_files["base"] / "site ö"
    bad_dir = scene_files["base"] / f"bad {kind}"
    if bad_dir.exists():
        shutil.rmtree(bad_dir)
    shutil.copytree(site, bad_dir)
    if kind == "other glb":  # the mesh file swapped: the browser hashes the GLB (WebCrypto)
        from axialdeform.core.io.gltf import encode_base_mesh

        (bad_dir / "mesh.glb").write_bytes(encode_base_mesh(ad.load_mesh("leaf")))
    else:
        (bad_dir / PARAMS_FILE).write_bytes(_corrupt(kind, (site / PARAMS_FILE).read_bytes()))
    v = Visit(browser, served + quote(f"bad {kind}") + "/index.html")
    try:
        assert v.state["ready"] is False and words in v.state["error"], v.state
        message = v.page.locator(".axd-message")
        name = "mesh.glb" if kind == "other glb" else PARAMS_FILE
        assert message.is_visible() and words in message.inner_text() and name in message.inner_text()
        assert v.page.locator("canvas").count() == 0  # nothing drawn, nothing wrong drawn
    finally:
        v.close()


#: what a notebook does when the kernel sets SceneWidget.params_adp (the widget harness's model)
PUSH_PARAMS = ("(b64) => { window.widgetStatus = undefined; "
               "window.widgetModel.set('params_adp', window.toDataView(b64)); }")


def _push_params(page, adp: bytes) -> dict:
    """Hand the widget new numbers as the kernel would; the status its front end reports back."""
    page.evaluate(PUSH_PARAMS, base64.b64encode(adp).decode())
    page.wait_for_function("window.widgetStatus !== undefined", timeout=60_000)
    return page.evaluate("window.widgetStatus")


def _picture_changes(page, clip, before: bytes) -> bool:
    """Whether the picture differs from ``before`` within the next frames (polled, up to 20 s)."""
    for _ in range(100):
        if page.screenshot(clip=clip) != before:
            return True
        page.wait_for_timeout(200)
    return False


@pytest.mark.slow
def test_widget_renders_and_set_params_updates_it(browser, tmp_path):
    from axialdeform.widget import SceneWidget

    mesh = ad.load_mesh("stone")
    w = SceneWidget(mesh, ad.random_params(mesh, 300, seed=2), size=SIZE, look=ad.Look(ground=False))
    state = widget_state(w)
    page, errors = widget_page(browser, tmp_path, state, w._esm)
    try:
        assert page.evaluate("window.widgetStatus") == {"ready": True, "instances": 300}
        clip = page.locator(".axd-stage").bounding_box()
        before = page.screenshot(clip=clip)
        w.set_params(ad.random_params(mesh, 40, seed=9))
        assert w.config["instances"] == 40
        assert _push_params(page, w.params_adp) == {"ready": True, "instances": 40}
        # the status line and the picture follow within the next frames: wait for them, not a fixed time
        page.wait_for_function("document.querySelector('.axd-status').innerText.includes('40 instances')",
                               timeout=60_000)
        assert "40 instances" in page.locator(".axd-status").inner_text()
        assert _picture_changes(page, clip, before)
        # a bad update: the page says why and draws nothing
        page.evaluate(PUSH_PARAMS, base64.b64encode(w.params_adp[:-8]).decode())
        page.wait_for_function("window.widgetStatus !== undefined", timeout=60_000)
        st = page.evaluate("window.widgetStatus")
        assert st["ready"] is False and "truncated" in st["error"]
        assert page.locator(".axd-message").is_visible()
        page.evaluate("window.cleanup()")
        assert page.locator("canvas").count() == 0
        assert errors == []
    finally:
        page.close()


@pytest.mark.slow
def test_widget_fits_its_ground_and_light_to_new_instances(browser, tmp_path):
    """set_params: the camera stays, but the ground plane and the key light's shadow camera are fitted to the new
    instances (as a new page of them has them), in Python's config and in the front end; the camera's depth range
    widens to hold new instances farther than it reached (its far plane cut them)."""
    from axialdeform.web import fit_ground_and_shadow
    from axialdeform.widget import SceneWidget

    mesh = ad.load_mesh("stone")
    w = SceneWidget(mesh, ad.random_params(mesh, 30, seed=2, placement="disc"), size=SIZE)
    first = {"ground": w.config["ground"], "shadow": w.config["shadow"]}
    assert first["ground"] is not None and first["shadow"] is not None
    page, errors = widget_page(browser, tmp_path, widget_state(w), w._esm)
    try:
        before = page.evaluate("document.getElementById('out').axialdeformView.fitted")
        depth0 = before["depth"]
        spread = ad.random_params(mesh, 30, seed=3, placement="disc", spacing=4.0)
        spread.position[:, 0] += 6.0
        w.set_params(spread)
        ground, shadow = fit_ground_and_shadow(mesh, spread)
        assert w.config["ground"] == ground and w.config["shadow"] == shadow
        assert ground["center"] != first["ground"]["center"] and shadow["matrix"] != first["shadow"]["matrix"]
        page.evaluate("(c) => { window.widgetModel.get('config').ground = c.ground; window.widgetModel.get('config').shadow = c.shadow; }",
                      {"ground": ground, "shadow": shadow})  # the synced config, as the kernel sends it with the numbers
        assert _push_params(page, w.params_adp) == {"ready": True, "instances": 30}
        fitted = page.evaluate("document.getElementById('out').axialdeformView.fitted")
        assert np.allclose(fitted["ground"]["center"], ground["center"], atol=1e-5)
        assert fitted["ground"]["radius"] == pytest.approx(ground["radius"], rel=1e-6)
        assert np.allclose(fitted["light"], shadow["matrix"], atol=1e-6)
        far = ad.random_params(mesh, 30, seed=4, placement="disc")
        far.position[:, 0] += 3.0 * depth0[1]  # beyond the far plane the first instances gave
        w.set_params(far)
        reach = w.config["reach"]
        page.evaluate("(c) => { Object.assign(window.widgetModel.get('config'), c); }",
                      {k: w.config[k] for k in ("ground", "shadow", "reach")})
        assert _push_params(page, w.params_adp) == {"ready": True, "instances": 30}
        fitted = page.evaluate("document.getElementById('out').axialdeformView.fitted")
        need = np.linalg.norm(np.subtract(fitted["target"], reach["center"])) + reach["radius"]
        assert fitted["target"] == pytest.approx(before["target"])  # the camera stays where it was
        assert fitted["depth"][1] > depth0[1] and fitted["depth"][1] >= need * (1 - 1e-6)
        assert errors == []
    finally:
        page.close()


@pytest.mark.slow
def test_widget_takes_a_scene_file(browser, tmp_path):
    """SceneWidget(SCENE.toml): every layer and the terrain, drawn as the page of the same file draws them."""
    from axialdeform.widget import SceneWidget

    scene = ad.Scene.load(ROOT / "examples" / "landscape" / "landscape.toml")
    for layer in scene.layers:  # a lighter scene, the same layers
        layer.params = layer.params[:200]
    w = SceneWidget(scene, size=SIZE, look=scene.look.replace(ground=False))
    assert [layer["name"] for layer in w.config["layers"]][0] == "terrain" and len(w.files) == 2 * len(w.config["layers"])
    with pytest.raises(ad.AxialDeformError, match="several layers"):
        w.set_params(scene.layers[0].params)
    state = widget_state(w)
    state["files"] = {n: {"b64": base64.b64encode(b).decode()} for n, b in w.files.items()}
    page, errors = widget_page(browser, tmp_path, state, w._esm)
    try:
        status = page.evaluate("window.widgetStatus")
        assert status == {"ready": True, "instances": scene.count}, status
        from io import BytesIO

        from PIL import Image

        shot = np.asarray(Image.open(BytesIO(page.screenshot(clip=page.locator(".axd-stage").bounding_box())))
                          .convert("RGB"))
        assert mask(shot, scene.background).mean() > 0.2  # the terrain and layers fill the picture
        assert errors == []
    finally:
        page.close()


@pytest.mark.slow
def test_widget_in_an_executed_notebook(browser, tmp_path):
    """A notebook executed by a real Jupyter kernel (nbclient): the cell shows
    the widget (widget-view output) and set_params changes its synced state;
    the widget state the notebook stores (what a front end receives) is then
    rendered by the widget's ESM in Chromium.  A real JupyterLab front end
    is tested in tests/web/test_notebook.py; VS Code is not tested."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_code_cell("import axialdeform as ad\nfrom axialdeform.widget import SceneWidget\n"
                                  "m = ad.load_mesh('stone')\n"
                                  f"w = SceneWidget(m, ad.random_params(m, 200, seed=3), size={SIZE!r}, look=ad.Look(ground=False))\nw"),
        nbformat.v4.new_code_cell("w.set_params(ad.random_params(m, 50, seed=4)); w.config['instances']"),
    ]
    NotebookClient(nb, timeout=180, kernel_name="python3", store_widget_state=True).execute()
    view = nb.cells[0].outputs[0]["data"]["application/vnd.jupyter.widget-view+json"]
    assert nb.cells[1].outputs[0]["data"]["text/plain"] == "50"
    stored = nb.metadata.widgets["application/vnd.jupyter.widget-state+json"]["state"][view["model_id"]]
    state = dict(stored["state"])
    for buf in stored.get("buffers", []):
        assert buf["encoding"] == "base64"
        state[buf["path"][0]] = {"b64": buf["data"]}
    assert len(base64.b64decode(state["params_adp"]["b64"])) == 96 + 128 + 32 * 50 + 4
    page, errors = widget_page(browser, tmp_path, state, state["_esm"])
    try:
        assert page.evaluate("window.widgetStatus") == {"ready": True, "instances": 50}
        assert page.locator("canvas").count() == 1 and errors == []
    finally:
        page.close()


def test_scene_bytes_counts_what_a_browser_downloads(tmp_path, stone):
    scene = build_scene(stone, ad.random_params(stone, 100, seed=1), page=PageOptions(size=SIZE))
    write_page(tmp_path / "s", scene)
    b = scene_bytes(tmp_path / "s")
    assert b["params"] == 96 + 128 + 32 * 100 + 4
    assert b["mesh"] == len(scene.glb) and b["three"] > 600_000


@pytest.mark.slow
def test_float32_leaves_flat_z_up_match_render(browser, tmp_path):
    """The other paths: float32 records, an open (two-sided) mesh, flat shading, z up."""
    from axialdeform.core.io.image import save_png

    mesh = ad.load_mesh("leaf")
    params = ad.random_params(mesh, 600, seed=5, variation=ad.Variation(bend=0.15), up="z", placement="disc")
    adp = tmp_path / "leaves.adp"
    ad.write_params(adp, params, mesh)
    out = tmp_path / "leaves.html"
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", "--no-ground", "leaf", str(adp), "-o", str(out), "--float32",
                        "--mode", "flat", "--up", "z", "--size", f"{SIZE[0]}x{SIZE[1]}"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert embedded_file(out.read_text(encoding="utf-8"), PARAMS_FILE)[10] == 0
    render = ad.render_image(mesh, params, SIZE, "flat", options=ad.RenderOptions(up="z"), look=ad.Look(ground=False, shadow=False))
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True and v.state["instances"] == 600, v.state
        shot = v.silhouette()
        score = iou(shot, render, BACKGROUND)
        if score < 0.95:
            save_png(tmp_path / "page.png", shot)
        assert score >= 0.95, f"IoU {score:.3f}; see {tmp_path}"
        assert v.errors == []
    finally:
        v.close()


def _page_of_a_file(tmp_path, mesh, params, quantize: bool, version: int):
    """``params`` written to an .adp, read back and made a single-file page:
    ``(the page, the parameters read back)``; the page's .adp has ``version``."""
    adp = tmp_path / "p.adp"
    ad.write_params(adp, params, mesh)
    back = ad.read_params(adp, mesh)
    out = tmp_path / "page.html"
    write_page(out, build_scene(mesh, back, page=PageOptions(size=SIZE, quantize=quantize), look=ad.Look(ground=False)))
    assert int.from_bytes(embedded_file(out.read_text(encoding="utf-8"), PARAMS_FILE)[8:10], "little") == version
    return out, back


@pytest.mark.slow
@pytest.mark.parametrize("quantize", [True, False])
def test_extended_instances_match_render(browser, tmp_path, quantize):
    """19-number instances (scale, twist, taper; .adp version 2) in the page."""
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 700, seed=8, variation=ad.Variation(bend=0.12, scale=0.5, twist=1.2, taper=0.4), placement="disc")
    assert params.shape == (700, 19)
    out, back = _page_of_a_file(tmp_path, mesh, params, quantize, version=2)
    render = ad.render_image(mesh, back, SIZE, look=ad.Look(ground=False, shadow=False))
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True and v.state["instances"] == 700, v.state
        assert iou(v.silhouette(), render, BACKGROUND) >= 0.95
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
@pytest.mark.parametrize("mesh_name,quantize", [("stone", True), ("stone", False), ("leafcard", True)])
def test_tinted_instances_match_render(browser, tmp_path, mesh_name, quantize):
    """22-number instances (the record's tint; .adp version 3): the page colours
    each instance by its own tint, pixel for pixel as render does, and the
    tint shows (the same instances untinted differ)."""
    mesh = ad.load_mesh(mesh_name)
    params = ad.random_params(mesh, 300, seed=9, placement="disc", variation=ad.Variation(tint=0.9, tint_color=(1.0, 0.45, 0.2)))
    assert params.shape == (300, 22)
    out, back = _page_of_a_file(tmp_path, mesh, params, quantize, version=3)
    look = ad.Look(ground=False, shadow=False)
    render = ad.render_image(ad.Scene.single(mesh, back), size=SIZE, look=look)
    plain = ad.render_image(ad.Scene.single(mesh, params[:, :19]), size=SIZE, look=look)
    covered = mask(render, BACKGROUND)
    assert np.abs(plain.astype(np.float64) - render)[covered].mean() > 10.0  # the tint shows at all
    assert_page_draws(browser, out.as_uri(), render, 300)


@pytest.mark.slow
def test_folder_page_from_disk_says_it_needs_a_server(browser, scene_files):
    v = Visit(browser, (scene_files["base"] / "site ö" / "index.html").as_uri())
    try:
        assert v.state["ready"] is False and "file://" in v.state["error"], v.state
        assert "--serve" in v.page.locator(".axd-message").inner_text()
        assert v.page.locator("canvas").count() == 0
    finally:
        v.close()


# ------------------------------------------------------------------ scene files, materials, wind, wireframe, window
LANDSCAPE = ROOT / "examples" / "landscape"


def _shot_of(browser, url, size=SIZE, viewport=None):
    v = Visit(browser, url, size=viewport or size)
    return v


def _mean_covered(image: np.ndarray, background) -> np.ndarray:
    return image[mask(image, background)].astype(np.float64).mean(axis=0)


def test_page_shader_includes_wind_glsl_verbatim():
    wind = (ROOT / "glsl" / "wind.glsl").read_text().rstrip("\n")
    for variant, stages in page_shaders().items():
        assert wind in stages["vertex"], variant
        assert "axial_wind(inst" in stages["vertex"].split(wind)[1]  # scene.vert calls it after the include


def _write(path: Path, text: str) -> Path:
    path.write_text(text.lstrip("\n"), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def scene_pages(tmp_path_factory):
    """Two scene files (a windy one without terrain; a landscape with terrain,
    textured leaf cards and stones), each exported as a folder and one file,
    and render's pictures of them."""

    base = tmp_path_factory.mktemp("scenes") / "scène files"
    base.mkdir()
    stone, leaf = ad.load_mesh("stone"), ad.load_mesh("leaf")
    ad.write_params(base / "stones.adp", ad.random_params(stone, 300, seed=3, variation=ad.Variation(bend=0.1), placement="disc"), stone)
    ad.write_params(base / "leaves.adp", ad.random_params(leaf, 400, seed=4, variation=ad.Variation(bend=0.1), placement="disc"), leaf)
    _write(base / "windy.toml", """
background = [0.80, 0.87, 0.95]
[light]
direction = [0.4, 0.9, 0.3]
ambient = 0.4
[wind]
direction = [1.0, 0.0, 0.3]
strength = 0.8
gustiness = 0.8
frequency = 0.4
[[layer]]
name = "stones"
mesh = "stone"
params = "stones.adp"
color = [0.5, 0.48, 0.45]
[[layer]]
name = "leaves"
mesh = "leaf"
params = "leaves.adp"
wind = true
""")
    shutil.copy(LANDSCAPE / "terrain.png", base / "terrain.png")  # a page carries files of the scene's folder
    _write(base / "land.toml", """
background = [0.80, 0.87, 0.95]
[terrain]
heightmap = "terrain.png"
height_scale = 6.0
extent = [40.0, 30.0]
color = [0.42, 0.40, 0.30]
[camera]
elevation = 24.0
azimuth = 25.0
fov = 30.0
[light]
direction = [0.3, 0.9, 0.5]
ambient = 0.3
[[layer]]
name = "cards"
mesh = "leafcard"
[layer.scatter]
count = 400
min_distance = 0.5
scale = [1.5, 2.5]
seed = 2
[[layer]]
name = "stones"
mesh = "stone"
color = [0.6, 0.58, 0.55]
[layer.scatter]
count = 150
min_distance = 0.8
scale = [0.5, 0.9]
anchor = "center"
seed = 5
""")
    cmd = [sys.executable, "-m", "axialdeform"]
    size = f"{SIZE[0]}x{SIZE[1]}"
    for name in ("windy", "land"):
        for out in (f"{name} site", f"{name}.html"):
            r = subprocess.run(cmd + ["web", "--no-ground", str(base / f"{name}.toml"), "-o", str(base / out), "--size", size],
                               capture_output=True, text=True)
            assert r.returncode == 0 and "2 layers" in r.stdout, r.stderr
    renders = {}
    for key, name, t in (("windy 1.5", "windy", 1.5), ("windy 0", "windy", 0.0), ("land", "land", None)):
        # render's picture of the scene file, with the scene's look less what the page does not draw: the
        # ground plane (--no-ground), and shadows where nothing receives them (no ground, no terrain); the
        # landscape's terrain casts and receives them in both
        scene = ad.Scene.load(base / f"{name}.toml")
        look = scene.look.replace(ground=False, shadow=scene.terrain is not None)
        renders[key] = ad.render_image(scene, size=SIZE, options=ad.RenderOptions(time=t), look=look)
    land = ad.Scene.load(base / "land.toml")
    renders["land, no shadow"] = ad.render_image(land, size=SIZE, look=land.look.replace(ground=False, shadow=False))
    server, _ = make_server(base, 0)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield {"base": base, "render": renders, "url": f"http://127.0.0.1:{server.server_address[1]}/"}
    server.shutdown()
    server.server_close()


def test_scene_page_config_has_every_layer_terrain_light_and_wind(tmp_path):
    from axialdeform.core.scene import load_scene
    from axialdeform.gl.scene import scene_camera
    from axialdeform.web import PageOptions, build_scene_file

    mesh = ad.load_mesh("stone")
    ad.write_params(tmp_path / "s.adp", ad.random_params(mesh, 20, seed=1), mesh)
    shutil.copy(LANDSCAPE / "terrain.png", tmp_path / "terrain.png")
    path = _write(tmp_path / "s.toml", """
background = [0.1, 0.2, 0.3]
[terrain]
heightmap = "terrain.png"
extent = 10.0
[light]
direction = [0.0, 1.0, 0.0]
ambient = 0.5
[wind]
strength = 0.3
frequency = 2.0
wavelength = 4.0
[[layer]]
name = "a"
mesh = "stone"
params = "s.adp"
wind = true
[[layer]]
name = "b"
mesh = "leafcard"
params = "s.adp"
""")
    with pytest.raises(ad.AxialDeformError, match="different base mesh"):  # s.adp is the stone's
        load_scene(path)
    path.write_text(path.read_text().replace('mesh = "leafcard"\nparams = "s.adp"', 'mesh = "stone"\nparams = "s.adp"'))
    scene = load_scene(path)
    web = build_scene_file(scene, page=PageOptions(size=SIZE))
    cfg = web.config
    assert [layer["name"] for layer in cfg["layers"]] == ["terrain", "a", "b"]
    assert [layer["terrain"] for layer in cfg["layers"]] == [True, False, False]
    assert cfg["instances"] == 40 and cfg["look"]["background"] == [0.1, 0.2, 0.3] and cfg["look"]["ambient"] == 0.5
    assert cfg["look"]["light_dir"] == [0.0, 1.0, 0.0]
    assert cfg["look"] == {**scene.look.to_json(), "light_dir": [0.0, 1.0, 0.0]}  # the Look, as JSON
    assert [layer["wind"] for layer in cfg["layers"]] == [False, True, False]
    assert cfg["wind"]["wavenumber"] == 0.25 and cfg["wind"]["frequency"] == 2.0 and cfg["wind"]["harmonic"] == 2.31
    cam = scene_camera(scene, SIZE[0] / SIZE[1])
    assert np.allclose(cfg["camera"]["eye"], cam.eye) and cfg["camera"]["far"] == cam.far
    assert set(web.files) == {"terrain.glb", "terrain.adp", "layer-a.glb", "layer-a.adp", "layer-b.glb", "layer-b.adp"}
    assert web.files["layer-a.adp"] == web.files["layer-b.adp"]
    assert web.files["terrain.glb"] != web.files["layer-a.glb"]
    # the CLI: a scene names its own parameters and up axis
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", str(path), "extra.adp", "-o", str(tmp_path / "x")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "names its own parameters" in r.stderr and "Traceback" not in r.stderr
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", str(path), "--up", "z", "-o", str(tmp_path / "x")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "--up" in r.stderr


def test_base_mesh_glb_carries_the_material(tmp_path):
    import pygltflib

    from axialdeform.core.io.gltf import encode_base_mesh

    card = ad.load_mesh("leafcard")
    path = tmp_path / "card.glb"
    path.write_bytes(encode_base_mesh(card))
    g = pygltflib.GLTF2().load(str(path))
    (mat,) = g.materials
    assert mat.alphaMode == "MASK" and mat.alphaCutoff == card.parts[0].material.alpha_cutoff and mat.doubleSided
    assert mat.pbrMetallicRoughness.baseColorTexture is not None and len(g.images) == 1
    assert "TEXCOORD_0" in g.meshes[0].primitives[0].attributes.__dict__ or g.meshes[0].primitives[0].attributes.TEXCOORD_0
    stone = pygltflib.GLTF2().load_from_bytes(encode_base_mesh(ad.load_mesh("stone")))
    assert stone.materials == [] and stone.meshes[0].primitives[0].material is None  # plain: no material
    from conftest import ALPHA_TEST, data_mesh
    from conftest import validate_gltf as _validate

    parts = ad.load_mesh(data_mesh(ALPHA_TEST))
    (tmp_path / "parts.glb").write_bytes(encode_base_mesh(parts))
    for report in _validate(path, tmp_path / "parts.glb"):
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    g = pygltflib.GLTF2().load(str(tmp_path / "parts.glb"))  # one primitive per part, in order, with its alpha mode
    modes = [g.materials[prim.material].alphaMode for prim in g.meshes[0].primitives]
    assert modes == [p.material.alpha_mode for p in parts.parts if p.count]
    assert [g.accessors[prim.indices].count for prim in g.meshes[0].primitives] == [3 * p.count for p in parts.parts if p.count]


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["folder", "single file"])
def test_scene_page_shows_what_render_shows(browser, scene_pages, kind):
    from urllib.parse import quote

    url = (scene_pages["url"] + quote("land site") + "/index.html" if kind == "folder"
           else (scene_pages["base"] / "land.html").as_uri())
    v = Visit(browser, url)
    try:
        assert v.state["ready"] is True and v.state["instances"] > 400, v.state
        shot = v.silhouette()
        render = scene_pages["render"]["land"]
        assert iou(shot, render, SKY) >= 0.95
        assert np.abs(shot.astype(np.float64) - render).mean() < 3.0  # the same colours, pixel by pixel
        # and the same shadows on the terrain: nearer render's than render's picture without them
        bare = scene_pages["render"]["land, no shadow"]
        assert np.abs(shot.astype(np.float64) - render).mean() < 0.5 * np.abs(shot.astype(np.float64) - bare).mean()
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_textured_cutout_page_draws_the_texture(browser, tmp_path):
    """The bundled leafcard (a textured quad, MASK cut-out, double-sided):
    same silhouette as render and the texture's colours, not the plain grey."""
    mesh = ad.load_mesh("leafcard")
    params = ad.random_params(mesh, 200, seed=5, variation=ad.Variation(bend=0.15), placement="disc")
    adp = tmp_path / "cards.adp"
    ad.write_params(adp, params, mesh)
    out = tmp_path / "cards.html"
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", "--no-ground", "leafcard", str(adp), "-o", str(out),
                        "--size", f"{SIZE[0]}x{SIZE[1]}"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    render = ad.render_image(mesh, ad.read_params(adp, mesh), SIZE, look=ad.Look(ground=False, shadow=False))
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True and v.state["instances"] == 200, v.state
        shot = v.silhouette()
        assert iou(shot, render, BACKGROUND) >= 0.95
        page_mean, render_mean = _mean_covered(shot, BACKGROUND), _mean_covered(render, BACKGROUND)
        assert np.abs(page_mean - render_mean).max() < 6.0, (page_mean, render_mean)
        r_, g_, b_ = page_mean
        assert g_ > r_ + 15 and g_ > b_ + 30, page_mean  # the leaf texture's green, not a grey card
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["folder", "single file"])
def test_wind_at_a_fixed_time_matches_render_time(browser, scene_pages, kind):
    from urllib.parse import quote

    url = (scene_pages["url"] + quote("windy site") + "/index.html" if kind == "folder"
           else (scene_pages["base"] / "windy.html").as_uri()) + "?t=1.5"
    v = Visit(browser, url)
    try:
        assert v.state["ready"] is True and v.state["instances"] == 700, v.state
        assert v.page.evaluate("window.axialdeformView.info().time") == 1.5
        shot = v.silhouette()
        at, still = scene_pages["render"]["windy 1.5"], scene_pages["render"]["windy 0"]
        assert iou(shot, at, SKY) >= 0.95
        near, far = (np.abs(shot.astype(np.float64) - ref).mean() for ref in (at, still))
        assert near < far / 3, (near, far)  # the page's wind is render's at t = 1.5, not at t = 0
        v.page.wait_for_timeout(700)
        assert np.array_equal(v.silhouette(), shot)  # frozen time: the picture stays
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_wind_moves_without_a_fixed_time(browser, scene_pages):
    v = Visit(browser, (scene_pages["base"] / "windy.html").as_uri())
    try:
        assert v.state["ready"] is True, v.state
        first = v.silhouette()
        changed = False
        for _ in range(20):
            v.page.wait_for_timeout(250)
            if not np.array_equal(v.silhouette(), first):
                changed = True
                break
        assert changed, "the wind did not move the leaves"
        assert v.errors == []
    finally:
        v.close()


def line_share(image: np.ndarray) -> float:
    """The share of the covered pixels that are (near) the wireframe's line colour."""
    covered = mask(image, BACKGROUND)
    line = np.asarray([0.12, 0.14, 0.18]) * 255
    near = np.abs(image.astype(np.float64) - line).max(axis=2) < 60
    return float((near & covered).sum() / max(covered.sum(), 1))


@pytest.mark.slow
def test_wireframe_key_and_mode(browser, scene_files, tmp_path):
    v = Visit(browser, (scene_files["base"] / "scène.html").as_uri())
    try:
        solid = v.silhouette()
        assert v.page.evaluate("window.axialdeformView.wireframe") is False
        v.page.keyboard.press("w")
        v.page.wait_for_function("window.axialdeformView.wireframe === true")
        assert v.page.locator(".axd-toggle").get_attribute("aria-pressed") == "true"
        v.page.wait_for_timeout(300)
        wire = v.silhouette()
        assert line_share(wire) > 0.3 and line_share(solid) < 0.02, (line_share(wire), line_share(solid))
        assert iou(wire, solid, BACKGROUND) > 0.5  # ... of the same instances
        v.page.locator(".axd-toggle").click()  # the button toggles back
        v.page.wait_for_function("window.axialdeformView.wireframe === false")
        v.page.wait_for_timeout(300)
        assert iou(v.silhouette(), solid, BACKGROUND) >= 0.99
        assert v.errors == []
    finally:
        v.close()
    mesh = scene_files["mesh"]
    out = tmp_path / "wire.html"
    write_page(out, build_scene(mesh, scene_files["params"], page=PageOptions(size=SIZE, mode="wireframe"), look=ad.Look(ground=False)))
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True and v.page.evaluate("window.axialdeformView.wireframe") is True
        assert line_share(v.silhouette()) > 0.3
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_canvas_fills_the_window_and_follows_resizes(browser, scene_files, tmp_path):
    out = tmp_path / "full.html"
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", "--no-ground", "stone",
                        str(scene_files["base"] / "stones ä.adp"), "-o", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert json.loads(out.read_text(encoding="utf-8").split('id="axd-config">', 1)[1].split("</script>", 1)[0]
                      .replace("<\\/", "</"))["fixed_size"] is False
    v = Visit(browser, out.as_uri(), size=(520, 360))
    try:
        info = v.page.evaluate("window.axialdeformView.info()")
        assert (info["width"], info["height"], info["fixed"]) == (520, 400, False), info  # the whole viewport
        assert abs(info["aspect"] - 520 / 400) < 1e-9
        v.page.set_viewport_size({"width": 700, "height": 300})
        v.page.wait_for_function("window.axialdeformView.info().width === 700")
        info = v.page.evaluate("window.axialdeformView.info()")
        assert (info["width"], info["height"]) == (700, 300) and abs(info["aspect"] - 700 / 300) < 1e-9
        assert mask(v.silhouette(), BACKGROUND).sum() > 1000  # still drawn after the resize
        fovy = json.loads(out.read_text(encoding="utf-8").split('id="axd-config">', 1)[1].split("</script>", 1)[0]
                          .replace("<\\/", "</"))["camera"]["fovy"]
        assert info["fov"] == fovy  # wider than the export (4:3): the exported camera as it is
        v.page.set_viewport_size({"width": 300, "height": 500})  # narrower: the same width stays in view
        v.page.wait_for_function("window.axialdeformView.info().width === 300")
        v.page.wait_for_timeout(300)
        assert v.page.evaluate("window.axialdeformView.info().fov") > fovy
        covered = mask(v.silhouette(), BACKGROUND)[:-80]  # the status line floats over the bottom rows
        assert covered.sum() > 1000 and not covered[:, 0].any() and not covered[:, -1].any()  # nothing cut off
        assert v.errors == []
    finally:
        v.close()
    v = Visit(browser, out.as_uri() + "?size=320x240", size=(520, 360))  # asked for a fixed size
    try:
        info = v.page.evaluate("window.axialdeformView.info()")
        assert (info["width"], info["height"], info["fixed"]) == (320, 240, True), info
        v.page.set_viewport_size({"width": 700, "height": 500})
        v.page.wait_for_timeout(300)
        assert v.page.evaluate("window.axialdeformView.info().width") == 320
    finally:
        v.close()
    v = Visit(browser, out.as_uri() + "?t=soon")
    try:
        assert v.state["ready"] is False and "?t=soon" in v.state["error"], v.state
        assert v.page.locator(".axd-message").is_visible()
    finally:
        v.close()


@pytest.mark.slow
@pytest.mark.parametrize("rel", ["assets/AlphaBlendModeTest.glb", "assets/cubevc.glb"])
def test_parts_alpha_modes_and_vertex_colours_match_render(browser, tmp_path, rel):
    """Nine parts (OPAQUE, MASK at three cutoffs, BLEND, textured, double-sided)
    and a mesh with vertex colours: one draw per part, the same picture as render."""
    from conftest import data_mesh

    mesh = ad.load_mesh(data_mesh(rel))
    assert mesh.has_appearance
    params = ad.random_params(mesh, 30, seed=1, variation=ad.Variation(bend=0.1), placement="disc")
    out = tmp_path / "parts.html"
    scene = build_scene(mesh, params, page=PageOptions(size=SIZE), look=ad.Look(ground=False))
    assert len(scene.config["layers"][0]["parts"]) == len([p for p in mesh.parts if p.count])
    write_page(out, scene)
    render = ad.render_image(mesh, params, SIZE, look=ad.Look(ground=False, shadow=False))
    assert_page_draws(browser, out.as_uri(), render, 30)


@pytest.mark.slow
def test_scene_page_with_a_bad_layer_file_says_which(browser, scene_pages):
    from urllib.parse import quote

    site = scene_pages["base"] / "windy site"
    bad = scene_pages["base"] / "windy bad"
    if bad.exists():
        shutil.rmtree(bad)
    shutil.copytree(site, bad)
    (bad / "layer-leaves.adp").write_bytes(_corrupt("checksum", (site / "layer-leaves.adp").read_bytes()))
    v = Visit(browser, scene_pages["url"] + quote("windy bad") + "/index.html")
    try:
        assert v.state["ready"] is False, v.state
        assert "layer-leaves.adp" in v.state["error"] and "checksum: stored CRC-32" in v.state["error"]
        assert v.page.locator(".axd-message").is_visible() and v.page.locator("canvas").count() == 0
    finally:
        v.close()


@pytest.mark.slow
def test_mesh_page_with_wind_and_a_frozen_time_matches_render(browser, tmp_path):
    """``web MESH PARAMS --wind ... --time T``: the page's clock stays at T (no
    query needed), the picture is render's with the same wind at T."""
    mesh = ad.load_mesh("leaf")
    params = ad.random_params(mesh, 400, seed=6, variation=ad.Variation(bend=0.1), placement="disc")
    adp = tmp_path / "leaves.adp"
    ad.write_params(adp, params, mesh)
    cmd = [sys.executable, "-m", "axialdeform", "web", "--no-ground", "leaf", str(adp), "--size", f"{SIZE[0]}x{SIZE[1]}"]
    r = subprocess.run(cmd + ["-o", str(tmp_path / "x.html"), "--time", "2"], capture_output=True, text=True)
    assert r.returncode == 2 and "--time" in r.stderr and "Traceback" not in r.stderr  # no wind to move
    out = tmp_path / "windy leaves.html"
    r = subprocess.run(cmd + ["-o", str(out), "--wind", "0.8,0.8,0.4", "--wind-dir", "1,0,0.3", "--time", "2"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    wind = ad.Wind(direction=(1, 0, 0.3), strength=0.8, gustiness=0.8, frequency=0.4)
    at = ad.render_image(mesh, params, SIZE, options=ad.RenderOptions(wind=wind, time=2.0), look=ad.Look(ground=False, shadow=False))
    still = ad.render_image(mesh, params, SIZE, look=ad.Look(ground=False, shadow=False))
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True and v.page.evaluate("window.axialdeformView.info().time") == 2
        shot = v.silhouette()
        assert iou(shot, at, BACKGROUND) >= 0.95
        assert iou(shot, at, BACKGROUND) > iou(shot, still, BACKGROUND) + 0.05, (iou(shot, at, BACKGROUND), iou(shot, still, BACKGROUND))
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_page_of_a_framed_mesh_shows_what_render_shows(browser, tmp_path):
    """A model lying diagonally, bent along its own length (``--axis oriented``):
    the page's ``_framed`` build draws render's picture."""
    import trimesh

    cap = trimesh.creation.capsule(height=3.0, radius=0.35, count=[16, 16])
    t = trimesh.transformations
    cap.apply_transform(t.rotation_matrix(0.6, [0, 0, 1]) @ t.rotation_matrix(1.1, [0, 1, 0]))
    obj = tmp_path / "diag.obj"
    cap.export(obj)
    mesh = ad.load_mesh(obj, axis="oriented")
    assert mesh.axis.framed
    params = ad.random_params(mesh, 40, seed=3, variation=ad.Variation(bend=0.25), placement="disc")
    adp = tmp_path / "rods.adp"
    ad.write_params(adp, params, mesh)
    out = tmp_path / "rods.html"
    r = subprocess.run([sys.executable, "-m", "axialdeform", "web", "--no-ground", str(obj), str(adp), "--axis", "oriented",
                        "-o", str(out), "--size", f"{SIZE[0]}x{SIZE[1]}"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    look = ad.Look(ground=False, shadow=False)
    render = ad.render_image(mesh, ad.read_params(adp, mesh), SIZE, look=look)
    auto = ad.render_image(mesh.with_axis("auto"), params, SIZE, look=look)
    assert iou(render, auto, BACKGROUND) < 0.9, iou(render, auto, BACKGROUND)  # the frame changes the picture
    assert_page_draws(browser, out.as_uri(), render, 40)


@pytest.mark.slow
@pytest.mark.parametrize("quantize", [True, False])
def test_page_of_trees_shows_what_render_shows(browser, tmp_path, quantize):
    """A mesh of ten axes (the bundled tree): the page splits each record into
    axis 0's attributes and the child axes' texture, and draws render's picture."""
    from axialdeform.core.axes import TREE_AXES

    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    params = ad.random_params(mesh, 60, seed=4, variation=ad.Variation(bend=(0.05, 0.5, 0.5), scale=(0.8, 1.2)), placement="disc",
                              spacing=3.0)
    out = tmp_path / "trees.html"
    write_page(out, build_scene(mesh, params, page=PageOptions(size=SIZE, quantize=quantize), look=ad.Look(ground=False)))
    look = ad.Look(ground=False, shadow=False)
    used = params
    if quantize:  # what the page holds: the quantized file's numbers
        from axialdeform.core.io.params import decode_binary, encode_binary

        used = decode_binary(encode_binary(params, axis=mesh, quantize=True)).values
    render = ad.render_image(mesh, used, SIZE, look=look)
    straight = params.copy()
    straight[:, 10:100] = 0  # the child axes unbent: the page must bend them to match
    unbent = ad.render_image(mesh, straight, SIZE, look=look)
    assert iou(render, unbent, BACKGROUND) < 0.9
    assert_page_draws(browser, out.as_uri(), render, 60)


@pytest.mark.slow
def test_widget_draws_trees_and_takes_new_tree_numbers(browser, tmp_path):
    """SceneWidget of a mesh of ten axes: drawn as render draws it; set_params
    with new numbers for every axis redraws it."""
    from axialdeform.core.axes import TREE_AXES
    from axialdeform.core.io.params import decode_binary
    from axialdeform.widget import SceneWidget

    mesh = ad.load_mesh("tree", axes=TREE_AXES)
    params = ad.random_params(mesh, 40, seed=2, variation=ad.Variation(bend=(0.05, 0.4)), placement="disc", spacing=3.0)
    w = SceneWidget(mesh, params, size=SIZE, look=ad.Look(ground=False))
    assert w.config["layers"][0]["mesh"]["axes"]["count"] == 10
    state = widget_state(w)
    page, errors = widget_page(browser, tmp_path, state, w._esm)
    try:
        assert page.evaluate("window.widgetStatus") == {"ready": True, "instances": 40}
        clip = page.locator(".axd-stage").bounding_box()
        before = page.screenshot(clip=clip)
        again = ad.random_params(mesh, 40, seed=3, variation=ad.Variation(bend=(0.05, 0.4)), placement="disc", spacing=3.0)
        w.set_params(again)
        assert decode_binary(w.params_adp).values.shape == (40, 106)
        assert _push_params(page, w.params_adp) == {"ready": True, "instances": 40}
        assert _picture_changes(page, clip, before)
        assert errors == []
    finally:
        page.close()


def test_the_module_files_come_each_after_what_it_imports():
    """The single-file page and the widget link the npm module's files in MODULE_FILES' order (loader.js): each
    file's imports of the module must be shipped and come before it (else the page waits on an import that
    never resolves)."""
    from axialdeform.web.sources import MODULE_FILES

    src = ROOT / "js" / "src"
    for k, name in enumerate(MODULE_FILES):
        text = (src / name).read_text()
        for spec in re.findall(r"""from\s*['"](\.\.?/[\w./]+)['"]""", text):
            dep = (src / name).parent.joinpath(spec).resolve().relative_to(src.resolve()).as_posix()
            assert dep in MODULE_FILES[:k], (name, dep)


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["solid", "wireframe"])
def test_the_page_draws_renders_shadows(browser, tmp_path, mode):
    """The default look: the page stands the stones on render's ground AND casts render's key-light shadows (the
    same light camera, core.bounds.light_box; glsl/shadow.glsl), so the page is render's picture, shadows and all
    -- which differs visibly from render's picture without them.  (In wireframe the page's lines are three's, not
    render's hidden lines: there the shadows on the ground are compared.)"""
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 40, seed=5, variation=ad.Variation(bend=0.2), placement="disc")
    out = tmp_path / "shadows.html"
    scene = build_scene(mesh, params, page=PageOptions(size=SIZE, mode=mode))
    assert scene.config["shadow"] is not None and scene.config["ground"] is not None
    write_page(out, scene)
    ref = ad.render_image(mesh, params, SIZE, mode).astype(np.float64)
    unshadowed = ad.render_image(mesh, params, SIZE, mode, look=ad.Look(shadow=False)).astype(np.float64)
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True, v.state
        shot = v.silhouette().astype(np.float64)
        from PIL import Image

        Image.fromarray(np.concatenate([shot, ref, unshadowed], 1).astype(np.uint8)).save(tmp_path / "shadows.png")
        colours, counts = np.unique(unshadowed.reshape(-1, 3), axis=0, return_counts=True)
        bare = np.abs(unshadowed - colours[counts.argmax()]).max(axis=2) <= 12  # the ground, no stone on it
        shadowed = (np.abs(ref - unshadowed).max(axis=2) > 24) & bare  # where render's shadows fall on it
        assert shadowed.mean() > 0.01
        assert np.abs(shot - ref)[shadowed].mean() < 0.35 * np.abs(unshadowed - ref)[shadowed].mean()
        if mode == "solid":
            assert np.abs(shot - ref).mean() < 3.0
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_without_a_ground_the_instances_shadow_each_other_as_in_render(browser, tmp_path):
    """A look without the ground plane (``web --no-ground``): render still draws the key light's shadows of
    instances on each other, and so does the page."""
    mesh = ad.load_mesh("tree")
    params = ad.random_params(mesh, 30, seed=2, variation=ad.Variation(bend=0.2), placement="disc", spacing=0.6)
    look = ad.Look(ground=False)
    scene = build_scene(mesh, params, page=PageOptions(size=SIZE, quantize=False), look=look)
    assert scene.config["ground"] is None and scene.config["shadow"] is not None
    out = tmp_path / "no-ground.html"
    write_page(out, scene)
    ref = ad.render_image(mesh, params, SIZE, look=look).astype(np.float64)
    unshadowed = ad.render_image(mesh, params, SIZE, look=ad.Look(ground=False, shadow=False)).astype(np.float64)
    v = Visit(browser, out.as_uri())
    try:
        assert v.state["ready"] is True, v.state
        shot = v.silhouette().astype(np.float64)
        from PIL import Image

        Image.fromarray(np.concatenate([shot, ref, unshadowed], 1).astype(np.uint8)).save(tmp_path / "no-ground.png")
        shadowed = np.abs(ref - unshadowed).max(axis=2) > 24  # where one instance's shadow falls on another
        assert shadowed.mean() > 0.005
        assert np.abs(shot - ref)[shadowed].mean() < 0.5 * np.abs(unshadowed - ref)[shadowed].mean()
        assert v.errors == []
    finally:
        v.close()


@pytest.mark.slow
def test_page_of_one_piece_woods_shows_what_render_shows(browser, tmp_path, monkeypatch):
    """axes="skeleton" on a one-piece wood with crowns and bark marks (tests/helpers/one_piece.py): the page
    bends every branch the skeleton found, and the carried pieces blending two branches (AxisTree.blend: the
    GLB's _AXIAL_AXIS code), as render does."""
    from helpers.one_piece import crowned_tree

    monkeypatch.setenv("AXIALDEFORM_CACHE", str(tmp_path / "cache"))
    mesh = crowned_tree().with_axes("skeleton")
    assert mesh.tree.blend is not None
    k = mesh.axis_count
    params = ad.random_params(mesh, 30, seed=4, variation=ad.Variation(bend=(0.05, 0.5)), placement="disc", spacing=3.0)
    out = tmp_path / "woods.html"
    write_page(out, build_scene(mesh, params, page=PageOptions(size=SIZE, quantize=False), look=ad.Look(ground=False)))
    look = ad.Look(ground=False, shadow=False)
    render = ad.render_image(mesh, params, SIZE, look=look)
    straight = params.copy()
    straight[:, 10:10 * k] = 0  # the branches unbent: the page must bend them to match
    assert iou(render, ad.render_image(mesh, straight, SIZE, look=look), BACKGROUND) < 0.9
    assert_page_draws(browser, out.as_uri(), render, 30)
