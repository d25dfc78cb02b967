"""Writing baked instances: ``.npz`` arrays (in pieces, bounded by the disk)
and folders of mesh files (OBJ with materials, PLY per part, GLB)."""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from ..bake import MESH_FORMATS, instance_name, part_file_names
from ..errors import ArgumentError, PathError
from ..material import to_trimesh_with_appearance
from .atomic import atomic_path, atomic_write_bytes
from .gltf import encode_baked
from .safeio import check_not_special

__all__ = [
    "INSTANCE_FILE", "check_bake_folder", "write_mesh_folder", "write_plain_obj", "write_npz", "write_npz_layers",
    "write_npz_pieces", "write_scene_npz",
]


def write_npz(path: str | os.PathLike, positions: np.ndarray, normals: np.ndarray) -> None:
    """``positions`` and ``normals`` arrays into one ``.npz``, atomically.

    positions, normals : (instances, vertices, 3) float32.  No copy is made
    of float32 arrays (numpy writes each in 16 MB pieces)."""
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, positions=np.asarray(positions, dtype=np.float32),
                     normals=np.asarray(normals, dtype=np.float32))


def write_npz_pieces(path: str | os.PathLike, pieces, count: int, vertices: int) -> Path:
    """Arrays ``positions`` and ``normals``, each ``(count, vertices, 3)
    float32``, into one ``.npz`` (what :func:`write_npz` writes, as
    ``np.load`` reads it) from ``pieces`` of ``(positions, normals)``,
    atomically, memory bounded by one piece (:func:`write_npz_layers`)."""
    return write_npz_layers(path, [("", pieces, count, vertices)])


