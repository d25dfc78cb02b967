// shader.js -- the bend in three's own materials: glsl/axial.glsl (glsl.js) and the code that calls
// it, injected into a built-in material's vertex shader (onBeforeCompile) before three's chunks, so
// maps, lights, shadows, fog and tone mapping stay three.js's.

import { AxialError } from '../core/adp.js';
import { AXIAL_GLSL, WIND_GLSL } from './glsl.js';
import { WIND_UNIFORMS } from '../core/record.js';

/** Per-instance culling's instance texture (instance_cull.js): texels an instance (the bend's numbers, the
 * matrix's three rows, the tint) and texels a row. */
export const CULL_TEXELS = 8;
export const CULL_WIDTH = 4096;

// the wind's uniforms as glsl/wind.glsl's functions take them (record.js's table, from axialdeform.core.wind)
const WIND_ARGS = WIND_UNIFORMS.map((w) => w.three).join(', ');

/** The uniforms and attributes the bend reads (attribute form; the feedback pass makes them `in`). */
export const UNIFORMS = `
#ifdef AXIAL_CULLED
// per-instance culling (instance_cull.js): the instances drawn are ids into the instance texture, 8 texels
// each -- the bend's numbers, the matrix's rows, the tint -- read once a vertex into what three's chunks and
// the bend read (instanceMatrix, instanceColor, the attributes below)
uniform highp sampler2D axialInstances;
attribute float axialIndex;
int axialInstanceId;
vec4 axialD12, axialD34;
vec2 axialD5, axialTwistTaper;
vec3 axialAngles; // the wind's only
mat4 axialInstanceMatrix;
#define instanceMatrix axialInstanceMatrix
#ifdef USE_INSTANCING_COLOR
vec3 axialInstanceColor;
#define instanceColor axialInstanceColor
#endif
#define AXIAL_ID axialInstanceId
void axial_fetch_instance() {
  axialInstanceId = int(axialIndex + 0.5);
  int x = (axialInstanceId % ${CULL_WIDTH / CULL_TEXELS}) * ${CULL_TEXELS}, y = axialInstanceId / ${CULL_WIDTH / CULL_TEXELS};
#ifndef AXIAL_NO_BEND
  axialD12 = texelFetch(axialInstances, ivec2(x, y), 0);
  axialD34 = texelFetch(axialInstances, ivec2(x + 1, y), 0);
  vec4 t = texelFetch(axialInstances, ivec2(x + 2, y), 0);
  axialD5 = t.xy;
  axialTwistTaper = t.zw;
#endif
#ifdef AXIAL_WIND
  axialAngles = texelFetch(axialInstances, ivec2(x + 3, y), 0).xyz;
#endif
  axialInstanceMatrix = transpose(mat4(texelFetch(axialInstances, ivec2(x + 4, y), 0), texelFetch(axialInstances, ivec2(x + 5, y), 0),
                                       texelFetch(axialInstances, ivec2(x + 6, y), 0), vec4(0.0, 0.0, 0.0, 1.0)));
#ifdef USE_INSTANCING_COLOR
  axialInstanceColor = texelFetch(axialInstances, ivec2(x + 7, y), 0).xyz;
#endif
}
#endif
#ifndef AXIAL_ID
#define AXIAL_ID gl_InstanceID
#endif
// the id of an instance's wind phase: its index, or (a generated mesh's, whose slots change as tiles come
// and go) where it stands (axial_position_id of glsl/wind.glsl)
#ifdef AXIAL_POSITION_IDS
#define AXIAL_PHASE_ID axial_position_id(axialPlaced.position)
#else
#define AXIAL_PHASE_ID uint(AXIAL_ID)
#endif
uniform mat3 axialFrame;
uniform float axialLo;
uniform float axialLen;
uniform vec2 axialCenter;
#ifdef AXIAL_AXES
uniform mat3 axialFrames[AXIAL_AXES];
uniform float axialLos[AXIAL_AXES];
uniform float axialLens[AXIAL_AXES];
uniform float axialAnchors[AXIAL_AXES];
uniform int axialParents[AXIAL_AXES];
uniform sampler2D axialChildren;
attribute float axialAxis;
#define AXIAL_TREE_WALK 1
#endif
#ifdef AXIAL_WIND
${WIND_UNIFORMS.map((w) => `uniform ${w.type} ${w.three};`).join('\n')}
#ifndef AXIAL_CULLED
attribute vec3 axialAngles;
#endif
#endif
#ifndef AXIAL_CULLED
attribute vec4 axialD12;
attribute vec4 axialD34;
attribute vec2 axialD5;
attribute vec2 axialTwistTaper;
#endif
`;

