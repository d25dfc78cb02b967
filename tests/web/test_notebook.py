"""The notebook widget in a REAL Jupyter front end: a JupyterLab server on
127.0.0.1 (a free port, a token, a temporary folder as its root, no browser
opened, nothing fetched from the network), a notebook opened in Debian's
headless chromium by Playwright, its cells run by JupyterLab itself.  The
widget must draw in the output area, follow ``set_params`` and show what
``axialdeform render`` shows.  Nothing here skips: without chromium,
playwright or jupyterlab the test fails (``pip install -e ".[test]"``
installs jupyterlab; the README's test command installs chromium).

VS Code's notebook front end is not tested (it cannot run here)."""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import socket
import subprocess
import sys
import time
from io import BytesIO
from pathlib import Path
from urllib.error import URLError
from urllib.parse import quote
from urllib.request import ProxyHandler, build_opener

import numpy as np
import pytest

import axialdeform as ad

SIZE = (400, 300)
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"]
BACKGROUND = (0.93, 0.94, 0.96)
STARTUP_S = 180  # the server's start on a busy machine; a dead server fails the test at once


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Lab:
    """A JupyterLab server of this interpreter (its kernel is this venv's
    python3), isolated from the user's Jupyter config and data."""

    def __init__(self, root: Path):
        self.root = root
        self.token = secrets.token_hex(16)
        self.port = _free_port()
        home = root.parent / "jupyter-home"
        env = {**os.environ, "JUPYTER_CONFIG_DIR": str(home / "config"), "JUPYTER_DATA_DIR": str(home / "data"),
               "JUPYTER_RUNTIME_DIR": str(home / "runtime"), "JUPYTER_PLATFORM_DIRS": "1",
               "IPYTHONDIR": str(home / "ipython"), "PYTHONUNBUFFERED": "1"}
        cmd = [sys.executable, "-m", "jupyterlab", "--no-browser", "--ip=127.0.0.1", f"--port={self.port}",
               "--ServerApp.port_retries=0", f"--IdentityProvider.token={self.token}",
               f"--ServerApp.root_dir={root}", "--expose-app-in-browser",
               # nothing fetched from the network: no news, no update check
               "--LabApp.news_url=None", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
               "--LabApp.extension_manager=readonly", "--ServerApp.terminals_enabled=False",
               f"--LabApp.user_settings_dir={home / 'settings'}", f"--LabApp.workspaces_dir={home / 'workspaces'}"]
        if hasattr(os, "geteuid") and os.geteuid() == 0:  # CI containers run as root
            cmd.append("--allow-root")
        # no "get Jupyter news?" pop-up over the output (nothing is fetched anyway: news_url=None)
        labconfig = home / "config" / "labconfig"
        labconfig.mkdir(parents=True)
        (labconfig / "page_config.json").write_text(json.dumps(
            {"disabledExtensions": {"@jupyterlab/apputils-extension:announcements": True}}))
        self.log = open(root.parent / "jupyterlab.log", "w+")
        self.proc = subprocess.Popen(cmd, stdout=self.log, stderr=subprocess.STDOUT, env=env, cwd=root)
        self.url = f"http://127.0.0.1:{self.port}"
        try:
            self.startup_s = self._wait()
        except BaseException:
            self.close()
            raise

    def _wait(self) -> float:
        direct = build_opener(ProxyHandler({}))  # 127.0.0.1 never through an http_proxy
        t0 = time.monotonic()
        while True:
            if self.proc.poll() is not None:
                raise AssertionError(f"jupyterlab exited with {self.proc.returncode}:\n{self.text_log()}")
            try:
                with direct.open(f"{self.url}/api/status?token={self.token}", timeout=5) as r:
                    if r.status == 200:
                        return time.monotonic() - t0
            except (URLError, OSError):
                pass
            assert time.monotonic() - t0 < STARTUP_S, f"jupyterlab did not answer in {STARTUP_S} s:\n{self.text_log()}"
            time.sleep(0.25)

    def text_log(self) -> str:
        self.log.flush()
        return Path(self.log.name).read_text(errors="replace")

    def close(self):
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=30)
        self.log.close()


def _notebook(path: Path, cells: list[str]) -> None:
    import nbformat

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(c) for c in cells]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nbformat.write(nb, str(path))


def _image(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(BytesIO(png)).convert("RGB"))


def _mask(image: np.ndarray) -> np.ndarray:
    return np.abs(image.astype(np.float64) - np.asarray(BACKGROUND) * 255.0).max(axis=2) > 12


