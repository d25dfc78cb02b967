"""A chosen axis frame (docs/method.md, "A chosen axis frame"): the maths on
the CPU, no GL.  auto/x/y/z keep the index path bit for bit; a framed axis
bends the local coordinates F·V and goes back by Fᵀ."""

import numpy as np
import pytest

import axialdeform as ad
from axialdeform.core import ArgumentError, MeshError, MeshMismatchError
from axialdeform.core.axis import ControlAxis
from axialdeform.core.bounds import instance_boxes
from axialdeform.core.io.params import decode_binary, encode_binary

from conftest import make_mesh


def rotation(a=0.6, b=0.5, c=0.3) -> np.ndarray:
    """A generic rotation (no axis-aligned column)."""
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return rz @ ry @ rx


@pytest.fixture(scope="module")
def rod():
    """A long box 4 × 1 × 0.5 along x, subdivided along its length (it can bend)."""
    import trimesh

    box = trimesh.creation.box(extents=(4.0, 1.0, 0.5))
    for _ in range(3):
        box = box.subdivide()
    return ad.BaseMesh.from_arrays(box.vertices, box.faces, name="rod")


def turned(mesh, q):
    return ad.BaseMesh(mesh.positions.astype(np.float64) @ q.T, mesh.normals.astype(np.float64) @ q.T, mesh.faces,
                       name=f"{mesh.name} turned")


def params_for(mesh, n=7, seed=1, extended=False):
    p = ad.random_params(mesh, n, seed=seed, variation=ad.Variation(bend=0.2))
    p[:, 10:16] = 0.0  # at the origin, unturned: the bend alone
    if extended:
        rng = np.random.default_rng(seed)
        extra = np.stack([rng.uniform(0.5, 1.5, n), rng.uniform(-1, 1, n), rng.uniform(-0.5, 0.6, n)], axis=1)
        p = np.hstack([p, extra]).astype(np.float32)
    return p


@pytest.mark.parametrize("name", ["stone", "leaf"])
def test_auto_and_the_same_forced_axis_are_bit_identical(name):
    mesh = ad.load_mesh(name)
    forced = ad.load_mesh(name, axis="xyz"[mesh.axis.index])
    also = ad.load_mesh(name, axis=np.eye(3)[[mesh.axis.index, *mesh.axis.perpendicular]])  # its permutation matrix
    assert not forced.axis.framed and not also.axis.framed and forced.axis == mesh.axis == also.axis
    p = ad.random_params(mesh, 20, seed=3, variation=ad.Variation(bend=0.2))
    ref = ad.deform(mesh, p)
    for other in (forced, also):
        got = ad.deform(other, p)
        assert np.array_equal(got[0], ref[0]) and np.array_equal(got[1], ref[1])
    assert mesh.axis.frame_digest == bytes(16)


def test_forced_axis_differs_from_auto(stone):
    z = ad.load_mesh("stone", axis="z")
    assert stone.axis.index == 0 and z.axis.index == 2 and z.axis.lo == float(stone.positions[:, 2].min())
    p = ad.random_params(stone, 5, seed=1, variation=ad.Variation(bend=0.2))
    assert not np.allclose(ad.deform(z, p)[0], ad.deform(stone, p)[0])


def test_oriented_frame_finds_a_diagonal_rod(rod):
    q = rotation()
    diag = turned(rod, q)
    assert diag.axis.framed is False  # auto still picks a coordinate
    a = ad.load_mesh(diag, axis="oriented").axis
    assert a.framed and a.kind == "oriented"
    f = a.matrix
    np.testing.assert_allclose(f @ f.T, np.eye(3), atol=1e-12)
    # e_a along the rod's length, e_u along its 1.0 side, e_v along its 0.5 side (up to sign)
    for row, column in zip(f, q.T):
        assert abs(row @ column) > 1 - 1e-6
    # each row's largest-magnitude component is positive: the same frame every time
    assert (f[np.arange(3), np.abs(f).argmax(axis=1)] > 0).all()
    assert a.length == pytest.approx(4.0, rel=1e-6)
    assert ad.load_mesh(diag, axis="oriented").axis == a


