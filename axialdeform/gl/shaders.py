"""Step 5 of the data flow: GLSL sources from ``glsl/`` into programs.

Shaders are real ``.glsl``/``.vert``/``.frag`` files.  ``#include "name"``
pulls in another file of the same folder (include cycles are an error);
every file gets a ``#line`` directive with its own source-string number, so
a compile error is reported as *file, stage, line*.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from importlib import resources

import moderngl

from ..core.errors import ShaderError

__all__ = ["GLSL_VERSION", "COMPUTE_VERSION", "shader_source", "assemble", "assemble_text", "deformation_glsl", "build_program",
           "build_compute", "Assembled"]

GLSL_VERSION = "#version 330 core"
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"\s*(?://.*)?$')
_STAGES = ("vertex_shader", "fragment_shader", "geometry_shader")


def shader_source(name: str) -> str:
    """The text of one file of the package's ``glsl/`` folder."""
    res = resources.files("axialdeform.glsl").joinpath(name)
    if not res.is_file():
        raise ShaderError(f"glsl/{name}: no such shader file")
    return res.read_text(encoding="utf-8")


def deformation_glsl() -> str:
    """The GLSL deformation (``glsl/axial.glsl``): paste or ``#include`` it in
    your own shaders and call ``axial_world(...)`` (see the file's header)."""
    return shader_source("axial.glsl")


@dataclass
class Assembled:
    """A complete shader stage: its source and the files behind each ``#line`` number."""

    source: str
    files: list[str] = field(default_factory=list)

    def locate(self, string_number: int, line: int) -> str:
        if 0 <= string_number < len(self.files):
            return f"glsl/{self.files[string_number]}, line {line}"
        return f"line {line}"


def assemble(name: str, defines: dict | None = None, loader=shader_source) -> Assembled:
    """Expand ``#include``s of ``name`` into one GLSL 3.30 core source.

    ``defines`` become ``#define KEY VALUE`` lines after ``#version``.
    """
    out = Assembled("")
    lines = [GLSL_VERSION]
    for key, value in (defines or {}).items():
        lines.append(f"#define {key} {'' if value is None else value}".rstrip())

    def expand(fname: str, stack: tuple[str, ...]) -> None:
        if fname in stack:
            raise ShaderError(f"glsl/{fname}: #include cycle: {' -> '.join(stack + (fname,))}")
        text = loader(fname)
        number = len(out.files)
        out.files.append(fname)
        lines.append(f"#line 1 {number}")
        for lineno, line in enumerate(text.splitlines(), start=1):
            if re.match(r"^\s*#\s*version\b", line):
                raise ShaderError(f"glsl/{fname}, line {lineno}: remove #version; the loader writes '{GLSL_VERSION}'")
            m = _INCLUDE.match(line)
            if m:
                expand(m.group(1), stack + (fname,))
                lines.append(f"#line {lineno + 1} {number}")
            else:
                # moderngl expands any '#include "x"' it still sees, even in a
                # comment: defuse the ones that are not directives
                lines.append(line.replace("#include", "#-include"))

    expand(name, ())
    out.source = "\n".join(lines) + "\n"
    return out


def assemble_text(source: str, name: str = "<string>", defines: dict | None = None) -> Assembled:
    """Expand ``#include "axial.glsl"`` (or any file of the package's
    ``glsl/`` folder) in the text of YOUR OWN shader.

    source : the shader text.  A ``#version`` line is optional; if present it
        must be the first non-blank line and is kept (else ``#version 330 core``).
    name : how error locations name your text (``Assembled.locate``).
    defines : ``#define KEY VALUE`` lines to add after ``#version``.

    Every file keeps its own ``#line`` numbering, so compiler errors point at
    the line of your text.  Returns an :class:`Assembled`; pass its
    ``.source`` to ``ctx.program``.
    """
    lines = str(source).splitlines()
    version = None
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        if re.match(r"^\s*#\s*version\b", line):
            version, lines[i] = line.strip(), ""  # a blank line keeps the numbering
        break
    text = "\n".join(lines)

    def loader(fname: str) -> str:
        return text if fname == name else shader_source(fname)

    out = assemble(name, defines, loader=loader)
    if version is not None:
        out.source = version + out.source[len(GLSL_VERSION):]
    return out


# Mesa "0:12(5): error", NVIDIA "0(12) : error", AMD/Intel "ERROR: 0:12:"
_LOG_LINE = re.compile(r"(?:ERROR:\s*)?(\d+)[:(](\d+)\)?(?:\(\d+\))?\s*:?\s*(.*)")


def _translate_log(log: str, stages: dict[str, Assembled]) -> str:
    """Rewrite moderngl's compile/link log so each error names file, stage, line."""
    current = None
    messages = []
    for raw in log.splitlines():
        text = raw.strip()
        if text in stages:
            current = text
            continue
        if not text or set(text) <= {"="} or text.startswith("GLSL Compiler failed") or text.startswith("GLSL Linker failed"):
            continue
        m = _LOG_LINE.match(text)
        if current is not None and m:
            where = stages[current].locate(int(m.group(1)), int(m.group(2)))
            messages.append(f"{where} ({current.replace('_', ' ')}): {m.group(3)}")
        else:
            messages.append(f"({current.replace('_', ' ') if current else 'link'}): {text}")
    return "; ".join(messages) if messages else log.strip()


def build_program(ctx, vertex: str, fragment: str | None = None, *, defines: dict | None = None, varyings=(),
                  loader=None, geometry: str | None = None):
    """Compile and link a program from files of ``glsl/``.

    ``loader(name) -> str`` replaces :func:`shader_source` (your own files,
    tests).  ``geometry`` names an optional geometry shader file.  Raises :class:`ShaderError` whose message names the file, the
    stage and the line of each compiler error.
    """

    loader = shader_source if loader is None else loader
    stages = {"vertex_shader": assemble(vertex, defines, loader=loader)}
    if fragment is not None:
        stages["fragment_shader"] = assemble(fragment, defines, loader=loader)
    if geometry is not None:
        stages["geometry_shader"] = assemble(geometry, defines, loader=loader)
    try:
        return ctx.program(**{k: v.source for k, v in stages.items()}, varyings=list(varyings))
    except moderngl.Error as exc:
        names = " + ".join(x for x in (vertex, geometry, fragment) if x)
        raise ShaderError(f"GLSL {names} failed: {_translate_log(str(exc), stages)}") from None


#: the version compute shaders are written for (``glsl/*.comp``; GL >= 4.3 only)
COMPUTE_VERSION = "#version 430 core"


def build_compute(ctx, name: str, *, defines: dict | None = None, loader=None):
    """Compile a compute shader from a file of ``glsl/`` (GL >= 4.3; the
    caller checks ``ctx.version_code``).  ``AXIAL_COMPUTE`` is defined, so
    shared files leave out their vertex attributes.  Raises
    :class:`ShaderError` naming the file and line of each compiler error."""

    loader = shader_source if loader is None else loader
    stage = assemble(name, {"AXIAL_COMPUTE": 1, **(defines or {})}, loader=loader)
    stage.source = COMPUTE_VERSION + stage.source[len(GLSL_VERSION):]
    try:
        return ctx.compute_shader(stage.source)
    except moderngl.Error as exc:
        raise ShaderError(f"GLSL {name} failed: {_translate_log(str(exc), {'compute_shader': stage})}") from None
