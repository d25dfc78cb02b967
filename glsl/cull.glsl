// cull.glsl -- what both culling passes share (docs/culling.md): the
// uniforms of the frustum test and of the LOD choice, and the choice itself.
// Included after "bounds.glsl" by cull.vert (GL 3.3: transform feedback) and
// cull.comp (GL >= 4.3: compute + indirect draws).

uniform vec4 u_planes[6];     // world-space frustum planes, unit normals, inside: dot(n, x) + d >= 0
uniform vec3 u_bound_center;  // base mesh bounding-box centre (model units)
uniform float u_radius;       // largest distance of a vertex (of any LOD level) from u_center
uniform int u_levels;         // LOD levels (1..4)
uniform float u_lod_error[4]; // geometric error of each level, model units (level 0: 0)
uniform vec3 u_eye;           // camera position (world)
uniform float u_px_scale;     // pixels per world unit at distance 1 (perspective) or everywhere (orthographic)
uniform bool u_ortho;
uniform float u_lod_px;       // allowed screen-space error, pixels
uniform float u_wind_reach;   // how far the wind can move a control point (model units), 0: still

// The LOD level of an instance whose bounding sphere is `sphere`: the
// coarsest level whose error, projected at the sphere's nearest point to
// the eye, is at most u_lod_px pixels (errors are model units: times |s|).
int axial_lod_level(vec4 sphere, float scale) {
    float px = abs(scale) * (u_ortho ? u_px_scale : u_px_scale / max(length(sphere.xyz - u_eye) - sphere.w, 1e-6));
    int level = 0;
    for (int k = 1; k < 4; ++k) {
        if (k < u_levels && u_lod_error[k] * px <= u_lod_px) level = k;
    }
    return level;
}

// The level an instance is drawn at, or -1 when its sphere is outside the frustum.
int axial_cull_level(AxialInstance inst) {
    vec4 sphere = axial_bound_sphere(inst, u_bound_center, u_radius, u_wind_reach);
    if (!axial_sphere_visible(sphere, u_planes)) return -1;
    return axial_lod_level(sphere, inst.scale);
}
