// axial.glsl -- THE axial deformation of axialdeform, shared by every program.
//
// Pull it in with an include directive of "axial.glsl" (after #version).  It declares no
// inputs or uniforms: callers pass the base mesh's axis and one instance.
// Conventions (docs/method.md):
//   axis a in {0,1,2}; t = clamp((v[a] - lo) / len, 0, 1);
//   offsets d1..d5 are 2-component, in the two other coordinates in
//   increasing order (x -> (y,z), y -> (x,z), z -> (x,y));
//   V' = V + E(sum B4_i(t) d_{i+1});  n' = normalize(n - e_a (D'(t).n) / len);
//   R = Rz(rz) * Ry(ry) * Rx(rx);  W = R V' + p;  world normal = R n'.
// Defining AXIAL_NO_BEND before the include keeps only the rigid part
// (rotation + position): the "all the same" method of the benchmark.

// The 16 numbers of one instance.
struct AxialInstance {
    vec4 d12;      // d1u d1v d2u d2v
    vec4 d34;      // d3u d3v d4u d4v
    vec2 d5;       // d5u d5v
    vec3 position; // px py pz (world units)
    vec3 angles;   // rx ry rz (radians)
};

// E: place a 2-component offset into the two coordinates across the axis.
vec3 axial_embed(vec2 w, int axis) {
    if (axis == 0) return vec3(0.0, w.x, w.y);
    if (axis == 1) return vec3(w.x, 0.0, w.y);
    return vec3(w.x, w.y, 0.0);
}

// Bend one model-space vertex and its unit normal along the instance's
// 4th-degree Bezier control axis.
void axial_bend(vec3 v, vec3 n, int axis, float lo, float len, AxialInstance inst,
                out vec3 v_out, out vec3 n_out) {
    float t = clamp((v[axis] - lo) / len, 0.0, 1.0);
    float s = 1.0 - t;
    vec2 d1 = inst.d12.xy, d2 = inst.d12.zw, d3 = inst.d34.xy, d4 = inst.d34.zw, d5 = inst.d5;
    // degree-4 Bernstein weights: the displacement D(t)
    vec2 disp = (s * s * s * s) * d1 + (4.0 * t * s * s * s) * d2 + (6.0 * t * t * s * s) * d3
              + (4.0 * t * t * t * s) * d4 + (t * t * t * t) * d5;
    // degree-3 Bernstein weights: the slope D'(t)
    vec2 slope = 4.0 * ((s * s * s) * (d2 - d1) + (3.0 * t * s * s) * (d3 - d2)
                      + (3.0 * t * t * s) * (d4 - d3) + (t * t * t) * (d5 - d4));
    v_out = v + axial_embed(disp, axis);
    n_out = n;
    n_out[axis] -= dot(axial_embed(slope, axis), n) / len;
    n_out = normalize(n_out);
}

// R = Rz(rz) * Ry(ry) * Rx(rx), column-vector convention.
mat3 axial_rotation(vec3 r) {
    vec3 c = cos(r), s = sin(r);
    // GLSL mat3(...) takes columns
    return mat3(
        c.z * c.y,                     s.z * c.y,                     -s.y,
        c.z * s.y * s.x - s.z * c.x,   s.z * s.y * s.x + c.z * c.x,   c.y * s.x,
        c.z * s.y * c.x + s.z * s.x,   s.z * s.y * c.x - c.z * s.x,   c.y * c.x);
}

// The whole map: model-space vertex/normal -> world-space vertex/normal.
void axial_world(vec3 v, vec3 n, int axis, float lo, float len, AxialInstance inst,
                 out vec3 w_out, out vec3 wn_out) {
    vec3 bent_v = v, bent_n = n;
#ifndef AXIAL_NO_BEND
    axial_bend(v, n, axis, lo, len, inst, bent_v, bent_n);
#endif
    mat3 rot = axial_rotation(inst.angles);
    w_out = rot * bent_v + inst.position;
    wn_out = rot * bent_n;
}
