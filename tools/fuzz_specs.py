"""Fuzzing of the glTF extension ``AXIALDEFORM_bend`` (both readers) and of tree specs.

    python3 tools/fuzz_specs.py --target extension --cases 400 --seed 31 [--node]
    python3 tools/fuzz_specs.py --target generated --cases 400 --seed 31 [--node]
    python3 tools/fuzz_specs.py --target trees --cases 400 --seed 31

``extension``: instanced GLBs written by ``export --instanced`` (16 numbers,
19 numbers, a ten-axis tree) with their ``AXIALDEFORM_bend``, their
``EXT_mesh_gpu_instancing`` attributes, the instance accessors or the
instance data corrupted (fields deleted, set to another type, to 0, -1,
2^33, 10^6, infinities, fractions; a tree's parents made cycles, self-,
forward or out-of-range parents; frames singular; accessor indices, counts,
types out of range; control offsets 1e30 or NaN).  Each file goes to
Python's ``read_instanced_glb`` (a forked child, memory capped) and, with
``--node``, to the npm module's ``AxialGLTFPlugin`` through three's
``GLTFLoader`` (``tools/fuzz_plugin.mjs``); Python's side checks, as
``render`` does, that every number can be drawn (``check_drawable``), since
the plugin loads a file to draw it.

``generated``: GLBs in the generated form (``export --generated`` of a field of stones and of trees of
ten axes) whose ``generate`` object -- the recipe, the generator's numbers, the maps' shapes -- is
corrupted, the recipe's sizes most often (rate, tile, reach: the files that froze the plugin or asked
for 10^15 slots).  Python reads the recipe (``read_generated_glb``) and makes the tiles within reach of
the origin; the plugin loads the file (its generated mesh sized by the recipe).  A checkout from before
``read_generated_glb`` reads the node's fallback, as it did.

``trees``: ``--axes`` TOML files (the bundled tree's, with entries deleted,
swapped, repeated, parents unknown or cyclic, frames degenerate or
non-finite, values of the wrong type), per-vertex axis indices and parents
given to ``tree_from_vertices``, and ``axis="oriented"`` on degenerate
meshes (a point, a line, a flat sheet, a tiny one), each in a forked child.

A case must end in a result that deforms to finite numbers (``ok``) or in
the library's own error naming the file or mesh (``refused``; in
JavaScript an ``AxialError``).  Anything else is a failure: another
exception (``crash``), numbers that are not finite (``garbage``), over 30 s
(``hang``) or over the memory cap (``memory``).  With ``--node`` a file the
two readers answer differently (one refuses, the other draws) counts as a
*disagreement*.  Prints one line of counts per target and examples of each
failure; exit status 1 if any.

To count *before* a change, run this file with ``PYTHONPATH`` pointing at an
older checkout (and ``--node-src`` at its ``js/src``): the bases are made
by that checkout's own ``export_glb`` unless ``--bases`` names a folder of
them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import struct
import subprocess
import sys
import tempfile
import time
import traceback
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TREE_AXES = ROOT / "examples" / "forest" / "tree-axes.toml"
MEMORY_CAP = 3 * 2**30
TIME_CAP_S = 30
INF = "__INF__"  # written as 1e999: both JSON parsers read it as infinity
HOSTILE = [0, -1, 1, 2.5, 2**33, 10**6, -(10**6), 1e30, INF, "-" + INF, "3", "", None, True, [], {}, [0], [[1, 0, 0]],
           [1, 2, 3, 4, 5, 6, 7, 8, 9], [-1, 0, 0], [-1, 1], [-1, 0, 5], [-1, -1], [0, 0], "nan"]


# ----------------------------------------------------------------------------- running one case
def forked(fn, *args) -> tuple[str, str]:
    """``fn(*args)`` in a forked child with :data:`MEMORY_CAP` bytes of address space and
    :data:`TIME_CAP_S` s: ``(verdict, detail)``; ``fn`` returns a verdict or raises."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        verdict = ("crash", "no verdict")
        try:
            resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))
            signal.alarm(TIME_CAP_S)
            verdict = fn(*args)
        except MemoryError:
            verdict = ("memory", f"over {MEMORY_CAP >> 30} GB of address space")
        except BaseException as exc:  # noqa: BLE001
            from axialdeform.core.errors import AxialDeformError

            if isinstance(exc, AxialDeformError):
                msg = str(exc)
                verdict = ("refused", msg) if "\n" not in msg else ("crash", "a message of several lines: " + msg)
            else:
                tb = traceback.extract_tb(exc.__traceback__)
                where = f"{Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else "?"
                verdict = ("crash", f"{type(exc).__name__} at {where}: {exc}"[:300])
        with os.fdopen(w, "w") as fh:
            json.dump(verdict, fh)
        os._exit(0)
    os.close(w)
    with os.fdopen(r) as fh:
        text = fh.read()
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        return ("hang", f"over {TIME_CAP_S} s") if sig == signal.SIGALRM else ("crash", f"killed by signal {sig}")
    try:
        return tuple(json.loads(text))
    except ValueError:
        return "crash", "no verdict"


