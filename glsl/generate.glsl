// generate.glsl -- a generated layer's instance: a pure function of (the recipe, its seed, the tile,
// the index), docs/generate.md; the numpy reference is axialdeform.core.generate (the tests hold
// this file to it: hash bit-exact, numbers to float32 rounding).
//
// Include after "axial.glsl" and "wind.glsl" (axial_wind_hash, the PCG hash).  Declares no inputs:
// callers pass the recipe.  Conventions (docs/generate.md):
//   tile (tx, tz) covers [tx T, (tx+1) T) x [tz T, (tz+1) T); m x m cells of side c = T / m;
//   instance i stands in cell (i mod m, i div m), jittered by j = 1 - min_distance / c; or, in clumps, in a disc
//   of radius R around the parent of its s x s cells;
//   offsets d = bend L (2 u - 1), every control point minus D(t_a) (t_a: the anchor on the axis);
//   u_k = (H(key ^ (32 i + k)) >> 8) / 2^24,  key = H(H(H(uint tx) ^ uint tz) ^ seed);
//   the ground: a height map (triangles as the terrain mesh's) or y = 0; kept: inside the height map,
//   u16 < the density map's nearest pixel, the height in the altitude band, tan^2 of the slope in its band,
//   u20 in this mesh's share (a layer of several meshes); the tint tint_color (1 - tint (u17 + hue ((u17, u18, u19) - u17))).

struct AxialRecipe {
    uint seed;
    int m;           // cells a side of a tile
    float cell;      // c = T / m
    float jitter;    // j = 1 - min_distance / c
    float bend;      // bend L: offsets in [-bend L, bend L]
    vec2 scale;      // lo, hi (1, 1: none)
    vec3 scale_mid;  // q1, q2, q3: the scale at u13 = 1/4, 1/2, 3/4, piecewise linear between (q1 < 0: uniform)
    vec4 scale_odd;  // o1, o3, o5, o7: at u13 = 1/8, 3/8, 5/8, 7/8 too (o1 < 0: five knots)
    float twist;     // tw in [-twist, twist]
    float taper;     // tp in [0, taper]
    float anchor_y;  // the anchor's y on the base mesh (bottom: its lowest y): it stands on the ground
    vec4 anchor_w;   // B4_0..3(t_a): the anchor's place on the axis (D(t_a) = 0: it stays put)
    float anchor_w4; // B4_4(t_a)
    float tint;      // 0: none; else tint_color (1 - tint u_{17+c})
    vec3 tint_color;
    float tint_hue;  // how far each channel's u goes its own way (0: one u, tint_color's hue kept)
    // the ground's height map (its texture: world heights, texel (col, row)); has_heights false: y = 0
    bool has_heights;
    vec2 h_lo;       // the grid's first vertex (x0, z0)
    vec2 h_inv;      // (cols - 1) / width, (rows - 1) / depth
    ivec2 h_size;    // cols, rows
    // the density map (its texture: grey levels in [0, 1]) over [d_lo, d_lo + size); repeated if d_wrap
    bool has_density;
    vec2 d_lo;
    vec2 d_inv;      // cols / width, rows / depth
    ivec2 d_size;
    bool d_wrap;
    vec2 altitude;   // kept where lo <= height <= hi
    vec2 slope_tan2; // kept where lo <= tan^2 of the ground's slope <= hi
    vec2 choice;     // kept where lo <= u20 < hi: this mesh's share of a layer of several meshes
    vec2 lift;       // an extra height lo + (hi - lo) u21 (world units)
    float align;     // align_to_normal: the turn toward the ground's normal, a fraction of its angle
    vec2 anchor_xz;  // the anchor's x, z on the base mesh (with anchor_y: the point that rests on the ground)
    vec2 yaw;        // the turn about up lo + (hi - lo) u2 (radians)
    float clump_cells;  // clumps: 8 parents to every s x s cells (s = clump_cells; 1 and no radius: none)
    float clump_radius; // clumps: each instance uniform in a disc of this radius around its parent
    float clump_core;   // clumps: the share of a clump's instances in its core (u25 < clump_core)
    float clump_core_radius;  // clumps: the core's radius (<= clump_radius)
};

