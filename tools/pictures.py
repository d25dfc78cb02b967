"""Record the project's pictures, or compare them with a recorded set.

    python tools/pictures.py record DIR     # demo, examples (--quick), render cases
    python tools/pictures.py compare OLD NEW  # per picture: byte-equal, or mean |diff| in 1/255

Used before and after a refactor: the pictures must stay the same (byte for
byte, or a small mean difference where a change is on purpose).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent
CLI = [sys.executable, "-m", "axialdeform"]

CASES = {
    "demo.png": [*CLI, "demo", "-n", "600", "--size", "400x300", "-o", "{out}"],
    "demo-fast.png": [*CLI, "demo", "-n", "600", "--size", "400x300", "--fast", "-o", "{out}"],
    "leafcard.png": [*CLI, "render", "leafcard", "{dir}/leaves.adp", "--size", "320x240", "-o", "{out}"],
    "leaf-wire.png": [*CLI, "render", "leaf", "{dir}/leaf.adp", "--size", "320x240", "--mode", "wireframe", "-o", "{out}"],
    "stone-flat-ext.png": [*CLI, "render", "stone", "{dir}/ext.adp", "--size", "320x240", "--mode", "flat", "-o", "{out}"],
    "landscape-scene.png": [*CLI, "render", str(ROOT / "examples/landscape/landscape.toml"), "--size", "320x240", "-o", "{out}"],
}
PREP = [
    [*CLI, "random", "leafcard", "-n", "60", "--seed", "3", "-o", "{dir}/leaves.adp"],
    [*CLI, "random", "leaf", "-n", "80", "--seed", "4", "--bend", "0.2", "-o", "{dir}/leaf.adp"],
    [*CLI, "random", "stone", "-n", "150", "--seed", "5", "--scale", "0.7:1.3", "--twist", "0.6", "--taper", "0.5",
     "-o", "{dir}/ext.adp"],
]
EXAMPLES = ["01_stones.py", "02_falling_leaves.py", "03_own_moderngl_program.py", "04_moderngl_window_app.py",
            "05_landscape.py"]


def run(cmd, cwd):
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if proc.returncode:
        print(" ".join(map(str, cmd)), "\n", proc.stdout, proc.stderr, file=sys.stderr)
    return proc.returncode


def record(folder: Path) -> None:
    folder = folder.resolve()
    folder.mkdir(parents=True, exist_ok=True)
    work = folder / "_work"
    work.mkdir(exist_ok=True)
    for cmd in PREP:
        run([c.format(dir=work) for c in cmd], work)
    for name, cmd in CASES.items():
        run([c.format(dir=work, out=folder / name) for c in cmd], work)
    for ex in EXAMPLES:
        out = folder / ex[:2]
        out.mkdir(exist_ok=True)
        run([sys.executable, str(ROOT / "examples" / ex), "--quick", "-o", str(out)], out)


def compare(old: Path, new: Path) -> int:
    worst = 0.0
    for a in sorted([*old.rglob("*.png"), *old.rglob("*.gif")]):
        if "_work" in a.parts:
            continue
        b = new / a.relative_to(old)
        if not b.exists():
            print(f"{a.relative_to(old)}: MISSING")
            worst = max(worst, 255)
            continue
        x = np.asarray(Image.open(a).convert("RGB"), dtype=np.int16)
        y = np.asarray(Image.open(b).convert("RGB"), dtype=np.int16)
        if x.shape != y.shape:
            print(f"{a.relative_to(old)}: shape {x.shape} -> {y.shape}")
            worst = max(worst, 255)
            continue
        mean = float(np.abs(x - y).mean())
        same = a.read_bytes() == b.read_bytes()
        print(f"{a.relative_to(old)}: {'byte-equal' if same else f'mean |diff| {mean:.4f}/255, max {int(np.abs(x - y).max())}'}")
        worst = max(worst, mean)
    print(f"worst mean difference {worst:.4f}/255")
    return 0


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "record":
        record(Path(sys.argv[2]))
    elif len(sys.argv) >= 4 and sys.argv[1] == "compare":
        sys.exit(compare(Path(sys.argv[2]), Path(sys.argv[3])))
    else:
        print(__doc__)
        sys.exit(2)
