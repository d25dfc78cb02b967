"""Draw the bundled textured leaf card (axialdeform/meshes/leafcard.glb).

    python tools/make_leaf_card.py

The way games and films make foliage: a few triangles (a gently cupped card,
7 stations along y x 3 across, 1 unit long, the stalk at y = 0) carrying a
texture whose alpha cuts the leaf's outline out of the card.  The 256 x 256
RGBA texture is drawn here with Pillow: a leaf silhouette (alpha 255 inside,
0 outside), a light-to-dark green gradient, a pale midrib and side veins,
and a short stalk.  The material is glTF ``alphaMode: MASK`` (cutoff 0.5),
double-sided, so both faces are lit and the holes show what is behind.
"""

from pathlib import Path

import numpy as np
import trimesh
from PIL import Image, ImageDraw, ImageFilter

OUT = Path(__file__).resolve().parent.parent / "axialdeform" / "meshes" / "leafcard.glb"
SIZE = 256


def leaf_texture(size: int = SIZE) -> Image.Image:
    """RGBA leaf: colour everywhere (so mipmaps do not bleed dark), alpha = the outline."""
    s = size
    # outline: the half-width of the blade along its length (t = 0 stalk end, 1 tip)
    t = np.linspace(0.0, 1.0, 64)
    half = 0.40 * np.sin(np.pi * t**0.85) ** 0.8 * (1.0 - 0.15 * t)
    y = s * (0.94 - 0.88 * t)  # image rows: stalk at the bottom, tip at the top
    left = [(s * (0.5 - h), yy) for h, yy in zip(half, y)]
    right = [(s * (0.5 + h), yy) for h, yy in zip(half[::-1], y[::-1])]
    mask = Image.new("L", (s, s), 0)
    draw = ImageDraw.Draw(mask)
    draw.polygon(left + right, fill=255)
    draw.line([(s * 0.5, s * 0.94), (s * 0.5, s * 0.995)], fill=255, width=max(2, s // 64))  # stalk
    mask = mask.filter(ImageFilter.GaussianBlur(0.6))

    rows = np.linspace(0.0, 1.0, s)[:, None]
    cols = np.abs(np.linspace(-1.0, 1.0, s))[None, :]
    green = np.stack([
        0.20 + 0.10 * rows + 0.05 * cols,
        0.42 + 0.16 * rows - 0.06 * cols,
        0.08 + 0.04 * rows + 0.0 * cols,
    ], axis=-1)
    rng = np.random.Generator(np.random.PCG64(12))
    green *= 1.0 + 0.06 * (rng.random((s, s, 1)) - 0.5)
    rgb = Image.fromarray(np.clip(green * 255, 0, 255).astype(np.uint8), "RGB")
    veins = ImageDraw.Draw(rgb)
    pale = (150, 178, 92)
    veins.line([(s * 0.5, s * 0.995), (s * 0.5, s * 0.08)], fill=pale, width=max(2, s // 80))  # midrib
    for k in range(1, 8):  # side veins, swept towards the tip
        yy = s * (0.90 - 0.10 * k)
        reach = s * 0.30 * np.sin(np.pi * (1 - yy / s)) ** 0.7
        for sign in (-1, 1):
            veins.line([(s * 0.5, yy), (s * 0.5 + sign * reach, yy - reach * 0.55)], fill=pale, width=max(1, s // 200))
    rgba = rgb.convert("RGBA")
    rgba.putalpha(mask)
    return rgba


def leaf_card() -> trimesh.Trimesh:
    stations, across = 7, 3
    ys = np.linspace(0.0, 1.0, stations)
    us = np.linspace(-1.0, 1.0, across)
    y, u = np.meshgrid(ys, us, indexing="ij")
    half_width = 0.36  # narrower than long: the control axis runs along y
    x = u * half_width
    z = 0.08 * u**2 - 0.03 * np.sin(np.pi * y)  # cupped across, a slight arch along
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    uv = np.stack([(u + 1) / 2, y], axis=-1).reshape(-1, 2)  # OBJ convention: v = 0 at the image's bottom (stalk)
    faces = []
    for i in range(stations - 1):
        for j in range(across - 1):
            a, b = i * across + j, i * across + j + 1
            c, d = a + across, b + across
            faces += [(a, b, d), (a, d, c)]
    material = trimesh.visual.material.PBRMaterial(
        name="leaf", baseColorTexture=leaf_texture(), baseColorFactor=[255, 255, 255, 255],
        alphaMode="MASK", alphaCutoff=0.5, doubleSided=True, metallicFactor=0.0, roughnessFactor=0.8)
    return trimesh.Trimesh(verts, np.array(faces), visual=trimesh.visual.TextureVisuals(uv=uv, material=material),
                           process=False)


def main() -> None:
    mesh = leaf_card()
    OUT.write_bytes(mesh.export(file_type="glb"))
    print(f"wrote {OUT} ({len(mesh.vertices)} vertices, {len(mesh.faces)} triangles, {SIZE}x{SIZE} texture)")


if __name__ == "__main__":
    main()
