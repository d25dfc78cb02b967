"""The GLSL loader: #include with #line kept, cycles refused, compile errors
name the file, the stage and the line; ONE deformation function everywhere."""

from pathlib import Path

import pytest

import axialdeform as ad
from axialdeform.gl.shaders import assemble, build_program

ROOT = Path(__file__).resolve().parents[2]


def loader_from(files):
    def load(name):
        if name not in files:
            raise ad.core.ShaderError(f"glsl/{name}: no such shader file")
        return files[name]

    return load


def test_include_keeps_line_numbers():
    files = {"main.vert": "// one\n#include \"lib.glsl\"\nvoid main() {}\n", "lib.glsl": "float f() { return 1.0; }\n"}
    out = assemble("main.vert", {"FOO": 2}, loader=loader_from(files))
    lines = out.source.splitlines()
    assert lines[0] == "#version 330 core" and lines[1] == "#define FOO 2"
    assert out.files == ["main.vert", "lib.glsl"]
    assert "#line 1 1" in lines and "#line 3 0" in lines
    assert lines[lines.index("#line 3 0") + 1] == "void main() {}"


def test_include_cycle_is_refused():
    files = {"a.glsl": '#include "b.glsl"\n', "b.glsl": '#include "a.glsl"\n'}
    with pytest.raises(ad.core.ShaderError, match=r"cycle: a.glsl -> b.glsl -> a.glsl"):
        assemble("a.glsl", loader=loader_from(files))


def test_version_in_an_included_file_is_refused():
    with pytest.raises(ad.core.ShaderError, match="lib.glsl, line 1: remove #version"):
        assemble("m.vert", loader=loader_from({"m.vert": '#include "lib.glsl"\n', "lib.glsl": "#version 330\n"}))


def test_compile_error_names_file_stage_and_line(ctx, monkeypatch):
    import axialdeform.gl.shaders as S

    files = {
        "bad.vert": '#include "lib.glsl"\nin vec3 p;\nvoid main() { gl_Position = vec4(f(p), 1.0); }\n',
        "lib.glsl": "// helper\n\nvec3 f(vec3 p) {\n    return p * undefined_thing;\n}\n",
        "ok.frag": "out vec4 c;\nvoid main() { c = vec4(1.0); }\n",
    }
    monkeypatch.setattr(S, "shader_source", loader_from(files))
    monkeypatch.setattr(S.assemble, "__defaults__", (None, loader_from(files)))
    with pytest.raises(ad.core.ShaderError) as err:
        build_program(ctx, "bad.vert", "ok.frag")
    msg = str(err.value)
    assert "glsl/lib.glsl, line 4" in msg and "vertex shader" in msg and "undefined_thing" in msg


def test_the_deformation_lives_in_one_glsl_file():
    """Every program includes glsl/axial.glsl; no other shader evaluates the curve."""
    sources = {p.name: p.read_text() for p in (ROOT / "glsl").iterdir() if p.suffix in (".glsl", ".vert", ".frag")}
    defining = [n for n, t in sources.items() if "void axial_bend(" in t or "mat3 axial_rotation(" in t]
    assert defining == ["axial.glsl"]
    users = [n for n, t in sources.items() if "axial_world(" in t and n != "axial.glsl"]
    assert users and all('#include "axial.glsl"' in sources[n] for n in users)
    assert ad.deformation_glsl() == sources["axial.glsl"]


def test_users_can_compile_their_own_shader_with_the_deformation(ctx):
    src = ad.deformation_glsl()
    prog = ctx.program(vertex_shader="#version 330 core\n" + src + """
in vec3 p;
out vec3 w;
out vec3 n;
void main() {
    AxialInstance inst = axial_instance(vec4(0.0), vec4(0.0), vec2(0.0), vec3(1.0, 2.0, 3.0), vec3(0.0));
    axial_world(p, vec3(0.0, 0.0, 1.0), 0, 0.0, 1.0, inst, w, n);
    gl_Position = vec4(w, 1.0);
}
""", varyings=["w"])
    prog.release()
