// generate.glsl -- a generated layer's instance: a pure function of (the recipe, its seed, the tile,
// the index), docs/generate.md; the numpy reference is axialdeform.core.generate (the tests hold
// this file to it: hash bit-exact, numbers to float32 rounding).
//
// Include after "axial.glsl" and "wind.glsl" (axial_wind_hash, the PCG hash).  Declares no inputs:
// callers pass the recipe.  Conventions (docs/generate.md):
//   tile (tx, tz) covers [tx T, (tx+1) T) x [tz T, (tz+1) T); m x m cells of side c = T / m;
//   instance i stands in cell (i mod m, i div m), jittered by j = 1 - min_distance / c;
//   offsets d = bend L (2 u - 1), every control point minus D(t_a) (t_a: the anchor on the axis);
//   u_k = (H(key ^ (32 i + k)) >> 8) / 2^24,  key = H(H(H(uint tx) ^ uint tz) ^ seed).

struct AxialRecipe {
    uint seed;
    int m;           // cells a side of a tile
    float cell;      // c = T / m
    float jitter;    // j = 1 - min_distance / c
    float bend;      // bend L: offsets in [-bend L, bend L]
    vec2 scale;      // lo, hi (1, 1: none)
    float twist;     // tw in [-twist, twist]
    float taper;     // tp in [0, taper]
    float lowest;    // the base mesh's lowest y: it stands on the ground
    vec4 anchor_w;   // B4_0..3(t_a): the anchor's place on the axis (D(t_a) = 0: it stays put)
    float anchor_w4; // B4_4(t_a)
};

// The tile's key.
uint axial_gen_key(uint seed, ivec2 tile) {
    return axial_wind_hash(axial_wind_hash(axial_wind_hash(uint(tile.x)) ^ uint(tile.y)) ^ seed);
}

// u_k of instance i, in [0, 1): 24 bits of the hash, exact in float32.
float axial_gen_u(uint key, uint i, uint k) {
    return float(axial_wind_hash(key ^ (i * 32u + k)) >> 8u) * (1.0 / 16777216.0);
}

// Instance i of tile `tile`: the 16 numbers (d12, d34, d5, position, angles) and the extension's 3.
void axial_generate(AxialRecipe r, ivec2 tile, int i, out vec4 d12, out vec4 d34, out vec2 d5, out vec3 position,
                    out vec3 angles, out vec3 extra) {
    uint key = axial_gen_key(r.seed, tile);
    uint ui = uint(i);
    float u[16];
    for (int k = 0; k < 16; ++k) u[k] = axial_gen_u(key, ui, uint(k));
    float cx = float(tile.x * r.m + i % r.m), cz = float(tile.y * r.m + i / r.m);
    position.x = (cx + 0.5 + r.jitter * (u[0] - 0.5)) * r.cell;
    position.z = (cz + 0.5 + r.jitter * (u[1] - 0.5)) * r.cell;
    angles = vec3(0.0, 6.283185307179586 * u[2], 0.0);
    vec2 d[5];
    for (int q = 0; q < 5; ++q) d[q] = vec2(r.bend * (2.0 * u[3 + 2 * q] - 1.0), r.bend * (2.0 * u[4 + 2 * q] - 1.0));
    // every control point shifted by D(t_a): the anchor stays where it is put
    vec2 at = r.anchor_w.x * d[0] + r.anchor_w.y * d[1] + r.anchor_w.z * d[2] + r.anchor_w.w * d[3] + r.anchor_w4 * d[4];
    d12 = vec4(d[0] - at, d[1] - at);
    d34 = vec4(d[2] - at, d[3] - at);
    d5 = d[4] - at;
    float s = r.scale.x + (r.scale.y - r.scale.x) * u[13];
    extra = vec3(s, r.twist * (2.0 * u[14] - 1.0), r.taper * u[15]);
    position.y = -r.lowest * s;
}
