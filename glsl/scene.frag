// scene.frag -- a sun (directional light) + hemisphere ambient + a faint highlight.
//   u_mode 0 "solid": the analytic normals from the vertex shader;
//   u_mode 1 "flat": the face normal of the deformed triangle, from the
//            screen-space derivatives of the world position;
//   u_mode 2 "wireframe": unlit line colour;
//   u_mode 3 the fill of a hidden-line wireframe: the solid shading, washed
//            out towards white, under the lines (so dense instances still
//            read as shapes).
// The base colour is u_color, or the instance's own colour when the program
// is built with AXIAL_TINT (the optional per-instance tint buffer).
// AXIAL_MATERIAL (gl/material.py): base colour = factor * vertex colour *
// texture (an sRGB texture, so samples are linear) [* tint]; alpha mode
// 0 OPAQUE, 1 MASK (discard below the cutoff), 2 BLEND (alpha kept; the
// renderer draws those parts last, unsorted); a tangent-space normal map;
// the back of a face is lit as its front only where the material is
// double-sided.
#include "lighting.glsl"

uniform int u_mode;
uniform vec3 u_color;       // base colour (linear RGB)
uniform vec3 u_line_color;
uniform float u_line_alpha; // lines over a hidden-line fill are blended (1: opaque)
uniform vec3 u_light_dir;   // unit vector towards the light, world space
uniform vec3 u_up;          // world up, for the hemisphere ambient
uniform vec3 u_eye;         // camera position, world space
uniform float u_ambient;    // share of the ambient light, 0 .. 1

in vec3 v_world;
in vec3 v_normal;
flat in float v_shade;
#ifdef AXIAL_TINT
flat in vec3 v_tint;
#endif

#ifdef AXIAL_MATERIAL
in vec2 v_uv;
in vec4 v_color;
in vec4 v_tangent;
uniform vec4 u_base_color;  // linear RGBA factor
uniform bool u_has_texture;
uniform sampler2D u_texture;
uniform int u_alpha_mode;
uniform float u_alpha_cutoff;
uniform bool u_double_sided;
uniform bool u_has_normal_map;
uniform sampler2D u_normal_map;
#endif
#ifdef AXIAL_SHADOW
#include "shadow.glsl"
#endif

out vec4 f_color;

void main() {
#ifdef AXIAL_MATERIAL
    vec4 base4 = u_base_color * v_color;
    if (u_has_texture) base4 *= texture(u_texture, v_uv);
    if (u_alpha_mode == 1 && base4.a < u_alpha_cutoff) discard;
    if (u_alpha_mode != 2) base4.a = 1.0;
#else
    vec4 base4 = vec4(u_color, 1.0);
#endif
#ifdef AXIAL_TINT
    base4.rgb *= v_tint;
#endif
    if (u_mode == 2) {
        f_color = vec4(u_line_color, u_line_alpha);
        return;
    }
    vec3 n = (u_mode == 1) ? normalize(cross(dFdx(v_world), dFdy(v_world))) : normalize(v_normal);
    vec3 to_eye = normalize(u_eye - v_world);
#ifdef AXIAL_MATERIAL
    bool flip = u_double_sided && dot(n, to_eye) < 0.0;
    if (flip) n = -n;
    if (u_has_normal_map && u_mode == 0) {
        vec3 t = normalize(v_tangent.xyz - n * dot(n, v_tangent.xyz));
        vec3 b = cross(n, t) * v_tangent.w * (flip ? -1.0 : 1.0);
        vec3 m = texture(u_normal_map, v_uv).xyz * 2.0 - 1.0;
        n = normalize(mat3(t, b, n) * m);
    }
#else
    // two-sided: light the side that faces the camera (thin leaves)
    if (dot(n, to_eye) < 0.0) n = -n;
#endif
    float sun = 1.0;
#ifdef AXIAL_SHADOW
    sun = shadow_visibility(v_world, n, u_light_dir);
#endif
    vec3 lit = shade_surface_shadowed(base4.rgb * v_shade, n, to_eye, u_light_dir, u_up, u_ambient, 0.12, sun);
    if (u_mode == 3) lit = mix(lit, vec3(1.0), 0.6);
    f_color = vec4(to_srgb(lit), base4.a);
}