// atan2(y, x) to a few float32 ulps on every GPU (Cephes' atanf: reduction to [0, tan(pi/8)], its polynomial).
float axial_gen_atan2(float y, float x) {
    float ax = abs(x), ay = abs(y);
    if (ax == 0.0 && ay == 0.0) return 0.0;
    bool swap = ay > ax;
    float t = swap ? ax / ay : ay / ax;  // in [0, 1]
    float base = 0.0;
    if (t > 0.41421356237309503) { base = 0.7853981633974483; t = (t - 1.0) / (t + 1.0); }
    float z = t * t;
    float a = (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1) * z * t + t + base;
    if (swap) a = 1.5707963267948966 - a;
    if (x < 0.0) a = 3.141592653589793 - a;
    return y < 0.0 ? -a : a;
}

// The turn of an instance that leans toward the ground's normal (gradient grad) by the fraction r.align,
// after its turn ry about up: R = Rt(k, align angle(up, n)) Ry(ry), k = up x n / |up x n|, as Euler
// angles (rx, ry, rz) of R = Rz Ry Rx (axialdeform.core.transforms.angles_from_matrices), and (R a).y.
vec3 axial_gen_lean(AxialRecipe r, float ry, vec2 grad, out float ay) {
    float inv = inversesqrt(grad.x * grad.x + 1.0 + grad.y * grad.y);
    vec3 n = vec3(-grad.x, 1.0, -grad.y) * inv;
    float sn = sqrt(n.x * n.x + n.z * n.z);
    vec3 k = sn > 1e-12 ? vec3(n.z, 0.0, -n.x) / sn : vec3(0.0);
    vec2 ta = axial_cos_sin(axial_gen_atan2(sn, n.y) * r.align);
    vec2 ty = axial_cos_sin(ry);
    // Rt = I + sin K + (1 - cos) K^2 (Rodrigues), K the cross-product matrix of k (k.y = 0)
    float c1 = 1.0 - ta.x;
    mat3 rt = mat3(1.0 - c1 * k.z * k.z, ta.y * k.z, c1 * k.x * k.z,       // column 0
                   -ta.y * k.z, 1.0 - c1 * (k.x * k.x + k.z * k.z), ta.y * k.x,  // column 1
                   c1 * k.x * k.z, -ta.y * k.x, 1.0 - c1 * k.x * k.x);      // column 2
    mat3 ryM = mat3(ty.x, 0.0, -ty.y, 0.0, 1.0, 0.0, ty.y, 0.0, ty.x);
    mat3 m = rt * ryM;  // m[col][row]
    float cy = sqrt(m[0][0] * m[0][0] + m[0][1] * m[0][1]);
    vec3 angles = cy < 1e-9 ? vec3(axial_gen_atan2(-m[2][1], m[1][1]), axial_gen_atan2(-m[0][2], cy), 0.0)
                            : vec3(axial_gen_atan2(m[1][2], m[2][2]), axial_gen_atan2(-m[0][2], cy),
                                   axial_gen_atan2(m[0][1], m[0][0]));
    ay = m[0][1] * r.anchor_xz.x + m[1][1] * r.anchor_y + m[2][1] * r.anchor_xz.y;
    return angles;
}

// The ground's height at xz on the height map's triangles (the terrain mesh's: (r,c),(r+1,c),(r,c+1)
// and (r,c+1),(r+1,c),(r+1,c+1)), its gradient, and whether xz is over the map.
float axial_gen_height(AxialRecipe r, sampler2D heights, vec2 xz, out vec2 grad, out bool inside) {
    vec2 g = (xz - r.h_lo) * r.h_inv;
    vec2 last = vec2(r.h_size - 1);
    inside = all(greaterThanEqual(g, vec2(0.0))) && all(lessThanEqual(g, last));
    g = clamp(g, vec2(0.0), last);
    ivec2 c = min(ivec2(floor(g)), r.h_size - 2);
    vec2 f = g - vec2(c);
    float h00 = texelFetch(heights, c, 0).r, h01 = texelFetch(heights, c + ivec2(1, 0), 0).r;
    float h10 = texelFetch(heights, c + ivec2(0, 1), 0).r, h11 = texelFetch(heights, c + ivec2(1, 1), 0).r;
    if (f.x + f.y <= 1.0) {
        grad = vec2(h01 - h00, h10 - h00) * r.h_inv;
        return h00 + f.x * (h01 - h00) + f.y * (h10 - h00);
    }
    grad = vec2(h11 - h10, h11 - h01) * r.h_inv;
    return h11 + (1.0 - f.x) * (h10 - h11) + (1.0 - f.y) * (h01 - h11);
}

