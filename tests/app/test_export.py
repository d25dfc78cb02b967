"""glTF export (axialdeform.core.export), checked by the Khronos glTF validator.

The validator is the npm package ``gltf-validator`` pinned in
``tests/gltf-validator/package.json``; install it with
``npm ci --prefix tests/gltf-validator``.  A missing node or validator is a
failure, not a skip.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
import pytest
import trimesh

import axialdeform as ad
from axialdeform.cli import main
from axialdeform.core.io import gltf as export
from axialdeform.core.params import ANGLES

from conftest import assert_valid_gltf, data_mesh

VALIDATOR = Path(__file__).resolve().parents[1] / "gltf-validator"
INSTALL = "npm ci --prefix tests/gltf-validator"


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """Baked and instanced GLBs of the stone (axis x) and the leaf (axis y)."""
    folder = tmp_path_factory.mktemp("glb")
    out = {}
    for name in ("stone", "leaf"):
        mesh = ad.load_mesh(name)
        params = ad.random_params(mesh, 9, seed=5, variation=ad.Variation(bend=0.1))
        out[name] = (mesh, params,
                     export.export_baked(folder / f"{name}-baked.glb", mesh, params),
                     export.export_instanced(folder / f"{name}-instanced.glb", mesh, params))
    return out


def test_validator_reports_zero_errors(scenes, validate):
    files = [p for _m, _p, baked, inst in scenes.values() for p in (baked, inst)]
    reports = validate(*files)
    for path, report in zip(files, reports):
        assert report["uri"] == path.name
        if "instanced" in path.name:
            # the validator does not know EXT_mesh_gpu_instancing: it says so (info) and
            # sees the per-instance accessors as unused (info); no errors, no warnings
            assert_valid_gltf(report, {"UNSUPPORTED_EXTENSION", "UNUSED_OBJECT"})
        else:
            assert_valid_gltf(report)


def test_validator_catches_errors(validate):
    """The harness really fails bad files (Khronos' own invalid samples)."""
    (report,) = validate(data_mesh("gltf/validator/index_buffer_oob.gltf"))
    assert report["issues"]["numErrors"] > 0


def test_baked_loads_in_trimesh(scenes):
    for mesh, params, baked, _inst in scenes.values():
        scene = trimesh.load(str(baked), process=False)
        assert isinstance(scene, trimesh.Scene)
        assert len(scene.geometry) == len(params)
        expected, expected_normals = ad.bake(mesh, params)
        for k in range(len(params)):
            node = f"instance_{k:06d}"
            transform, geom = scene.graph[node]
            assert np.allclose(transform, np.eye(4))
            g = scene.geometry[geom]
            assert len(g.vertices) == mesh.vertex_count and len(g.faces) == len(mesh.faces)
            assert np.array_equal(np.asarray(g.vertices, dtype=np.float32), expected[k])
            assert np.array_equal(np.asarray(g.faces), mesh.faces.astype(np.int64))


def test_instanced_loads_in_trimesh(scenes):
    for mesh, _params, _baked, inst in scenes.values():
        scene = trimesh.load(str(inst), process=False)
        (g,) = scene.geometry.values()  # trimesh ignores the extension: the base mesh once
        assert len(g.vertices) == mesh.vertex_count
        assert np.array_equal(np.asarray(g.vertices, dtype=np.float32), mesh.positions)


def test_instanced_round_trip_is_exact(scenes):
    for mesh, params, _baked, inst in scenes.values():
        back_mesh, back = export.read_instanced_glb(inst)
        assert back.dtype == np.float32 and back.shape == params.shape
        assert back.view(np.uint32).tobytes() == params.view(np.uint32).tobytes()  # bit for bit
        assert np.array_equal(back_mesh.positions, mesh.positions)
        assert np.array_equal(back_mesh.normals, mesh.normals)
        assert np.array_equal(back_mesh.faces, mesh.faces)
        assert back_mesh.fingerprint == mesh.fingerprint
        assert back_mesh.axis.index == mesh.axis.index and back_mesh.axis.length == mesh.axis.length


def test_instanced_layout_follows_the_extension(scenes):
    mesh, params, _baked, inst = scenes["leaf"]
    gltf = pygltflib.GLTF2.load_binary(str(inst))
    assert export.INSTANCING in gltf.extensionsUsed
    (node,) = [n for n in gltf.nodes if n.extensions]
    attrs = node.extensions[export.INSTANCING]["attributes"]
    assert set(attrs) == {"TRANSLATION", "ROTATION", "_AXIAL_D12", "_AXIAL_D34", "_AXIAL_D5", "_AXIAL_ANGLES"}
    expected_type = {"TRANSLATION": "VEC3", "ROTATION": "VEC4", "_AXIAL_D12": "VEC4", "_AXIAL_D34": "VEC4",
                     "_AXIAL_D5": "VEC2", "_AXIAL_ANGLES": "VEC3"}
    for name, index in attrs.items():
        acc = gltf.accessors[index]
        assert name in ("TRANSLATION", "ROTATION") or name.startswith("_")
        assert acc.count == len(params) and acc.type == expected_type[name]
        assert acc.componentType == pygltflib.FLOAT
        assert gltf.bufferViews[acc.bufferView].target is None  # not a vertex attribute
    # ROTATION: unit quaternions (x, y, z, w) of R = Rz·Ry·Rx
    blob = gltf.binary_blob()
    acc = gltf.accessors[attrs["ROTATION"]]
    view = gltf.bufferViews[acc.bufferView]
    quats = np.frombuffer(blob, "<f4", acc.count * 4, (view.byteOffset or 0) + (acc.byteOffset or 0)).reshape(-1, 4)
    assert np.abs(np.linalg.norm(quats.astype(np.float64), axis=1) - 1).max() < 1e-6
    rot = export.matrices_from_quaternions(quats)
    assert np.abs(rot - ad.core.rotation_matrices(params[:, ANGLES])).max() < 1e-6
    extras = node.extras[export.EXTRAS_KEY]
    assert extras["axis"] == {"index": 1, "name": "y", "lo": mesh.axis.lo, "length": mesh.axis.length}
    assert extras["mesh_fingerprint"] == mesh.fingerprint.hex()
    assert extras["count"] == len(params) and extras["layout"] == "instanced"


def test_quaternions_match_rotation_matrices():
    rng = np.random.default_rng(2)
    angles = rng.uniform(-2 * np.pi, 2 * np.pi, size=(300, 3))
    angles[:3] = [(0, 0, 0), (0.3, np.pi / 2, -1.0), (np.pi, -np.pi / 2, np.pi)]
    q = export.quaternions_from_angles(angles)
    assert q.shape == (300, 4) and np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert (q[:, 3] >= 0).all()
    assert np.abs(export.matrices_from_quaternions(q) - ad.core.rotation_matrices(angles)).max() < 1e-12
    assert np.allclose(q[0], [0, 0, 0, 1])


def test_reader_falls_back_to_the_quaternion(scenes, tmp_path):
    """A file without _AXIAL_ANGLES still gives the same rotations (angles may differ)."""
    mesh, params, _baked, inst = scenes["stone"]
    gltf = pygltflib.GLTF2.load_binary(str(inst))
    (node,) = [n for n in gltf.nodes if n.extensions]
    del node.extensions[export.INSTANCING]["attributes"]["_AXIAL_ANGLES"]
    path = tmp_path / "no-angles.glb"
    path.write_bytes(b"".join(gltf.save_to_bytes()))
    _m, back = export.read_instanced_glb(path)
    assert np.array_equal(back[:, :13], params[:, :13])
    assert np.abs(ad.core.rotation_matrices(back[:, ANGLES]) - ad.core.rotation_matrices(params[:, ANGLES])).max() < 1e-6


def test_reader_refuses_other_files(scenes, tmp_path):
    _mesh, _params, baked, _inst = scenes["stone"]
    with pytest.raises(export.GltfError, match="EXT_mesh_gpu_instancing"):
        export.read_instanced_glb(baked)
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"not a glb at all")
    with pytest.raises(export.GltfError, match="not a binary glTF"):
        export.read_instanced_glb(junk)
    with pytest.raises(export.GltfError, match="missing.glb: no such binary glTF file"):
        export.read_instanced_glb(tmp_path / "missing.glb")


