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

uniform vec4 u_planes[6];     // world-space frustum planes, unit normals, inside: dot(n, x) + d >= 0
uniform vec3 u_bound_center;  // base mesh bounding-box centre (model units)
uniform float u_radius;       // largest distance of a vertex (of any LOD level) from u_center
uniform int u_level;          // -1: keep every visible instance; k: only the visible ones whose LOD level is k
uniform int u_levels;         // LOD levels (1..4)
uniform float u_lod_error[4]; // geometric error of each level, model units (level 0: 0)
uniform vec3 u_eye;           // camera position (world)
uniform float u_px_scale;     // pixels per world unit at distance 1 (perspective) or everywhere (orthographic)
uniform bool u_ortho;
uniform float u_lod_px;       // allowed screen-space error, pixels
uniform float u_wind_reach;   // how far the wind can move a control point (model units), 0: still

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

// The LOD level of an instance whose bounding sphere is `sphere`: the
// coarsest level whose error, projected at the sphere's nearest point to
// the eye, is at most u_lod_px pixels (errors are model units: times |s|).
int axial_lod_level(vec4 sphere, float scale) {
    float px = abs(scale) * (u_ortho ? u_px_scale : u_px_scale / max(length(sphere.xyz - u_eye) - sphere.w, 1e-6));
    int level = 0;
    for (int k = 1; k < 4; ++k) {
        if (k < u_levels && u_lod_error[k] * px <= u_lod_px) level = k;
    }
    return level;
}

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
    vec4 sphere = axial_bound_sphere(inst, u_bound_center, u_radius, u_wind_reach);
    bool keep = axial_sphere_visible(sphere, u_planes);
    if (keep && u_level >= 0) keep = axial_lod_level(sphere, inst.scale) == u_level;
    vs_keep = keep ? 1 : 0;
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
