// scene.vert -- one instanced draw of the base mesh, every instance bent by
// its own control axis.  Also the capture program (transform feedback of
// v_world and v_normal): what is drawn is exactly what is captured.
// What the instances of this build do not use is left out of it (the same picture, less vertex work):
// 16-number records have no twist or taper (the page picks its build by the record's width too); AXIAL_WIND
// (defined only while a wind blows; the page's builds always: its wind is a uniform switch) keeps the wind
#ifndef AXIAL_EXTENDED
#define AXIAL_NO_TURN 1
#endif
#ifdef AXIAL_AXES
#define AXIAL_TREE_WALK 1  // several axes: main walks them; the storage below main's declarations
#endif
#include "axial.glsl"
// the wind: moves control points from uniforms alone (no per-frame upload)
#include "wind.glsl"
// AXIAL_QUANTIZED: the 32-byte instance record and its decode
#include "quantized.glsl"

uniform mat4 u_view;        // pyrr layout, uploaded as-is: clip = u_proj * u_view * world
uniform mat4 u_proj;
#ifdef AXIAL_THREE
// the web page: the axis and the wind are the npm module's uniforms (js/src/mesh.js, wind.js), by
// its names and from its mesh: one naming of them in JavaScript
#define u_frame axialFrame
#define u_lo axialLo
#define u_len axialLen
#define u_center axialCenter
#define u_axes_frame axialFrames
#define u_axes_lo axialLos
#define u_axes_len axialLens
#define u_axes_anchor axialAnchors
#define u_axes_parent axialParents
#define u_axes_offsets axialChildren
// wind names: ---- written by tools/make_tables.py from axialdeform/core/wind.py: edit the table, then rerun it ----
#define u_wind_dir axialWindDir
#define u_wind_strength axialWindStrength
#define u_wind_gust axialWindGust
#define u_wind_cycles axialWindCycles
#define u_wind_wavenumber axialWindWavenumber
// wind names: ---- end of what tools/make_tables.py writes ----
#endif
#ifdef AXIAL_FRAME
uniform mat3 u_frame;       // a chosen axis frame: u_frame * v = local coordinates (axis first)
#define AXIAL_AXIS u_frame
#else
uniform int u_axis;         // control axis of the base mesh: 0 x, 1 y, 2 z
#define AXIAL_AXIS u_axis
#endif
uniform float u_lo;         // min coordinate along the axis
uniform float u_len;        // L = max - min along the axis
uniform vec2 u_center;      // the axis line: bounding-box centre across the axis (twist/taper turn about it)
// wind (docs/wind.md); u_wind_strength == 0 is the still scene; AXIAL_WIND_ARGS: them, as wind.glsl's functions take them
// wind uniforms: ---- written by tools/make_tables.py from axialdeform/core/wind.py: edit the table, then rerun it ----
uniform vec3 u_wind_dir;         // unit direction, world
uniform float u_wind_strength;   // tip displacement, in units of L; 0: still
uniform float u_wind_gust;       // gustiness
uniform vec2 u_wind_cycles;      // (fract(f T), fract(2.31 f T)), computed on the CPU
uniform float u_wind_wavenumber; // 1 / gust wavelength (world units), 0: no travelling fronts
#define AXIAL_WIND_ARGS u_wind_dir, u_wind_strength, u_wind_gust, u_wind_cycles, u_wind_wavenumber
// wind uniforms: ---- end of what tools/make_tables.py writes ----
uniform int u_instance_base;     // index of the first instance drawn (capture works in chunks)

#ifdef AXIAL_THREE
// the web page: the npm module's AxialInstancedMesh (js/src/mesh.js) holds the instances, and
// three.js binds its attributes by name: the base mesh's position and normal, each instance's
// rigid part as instanceMatrix = T(p) R(angles) S(s) and the bend's numbers (float32)
in vec3 position;
in vec3 normal;
in mat4 instanceMatrix;
in vec4 axialD12;
in vec4 axialD34;
in vec2 axialD5;
in vec2 axialTwistTaper;    // tw tp (0 0 for 16 numbers)
in vec3 axialAngles;        // rx ry rz: R of instanceMatrix, as angles (the wind's push wants R^T)
#define in_position position
#define in_normal normal
#else
in vec3 in_position;        // base mesh, model units
in vec3 in_normal;          // unit vertex normal
#endif
#ifdef AXIAL_AXES
// several axes (AXIAL_AXES = K): the vertex's axis, every axis's frame, lo, L and parent, and
// the child axes' offsets in a texture fetched by instance id (axial.glsl, axial_child_offsets)
#ifdef AXIAL_THREE
in float axialAxis;
#define in_axis axialAxis
#else
in float in_axis;
#endif
uniform mat3 u_axes_frame[AXIAL_AXES];
uniform float u_axes_lo[AXIAL_AXES];
uniform float u_axes_len[AXIAL_AXES];
uniform float u_axes_anchor[AXIAL_AXES];  // each child axis's joint, t on its own axis (the wind leaves it)
uniform int u_axes_parent[AXIAL_AXES];
uniform sampler2D u_axes_offsets;
#endif