@pytest.mark.parametrize("extended", [False, True])
def test_a_turned_mesh_with_its_turned_frame_bends_as_the_original(rod, extended):
    """Frame equivariance: the rod turned by Q, with the frame P·Qᵀ (P: its
    aligned axis's permutation), bends to exactly Q times the rod's own bend."""
    q = rotation()
    diag = turned(rod, q).with_axis(rod.axis.matrix @ q.T)
    assert diag.axis.framed
    p = params_for(rod, extended=extended)
    ref_pos, ref_nrm = ad.deform(rod, p)
    pos, nrm = ad.deform(diag, p)
    scale = rod.axis.length
    np.testing.assert_allclose(pos, ref_pos @ q.T, atol=2e-6 * scale)
    np.testing.assert_allclose(nrm, ref_nrm @ q.T, atol=2e-6)


def test_zero_offsets_give_the_mesh_exactly(rod):
    diag = ad.load_mesh(turned(rod, rotation()), axis="oriented")
    pos, nrm = ad.deform(diag, np.zeros((3, 16), np.float32))
    assert np.array_equal(pos[1], diag.positions)
    np.testing.assert_allclose(nrm[1], diag.normals, atol=1e-6)


def test_framed_normals_are_the_exact_ones(rod):
    """n'' = cof(J)·n is perpendicular to J·T for every tangent T ⟂ n
    (J·T by central differences of the map itself), extended instances included."""
    diag = ad.load_mesh(turned(rod, rotation()), axis="oriented")
    axis = diag.axis
    rng = np.random.default_rng(4)
    v = rng.uniform(diag.positions.min(0), diag.positions.max(0), (50, 3))
    n = rng.normal(size=(50, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    t1 = np.cross(n, rng.normal(size=(50, 3)))
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    p = params_for(rod, n=3, extended=True).astype(np.float64)
    _, bent = ad.deform(axis, v, n, p)
    h = 1e-4
    for t in (t1, t2):
        plus = ad.deform(axis, v + h * t, n, p)[0].astype(np.float64)
        minus = ad.deform(axis, v - h * t, n, p)[0].astype(np.float64)
        jt = (plus - minus) / (2 * h)
        cos = np.einsum("nvk,nvk->nv", bent, jt) / np.linalg.norm(jt, axis=-1)
        assert np.abs(cos).max() < 2e-3, np.abs(cos).max()


def test_bounds_hold_every_framed_vertex(rod):
    diag = ad.load_mesh(turned(rod, rotation()), axis="oriented")
    p = ad.random_params(diag, 40, seed=9, variation=ad.Variation(bend=0.3))
    lo, hi = instance_boxes(diag, p)
    pos = ad.deform(diag, p)[0]
    tol = 1e-5 * diag.axis.length
    assert (pos >= lo[:, None] - tol).all() and (pos <= hi[:, None] + tol).all()


def test_frames_that_are_not_frames_are_refused(rod):
    with pytest.raises(ArgumentError, match="not orthogonal"):
        rod.with_axis(np.diag([1.0, 1.0, 2.0]))
    with pytest.raises(ArgumentError, match="3×3"):
        rod.with_axis([[1, 0], [0, 1]])
    with pytest.raises(ArgumentError, match="expected one of auto, x, y, z, oriented"):
        rod.with_axis("diagonal")
    flat = make_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], name="flat")
    with pytest.raises(MeshError, match=r"flat: the mesh's extent along its axis \(z\) is 0"):
        flat.with_axis("z")


