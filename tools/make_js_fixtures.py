"""Write js/test/fixtures/: small .adp files and what the Python library makes of them.

The node tests (``node --test js/test``) parse each file with the npm module's
``parseADP``, place its instances with ``instanceMatrices`` and bound them with
``bentRadii``, and compare with ``expected.json``: the header, the decoded
numbers, each instance's matrix and the bent world positions
:func:`axialdeform.deform` gives (the CPU reference), which must lie in the bounds.  Rerun
after changing the file format or the method; ``tests/test_js.py`` checks that
the committed fixtures are what this script writes.

    .venv/bin/python tools/make_js_fixtures.py [OUT_DIR]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import axialdeform as ad
from axialdeform.core.io.params import encode_binary
from axialdeform.core.transforms import rotation_matrices

VERTICES = 120  # of each mesh, in the expected positions (the JS test bends these)


def cases():
    stone = ad.load_mesh("stone")
    tree = ad.load_mesh("tree", axes=str(Path(__file__).resolve().parents[1] / "examples" / "forest" / "tree-axes.toml"))
    turned = stone.with_axis("oriented")
    yield "stone16", stone, ad.random_params(stone, 3, seed=1, variation=ad.Variation(bend=0.12)), False
    yield "stone16q", stone, ad.random_params(stone, 3, seed=2, variation=ad.Variation(bend=0.12)), True
    yield "stone19", stone, ad.random_params(stone, 3, seed=3, variation=ad.Variation(bend=0.1, scale=(0.5, 1.5), twist=1.2,
                                                                                      taper=0.5)), False
    yield "stone22", stone, ad.random_params(stone, 2, seed=4, variation=ad.Variation(bend=0.1, scale=(0.8, 1.2), twist=0.5, taper=0.3,
                                                                                      tint=0.4)), True
    yield "framed", turned, ad.random_params(turned, 3, seed=5, variation=ad.Variation(bend=0.1, twist=0.7, taper=0.2)), False
    yield "tree", tree, ad.random_params(tree, 2, seed=6, variation=ad.Variation(twist=0.3, taper=0.2)), False


def placements(params) -> np.ndarray:
    """(n, 16) column-major T(p) R S(s) of every instance (docs/method.md: W = R (s V'') + p)."""
    from axialdeform.core.record import ANGLES, POSITION, SCALE, tree_shape

    params = np.asarray(params, dtype=np.float64)
    shift = 10 * (tree_shape(params.shape[1])[0] - 1)  # several axes: the child axes' offsets come first
    rot = rotation_matrices(params[:, ANGLES.start + shift:ANGLES.stop + shift])
    scale = params[:, SCALE + shift] if params.shape[1] - shift >= 19 else np.ones(len(params))
    m = np.zeros((len(params), 4, 4))
    m[:, :3, :3] = rot * scale[:, None, None]
    m[:, :3, 3] = params[:, POSITION.start + shift:POSITION.stop + shift]
    m[:, 3, 3] = 1.0
    return m.transpose(0, 2, 1).reshape(len(params), 16)  # column-major, as three's Matrix4.elements


def axis_json(mesh) -> dict:
    a = mesh.axis
    out = {"axis": {"index": int(a.index), "lo": float(a.lo), "length": float(a.length),
                    "frame": a.matrix.tolist(), "center": list(a.line)}}
    if mesh.tree is not None:
        t = mesh.tree
        out["axes"] = {"count": t.count, "parents": list(t.parents), "frames": [x.matrix.tolist() for x in t.axes],
                       "lo": [float(x.lo) for x in t.axes], "length": [float(x.length) for x in t.axes]}
    return out


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    expected = {}
    for name, mesh, params, quantize in cases():
        blob = encode_binary(params, axis=mesh, mesh_fingerprint=mesh.fingerprint, quantize=quantize)
        (out / f"{name}.adp").write_bytes(blob)
        decoded = ad.read_params(out / f"{name}.adp", mesh=mesh)  # what Python decodes (quantized: dequantized)
        world = ad.deform(mesh, decoded)[0]  # (n, v, 3) world positions
        pick = np.linspace(0, mesh.vertex_count - 1, VERTICES).astype(int)
        expected[name] = {
            "count": len(params), "numbersPerInstance": int(params.shape[1]),
            "encoding": "quantized" if quantize else "float32", "axisCount": mesh.axis_count,
            "fingerprint": mesh.fingerprint.hex(),
            "data": np.asarray(decoded, dtype=np.float64).round(8).tolist(),
            **axis_json(mesh),
            "positions": mesh.positions[pick].astype(np.float64).tolist(),
            "vertexAxis": None if mesh.tree is None else mesh.tree.vertex_axis[pick].tolist(),
            "world": np.asarray(world, dtype=np.float64)[:, pick].round(7).tolist(),
            "matrices": placements(decoded).round(7).tolist(),
            "length": float(mesh.axis.length),
        }
    text = json.dumps(expected, indent=None, separators=(",", ":"))
    (out / "expected.json").write_text(text + "\n")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "js" / "test" / "fixtures")
