"""glTF node graphs are walked once: a deep chain of nodes
loads (it took 55 s and ended in a RecursionError at 1 000 nodes), a cycle is
a MeshError naming the file, and the world transforms are trimesh's own."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import axialdeform as ad
from axialdeform.core.material import _geometry_nodes

from conftest import DATA

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
import fuzz_params  # noqa: E402 - tools/ is not a package


def _gltf(path: Path, nodes: list, scene_nodes: list) -> Path:
    """A one-triangle glTF with this node graph (the fuzzer's own builder)."""
    return Path(fuzz_params.gltf_with_nodes(path, nodes, scene_nodes))


def test_a_deep_chain_of_nodes_loads_with_its_transforms(tmp_path):
    n = 3000
    nodes = [{"children": [k + 1], "translation": [0.001, 0, 0]} for k in range(n - 1)] + [{"mesh": 0}]
    mesh = ad.load_mesh(_gltf(tmp_path / "chain.gltf", nodes, [0]))
    assert np.allclose(mesh.positions.min(axis=0), [0.001 * (n - 1), 0, 0], atol=1e-4)


def test_a_cycle_beside_the_scene_is_not_drawn(tmp_path):
    """Nodes no scene reaches are not drawn (glTF): a cycle among them changes nothing."""
    nodes = [{"mesh": 0}, {"children": [2]}, {"children": [1], "mesh": 0}]
    mesh = ad.load_mesh(_gltf(tmp_path / "beside.gltf", nodes, [0]))
    assert len(mesh.faces) == 1


def test_a_cycle_in_the_node_graph_is_our_error(tmp_path):
    nodes = [{"children": [1]}, {"children": [2], "mesh": 0}, {"children": [1]}]  # 0 -> 1 -> 2 -> 1
    path = _gltf(tmp_path / "cycle.gltf", nodes, [0])
    try:
        loaded = trimesh.load(str(path))
    except Exception:  # trimesh refusing it itself is fine too; then load_mesh says MeshError
        loaded = None
    with pytest.raises(ad.core.MeshError, match="cycle.gltf"):
        ad.load_mesh(path)
    assert loaded is None or isinstance(loaded, trimesh.Scene)


def test_world_transforms_are_trimeshs():
    """One walk gives what ``graph[node]`` gives, node by node, on the shared scenes."""
    checked = 0
    for path in sorted(DATA.rglob("*.gl*")):
        try:
            scene = trimesh.load(str(path))
        except Exception:  # noqa: BLE001 - files trimesh cannot read are not this test's
            continue
        if not isinstance(scene, trimesh.Scene):
            continue
        mine = {node: (m, g) for node, m, g, _ in _geometry_nodes(scene.graph, str(path))}
        for node in scene.graph.nodes_geometry:
            matrix, geometry = scene.graph[node]
            assert mine[node][1] == geometry and np.allclose(mine[node][0], matrix), (path, node)
        checked += 1
    assert checked >= 10, f"only {checked} glTF scenes read under {DATA}"


def test_part_names_and_fingerprint_are_the_same_on_every_load(tmp_path):
    """A glTF mesh of several primitives: trimesh names their frames with random
    hex digits; the parts are ``NODE_k`` (the primitive's index), load after load."""
    path = _gltf(tmp_path / "prims.gltf", [{"name": "Bottle", "mesh": 0}], [0])
    doc = json.loads(path.read_text())
    prim = doc["meshes"][0]["primitives"][0]
    doc["meshes"][0]["primitives"] = [prim, dict(prim), dict(prim)]
    doc["materials"] = [{"name": m} for m in ("Glass", "Cap", "Label")]
    for k, p in enumerate(doc["meshes"][0]["primitives"]):
        p["material"] = k
    path.write_text(json.dumps(doc))
    loads = [ad.load_mesh(path) for _ in range(4)]
    names = [[p.name for p in m.parts] for m in loads]
    assert names[0] == ["Bottle_0", "Bottle_1", "Bottle_2"] and all(n == names[0] for n in names), names
    assert len({m.fingerprint for m in loads}) == 1
    assert [p.material.name for p in loads[0].parts] == ["Glass", "Cap", "Label"]  # primitive order kept


def test_skins_morph_targets_and_animations_are_said_once(tmp_path):
    """They are drawn in the rest pose, with ONE warning naming what the file asks for."""
    import warnings

    path = _gltf(tmp_path / "rig.gltf", [{"mesh": 0, "skin": 0}, {"name": "joint"}], [0, 1])
    doc = json.loads(path.read_text())
    doc["skins"] = [{"joints": [1]}]
    doc["meshes"][0]["primitives"][0]["targets"] = [{"POSITION": 0}]
    doc["animations"] = [{"channels": [], "samplers": []}]
    path.write_text(json.dumps(doc))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            mesh = ad.load_mesh(path)
        except ad.core.MeshError:  # trimesh refusing the rig is fine; the point is our one warning first
            mesh = None
    said = [str(w.message) for w in caught if issubclass(w.category, ad.core.AssetWarning)]
    assert len(said) == 1 and "rig.gltf: 1 skin(s), morph targets on 1 primitive(s), 1 animation(s)" in said[0]
    assert "rest pose" in said[0]
    assert mesh is None or len(mesh.faces) == 1
    plain = ad.load_mesh(_gltf(tmp_path / "plain.gltf", [{"mesh": 0}], [0]))  # nothing to say
    assert len(plain.faces) == 1


def test_trimesh_failures_are_said_in_words():
    """A file trimesh cannot read is a MeshError in words, never Python's own text
    (116 of the validator suite's refusals showed ``UnboundLocalError: ...``)."""
    import re
    import warnings

    failures = 0
    for path in sorted((DATA / "gltf" / "validator").rglob("*.gl*")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                ad.load_mesh(path)
            except ad.core.MeshError as exc:
                failures += 1
                assert not re.search(r"\b[A-Z]\w*(Error|Exception)\b|Traceback", str(exc)), str(exc)
    assert failures >= 5, f"only {failures} of the validator's invalid files under {DATA} refused"
