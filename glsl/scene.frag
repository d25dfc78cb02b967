// scene.frag -- a sun (directional light) + hemisphere ambient + a faint highlight.
//   u_mode 0 "solid": the analytic normals from the vertex shader;
//   u_mode 1 "flat": the face normal of the deformed triangle, from the
//            screen-space derivatives of the world position;
//   u_mode 2 "wireframe": unlit line colour.
// The base colour is u_color, or the instance's own colour when the program
// is built with AXIAL_TINT (the optional per-instance tint buffer).
#include "lighting.glsl"

uniform int u_mode;
uniform vec3 u_color;       // base colour (linear RGB)
uniform vec3 u_line_color;
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

out vec4 f_color;

void main() {
    if (u_mode == 2) {
        f_color = vec4(u_line_color, 1.0);
        return;
    }
#ifdef AXIAL_TINT
    vec3 base = v_tint;
#else
    vec3 base = u_color;
#endif
    vec3 n = (u_mode == 1) ? normalize(cross(dFdx(v_world), dFdy(v_world))) : normalize(v_normal);
    vec3 to_eye = normalize(u_eye - v_world);
    // two-sided: light the side that faces the camera (thin leaves)
    if (dot(n, to_eye) < 0.0) n = -n;
    vec3 lit = shade_surface(base * v_shade, n, to_eye, u_light_dir, u_up, u_ambient, 0.12);
    f_color = vec4(to_srgb(lit), 1.0);
}
