// quantized.glsl -- the compact (32-byte) instance record, decoded BEFORE the
// shared deformation of axial.glsl.  Only used when AXIAL_QUANTIZED is
// defined (AxialRenderer(..., quantized=True)).
//
// The 16 numbers arrive as 16 uint16 in four integer attributes (moderngl
// format "4u2", GLSL uvec4); each decodes as  value = u_qmin[k] + q * u_qstep[k],
// the same per-column table as the quantized .adp file (params.quantize_params).
// With AXIAL_EXTENDED too, s tw tp follow as a fifth attribute (3 uint16 + 2 bytes
// of padding: a 40-byte record) with their own table u_qmin_extra / u_qstep_extra.
#ifdef AXIAL_QUANTIZED
in uvec4 i_q0;              // d1u d1v d2u d2v
in uvec4 i_q1;              // d3u d3v d4u d4v
in uvec4 i_q2;              // d5u d5v px  py
in uvec4 i_q3;              // pz  rx  ry  rz
uniform vec4 u_qmin[4];     // per-column minimum, columns 4k .. 4k+3
uniform vec4 u_qstep[4];    // per-column step
#ifdef AXIAL_EXTENDED
in uvec3 i_q4;              // s tw tp
uniform vec3 u_qmin_extra;
uniform vec3 u_qstep_extra;
#endif

AxialInstance axial_dequantize() {
    vec4 c0 = u_qmin[0] + vec4(i_q0) * u_qstep[0];
    vec4 c1 = u_qmin[1] + vec4(i_q1) * u_qstep[1];
    vec4 c2 = u_qmin[2] + vec4(i_q2) * u_qstep[2];
    vec4 c3 = u_qmin[3] + vec4(i_q3) * u_qstep[3];
#ifdef AXIAL_EXTENDED
    vec3 c4 = u_qmin_extra + vec3(i_q4) * u_qstep_extra;
    return AxialInstance(c0, c1, c2.xy, vec3(c2.zw, c3.x), c3.yzw, c4.x, c4.y, c4.z);
#else
    return axial_instance(c0, c1, c2.xy, vec3(c2.zw, c3.x), c3.yzw);
#endif
}
#endif