// the bend of this vertex, before three's chunks: model space, the instance's rigid part
// is instanceMatrix (three applies it in project_vertex, worldpos_vertex, defaultnormal_vertex)
export const BEND = `
#ifdef AXIAL_CULLED
  axial_fetch_instance();
#endif
  vec3 axialV = position, axialN = normal, axialT = vec3(1.0, 0.0, 0.0);
#ifdef AXIAL_NO_BEND
  // no instance bends (core/variant.js): only the rigid part, instanceMatrix's
#ifdef USE_TANGENT
  axialT = tangent.xyz;
#endif
#else
  {
    AxialInstance axialInst = AxialInstance(axialD12, axialD34, axialD5, vec3(0.0), vec3(0.0), 1.0,
                                            axialTwistTaper.x, axialTwistTaper.y);
    vec3 axialPush = vec3(0.0);
#ifdef AXIAL_WIND
    if (axialWindStrength != 0.0) {  // glsl/wind.glsl: the wind moves the control points
      AxialInstance axialPlaced = axialInst;
      axialPlaced.position = instanceMatrix[3].xyz;
      axialPlaced.angles = axialAngles;
#ifdef AXIAL_AXES
      axialPush = axial_wind_push(axialPlaced, AXIAL_PHASE_ID, 1.0, ${WIND_ARGS});
#endif
      axialInst = axial_wind(axialPlaced, AXIAL_PHASE_ID, axialFrame, axialLen, ${WIND_ARGS});
      axialInst.position = vec3(0.0);  // the rigid part stays instanceMatrix's
      axialInst.angles = vec3(0.0);
    }
#endif
#ifdef AXIAL_AXES
    mat3 axialJac;
#ifdef AXIAL_WIND
    AxialTreeWind axialTreeWind = AxialTreeWind(true, axialPush);
#else
    AxialTreeWind axialTreeWind = AxialTreeWind(false, axialPush);
#endif
    axial_tree_world(position, normal, int(axialAxis + 0.5), AXIAL_AXES, axialCenter, axialInst, AXIAL_ID,
                     axialTreeWind, axialV, axialN, axialJac);
#ifdef USE_TANGENT
    axialT = axialJac * tangent.xyz;
#endif
#else
    axial_bend(position, normal, axialFrame, axialLo, axialLen, axialCenter, axialInst, axialV, axialN);
#ifdef USE_TANGENT
    axialT = transpose(axialFrame) * axial_bend_tangent(axialFrame * position, axialFrame * tangent.xyz, 0,
                                                        axialLo, axialLen, axialCenter, axialInst);
#endif
#endif
  }
#endif
`;

// the tree walk's storage (glsl/axial.glsl's axial_tree_axis and axial_tree_offsets): the uniform arrays and
// the offsets' texture declared above
export const TREE_STORAGE = `
#ifdef AXIAL_AXES
void axial_tree_axis(int j, out mat3 frame, out float lo, out float len, out float anchor, out int parent) {
  frame = axialFrames[j];
  lo = axialLos[j];
  len = axialLens[j];
  anchor = axialAnchors[j];
  parent = axialParents[j];
}
void axial_tree_offsets(int id, int k, out vec4 d12, out vec4 d34, out vec2 d5) {
  axial_child_offsets(axialChildren, id, k, AXIAL_AXES, d12, d34, d5);
}
#endif
`;

function replaceOnce(text, what, by, where) {
  if (!text.includes(what)) throw new AxialError(`${where}: its vertex shader has no ${what} to bend`);
  return text.replace(what, by);
}

/** Inject the bend into a vertex shader of three's built-in materials (the text onBeforeCompile gets). */
export function injectBend(vertexShader, where = 'material') {
  let vs = replaceOnce(vertexShader, 'void main() {', `${UNIFORMS}\n${AXIAL_GLSL}\n${WIND_GLSL}\n${TREE_STORAGE}\nvoid main() {\n${BEND}`, where);
  if (vs.includes('#include <beginnormal_vertex>')) {
    vs = vs.replace('#include <beginnormal_vertex>',
      'vec3 objectNormal = axialN;\n#ifdef USE_TANGENT\n\tvec3 objectTangent = axialT;\n#endif');
  }
  return replaceOnce(vs, '#include <begin_vertex>',
    'vec3 transformed = axialV;\n#ifdef USE_ALPHAHASH\n\tvPosition = vec3( position );\n#endif', where);
}
