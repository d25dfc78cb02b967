// generate_keep.vert -- the kept instances of generated tiles, compacted on the GPU
// (axialdeform.gl.generated): every slot generate.vert wrote (slot.glsl: the 22-number record, then
// kept) is read as a point; generate_keep.geom emits the kept ones and transform feedback writes them,
// in slot order, into the buffer the renderer draws from.  One define picks what a pass writes:
//   AXIAL_KEEP_RECORD  the record's first 16 numbers, 19 with AXIAL_EXTENDED (the instance buffer's layouts)
//   AXIAL_KEEP_TINT    the tint's 3 (the renderer's tint buffer)
//   AXIAL_KEEP_CELL    (tile x, tile z, cell) of the instance (what the child axes' pass needs)
#define AXIAL_SLOT_READ 1
#define AXIAL_SLOT_PASS 1
#include "slot.glsl"

uniform int u_count;             // instances a tile (m^2)
uniform isampler2D u_tiles;      // the tiles in slot order: texel k = tile k's (tx, tz)

flat out ivec3 vs_cell;

void main() {
    axial_slot_pass();
#ifdef AXIAL_KEEP_CELL
    int k = gl_VertexID / u_count;
    vs_cell = ivec3(texelFetch(u_tiles, ivec2(k, 0), 0).xy, gl_VertexID - k * u_count);
#else
    vs_cell = ivec3(0);
#endif
    gl_Position = vec4(0.0);
}
