// lighting.glsl -- the light model shared by scene.frag and ground.frag, so
// instances and the ground plane read as one scene.
//   a warm sun from u_light_dir (Lambert, slightly wrapped so shadowed sides
//   keep their shape), a hemisphere ambient (cool sky above, warm bounce
//   from the ground below) and a faint Blinn-Phong highlight.
// All colours are linear RGB; to_srgb() encodes the result for display.

const vec3 SUN_COLOR = vec3(1.0, 0.96, 0.88);
const vec3 SKY_COLOR = vec3(0.80, 0.88, 1.05);
const vec3 BOUNCE_COLOR = vec3(0.50, 0.44, 0.38);

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
    vec3 amb = ambient * mix(BOUNCE_COLOR, SKY_COLOR, sky);
    vec3 h = normalize(light + to_eye);
    float spec = specular * sun * pow(max(dot(n, h), 0.0), 24.0) * step(0.0, ndl);
    return base * (amb + (1.0 - ambient) * 1.15 * diffuse * SUN_COLOR) + spec * SUN_COLOR;
}

vec3 shade_surface(vec3 base, vec3 n, vec3 to_eye, vec3 light, vec3 up, float ambient, float specular) {
    return shade_surface_shadowed(base, n, to_eye, light, up, ambient, specular, 1.0);
}

vec3 to_srgb(vec3 linear) {
    return pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2));
}
