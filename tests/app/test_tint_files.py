"""Tinted instances through the command line and glTF: ``random --tint``
writes them, ``info`` says their version, ``render`` colours them, and both
glTF layouts carry the tint (instanced ``_COLOR_0``, which three.js reads
as ``instanceColor``; baked: materials whose base colour is multiplied)."""

from __future__ import annotations

import numpy as np
import pygltflib
import pytest

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.io.gltf import read_instanced_glb

from conftest import data_mesh, validate_gltf


def _cli(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_random_tint_info_render(tmp_path, capsys):
    adp = tmp_path / "t.adp"
    code, out, err = _cli(capsys, "random", "stone", "-n", 25, "--tint", 0.6, "--tint-color", "0.9,0.5,0.3", "-o", adp)
    assert code == 0, err
    params = ad.read_params(adp, ad.load_mesh("stone"))
    assert params.shape == (25, 22) and (params[:, 19:22] <= np.float32([0.9, 0.5, 0.3])).all()
    code, out, _ = _cli(capsys, "info", adp)
    assert code == 0 and "binary v3" in out and "tinted" in out
    png = tmp_path / "t.png"
    assert _cli(capsys, "render", "stone", adp, "-o", png, "--size", "160x120")[0] == 0
    for bad, words in ((["--tint", "1.5"], "--tint: expected a variation amount between 0 and 1"),
                       (["--tint-color", "1,1,1"], "--tint-color: only meaningful with --tint"),
                       (["--tint", "0.2", "--tint-color", "1,2"], "--tint-color: expected R,G,B")):
        code, _, err = _cli(capsys, "random", "stone", "-n", 3, *bad, "-o", tmp_path / "bad.adp")
        assert code == 2 and words in err and "Traceback" not in err
        assert not (tmp_path / "bad.adp").exists()


@pytest.mark.parametrize("rel", [None, "assets/AlphaBlendModeTest.glb"])
def test_both_gltf_layouts_carry_the_tint(tmp_path, rel):
    mesh = ad.load_mesh("stone" if rel is None else data_mesh(rel))
    params = ad.random_params(mesh, 6, seed=2, variation=ad.Variation(tint=0.7, tint_color=(0.8, 0.9, 1.0)))
    inst, baked = tmp_path / "i.glb", tmp_path / "b.glb"
    ad.core.export_instanced(inst, mesh, params)
    ad.core.export_baked(baked, mesh, params)
    back_mesh, back = read_instanced_glb(inst)
    assert back.shape == (6, 22) and np.array_equal(back, params)
    g = pygltflib.GLTF2().load(str(inst))
    node = next(n for n in g.nodes if n.extensions)
    assert "_COLOR_0" in node.extensions["EXT_mesh_gpu_instancing"]["attributes"]
    # baked: instance k's primitives use materials whose base colour is the part's times tint k
    g = pygltflib.GLTF2().load(str(baked))
    parts = [p for p in mesh.parts if p.count]
    for k in (0, 5):
        prims = g.meshes[k].primitives
        assert len(prims) == len(parts)
        for prim, part in zip(prims, parts):
            factor = np.array(g.materials[prim.material].pbrMetallicRoughness.baseColorFactor)
            # a part without a material: render's colour for the mesh (what the export writes, as render draws it)
            base = np.array(part.material.base_color) if not part.material.is_default else np.array(
                [*ad.core.material.default_color(mesh), 1.0])
            assert np.allclose(factor[:3], base[:3] * params[k, 19:22], atol=1e-6)
            assert np.isclose(factor[3], base[3])
    for report in validate_gltf(inst, baked):
        assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]


def test_scene_export_of_a_tinted_layer(tmp_path, capsys):
    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, 8, seed=3, variation=ad.Variation(tint=0.5))
    ad.write_params(tmp_path / "stones.adp", params, mesh)
    (tmp_path / "s.toml").write_text('[[layer]]\nmesh = "stone"\nparams = "stones.adp"\ncolor = [0.5, 0.5, 0.5]\n')
    for layout in ("--baked", "--instanced"):
        out = tmp_path / f"s{layout}.glb"
        code, _, err = _cli(capsys, "export", tmp_path / "s.toml", layout, "-o", out)
        assert code == 0, err
        assert validate_gltf(out)[0]["issues"]["numErrors"] == 0
    g = pygltflib.GLTF2().load(str(tmp_path / "s--baked.glb"))
    assert any(p.attributes.COLOR_0 is not None for m in g.meshes for p in m.primitives)
    g = pygltflib.GLTF2().load(str(tmp_path / "s--instanced.glb"))
    layer = next(n.name for n in g.nodes if n.extensions)
    _, back = read_instanced_glb(tmp_path / "s--instanced.glb", node=layer)
    assert np.array_equal(back, params)
