"""The glTF generated form (docs/gltf/AXIALDEFORM_bend, ``generate``): a scene's generated layer written as
its recipe -- the generator's numbers and the ground maps -- on an instancing node that also holds a small
plain fallback (the instances of the tile at the extent's centre), so a viewer without the extension
still shows some of the layer and one with it makes the tiles around its camera
(axialdeform-three's ``AxialGLTFPlugin``)."""

from __future__ import annotations

import numpy as np

from ..errors import GltfError
from ..generate import children_table, generate_tiles, recipe_json, recipe_uniforms, tiles_around
from .glb import FLOAT

__all__ = ["generated_form", "check_generated", "FALLBACK_TILES"]

#: the most tiles the fallback looks through for instances (nearest the extent's centre first)
FALLBACK_TILES = 9


def check_generated(scene, layers) -> None:
    """Refuse a ``generated`` export of a scene without a generated layer."""
    if not any(getattr(layer, "generate", None) is not None for layer in layers):
        raise GltfError(f"{scene.path}: --generated writes a scene's generated layers ([layer.generate]) as their "
                        "recipe; this scene has none (expected --instanced or --baked)")


def generated_form(b, layer) -> tuple[np.ndarray, dict]:
    """A generated layer's fallback instances ((n, 16, 19 or 22) float32: the first tile near its extent's
    centre that keeps any) and the ``generate`` member of its node's ``AXIALDEFORM_bend``: the recipe, the
    generator's numbers (:func:`~axialdeform.core.generate.recipe_uniforms`) and each ground map (and a tree's
    child-axis table) as a FLOAT SCALAR accessor of rows x cols numbers, row after row."""
    gen = layer.generate
    recipe, maps = gen.generate, gen.maps
    x0, z0, x1, z1 = gen.extent
    fallback = np.zeros((0, recipe.width), np.float32)
    for tile in tiles_around(recipe, (x0 + x1) / 2, (z0 + z1) / 2, gen.reach)[:FALLBACK_TILES]:
        fallback = generate_tiles(recipe, layer.mesh, [tile], maps)
        if len(fallback):
            break
    if not len(fallback):
        raise GltfError(f"layer {layer.name}: the {FALLBACK_TILES} tiles nearest its extent's centre keep no "
                        "instance; a generated node needs a fallback of at least one (move the extent)")
    spec = {"recipe": recipe_json(recipe, gen.reach), "uniforms": recipe_uniforms(recipe, layer.mesh, maps)}
    tree = getattr(layer.mesh, "tree", None)  # several axes: each child axis's amplitude and joint projection
    for key in ("heights", "density", "children"):
        grid = (children_table(recipe, layer.mesh) if tree is not None else None) if key == "children" else (
            getattr(maps, key, None) if maps is not None else None)
        if grid is not None:
            data = np.ascontiguousarray(grid, "<f4").ravel()
            spec[key] = {"accessor": b.accessor(b.view(data), FLOAT, len(data), "SCALAR", name=f"{layer.name}_{key}"),
                         "cols": int(grid.shape[1]), "rows": int(grid.shape[0])}
    return fallback, {"generate": spec}
