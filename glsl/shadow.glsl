// shadow.glsl -- the key light's shadow map (gl/shadow.py), shared by
// scene.frag and ground.frag.  A depth map rendered from the sun with an
// orthographic camera around the instances; sampled with hardware depth
// comparison and a 3x3 percentage-closer filter for soft edges.

uniform sampler2DShadow u_shadow_map;
uniform mat4 u_light_matrix;    // world -> light clip space (column-major, as uploaded)
uniform float u_shadow_offset;  // world units: push the lookup along the normal (acne)
uniform float u_shadow_texel;   // 1 / shadow map size

// 1: the sun reaches the point; 0: in shadow; between: the filtered edge.
float shadow_visibility(vec3 world, vec3 n, vec3 light) {
    float cos_l = clamp(dot(n, light), 0.0, 1.0);
    vec3 p_world = world + n * u_shadow_offset * (1.5 - cos_l);
    vec4 c = u_light_matrix * vec4(p_world, 1.0);
    vec3 p = c.xyz / c.w * 0.5 + 0.5;
    if (p.x <= 0.0 || p.x >= 1.0 || p.y <= 0.0 || p.y >= 1.0 || p.z >= 1.0) return 1.0;
    float bias = 0.0015;
    float sum = 0.0;
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            sum += texture(u_shadow_map, vec3(p.xy + vec2(dx, dy) * u_shadow_texel, p.z - bias));
    return sum / 9.0;
}
