// ground.frag -- the ground plane: lit like the instances (lighting.glsl),
// a faint grid every u_cell world units, fading into the background colour as
// the view grazes it (towards the horizon, like haze) and towards the edge of
// the square, so it has neither a hard horizon nor a visible edge.
#include "lighting.glsl"
#ifdef AXIAL_SHADOW
#include "shadow.glsl"
#endif

uniform vec3 u_color;       // ground colour (linear RGB)
uniform vec3 u_background;  // colour it fades to (sRGB, as the framebuffer is cleared)
uniform vec3 u_light_dir;   // unit vector towards the light
uniform vec3 u_up;          // world up = the plane's normal
uniform vec3 u_eye;
uniform float u_ambient;
uniform float u_cell;       // grid spacing, world units (0: no grid)
uniform vec3 u_axis_u;
uniform vec3 u_axis_v;
uniform mat4 u_view;        // the camera (as ground.vert): the plane also fades before the far plane
uniform mat4 u_proj;

in vec3 v_world;
in vec2 v_plane;

out vec4 f_color;

void main() {
    vec3 to_eye = normalize(u_eye - v_world);
    vec3 base = u_color;
    if (u_cell > 0.0) {
        vec2 g = vec2(dot(v_world, u_axis_u), dot(v_world, u_axis_v)) / u_cell;
        vec2 w = fwidth(g);
        vec2 line = 1.0 - clamp(abs(fract(g - 0.5) - 0.5) / max(w, 1e-6), 0.0, 1.0);
        base *= 1.0 - 0.12 * max(line.x, line.y) * (1.0 - clamp(max(w.x, w.y) * 2.0, 0.0, 1.0));
    }
    float sun = 1.0;
#ifdef AXIAL_SHADOW
    sun = shadow_visibility(v_world, u_up, u_light_dir);
#endif
    vec3 lit = to_srgb(shade_surface_shadowed(base, u_up, to_eye, u_light_dir, u_up, u_ambient, 0.0, sun));
    float edge = smoothstep(0.55, 1.0, length(v_plane));
    float haze = 1.0 - smoothstep(0.0, 0.16, abs(dot(to_eye, u_up)));  // 1 at the horizon, 0 from ~9 degrees up
    // a camera whose far plane cuts the plane: faded out before it, never a hard edge
    float depth = -(u_view * vec4(v_world, 1.0)).z;
    float far = (u_proj[2][3] != 0.0) ? u_proj[3][2] / (u_proj[2][2] + 1.0) : 1e30;  // perspective: -2fn/(f-n) / ...
    float clip = smoothstep(0.6 * far, 0.95 * far, depth);
    f_color = vec4(mix(lit, u_background, max(max(edge, haze), clip)), 1.0);
}
