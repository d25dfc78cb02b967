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
// Extended instances (19 numbers, "s tw tp" after the 16; the extension section of the spec):
//   the cross-section w (the two other coordinates minus the axis line's centre c) turns by
//   theta = tw t and shrinks by k = 1 - tp t:  V'' = V + E(k Rot(theta) w - w) + E(D(t));
//   W = R (s V'') + p;  normal = R normalize(cof(J) n), J = dV''/dV.
//   s = 1, tw = 0, tp = 0 (what axial_instance(...) sets) gives exactly the 16-number result.
// A chosen axis frame (docs/method.md): every function taking `int axis` has a twin taking
//   `mat3 frame` -- the frame F's rows e_a, e_u, e_v as a GLSL mat3 built with
//   transpose(mat3(e_a, e_u, e_v)), i.e. frame * v = local coordinates (F V).  The bend
//   happens in local coordinates along their first one and goes back by F^T:
//   V'' = V + F^T (bend(F V) - F V),  n'' = F^T bendnormal(F n);  lo, len, center are local.
// Defining AXIAL_NO_BEND before the include keeps only the rigid part
// (rotation + position): the "all the same" method of the benchmark.
// What a program's instances do not use is left out of its build, the same numbers without the work:
// AXIAL_NO_TURN (16-number records: no twist or taper), and without AXIAL_WIND a tree's child axes take
// no wind (a program passes AxialTreeWind(false, ...) to axial_tree_world then).

// One instance: the 16 numbers, then the extension's 3 (1, 0, 0 for a 16-number instance).
struct AxialInstance {
    vec4 d12;      // d1u d1v d2u d2v
    vec4 d34;      // d3u d3v d4u d4v
    vec2 d5;       // d5u d5v
    vec3 position; // px py pz (world units)
    vec3 angles;   // rx ry rz (radians)
    float scale;   // s  (> 0): uniform scale in model space, after the bend
    float twist;   // tw (radians over the whole axis): the cross-section at t turns by tw t
    float taper;   // tp (< 1): the cross-section at t is scaled by 1 - tp t
};

// A 16-number instance (s = 1, tw = 0, tp = 0).
AxialInstance axial_instance(vec4 d12, vec4 d34, vec2 d5, vec3 position, vec3 angles) {
    return AxialInstance(d12, d34, d5, position, angles, 1.0, 0.0, 0.0);
}

// (cos x, sin x) to float32 rounding on every GPU -- the builtins' precision is each implementation's (WGSL's
// need only be within 2^-11: SwiftShader's are ~1e-4 off, which would bend a twisted instance by 1e-4 L).
// Reduction by pi/2 (two constants), Taylor polynomials on [-pi/4, pi/4], the quadrant applied exactly
// (axialdeform.core.generate_ground.cos_sin_f32, operation for operation).  The one sine and cosine of
// every program: the bend's twist, the rotation, the wind and the generator.
vec2 axial_cos_sin(float x) {
    float q = floor(x * 0.6366197723675814 + 0.5);
    float r = (x - q * 1.5707963705062866) - q * -4.371139000186243e-8;
    float r2 = r * r;
    float s = r * (r2 * (r2 * (r2 * (r2 * (1.0 / 362880.0) - 1.0 / 5040.0) + 1.0 / 120.0) - 1.0 / 6.0) + 1.0);
    float c = r2 * (r2 * (r2 * (r2 * (r2 * (-1.0 / 3628800.0) + 1.0 / 40320.0) - 1.0 / 720.0) + 1.0 / 24.0) - 0.5) + 1.0;
    float m = q - 4.0 * floor(q * 0.25);
    bool odd = m == 1.0 || m == 3.0;
    float cs = odd ? s : c, sn = odd ? c : s;
    return vec2((m == 1.0 || m == 2.0) ? -cs : cs, m >= 1.5 ? -sn : sn);
}

// E: place a 2-component offset into the two coordinates across the axis.
vec3 axial_embed(vec2 w, int axis) {
    if (axis == 0) return vec3(0.0, w.x, w.y);
    if (axis == 1) return vec3(w.x, 0.0, w.y);
    return vec3(w.x, w.y, 0.0);
}

