"""What a mesh file references (textures, .mtl files, glTF buffers and
images), found and read safely: regular files only, bounded sizes, inside
the file's folder."""

from __future__ import annotations

import json
import os
import stat
import struct

from ..errors import MeshError, PathError
from . import safeio
from .safeio import MAX_REFERENCED_BYTES, open_regular, read_regular

__all__ = ['BUFFER_SLACK', 'IMAGE_SUFFIXES', 'SafeResolver', 'error_in_words', 'gltf_json', 'gltf_references',
           'is_image_name', 'unsupported_features']


#: suffixes of the files a mesh refers to that are pictures (textures)
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".gif", ".webp", ".tif", ".tiff", ".ktx", ".ktx2", ".dds")


def is_image_name(name: str) -> bool:
    """True for a referenced file that is a picture (a texture), by its suffix."""
    return os.path.splitext(str(name))[1].lower() in IMAGE_SUFFIXES


def error_in_words(exc: BaseException, kind: str) -> str:
    """What went wrong inside a parser (trimesh, pygltflib) reading a ``kind``
    file (``"obj"``, ``"glb"``, ...), in words: never Python's own text."""
    what = {"glb": "binary glTF", "gltf": "glTF"}.get(kind, kind.upper())
    if isinstance(exc, KeyError) and exc.args:
        return f"a field it needs is missing ({exc.args[0]!r}); expected a complete {what} file"
    if isinstance(exc, (IndexError, UnboundLocalError)):
        return f"it refers to data it does not hold (an index out of range); expected a consistent {what} file"
    if isinstance(exc, (ValueError, TypeError)):
        text = str(exc).splitlines()[0][:120] if str(exc) else "a value of the wrong kind"
        return f"a malformed value ({text}); expected a valid {what} file"
    if isinstance(exc, (UnicodeError, EOFError)):
        return f"its bytes end early or are not text where text belongs; expected a valid {what} file"
    if isinstance(exc, MemoryError):
        return "it asks for more memory than this machine has"
    return f"it cannot be parsed; expected a valid {what} file"


