// wind.glsl -- wind on the GPU (docs/wind.md): it moves an instance's CONTROL POINTS,
// so the exact normals of axial.glsl still hold, and it needs no per-frame upload.
//
// Include after "axial.glsl".  Declares no inputs or uniforms: callers pass them.
// Model (the CPU reference is axialdeform.core.wind, the same function of time):
//   h     = (pcg(id) >> 8) / 2^24                      per-instance phase in [0, 1), exact on CPU
//   ph    = h - dot(p, dir) * wavenumber                gust fronts travel along dir
//   wave  = 0.6 sin(2 pi (cycles.x + ph)) + 0.4 sin(2 pi (cycles.y + 1.7 ph))
//   amp   = strength * L * (1 + gustiness * wave)       tip displacement, model units
//   u     = amp * (R^T dir) across the axis             the wind in the instance's own frame
//   d_k  += c_k u,  c = (0, 0, 1/6, 1/2, 1)             control polygon of D(t) = t^2:
//                                                       P1 and the base tangent stay, the tip moves most
// cycles = (fract(f T), fract(2.31 f T)) are computed on the CPU in double precision,
// so a long-running clock loses no accuracy in float32.

// PCG hash of an instance index (integer maths: bit-exact on every GPU and in numpy).
uint axial_wind_hash(uint i) {
    uint h = i * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    return (h >> 22u) ^ h;
}

// A generated instance's lasting identity (docs/generate.md), from where it stands: the float32 bits of
// its x and z hashed.  Its index changes as tiles come and go; this does not, so neither do its wind
// phase and shade (AXIAL_POSITION_IDS in scene.vert).
uint axial_position_id(vec3 p) {
    return axial_wind_hash(floatBitsToUint(p.x) ^ axial_wind_hash(floatBitsToUint(p.z)));
}

// The instance's phase in [0, 1): 24 bits of the hash, exact in float32.
float axial_wind_phase(uint id) {
    return float(axial_wind_hash(id) >> 8u) * (1.0 / 16777216.0);
}

// dir: unit wind direction (world); strength: tip displacement in units of L;
// gust: gustiness (0 = steady lean); cycles: see above; wavenumber: 1 / gust wavelength (world units).
// The wind's push on instance `inst` (index `id`) at this moment, in the instance's model
// frame (model units): amp * (R^T dir).  Only its part across the axis bends (axial_wind).
vec3 axial_wind_push(AxialInstance inst, uint id, float len, vec3 dir, float strength,
                     float gust, vec2 cycles, float wavenumber) {
    float ph = axial_wind_phase(id) - dot(inst.position, dir) * wavenumber;
    float wave = 0.6 * axial_cos_sin(6.283185307179586 * (cycles.x + ph)).y
               + 0.4 * axial_cos_sin(6.283185307179586 * (cycles.y + 1.7 * ph)).y;
    float amp = strength * len * (1.0 + gust * wave);
    return amp * (transpose(axial_rotation(inst.angles)) * dir);  // world -> the instance's model frame
}

// The control points moved by u (across the axis): d_k += c_k u, c = (0, 0, 1/6, 1/2, 1).
AxialInstance axial_wind_move(AxialInstance inst, vec2 u) {
    inst.d34 += vec4(u * (1.0 / 6.0), u * 0.5);
    inst.d5 += u;
    return inst;
}

// The instance `inst` (index `id`) as the wind at this moment bends it.
AxialInstance axial_wind(AxialInstance inst, uint id, int axis, float len, vec3 dir, float strength,
                         float gust, vec2 cycles, float wavenumber) {
    return axial_wind_move(inst, axial_across(axial_wind_push(inst, id, len, dir, strength, gust, cycles,
                                                              wavenumber), axis));
}

// The same for a chosen axis frame (frame * v = local coordinates).
AxialInstance axial_wind(AxialInstance inst, uint id, mat3 frame, float len, vec3 dir, float strength,
                         float gust, vec2 cycles, float wavenumber) {
    return axial_wind_move(inst, axial_across(axial_wind_push(inst, id, len, dir, strength, gust, cycles,
                                                              wavenumber), frame));
}
