// lighting.glsl -- the light model shared by scene.frag and ground.frag, so
// instances and the ground plane read as one scene.
//   a sun from u_light_dir in u_light_color (Lambert, slightly wrapped so
//   shadowed sides keep their shape), a hemisphere ambient (u_sky_color
//   above, u_bounce_color from the ground below) and a faint Blinn-Phong
//   highlight.  The colours are axialdeform.Look's (core/look.py: a warm
//   sun, a cool sky, a warm bounce by default), set by every program.
// All colours are linear RGB; to_srgb() encodes the result for display.

uniform vec3 u_light_color;   // Look.light_color
uniform vec3 u_sky_color;     // Look.sky_color
uniform vec3 u_bounce_color;  // Look.ground_color

// base: surface colour; n: unit normal facing the viewer; to_eye: unit vector
// to the camera; light: unit vector to the sun; up: world up;
// ambient: share of ambient light (0..1); specular: highlight strength;
// sun: 0..1, how much of the sun reaches the point (1 unshadowed, else a
// shadow map's visibility); the sky/bounce ambient is never shadowed.
vec3 shade_surface_shadowed(vec3 base, vec3 n, vec3 to_eye, vec3 light, vec3 up, float ambient, float specular,
                            float sun) {
    float ndl = dot(n, light);
    float diffuse = clamp((ndl + 0.15) / 1.15, 0.0, 1.0) * sun;   // a little wrap
    float sky = 0.5 + 0.5 * dot(n, up);
    vec3 amb = ambient * mix(u_bounce_color, u_sky_color, sky);
    vec3 h = normalize(light + to_eye);
    float spec = specular * sun * pow(max(dot(n, h), 0.0), 24.0) * step(0.0, ndl);
    return base * (amb + (1.0 - ambient) * 1.15 * diffuse * u_light_color) + spec * u_light_color;
}

vec3 shade_surface(vec3 base, vec3 n, vec3 to_eye, vec3 light, vec3 up, float ambient, float specular) {
    return shade_surface_shadowed(base, n, to_eye, light, up, ambient, specular, 1.0);
}

vec3 to_srgb(vec3 linear) {
    return pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2));
}
