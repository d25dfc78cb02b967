// quantized.glsl -- the compact (32-byte) instance record, decoded BEFORE the
// shared deformation of axial.glsl.  Only used when AXIAL_QUANTIZED is
// defined (AxialRenderer(..., quantized=True)).
//
// The 16 numbers arrive as 16 uint16 in four integer attributes (moderngl
// format "4u2", GLSL uvec4); each decodes as  value = u_qmin[k] + q * u_qstep[k],
// the same per-column table as the quantized .adp file (params.quantize_params).
// With AXIAL_EXTENDED too, s tw tp follow as a fifth attribute (3 uint16 + 2 bytes
// of padding: a 40-byte record) with their own table u_qmin_extra / u_qstep_extra.
// AXIAL_COMPUTE (cull.comp): no attributes; the caller unpacks the words itself.
#ifdef AXIAL_QUANTIZED
#ifndef AXIAL_COMPUTE
in uvec4 i_q0;              // d1u d1v d2u d2v
in uvec4 i_q1;              // d3u d3v d4u d4v
in uvec4 i_q2;              // d5u d5v px  py
in uvec4 i_q3;              // pz  rx  ry  rz
#endif
uniform vec4 u_qmin[4];     // per-column minimum, columns 4k .. 4k+3
uniform vec4 u_qstep[4];    // per-column step
#ifdef AXIAL_EXTENDED
#ifndef AXIAL_COMPUTE
in uvec3 i_q4;              // s tw tp
#endif
uniform vec3 u_qmin_extra;
uniform vec3 u_qstep_extra;
#endif

// The instance of the 16 (19) uint16 of one record (q4: s tw tp, unused unless extended).
AxialInstance axial_dequantize(uvec4 q0, uvec4 q1, uvec4 q2, uvec4 q3, uvec3 q4) {
    vec4 c0 = u_qmin[0] + vec4(q0) * u_qstep[0];
    vec4 c1 = u_qmin[1] + vec4(q1) * u_qstep[1];
    vec4 c2 = u_qmin[2] + vec4(q2) * u_qstep[2];
    vec4 c3 = u_qmin[3] + vec4(q3) * u_qstep[3];
#ifdef AXIAL_EXTENDED
    vec3 c4 = u_qmin_extra + vec3(q4) * u_qstep_extra;
    return AxialInstance(c0, c1, c2.xy, vec3(c2.zw, c3.x), c3.yzw, c4.x, c4.y, c4.z);
#else
    return axial_instance(c0, c1, c2.xy, vec3(c2.zw, c3.x), c3.yzw);
#endif
}

#ifndef AXIAL_COMPUTE
// The instance of this vertex's record (the attributes above).
AxialInstance axial_dequantize() {
#ifdef AXIAL_EXTENDED
    return axial_dequantize(i_q0, i_q1, i_q2, i_q3, i_q4);
#else
    return axial_dequantize(i_q0, i_q1, i_q2, i_q3, uvec3(0u));
#endif
}
#endif
#endif
