"""Pictures and files of the earlier forms, to compare two versions byte for byte.

    python tools/outputs_snapshot.py OUT

Renders (plain, wireframe, extended, wind, tinted, the Khronos alpha test,
the landscape scene), writes parameter files (float32, quantized, text) and
glTF exports (instanced, baked) and a CPU bake with wind, all into OUT, with
whichever axialdeform is imported.  Run it at two commits (each with ITS
glsl/ in place: the editable install maps axialdeform.glsl to the checkout's
glsl/) and compare the folders (numpy arrays: np.array_equal; files: bytes).
"""
import os
import sys
from pathlib import Path

import numpy as np

import axialdeform as ad

out = sys.argv[1]
os.makedirs(out, exist_ok=True)
print(ad.__file__)
shared = str(Path(__file__).resolve().parents[1] / "tests" / "data" / "meshes" / "assets" / "AlphaBlendModeTest.glb")
look = ad.Look()
jobs = []
stone, leaf, card = ad.load_mesh("stone"), ad.load_mesh("leaf"), ad.load_mesh("leafcard")
alpha = ad.load_mesh(shared)
p16 = ad.random_params(stone, 300, seed=1, variation=ad.Variation(bend=0.15))
p19 = ad.random_params(leaf, 200, seed=2, variation=ad.Variation(bend=0.2, scale=(0.5, 1.5), twist=1.0, taper=0.5))
p22 = ad.random_params(card, 100, seed=3, variation=ad.Variation(tint=0.5))
pa = ad.random_params(alpha, 5, seed=4, variation=ad.Variation(bend=0.1, scale=(0.8, 1.2)))
wind = ad.Wind(direction=(1, 0, 0.3), strength=0.2, gustiness=0.5)
pics = {
  "stone": ad.render_image(stone, p16, (320, 240)),
  "stone_wire": ad.render_image(stone, p16, (320, 240), modes="wireframe"),
  "leaf19": ad.render_image(leaf, p19, (320, 240)),
  "leaf19_wind": ad.render_image(leaf, p19, (320, 240), options=ad.RenderOptions(wind=wind, time=2.5)),
  "card22": ad.render_image(card, p22, (320, 240)),
  "alpha": ad.render_image(alpha, pa, (320, 240)),
  "landscape": ad.render_image(ad.Scene.load(str(Path(__file__).resolve().parents[1] / "examples" / "landscape" / "landscape.toml"),
                                             scale_counts=0.1), size=(320, 240)),
}
for k, v in pics.items():
    np.save(f"{out}/{k}.npy", v)
for name, mesh, p in (("s16", stone, p16), ("l19", leaf, p19), ("c22", card, p22)):
    ad.write_params(f"{out}/{name}.adp", p, mesh)
    ad.write_params(f"{out}/{name}q.adp", p, mesh, quantize=True)
    ad.write_params(f"{out}/{name}.txt", p, mesh)
    ad.export_glb(f"{out}/{name}_i.glb", mesh, p[:20], "instanced")
    ad.export_glb(f"{out}/{name}_b.glb", mesh, p[:20])
pos, nrm = ad.bake(leaf, p19, "cpu", options=ad.RenderOptions(wind=wind, time=1.0))
np.save(f"{out}/bake.npy", np.concatenate([pos, nrm]))
