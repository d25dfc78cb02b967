// generate_nodes.js -- a generated layer's instance for three's WebGPURenderer: glsl/generate.glsl's
// axial_generate and axial_generate_child as node functions (src/webgpu/glsl_generate_nodes.js, GENERATED from glsl/ by
// build.mjs), run by a compute pass (webgpu/generate.js); the tests hold them to
// axialdeform.core.generate (hash bit-exact, numbers to float32 rounding).  Here: the recipe's numbers
// as uniform nodes, and the calls with their out-variables made -- no formula.
//
// `r`: the recipe's numbers as nodes (recipeNodes: generate.glsl's AxialRecipe, the booleans plain
// JavaScript: they choose the code), `maps`: {heights, density, children} -- float textures (texel (col,
// row), red channel) read by textureLoad.

import { float, vec2, vec3, vec4, ivec2, uniform } from 'three/tsl';
import { Vector2, Vector3, Vector4 } from 'three/webgpu';
import * as glsl from './glsl_generate_nodes.js';
import { RECIPE_FIELDS } from '../core/record.js';

const VECTORS = { vec2: Vector2, vec3: Vector3, vec4: Vector4 };

/** generate.glsl's AxialRecipe from generatorUniforms (generate.js's recipeUniforms, or the Python
 * library's), field by field as the struct declares them (RECIPE_FIELDS): every number a uniform node,
 * the booleans (has_heights, has_density, d_wrap) plain: they choose the code. */
export function recipeNodes(u) {
  return Object.fromEntries(RECIPE_FIELDS.map(([name, type]) => {
    const v = u[name];
    if (type === 'bool') return [name, Boolean(v)];
    if (type === 'ivec2') return [name, ivec2(uniform(new Vector2(v[0], v[1])))];
    if (VECTORS[type]) return [name, uniform(new VECTORS[type](...v))];
    return [name, type === 'float' ? uniform(v) : uniform(v, type)];
  }));
}

/** The tile's key (axial_gen_key). */
export const axialGenKey = glsl.axialGenKey;

/** Instance i (an int node) of tile `tile` (an ivec2 node), axial_generate: {d12, d34, d5, position,
 * angles, extra (s, tw, tp), tint, kept (1.0 or 0.0)}, node variables. */
export function axialGenerate(r, maps, tile, i) {
  const g = { d12: vec4(0).toVar(), d34: vec4(0).toVar(), d5: vec2(0).toVar(), position: vec3(0).toVar(),
    angles: vec3(0).toVar(), extra: vec3(0).toVar(), tint: vec3(0).toVar(), kept: float(0).toVar() };
  glsl.axialGenerate(r, maps.heights, maps.density, tile, i, g.d12, g.d34, g.d5, g.position, g.angles, g.extra, g.tint, g.kept);
  return g;
}

/** Child axis j (an int node, 1 .. K-1) of instance i (axial_generate_child): its 5 offsets, vec2 node
 * variables.  `children`: K - 1 rows of 26 texels, amp_j then P_j row after row. */
export function axialGenerateChild(key, i, j, children) {
  const d = Array.from({ length: 5 }, () => vec2(0).toVar());
  glsl.axialGenerateChild(key, i, j, children, d);
  return d;
}