def gltf_json(data: bytes, kind: str, name: str) -> dict:
    """The JSON object of a glTF (``kind`` ``"gltf"``: the file; ``"glb"``:
    its first chunk), read once per load; :class:`MeshError` naming ``name``
    when it is not one -- said here, before trimesh, which would go looking
    for a ``model.gltf`` the file never mentions."""
    what = "binary glTF" if kind == "glb" else "glTF"
    if kind == "glb":
        if len(data) < 20:
            raise MeshError(f"{name}: not a {what} file: {len(data)} bytes, shorter than the 20-byte header")
        magic, _version, _length, chunk, ctype = struct.unpack_from("<4sIIII", data)
        if magic != b"glTF":
            raise MeshError(f"{name}: not a {what} file: magic {magic!r}, expected b'glTF'")
        if ctype != 0x4E4F534A:
            raise MeshError(f"{name}: not a {what} file: its first chunk is not JSON (type {ctype:#x}, expected 0x4e4f534a)")
        if 20 + chunk > len(data):
            raise MeshError(f"{name}: truncated: its JSON chunk declares {chunk} bytes, {len(data) - 20} follow the header")
        data = bytes(data[20 : 20 + chunk])
    try:
        tree = json.loads(bytes(data).decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise MeshError(f"{name}: not a {what} file: byte {exc.start} of its JSON is not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise MeshError(f"{name}: not a {what} file: its JSON is not valid (line {exc.lineno}, column {exc.colno}: "
                        f"{exc.msg})") from None
    except RecursionError:
        raise MeshError(f"{name}: not a {what} file: its JSON is nested too deeply") from None
    if not isinstance(tree, dict):
        raise MeshError(f"{name}: not a {what} file: its JSON is a {type(tree).__name__}, expected an object")
    return tree


def unsupported_features(tree: dict) -> list[str]:
    """What a glTF's JSON asks for that the bend does not draw: skins, morph
    targets, animations (each drawn in the rest pose)."""
    found = []
    meshes = tree.get("meshes") if isinstance(tree.get("meshes"), list) else []
    if isinstance(tree.get("skins"), list) and tree["skins"]:
        found.append(f"{len(tree['skins'])} skin(s)")
    targets = sum(1 for m in meshes if isinstance(m, dict) for p in (m.get("primitives") or [])
                  if isinstance(p, dict) and p.get("targets"))
    if targets:
        found.append(f"morph targets on {targets} primitive(s)")
    if isinstance(tree.get("animations"), list) and tree["animations"]:
        found.append(f"{len(tree['animations'])} animation(s)")
    return found


def gltf_references(tree: dict, name: str = "<gltf>") -> dict[str, tuple[str, int | None]]:
    """What a glTF's JSON (:func:`gltf_json`) declares about the files it refers to: ``{uri: (field, byte length)}``,
    the length a buffer's ``byteLength`` (``field`` e.g.
    ``"buffers[0].byteLength"``), None for an image (``"images[2].uri"``:
    bounded by :data:`axialdeform.core.io.safeio.MAX_IMAGE_BYTES`).  ``data:``
    URIs are inside the file and not listed.  A buffer ``byteLength`` that is not a whole number >= 1 raises :class:`MeshError`
    naming ``name`` and the field."""
    out: dict[str, tuple[str, int | None]] = {}
    for group in ("buffers", "images"):
        items = tree.get(group)
        for i, item in enumerate(items if isinstance(items, list) else []):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or "base64," in uri or uri in out:
                continue
            if group == "images":
                out[uri] = (f"images[{i}].uri", None)
                continue
            size = item.get("byteLength")
            if isinstance(size, bool) or not isinstance(size, int) or size < 1:
                raise MeshError(f"{name}: buffers[{i}].byteLength: expected a whole number of bytes >= 1 "
                                f"(the size of {uri}), found {size!r}")
            out[uri] = (f"buffers[{i}].byteLength", size)
    return out


#: bytes a referenced buffer may have beyond its declared ``byteLength``
#: (padding to a multiple of 4, as in a GLB's binary chunk); more is refused
BUFFER_SLACK = 3


class _Outside(Exception):
    """A reference that leaves the model's folder."""


class SafeResolver:
    """A trimesh resolver for the files a mesh refers to (``.mtl``, textures,
    glTF buffers): only regular files in the mesh's folder tree are read, so a
    FIFO or a device never blocks, each with a bound that depends on what it
    claims to hold:

    * a glTF buffer named in ``declared`` (:func:`gltf_references`): its
      ``byteLength`` exactly (up to :data:`BUFFER_SLACK` bytes of padding
      more, which are not read); a file smaller or larger is refused without
      being read, the message naming the file, the field and the expectation;
    * a picture (a glTF image, an OBJ texture):
      :data:`axialdeform.core.io.safeio.MAX_IMAGE_BYTES`;
    * anything else (a material library): ``max_bytes``
      (:data:`axialdeform.core.io.safeio.MAX_REFERENCED_BYTES`).

    Every refusal or failure is recorded in ``failed`` as ``(name, reason)``
    for the loader's warning, and the refusals (not a regular file, too
    large, not the declared size) also in ``refused`` as ``(name,
    message)``: the loader refuses the mesh for those that are not textures."""

    def __init__(self, folder: str | os.PathLike, max_bytes: int | None = None, *,
                 declared: dict | None = None, referrer: str | None = None, root: str | os.PathLike | None = None):
        self.parent = os.path.abspath(os.fspath(folder))
        #: the model's folder: nothing outside it is read (absolute paths, ``..`` and links out of it)
        self.root = os.path.realpath(self.parent if root is None else os.fspath(root))
        self.max_bytes = MAX_REFERENCED_BYTES if max_bytes is None else int(max_bytes)
        self.declared = dict(declared or {})
        self.referrer = referrer
        self.failed: list[tuple[str, str]] = []
        self.refused: list[tuple[str, str]] = []
        #: every file read (paths): what the mesh was made from beside its own file
        self.read: list[str] = []

    def _path(self, name: str) -> str:
        """The file ``name`` refers to, inside the model's folder; :class:`_Outside` if it is not."""
        name = str(name).replace("\\", "/")
        if os.path.isabs(name) or (len(name) > 1 and name[1] == ":"):  # /etc/x, C:/x
            raise _Outside("an absolute path")
        path = os.path.join(self.parent, name)
        real = os.path.realpath(path)  # through every symlink
        if os.path.commonpath([real, self.root]) != self.root:
            raise _Outside("a link out of it" if os.path.islink(path) else "a path out of it (..)")
        return path

    def get(self, name: str) -> bytes:
        try:
            path = self._path(name)
        except _Outside as why:
            # a model reads only its own folder: the part keeps its base colour, the loader warns
            self.failed.append((str(name), f"is outside the model's folder {self.root} ({why}); not read"))
            raise OSError(f"{name}: outside the model's folder") from None
        try:
            st = os.stat(path)
        except OSError as exc:
            self.failed.append((str(name), exc.strerror or "cannot be read"))
            raise
        if not stat.S_ISREG(st.st_mode):
            self.failed.append((str(name), "is not a regular file"))
            self.refused.append((str(name), f"{name}: not a regular file"))
            raise OSError(f"{name}: not a regular file")
        field, size = self.declared.get(str(name), (None, None))
        by = f" by {self.referrer}" if self.referrer else ""
        self.read.append(path)  # named by the model: an output must never replace it, read or not
        try:
            if size is not None:
                return bytes(self._read_declared(path, name, field, size, by))
            if field is not None or is_image_name(name):
                return bytes(read_regular(path, safeio.MAX_IMAGE_BYTES, f"a picture referred to{by} (a texture)"))
            return bytes(read_regular(path, self.max_bytes, f"a file referred to{by}"))
        except PathError as exc:
            self.failed.append((str(name), str(exc)))
            self.refused.append((str(name), str(exc)))
            raise OSError(str(exc)) from None
        except OSError as exc:
            self.failed.append((str(name), exc.strerror or "cannot be read"))
            raise

    def _read_declared(self, path: str, name: str, field: str, size: int, by: str) -> bytearray:
        """The first ``size`` bytes of ``path``, a buffer whose declared length is ``size``."""

        what = f"a buffer referred to{by}"
        if size > safeio.memory_available() // 2:
            raise PathError(f"{name}: {self.referrer or 'the mesh'} declares {field} = {size}; expected a buffer of at most "
                            f"{safeio.memory_available() // 2} bytes (half the memory available)")
        with open_regular(path, what) as (fh, actual):
            if not size <= actual <= size + BUFFER_SLACK:
                raise PathError(f"{name}: is {actual} bytes, but {self.referrer or 'the mesh'} declares {field} = {size}; "
                                f"expected a file of exactly {size} bytes"
                                + (f" (or up to {BUFFER_SLACK} more of padding)" if BUFFER_SLACK else "")
                                + (" (truncated?)" if actual < size else ""))
            data = safeio.read_sized(fh, actual, name, what, PathError)
        del data[size:]  # padding is not part of the buffer
        return data

    __getitem__ = get

    def get_base(self):  # trimesh asks for it when writing
        return self.parent

    def namespaced(self, namespace):
        child = SafeResolver(os.path.join(self.parent, namespace), self.max_bytes, referrer=self.referrer,
                             root=self.root)
        child.failed, child.refused, child.read = self.failed, self.refused, self.read  # one record for the whole load
        return child

    def keys(self):
        return iter(())

    def write(self, name, data):  # pragma: no cover - never used for loading
        raise OSError("read-only resolver")
