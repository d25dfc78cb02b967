"""Mesh input through trimesh: vertex order kept, file normals used, bad files refused."""

import numpy as np
import pytest
import trimesh

import axialdeform as ad

from conftest import data_mesh, make_mesh


def test_bundled_meshes():
    stone = ad.load_mesh("stone")
    leaf = ad.load_mesh("leaf")
    assert stone.vertex_count == 58 and stone.axis.name == "x"
    assert 20 <= leaf.vertex_count <= 200 and leaf.axis.name == "y"
    assert np.allclose(np.linalg.norm(stone.normals, axis=1), 1, atol=1e-6)
    # the stone is closed and its area-weighted normals point outwards
    assert np.einsum("ij,ij->i", stone.normals, stone.positions - stone.positions.mean(0)).min() > 0


def test_vertex_count_and_order_are_kept():
    path = data_mesh("base/rock_caustics.obj")
    raw = [list(map(float, line.split()[1:4])) for line in path.read_text().splitlines() if line.startswith("v ")]
    mesh = ad.load_mesh(path)
    # OBJ with per-corner normals may split vertices; trimesh keeps the first occurrences in order
    tm = trimesh.load(path, process=False)
    assert mesh.vertex_count == len(tm.vertices)
    assert np.allclose(mesh.positions, tm.vertices)
    assert mesh.normals_from_file
    assert np.allclose(mesh.positions[0], raw[0])


def test_file_normals_are_used(tmp_path, stone):
    tm = stone.to_trimesh(normals=np.tile([0.0, 0.0, 2.0], (stone.vertex_count, 1)))
    path = tmp_path / "n.ply"
    path.write_bytes(trimesh.exchange.ply.export_ply(tm, vertex_normal=True))
    mesh = ad.load_mesh(path)
    assert mesh.normals_from_file
    assert np.allclose(mesh.normals, [0, 0, 1])  # normalized


def test_area_weighted_normals():
    from axialdeform.core.mesh import area_weighted_normals

    # two triangles sharing vertex 0: a big one in z=0 (normal +z) and a small one in x=0 (normal +x)
    pos = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0], [0, 0, 0.0], [0, 1, 0], [0, 0, 1]], float)
    pos[3:] = [[0, 0, 0], [0, 1, 0], [0, 0, 1]]
    faces = np.array([[0, 1, 2], [0, 4, 5]])
    n = area_weighted_normals(pos, faces)
    expected = np.array([1 / 2, 0, 8]) / np.linalg.norm([1 / 2, 0, 8])  # areas 8 and 1/2
    assert np.allclose(n[0], expected, atol=1e-6)
    assert np.allclose(n[3], [0, 0, 1])  # unused vertex: the documented default


@pytest.mark.parametrize("rel,message", [
    ("edge_cases/empty.obj", "no triangle mesh"),
    ("edge_cases/empty.ply", "vertices and 0 faces|no triangle mesh"),
    ("edge_cases/points_ascii.ply", "without faces|0 faces"),
    ("gltf/empty_nodes.glb", "no triangle mesh"),
    ("gltf/validator/empty_file.glb", "not a binary glTF file: 0 bytes, shorter than the 20-byte header"),
])
def test_bad_meshes_are_refused_with_the_file_named(rel, message):
    path = data_mesh(rel)
    with pytest.raises(ad.core.MeshError, match=message) as err:
        ad.load_mesh(path)
    assert str(path) in str(err.value)


def test_nan_and_zero_extent_and_missing(tmp_path):
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ad.core.MeshError, match="vertex 1 has a non-finite coordinate"):
        ad.load_mesh(tmp_path / "nan.obj")
    (tmp_path / "point.obj").write_text("v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n")
    with pytest.raises(ad.core.MeshError, match="longest extent is 0"):
        ad.load_mesh(tmp_path / "point.obj")
    with pytest.raises(ad.core.MeshError, match="no such mesh file"):
        ad.load_mesh(tmp_path / "missing.obj")
    (tmp_path / "x.abc").write_text("hello")
    with pytest.raises(ad.core.MeshError, match="unsupported mesh file type"):
        ad.load_mesh(tmp_path / "x.abc")


