// generate.vert -- instance gl_VertexID of a tile by transform feedback (axialdeform.gl.generate):
// no inputs, the slot (slot.glsl) captured from the outputs.  generate.comp (GL >= 4.3) includes it for its
// uniforms and axial_gen_recipe (AXIAL_COMPUTE defined: no outputs, no main).
#include "axial.glsl"
#include "wind.glsl"
#include "generate.glsl"

// ---- written by js/build.mjs from AxialRecipe (glsl/generate.glsl): edit the struct, then `npm run build` in js/ ----
uniform uint u_seed;
uniform int u_m;
uniform float u_cell;
uniform float u_jitter;
uniform float u_bend;
uniform vec2 u_scale;
uniform vec3 u_scale_mid;
uniform vec4 u_scale_odd;
uniform float u_twist;
uniform float u_taper;
uniform float u_anchor_y;
uniform vec4 u_anchor_w;
uniform float u_anchor_w4;
uniform float u_tint;
uniform vec3 u_tint_color;
uniform float u_tint_hue;
uniform bool u_has_heights;
uniform vec2 u_h_lo;
uniform vec2 u_h_inv;
uniform ivec2 u_h_size;
uniform bool u_has_density;
uniform vec2 u_d_lo;
uniform vec2 u_d_inv;
uniform ivec2 u_d_size;
uniform bool u_d_wrap;
uniform vec2 u_altitude;
uniform vec2 u_slope_tan2;
uniform vec2 u_choice;
uniform vec2 u_lift;
uniform float u_align;
uniform vec2 u_anchor_xz;
uniform vec2 u_yaw;
uniform float u_clump_cells;
uniform float u_clump_radius;
uniform float u_clump_core;
uniform float u_clump_core_radius;

// the recipe from the uniforms above
AxialRecipe axial_gen_recipe() {
    return AxialRecipe(u_seed, u_m, u_cell, u_jitter, u_bend, u_scale,
                       u_scale_mid, u_scale_odd, u_twist, u_taper, u_anchor_y, u_anchor_w,
                       u_anchor_w4, u_tint, u_tint_color, u_tint_hue, u_has_heights, u_h_lo,
                       u_h_inv, u_h_size, u_has_density, u_d_lo, u_d_inv, u_d_size,
                       u_d_wrap, u_altitude, u_slope_tan2, u_choice, u_lift, u_align,
                       u_anchor_xz, u_yaw, u_clump_cells, u_clump_radius, u_clump_core, u_clump_core_radius);
}
// ---- end of what js/build.mjs writes ----
uniform sampler2D u_heights;  // unit 0
uniform sampler2D u_density;  // unit 1
uniform ivec2 u_tile;

#ifndef AXIAL_COMPUTE
#define AXIAL_SLOT_WRITE 1
#endif
#include "slot.glsl"

#ifndef AXIAL_COMPUTE
void main() {
    AxialRecipe r = axial_gen_recipe();
    vec4 d12, d34;
    vec2 d5;
    vec3 position, angles, extra, tint;
    float kept;
    axial_generate(r, u_heights, u_density, u_tile, gl_VertexID, d12, d34, d5, position, angles, extra, tint, kept);
    axial_slot_write(d12, d34, d5, position, angles, extra, tint, kept);
    gl_Position = vec4(0.0);
}
#endif
