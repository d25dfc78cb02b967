"""Make the Blender add-on's installable zip (Blender's extension format).

    python tools/build_blender_addon.py [-o dist/] [--wheels]

The zip holds ``blender/axialdeform_blender/`` (its ``blender_manifest.toml`` at the top).  The add-on
reads and writes files through the axialdeform library, which Blender's Python must be able to import:
``--wheels`` puts the library's wheel and those of what it needs (for this machine's platform, Python
3.11, numpy left to Blender's own) into the zip and lists them in the manifest, so Blender installs them
with the extension; without it, install axialdeform into Blender's Python yourself
(``BLENDER_PYTHON -m pip install axialdeform``).  Install the zip with Edit > Preferences > Get
Extensions > Install from Disk, or ``blender --command extension install-file -r user_default ZIP``.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ADDON = ROOT / "blender" / "axialdeform_blender"
#: what Blender's Python has already (Blender 4.2 - 5.0 bundle these)
BLENDER_HAS = ("numpy", "requests", "urllib3", "idna", "certifi", "charset_normalizer", "zstandard", "cython")


def _version() -> str:
    return re.search(r'^version = "([^"]+)"', (ADDON / "blender_manifest.toml").read_text(), re.M).group(1)


def _wheels(folder: Path) -> list[Path]:
    """The library's wheel and its dependencies' (binary wheels for Python 3.11 on this platform)."""
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(folder), str(ROOT)], check=True)
    subprocess.run([sys.executable, "-m", "pip", "download", "-q", "-d", str(folder), "--only-binary=:all:",
                    "--python-version", "3.11", str(next(folder.glob("axialdeform-*.whl"))),
                    "numpy>=1.26,<2"], check=True)  # resolved against Blender's numpy (1.26 in Blender 4.2 - 5.0)
    keep = []
    for wheel in sorted(folder.glob("*.whl")):
        name = wheel.name.split("-")[0].lower().replace("_", "-")
        if name.replace("-", "_") in BLENDER_HAS or name in BLENDER_HAS:
            wheel.unlink()
        else:
            keep.append(wheel)
    return keep


def build(out: Path, wheels: bool = False) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"axialdeform_blender-{_version()}.zip"
    with tempfile.TemporaryDirectory() as tmp:
        found = _wheels(Path(tmp)) if wheels else []
        manifest = (ADDON / "blender_manifest.toml").read_text()
        if found:
            listed = ",\n".join(f'    "./wheels/{w.name}"' for w in found)
            manifest = manifest.replace("[permissions]", f"wheels = [\n{listed},\n]\n\n[permissions]")
        partial = target.with_suffix(".zip.part")
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as zf:
            for path in sorted(ADDON.rglob("*")):
                if path.is_file() and "__pycache__" not in path.parts and path.name != "blender_manifest.toml":
                    zf.write(path, path.relative_to(ADDON).as_posix())
            zf.writestr("blender_manifest.toml", manifest)
            for wheel in found:
                zf.write(wheel, f"wheels/{wheel.name}")
        partial.replace(target)
    return target


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--out", default=str(ROOT / "dist"), help="the folder for the zip (default dist/)")
    parser.add_argument("--wheels", action="store_true",
                        help="bundle the library's wheel and its dependencies' (default: off)")
    args = parser.parse_args()
    print(build(Path(args.out), args.wheels))


if __name__ == "__main__":
    main()
