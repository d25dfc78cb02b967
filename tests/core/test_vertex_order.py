"""the file's own vertex order (BaseMesh.source_index) and
fits of variants written in it."""

from __future__ import annotations

import re

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core.fit import fit_files, fit_params

from conftest import data_mesh

# a quad strip along x with a UV seam in the middle: vertices 2 and 3 have two
# texture coordinates each, so trimesh splits them (6 `v` lines load as 8 vertices)
SEAM_OBJ = """\
v 0 0 0
v 0 1 0
v 1 0 0.1
v 1 1 0.1
v 2 0 0
v 2 1 0
vt 0 0
vt 0 1
vt 1 0
vt 1 1
vt 0 0
vt 0 1
vn 0 0 1
f 1/1/1 3/3/1 4/4/1
f 1/1/1 4/4/1 2/2/1
f 3/5/1 5/3/1 6/4/1
f 3/5/1 6/4/1 4/6/1
"""


def _v_lines(path):
    rows = re.findall(rb"^v\s+(\S+)\s+(\S+)\s+(\S+)", path.read_bytes(), re.M)
    return np.array(rows, dtype=np.float64)


def test_seam_split_obj_keeps_its_file_index(tmp_path):
    path = tmp_path / "seam.obj"
    path.write_text(SEAM_OBJ)
    mesh = ad.load_mesh(path)
    file_v = _v_lines(path)
    assert mesh.source_count == 6 and mesh.vertex_count == 8
    assert mesh.source_index.dtype == np.int64 and mesh.source_index.shape == (8,)
    assert np.allclose(file_v[mesh.source_index], mesh.positions)
    assert sorted(set(mesh.source_index.tolist())) == list(range(6))


def test_real_obj_with_seams_maps_every_vertex():
    path = data_mesh("base/rock_caustics.obj")
    mesh = ad.load_mesh(path)
    file_v = _v_lines(path)
    assert mesh.vertex_count != len(file_v)  # trimesh split it
    assert mesh.source_count == len(file_v)
    assert (mesh.source_index >= 0).all()
    assert np.abs(file_v[mesh.source_index] - mesh.positions).max() < 1e-5 * mesh.axis.length
    tet = ad.load_mesh(data_mesh("edge_cases/textured_tetrahedron.obj"))
    assert (tet.vertex_count, tet.source_count) == (6, 4)


def test_identity_where_nothing_was_split(stone):
    assert np.array_equal(stone.source_index, np.arange(stone.vertex_count))
    assert stone.source_count == stone.vertex_count


def test_fit_takes_variants_in_file_order_and_loaded_order(tmp_path):
    mesh = ad.load_mesh(data_mesh("base/rock_caustics.obj"))
    params = ad.random_params(mesh, 3, seed=6, variation=ad.Variation(bend=0.15))
    world, _ = ad.deform(mesh.axis, mesh.positions, mesh.normals, params)
    # the file's own order: scatter back through source_index (split copies agree)
    file_order = np.zeros((3, mesh.source_count, 3), dtype=np.float32)
    file_order[:, mesh.source_index] = world
    a = fit_params(mesh, world)
    b = fit_params(mesh, file_order)
    assert a.rms.max() < 1e-5 and b.rms.max() < 1e-5
    assert np.allclose(a.params, b.params, atol=1e-5)
    with pytest.raises(ad.core.TopologyError, match=f"or {mesh.source_count}"):
        fit_params(mesh, file_order[:, :-1])


def test_fit_files_written_by_a_tool_without_the_seams(tmp_path):
    base_path = tmp_path / "seam.obj"
    base_path.write_text(SEAM_OBJ)
    mesh = ad.load_mesh(base_path)
    params = ad.random_params(mesh, 2, seed=2, variation=ad.Variation(bend=0.1))
    world, _ = ad.deform(mesh.axis, mesh.positions, mesh.normals, params)
    paths = []
    for k in range(2):  # as a DCC tool writes it: the 6 file vertices, no UVs
        file_v = np.zeros((6, 3))
        file_v[mesh.source_index] = world[k]
        faces = "f 1 3 4\nf 1 4 2\nf 3 5 6\nf 3 6 4\n"
        text = "".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in file_v) + faces
        paths.append(tmp_path / f"variant_{k}.obj")
        paths[-1].write_text(text)
    result = fit_files(mesh, paths)
    assert result.max.max() < 1e-4
    assert np.allclose(ad.core.rotation_matrices(result.params[:, 13:16]), ad.core.rotation_matrices(params[:, 13:16]), atol=1e-4)