// The density map's nearest pixel under xz (clamped at its edges, or repeated).
float axial_gen_density(AxialRecipe r, sampler2D density, vec2 xz) {
    ivec2 c = ivec2(floor((xz - r.d_lo) * r.d_inv));
    c = r.d_wrap ? ((c % r.d_size) + r.d_size) % r.d_size : clamp(c, ivec2(0), r.d_size - 1);
    return texelFetch(density, c, 0).r;
}

// The tile's key.
uint axial_gen_key(uint seed, ivec2 tile) {
    return axial_wind_hash(axial_wind_hash(axial_wind_hash(uint(tile.x)) ^ uint(tile.y)) ^ seed);
}

// u_k of instance i, in [0, 1): 24 bits of the hash, exact in float32.
float axial_gen_u(uint key, uint i, uint k) {
    return float(axial_wind_hash(key ^ (i * 32u + k)) >> 8u) * (1.0 / 16777216.0);
}

// Instance i of tile `tile`: the 16 numbers (d12, d34, d5, position, angles), the extension's 3
// (extra), the tint's 3 and whether it is kept (1.0) or dropped (0.0).
void axial_generate(AxialRecipe r, sampler2D heights, sampler2D density, ivec2 tile, int i, out vec4 d12, out vec4 d34,
                    out vec2 d5, out vec3 position, out vec3 angles, out vec3 extra, out vec3 tint, out float kept) {
    uint key = axial_gen_key(r.seed, tile);
    uint ui = uint(i);
    float u[22];  // u22 .. u25: only a layer in clumps draws them (below)
    for (int k = 0; k < 22; ++k) u[k] = axial_gen_u(key, ui, uint(k));
    float cx = float(tile.x * r.m + i % r.m), cz = float(tile.y * r.m + i / r.m);
    position.x = (cx + 0.5 + r.jitter * (u[0] - 0.5)) * r.cell;
    position.z = (cz + 0.5 + r.jitter * (u[1] - 0.5)) * r.cell;
    if (r.clump_cells > 1.0 || r.clump_radius > 0.0) {
        // a clump: one of the 8 parents (q = floor(8 u24)) of the s x s cells (p = floor((c + 1/2) / s)), each
        // anywhere in them from a hash of its own; the instance uniform in a disc of radius R around it:
        // R sqrt(u22) (cos, sin)(2 pi u23), or in the clump's core (u25 < clump_core) of radius clump_core_radius
        vec2 pc = floor((vec2(cx, cz) + 0.5) / r.clump_cells);
        uint pkey = axial_gen_key(r.seed ^ 2654435769u, ivec2(pc));
        uint q = uint(min(floor(axial_gen_u(key, ui, 24u) * 8.0), 7.0));
        vec2 parent = (pc + vec2(axial_gen_u(pkey, q, 0u), axial_gen_u(pkey, q, 1u))) * (r.clump_cells * r.cell);
        vec2 cs = axial_cos_sin(6.283185307179586 * axial_gen_u(key, ui, 23u));
        float radius = axial_gen_u(key, ui, 25u) < r.clump_core ? r.clump_core_radius : r.clump_radius;
        float rho = radius * sqrt(axial_gen_u(key, ui, 22u));
        position.x = parent.x + rho * cs.x;
        position.z = parent.y + rho * cs.y;
    }
    angles = vec3(0.0, r.yaw.x + (r.yaw.y - r.yaw.x) * u[2], 0.0);
    vec2 d[5];
    for (int q = 0; q < 5; ++q) d[q] = vec2(r.bend * (2.0 * u[3 + 2 * q] - 1.0), r.bend * (2.0 * u[4 + 2 * q] - 1.0));
    // every control point shifted by D(t_a): the anchor stays where it is put
    vec2 at = r.anchor_w.x * d[0] + r.anchor_w.y * d[1] + r.anchor_w.z * d[2] + r.anchor_w.w * d[3] + r.anchor_w4 * d[4];
    d12 = vec4(d[0] - at, d[1] - at);
    d34 = vec4(d[2] - at, d[3] - at);
    d5 = d[4] - at;
    float s = r.scale.x + (r.scale.y - r.scale.x) * u[13];
    if (r.scale_mid.x > 0.0) {  // piecewise linear through the knots at u13 = 0, 1/4, .., 1 (or 1/8: nine knots)
        float q[9];
        float n = 4.0;
        q[0] = r.scale.x;
        q[1] = r.scale_mid.x;
        q[2] = r.scale_mid.y;
        q[3] = r.scale_mid.z;
        q[4] = r.scale.y;
        for (int j = 5; j < 9; ++j) q[j] = r.scale.y;
        if (r.scale_odd.x > 0.0) {
            n = 8.0;
            q[1] = r.scale_odd.x;
            q[2] = r.scale_mid.x;
            q[3] = r.scale_odd.y;
            q[4] = r.scale_mid.y;
            q[5] = r.scale_odd.z;
            q[6] = r.scale_mid.z;
            q[7] = r.scale_odd.w;
        }
        float v = u[13] * n;
        float k = min(floor(v), n - 1.0);
        float a = q[0], b = q[1];
        for (int j = 1; j < 8; ++j) {  // q[k], q[k + 1] (arrays are indexed by constants in every target)
            if (float(j) == k) {
                a = q[j];
                b = q[j + 1];
            }
        }
        s = a + (b - a) * (v - k);
    }
    extra = vec3(s, r.twist * (2.0 * u[14] - 1.0), r.taper * u[15]);
    vec3 ut = vec3(u[17], u[18], u[19]);
    tint = r.tint_color * (1.0 - r.tint * (u[17] + r.tint_hue * (ut - u[17])));
    float h = 0.0;
    vec2 grad = vec2(0.0);
    bool inside = true;
    if (r.has_heights) h = axial_gen_height(r, heights, position.xz, grad, inside);
    float t2 = dot(grad, grad);
    bool keep = inside && h >= r.altitude.x && h <= r.altitude.y && t2 >= r.slope_tan2.x && t2 <= r.slope_tan2.y
                && u[20] >= r.choice.x && u[20] < r.choice.y;
    if (r.has_density) keep = keep && u[16] < axial_gen_density(r, density, position.xz);
    kept = keep ? 1.0 : 0.0;
    float ay = r.anchor_y;
    if (r.align > 0.0 && r.has_heights) angles = axial_gen_lean(r, angles.y, grad, ay);
    position.y = h - ay * s + (r.lift.x + (r.lift.y - r.lift.x) * u[21]);
}