def _finite_deform(mesh, params) -> tuple[str, str]:
    from axialdeform.core.deform import deform

    p = np.asarray(params)
    if not np.isfinite(p).all():
        return "garbage", "parameters that are not finite were accepted"
    pos, nor = deform(mesh, p[:16])
    if not (np.isfinite(pos).all() and np.isfinite(nor).all()):
        return "garbage", "the bent instances are not finite"
    return "ok", f"{len(p)} instances of {p.shape[1]} numbers"


# ----------------------------------------------------------------------------- the extension
def make_bases(folder: Path) -> list[Path]:
    """Instanced GLBs as ``export --instanced`` writes them: 16, 19 numbers, a ten-axis tree."""
    from axialdeform.core.io.gltf import export_glb
    from axialdeform.core.io.mesh import load_mesh
    from axialdeform.core.variation import Variation, random_params

    folder.mkdir(parents=True, exist_ok=True)
    stone, tree = load_mesh("stone"), load_mesh("tree", axes=str(TREE_AXES))
    out = []
    for name, mesh, params in (("stone16", stone, random_params(stone, 6, seed=1)),
                               ("stone19", stone, random_params(stone, 6, seed=2, variation=Variation(twist=0.3))),
                               ("tree", tree, random_params(tree, 4, seed=3))):
        path = folder / f"{name}.glb"
        if not path.exists():
            export_glb(path, mesh, params, "instanced")
        out.append(path)
    return out


def split_glb(data: bytes) -> tuple[dict, bytes]:
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + length])
    rest = data[20 + length:]
    blob = rest[8:8 + struct.unpack_from("<I", rest, 0)[0]] if len(rest) >= 8 else b""
    return doc, blob


