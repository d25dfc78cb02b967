// ground.vert -- a square ground plane across the world up axis, built from
// gl_VertexID (4 vertices, triangle strip; no vertex buffer).  Drawn by
// axialdeform.ground.GroundPlane, apart from the instanced draw call.
uniform mat4 u_view;        // pyrr layout: clip = u_proj * u_view * world
uniform mat4 u_proj;
uniform vec3 u_center;      // centre of the square, world units (on the plane)
uniform vec3 u_axis_u;      // unit vectors spanning the plane
uniform vec3 u_axis_v;
uniform float u_radius;     // half the side, world units

out vec3 v_world;
out vec2 v_plane;           // -1 .. 1 across the square

void main() {
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
    v_plane = corner;
    v_world = u_center + u_radius * (corner.x * u_axis_u + corner.y * u_axis_v);
    gl_Position = u_proj * u_view * vec4(v_world, 1.0);
}