def write_npz_layers(path: str | os.PathLike, layers) -> Path:
    """Several baked layers into one ``.npz``, atomically, memory bounded by
    one piece: ``layers`` is a list of ``(suffix, pieces, count, vertices)``
    and each becomes arrays ``positions{suffix}`` and ``normals{suffix}``,
    ``(count, vertices, 3) float32``, from its ``pieces`` of ``(positions,
    normals)``.  Positions go straight into the archive, normals to an
    unnamed temporary file beside ``path`` (gone with the process, whatever
    happens) that is copied in after them.  Pieces that do not add up to
    ``count`` raise :class:`ArgumentError`, as does a non-finite piece its
    producer refuses; nothing is written then."""

    path = Path(path)
    with atomic_path(path, suffix=".npz") as tmp, open(tmp, "wb") as fh, \
            zipfile.ZipFile(fh, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for suffix, pieces, count, vertices in layers:
            shape = (int(count), int(vertices), 3)
            header = {"descr": "<f4", "fortran_order": False, "shape": shape}
            with tempfile.TemporaryFile(dir=path.parent if str(path.parent) else ".") as spool:
                done = 0
                with zf.open(f"positions{suffix}.npy", "w", force_zip64=True) as entry:
                    np.lib.format.write_array_header_2_0(entry, header)
                    for positions, normals in pieces:
                        if positions.shape[1:] != shape[1:] or normals.shape != positions.shape:
                            raise ArgumentError(f"{path}: a piece of shape {positions.shape} / {normals.shape}; "
                                                f"expected (m, {vertices}, 3) both")
                        done += len(positions)
                        if done > count:
                            break
                        entry.write(np.ascontiguousarray(positions, dtype="<f4").data)
                        spool.write(np.ascontiguousarray(normals, dtype="<f4").data)
                        del positions, normals  # one piece alive while the next is made
                if done != count:
                    raise ArgumentError(f"{path}: the pieces{' of ' + suffix.lstrip('_') if suffix else ''} hold "
                                        f"{'at least ' if done > count else ''}{done} instances; expected {count}")
                spool.seek(0)
                with zf.open(f"normals{suffix}.npy", "w", force_zip64=True) as entry:
                    np.lib.format.write_array_header_2_0(entry, header)
                    shutil.copyfileobj(spool, entry, 1 << 24)
    return path


def write_scene_npz(path: str | os.PathLike, layers: dict) -> None:
    """Several layers into one ``.npz``, atomically: ``{name: (positions, normals)}``
    becomes arrays ``positions_NAME`` and ``normals_NAME``, each (instances, vertices, 3) float32."""
    arrays = {}
    for name, (positions, normals) in layers.items():
        arrays[f"positions_{name}"] = np.asarray(positions, dtype=np.float32)
        arrays[f"normals_{name}"] = np.asarray(normals, dtype=np.float32)
    with atomic_path(path, suffix=".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)


#: the file names :func:`write_mesh_folder` writes, and recognises as its own
#: (``instance_NNNNNN.EXT``, or ``instance_NNNNNN_PART.ply`` for one part)
INSTANCE_FILE = re.compile(r"^instance_(\d{6,})(_[A-Za-z0-9_-]+)?\.(" + "|".join(MESH_FORMATS) + r")$")


def write_mesh_folder(folder: str | os.PathLike, mesh, baked, fmt: str = "obj", progress=None,
                      *, overwrite: bool = False, params=None, inputs=()) -> list[Path]:
    """One mesh file per instance (``instance_000000.obj`` …), each written atomically.

    ``baked`` is ``(positions, normals)``, each ``(instances, vertices, 3)``: what
    :func:`axialdeform.bake` returns.

    A mesh with appearance keeps it: ``obj`` writes ``vt``, one shared
    ``material.mtl`` and its textures beside the files; ``glb`` writes each
    instance as :func:`axialdeform.core.io.gltf.encode_baked` does (UVs,
    colours, the material with its texture embedded, and -- given ``params``
    (n, 16|19), the instances the arrays were baked from -- tangents bent by
    the Jacobian); ``ply`` of a mesh with several parts writes one file per
    part and instance, ``instance_000000_PART.ply`` (PLY has no parts or
    materials: a part per file is what Blender and trimesh open as separate
    objects), each with its own vertices, UVs or colours.

    ``folder`` must be new or empty (hidden files aside); a folder that holds
    anything else is refused, unless ``overwrite``: then every new file is
    written first (atomically), and only afterwards are the old instance files
    it recognises (``instance_NNNNNN.obj|ply|glb``) that were not just
    rewritten removed; other files are left alone.  So an interrupted
    overwrite leaves every old or new file whole, never a half-written one.
    ``inputs`` (the files the bake read) are never replaced or removed: a
    folder whose files the bake would replace or remove holds one of them is
    refused before anything is written.
    """
    positions, normals = baked
    if fmt not in MESH_FORMATS:
        raise ArgumentError(f"format: expected one of {', '.join(MESH_FORMATS)}, found {fmt!r}")
    folder = Path(folder)
    old = check_bake_folder(folder, overwrite, inputs)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    plain = not mesh.has_appearance
    shared_written = False
    per_part = fmt == "ply" and len(mesh.parts) > 1
    part_names = part_file_names(mesh.parts) if per_part else []
    if params is not None and len(params) != len(positions):
        raise ArgumentError(f"params: {len(params)} instances for {len(positions)} baked ones; expected one per instance")
    for i in range(len(positions)):  # one file per instance: file I/O, not maths
        path = folder / instance_name(i, len(positions), f".{fmt}")
        if per_part:
            scene = to_trimesh_with_appearance(mesh, positions[i], normals[i])
            for part, file_part in zip(mesh.parts, part_names):
                if part.name not in scene.geometry:
                    continue  # a part without triangles
                path = folder / instance_name(i, len(positions), ".ply", part=file_part)
                with atomic_path(path) as tmp:
                    scene.geometry[part.name].export(str(tmp), file_type="ply")
                written.append(path)
            if progress is not None:
                progress.update(1)
            continue
        if plain and fmt == "obj":  # the common case, written 3x faster than trimesh's OBJ writer
            with atomic_path(path) as tmp, open(tmp, "wb") as fh:
                write_plain_obj(fh, positions[i], normals[i], mesh.faces)
        elif plain:
            tm = mesh.to_trimesh(positions[i], normals[i])
            with atomic_path(path) as tmp:
                tm.export(str(tmp), file_type=fmt)
        elif fmt == "obj":
            # every instance shares one material.mtl and its textures beside the files
            from trimesh.exchange.obj import export_obj

            tm = to_trimesh_with_appearance(mesh, positions[i], normals[i])
            text, extra = export_obj(tm, include_normals=True, include_texture=True, return_texture=True,
                                     mtl_name="material.mtl")
            if not shared_written:
                for name, data in extra.items():
                    atomic_write_bytes(folder / name, data)
                    written.append(folder / name)
                shared_written = True
            atomic_write_bytes(path, text.encode("utf-8"))
        elif fmt == "glb":

            one = slice(i, i + 1)
            atomic_write_bytes(path, encode_baked(mesh, _identity_params(1) if params is None else params[one],
                                                  positions=positions[one], normals=normals[one],
                                                  tangents=params is not None))
        else:
            tm = to_trimesh_with_appearance(mesh, positions[i], normals[i])
            with atomic_path(path) as tmp:
                tm.export(str(tmp), file_type=fmt)
        written.append(path)
        if progress is not None:
            progress.update(1)
    if overwrite:
        keep = {p.name for p in written}
        for name in old:
            if name not in keep and INSTANCE_FILE.match(name):
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(folder / name)
    return written


#: rows formatted at a time by :func:`write_plain_obj` (its memory stays bounded)
_OBJ_ROWS = 1 << 16


def write_plain_obj(fh, positions, normals, faces) -> None:
    """One mesh as OBJ text into the binary file ``fh``: ``v`` and ``vn``
    lines (``%.9g``: every float32 exactly) and ``f a//a b//b c//c``, in
    pieces of :data:`_OBJ_ROWS` rows.  The same file trimesh writes for a
    mesh without appearance, but formatted by one C-level ``%`` per piece
    (a 1 M-face mesh: about 1 s instead of 3.4 s).

    positions, normals : (v, 3) float32; faces : (m, 3) int."""
    fh.write(b"# axialdeform: one baked instance (v, vn, f)\n")
    for tag, values in (("v", positions), ("vn", normals)):
        values = np.asarray(values, dtype=np.float32)
        for a in range(0, len(values), _OBJ_ROWS):
            piece = values[a : a + _OBJ_ROWS]
            fh.write(((f"{tag} %.9g %.9g %.9g\n" * len(piece)) % tuple(piece.ravel().tolist())).encode("ascii"))
    faces = np.asarray(faces, dtype=np.int64)
    for a in range(0, len(faces), _OBJ_ROWS):
        piece = np.repeat(faces[a : a + _OBJ_ROWS] + 1, 2, axis=1)
        fh.write((("f %d//%d %d//%d %d//%d\n" * len(piece)) % tuple(piece.ravel().tolist())).encode("ascii"))


def _identity_params(n: int) -> np.ndarray:
    """``n`` instances that change nothing (zero offsets, at the origin, unrotated)."""
    return np.zeros((n, 16), dtype=np.float32)


#: what a bake into a folder writes or removes besides instance files: the shared material and its textures
_BAKE_COMPANIONS = re.compile(r"^(material\.mtl|.*\.(png|jpe?g|bmp|tga|webp|tiff?))$", re.I)


def check_bake_folder(folder: str | os.PathLike, overwrite: bool = False, inputs=()) -> list[str]:
    """Check ``folder`` as the target of :func:`write_mesh_folder` before any
    work: it must be new, empty (hidden files aside), or — with
    ``overwrite`` — anything; never a file, a device or a FIFO; and none of
    the files an overwrite would replace or remove (``instance_*`` files, the
    material and its textures) may be one of ``inputs`` (by device and
    inode: a hard link or a symlink of an input counts).  Returns the names
    it holds now.  Changes nothing."""
    folder = Path(folder)
    check_not_special(folder, "output folder", allow_folder=True)
    if folder.exists() and not folder.is_dir():
        raise PathError(f"{folder}: exists and is not a folder; expected a folder for one mesh file per instance")
    old = _folder_entries(folder)
    if old and not overwrite:
        sample = ", ".join(sorted(old)[:3]) + (", ..." if len(old) > 3 else "")
        raise PathError(f"{folder}: holds {len(old)} files that exist ({sample}); refusing to write into it, expected a "
                        "new or empty folder (--overwrite replaces an earlier bake: it removes the old instance_* files)")
    touched = [folder / name for name in old if INSTANCE_FILE.match(name) or _BAKE_COMPANIONS.match(name)]
    for path in touched:
        for src in inputs:
            if src is not None and _same_file(path, src):
                raise PathError(f"{path}: is the input {src}; a bake into {folder} would replace or remove it "
                                "(--overwrite never touches an input: bake into another folder)")
    return old


def _same_file(a, b) -> bool:
    try:
        sa, sb = os.stat(a), os.stat(b)
    except OSError:
        return False
    return (sa.st_dev, sa.st_ino) == (sb.st_dev, sb.st_ino)


def _folder_entries(folder: Path) -> list[str]:
    """Names in ``folder`` other than hidden ones (atomic writes' ``.part`` files)."""
    try:
        with os.scandir(folder) as it:
            return [e.name for e in it if not e.name.startswith(".")]
    except FileNotFoundError:
        return []
    except OSError as exc:
        raise PathError(f"{folder}: cannot list: {exc.strerror}") from None
