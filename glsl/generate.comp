// generate.comp -- the generator's slots by a compute shader (GL >= 4.3; axialdeform.gl.generate): one
// invocation a slot of the tiles in Tiles (m^2 slots a tile, tile after tile) writes the slot's numbers
// generate.vert's outputs capture, in their order (slot.glsl: the 22-number record, then kept), into a storage
// buffer from float u_first on -- the same slots as the transform-feedback pass, all the tiles of a set
// in one dispatch (the tests hold them to it and to the numpy reference).
#define AXIAL_SLOT_VALUES 1
#include "generate.vert"

layout(local_size_x = 64) in;
layout(std430, binding = 0) writeonly buffer Slots { float slots[]; };
layout(std430, binding = 1) readonly buffer Tiles { ivec2 tiles[]; };

uniform uint u_first;   // where the first tile's first slot starts, in floats
uniform uint u_count;   // slots a tile (m^2)
uniform uint u_tiles;   // tiles

void main() {
    uint s = gl_GlobalInvocationID.x, t = s / u_count, i = s - t * u_count;
    if (t >= u_tiles) return;
    vec4 d12, d34;
    vec2 d5;
    vec3 position, angles, extra, tint;
    float kept;
    axial_generate(axial_gen_recipe(), u_heights, u_density, tiles[t], int(i), d12, d34, d5, position, angles, extra,
                   tint, kept);
    float v[AXIAL_SLOT_FLOATS];
    axial_slot_values(d12, d34, d5, position, angles, extra, tint, kept, v);
    uint o = u_first + uint(AXIAL_SLOT_FLOATS) * s;
    for (int k = 0; k < AXIAL_SLOT_FLOATS; ++k) slots[o + uint(k)] = v[k];
}