def test_gpu_baked_export_is_valid(ctx, stone, tmp_path, validate):
    params = ad.random_params(stone, 5, seed=8)
    positions, normals = ad.bake(stone, params, "gpu", ctx=ctx)
    path = export.export_baked(tmp_path / "gpu.glb", stone, params, positions=positions, normals=normals)
    (report,) = validate(path)
    assert_valid_gltf(report)
    scene = trimesh.load(str(path), process=False)
    assert sum(len(g.vertices) for g in scene.geometry.values()) == 5 * stone.vertex_count


def test_cli_export(tmp_path, validate, capsys):
    params_file = tmp_path / "p.adp"
    assert main(["random", "leaf", "-n", "4", "-o", str(params_file)]) == 0
    baked, inst = tmp_path / "b.glb", tmp_path / "i.glb"
    assert main(["export", "leaf", str(params_file), "-o", str(baked)]) == 0  # --baked is the default
    assert main(["export", "leaf", str(params_file), "-o", str(inst), "--instanced"]) == 0
    assert main(["export", "leaf", str(params_file), "-o", str(tmp_path / "b2.glb"), "--baked"]) == 0
    assert "4 instances, instanced" in capsys.readouterr().out
    reports = validate(baked, inst)
    assert_valid_gltf(reports[0])
    assert_valid_gltf(reports[1], {"UNSUPPORTED_EXTENSION", "UNUSED_OBJECT"})
    assert len(trimesh.load(str(baked)).geometry) == 4
    _m, back = export.read_instanced_glb(inst)
    assert np.array_equal(back, ad.read_params(params_file))


