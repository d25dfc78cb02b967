"""A built wheel, installed into a fresh virtual environment, still finds
its shaders and meshes (the package data list is checked against the tree)."""

import json
import os
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _ok(argv, cwd):
    """Run ``argv`` in ``cwd``; it must succeed (its stderr is the failure message)."""
    done = subprocess.run([str(a) for a in argv], capture_output=True, text=True, cwd=cwd)
    assert done.returncode == 0, done.stderr
    return done


@pytest.mark.slow
def test_wheel_carries_shaders_and_meshes_and_runs(tmp_path):
    dist = tmp_path / "dist"
    build = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist), str(ROOT)],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr[-2000:]
    (wheel,) = dist.glob("axialdeform-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    shaders = [p.name for p in (ROOT / "glsl").iterdir() if p.is_file() and p.suffix not in (".py", ".pyc")]
    meshes = [p.name for p in (ROOT / "axialdeform" / "meshes").iterdir() if p.suffix in (".obj", ".glb")]
    assert shaders and meshes
    missing = [f"axialdeform/glsl/{n}" for n in shaders if f"axialdeform/glsl/{n}" not in names]
    missing += [f"axialdeform/meshes/{n}" for n in meshes if f"axialdeform/meshes/{n}" not in names]
    web = [p.relative_to(ROOT).as_posix() for p in (ROOT / "axialdeform" / "web").rglob("*")
           if p.is_file() and p.suffix != ".pyc" and "__pycache__" not in p.parts]
    assert "axialdeform/web/vendor/three.module.min.js" in web and "axialdeform/web/vendor/LICENSE" in web
    missing += [n for n in web if n not in names]
    src = ROOT / "js" / "src"
    module = [p.relative_to(src).as_posix() for p in src.rglob("*") if p.suffix in (".js", ".ts")]
    assert "webgl/glsl.js" in module and "index.d.ts" in module and "core/mesh.js" in module and "webgpu/mesh.js" in module
    missing += [f"axialdeform/three/{n}" for n in module if f"axialdeform/three/{n}" not in names]
    assert not missing, f"the wheel lacks {missing}"

    # a fresh venv: only the wheel's axialdeform; the dependencies come from this
    # interpreter's site-packages through a plain path entry (its .pth files,
    # such as an editable install of axialdeform, are not processed)
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    py = env_dir / ("Scripts" if os.name == "nt" else "bin") / "python"
    site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    Path(site, "_deps.pth").write_text("\n".join(sorted(deps)) + "\n")
    inst = subprocess.run([str(py), "-m", "pip", "install", "--no-deps", "-q", str(wheel)], capture_output=True, text=True)
    assert inst.returncode == 0, inst.stderr[-2000:]

    work = tmp_path / "elsewhere"
    work.mkdir()
    check = _ok([str(py), "-c", (
        "import axialdeform as ad, sys; "
        "assert ad.__file__.startswith(sys.prefix), ad.__file__; "
        "print(ad.__file__); print(ad.__version__); "
        "m = ad.load_mesh('leaf'); print(m.vertex_count); "
        "c = ad.load_mesh('leafcard'); assert c.parts[0].material.texture is not None; "
        "print(len(ad.deformation_glsl()))"
    )], work)
    assert str(env_dir) in check.stdout and "0+unknown" not in check.stdout
    script = env_dir / "bin" / "axialdeform"
    _ok([str(script), "demo", "-n", "60", "--size", "96x64", "-o", "d.png"], work)
    assert (work / "d.png").stat().st_size > 1000
    # the web page from the wheel's own page code and vendored three.js
    _ok([str(script), "random", "stone", "-n", "20", "-o", "s.adp"], work)
    _ok([str(script), "web", "stone", "s.adp", "-o", "s.html"], work)
    html = (work / "s.html").read_text(encoding="utf-8")
    assert 'id="axd-three"' in html and (work / "s.html").stat().st_size > 800_000
    # the notebook widget from the wheel: its model carries the page code and the whole
    # vendored three.js (a notebook front end fetches nothing), read from the wheel's files
    wid = _ok([str(py), "-c", (
        "import sys, json; from axialdeform.widget import SceneWidget; import axialdeform as ad; "
        "m = ad.load_mesh('stone'); w = SceneWidget(m, ad.random_params(m, 5, seed=1)); "
        "import axialdeform.widget as aw; assert aw.__file__.startswith(sys.prefix), aw.__file__; "
        "print(json.dumps({k: len(v) for k, v in w._sources.items()})); "
        "assert 'export default' in w._esm and 'loadModules' in w._esm; "
        "assert all(s not in w._esm for s in ('http://', 'https://'))"
    )], work)
    sizes = json.loads(wid.stdout.strip().splitlines()[-1])
    assert set(sizes) == {"three", "orbit", "gltf", "bgu", "app", "module"} and sizes["three"] > 600_000, sizes
    # every file of the npm module's WebGL entry (js/src; the page and the widget draw with WebGLRenderer),
    # from the wheel's axialdeform/three: all but axialdeform-three/webgpu's own (webgpu.js, webgpu/)
    src = ROOT / "js" / "src"
    webgl = [p for p in src.rglob("*.js") if p.name != "webgpu.js" and p.parent.name != "webgpu"]
    assert sizes["module"] == len(webgl), sizes
