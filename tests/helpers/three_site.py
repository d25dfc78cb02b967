"""A site of the npm module's examples (examples/web) with their data, served on loopback, and the
pictures ``render`` draws of the same scenes: what the three.js tests compare."""

from __future__ import annotations

import shutil
import subprocess
import sys
import threading
from io import BytesIO
from pathlib import Path

import numpy as np
from PIL import Image

import axialdeform as ad
from axialdeform.web import make_server

from conftest import ALPHA_TEST, data_mesh

ROOT = Path(__file__).resolve().parents[2]
JS = ROOT / "js"
EXAMPLES = ROOT / "examples" / "web"
BACKGROUND = (0.93, 0.94, 0.96)  # Look()'s: render draws on it, the examples are set to it
SIZE = (480, 360)
CAMERA = ["--eye", "7,5,7", "--target", "0,0,0", "--fov", "40"]  # the examples' camera


def cli(*args, cwd=None):
    r = subprocess.run([sys.executable, "-m", "axialdeform", *map(str, args)], capture_output=True, text=True, cwd=cwd)
    assert r.returncode == 0, r.stderr
    return r


def node_modules_three() -> Path:
    three = JS / "node_modules" / "three"
    assert (three / "build" / "three.module.js").is_file(), \
        "js/node_modules/three is missing: the README's test command runs `npm ci --prefix js`"
    return three


TREE_AXES = ROOT / "examples" / "forest" / "tree-axes.toml"
# name, mesh, options of `random` (the first two, the mesh's axis, also for export and render)
MORE = [
    ("trees", "tree", ["--axes", TREE_AXES, "-n", 9, "--seed", 2, "--spacing", 3, "--twist", 0.3]),
    ("framed", "stone", ["--axis", "oriented", "-n", 30, "--seed", 4, "--twist", 0.8, "--taper", 0.3,
                         "--scale", "0.7:1.3", "--bend", 0.15]),
    ("leaves", "leafcard", ["--axis", "auto", "-n", 40, "--seed", 5, "--tint", 0.3, "--bend", 0.15]),
    # the Khronos alpha-modes model: 9 textured parts (opaque, mask, blend), as an artist ships it
    ("alpha", str(data_mesh(ALPHA_TEST)),
     ["--axis", "auto", "-n", 4, "--seed", 1, "--bend", 0.05, "--spacing", 6]),
]


def make_site(folder: Path, modules: bool = True) -> Path:
    """The examples with their data: stone.obj, stones.adp (60 stones), stones.glb (instanced)."""
    folder.mkdir(parents=True, exist_ok=True)
    if modules:
        (folder / "node_modules").mkdir()
        (folder / "node_modules" / "three").symlink_to(node_modules_three())
        (folder / "node_modules" / "axialdeform-three").symlink_to(JS)
    for f in EXAMPLES.glob("*.html"):
        shutil.copy(f, folder / f.name)
    shutil.copy(ROOT / "tests" / "web" / "three" / "checks.html", folder / "checks.html")
    shutil.copy(ROOT / "axialdeform" / "meshes" / "stone.obj", folder / "stone.obj")
    cli("random", "stone", "-n", 60, "--seed", 3, "--bend", 0.15, "-o", folder / "stones.adp")
    cli("export", "stone", folder / "stones.adp", "--instanced", "-o", folder / "stones.glb")
    for name, mesh, opts in MORE:  # a tree of ten axes, a chosen frame with twist/taper, tinted leaves, 9 parts
        cli("random", mesh, *opts, "-o", folder / f"{name}.adp")
        cli("export", mesh, folder / f"{name}.adp", *opts[:2], "--instanced", "-o", folder / f"{name}.glb")
    mesh = ad.load_mesh("stone")
    one = np.zeros((1, 16), np.float32)
    L = mesh.axis.length
    one[0, :10] = np.array([0, 0, 0.1, 0.35, -0.2, 0.5, 0.1, 0.35, 0, 0]) * L  # an arch across, its ends in place
    ad.write_params(folder / "one.adp", one, mesh)
    return folder


class Server:
    def __init__(self, folder):
        self.server, _ = make_server(folder, 0, follow=(ROOT / "js",))  # the sites link node_modules there
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}/"

    def close(self):
        self.server.shutdown()
        self.server.server_close()


def mask(image, background=BACKGROUND):
    return np.abs(image.astype(np.float64) - np.asarray(background) * 255.0).max(axis=2) > 12


def iou(a, b) -> float:
    ma, mb = mask(a), mask(b)
    return float((ma & mb).sum() / max((ma | mb).sum(), 1))


def example_picture(browser, url, extra: str = "") -> tuple[np.ndarray, list]:
    """The example at ``url`` drawn on render's background without its ground and fog."""
    page = browser.new_page(viewport={"width": SIZE[0], "height": SIZE[1]})
    errors = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        page.goto(url)
        page.wait_for_function("window.app !== undefined", timeout=120_000)
        page.evaluate("""() => {
            const { THREE, renderer, scene, camera, ground } = window.app;
            renderer.setAnimationLoop(null);
            """ + extra + """
            ground.visible = false;
            scene.fog = null;
            scene.background = new THREE.Color().setRGB(0.93, 0.94, 0.96, THREE.SRGBColorSpace);
            renderer.render(scene, camera);
        }""")
        png = page.locator("canvas").screenshot()
        return np.asarray(Image.open(BytesIO(png)).convert("RGB")), errors
    finally:
        page.close()


def render_reference(folder: Path, what, **kw) -> np.ndarray:
    """What ``axialdeform render MESH PARAMS [--axis|--axes X] --eye 7,5,7 --target 0,0,0 --fov 40``
    draws (render_image, the command's own call), multisampled as three's antialias, without
    the ground and shadow (the examples' ground is hidden for the comparison)."""
    mesh, params, *axis = what
    base = ad.load_mesh(mesh, **({axis[0].lstrip("-"): str(axis[1])} if axis else {}))
    look = ad.Look(ground=False, shadow=False)
    camera = ad.Camera(eye=(7, 5, 7), target=(0, 0, 0), fovy=40.0, near=0.1, far=100.0)
    image = ad.render_image(base, ad.read_params(params, mesh=base), size=SIZE, look=look, camera=camera,
                           options=ad.RenderOptions(**kw))
    Image.fromarray(image).save(folder / "reference.png")
    return image
