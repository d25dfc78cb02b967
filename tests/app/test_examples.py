"""Every script in examples/ runs (quick mode, headless, in a subprocess) and
its pictures show what they claim; the viewer runs headless and reacts to
keys and the mouse.  Nothing here skips: no EGL context is a failure."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

import axialdeform as ad

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES_DIR = ROOT / "examples"
#: every example, with the files it writes; the meta-test keeps this in step with the folder
EXAMPLES = {
    "01_stones.py": ("01_stones.png", "01_stones_bank.png"),
    "02_falling_leaves.py": ("02_falling_leaves.gif", "02_falling_leaves.png"),
    "03_own_moderngl_program.py": ("03_own_moderngl_program.png",),
    "04_moderngl_window_app.py": ("04_moderngl_window_app.png",),
    "05_landscape.py": ("05_landscape.png", "05_landscape.gif"),
    "06_forest.py": ("06_forest.png", "06_forest_close.png", "06_forest.gif"),
    "07_generated_walk.py": ("07_generated_walk.png", "07_generated_walk_far.png"),
    "08_learned_forest.py": ("08_learned_forest.png", "08_survey.csv"),
}
BACKGROUND = np.array([0.93, 0.94, 0.96]) * 255  # render_image's default clear colour


def test_every_example_is_tested():
    found = {p.name for p in EXAMPLES_DIR.glob("[0-9][0-9]_*.py")}
    assert found == set(EXAMPLES), (
        f"examples/ and tests/app/test_examples.py disagree: untested {sorted(found - set(EXAMPLES))}, "
        f"missing {sorted(set(EXAMPLES) - found)}")


@pytest.fixture(scope="module")
def run_example(tmp_path_factory):
    """Run an example once per module (``--quick -o DIR``); returns DIR."""
    done = {}

    def run(name: str) -> Path:
        if name not in done:
            out = tmp_path_factory.mktemp(name[:2])
            proc = subprocess.run([sys.executable, str(EXAMPLES_DIR / name), "--quick", "-o", str(out)],
                                  cwd=out, capture_output=True, text=True, timeout=300)
            assert proc.returncode == 0, f"{name} failed:\n{proc.stdout}\n{proc.stderr}"
            for f in EXAMPLES[name]:
                assert (out / f).is_file(), f"{name} did not write {f}"
            done[name] = (out, proc.stdout)
        return done[name]

    return run


def load(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def foreground(image: np.ndarray, background) -> np.ndarray:
    """Pixels that differ from the background colour (bool mask)."""
    return np.abs(image.astype(np.int16) - np.asarray(background, dtype=np.float64)).max(axis=2) > 14


def blobs(mask: np.ndarray) -> int:
    return int(ndimage.label(mask)[1])


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_example_runs(run_example, name):
    out, stdout = run_example(name)
    assert "wrote" in stdout
    for f in EXAMPLES[name]:
        assert (out / f).stat().st_size > 1000


@pytest.mark.slow
def test_stones_solid_and_wireframe_agree(run_example):
    out, _ = run_example("01_stones.py")
    image = load(out / "01_stones.png")
    h, w, _ = image.shape
    assert w == 2 * h * 4 // 3, "solid | wireframe side by side, 4:3 panels"
    # the panels stand on the ground: no bare background (a void) below the horizon
    assert foreground(image[h // 3:], BACKGROUND).mean() > 0.99, "background showing under the stones"
    # solid and wireframe agree: the example's stones and camera drawn without the ground, each
    # silhouette against the background
    import importlib.util

    spec = importlib.util.spec_from_file_location("stones_example", ROOT / "examples" / "01_stones.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    mesh = ad.load_mesh("stone")
    params = example.river_bank(mesh, 600, 7)
    image = ad.render_image(mesh, params, (320, 240), ("solid", "wireframe"), camera=example.camera(params),
                            look=ad.Look(ground=False))
    h, w, _ = image.shape
    solid = foreground(image[:, : w // 2], BACKGROUND)
    wire = foreground(image[:, w // 2:], BACKGROUND)
    assert 0.2 < solid.mean() < 0.95, f"stones cover {solid.mean():.0%} of the solid panel"
    assert blobs(solid[h // 2:]) >= 8, "separate stones are visible in the foreground"
    # the wireframe lies on the solid silhouette ...
    inside = ndimage.binary_dilation(solid, iterations=2)
    assert (wire & ~inside).sum() <= 0.01 * wire.sum(), "wireframe pixels outside the solid stones"
    # ... and, filled, covers it
    filled = ndimage.binary_fill_holes(ndimage.binary_closing(wire, iterations=2))
    assert (filled & solid).sum() >= 0.9 * solid.sum(), "the filled wireframe misses solid pixels"


@pytest.mark.slow
def test_stones_bank_has_ground_and_tints(run_example):
    out, _ = run_example("01_stones.py")
    image = load(out / "01_stones_bank.png").astype(np.float64)
    bottom = image[image.shape[0] // 2:]
    assert bottom.std() > 15, "stones on the ground show contrast"
    # per-instance tint: some stones are ochre (red clearly above blue)
    warm = (bottom[..., 0] - bottom[..., 2]) > 40
    assert 0.002 < warm.mean() < 0.5


@pytest.mark.slow
def test_leaves_gif_animates(run_example):
    out, stdout = run_example("02_falling_leaves.py")
    assert "0 reallocations" in stdout
    gif = Image.open(out / "02_falling_leaves.gif")
    assert gif.n_frames >= 5
    frames = []
    for i in range(gif.n_frames):
        gif.seek(i)
        frames.append(np.asarray(gif.convert("RGB")).astype(np.int16))
    for a, b in zip(frames, frames[1:]):
        assert np.abs(a - b).mean() > 0.5, "consecutive frames must differ"
    first = load(out / "02_falling_leaves.png").astype(np.int16)
    leaves = (first[..., 0] - first[..., 2]) > 30  # autumn colours against a blue-grey sky and grey ground
    assert blobs(leaves) >= 20, f"only {blobs(leaves)} leaves visible"


@pytest.mark.slow
def test_own_program_picture(run_example):
    out, _ = run_example("03_own_moderngl_program.py")
    image = load(out / "03_own_moderngl_program.png").astype(np.int16)
    mask = foreground(image, (0.95 * 255, 0.95 * 255, 0.93 * 255))
    assert blobs(mask) >= 40, "separate stones are visible"
    blue = (image[..., 2] - image[..., 0]) > 40
    orange = (image[..., 0] - image[..., 2]) > 40
    assert blue.sum() > 50 and orange.sum() > 20, "the shader colours by bend: both ends of the ramp appear"


@pytest.mark.slow
def test_moderngl_window_app_picture(run_example):
    out, _ = run_example("04_moderngl_window_app.py")
    image = load(out / "04_moderngl_window_app.png").astype(np.int16)
    green = (image[..., 1] - image[..., 0] > 20) & (image[..., 1] - image[..., 2] > 20)
    assert green.mean() > 0.05, f"blades cover {green.mean():.1%} of the picture"


def test_landscape_picture_and_animation(run_example):
    out, stdout = run_example("05_landscape.py")
    assert "stones" in stdout and "grass" in stdout and "trunks" in stdout and "leaves" in stdout
    image = load(out / "05_landscape.png").astype(np.int16)
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    grass = (g - r > 10) & (g - b > 10)
    leaves = (r - b > 70) & (r - g > 25)  # orange
    sky = (b - r > 20) & (image.sum(axis=2) > 600)
    assert grass.mean() > 0.01, f"grass covers {grass.mean():.1%}"
    assert blobs(leaves) >= 5, f"only {blobs(leaves)} leaves visible"
    assert 0.2 < sky.mean() < 0.9, "the terrain fills part of the picture, the sky the rest"
    gif = Image.open(out / "05_landscape.gif")
    frames = []
    for i in range(gif.n_frames):
        gif.seek(i)
        frames.append(np.asarray(gif.convert("RGB")).astype(np.int16))
    assert len(frames) >= 5
    assert np.abs(frames[0] - frames[-1]).mean() > 0.3, "leaves fall and grass sways"


@pytest.mark.slow
def test_forest_picture_and_wind(run_example):
    out, stdout = run_example("06_forest.py")
    assert "trees of 10 axes: 436 bytes a tree" in stdout
    for name in ("06_forest.png", "06_forest_close.png"):
        image = load(out / name).astype(np.int16)
        r, g, b = image[..., 0], image[..., 1], image[..., 2]
        leaves = (g - r > 15) & (g - b > 15)
        assert leaves.mean() > 0.02, f"{name}: leaves cover {leaves.mean():.1%}"
        assert blobs(leaves) >= 10, f"{name}: only {blobs(leaves)} crowns"
    gif = Image.open(out / "06_forest.gif")
    frames = []
    for i in range(gif.n_frames):
        gif.seek(i)
        frames.append(np.asarray(gif.convert("RGB")).astype(np.int16))
    assert len(frames) >= 4 and np.abs(frames[0] - frames[-1]).mean() > 0.3, "the wind sways the trees"


# ---------------------------------------------------------------- the viewer
@pytest.fixture(scope="module")
def viewer():
    from axialdeform.viewer import Viewer, ViewerSettings

    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 60, seed=2, variation=ad.Variation(bend=0.1))
    v = Viewer.create(mesh, params, headless=True, size=(160, 120), settings=ViewerSettings(seed=2, bend=0.1))
    yield v
    v.release()
    v.wnd.destroy()


def press(v, key):
    v.on_key_event(key, v.wnd.keys.ACTION_PRESS, None)
    v.step()
    return v.screenshot()


def test_viewer_draws_headless(viewer):
    viewer.step(2)
    image = viewer.screenshot()
    assert image.shape == (120, 160, 3)
    assert image.std() > 10
    assert "60 instances" in viewer.wnd.title and "fps" in viewer.wnd.title


def test_viewer_keys_switch_modes(viewer):
    pictures = {}
    for key, mode in (("2", "flat"), ("3", "wireframe"), ("1", "solid")):
        pictures[mode] = press(viewer, key)
        assert viewer.mode == mode
        assert mode in viewer.wnd.title
    assert np.abs(pictures["solid"].astype(int) - pictures["wireframe"]).mean() > 1
    press(viewer, "w")
    assert viewer.mode == "flat"
    press(viewer, "1")


def test_viewer_new_seed_and_bend(viewer):
    before = press(viewer, "G")  # ground off: only the instances differ below
    seed = viewer.seed
    after = press(viewer, "n")
    assert viewer.seed == seed + 1
    assert np.abs(before.astype(int) - after).sum() > 0
    scale = viewer.bend_scale
    bent = press(viewer, "UP")
    assert viewer.bend_scale == pytest.approx(scale * 1.25)
    assert np.abs(bent.astype(int) - after).sum() > 0
    shown = viewer.renderer.instances.read()
    np.testing.assert_allclose(shown[:, :10], viewer.base[:, :10] * viewer.bend_scale, rtol=1e-6, atol=1e-7)
    press(viewer, "DOWN")
    assert viewer.bend_scale == pytest.approx(scale)
    assert viewer.renderer.instances.reallocations == 0
    press(viewer, "G")


def test_viewer_title_shows_the_real_seed_or_none(viewer):
    assert isinstance(viewer.seed, int) and f"seed {viewer.seed}" in viewer.status()  # made with seed 2 (+1 per N)
    seed = viewer.seed
    try:
        viewer.seed = None  # what Viewer.create(..., seed=None) sets: parameters from a file
        viewer.step()
        assert "seed" not in viewer.status()
        press(viewer, "n")  # new offsets: now there is a seed to show
        assert viewer.seed == 0 and "seed 0" in viewer.wnd.title
    finally:
        viewer.regenerate(seed)


def test_viewer_mouse_orbits_and_zooms(viewer):
    before = press(viewer, "r")
    az, dist = viewer.azimuth, viewer.distance
    viewer.on_mouse_drag_event(0, 0, 40, 10)
    viewer.on_mouse_scroll_event(0, 2)
    viewer.step()
    assert viewer.azimuth != az and viewer.distance < dist
    assert np.abs(viewer.screenshot().astype(int) - before).mean() > 1
    press(viewer, "r")
    assert viewer.distance == pytest.approx(dist)


@pytest.mark.slow
def test_view_command_headless(tmp_path):
    shot = tmp_path / "view.png"
    proc = subprocess.run([sys.executable, "-m", "axialdeform", "view", "leaf", "-n", "40", "--headless", "--frames",
                           "2", "--size", "160x120", "--mode", "wireframe", "--screenshot", str(shot)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "40 instances - wireframe" in proc.stdout
    assert load(shot).shape == (120, 160, 3)


def test_view_command_errors_are_one_line(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "axialdeform", "view", str(tmp_path / "missing.obj"), "--headless"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.startswith("axialdeform view: error:") and "Traceback" not in proc.stderr


def test_viewer_animates_the_leaves_in_place():
    import importlib.util

    from axialdeform.viewer import Viewer, ViewerSettings

    spec = importlib.util.spec_from_file_location("falling_leaves", EXAMPLES_DIR / "02_falling_leaves.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    leaves = module.FallingLeaves(80)
    v = Viewer.create(ad.load_mesh("leaf"), leaves.at(0.0), settings=ViewerSettings(animate=leaves.at, tint=leaves.colours()),
                      headless=True, size=(120, 90))
    try:
        v.step(2)
        a = v.screenshot()
        v.step(3)
        assert np.abs(a.astype(int) - v.screenshot()).mean() > 0.1
        assert v.renderer.instances.reallocations == 0
        with pytest.raises(ad.core.ParamError):
            Viewer.create(ad.load_mesh("leaf"), leaves.at(0.0)[:5], settings=ViewerSettings(animate=leaves.at), headless=True)
    finally:
        v.release()
        v.wnd.destroy()


def test_viewer_draws_trees_and_new_seeds_bend_every_axis():
    from axialdeform.core.axes import TREE_AXES
    from axialdeform.viewer import Viewer, ViewerSettings

    tree = ad.load_mesh("tree", axes=TREE_AXES)
    params = ad.random_params(tree, 12, seed=2, variation=ad.Variation(bend=(0.05, 0.3)), spacing=3.0)
    v = Viewer.create(tree, params, headless=True, size=(160, 120), settings=ViewerSettings(seed=2, bend=0.3))
    try:
        v.step()
        first = v.screenshot()
        before = v.base.copy()
        after = press(v, "n")
        assert np.abs(v.base[:, 10:100] - before[:, 10:100]).max() > 0  # the child axes got new numbers too
        assert np.array_equal(v.base[:, 100:], before[:, 100:])  # placement and orientation stay
        assert np.abs(after.astype(int) - first).mean() > 0.5
    finally:
        v.release()
        v.wnd.destroy()


@pytest.mark.slow
def test_the_generated_walk_does_not_end_and_holds_the_same_count(run_example):
    """Seven hundred units from the start the field is as full as at the start (the tiles there were
    made as the camera came), with the same number of instances held (the far ones let go)."""
    import re

    out, stdout = run_example("07_generated_walk.py")
    m = re.search(r"(\d+) instances held at .*?, (\d+) at .*?, (\d+) units away", stdout)
    assert m, stdout
    start, far, away = (int(x) for x in m.groups())
    assert away > 500 and start == far and 2000 < start < 40_000, stdout
    sky = np.array([0.80, 0.87, 0.95]) * 255
    for f in EXAMPLES["07_generated_walk.py"]:
        img = load(out / f)
        lower = img[img.shape[0] // 2:]  # the ground half: stones, blades and trees everywhere, no sky
        assert foreground(lower, sky).mean() > 0.97, f
        # many separate things on the ground (the ground's colour: the commonest, the median pixel)
        assert blobs(foreground(lower, np.median(lower.reshape(-1, 3), axis=0))) > 40, f



@pytest.mark.slow
def test_the_learned_forest_stands_in_clumps_on_the_landscape(run_example):
    """The survey is learned as clumps thicker on steep ground, and the landscape grows trees from it."""
    out, stdout = run_example("08_learned_forest.py")
    assert "cluster" in stdout and "slope" in stdout, stdout
    scene = ad.Scene.load(out / "08_learned_forest.toml")
    gen = scene.layers[0].generate.generate
    assert gen.clumped and len(scene.layers[0].params) > 100
    img = load(out / "08_learned_forest.png")
    green = (img[:, :, 1].astype(int) - img[:, :, 0] > 20) & (img[:, :, 1].astype(int) - img[:, :, 2] > 20)
    assert green.mean() > 0.05, green.mean()  # the crowns
