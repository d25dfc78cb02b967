"""Parts and axes lists of thousands of names: answered in time proportional to their size (no scan of
every name for every name) and in ONE short line (a list of 10 000 names is summarized, not printed)."""

from __future__ import annotations

import subprocess
import sys

import pytest

import axialdeform as ad
from axialdeform.core.errors import AxialDeformError, brief_names

N = 10_000


@pytest.fixture(scope="module")
def many(tmp_path_factory):
    folder = tmp_path_factory.mktemp("many")
    path = folder / "many.obj"
    v = "".join(f"v {i} 0 0\nv {i} 1 0\nv {i} 0 1\n" for i in range(N))
    f = "".join(f"o p{i}\nf {3 * i + 1} {3 * i + 2} {3 * i + 3}\n" for i in range(N))
    path.write_text(v + f)
    return path


def one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 600, msg[:300]
    return msg


def test_brief_names_summarizes():
    assert brief_names(["a", "b"]) == "'a', 'b'"
    assert brief_names([f"n{i}" for i in range(N)]).endswith(f"... ({N} in all)")
    assert len(brief_names(["x" * 10_000] * 3)) < 200


def test_a_ten_thousand_part_obj_in_every_listing(many, tmp_path):
    mesh = ad.load_mesh(many)
    assert len(mesh.parts) == N
    assert len(mesh.with_parts([f"p{i}" for i in range(N)]).parts) == N
    with pytest.raises(AxialDeformError) as info:
        mesh.with_parts([f"q{i}" for i in range(15_000)])
    assert "(15000 in all)" in one_line(info) and f"({N} in all)" in one_line(info)
    with pytest.raises(AxialDeformError) as info:
        mesh.with_axes(axes="parts")
    one_line(info)
    spec = [{"part": f"p{i}", **({"parent": "p0"} if i else {})} for i in range(60)]
    with pytest.raises(AxialDeformError) as info:
        mesh.with_axes(axes=spec)
    assert f"({N - 60} in all) have no axis" in one_line(info)
    with pytest.raises(AxialDeformError) as info:
        mesh.part("nothing")
    one_line(info)
    # the command line: info lists the parts in one line, a scene's long parts list is one line too
    r = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(many)], capture_output=True, text=True, timeout=120)
    parts = next(x for x in r.stdout.splitlines() if x.startswith("parts:"))
    assert r.returncode == 0 and f"({N} in all)" in parts and len(parts) < 600
    scene = tmp_path / "s.toml"
    scene.write_text(f'[[layer]]\nname = "a"\nmesh = "{many.as_posix()}"\nparts = ['
                     + ", ".join(f'"q{i}"' for i in range(20_000)) + ']\n[layer.scatter]\ncount = 3\n'
                     f'surface = "{many.as_posix()}"\n')
    r = subprocess.run([sys.executable, "-m", "axialdeform", "info", str(scene)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and len(r.stderr) < 600, r.stderr[:300]
