"""A model reads only its own folder: a texture or material
file named by an absolute path, a ``..`` escape or a link out of the folder is
not read -- one warning names the reference, the part keeps its base colour,
and nothing of the file reaches an export.  Data URIs still work."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.io.gltf import encode_base_mesh
from axialdeform.core.io.mesh import bundled_mesh_path


@pytest.fixture
def secret(tmp_path) -> Path:
    from PIL import Image

    img = np.zeros((8, 8, 4), np.uint8)  # red and blue halves: a real texture, not a flat colour
    img[:, :4, 0], img[:, 4:, 2], img[..., 3] = 255, 255, 255
    Image.fromarray(img, "RGBA").save(tmp_path / "secret.png")
    (tmp_path / "model").mkdir()
    return tmp_path / "secret.png"


def _card(folder: Path, texture: str) -> Path:
    (folder / "card.mtl").write_text(f"newmtl Leafy\nKd 1 1 1\nmap_Kd {texture}\n")
    obj = folder / "card.obj"
    obj.write_text("mtllib card.mtl\no card\nv 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                   "usemtl Leafy\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    return obj


def _load(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = ad.load_mesh(path)
    return mesh, [str(w.message) for w in caught if issubclass(w.category, ad.core.AssetWarning)]


@pytest.mark.parametrize("how", ["dotdot", "absolute", "link"])
def test_a_texture_outside_the_model_folder_is_not_read(secret, how):
    folder = secret.parent / "model"
    if how == "link":
        os.symlink(secret, folder / "tex.png")
    ref = {"dotdot": "../secret.png", "absolute": str(secret), "link": "tex.png"}[how]
    mesh, said = _load(_card(folder, ref))
    assert len(said) == 1 and repr(ref) in said[0] and "outside the model's folder" in said[0], said
    assert all(p.material.texture is None for p in mesh.parts)  # the base colour (Kd 1 1 1), nothing of the file
    assert np.allclose(mesh.parts[0].material.base_color, 1.0)
    assert secret.read_bytes()[-40:] not in encode_base_mesh(mesh)  # nothing of it in an export


def test_a_texture_inside_the_folder_and_a_data_uri_still_load(secret, tmp_path):
    import shutil

    folder = secret.parent / "model"
    shutil.copy(secret, folder / "own.png")
    (folder / "sub").mkdir()
    shutil.copy(secret, folder / "sub" / "deeper.png")
    for ref in ("own.png", "sub/deeper.png", "sub/../own.png"):
        mesh, said = _load(_card(folder, ref))
        assert said == [] and mesh.parts[0].material.texture is not None, (ref, said)
    import pygltflib

    g = pygltflib.GLTF2.load(str(bundled_mesh_path("leafcard")))
    g.convert_images(pygltflib.ImageFormat.DATAURI)
    g.convert_buffers(pygltflib.BufferFormat.DATAURI)
    g.save_json(str(tmp_path / "leaf.gltf"))
    mesh, said = _load(tmp_path / "leaf.gltf")
    assert said == [] and any(p.material.texture is not None for p in mesh.parts)
    for im in g.images:  # the same file pointing out of its folder
        im.uri, im.bufferView, im.mimeType = "../secret.png", None, None
    (tmp_path / "model" / "x").mkdir()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pygltflib's own note about the bufferView it keeps
        g.save_json(str(tmp_path / "model" / "x" / "leaf.gltf"))
    mesh, said = _load(tmp_path / "model" / "x" / "leaf.gltf")
    assert len(said) == 1 and "'../secret.png'" in said[0] and "outside the model's folder" in said[0]


def test_a_texture_over_the_pixel_budget_is_not_decoded(secret, monkeypatch):
    """The size is read from the image header; over the budget the texture is never
    decoded (a 9000 x 9000 PNG of 258 KB took 1.36 GB in every command before)."""
    folder = secret.parent / "model"
    import shutil

    shutil.copy(secret, folder / "own.png")  # 8 x 8 = 64 pixels
    monkeypatch.setenv("AXIALDEFORM_MAX_TEXTURE_PIXELS", "63")
    mesh, said = _load(_card(folder, "own.png"))
    assert len(said) == 1 and "card.obj: material 'Leafy': a texture of 8x8 pixels is over the budget of 63" in said[0]
    assert "AXIALDEFORM_MAX_TEXTURE_PIXELS" in said[0] and mesh.parts[0].material.texture is None
    monkeypatch.setenv("AXIALDEFORM_MAX_TEXTURE_PIXELS", "64")
    mesh, said = _load(_card(folder, "own.png"))
    assert said == [] and mesh.parts[0].material.texture is not None
