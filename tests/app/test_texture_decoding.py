"""Textures are decoded only by commands that draw or write them: ``random``,
``scatter`` and ``fit`` load the mesh with ``textures=False`` -- the same
positions, parts and fingerprint, no pixels -- so a model's big texture costs
them no memory."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import axialdeform as ad

from conftest import data_mesh
from helpers.memory import peak_rss_mb


def test_textures_false_keeps_the_mesh_and_decodes_nothing():
    path = data_mesh("assets/AlphaBlendModeTest.glb")
    full = ad.load_mesh(path)
    bare = ad.load_mesh(path, textures=False)
    assert any(p.material.texture is not None for p in full.parts)
    assert all(p.material.texture is None and p.material.normal_texture is None for p in bare.parts)
    assert bare.fingerprint == full.fingerprint
    assert [p.name for p in bare.parts] == [p.name for p in full.parts]
    assert np.array_equal(bare.positions, full.positions) and np.array_equal(bare.faces, full.faces)
    for a, b in zip(bare.parts, full.parts):  # the factors, alpha modes and sides are the file's either way
        assert np.array_equal(a.material.base_color, b.material.base_color) or b.material.texture is not None
        assert (a.material.alpha_mode, a.material.double_sided) == (b.material.alpha_mode, b.material.double_sided)


def _big_textured_obj(folder, side: int = 6000):
    """A quad OBJ whose material names a ``side`` x ``side`` PNG (a gradient:
    a small file, ``4 side^2`` bytes decoded)."""
    img = Image.linear_gradient("L").resize((side, side)).convert("RGB")
    img.save(folder / "big.png", optimize=False, compress_level=1)
    (folder / "m.mtl").write_text("newmtl skin\nKd 1 1 1\nmap_Kd big.png\n")
    (folder / "quad.obj").write_text("mtllib m.mtl\nv 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl skin\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    (folder / "plain.obj").write_text("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    return folder / "quad.obj", folder / "plain.obj"


@pytest.mark.slow
def test_random_of_a_big_texture_costs_no_texture_memory(tmp_path):
    textured, plain = _big_textured_obj(tmp_path)
    decoded_mb = 6000 * 6000 * 4 / 2**20  # what decoding the texture as RGBA holds (137 MB)
    base = peak_rss_mb(["random", plain, "-n", "1000", "-o", tmp_path / "plain.adp"])
    peak = peak_rss_mb(["random", textured, "-n", "1000", "-o", tmp_path / "tex.adp"])
    assert peak - base < decoded_mb / 3, (base, peak)
    # a command that draws does decode it (the measurement can see the texture)
    drawn = peak_rss_mb(["render", textured, tmp_path / "tex.adp", "--size", "64x48", "-o", tmp_path / "t.png"])
    assert drawn - base > decoded_mb / 2, (base, drawn)