def test_files_record_the_frame_and_refuse_another(rod, tmp_path):
    diag = ad.load_mesh(turned(rod, rotation()), axis="oriented")
    p = ad.random_params(diag, 5, seed=2)
    data = encode_binary(p, axis=diag.axis, mesh_fingerprint=diag.fingerprint)
    assert data[24] == 3 and data[80:96] == diag.axis.frame_digest != bytes(16)
    pf = decode_binary(data)
    assert pf.axis.framed and pf.axis.matches(diag.axis)
    path = tmp_path / "p.adp"
    ad.write_params(path, p, diag)
    np.testing.assert_array_equal(ad.read_params(path, diag), p)
    other = diag.with_axis(rotation(0.1, 0.2, 0.3) @ diag.axis.matrix.T @ diag.axis.matrix)  # another frame
    for mesh in (diag.with_axis("auto"), other):
        with pytest.raises(MeshMismatchError, match="made for a chosen axis frame"):
            ad.read_params(path, mesh)
    # an aligned axis writes the bytes every earlier file has there: zeros
    aligned = encode_binary(p, axis=rod.axis, mesh_fingerprint=rod.fingerprint)
    assert aligned[24] == rod.axis.index and aligned[80:96] == bytes(16)


def test_a_corrupt_frame_record_is_a_param_file_error():
    import zlib

    from axialdeform.core import ParamFileError

    data = bytearray(encode_binary(np.zeros((1, 16), np.float32), axis=ControlAxis(0, 0.0, 1.0)))
    data[80] = 7  # a digest on an aligned axis
    data[-4:] = zlib.crc32(bytes(data[:-4])).to_bytes(4, "little")
    with pytest.raises(ParamFileError, match="frame digest: expected zeros for axis x"):
        decode_binary(bytes(data), "bad.adp")
    data[24] = 9
    data[-4:] = zlib.crc32(bytes(data[:-4])).to_bytes(4, "little")
    with pytest.raises(ParamFileError, match=r"bad.adp: axis: expected -1 \(not recorded\), 0, 1, 2"):
        decode_binary(bytes(data), "bad.adp")


def test_wind_pushes_across_a_framed_axis(rod):
    from axialdeform.core.wind import wind_offsets

    q = rotation()
    diag = turned(rod, q).with_axis(rod.axis.matrix @ q.T)
    wind = ad.Wind(direction=(1.0, 0.2, 0.5), strength=0.3)
    p = params_for(rod, n=4)
    # the wind in the turned model: the same push as the original under the turned wind direction
    ref = wind_offsets(ad.Wind(direction=tuple(q.T @ np.array(wind.unit_direction)), strength=0.3), rod.axis, p, 1.5)
    got = wind_offsets(wind, diag.axis, p, 1.5)
    # the phase uses the position (zero here) only: equal pushes
    np.testing.assert_allclose(got, ref, atol=1e-9)


@pytest.mark.parametrize("extended", [False, True])
def test_fit_recovers_the_shapes_of_a_framed_mesh(rod, extended):
    diag = ad.load_mesh(turned(rod, rotation()), axis="oriented")
    p = ad.random_params(diag, 6, seed=8, variation=ad.Variation(bend=0.15))
    if extended:
        p = np.hstack([p, np.tile(np.float32([1.1, 0.3, 0.2]), (6, 1))]).astype(np.float32)
    shapes = ad.deform(diag, p)[0]
    fit = ad.fit_params(diag, shapes, extended=extended)
    back = ad.deform(diag, fit.params)[0]
    assert np.abs(back - shapes).max() <= 1e-4 * diag.axis.length


def test_oriented_on_an_axis_aligned_model_is_its_aligned_axis():
    """The Khronos alpha test lies along x: its minimum-volume box is the
    aligned one, so 'oriented' is the index path."""
    from conftest import data_mesh

    mesh = ad.load_mesh(data_mesh("assets/AlphaBlendModeTest.glb"), axis="oriented", textures=False)
    assert not mesh.axis.framed and mesh.axis.index == 0


def test_a_frame_with_a_nan_names_the_entry():
    frame = np.eye(3)
    frame[2, 1] = np.nan
    with pytest.raises(ad.core.ArgumentError, match=r"stone: axis: row 3, column 2 of the frame is nan; expected a 3×3"):
        ad.load_mesh("stone", axis=frame)
