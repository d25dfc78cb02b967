// generate_axes.vert -- a generated tree's child-axis offsets written straight into the offsets
// texture the draw fetches (glsl/axial.glsl's layout: gl/axes.py, the npm module's axialChildren): one
// point a texel, drawn into the texture.  Instance j (gl_InstanceID) is (tile x, tile z, cell) i_cell --
// the kept instances compacted (axialdeform.gl.generated) -- or, with AXIAL_SLOT_CELLS, slot j of the
// tiles in u_tiles, m^2 a tile (the page: every slot drawn, the dropped ones collapsed).  Its axis k's
// three texels ``d1u d1v d2u d2v | d3u d3v d4u d4v | d5u d5v 0 0`` sit from (j (K-1) + k - 1) 3 on, in
// rows of u_row texels.  The offsets: axial_generate_child, the function generate_children.vert runs.
#include "axial.glsl"
#include "wind.glsl"
#include "generate.glsl"

#ifdef AXIAL_SLOT_CELLS
uniform int u_count;                 // slots a tile (m^2)
uniform highp isampler2D u_tiles;    // texel k: tile k's (tx, tz)
#else
in ivec3 i_cell;
#endif

uniform uint u_seed;
uniform int u_children_n;    // K - 1
uniform int u_row;           // texels a row
uniform ivec2 u_size;        // the texture's size
uniform sampler2D u_children;

flat out vec4 v_value;

void main() {
#ifdef AXIAL_SLOT_CELLS
    int tile = gl_InstanceID / u_count;
    ivec3 cell = ivec3(texelFetch(u_tiles, ivec2(tile, 0), 0).xy, gl_InstanceID - tile * u_count);
#else
    ivec3 cell = i_cell;
#endif
    int k = gl_VertexID / 3 + 1, t = gl_VertexID - 3 * (k - 1);
    vec2 d[5];
    axial_generate_child(axial_gen_key(u_seed, cell.xy), cell.z, k, u_children, d);
    v_value = t == 0 ? vec4(d[0], d[1]) : (t == 1 ? vec4(d[2], d[3]) : vec4(d[4], 0.0, 0.0));
    int p = (gl_InstanceID * u_children_n + k - 1) * 3 + t;
    int y = p / u_row, x = p - y * u_row;
    gl_Position = vec4((vec2(x, y) + 0.5) / vec2(u_size) * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
}
