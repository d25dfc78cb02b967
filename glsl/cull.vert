// cull.vert -- the per-instance culling (and LOD choice) pass.  One point per
// instance, the instance records read as ordinary (divisor 0) attributes; the
// geometry shader cull.geom keeps the points with vs_keep != 0 and transform
// feedback writes them, compacted and in their original order, into the
// buffer the draw then reads (docs/culling.md).  The records are passed
// through bit for bit, with the instance's original index (and tint).
// With LOD, a second stage (AXIAL_CULL_INDEXED) reads the first pass's
// output and keeps, once per level, the instances of that level.
#include "axial.glsl"
#include "quantized.glsl"
#include "bounds.glsl"
#include "cull.glsl"

uniform int u_level;          // -1: keep every visible instance; k: only the visible ones whose LOD level is k

#ifndef AXIAL_QUANTIZED
in vec4 i_d12;
in vec4 i_d34;
in vec2 i_d5;
in vec3 i_position;
in vec3 i_angles;
flat out vec4 vs_d12;
flat out vec4 vs_d34;
flat out vec2 vs_d5;
flat out vec3 vs_position;
flat out vec3 vs_angles;
#ifdef AXIAL_EXTENDED
in vec3 i_extra;              // s tw tp
flat out vec3 vs_extra;
#endif
#else
flat out uvec2 vs_q0;         // two uint16 per uint: the 32-byte record, byte for byte
flat out uvec2 vs_q1;
flat out uvec2 vs_q2;
flat out uvec2 vs_q3;
#ifdef AXIAL_EXTENDED
flat out uvec2 vs_q4;         // s tw tp as three uint16, then the record's two bytes of padding (0)
#endif
#endif
#ifdef AXIAL_TINT
in vec3 i_tint;
flat out vec3 vs_tint;
#endif
#ifdef AXIAL_CULL_INDEXED
in int i_index;               // second stage (LOD): the records come from the first pass, with their index
#endif
flat out int vs_index;
flat out int vs_keep;

void main() {
#ifdef AXIAL_QUANTIZED
    AxialInstance inst = axial_dequantize();
    vs_q0 = uvec2(i_q0.x | (i_q0.y << 16u), i_q0.z | (i_q0.w << 16u));
    vs_q1 = uvec2(i_q1.x | (i_q1.y << 16u), i_q1.z | (i_q1.w << 16u));
    vs_q2 = uvec2(i_q2.x | (i_q2.y << 16u), i_q2.z | (i_q2.w << 16u));
    vs_q3 = uvec2(i_q3.x | (i_q3.y << 16u), i_q3.z | (i_q3.w << 16u));
#ifdef AXIAL_EXTENDED
    vs_q4 = uvec2(i_q4.x | (i_q4.y << 16u), i_q4.z);
#endif
#elif defined(AXIAL_EXTENDED)
    AxialInstance inst = AxialInstance(i_d12, i_d34, i_d5, i_position, i_angles, i_extra.x, i_extra.y, i_extra.z);
    vs_d12 = i_d12;
    vs_d34 = i_d34;
    vs_d5 = i_d5;
    vs_position = i_position;
    vs_angles = i_angles;
    vs_extra = i_extra;
#else
    AxialInstance inst = axial_instance(i_d12, i_d34, i_d5, i_position, i_angles);
    vs_d12 = i_d12;
    vs_d34 = i_d34;
    vs_d5 = i_d5;
    vs_position = i_position;
    vs_angles = i_angles;
#endif
#ifdef AXIAL_TINT
    vs_tint = i_tint;
#endif
#ifdef AXIAL_CULL_INDEXED
    vs_index = i_index;
#else
    vs_index = gl_VertexID;
#endif
    int level = axial_cull_level(inst);
    vs_keep = (level >= 0 && (u_level < 0 || level == u_level)) ? 1 : 0;
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
