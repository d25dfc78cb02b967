// bounds.glsl -- THE bound of one deformed instance on the GPU (the same
// maths as axialdeform/core/bounds.py; docs/culling.md).  Include it after
// "axial.glsl" (it uses AxialInstance and axial_rotation).
//
// The bend moves a vertex by D(t) = sum B4_i(t) d_{i+1}: the weights are
// non-negative and sum to 1, so |D(t)| <= max_i |d_i| (convex hull of the
// control points).  A rotation keeps distances.  So with the base mesh's
// bounding-box centre c and r0 = max |v - c| over its vertices (all LOD
// levels), every world vertex of the instance lies in the sphere
//     centre R c + p,   radius r0 + max_i |d_i|.
// Extended instances: twist keeps a vertex's distance from the axis line,
// taper scales it by at most max(1, |1 - tp|), s scales everything about the
// model origin:  centre s R c + p,  radius |s| (r0 max(1, |1 - tp|) + max_i |d_i| + wind).
// `reach`: how far the wind can move a control point (model units; 0: none).

// Largest control-point offset of an instance: how far its bend can move a vertex.
float axial_bend_reach(AxialInstance inst) {
#ifdef AXIAL_NO_BEND
    return 0.0;
#else
    float m = max(dot(inst.d12.xy, inst.d12.xy), dot(inst.d12.zw, inst.d12.zw));
    m = max(m, max(dot(inst.d34.xy, inst.d34.xy), dot(inst.d34.zw, inst.d34.zw)));
    m = max(m, dot(inst.d5, inst.d5));
    return sqrt(m);
#endif
}

// The world-space bounding sphere of an instance: centre (xyz) and radius (w).
// center, radius: the base mesh's bounding-box centre and the largest distance
// of a vertex from it (model units).
vec4 axial_bound_sphere(AxialInstance inst, vec3 center, float radius, float reach) {
    vec3 c = axial_rotation(inst.angles) * (inst.scale * center) + inst.position;
    float grow = max(1.0, abs(1.0 - inst.taper));
    return vec4(c, abs(inst.scale) * (radius * grow + axial_bend_reach(inst) + reach));
}

// False only when the sphere lies entirely on the outer side of one of the
// six frustum planes (world space, (n, d) with n.x + d >= 0 inside, n unit),
// so no vertex of the instance can reach the clip volume.  The radius is
// widened by a relative margin for float32 rounding of the vertex shader.
bool axial_sphere_visible(vec4 sphere, vec4 planes[6]) {
    float r = sphere.w * 1.0001 + 1e-6 * (abs(sphere.x) + abs(sphere.y) + abs(sphere.z) + sphere.w);
    for (int i = 0; i < 6; ++i) {
        if (dot(planes[i].xyz, sphere.xyz) + planes[i].w < -r) return false;
    }
    return true;
}