// The displacement D(t) = sum B4_i(t) d_{i+1}: degree-4 Bernstein weights of the five offsets.
vec2 axial_curve(float t, vec4 d12, vec4 d34, vec2 d5) {
    float s = 1.0 - t;
    vec2 d1 = d12.xy, d2 = d12.zw, d3 = d34.xy, d4 = d34.zw;
    return (s * s * s * s) * d1 + (4.0 * t * s * s * s) * d2 + (6.0 * t * t * s * s) * d3
         + (4.0 * t * t * t * s) * d4 + (t * t * t * t) * d5;
}

// The slope D'(t) of the displacement: degree-3 Bernstein weights of the offsets' differences.
vec2 axial_slope(float t, vec4 d12, vec4 d34, vec2 d5) {
    float s = 1.0 - t;
    vec2 d1 = d12.xy, d2 = d12.zw, d3 = d34.xy, d4 = d34.zw;
    return 4.0 * ((s * s * s) * (d2 - d1) + (3.0 * t * s * s) * (d3 - d2)
                + (3.0 * t * t * s) * (d4 - d3) + (t * t * t) * (d5 - d4));
}

vec2 axial_slope(float t, AxialInstance inst) {
    return axial_slope(t, inst.d12, inst.d34, inst.d5);
}

// The twist and taper of the cross-section at t: w (the two coordinates across the axis minus the
// axis line's centre) turns by theta = tw t and shrinks by k = 1 - tp t.  Gives k, (cos, sin) of
// theta and the turned rw = Rot(theta) w; exactly no change for tw = tp = 0.
// AXIAL_NO_TURN (a program whose instances are all 16-number records): the turn is left out of the build,
// the same numbers (k = 1, cs = (1, 0), rw = w are what tw = tp = 0 give) without the vertex work.
void axial_turn(float t, vec2 w, AxialInstance inst, out float k, out vec2 cs, out vec2 rw) {
#ifdef AXIAL_NO_TURN
    k = 1.0;
    cs = vec2(1.0, 0.0);
    rw = w;
#else
    k = 1.0 - inst.taper * t;
    cs = axial_cos_sin(inst.twist * t);
    rw = vec2(cs.x * w.x - cs.y * w.y, cs.y * w.x + cs.x * w.y);
#endif
}

// g = dV''_across/dt of the turned cross-section: D'(t) + k tw Rot(w turned by 90 degrees) - tp Rot w
// (without D'(t) where `slope` is zero).
vec2 axial_turn_rate(vec2 slope, float k, vec2 rw, AxialInstance inst) {
#ifdef AXIAL_NO_TURN
    return slope;
#else
    return slope + ((k * inst.twist) * vec2(-rw.y, rw.x) - inst.taper * rw);
#endif
}

// The two coordinates across the axis (the inverse of axial_embed).
vec2 axial_across(vec3 v, int axis) {
    if (axis == 0) return v.yz;
    if (axis == 1) return v.xz;
    return v.xy;
}

// Bend one model-space vertex and its unit normal along the instance's
// 4th-degree Bezier control axis, twisting and tapering the cross-section
// about the axis line through `center` (the bounding-box centre of the base
// mesh in the two other coordinates, in offset component order).
void axial_bend(vec3 v, vec3 n, int axis, float lo, float len, vec2 center, AxialInstance inst,
                out vec3 v_out, out vec3 n_out) {
    float t = clamp((v[axis] - lo) / len, 0.0, 1.0);
    vec2 disp = axial_curve(t, inst.d12, inst.d34, inst.d5);
    vec2 slope = axial_slope(t, inst);
    float k;
    vec2 cs, rw, w = axial_across(v, axis) - center;
    axial_turn(t, w, inst, k, cs, rw);
    v_out = v + axial_embed(k * rw - w, axis) + axial_embed(disp, axis);
    // cof(J) n / k: across = Rot n_across, along = k n_a - g . (Rot n_across) / len
    vec2 nw = axial_across(n, axis);
    vec2 g = axial_turn_rate(slope, k, rw, inst);
    n_out = axial_embed(vec2(cs.x * nw.x - cs.y * nw.y, cs.y * nw.x + cs.x * nw.y), axis);
    n_out[axis] = k * n[axis];
    n_out[axis] -= dot(axial_embed(g, axis), n_out) / len;
    n_out = normalize(n_out);
}

