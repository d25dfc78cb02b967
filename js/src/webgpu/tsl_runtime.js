// tsl_runtime.js -- what the node functions generated from glsl/ (js/glsl_tsl.mjs) call that TSL does not
// spell as GLSL does: a mat3 is three column vectors (a JavaScript array), a struct a JavaScript object of
// nodes, texelFetch a texture's textureLoad or a storage buffer's element.  No formula lives here.

import { textureLoad, vec3, float } from 'three/tsl';

/** The switches of the generated node functions (glsl_tsl.mjs: a define such as AXIAL_NO_TURN kept as a static
 * if): set while a mesh's _bend composes its nodes (webgpu/mesh.js, core/variant.js), false otherwise.  A function
 * that reads one inside a dynamic If (whose body TSL builds later) gets the whole build: the same numbers. */
export const switches = { AXIAL_NO_TURN: false };

/** M v for M = [c0, c1, c2] (columns). */
export function matVec(m, v) {
  return m[0].mul(v.x).add(m[1].mul(v.y)).add(m[2].mul(v.z));
}

/** A B, column by column. */
export function matMul(a, b) {
  return b.map((c) => matVec(a, c));
}

/** s M. */
export function matScale(m, s) {
  return m.map((c) => c.mul(s));
}

/** A + B. */
export function matAdd(a, b) {
  return a.map((c, k) => c.add(b[k]));
}

/** A - B. */
export function matSub(a, b) {
  return a.map((c, k) => c.sub(b[k]));
}

/** M^T. */
export function matTranspose(m) {
  return [vec3(m[0].x, m[1].x, m[2].x), vec3(m[0].y, m[1].y, m[2].y), vec3(m[0].z, m[1].z, m[2].z)];
}

/** a b^T (GLSL's outerProduct): column k is a b_k. */
export function matOuter(a, b) {
  return [a.mul(b.x), a.mul(b.y), a.mul(b.z)];
}

/** s I. */
export function matDiagonal(s) {
  const z = float(0);
  return [vec3(s, z, z), vec3(z, s, z), vec3(z, z, s)];
}

/** A matrix variable: its three columns variables. */
export function matVar(m) {
  return m.map((c) => vec3(c).toVar());
}

/** M = value, column by column. */
export function matAssign(m, value) {
  m.forEach((c, k) => c.assign(value[k]));
}

/** A struct variable: every node field a variable (static booleans and other JavaScript values stay as they are). */
export function structVar(s) {
  return Object.fromEntries(Object.entries(s).map(([k, v]) => [k, v && v.isNode ? v.toVar() : v]));
}

/** texelFetch(tex, at, 0): a texture's texel, or -- `tex` a function of the texel -- a storage buffer's. */
export function texelFetch(tex, at) {
  return typeof tex === 'function' ? tex(at) : textureLoad(tex, at);
}
