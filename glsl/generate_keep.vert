// generate_keep.vert -- the kept instances of generated tiles, compacted on the GPU
// (axialdeform.gl.generated): every slot generate.vert wrote (23 floats: the 22-number record, then
// kept) is read as a point; generate_keep.geom emits the kept ones and transform feedback writes them,
// in slot order, into the buffer the renderer draws from.  One define picks what a pass writes:
//   AXIAL_KEEP_RECORD  the record's first 16 numbers, 19 with AXIAL_EXTENDED (the instance buffer's layouts)
//   AXIAL_KEEP_TINT    the tint's 3 (the renderer's tint buffer)
//   AXIAL_KEEP_CELL    (tile x, tile z, cell) of the instance (what the child axes' pass needs)
in vec4 a_0;        // d1u d1v d2u d2v
in vec4 a_1;        // d3u d3v d4u d4v
in vec4 a_2;        // d5u d5v px py
in vec4 a_3;        // pz rx ry rz
in vec3 a_4;        // s tw tp
in vec3 a_tint;     // tr tg tb
in float a_kept;    // 1: kept, 0: dropped

uniform int u_count;             // instances a tile (m^2)
uniform isampler2D u_tiles;      // the tiles in slot order: texel k = tile k's (tx, tz)

flat out vec4 vs_0;
flat out vec4 vs_1;
flat out vec4 vs_2;
flat out vec4 vs_3;
flat out vec3 vs_4;
flat out vec3 vs_tint;
flat out ivec3 vs_cell;
flat out int vs_keep;

void main() {
    vs_0 = a_0;
    vs_1 = a_1;
    vs_2 = a_2;
    vs_3 = a_3;
    vs_4 = a_4;
    vs_tint = a_tint;
    vs_keep = a_kept > 0.5 ? 1 : 0;
#ifdef AXIAL_KEEP_CELL
    int k = gl_VertexID / u_count;
    vs_cell = ivec3(texelFetch(u_tiles, ivec2(k, 0), 0).xy, gl_VertexID - k * u_count);
#else
    vs_cell = ivec3(0);
#endif
    gl_Position = vec4(0.0);
}