// The 16-number form (no axis line needed: without twist and taper it does not matter).
void axial_bend(vec3 v, vec3 n, int axis, float lo, float len, AxialInstance inst,
                out vec3 v_out, out vec3 n_out) {
    axial_bend(v, n, axis, lo, len, vec2(0.0), inst, v_out, n_out);
}

// R = Rz(rz) * Ry(ry) * Rx(rx), column-vector convention.
mat3 axial_rotation(vec3 r) {
    vec2 x = axial_cos_sin(r.x), y = axial_cos_sin(r.y), z = axial_cos_sin(r.z);
    vec3 c = vec3(x.x, y.x, z.x), s = vec3(x.y, y.y, z.y);
    // GLSL mat3(...) takes columns
    return mat3(
        c.z * c.y,                     s.z * c.y,                     -s.y,
        c.z * s.y * s.x - s.z * c.x,   s.z * s.y * s.x + c.z * c.x,   c.y * s.x,
        c.z * s.y * c.x + s.z * s.x,   s.z * s.y * c.x - c.z * s.x,   c.y * c.x);
}

// The rigid part: a bent model-space vertex and normal placed in the world, W = R (s V'') + p.
void axial_place(vec3 bent_v, vec3 bent_n, AxialInstance inst, out vec3 w_out, out vec3 wn_out) {
    mat3 rot = axial_rotation(inst.angles);
    w_out = rot * (inst.scale * bent_v) + inst.position;
    wn_out = rot * bent_n;
}

// A bent normal or tangent placed by m, the columns of R or s R: the unit normalize(m d).
vec3 axial_place_direction(mat3 m, vec3 d) {
    return normalize(m * d);
}

// The rigid part as an engine's instance matrix holds it -- m the columns of s R, p the position, made on the
// CPU in double precision (three's instanceMatrix): W = m V'' + p, the world normal normalize(m n'').
void axial_place_matrix(vec3 bent_v, vec3 bent_n, mat3 m, vec3 p, out vec3 w_out, out vec3 wn_out) {
    w_out = m * bent_v + p;
    wn_out = axial_place_direction(m, bent_n);
}

// The whole map: model-space vertex/normal -> world-space vertex/normal.
// `center`: the axis line (see axial_bend); W = R (s V'') + p.
void axial_world(vec3 v, vec3 n, int axis, float lo, float len, vec2 center, AxialInstance inst,
                 out vec3 w_out, out vec3 wn_out) {
    vec3 bent_v = v, bent_n = n;
#ifndef AXIAL_NO_BEND
    axial_bend(v, n, axis, lo, len, center, inst, bent_v, bent_n);
#endif
    axial_place(bent_v, bent_n, inst, w_out, wn_out);
}

// The 16-number call of earlier versions: right for any instance without twist
// and taper (the axis line only matters for those).
void axial_world(vec3 v, vec3 n, int axis, float lo, float len, AxialInstance inst,
                 out vec3 w_out, out vec3 wn_out) {
    axial_world(v, n, axis, lo, len, vec2(0.0), inst, w_out, wn_out);
}

// A surface tangent (normal mapping) through the same map: a tangent is a
// differential of the position, so it transforms by the Jacobian J = dV''/dV
// of the extended bend (the normal above by cof(J)):
//   across = k Rot(theta) T_across + g T_a / len,  along = T_a,
//   g = D'(t) + k tw Rot(w rotated by 90 degrees) - tp Rot w  (as in axial_bend),
// then by R (the uniform scale s drops out after normalising).  Returns the unit
// world tangent.  Wind moves the control points, so a wind-moved instance
// (axial_wind) gives its tangent here too.
// The model-space part of axial_world_tangent (before R; not normalised).
vec3 axial_bend_tangent(vec3 v, vec3 tangent, int axis, float lo, float len, vec2 center,
                        AxialInstance inst) {
    vec3 bent = tangent;
#ifndef AXIAL_NO_BEND
    float t = clamp((v[axis] - lo) / len, 0.0, 1.0);
    float k;
    vec2 cs, rw;
    axial_turn(t, axial_across(v, axis) - center, inst, k, cs, rw);
    vec2 g = axial_turn_rate(axial_slope(t, inst), k, rw, inst);
    vec2 tw = axial_across(tangent, axis);
    bent = axial_embed(k * vec2(cs.x * tw.x - cs.y * tw.y, cs.y * tw.x + cs.x * tw.y)
                       + g * (tangent[axis] / len), axis);
    bent[axis] = tangent[axis];
#endif
    return bent;
}

