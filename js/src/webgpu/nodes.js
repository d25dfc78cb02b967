// nodes.js -- the bend as three.js node functions (TSL), for WebGPURenderer (three/webgpu, both its
// WebGPU and WebGL 2 backends) and its node materials.  Every formula is glsl/axial.glsl's and
// glsl/wind.glsl's, GENERATED into src/webgpu/glsl_nodes.js and glsl_wind_nodes.js by build.mjs; this file only calls
// them the way the mesh holds its data: a frame as three uniform rows, a tree's axes in a texture, the
// child offsets in a texture or a storage buffer, the rigid part from three's instanceMatrix when the CPU
// made it.  The tests hold the result to axialdeform.deform on every feature (tests/web/test_webgpu.py).
//
// Values: an instance is {d12, d34, d5, position, angles, scale, twist, taper} of nodes (and `matrix`, the
// columns of s R and p, when the CPU made them); a frame is {ea, eu, ev} (its rows: local coordinates
// F v = (ea.v, eu.v, ev.v), axis first).

import { float, int, uint, vec3, textureLoad, ivec2 } from 'three/tsl';
import * as glsl from './glsl_nodes.js';
import * as windGlsl from './glsl_wind_nodes.js';
import { WIND_UNIFORMS } from '../core/record.js';
import { matAssign, matDiagonal, matTranspose, matVar, matVec } from './tsl_runtime.js';

export { axialCosSin, axialCurve, axialRotation } from './glsl_nodes.js';
export { axialWindHash, axialPositionId } from './glsl_wind_nodes.js';

/** The frame {ea, eu, ev} as GLSL's mat3 `frame` (frame * v = F v): three columns. */
export function axialFrameMatrix(f) {
  return matTranspose([f.ea, f.eu, f.ev]);
}

/** The slope D'(t) (axial_slope). */
export const axialSlope = glsl.axialSlope_fv4v4v2;

/** Bend model-space v and unit n along one axis of frame f (axial_bend with a frame): {v, n}. */
export function axialBend(v, n, f, lo, len, center, inst) {
  const out = { v: vec3(0).toVar(), n: vec3(0).toVar() };
  glsl.axialBend_v3v3m3ffv2AIv3v3(v, n, axialFrameMatrix(f), lo, len, center, inst, out.v, out.n);
  return out;
}

/** The model-space part of a tangent through the bend (axial_bend_tangent with a frame; not normalised). */
export function axialBendTangent(v, tangent, f, lo, len, center, inst) {
  return glsl.axialBendTangent_v3v3m3ffv2AI(v, tangent, axialFrameMatrix(f), lo, len, center, inst);
}

/** The rigid part: W = R (s V'') + p, normal R n'' (axial_place): {v, n, rot (columns of R or s R)}.
 * With inst.matrix (the columns of s R and p, made on the CPU in double precision as three's
 * instanceMatrix is), the matrix places; without it, axial_place does, R from inst.angles. */
export function axialPlace(bentV, bentN, inst) {
  const out = { v: vec3(0).toVar(), n: vec3(0).toVar() };
  if (inst.matrix) {
    const m = inst.matrix.slice(0, 3);
    glsl.axialPlaceMatrix(bentV, bentN, m, inst.matrix[3], out.v, out.n);
    return { ...out, rot: m };
  }
  glsl.axialPlace(bentV, bentN, inst, out.v, out.n);
  return { ...out, rot: glsl.axialRotation(inst.angles) };
}

/** A bent tangent placed by `rot` (axialPlace's): the unit world tangent (axial_place_direction). */
export const axialPlaceDirection = glsl.axialPlaceDirection;

/** The wind's uniforms `w` ({dir, strength, ...}) as wind.glsl's functions take them (record.js's WIND_UNIFORMS). */
const windArgs = (w) => WIND_UNIFORMS.map((u) => w[u.name]);

/** The wind's push on instance `inst` (index id) in its model frame (axial_wind_push); w: the wind's
 * uniforms {dir, strength, gust, cycles, wavenumber}. */
export function axialWindPush(inst, id, len, w) {
  return windGlsl.axialWindPush(inst, uint(id), float(len), ...windArgs(w));
}

/** The instance as the wind bends it along frame f (axial_wind): d3 += u/6, d4 += u/2, d5 += u. */
export function axialWind(inst, id, f, len, w) {
  const moved = windGlsl.axialWind_AIum3fv3ffv2f(inst, uint(id), axialFrameMatrix(f), len, ...windArgs(w));
  return { ...inst, ...moved };
}

// ---- several axes: the walk is axial_tree_bend's (generated); here only its storage, the hooks it calls ----

/** axial_tree_axis and axial_tree_offsets over the mesh's storage: the axes texture (rows (e_a, lo), (e_u, len),
 * (e_v, anchor), (parent, 0, 0, 0)) and the child offsets' texture or a function of a texel's index (an int
 * node) giving it (a storage buffer's); K: the axes. */
function treeStorage(axesTex, children, K) {
  const texels = typeof children === 'function' ? (at) => children(glsl.axialTexelIndex(at)) : children;
  return {
    axialTreeAxis(j, frame, lo, len, anchor, parent) {
      const r0 = textureLoad(axesTex, ivec2(0, j)).toVar(), r1 = textureLoad(axesTex, ivec2(1, j)).toVar();
      const r2 = textureLoad(axesTex, ivec2(2, j)).toVar(), r3 = textureLoad(axesTex, ivec2(3, j));
      matAssign(frame, axialFrameMatrix({ ea: r0.xyz, eu: r1.xyz, ev: r2.xyz }));
      lo.assign(r0.w);
      len.assign(r1.w);
      anchor.assign(r2.w);
      parent.assign(int(r3.x));
    },
    axialTreeOffsets(id, k, d12, d34, d5) {
      glsl.axialChildOffsets(texels, id, k, int(K), d12, d34, d5);
    },
  };
}

/**
 * The bend of a K-axis mesh (axial_tree_bend): model-space v and n -> {v, n, jac (columns)} in the mesh's
 * space; b: the vertex's axes (an int node): its axis, or for a vertex blending two chains b + 64 b1 + 4096 q.
 * children: the child offsets' texture (the mesh's axialChildren) or a function of a texel's index (an int
 * node) giving it (a storage buffer's), id: the instance (int node), wind: the push per unit of axis length
 * (a vec3 node) or null.
 */
export function axialTreeWorld(v, n, b, K, axesTex, center, inst, children, id, wind) {
  const out = { v: vec3(0).toVar(), n: vec3(0).toVar(), jac: matVar(matDiagonal(float(1))) };
  const treeWind = { on: Boolean(wind), push: wind || vec3(0) };
  glsl.axialTreeBend(v, n, int(b), int(K), center, inst, int(id), treeWind, out.v, out.n, out.jac,
    treeStorage(axesTex, children, K));
  return out;
}

/** J x for the tree's Jacobian columns (tangents): the runtime's mat3 times a vector. */
export const axialJacobianTimes = matVec;