// Child axis j (1 .. K-1) of instance i, a mesh of several axes: offsets uniform in +-amp_j, then the
// 5 x 5 projection P_j that keeps the joint with its parent closed (axialdeform.core.axes.anchor_projection),
// summed in order.  `children`: row j - 1 holds amp_j, then P_j row after row (26 texels).
//   u^j_k = (H(H(key + j) ^ (32 i + k)) >> 8) / 2^24,  raw_q = amp_j (2 u^j_{2q,2q+1} - 1),  d_a = sum_b P_ab raw_b
void axial_generate_child(uint key, int i, int j, sampler2D children, out vec2 d[5]) {
    uint kj = axial_wind_hash(key + uint(j));
    float amp = texelFetch(children, ivec2(0, j - 1), 0).r;
    vec2 raw[5];
    for (int q = 0; q < 5; ++q) {
        raw[q] = amp * (2.0 * vec2(axial_gen_u(kj, uint(i), uint(2 * q)), axial_gen_u(kj, uint(i), uint(2 * q + 1))) - 1.0);
    }
    for (int a = 0; a < 5; ++a) {
        vec2 s = vec2(0.0);
        for (int b = 0; b < 5; ++b) s += texelFetch(children, ivec2(1 + 5 * a + b, j - 1), 0).r * raw[b];
        d[a] = s;
    }
}