def iou(a: np.ndarray, b: np.ndarray) -> float:
    ma, mb = _mask(a), _mask(b)
    return float((ma & mb).sum() / max((ma | mb).sum(), 1))


def _cell(page, i: int):
    return page.locator(".jp-Notebook .jp-Cell").nth(i)


def _run_cell(page, i: int) -> None:
    """Run cell ``i`` the way a user does (JupyterLab's own run command)."""
    page.evaluate("""(i) => { const nb = window.jupyterapp.shell.currentWidget;
        nb.content.activeCellIndex = i; window.jupyterapp.commands.execute('notebook:run-cell'); }""", i)


def _stage_image(page) -> np.ndarray:
    box = page.locator(".jp-OutputArea-output .axd-stage").bounding_box()
    return _image(page.screenshot(clip=box))


@pytest.mark.slow
def test_widget_in_jupyterlab(tmp_path, playwright_driver):
    """JupyterLab runs the cells: ``SceneWidget(...)`` draws in the output
    area, the silhouettes equal ``axialdeform render``'s (its function,
    without ground and shadow) of the same file at the same size, ``set_params`` changes the count shown and the
    picture, the status comes back to Python; keys on the focused picture
    are its own, not JupyterLab's shortcuts; a second view shares the
    one copy of three.js and re-running its cell releases the old view's
    WebGL context; the browser reports no console error and asks nothing
    of the network."""
    chromium = shutil.which("chromium")
    assert chromium, "Debian's chromium is required (apt-get install chromium); this test does not skip"
    root = tmp_path / "notebooks ü"
    root.mkdir()
    mesh = ad.load_mesh("stone")
    adp = root / "stones ä.adp"
    ad.write_params(adp, ad.random_params(mesh, 1200, seed=7, variation=ad.Variation(bend=0.12), placement="disc"), mesh)
    # axialdeform render's picture of the same file at the same size: its function, with antialiasing
    # like the widget's canvas but without render's ground and shadow (the widget draws neither);
    # `render --fast` also drops the antialiasing, which thins these 8-pixel stones (IoU about 0.84)
    render = ad.render_image(mesh, ad.read_params(adp, mesh), SIZE, look=ad.Look(ground=False, shadow=False))
    _notebook(root / "scène.ipynb", [
        "import axialdeform as ad\nfrom axialdeform.widget import SceneWidget\n"
        f"m = ad.load_mesh('stone')\nw = SceneWidget(m, ad.read_params({adp.name!r}, m), size={SIZE!r}, look=ad.Look(ground=False))\nw",
        "w.set_params(ad.random_params(m, 150, seed=8, variation=ad.Variation(bend=0.12), placement='disc'))\nw.config['instances']",
        "w.status",
        "w",  # a second view of the same widget
    ])
    t0 = time.monotonic()
    lab = Lab(root)
    timings = {"server": lab.startup_s}
    try:
        with contextlib.nullcontext(playwright_driver) as pw:  # the process's one Playwright (conftest)
            browser = pw.chromium.launch(executable_path=chromium, args=CHROMIUM_ARGS)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 1000})
                errors, warnings, outside = [], [], []
                page.on("console", lambda m: errors.append(m.text) if m.type == "error" else
                        warnings.append(m.text) if m.type == "warning" else None)
                page.on("pageerror", lambda e: errors.append(str(e)))

                def only_local(route):  # the notebook must work with no network: record and refuse the rest
                    if route.request.url.startswith(lab.url + "/"):
                        route.continue_()
                    else:
                        outside.append(route.request.url)
                        route.abort()

                page.route("**/*", only_local)
                page.goto(f"{lab.url}/lab/tree/{quote('scène.ipynb')}?token={lab.token}")
                page.wait_for_function("""() => { const w = window.jupyterapp && window.jupyterapp.shell.currentWidget;
                    const k = w && w.sessionContext && w.sessionContext.session && w.sessionContext.session.kernel;
                    return k && k.status === 'idle'; }""", timeout=STARTUP_S * 1000)
                timings["notebook open"] = time.monotonic() - t0

                _run_cell(page, 0)
                status = _cell(page, 0).locator(".jp-OutputArea-output .axd-status")
                try:
                    status.wait_for(timeout=120_000)
                except Exception as exc:  # say what the cell printed (an import error, a traceback)
                    raise AssertionError(f"no widget in the output: {_cell(page, 0).inner_text()}\n"
                                         f"{lab.text_log()[-3000:]}") from exc
                page.wait_for_function("""() => /1,200 instances/.test(
                    document.querySelector('.jp-OutputArea-output .axd-status').innerText)""", timeout=120_000)
                timings["first frame"] = time.monotonic() - t0
                assert _cell(page, 0).locator(".jp-OutputArea-output .axd-stage canvas").count() == 1
                shot = _stage_image(page)
                assert shot.shape == render.shape == (SIZE[1], SIZE[0], 3)
                drawn = _mask(shot).mean()
                assert drawn > 0.02, f"the widget's canvas is (nearly) empty: {drawn:.4f} of it drawn"
                assert np.allclose(shot[0, 0], np.asarray(BACKGROUND) * 255, atol=1.5)  # render's background
                score = iou(shot, render)
                timings["IoU with render"] = score
                if score < 0.95:
                    from axialdeform.core.io.image import save_png

                    save_png(tmp_path / "widget.png", shot)
                    save_png(tmp_path / "render.png", render)
                assert score >= 0.95, f"IoU {score:.3f} (widget.png and render.png in {tmp_path})"

                _run_cell(page, 1)
                page.wait_for_function("""() => /^150 instances/.test(
                    document.querySelector('.jp-OutputArea-output .axd-status').innerText)""", timeout=120_000)
                _cell(page, 1).locator(".jp-OutputArea-output").wait_for(timeout=60_000)
                assert _cell(page, 1).locator(".jp-OutputArea-output").inner_text().strip() == "150"
                fewer = _stage_image(page)
                for _ in range(50):  # the next frame shows the new instances
                    if _mask(fewer).mean() < 0.5 * drawn:
                        break
                    page.wait_for_timeout(200)
                    fewer = _stage_image(page)
                assert 0 < _mask(fewer).mean() < 0.5 * drawn, (drawn, _mask(fewer).mean())

                _run_cell(page, 2)  # what the front end reported reached the kernel
                out = _cell(page, 2).locator(".jp-OutputArea-output")
                out.wait_for(timeout=60_000)
                assert out.inner_text().strip() == "{'ready': True, 'instances': 150}"

                _run_cell(page, 3)  # a second view: both draw the 150, from ONE copy of three.js
                second = _cell(page, 3).locator(".jp-OutputArea-output .axd-status")
                second.wait_for(timeout=120_000)
                page.wait_for_function("""() => [...document.querySelectorAll('.jp-OutputArea-output .axd-status')]
                    .map((s) => s.innerText).filter((t) => /^150 instances/.test(t)).length === 2""", timeout=120_000)
                # re-running the cell disposes the old view: its WebGL context is released at once
                page.evaluate("window.__oldCanvas = document.querySelectorAll('.jp-OutputArea-output canvas')[1]")
                assert page.evaluate("window.__oldCanvas.getContext('webgl2').isContextLost()") is False
                _run_cell(page, 3)
                page.wait_for_function("""() => window.__oldCanvas.getContext('webgl2').isContextLost()
                    && !document.body.contains(window.__oldCanvas)""", timeout=60_000)
                page.wait_for_function("""() => [...document.querySelectorAll('.jp-OutputArea-output .axd-status')]
                    .map((s) => s.innerText).filter((t) => /^150 instances/.test(t)).length === 2""", timeout=120_000)
                # keys on a focused picture are the picture's (W: wireframe), not JupyterLab's shortcuts
                cells = page.locator(".jp-Notebook .jp-Cell").count()
                toggle = _cell(page, 0).locator(".axd-toggle").element_handle()
                _cell(page, 0).locator(".axd-stage").click()
                assert page.evaluate("!!document.activeElement.closest('.axd-stage')")
                for keys in (("a", "b"), ("d", "d")):  # command mode: insert above and below; delete
                    for key in keys:
                        page.keyboard.press(key)
                    assert page.locator(".jp-Notebook .jp-Cell").count() == cells, f"JupyterLab took {keys}"
                page.keyboard.press("w")
                page.wait_for_function("(t) => t.getAttribute('aria-pressed') === 'true'", arg=toggle, timeout=30_000)
                assert not [w for w in warnings if "Multiple instances of Three.js" in w
                            or "Too many active WebGL contexts" in w], warnings
                assert errors == [], errors
                assert outside == [], f"requests beyond the local server: {outside}"
            finally:
                browser.close()
    finally:
        lab.close()
    print("JupyterLab widget timings (s from the server's start):",
          ", ".join(f"{k} {v:.3f}" if k.startswith("IoU") else f"{k} {v:.1f}" for k, v in timings.items()))