@pytest.mark.parametrize("rel", ["gltf/monkey.glb", "edge_cases/whitespace.off", "classic/teapot_trimesh.stl",
                                 "edge_cases/plane.ply", "edge_cases/polygonfaces.obj", "edge_cases/wallhole.obj"])
def test_real_meshes_load(rel):
    mesh = ad.load_mesh(data_mesh(rel))
    assert np.isfinite(mesh.normals).all() and mesh.axis.length > 0
    assert len(mesh.fingerprint) == 32


@pytest.mark.parametrize("rel", ["base/rock_trimesh.obj", "base/rock_caustics.obj", "base/grass_blade_flora.obj",
                                 "edge_cases/cube.OBJ", "edge_cases/tet.ply", "edge_cases/mirror.ply",
                                 "edge_cases/wallhole.obj", "edge_cases/joined_tetrahedra.obj",
                                 "edge_cases/not_convex.obj", "edge_cases/plane.ply", "gltf/cubevc.glb",
                                 "gltf/monkey.glb", "classic/bunny_trimesh.ply"])
def test_is_volume_agrees_with_trimesh(rel):
    mesh = ad.load_mesh(data_mesh(rel))
    tm = trimesh.Trimesh(mesh.positions, mesh.faces, process=False)
    tm.merge_vertices(merge_tex=True, merge_norm=True)  # merge by position only, as is_volume does
    assert mesh.is_volume == bool(tm.is_volume)


def test_is_volume_needs_closed_consistent_outward_triangles(stone, leaf):
    assert stone.is_volume and not leaf.is_volume
    inside_out = make_mesh(stone.positions, stone.faces[:, ::-1])
    assert not inside_out.is_volume
    one_flipped = stone.faces.copy()
    one_flipped[0] = one_flipped[0, ::-1]
    assert not make_mesh(stone.positions, one_flipped).is_volume
    assert not make_mesh(stone.positions, stone.faces[1:]).is_volume  # a hole


@pytest.mark.parametrize("rows,cols", [(2, 2), (3, 5), (7, 2), (40, 33)])
def test_grid_edges_are_the_unique_edges_of_a_height_map(tmp_path, rows, cols):
    """A height map's edges come from its grid (no sort of 3 keys a triangle):
    the same edges, in the same order, as searching its triangles."""
    from PIL import Image

    from axialdeform.core.mesh import grid_edges, unique_edges
    from axialdeform.core.surface import load_surface

    heights = (np.random.default_rng(rows * cols).random((rows, cols)) * 255).astype(np.uint8)
    Image.fromarray(heights).save(tmp_path / "h.png")
    for up in ("y", "z"):
        surface = load_surface(tmp_path / "h.png", up=up)
        assert surface.grid == (rows, cols)
        assert np.array_equal(grid_edges(*surface.grid), unique_edges(surface.faces, len(surface.vertices)))


@pytest.mark.parametrize("rows, cols", [(2, 2), (3, 5), (65, 3), (130, 7), (200, 41)])
def test_grid_edges_in_pieces_are_the_whole(rows, cols):
    from axialdeform.core.mesh import grid_edge_count, grid_edge_pieces, grid_edges

    full = grid_edges(rows, cols)
    pieces = list(grid_edge_pieces(rows, cols, piece_rows=64))
    assert np.array_equal(np.concatenate([p for _, p in pieces]), full) and len(full) == grid_edge_count(rows, cols)
    assert [first for first, _ in pieces] == list(np.cumsum([0] + [len(p) for _, p in pieces])[:-1])
    assert max(len(p) for _, p in pieces) <= 64 * (3 * cols - 2)  # one piece at a time