vec3 axial_world_tangent(vec3 v, vec3 tangent, int axis, float lo, float len, vec2 center,
                         AxialInstance inst) {
    return normalize(axial_rotation(inst.angles) * axial_bend_tangent(v, tangent, axis, lo, len, center, inst));
}

// ---- the same map for a chosen axis frame (frame * v = F V: local coordinates, axis first) ----

// The two coordinates across a framed axis (e_u . v, e_v . v).
vec2 axial_across(vec3 v, mat3 frame) {
    return (frame * v).yz;
}

void axial_bend(vec3 v, vec3 n, mat3 frame, float lo, float len, vec2 center, AxialInstance inst,
                out vec3 v_out, out vec3 n_out) {
    vec3 l = frame * v, lv, ln;
    axial_bend(l, frame * n, 0, lo, len, center, inst, lv, ln);
    v_out = v + transpose(frame) * (lv - l);  // zero offsets: exactly v
    n_out = transpose(frame) * ln;
}

void axial_world(vec3 v, vec3 n, mat3 frame, float lo, float len, vec2 center, AxialInstance inst,
                 out vec3 w_out, out vec3 wn_out) {
    vec3 bent_v = v, bent_n = n;
#ifndef AXIAL_NO_BEND
    axial_bend(v, n, frame, lo, len, center, inst, bent_v, bent_n);
#endif
    axial_place(bent_v, bent_n, inst, w_out, wn_out);
}

// The model-space part of axial_world_tangent for a framed axis (before R; not normalised).
vec3 axial_bend_tangent(vec3 v, vec3 tangent, mat3 frame, float lo, float len, vec2 center, AxialInstance inst) {
    return transpose(frame) * axial_bend_tangent(frame * v, frame * tangent, 0, lo, len, center, inst);
}

vec3 axial_world_tangent(vec3 v, vec3 tangent, mat3 frame, float lo, float len, vec2 center,
                         AxialInstance inst) {
    return normalize(axial_rotation(inst.angles) * axial_bend_tangent(v, tangent, frame, lo, len, center, inst));
}

// The 16-number form of axial_world_tangent (no twist/taper: the axis line does not matter).
vec3 axial_world_tangent(vec3 v, vec3 tangent, int axis, float lo, float len, AxialInstance inst) {
    return axial_world_tangent(v, tangent, axis, lo, len, vec2(0.0), inst);
}

// ---- several axes in a hierarchy (docs/method.md, "Several axes"): define AXIAL_AXES K ----
// Axis j moves a vertex by F_j^T E(D_j(t_j)) and adds F_j^T E(D_j'(t_j)) (x) e_a,j / L_j to the
// Jacobian where t_j is not clamped; a vertex sums its own axis and every ancestor's (the chain),
// each at the vertex itself; n' = normalize(cof(J) n).  Scale, twist and taper act about axis 0's
// axis line before the displacements.  `frame * v` = axis j's local coordinates (axis first).

// A vertex's own axis spans it exactly (t in [0, 1]); float32 rounding must not drop its slope, so
// "clamped" (a vertex beyond an ancestor axis's end: no derivative) means beyond this slack.
const float AXIAL_T_SLACK = 1e-4;

// Add axis (frame, lo, len)'s displacement of model-space v, and its Jacobian term, to disp and jac.
void axial_axis_add(vec3 v, mat3 frame, float lo, float len, vec4 d12, vec4 d34, vec2 d5,
                    inout vec3 disp, inout mat3 jac) {
    float raw = ((frame * v).x - lo) / len;
    float t = clamp(raw, 0.0, 1.0);
    mat3 back = transpose(frame);  // columns e_a, e_u, e_v
    disp += back * vec3(0.0, axial_curve(t, d12, d34, d5));
    if (raw >= -AXIAL_T_SLACK && raw <= 1.0 + AXIAL_T_SLACK) {
        jac += outerProduct(back * vec3(0.0, axial_slope(t, d12, d34, d5) / len), back[0]);
    }
}

// cof(J) n: the columns of cof(J) are the cross products of pairs of J's columns.
vec3 axial_cofactor(mat3 j, vec3 n) {
    return n.x * cross(j[1], j[2]) + n.y * cross(j[2], j[0]) + n.z * cross(j[0], j[1]);
}