def join_glb(doc: dict, blob: bytes) -> bytes:
    text = json.dumps(doc, separators=(",", ":")).replace(f'"-{INF}"', "-1e999").replace(f'"{INF}"', "1e999").encode()
    text += b" " * (-len(text) % 4)
    blob += b"\0" * (-len(blob) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def _paths(obj, prefix=()):
    """Every path into a JSON value (dict keys, list indices)."""
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(obj, list) and len(obj) <= 16:
        for i, v in enumerate(obj):
            yield from _paths(v, (*prefix, i))


def _set(obj, path, value, delete=False):
    for key in path[:-1]:
        obj = obj[key]
    if delete and isinstance(obj, dict):
        del obj[path[-1]]
    else:
        obj[path[-1]] = value


def _pick(rng, items):
    """One of ``items``, a copy (a list or table picked twice must not become one object)."""
    item = items[int(rng.integers(len(items)))]
    return json.loads(json.dumps(item)) if isinstance(item, (list, dict)) else item


def mutate_extension(doc: dict, blob: bytes, rng: np.random.Generator) -> tuple[dict, bytes, str]:
    """1 to 3 corruptions of the instanced node's extension, attributes, accessors or data."""
    node = next(n for n in doc["nodes"] if "AXIALDEFORM_bend" in n.get("extensions", {}))
    ext, attrs = node["extensions"]["AXIALDEFORM_bend"], node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]
    blob = bytearray(blob)
    said = []
    for _ in range(int(rng.integers(1, 4))):
        kind = int(rng.integers(8))
        if kind <= 2:  # any field of the extension
            path = _pick(rng, [p for p in _paths(ext) if p])
            if rng.random() < 0.2:
                _set(ext, path, None, delete=True)
                said.append(f"delete {'/'.join(map(str, path))}")
            else:
                value = _pick(rng, HOSTILE)
                _set(ext, path, value)
                said.append(f"{'/'.join(map(str, path))}={value!r:.30}")
        elif kind == 3 and "axes" in ext:  # a tree's parents: cycles, self, forward, out of range
            parents = ext["axes"].get("parents") if isinstance(ext["axes"], dict) else None
            parents = list(parents) if isinstance(parents, list) else []
            if parents:
                i = int(rng.integers(len(parents)))
                parents[i] = _pick(rng, [i, i + 1, len(parents) + 3, -2, (i + 1) % len(parents), 1.5])
                ext["axes"]["parents"] = parents
                said.append(f"parents[{i}]={parents[i]}")
        elif kind == 4:  # the numbers per instance or the axes count
            key = _pick(rng, ["numbersPerInstance", "axes"])
            if key == "axes" and isinstance(ext.get("axes"), dict):
                ext["axes"]["count"] = _pick(rng, [0, 1, 65, 10**6, -1, 2.5, "3"])
                said.append(f"axes/count={ext['axes']['count']!r}")
            else:
                ext["numbersPerInstance"] = _pick(rng, [16, 19, 22, 36, 106, 0, -1, 10**9])
                said.append(f"numbersPerInstance={ext['numbersPerInstance']}")
        elif kind == 5:  # an instance attribute's accessor index
            name = _pick(rng, sorted(attrs))
            if rng.random() < 0.2:
                del attrs[name]
                said.append(f"delete attribute {name}")
            else:
                attrs[name] = _pick(rng, [-1, len(doc["accessors"]), 10**9, "2", 0, 1.5])
                said.append(f"attribute {name}={attrs[name]!r}")
        elif kind == 6:  # an instance accessor's count, type, component type or view
            acc = doc["accessors"][_pick(rng, [a for a in attrs.values() if isinstance(a, int)
                                               and 0 <= a < len(doc["accessors"])] or [0])]
            field = _pick(rng, ["count", "type", "componentType", "bufferView", "byteOffset"])
            acc[field] = _pick(rng, {"count": [-2, 0, 2**33, 10**7, 1.5, 1], "type": ["SCALAR", "MAT4", "BAD", 3],
                                     "componentType": [5121, 5123, 5125, 0], "bufferView": [-1, 99, "0"],
                                     "byteOffset": [2**31, 3, -4]}[field])
            said.append(f"accessor {field}={acc[field]!r}")
        elif spans := _instance_spans(doc, attrs):  # huge or non-finite control offsets in the instance data
            value = _pick(rng, [np.float32(1e30), np.float32(np.nan), np.float32(np.inf), np.float32(-3e38)])
            for _k in range(int(rng.integers(1, 6))):
                start, stop = _pick(rng, spans)
                at = start + int(rng.integers(max(1, (stop - start) // 4))) * 4
                blob[at:at + 4] = value.tobytes()
            said.append(f"data {float(value):g}")
    return doc, bytes(blob), "; ".join(said)


def _instance_spans(doc: dict, attrs: dict) -> list:
    """Byte ranges of the float instance attributes' data (the bend's numbers, placement)."""
    spans = []
    for a in attrs.values():
        try:
            acc = doc["accessors"][a]
            view = doc["bufferViews"][acc["bufferView"]]
            start = int(view.get("byteOffset", 0)) + int(acc.get("byteOffset", 0))
            if acc.get("componentType") == 5126:
                spans.append((start, start + int(acc["count"]) * 4 * {"SCALAR": 1, "VEC2": 2, "VEC3": 3,
                                                                      "VEC4": 4}[acc["type"]]))
        except (KeyError, IndexError, TypeError, ValueError):
            continue
    return spans


def read_python(path: str) -> tuple[str, str]:
    """What ``render``/``web`` do with the file: read it, and check every number can be drawn
    (the plugin loads a file to draw it)."""
    from axialdeform.core.io.gltf import read_instanced_glb
    from axialdeform.core.params import check_drawable

    mesh, params = read_instanced_glb(path)
    check_drawable(params, path)
    return _finite_deform(mesh, params)


def read_node(files: list, src: Path) -> dict:
    """Every GLB through the plugin (``tools/fuzz_plugin.mjs``): ``{name: [verdict, detail]}``.
    A run that dies (out of memory, a signal) or stalls is a failure of the file it was on;
    the rest go on in a fresh run."""
    script = ROOT / "tools" / "fuzz_plugin.mjs"
    verdicts: dict = {}
    todo = [str(f) for f in files]
    while todo:
        proc = subprocess.Popen(["node", "--max-old-space-size=3072", str(script), str(src)], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
        try:
            out, err = proc.communicate("\n".join(todo) + "\n", timeout=TIME_CAP_S + 2 * len(todo))
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
            err = f"over {TIME_CAP_S + 2 * len(todo)} s: " + err
        current = None
        for line in out.splitlines():
            item = json.loads(line)
            if "start" in item:
                current = item["start"]
            else:
                verdicts[item["file"]] = [item["verdict"], item["detail"]]
                current = None
        if current is not None:  # the run ended inside this file
            tail = (err.strip().splitlines() or [f"exit {proc.returncode}"])[-1][:200]
            verdicts[current] = ["memory" if "heap" in err.lower() else "crash", f"node died: {tail}"]
        elif proc.returncode and not out:
            raise SystemExit(f"fuzz_plugin.mjs failed: {err[-2000:]}")
        todo = [f for f in todo if Path(f).name not in verdicts]
    return verdicts


def fuzz_extension(cases: int, seed: int, node: bool, node_src: Path, bases: Path | None, keep: Path | None) -> int:
    rng = np.random.default_rng(seed)
    work = Path(tempfile.mkdtemp(prefix="fuzz-ext-")) if keep is None else keep
    work.mkdir(parents=True, exist_ok=True)
    base_files = make_bases(bases or work / "bases")
    originals = [split_glb(p.read_bytes()) for p in base_files]
    files, about = [], {}
    for k in range(cases):
        b = int(rng.integers(len(originals)))
        doc, blob = json.loads(json.dumps(originals[b][0])), originals[b][1]
        doc, blob, said = mutate_extension(doc, blob, rng)
        path = work / f"case{k:05d}-{base_files[b].stem}.glb"
        path.write_bytes(join_glb(doc, blob))
        files.append(path)
        about[path.name] = said
    _preload()
    py = Counter()
    failures = []
    t0 = time.monotonic()
    python = {}
    for path in files:
        verdict, detail = forked(read_python, str(path))
        if verdict == "refused" and path.name not in detail:
            verdict, detail = "crash", "a refusal that does not name the file: " + detail
        python[path.name] = (verdict, detail)
        py[verdict] += 1
        if verdict not in ("ok", "refused"):
            failures.append(("python", verdict, path.name, about[path.name], detail))
    print(f"fuzz extension, Python read_instanced_glb: {cases} files (seed {seed}) in {time.monotonic() - t0:.0f} s: "
          + ", ".join(f"{v} {py[v]}" for v in ("ok", "refused", "crash", "garbage", "hang", "memory")))
    status = 1 if failures else 0
    if node:
        t0 = time.monotonic()
        js = read_node(files, node_src)
        counts = Counter(v for v, _ in js.values())
        missing = [p.name for p in files if p.name not in js]
        for name in missing:
            js[name] = ["hang", "no verdict (the run ended before this file)"]
            counts["hang"] += 1
        for name, (verdict, detail) in js.items():
            if verdict not in ("ok", "refused"):
                failures.append(("node", verdict, name, about.get(name, ""), detail))
        agree = Counter()
        for path in files:
            a, b = python[path.name][0], js[path.name][0]
            agree["same" if (a == "ok") == (b == "ok") else f"python {a}, node {b}"] += 1
        differ = sum(v for k, v in agree.items() if k != "same")
        for path in files:
            a, b = python[path.name][0], js[path.name][0]
            if (a == "ok") != (b == "ok") and a in ("ok", "refused") and b in ("ok", "refused"):
                failures.append(("disagree", f"python {a}, node {b}", path.name, about[path.name],
                                 python[path.name][1] if a == "refused" else js[path.name][1]))
        print(f"fuzz extension, npm AxialGLTFPlugin: {len(files)} files in {time.monotonic() - t0:.0f} s: "
              + ", ".join(f"{v} {counts[v]}" for v in ("ok", "refused", "crash", "garbage", "hang", "memory"))
              + f"; the two readers differ on {differ}")
        status |= 1 if failures else 0
    _report(failures)
    return status


# ----------------------------------------------------------------------------- the generated form
GENERATED_SCENES = {
    "stones": """[[layer]]
name = "stones"
mesh = "stone"
[layer.generate]
rate = 1.0
tile = 8.0
min_distance = 0.3
seed = 4
scale = [0.5, 1.0]
scale_quartiles = [0.6, 0.7, 0.85]
scale_octiles = [0.55, 0.65, 0.8, 0.95]
tint = 0.3
lift = [0.0, 0.1]
extent = [-8, -8, 8, 8]
reach = 24.0
""",
    "trees": f"""[[layer]]
name = "trees"
mesh = "tree"
axes = "{TREE_AXES.as_posix()}"
[layer.generate]
rate = 0.05
tile = 16.0
min_distance = 2.0
bend = [0.03, 0.25]
extent = [-16, -16, 16, 16]
reach = 40.0
""",
}
#: what a hostile generated form asks for: the sizes that froze or exhausted the plugin before, and types
GENERATED_HOSTILE = [0, -1, 1e-6, 1e-3, 0.5, 1e5, 2000, 400, 1e9, 1e12, 1e30, 1e308, INF, "-" + INF, "abc", None,
                     True, [], [-5, 0], [3e38, 3.4e38], [0, 7], 2**33, 4000, 100000, 4.0, 16.0, 26.0, 1.0]


def make_generated_bases(folder: Path) -> list[Path]:
    """GLBs in the generated form as ``export --generated`` writes them: stones (scaled, tinted, lifted), a
    tree of ten axes."""
    from axialdeform.core.io.gltf import export_scene
    from axialdeform.core.scene import load_scene

    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, text in GENERATED_SCENES.items():
        path = folder / f"gen-{name}.glb"
        if not path.exists():
            (folder / f"{name}.toml").write_text(text)
            export_scene(path, load_scene(folder / f"{name}.toml"), layout="generated")
        out.append(path)
    return out


def mutate_generated(doc: dict, rng: np.random.Generator) -> tuple[dict, str]:
    """1 to 3 corruptions of the node's ``generate`` object (its recipe, the generator's numbers, the maps'
    shapes), or of the recipe's sizes alone (rate, tile, reach: the unbounded-work cases)."""
    node = next(n for n in doc["nodes"] if "AXIALDEFORM_bend" in n.get("extensions", {}))
    gen = node["extensions"]["AXIALDEFORM_bend"]["generate"]
    said = []
    for _ in range(int(rng.integers(1, 4))):
        if rng.random() < 0.4:  # a size of the recipe
            path = ("recipe", _pick(rng, ["rate", "tile", "reach", "min_distance", "bend", "scale", "scale_quartiles",
                                          "scale_octiles"]))
        else:
            path = _pick(rng, [p for p in _paths(gen) if p])
        if rng.random() < 0.15 and len(path) > 1:
            try:
                _set(gen, path, None, delete=True)
            except (KeyError, IndexError, TypeError):
                continue
            said.append(f"delete {'/'.join(map(str, path))}")
        else:
            value = _pick(rng, GENERATED_HOSTILE)
            try:
                _set(gen, path, value)
            except (KeyError, IndexError, TypeError):
                continue
            said.append(f"{'/'.join(map(str, path))}={value!r:.30}")
    return doc, "; ".join(said)


def read_generated(path: str) -> tuple[str, str]:
    """What a viewer does with a generated node: read its recipe and make the tiles within its reach of the
    origin (the Python library: ``read_generated_glb``, then ``generate_tiles``); a checkout without it reads
    the node as ``read_instanced_glb`` did (its fallback)."""
    from axialdeform.core.params import check_drawable

    try:
        from axialdeform.core.io.gltf_generate import read_generated_glb
    except ImportError:  # before: the node read as its fallback instances
        from axialdeform.core.io.gltf import read_instanced_glb

        mesh, params = read_instanced_glb(path)
        check_drawable(params, path)
        return _finite_deform(mesh, params)
    from axialdeform.core.generate import generate_tiles, tiles_around

    node = read_generated_glb(path)
    params = generate_tiles(node.generate, node.mesh, tiles_around(node.generate, 0.0, 0.0, node.reach), node.maps)
    check_drawable(params, path)
    return _finite_deform(node.mesh, params) if len(params) else ("ok", "no instance within reach")


def fuzz_generated(cases: int, seed: int, node: bool, node_src: Path, keep: Path | None) -> int:
    rng = np.random.default_rng(seed)
    work = Path(tempfile.mkdtemp(prefix="fuzz-gen-")) if keep is None else keep
    work.mkdir(parents=True, exist_ok=True)
    bases = make_generated_bases(work / "bases")
    originals = [split_glb(p.read_bytes()) for p in bases]
    files, about = [], {}
    for k in range(cases):
        b = int(rng.integers(len(originals)))
        doc, said = mutate_generated(json.loads(json.dumps(originals[b][0])), rng)
        path = work / f"gen{k:05d}-{bases[b].stem}.glb"
        path.write_bytes(join_glb(doc, originals[b][1]))
        files.append(path)
        about[path.name] = said
    _preload()
    counts, failures, python = Counter(), [], {}
    t0 = time.monotonic()
    for path in files:
        verdict, detail = forked(read_generated, str(path))
        python[path.name] = (verdict, detail)
        counts[verdict] += 1
        if verdict not in ("ok", "refused"):
            failures.append(("python", verdict, path.name, about[path.name], detail))
    print(f"fuzz generated form, Python: {cases} files (seed {seed}) in {time.monotonic() - t0:.0f} s: "
          + ", ".join(f"{v} {counts[v]}" for v in ("ok", "refused", "crash", "garbage", "hang", "memory")))
    if node:
        t0 = time.monotonic()
        js = read_node(files, node_src)
        jc = Counter(v for v, _ in js.values())
        differ = 0
        for path in files:
            a, (b, detail) = python[path.name][0], js.get(path.name, ["hang", "no verdict"])
            if b not in ("ok", "refused"):
                failures.append(("node", b, path.name, about[path.name], detail))
            if (a == "ok") != (b == "ok"):
                differ += 1
                failures.append(("disagree", f"python {a}, node {b}", path.name, about[path.name],
                                 python[path.name][1] if a != "ok" else detail))
        print(f"fuzz generated form, npm AxialGLTFPlugin: {len(files)} files in {time.monotonic() - t0:.0f} s: "
              + ", ".join(f"{v} {jc[v]}" for v in ("ok", "refused", "crash", "garbage", "hang", "memory"))
              + f"; the two readers differ on {differ}")
    _report(failures)
    return 1 if failures else 0


# ----------------------------------------------------------------------------- trees
def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return "inf" if v == float("inf") else "nan" if v != v else repr(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(x)}" for k, x in v.items()) + "}"
    return str(v)


def axes_toml(entries: list) -> str:
    return "".join("[[axis]]\n" + "".join(f"{json.dumps(k)} = {_toml_value(v)}\n" for k, v in e.items()) + "\n"
                   for e in entries)


TREE_HOSTILE = ["trunk", "nope", "", 3, -1, 2.5, True, [1, 0, 0], [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
                [[1, 0, 0], [1, 0, 0], [0, 0, 1]], [1, 0, 0, 0, 1, 0, 0, 0, float("nan")], [0] * 9, "oriented",
                "x", "auto", float("inf"), {"a": 1}, "parts"]


def mutate_axes(entries: list, rng) -> tuple[list, str]:
    entries = [dict(e) for e in entries]
    said = []
    for _ in range(int(rng.integers(1, 4))):
        op = int(rng.integers(6))
        i = int(rng.integers(len(entries))) if entries else 0
        if op == 0 and entries:
            del entries[i]
            said.append(f"delete entry {i}")
        elif op == 1 and len(entries) > 1:
            j = int(rng.integers(len(entries)))
            entries[i], entries[j] = entries[j], entries[i]
            said.append(f"swap {i} {j}")
        elif op == 2 and entries:
            entries.insert(int(rng.integers(len(entries) + 1)), dict(entries[i]))
            said.append(f"repeat {i}")
        elif op == 3 and entries:  # a parent: itself, a later one, unknown: a cycle or a forward parent
            entries[i]["parent"] = _pick(rng, [entries[i]["part"], entries[-1]["part"], "nope", entries[0]["part"]])
            said.append(f"entry {i} parent={entries[i]['parent']}")
        elif op == 4 and entries:
            key = _pick(rng, ["part", "parent", "axis", "extra"])
            entries[i][key] = _pick(rng, TREE_HOSTILE)
            said.append(f"entry {i} {key}={entries[i][key]!r:.30}")
        else:
            entries = entries * int(rng.integers(2, 12))
            said.append(f"x{len(entries)} entries")
    return entries, "; ".join(said)


def tree_case(kind: str, payload) -> tuple[str, str]:
    from axialdeform.core.io.mesh import load_mesh
    from axialdeform.core.mesh import BaseMesh, area_weighted_normals
    from axialdeform.core.variation import random_params

    if kind == "toml":
        mesh = load_mesh("tree", axes=payload)
    elif kind == "vertices":
        vertex_axis, parents = payload
        mesh = load_mesh("stone").with_axes({"vertex_axis": np.asarray(vertex_axis), "parents": parents})
    else:
        positions, faces = (np.asarray(a) for a in payload)
        normals = area_weighted_normals(positions.astype(np.float32), faces.astype(np.uint32))
        mesh = BaseMesh(positions.astype(np.float32), normals, faces.astype(np.uint32)).with_axis("oriented")
    return _finite_deform(mesh, random_params(mesh, 3, seed=1))


def degenerate_mesh(rng) -> tuple[list, list, str]:
    kind = _pick(rng, ["point", "line", "flat", "tiny", "huge", "two"])
    n = int(rng.integers(3, 40))
    if kind == "point":
        pos = np.zeros((n, 3))
    elif kind == "line":
        pos = np.outer(rng.random(n), rng.normal(size=3))
    elif kind == "flat":
        pos = np.c_[rng.random((n, 2)), np.zeros(n)] @ np.linalg.qr(rng.normal(size=(3, 3)))[0]
    elif kind == "tiny":
        pos = rng.random((n, 3)) * 1e-30
    elif kind == "huge":
        pos = rng.random((n, 3)) * 1e38
    else:
        pos = np.array([[0, 0, 0], [1, 1, 1]] * (n // 2 + 2), float)[:n]
    faces = rng.integers(0, len(pos), (max(1, n // 3), 3))
    return pos.tolist(), faces.tolist(), kind


def _preload() -> None:
    """What the children use, imported once before they are forked (no GL context in this process)."""
    import trimesh  # noqa: F401

    import axialdeform.core.deform  # noqa: F401
    import axialdeform.core.io.gltf  # noqa: F401
    import axialdeform.core.io.mesh  # noqa: F401
    import axialdeform.core.variation  # noqa: F401


def fuzz_trees(cases: int, seed: int, keep: Path | None) -> int:
    import tomllib

    _preload()

    rng = np.random.default_rng(seed)
    work = Path(tempfile.mkdtemp(prefix="fuzz-trees-")) if keep is None else keep
    work.mkdir(parents=True, exist_ok=True)
    entries = tomllib.loads(TREE_AXES.read_text())["axis"]
    vcount = 58  # the bundled stone's vertices
    counts: dict = {}
    failures = []
    t0 = time.monotonic()
    for k in range(cases):
        kind = _pick(rng, ["toml", "toml", "vertices", "oriented"])
        if kind == "toml":
            mutated, said = mutate_axes(entries, rng)
            path = work / f"axes{k:05d}.toml"
            path.write_text(axes_toml(mutated))
            payload, name = str(path), path.name
        elif kind == "vertices":
            axes = int(rng.integers(1, 9)) if rng.random() < 0.8 else int(rng.integers(9, 70))
            vertex_axis = rng.integers(-1 if rng.random() < 0.1 else 0, axes + (rng.random() < 0.1), vcount)
            parents = [-1] + [int(rng.integers(0, i)) for i in range(1, axes)]
            if rng.random() < 0.6 and axes > 1:
                i = int(rng.integers(1, axes))
                parents[i] = _pick(rng, [i, i + 1, -1, -5, axes + 2, 0.5])
            said, payload, name = f"{axes} axes, parents {parents[:8]}", (vertex_axis.tolist(), parents), "stone"
        else:
            pos, faces, shape = degenerate_mesh(rng)
            said, payload, name = f"oriented on {shape}", (pos, faces), "mesh"
        verdict, detail = forked(tree_case, kind, payload)
        if verdict == "refused" and kind == "toml" and name not in detail:
            verdict, detail = "crash", "a refusal that does not name the file: " + detail
        counts.setdefault(kind, Counter())[verdict] += 1
        if verdict not in ("ok", "refused"):
            failures.append((kind, verdict, name, said, detail))
    total = sum(counts.values(), Counter())
    print(f"fuzz trees: {cases} cases (seed {seed}) in {time.monotonic() - t0:.0f} s: "
          + ", ".join(f"{v} {total[v]}" for v in ("ok", "refused", "crash", "garbage", "hang", "memory"))
          + " (" + "; ".join(f"{k}: {sum(c.values())}" for k, c in sorted(counts.items())) + ")")
    _report(failures)
    return 1 if failures else 0


def _report(failures) -> None:
    seen = Counter()
    for where, verdict, name, said, detail in failures:
        key = (where, verdict, detail.split(":")[0][:60])
        seen[key] += 1
        if seen[key] <= 2:
            print(f"  {where} {verdict}: {name} [{said}]: {detail[:240]}", file=sys.stderr)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", choices=("extension", "generated", "trees", "all"), default="all")
    ap.add_argument("--cases", type=int, default=300, help="files or specs per target (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=31)
    ap.add_argument("--node", action="store_true", help="also feed every GLB to the npm module's plugin (needs node)")
    ap.add_argument("--node-src", type=Path, default=ROOT / "js" / "src",
                    help="the npm module's src folder to test (default: %(default)s)")
    ap.add_argument("--bases", type=Path, default=None, help="folder of the instanced GLBs to corrupt (made if missing)")
    ap.add_argument("--keep", type=Path, default=None, help="write the cases here and keep them (default: a temp folder)")
    args = ap.parse_args(argv)
    status = 0
    if args.target in ("extension", "all"):
        status |= fuzz_extension(args.cases, args.seed, args.node, args.node_src.resolve(), args.bases,
                                 None if args.keep is None else args.keep / "extension")
    if args.target in ("generated", "all"):
        status |= fuzz_generated(args.cases, args.seed, args.node, args.node_src.resolve(),
                                 None if args.keep is None else args.keep / "generated")
    if args.target in ("trees", "all"):
        status |= fuzz_trees(args.cases, args.seed, None if args.keep is None else args.keep / "trees")
    return status


if __name__ == "__main__":
    sys.exit(main())
