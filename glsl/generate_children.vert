// generate_children.vert -- the child axes' offsets of instance gl_VertexID of a tile (a mesh of several
// axes), AXIAL_CHILD_AXES_A_PASS axes a pass (slot.glsl: u_first on; past the last: zeros), by transform
// feedback (axialdeform.gl.generate): 10 numbers an axis, axis after axis, d1u, d1v, ..., d5v.
#include "axial.glsl"
#include "wind.glsl"
#include "generate.glsl"

uniform uint u_seed;
uniform ivec2 u_tile;
uniform int u_first;       // the pass's first child axis (1, 7, 13, ...)
uniform int u_children_n;  // K - 1
uniform sampler2D u_children;

#define AXIAL_CHILD_WRITE 1
#include "slot.glsl"

void main() {
    uint key = axial_gen_key(u_seed, u_tile);
    float o[10 * AXIAL_CHILD_AXES_A_PASS];
    for (int k = 0; k < AXIAL_CHILD_AXES_A_PASS; ++k) {
        int j = u_first + k;
        vec2 d[5];
        for (int q = 0; q < 5; ++q) d[q] = vec2(0.0);
        if (j <= u_children_n) axial_generate_child(key, gl_VertexID, j, u_children, d);
        for (int q = 0; q < 5; ++q) {
            o[10 * k + 2 * q] = d[q].x;
            o[10 * k + 2 * q + 1] = d[q].y;
        }
    }
    axial_child_write(o);
    gl_Position = vec4(0.0);
}