// the instanced attribute buffer (divisor 1): the 16 numbers (quantized:
// quantized.glsl's i_q*, and these are not declared -- WebGL 2 counts every
// declared attribute against its 16)
#if !defined(AXIAL_QUANTIZED) && !defined(AXIAL_THREE)
in vec4 i_d12;
in vec4 i_d34;
in vec2 i_d5;
in vec3 i_position;
in vec3 i_angles;
#endif
#ifdef AXIAL_CULLED
in int i_index;             // the instance's index before culling (the records come from cull.geom)
#define AXIAL_INSTANCE_ID i_index
#else
uniform int u_slice_base;   // the first instance of this draw (a slice of the instances, gl/renderer.py); 0 else
#define AXIAL_INSTANCE_ID (gl_InstanceID + u_slice_base)
#endif
#if defined(AXIAL_EXTENDED) && !defined(AXIAL_QUANTIZED) && !defined(AXIAL_THREE)
in vec3 i_extra;            // s tw tp: extended instances (19 numbers)
#endif
#ifdef AXIAL_TINT
#ifdef AXIAL_THREE
in vec3 instanceColor;      // AxialInstancedMesh's tint: three's instanceColor (the record's tr tg tb)
#define i_tint instanceColor
#else
in vec3 i_tint;             // a second instanced buffer: the instance's tint (linear RGB; the record's
                            // tr tg tb, or AxialRenderer.set_tint)
#endif
flat out vec3 v_tint;
#endif

#ifdef AXIAL_MATERIAL
// the mesh's appearance (gl/material.py): texture coordinates, linear vertex
// colour and tangent (xyz, handedness w); they do not bend, the tangent does
in vec2 in_uv;
in vec4 in_color;
in vec4 in_tangent;
out vec2 v_uv;
out vec4 v_color;
out vec4 v_tangent;         // world tangent (by J, then R) + handedness
#endif

out vec3 v_world;           // world position
out vec3 v_normal;          // world normal (analytic)
flat out float v_shade;     // per-instance brightness variation, 0.85 .. 1.15

// the id of an instance's wind phase: its index, or (AXIAL_POSITION_IDS: a generated layer's instances,
// whose index changes as tiles come and go) its lasting identity from where it stands (wind.glsl)
#ifdef AXIAL_POSITION_IDS
#define AXIAL_PHASE_ID axial_position_id(inst.position)
#else
#define AXIAL_PHASE_ID uint(AXIAL_INSTANCE_ID + u_instance_base)
#endif

float instance_hash(int i) {
    uint h = uint(i) * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = (h >> 22u) ^ h;
    return float(h) / 4294967295.0;
}

#ifdef AXIAL_AXES
// the walk's storage (axial.glsl): the uniform arrays and the offsets' texture above
void axial_tree_axis(int j, out mat3 frame, out float lo, out float len, out float anchor, out int parent) {
    frame = u_axes_frame[j];
    lo = u_axes_lo[j];
    len = u_axes_len[j];
    anchor = u_axes_anchor[j];
    parent = u_axes_parent[j];
}
void axial_tree_offsets(int id, int k, out vec4 d12, out vec4 d34, out vec2 d5) {
    axial_child_offsets(u_axes_offsets, id, k, AXIAL_AXES, d12, d34, d5);
}
#endif

void main() {
#ifdef AXIAL_THREE
    // s = |first column of R S| (R orthonormal); 16-number records: s = 1, tw = tp = 0
    AxialInstance inst = AxialInstance(axialD12, axialD34, axialD5, instanceMatrix[3].xyz, axialAngles,
                                       length(instanceMatrix[0].xyz), axialTwistTaper.x, axialTwistTaper.y);
#elif defined(AXIAL_QUANTIZED)
    AxialInstance inst = axial_dequantize();
#elif defined(AXIAL_EXTENDED)
    AxialInstance inst = AxialInstance(i_d12, i_d34, i_d5, i_position, i_angles, i_extra.x, i_extra.y, i_extra.z);
#else
    AxialInstance inst = axial_instance(i_d12, i_d34, i_d5, i_position, i_angles);
#endif
#ifdef AXIAL_AXES
    vec3 push = vec3(0.0);  // the wind's push per unit of axis length: every child axis's
#endif
#ifdef AXIAL_WIND
    if (u_wind_strength != 0.0) {
#ifdef AXIAL_AXES
        push = axial_wind_push(inst, AXIAL_PHASE_ID, 1.0, AXIAL_WIND_ARGS);
#endif
        inst = axial_wind(inst, AXIAL_PHASE_ID, AXIAL_AXIS, u_len, AXIAL_WIND_ARGS);
    }
#endif
#ifdef AXIAL_AXES
    mat3 jac;
#ifdef AXIAL_WIND
    AxialTreeWind tree_wind = AxialTreeWind(true, push);
#else
    AxialTreeWind tree_wind = AxialTreeWind(false, push);
#endif
    axial_tree_world(in_position, in_normal, int(in_axis + 0.5), AXIAL_AXES, u_center, inst,
                     AXIAL_INSTANCE_ID + u_instance_base, tree_wind, v_world, v_normal, jac);
#else
    axial_world(in_position, in_normal, AXIAL_AXIS, u_lo, u_len, u_center, inst, v_world, v_normal);
#endif
#ifdef AXIAL_MATERIAL
    v_uv = in_uv;
    v_color = in_color;
#ifdef AXIAL_AXES
    v_tangent = vec4(normalize(axial_rotation(inst.angles) * (jac * in_tangent.xyz)), in_tangent.w);
#else
    v_tangent = vec4(axial_world_tangent(in_position, in_tangent.xyz, AXIAL_AXIS, u_lo, u_len, u_center, inst),
                     in_tangent.w);
#endif
#endif
#ifdef AXIAL_POSITION_IDS
    v_shade = 0.85 + 0.3 * instance_hash(int(axial_position_id(inst.position)));
#else
    v_shade = 0.85 + 0.3 * instance_hash(AXIAL_INSTANCE_ID);
#endif
#ifdef AXIAL_TINT
    v_tint = i_tint;
#endif
    gl_Position = u_proj * u_view * vec4(v_world, 1.0);
}
