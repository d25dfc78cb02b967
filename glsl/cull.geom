// cull.geom -- keeps the instances cull.vert marked (vs_keep != 0): one
// point in, zero or one point out, captured by transform feedback into the
// compacted instance buffer (o_* varyings, interleaved, in this order).
layout(points) in;
layout(points, max_vertices = 1) out;

#ifndef AXIAL_QUANTIZED
flat in vec4 vs_d12[];
flat in vec4 vs_d34[];
flat in vec2 vs_d5[];
flat in vec3 vs_position[];
flat in vec3 vs_angles[];
flat out vec4 o_d12;
flat out vec4 o_d34;
flat out vec2 o_d5;
flat out vec3 o_position;
flat out vec3 o_angles;
#ifdef AXIAL_EXTENDED
flat in vec3 vs_extra[];
flat out vec3 o_extra;
#endif
#else
flat in uvec2 vs_q0[];
flat in uvec2 vs_q1[];
flat in uvec2 vs_q2[];
flat in uvec2 vs_q3[];
flat out uvec2 o_q0;
flat out uvec2 o_q1;
flat out uvec2 o_q2;
flat out uvec2 o_q3;
#ifdef AXIAL_EXTENDED
flat in uvec2 vs_q4[];
flat out uvec2 o_q4;
#endif
#endif
flat in int vs_index[];
flat out int o_index;
#ifdef AXIAL_TINT
flat in vec3 vs_tint[];
flat out vec3 o_tint;
#endif
flat in int vs_keep[];

void main() {
    if (vs_keep[0] == 0) return;
#ifndef AXIAL_QUANTIZED
    o_d12 = vs_d12[0];
    o_d34 = vs_d34[0];
    o_d5 = vs_d5[0];
    o_position = vs_position[0];
    o_angles = vs_angles[0];
#ifdef AXIAL_EXTENDED
    o_extra = vs_extra[0];
#endif
#else
    o_q0 = vs_q0[0];
    o_q1 = vs_q1[0];
    o_q2 = vs_q2[0];
    o_q3 = vs_q3[0];
#ifdef AXIAL_EXTENDED
    o_q4 = vs_q4[0];
#endif
#endif
    o_index = vs_index[0];
#ifdef AXIAL_TINT
    o_tint = vs_tint[0];
#endif
    gl_Position = gl_in[0].gl_Position;
    EmitVertex();
    EndPrimitive();
}
