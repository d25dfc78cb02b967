"""One error family: every failure the library raises on purpose is an
:class:`AxialDeformError`, and its message says what was expected and what
was found (and, for files, which file and which field)."""

from __future__ import annotations

__all__ = [
    "AxialDeformError",
    "ArgumentError",
    "MeshError",
    "ParamError",
    "ExampleError",
    "ParamFileError",
    "MeshMismatchError",
    "ShaderError",
    "ContextError",
    "TopologyError",
    "ResidualError",
    "GltfError",
    "PathError",
    "ScatterError",
    "TooFewError",
    "SceneError",
    "brief_names",
]

#: the most names a message lists before it says how many more there are
BRIEF_NAMES = 8


def brief_names(names, limit: int = BRIEF_NAMES) -> str:
    """``names`` for a one-line message: the first ``limit`` quoted (each cut to 40 characters), then
    ``... (N in all)`` -- a list of 10 000 names is summarized, not printed."""
    names = list(names)
    shown = ", ".join(repr(str(n)[:40]) for n in names[:limit])
    return shown + (f", ... ({len(names)} in all)" if len(names) > limit else "")


class AxialDeformError(Exception):
    """Base class of every error raised by axialdeform."""


class ArgumentError(AxialDeformError, ValueError):
    """A wrong argument value or shape given to a public function or class
    (an unknown mode, a view matrix that is not 4x4, a negative count); the
    message names the argument, what was expected and what was found."""


class MeshError(AxialDeformError, ValueError):
    """A base mesh that cannot be used (unreadable, empty, several meshes,
    non-finite coordinates, zero extent)."""


class ParamError(AxialDeformError, ValueError):
    """Parameter values of the wrong shape or with non-finite numbers."""


class ParamFileError(ParamError):
    """A parameter file that cannot be read: bad magic, version, length,
    checksum, column count or number."""


class MeshMismatchError(ParamFileError):
    """A binary parameter file that was made for a different base mesh."""


class ShaderError(AxialDeformError, RuntimeError):
    """A GLSL source that cannot be assembled or compiled; the message names
    the file, the stage and the line."""


class ContextError(AxialDeformError, RuntimeError):
    """No OpenGL 3.3 core context could be created."""


class TopologyError(MeshError):
    """A variant mesh whose vertex or triangle count (or triangles) differ
    from the base mesh's (``axialdeform fit``)."""


class ResidualError(AxialDeformError):
    """Fits whose residual exceeds the allowed limit (``axialdeform fit``)."""


class GltfError(AxialDeformError, ValueError):
    """A glTF file that cannot be written or read back as axialdeform
    instances (wrong extension, missing attribute, unexpected accessor type)."""


class PathError(AxialDeformError, ValueError):
    """A path that cannot be used: an input that is not a regular file (a
    FIFO, a device, a folder, a symlink to one) or too big for what it claims
    to hold; an output that is an input, or exists and is not a regular file."""


class ScatterError(AxialDeformError, ValueError):
    """Scatter input that cannot be used: a surface with no faces or none
    facing up, an all-black density map, a 1x1 height map, a bad range."""


class TooFewError(ScatterError):
    """Fewer instances fit on the surface than were asked for; ``params``
    holds the ones that fit."""

    def __init__(self, message: str, params=None) -> None:
        super().__init__(message)
        self.params = params


class ExampleError(AxialDeformError, ValueError):
    """An example to learn scenery from that cannot be used (``axialdeform learn``); the message names the
    file, the row or node, the column and what was expected."""


class SceneError(AxialDeformError, ValueError):
    """A scene file that cannot be used; the message names the file, the line
    and the key."""
