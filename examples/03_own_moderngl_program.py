"""The deformation inside YOUR OWN moderngl program: your buffers, your
camera, your shader -- it only includes "axial.glsl" and calls its functions.

Here the shader colours every vertex by how far its own control axis moved
it (blue: barely bent, orange: strongly bent).  Writes
``03_own_moderngl_program.png`` into --output.

    python examples/03_own_moderngl_program.py
    python examples/03_own_moderngl_program.py --quick

Two ways to bring the deformation into a shader:
* moderngl's include table (used below):
  ``ctx.includes["axial.glsl"] = ad.deformation_glsl()``;
* ``ad.gl.assemble_text(my_source).source``: expands the include yourself and
  keeps ``#line`` numbers, so compiler errors point at your own lines.
"""

import argparse
from pathlib import Path

import moderngl
import numpy as np
import pyrr

import axialdeform as ad
from axialdeform.core import record
from axialdeform.gl.image import parse_size

VERTEX = """
#version 330 core
#include "axial.glsl"

uniform mat4 mvp;           // your own camera: projection * view
uniform int axis;           // the base mesh's control axis (0 x, 1 y, 2 z)
uniform float lo, len;      // its start and length

in vec3 position;           // your own vertex buffer
in vec3 normal;
// the instance record's attributes, as the record table names them (axialdeform.core.record)
in vec4 i_d12; in vec4 i_d34; in vec2 i_d5; in vec3 i_position; in vec3 i_angles;

out vec3 world_normal;
out float bent;             // how far the bend moved this vertex, fraction of len

void main() {
    AxialInstance inst = axial_instance(i_d12, i_d34, i_d5, i_position, i_angles);   // 16 numbers: s = 1, tw = tp = 0
    vec3 v, n;
    axial_bend(position, normal, axis, lo, len, inst, v, n);   // the bend alone
    bent = length(v - position) / len;
    mat3 r = axial_rotation(inst.angles);                       // then rotate and place
    world_normal = r * n;
    gl_Position = mvp * vec4(r * v + inst.position, 1.0);
}
"""

FRAGMENT = """
#version 330 core
in vec3 world_normal;
in float bent;
out vec4 color;
void main() {
    vec3 cold = vec3(0.15, 0.35, 0.75), hot = vec3(0.95, 0.45, 0.10);
    vec3 base = mix(cold, hot, smoothstep(0.02, 0.14, bent));
    float light = 0.35 + 0.65 * max(dot(normalize(world_normal), normalize(vec3(0.4, 1.0, 0.3))), 0.0);
    color = vec4(pow(base * light, vec3(1.0 / 2.2)), 1.0);
}
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default=".", help="folder for the PNG (default: current folder)")
    ap.add_argument("-n", "--count", type=int, default=1000)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--quick", action="store_true", help="200 stones, a small picture (tests)")
    args = ap.parse_args()
    count, (w, h) = (200, (320, 240)) if args.quick else (args.count, parse_size(args.size))

    mesh = ad.load_mesh("stone")
    params = ad.random_params(mesh, count, seed=3, variation=ad.Variation(bend=0.25), placement="disc")   # (count, 16) float32

    ctx = moderngl.create_standalone_context(backend="egl")    # or your window's context
    ctx.includes["axial.glsl"] = ad.deformation_glsl()
    prog = ctx.program(vertex_shader=VERTEX, fragment_shader=FRAGMENT)
    prog["axis"].value = mesh.axis.index
    prog["lo"].value = mesh.axis.lo
    prog["len"].value = mesh.axis.length

    vertices = ctx.buffer(np.hstack([mesh.positions, mesh.normals]).astype("f4").tobytes())
    indices = ctx.buffer(mesh.faces.astype("u4").tobytes())
    instances = ctx.buffer(params.tobytes())                    # 64 bytes an instance, divisor 1
    # the buffer's layout comes from the record table: ("4f", "4f", "2f", "3f", "3f"), ("i_d12", ...)
    formats, names, _ = record.gl_layout(extended=False, quantized=False)
    vao = ctx.vertex_array(prog, [(vertices, "3f 3f", "position", "normal"),
                                  (instances, " ".join(formats) + "/i", *names)],
                           index_buffer=indices, index_element_size=4)

    # your own camera, straight from pyrr
    radius = 1.1 * mesh.axis.length * np.sqrt(count / np.pi)
    view = pyrr.matrix44.create_look_at([1.0 * radius, 1.35 * radius, 1.9 * radius], [0, 0, 0], [0, 1, 0])
    proj = pyrr.matrix44.create_perspective_projection(35.0, w / h, 0.1 * radius, 10.0 * radius)
    prog["mvp"].write((view @ proj).astype("f4").tobytes())      # pyrr layout: row-vector order

    fbo = ctx.simple_framebuffer((w, h))
    fbo.use()
    fbo.clear(0.95, 0.95, 0.93, 1.0)
    ctx.enable(moderngl.DEPTH_TEST)
    vao.render(moderngl.TRIANGLES, instances=count)            # ONE instanced draw call
    image = ad.gl.read_pixels(ctx, fbo)                           # (h, w, 3) uint8, top row first
    assert ctx.error == "GL_NO_ERROR", ctx.error

    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    ad.save_png(out / "03_own_moderngl_program.png", image)
    print(f"wrote {out / '03_own_moderngl_program.png'} ({count} stones, your own shader)")
    ctx.release()


if __name__ == "__main__":
    main()