// A tree's twist and taper, about axis 0's axis line (frame f0, lo0, len0; `center` as in axial_bend),
// before the displacements: adds the turn of the cross-section to `moved` and sets `jac` to its Jacobian.
void axial_tree_turn(vec3 v, mat3 f0, float lo0, float len0, vec2 center, AxialInstance inst,
                     inout vec3 moved, inout mat3 jac) {
    vec3 l = f0 * v;
    float raw = (l.x - lo0) / len0;
    float t = clamp(raw, 0.0, 1.0);
    float k;
    vec2 cs, rw, w = l.yz - center;
    axial_turn(t, w, inst, k, cs, rw);
    moved += transpose(f0) * vec3(0.0, k * rw - w);
    vec2 g = (raw >= -AXIAL_T_SLACK && raw <= 1.0 + AXIAL_T_SLACK)
           ? axial_turn_rate(vec2(0.0), k, rw, inst) / len0 : vec2(0.0);
    mat3 jl = mat3(vec3(1.0, g), vec3(0.0, k * cs.x, k * cs.y), vec3(0.0, -k * cs.y, k * cs.x));  // columns
    jac = transpose(f0) * jl * f0;
}

// A child axis's offsets as the wind moves them: `wind`, the push per unit of axis length in the model frame
// (axial_wind_push with len 1), moves axis (frame, len) by len times its part across the axis on the control
// polygon of (t - a)^2 / max(a^2, (1 - a)^2), a the anchor (its joint stays; a = 0: c = (0, 0, 1/6, 1/2, 1)).
void axial_anchor_wind(mat3 frame, float len, float a, vec3 wind, inout vec4 d12, inout vec4 d34, inout vec2 d5) {
    vec2 u = len * (frame * wind).yz / max(a * a, (1.0 - a) * (1.0 - a));
    d12 += vec4(u * (a * a), u * (a * a - 0.5 * a));
    d34 += vec4(u * (1.0 / 6.0 - a + a * a), u * (0.5 - 1.5 * a + a * a));
    d5 += u * ((1.0 - a) * (1.0 - a));
}

// The texture of the child axes' offsets: instance id's axis k (1..K-1) is the three texels from
// (id (K-1) + k - 1) 3 on, rows AXIAL_AXES_ROW texels wide (RGBA32F):
// d1u d1v d2u d2v | d3u d3v d4u d4v | d5u d5v 0 0.
const int AXIAL_AXES_ROW = 4095;

// the first of instance id's three texels of child axis k (of a mesh of `axes` axes), and where texel i lies
int axial_child_texel(int id, int k, int axes) {
    return (id * (axes - 1) + k - 1) * 3;
}
ivec2 axial_texel_at(int i) {
    return ivec2(i % AXIAL_AXES_ROW, i / AXIAL_AXES_ROW);
}
// the index of the texel at `at` (axial_texel_at's inverse: a storage buffer of the same texels reads it)
int axial_texel_index(ivec2 at) {
    return at.y * AXIAL_AXES_ROW + at.x;
}

// instance id's offsets of child axis k (of a mesh of `axes` axes) as stored in `tex` with the layout above
// (what a program's axial_tree_offsets reads)
void axial_child_offsets(sampler2D tex, int id, int k, int axes, out vec4 d12, out vec4 d34, out vec2 d5) {
    ivec2 at = axial_texel_at(axial_child_texel(id, k, axes));
    d12 = texelFetch(tex, at, 0);
    d34 = texelFetch(tex, at + ivec2(1, 0), 0);
    d5 = texelFetch(tex, at + ivec2(2, 0), 0).xy;
}

// ---- the walk up a vertex's chain of axes: a program that draws several axes defines AXIAL_TREE_WALK before
// the include and then the two functions declared here (after it), reading its own storage -- uniform arrays
// and a texture in GL and WebGL 2, a texture or a storage buffer in the node functions generated from this file.
#ifdef AXIAL_TREE_WALK
// Axis j's frame, lo, L, anchor (t of its joint on its own axis) and parent (-1: the root).
void axial_tree_axis(int j, out mat3 frame, out float lo, out float len, out float anchor, out int parent);
// Instance id's offsets of child axis k (1..K-1), as stored (before the wind).
void axial_tree_offsets(int id, int k, out vec4 d12, out vec4 d34, out vec2 d5);

