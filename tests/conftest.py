"""Shared fixtures.  GL tests get ONE EGL context per session; every test
that uses it is checked for ``ctx.error == "GL_NO_ERROR"`` afterwards.
A GL test never skips: no context is a failure (here and in CI)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad

ROOT = Path(__file__).resolve().parent.parent
#: third-party test meshes carried by the repository (sources and licences in tests/data/meshes)
DATA = ROOT / "tests" / "data" / "meshes"


#: the Khronos conformance model for alpha modes (9 textured parts)
ALPHA_TEST = "assets/AlphaBlendModeTest.glb"
#: the Khronos glTF validator (npm ci --prefix tests/gltf-validator)
VALIDATOR = ROOT / "tests" / "gltf-validator"


def validate_gltf(*paths) -> list:
    """The Khronos validator's JSON report of each file; no node or validator is a failure."""
    import json
    import shutil
    import subprocess

    node = shutil.which("node")
    if node is None or not (VALIDATOR / "node_modules" / "gltf-validator").exists():
        pytest.fail("node and the Khronos validator are needed (npm ci --prefix tests/gltf-validator)")
    out = subprocess.run([node, str(VALIDATOR / "validate.js"), *map(str, paths)], capture_output=True, text=True,
                         check=True, timeout=300).stdout
    reports = json.loads(out)
    return reports if isinstance(reports, list) else [reports]


@pytest.fixture(scope="session")
def validate():
    """``validate(*paths) -> [report, ...]``: the Khronos validator's JSON reports (validate_gltf)."""
    return validate_gltf


def assert_valid_gltf(report, allowed_infos=()) -> None:
    """A validator report with no error, no warning and no info outside ``allowed_infos``."""
    issues = report["issues"]
    messages = [(m["code"], m["severity"], m.get("pointer")) for m in issues["messages"]]
    assert issues["numErrors"] == 0, messages
    assert issues["numWarnings"] == 0, messages
    assert {code for code, _sev, _ptr in messages} <= set(allowed_infos), messages


def data_mesh(rel: str) -> Path:
    """A test mesh from ``tests/data/meshes`` (in the repository); a missing one is a failure, not a skip."""
    path = DATA / rel
    assert path.exists(), f"test data {path} is missing: tests/data/meshes/SOURCES.txt says where it comes from"
    return path


@pytest.fixture(scope="session")
def gl():
    ctx = ad.create_context()  # raises ContextError: the test fails, it does not skip
    yield ctx
    ctx.release()


@pytest.fixture
def ctx(gl):
    # a test that opened a window of its own (the viewer) leaves that window's
    # context current; GL calls go to the current context, so make ours current
    gl.__enter__()
    assert gl.error == "GL_NO_ERROR", "a previous test left a GL error behind"
    yield gl
    err = gl.error
    assert err == "GL_NO_ERROR", f"GL error after the test: {err}"


@pytest.fixture(scope="session")
def stone():
    return ad.load_mesh("stone")


@pytest.fixture(scope="session")
def leaf():
    return ad.load_mesh("leaf")


def make_mesh(positions, faces, name="<test>"):
    from axialdeform.core.mesh import area_weighted_normals

    positions = np.asarray(positions, dtype=np.float64)
    return ad.BaseMesh(positions, area_weighted_normals(positions, faces), faces, name=name)


#: Chromium's flags for the web tests: WebGL 2 on SwiftShader, headless, as root
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"]


#: and WebGPU on SwiftShader's Vulkan (tests/web/test_webgpu.py: three's WebGPURenderer)
WEBGPU_ARGS = CHROMIUM_ARGS + ["--enable-unsafe-webgpu", "--use-webgpu-adapter=swiftshader",
                               "--enable-features=Vulkan", "--use-vulkan=swiftshader"]


@pytest.fixture(scope="session")
def playwright_driver():
    """One Playwright (sync API) for the process: every browser below is launched from it."""
    from playwright.sync_api import sync_playwright  # a missing package is a failure

    with sync_playwright() as pw:
        yield pw


def _chromium() -> str:
    import shutil

    chromium = shutil.which("chromium")
    assert chromium, "Debian's chromium is required (apt-get install chromium); browser tests do not skip"
    return chromium


@pytest.fixture(scope="session")
def browser(playwright_driver):
    """Debian's chromium through Playwright, shared by the web tests.  No browser is a failure,
    never a skip (the README's test command installs it)."""
    b = playwright_driver.chromium.launch(executable_path=_chromium(), args=CHROMIUM_ARGS)
    yield b
    b.close()


@pytest.fixture(scope="session")
def webgpu_browser(playwright_driver):
    """The same chromium with a WebGPU adapter (SwiftShader's Vulkan): three's WebGPU backend."""
    b = playwright_driver.chromium.launch(executable_path=_chromium(), args=WEBGPU_ARGS)
    yield b
    b.close()
