"""Reading the variant meshes a fit takes: one file checked against the base mesh (same
vertices and triangles, or the same file triangles in another reader's order), or the mesh files
of one folder."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..errors import AxialDeformError, TopologyError
from .mesh import MESH_SUFFIXES, load_mesh

__all__ = ["load_variant", "variant_paths"]


def load_variant(path: str | os.PathLike, mesh) -> np.ndarray:
    """Vertex positions ``(v, 3) float64`` of a variant mesh file, checked against ``mesh``.

    Raises :class:`TopologyError` naming the file if its vertex count, triangle
    count or triangles differ from the base mesh's.
    """

    variant = load_mesh(path)
    name = str(path)
    if not (variant.vertex_count == mesh.vertex_count and np.array_equal(variant.faces, mesh.faces)):
        # the same file vertices and triangles, split or ordered differently by the reader
        # (an OBJ written with other UV seams, or none): compare and map in the file's own order
        same_file_triangles = (len(variant.faces) == len(mesh.faces) and variant.source_count == mesh.source_count
                               and not (variant.source_index < 0).any() and not (mesh.source_index < 0).any()
                               and np.array_equal(variant.source_index[variant.faces], mesh.source_index[mesh.faces]))
        if same_file_triangles:
            file_positions = np.zeros((variant.source_count, 3))
            file_positions[variant.source_index] = variant.positions
            return file_positions[mesh.source_index]
    if variant.vertex_count != mesh.vertex_count:
        raise TopologyError(f"{name}: has {variant.vertex_count} vertices, expected {mesh.vertex_count} "
                            f"(the base mesh {mesh.name}'s count, same order)")
    if len(variant.faces) != len(mesh.faces):
        raise TopologyError(f"{name}: has {len(variant.faces)} triangles, expected {len(mesh.faces)} "
                            f"(the base mesh {mesh.name}'s count)")
    if not np.array_equal(variant.faces, mesh.faces):
        k = int(np.argwhere((variant.faces != mesh.faces).any(axis=1))[0, 0])
        raise TopologyError(f"{name}: triangle {k} is {variant.faces[k].tolist()}, expected {mesh.faces[k].tolist()} "
                            f"as in the base mesh {mesh.name} (same vertices in the same order)")
    return variant.positions.astype(np.float64)


def variant_paths(inputs) -> list[Path]:
    """The variant files: the given files in order, or the mesh files of ONE folder sorted by name."""
    paths = [Path(p) for p in inputs]
    if not paths:
        raise AxialDeformError("variants: expected mesh files or one folder of mesh files, found none")
    folders = [p for p in paths if p.is_dir()]
    if folders:
        if len(paths) != 1:
            raise AxialDeformError(f"variants: a folder ({folders[0]}) must be the only VARIANTS argument; "
                                   f"found {len(paths)} arguments")
        found = sorted((p for p in paths[0].iterdir() if p.is_file() and p.suffix.lower() in MESH_SUFFIXES
                        and not p.name.startswith(".")), key=lambda p: p.name)
        if not found:
            raise AxialDeformError(f"{paths[0]}: no mesh files ({', '.join(MESH_SUFFIXES)}) in the folder")
        return found
    return paths
