// generate_children.vert -- the child axes' offsets of instance gl_VertexID of a tile (a mesh of several
// axes), six axes a pass (u_first .. u_first + 5; past the last: zeros), by transform feedback
// (axialdeform.gl.generate): 60 numbers an instance, axis after axis, d1u, d1v, ..., d5v.
#include "axial.glsl"
#include "wind.glsl"
#include "generate.glsl"

uniform uint u_seed;
uniform ivec2 u_tile;
uniform int u_first;       // the pass's first child axis (1, 7, 13, ...)
uniform int u_children_n;  // K - 1
uniform sampler2D u_children;

out vec4 c_0;
out vec4 c_1;
out vec4 c_2;
out vec4 c_3;
out vec4 c_4;
out vec4 c_5;
out vec4 c_6;
out vec4 c_7;
out vec4 c_8;
out vec4 c_9;
out vec4 c_10;
out vec4 c_11;
out vec4 c_12;
out vec4 c_13;
out vec4 c_14;

void main() {
    uint key = axial_gen_key(u_seed, u_tile);
    float o[60];
    for (int k = 0; k < 6; ++k) {
        int j = u_first + k;
        vec2 d[5];
        for (int q = 0; q < 5; ++q) d[q] = vec2(0.0);
        if (j <= u_children_n) axial_generate_child(key, gl_VertexID, j, u_children, d);
        for (int q = 0; q < 5; ++q) {
            o[10 * k + 2 * q] = d[q].x;
            o[10 * k + 2 * q + 1] = d[q].y;
        }
    }
    c_0 = vec4(o[0], o[1], o[2], o[3]);
    c_1 = vec4(o[4], o[5], o[6], o[7]);
    c_2 = vec4(o[8], o[9], o[10], o[11]);
    c_3 = vec4(o[12], o[13], o[14], o[15]);
    c_4 = vec4(o[16], o[17], o[18], o[19]);
    c_5 = vec4(o[20], o[21], o[22], o[23]);
    c_6 = vec4(o[24], o[25], o[26], o[27]);
    c_7 = vec4(o[28], o[29], o[30], o[31]);
    c_8 = vec4(o[32], o[33], o[34], o[35]);
    c_9 = vec4(o[36], o[37], o[38], o[39]);
    c_10 = vec4(o[40], o[41], o[42], o[43]);
    c_11 = vec4(o[44], o[45], o[46], o[47]);
    c_12 = vec4(o[48], o[49], o[50], o[51]);
    c_13 = vec4(o[52], o[53], o[54], o[55]);
    c_14 = vec4(o[56], o[57], o[58], o[59]);
    gl_Position = vec4(0.0);
}
