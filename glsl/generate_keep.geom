// generate_keep.geom -- one slot in, the kept one out (generate_keep.vert says what a pass writes).
layout(points) in;
layout(points, max_vertices = 1) out;

flat in vec4 vs_0[];
flat in vec4 vs_1[];
flat in vec4 vs_2[];
flat in vec4 vs_3[];
flat in vec3 vs_4[];
flat in vec3 vs_tint[];
flat in ivec3 vs_cell[];
flat in int vs_keep[];

#ifdef AXIAL_KEEP_RECORD
flat out vec4 o_0;
flat out vec4 o_1;
flat out vec4 o_2;
flat out vec4 o_3;
#ifdef AXIAL_EXTENDED
flat out vec3 o_4;
#endif
#endif
#ifdef AXIAL_KEEP_TINT
flat out vec3 o_tint;
#endif
#ifdef AXIAL_KEEP_CELL
flat out ivec3 o_cell;
#endif

void main() {
    if (vs_keep[0] == 0) return;
#ifdef AXIAL_KEEP_RECORD
    o_0 = vs_0[0];
    o_1 = vs_1[0];
    o_2 = vs_2[0];
    o_3 = vs_3[0];
#ifdef AXIAL_EXTENDED
    o_4 = vs_4[0];
#endif
#endif
#ifdef AXIAL_KEEP_TINT
    o_tint = vs_tint[0];
#endif
#ifdef AXIAL_KEEP_CELL
    o_cell = vs_cell[0];
#endif
    gl_Position = gl_in[0].gl_Position;
    EmitVertex();
    EndPrimitive();
}
