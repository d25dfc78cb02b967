// nodes.js -- the bend as three.js node functions (TSL), for WebGPURenderer (three/webgpu, both its
// WebGPU and WebGL 2 backends) and its node materials.  Every formula is glsl/axial.glsl's and
// glsl/wind.glsl's, GENERATED into src/webgpu/glsl_nodes.js by build.mjs (glsl_tsl.mjs); this file only calls
// them the way the mesh holds its data: a frame as three uniform rows, a tree's axes in a texture, the
// child offsets in a texture or a storage buffer, the rigid part from three's instanceMatrix when the CPU
// made it.  The tests hold the result to axialdeform.deform on every feature (tests/web/test_webgpu.py).
//
// Values: an instance is {d12, d34, d5, position, angles, scale, twist, taper} of nodes (and `matrix`, the
// columns of s R and p, when the CPU made them); a frame is {ea, eu, ev} (its rows: local coordinates
// F v = (ea.v, eu.v, ev.v), axis first).

import { If, Loop, float, int, uint, vec2, vec3, vec4, normalize, textureLoad, ivec2 } from 'three/tsl';
import * as glsl from './glsl_nodes.js';
import { WIND_UNIFORMS } from '../core/record.js';
import { matDiagonal, matTranspose, matVar, matVec } from './tsl_runtime.js';

export { axialCosSin, axialCurve, axialRotation, axialWindHash, axialPositionId } from './glsl_nodes.js';

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
  if (inst.matrix) {
    const m = inst.matrix;
    return { v: matVec(m, bentV).add(m[3]), n: normalize(matVec(m, bentN)), rot: m };
  }
  const out = { v: vec3(0).toVar(), n: vec3(0).toVar() };
  glsl.axialPlace(bentV, bentN, inst, out.v, out.n);
  return { ...out, rot: glsl.axialRotation(inst.angles) };
}

/** The wind's uniforms `w` ({dir, strength, ...}) as wind.glsl's functions take them (record.js's WIND_UNIFORMS). */
const windArgs = (w) => WIND_UNIFORMS.map((u) => w[u.name]);

/** The wind's push on instance `inst` (index id) in its model frame (axial_wind_push); w: the wind's
 * uniforms {dir, strength, gust, cycles, wavenumber}. */
export function axialWindPush(inst, id, len, w) {
  return glsl.axialWindPush(inst, uint(id), float(len), ...windArgs(w));
}

/** The instance as the wind bends it along frame f (axial_wind): d3 += u/6, d4 += u/2, d5 += u. */
export function axialWind(inst, id, f, len, w) {
  const moved = glsl.axialWind_AIum3fv3ffv2f(inst, uint(id), axialFrameMatrix(f), len, ...windArgs(w));
  return { ...inst, ...moved };
}

// ---- several axes (axial_tree_world's walk; its formulas are axial_tree_turn, axial_anchor_wind,
// axial_axis_add and axial_cofactor) ----

/** Axis j of the axes texture (rows: (e_a, lo), (e_u, len), (e_v, anchor), (parent, 0, 0, 0)). */
function treeAxis(axesTex, j) {
  const r0 = textureLoad(axesTex, ivec2(0, j)).toVar(), r1 = textureLoad(axesTex, ivec2(1, j)).toVar();
  const r2 = textureLoad(axesTex, ivec2(2, j)).toVar(), r3 = textureLoad(axesTex, ivec2(3, j));
  return { frame: axialFrameMatrix({ ea: r0.xyz, eu: r1.xyz, ev: r2.xyz }), lo: r0.w, len: r1.w, anchor: r2.w,
    parent: int(r3.x) };
}

/**
 * The whole map of a K-axis mesh (axial_tree_world): model-space v of axis b (an int node) and n ->
 * {v, n, jac (columns)} in the mesh's space.  children: the child offsets' texture (the mesh's
 * axialChildren) or a function of a texel's index (an int node) giving it (a storage buffer's), id: the
 * instance (int node), wind: the push per unit of axis length (a vec3 node) or null.
 */
export function axialTreeWorld(v, n, b, K, axesTex, center, inst, children, id, wind) {
  const moved = vec3(v).toVar();
  const jac = matVar(matDiagonal(float(1)));
  If(inst.twist.notEqual(0).or(inst.taper.notEqual(0)), () => { // about axis 0's line, before the displacements
    const a0 = treeAxis(axesTex, int(0));
    glsl.axialTreeTurn(v, a0.frame, a0.lo, a0.len, center, inst, moved, jac);
  });
  const disp = vec3(0).toVar();
  const j = int(b).toVar();
  Loop(K, () => {
    If(j.greaterThanEqual(int(0)), () => {
      const ax = treeAxis(axesTex, j);
      const d12 = vec4(inst.d12).toVar(), d34 = vec4(inst.d34).toVar(), d5 = vec2(inst.d5).toVar();
      If(j.greaterThan(int(0)), () => { // axial_child_offsets: texel i on of instance id's axis j
        const i = glsl.axialChildTexel(id, j, int(K)).toVar();
        if (typeof children === 'function') { // texel i of a storage buffer (a generated mesh's)
          d12.assign(children(i));
          d34.assign(children(i.add(int(1))));
          d5.assign(children(i.add(int(2))).xy);
        } else {
          const at = glsl.axialTexelAt(i).toVar();
          d12.assign(textureLoad(children, at));
          d34.assign(textureLoad(children, at.add(ivec2(1, 0))));
          d5.assign(textureLoad(children, at.add(ivec2(2, 0))).xy);
        }
        if (wind) glsl.axialAnchorWind(ax.frame, ax.len, ax.anchor, wind, d12, d34, d5);
      });
      glsl.axialAxisAdd(v, ax.frame, ax.lo, ax.len, d12, d34, d5, disp, jac);
      j.assign(ax.parent);
    });
  });
  moved.addAssign(disp);
  return { v: moved, n: normalize(glsl.axialCofactor(jac, n)), jac };
}

/** J x for the tree's Jacobian columns (tangents). */
export function axialJacobianTimes(jac, x) {
  return matVec(jac, x);
}
