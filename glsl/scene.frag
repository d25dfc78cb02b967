// scene.frag -- directional light + hemisphere ambient.
//   u_mode 0 "solid": the analytic normals from the vertex shader;
//   u_mode 1 "flat": the face normal of the deformed triangle, from the
//            screen-space derivatives of the world position;
//   u_mode 2 "wireframe": unlit line colour.
uniform int u_mode;
uniform vec3 u_color;       // base colour (linear RGB)
uniform vec3 u_line_color;
uniform vec3 u_light_dir;   // unit vector towards the light, world space
uniform vec3 u_up;          // world up, for the hemisphere ambient
uniform vec3 u_eye;         // camera position, world space
uniform float u_ambient;

in vec3 v_world;
in vec3 v_normal;
flat in float v_shade;

out vec4 f_color;

void main() {
    if (u_mode == 2) {
        f_color = vec4(u_line_color, 1.0);
        return;
    }
    vec3 n = (u_mode == 1) ? normalize(cross(dFdx(v_world), dFdy(v_world))) : normalize(v_normal);
    // two-sided: light the side that faces the camera (thin leaves)
    if (dot(n, u_eye - v_world) < 0.0) n = -n;
    float diffuse = max(dot(n, u_light_dir), 0.0);
    float sky = 0.5 + 0.5 * dot(n, u_up);
    vec3 ambient = u_ambient * mix(vec3(0.55, 0.5, 0.45), vec3(0.9, 0.95, 1.05), sky);
    vec3 lit = u_color * v_shade * (ambient + (1.0 - u_ambient) * diffuse * vec3(1.0, 0.97, 0.9));
    f_color = vec4(pow(clamp(lit, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
