// generate_keep.geom -- one slot in, the kept one out (generate_keep.vert says what a pass writes;
// slot.glsl which of the slot's vectors it is).
layout(points) in;
layout(points, max_vertices = 1) out;

#define AXIAL_SLOT_KEEP 1
#include "slot.glsl"

flat in ivec3 vs_cell[];
#ifdef AXIAL_KEEP_CELL
flat out ivec3 o_cell;
#endif

void main() {
    if (slot_kept_in <= 0.5) return;
    axial_slot_keep();
#ifdef AXIAL_KEEP_CELL
    o_cell = vs_cell[0];
#endif
    gl_Position = gl_in[0].gl_Position;
    EmitVertex();
    EndPrimitive();
}