// The wind on a tree's child axes: `push`, the wind's push per unit of axis length in the instance's model
// frame (axial_wind_push with len 1), moves every child axis j by L_j times its part across that axis on the
// control polygon of (t - a)^2 / max(a^2, (1 - a)^2), a its anchor (its joint stays; a = 0:
// c = (0, 0, 1/6, 1/2, 1)).  `on` false (a still program): no wind, and no work for it.
struct AxialTreeWind {
    bool on;
    vec3 push;
};

// A vertex's axes from its code (AxisTree.vertex_code): its own axis b, a second axis b1 and the blend's
// weight w of b1 (0: none), code = b + 64 b1 + 4096 q, w = q / 2047.
void axial_tree_code(int code, out int b, out int b1, out float w) {
    b = code % 64;
    b1 = (code / 64) % 64;
    w = float(code / 4096) / 2047.0;
}

// Add to disp and jac the bend of v by the chain of axis b (b and its ancestors), every axis's offsets
// weighed by `weight` (the bend is linear in them).
void axial_tree_chain(vec3 v, int b, float weight, int axes, AxialInstance inst, int id, AxialTreeWind wind,
                      inout vec3 disp, inout mat3 jac) {
    int j = b;
    for (int guard = 0; guard < axes; ++guard) {
        if (j < 0) break;
        mat3 frame;
        float lo, len, anchor;
        int parent;
        axial_tree_axis(j, frame, lo, len, anchor, parent);
        vec4 d12 = inst.d12, d34 = inst.d34;
        vec2 d5 = inst.d5;
        if (j > 0) {
            axial_tree_offsets(id, j, d12, d34, d5);
            if (wind.on) axial_anchor_wind(frame, len, anchor, wind.push, d12, d34, d5);
        }
        axial_axis_add(v, frame, lo, len, weight * d12, weight * d34, weight * d5, disp, jac);
        j = parent;
    }
}

// The bend of a K-axis mesh (`axes` = K) in model space: v (its axes' code, axial_tree_code) and n -> v_out,
// n_out and the Jacobian jac_out (for tangents).  inst: axis 0's offsets (wind already applied) and the rigid
// part; id: the instance (its child axes' offsets, axial_tree_offsets).  A blended vertex moves by (1 - w)
// times its own chain's bend plus w times b1's.
void axial_tree_bend(vec3 v, vec3 n, int code, int axes, vec2 center, AxialInstance inst, int id, AxialTreeWind wind,
                     out vec3 v_out, out vec3 n_out, out mat3 jac_out) {
    vec3 moved = v;
    mat3 jac = mat3(1.0);
#ifndef AXIAL_NO_BEND
#ifndef AXIAL_NO_TURN
    if (inst.twist != 0.0 || inst.taper != 0.0) {  // about axis 0's axis line, before the displacements
        mat3 f0;
        float lo0, len0, a0;
        int p0;
        axial_tree_axis(0, f0, lo0, len0, a0, p0);
        axial_tree_turn(v, f0, lo0, len0, center, inst, moved, jac);
    }
#endif
    vec3 disp = vec3(0.0);
    int b, b1;
    float w;
    axial_tree_code(code, b, b1, w);
    axial_tree_chain(v, b, 1.0 - w, axes, inst, id, wind, disp, jac);
    if (w > 0.0) axial_tree_chain(v, b1, w, axes, inst, id, wind, disp, jac);
    moved += disp;
#endif
    v_out = moved;
    n_out = normalize(axial_cofactor(jac, n));
    jac_out = jac;
}

// The whole map of a K-axis mesh: model-space v (its axes' code) and n -> world w_out, wn_out (axial_tree_bend,
// then axial_place), and the model-space Jacobian jac_out.
void axial_tree_world(vec3 v, vec3 n, int code, int axes, vec2 center, AxialInstance inst, int id, AxialTreeWind wind,
                      out vec3 w_out, out vec3 wn_out, out mat3 jac_out) {
    vec3 bent_v, bent_n;
    axial_tree_bend(v, n, code, axes, center, inst, id, wind, bent_v, bent_n, jac_out);
    axial_place(bent_v, bent_n, inst, w_out, wn_out);
}
#endif
