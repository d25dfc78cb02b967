"""The bench's plan and its cached files: what is measured, in which order,
and the parameter files and pre-deformed OBJ files every measurement reads.

Imported by the measurement child too, so it imports only the standard
library and numpy at the top.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

from ..core.bake import bake_cpu, instance_name
from ..core.camera import frame_instances
from ..core.errors import AxialDeformError
from ..core.io.bake import write_mesh_folder
from ..core.io.mesh import BUNDLED_MESHES, bundled_mesh_path
from ..core.io.params import write_params
from ..core.variation import Variation, random_params

METHODS = ("same", "loaded", "axial", "axial-quantized")
COUNTS = (100, 1000, 10000, 100000)
QUICK_COUNTS = (100, 1000)
BENCH_MODES = ("solid", "wireframe")
#: scene settings shared by the parent (files, camera) and the children
SCENE = {"bend": 0.12, "spacing_factor": 1.15, "placement": "grid"}
LEAF_SCENE = {"count": 1000, "placement": "box", "bend": 0.12}
#: frames each first-frame child also times (a cross-check only: ``frame_s`` comes from the interleaved process)
SEPARATE_FRAMES = 3


def scene_kwargs(mesh, scene: dict) -> dict:
    """``random_params`` keyword arguments of a scene setting."""
    kw = {"variation": Variation(bend=scene["bend"]), "placement": scene["placement"]}
    if "spacing_factor" in scene:
        kw["spacing"] = scene["spacing_factor"] * mesh.axis.length
    return kw


def obj_name(i: int, count: int = 0) -> str:
    """File name of instance ``i`` in a folder of pre-deformed OBJ files."""

    return instance_name(i, count, ".obj")


def repeats_for(method: str, count: int, repeats: int) -> int:
    """Fewer repeats where one run takes minutes: loading 10 000 or more files.
    The instanced methods repeat at every count (at 100 000 a single process
    per method cannot tell the method from the machine's load), alternating."""
    if count >= 100000 and method == "loaded":
        return 1
    if count >= 10000 and method == "loaded":
        return min(repeats, 2)
    return repeats


def first_frame_plan(counts, modes, methods, repeats: int) -> list[tuple[int, str, int, str]]:
    """``(count, mode, repeat, method)`` of every first-frame process, the
    methods interleaved (A B C D A B C D ...) so that drift hits all alike."""
    plan = []
    for c in counts:
        for mode in modes:
            for rep in range(max(repeats_for(m, c, repeats) for m in methods)):
                for m in methods:
                    if rep < repeats_for(m, c, repeats):
                        plan.append((c, mode, rep, m))
    return plan


def cache_root(cache) -> Path:
    """``cache``, or ``$XDG_CACHE_HOME/axialdeform/bench`` (``~/.cache/...``)."""
    if cache is not None:
        return Path(cache)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "axialdeform" / "bench"


def mesh_file(source) -> Path:
    """The file of a mesh argument (a path, or a bundled mesh's name)."""

    if isinstance(source, str) and source in BUNDLED_MESHES and not os.path.exists(source):
        return bundled_mesh_path(source)
    return Path(source).resolve()


def camera(mesh, params, size) -> tuple[list, list]:
    """``(view, projection)`` as nested lists: the fixed camera every child of a count gets."""

    cam = frame_instances(mesh, params, size[0] / size[1])
    return cam.view().astype(float).tolist(), cam.projection(size[0] / size[1]).astype(float).tolist()


class Scene:
    """The files of one (mesh, count) scene: parameter files, and on demand
    the folder of pre-deformed OBJ files (cached by mesh + parameters)."""

    def __init__(self, mesh, mesh_path: Path, count: int, seed: int, scene: dict, cache: Path):
        self.mesh, self.mesh_path, self.count, self.seed, self.scene = mesh, mesh_path, count, seed, scene
        self.params = random_params(mesh, count, seed, **scene_kwargs(mesh, scene))
        # the writer's identity is part of the key: files from another writer are never reused
        key = hashlib.sha256(b"bake.write_mesh_folder obj\0" + mesh_path.read_bytes() + self.params.tobytes()).hexdigest()[:20]
        self.dir = cache / f"{mesh_path.stem}-{count}-{key}"
        self.dir.mkdir(parents=True, exist_ok=True)
        self.adp = self.dir / "params.adp"
        self.adp_q = self.dir / "params-quantized.adp"
        for path, q in ((self.adp, False), (self.adp_q, True)):
            if not path.exists():
                write_params(path, self.params, mesh, quantize=q)
        self.folder = self.dir / "objs"
        self._loaded_bytes = None

    def params_file(self, method: str) -> Path:
        return self.adp_q if method == "axial-quantized" else self.adp

    def ensure_objs(self, progress=None) -> Path:
        """Write the N pre-deformed OBJ files once (atomically as a folder);
        ``progress`` is an optional ``f(files_written_since_last_call)``."""
        if self.folder.is_dir():
            return self.folder
        need = self.count * (self.mesh.vertex_count * 80 + len(self.mesh.faces) * 40) + (1 << 28)
        free = shutil.disk_usage(self.dir).free
        if free < need:
            raise AxialDeformError(
                f"bench cache {self.dir}: about {need >> 20} MiB needed for {self.count} OBJ files, "
                f"{free >> 20} MiB free; use --cache DIR on a larger disk or leave out this count"
            )

        tmp = self.dir / f"objs.tmp-{os.getpid()}"
        shutil.rmtree(tmp, ignore_errors=True)
        # the "load every one" data is exactly what `axialdeform bake MESH PARAMS -o DIR` writes
        positions, normals = bake_cpu(self.mesh, self.params)
        written = write_mesh_folder(tmp, self.mesh, (positions, normals), "obj",
                                    progress=None if progress is None else _Counter(progress))
        if written and written[0].name != obj_name(0):
            raise AxialDeformError(f"bench cache: expected files named like {obj_name(0)}, found {written[0].name}")
        os.replace(tmp, self.folder)  # the folder appears complete or not at all
        return self.folder

    def loaded_bytes(self) -> int:
        if self._loaded_bytes is None:
            self._loaded_bytes = sum(os.stat(self.folder / obj_name(i)).st_size for i in range(self.count))
        return self._loaded_bytes

    def file_bytes(self, method: str) -> int:
        """Bytes ``method`` reads from disk before its first frame."""
        mesh_bytes = self.mesh_path.stat().st_size
        if method == "same":
            return mesh_bytes
        if method == "loaded":
            return self.loaded_bytes()
        return mesh_bytes + self.params_file(method).stat().st_size


class _Counter:
    """Adapts a ``progress(n)`` callable to the ``update(n)`` interface."""

    def __init__(self, fn):
        self.update = fn