def test_cli_export_errors(tmp_path, capsys):
    params_file = tmp_path / "p.txt"
    assert main(["random", "stone", "-n", "2", "-o", str(params_file)]) == 0
    capsys.readouterr()
    assert main(["export", "stone", str(params_file), "-o", str(tmp_path / "x.gltf")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "expected a .glb" in err[0]
    assert main(["export", "leaf", str(tmp_path / "missing.adp"), "-o", str(tmp_path / "x.glb")]) == 2
    assert not (tmp_path / "x.glb").exists()
    with pytest.raises(export.GltfError, match="at least one instance"):
        export.export_baked(tmp_path / "none.glb", ad.load_mesh("stone"), np.zeros((0, 16), np.float32))
    with pytest.raises(SystemExit):
        main(["export", "stone", str(params_file), "-o", str(tmp_path / "y.glb"), "--baked", "--instanced"])


def test_extended_instances_export_scale_and_twist_taper(tmp_path, validate):
    from axialdeform.core.params import extend_params

    mesh = ad.load_mesh("leaf")
    params = extend_params(ad.random_params(mesh, 7, seed=2, variation=ad.Variation(bend=0.1)))
    params[:, 16] = np.linspace(0.5, 2.0, 7)
    params[:, 17] = np.linspace(-1.0, 1.5, 7)
    params[:, 18] = np.linspace(-0.3, 0.7, 7)
    inst = export.export_instanced(tmp_path / "ext-instanced.glb", mesh, params)
    baked = export.export_baked(tmp_path / "ext-baked.glb", mesh, params)
    r_inst, r_baked = validate(inst, baked)
    assert_valid_gltf(r_inst, {"UNSUPPORTED_EXTENSION", "UNUSED_OBJECT"})
    assert_valid_gltf(r_baked)
    gltf = pygltflib.GLTF2.load_binary(str(inst))
    attrs = gltf.nodes[0].extensions[export.INSTANCING]["attributes"]
    assert {"SCALE", "_AXIAL_TWIST_TAPER"} <= set(attrs)
    _m, back = export.read_instanced_glb(inst)
    assert back.shape == (7, 19)
    assert back.view(np.uint32).tobytes() == params.view(np.uint32).tobytes()  # bit for bit
    scene = trimesh.load(str(baked), process=False)
    expected, _n = ad.bake(mesh, params)
    g = scene.geometry[scene.graph["instance_000003"][1]]
    assert np.array_equal(np.asarray(g.vertices, dtype=np.float32), expected[3])
    # 16-number instances keep the old layout: no SCALE
    plain = export.export_instanced(tmp_path / "plain.glb", mesh, params[:, :16])
    assert "SCALE" not in pygltflib.GLTF2.load_binary(str(plain)).nodes[0].extensions[export.INSTANCING]["attributes"]


def test_instanced_glb_readers_use_the_bounded_reader(tmp_path):
    """read_instanced_glb and read_extras read through core.io.safeio: a FIFO is refused
    (never opened for a blocking read), a missing file is named, garbage is a GltfError."""
    import os

    fifo = tmp_path / "pipe.glb"
    os.mkfifo(fifo)
    for reader in (export.read_instanced_glb, export.read_extras):
        with pytest.raises(ad.core.GltfError, match="pipe.glb: not a regular file"):
            reader(fifo)
        with pytest.raises(ad.core.GltfError, match="gone.glb: no such binary glTF file"):
            reader(tmp_path / "gone.glb")
    (tmp_path / "junk.glb").write_bytes(b"glTF" + b"\0" * 40)
    with pytest.raises(ad.core.GltfError, match="junk.glb: not a binary glTF file"):
        export.read_extras(tmp_path / "junk.glb")


def test_the_streamed_glb_is_pygltflibs_byte_for_byte(tmp_path):
    """export_baked streams the GLB chunk after chunk (never joined in memory); the
    file is what pygltflib's own writer makes of the same glTF."""
    for name in ("stone", "leafcard"):
        mesh = ad.load_mesh(name)
        params = ad.random_params(mesh, 3, seed=1)
        b = export._build_baked(mesh, params)
        blob = b"".join(bytes(c) for c in b.chunks)
        b.gltf.buffers = [b.g.Buffer(byteLength=len(blob))]
        b.gltf.set_binary_blob(blob)
        reference = b"".join(b.gltf.save_to_bytes())
        path = export.export_baked(tmp_path / f"{name}.glb", mesh, params)
        assert path.read_bytes() == reference == export.encode_baked(mesh, params)


def test_a_mesh_without_a_material_exports_with_renders_look(tmp_path):
    """The bundled stone has no material: its GLB gets one (dielectric, render's stone grey), not
    glTF's default (white, metallic 1: black in three.js where nothing is reflected)."""
    from axialdeform.core.material import default_color

    stone = ad.load_mesh("stone")
    for layout in ("instanced", "baked"):
        path = export.export_glb(tmp_path / f"{layout}.glb", stone, ad.random_params(stone, 3, seed=1), layout)
        gltf = pygltflib.GLTF2().load(str(path))
        assert len(gltf.materials) == 1, layout
        pbr = gltf.materials[0].pbrMetallicRoughness
        assert pbr.metallicFactor == 0.0 and np.allclose(pbr.baseColorFactor[:3], default_color(stone), atol=1e-6)
        assert all(p.material == 0 for m in gltf.meshes for p in m.primitives)
