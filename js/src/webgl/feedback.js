// feedback.js -- the one raw WebGL 2 pass of the module: a mesh's BEND (the materials' vertex code,
// glsl/axial.glsl) run by transform feedback over some or all of its instances, their placed
// positions, normals (and tangents) captured in GL buffers.  bake() draws from them, raycast()
// reads them back: there is no CPU copy of the Bézier maths.

import { AxialError } from '../core/adp.js';
import { AXIAL_GLSL, WIND_GLSL } from './glsl.js';
import { ATTRIBUTES } from '../core/record.js';
import { UNIFORMS, BEND, TREE_STORAGE } from './shader.js';
import { plainArray } from '../core/baked.js';


/**
 * One transform-feedback pass of the mesh's BEND (the materials' vertex code) over instances
 * `ids` (null: all): their placed positions, normals (and tangents) in new GL buffers, instance
 * after instance.  Leaves GL state changed: the caller resets three's (renderer.resetState()).
 */
/** Refuse three's WebGPURenderer in words (never a silent unbent picture): `what` it lacks. */
/** Why WebGLRenderer's mesh cannot be drawn by WebGPURenderer (refuseWebGPU's `what`). */
export const UNBENT_DRAW = 'does not run the onBeforeCompile patch the bend is made with, so every instance would be drawn unbent';

/** Throws for a node material given to the WebGL entry's mesh: it would be drawn unbent. */
export function refuseNodeMaterial(material) {
  throw new AxialError(`AxialInstancedMesh: ${material.type || 'a node material'} is a node material (three/webgpu): `
    + 'the bend is injected through onBeforeCompile, which node materials never run, so every instance would be '
    + 'drawn unbent; import AxialInstancedMesh from \'axialdeform-three/webgpu\' for node materials and WebGPURenderer, '
    + 'or use the classic material (MeshStandardMaterial, ...) with WebGLRenderer (docs/three.md)');
}

export function refuseWebGPU(renderer, what) {
  if (renderer && renderer.isWebGPURenderer) {
    throw new AxialError(`AxialInstancedMesh: three's WebGPURenderer (three/webgpu, either backend) ${what}; `
      + 'import AxialInstancedMesh from \'axialdeform-three/webgpu\' for WebGPURenderer, or draw this mesh with '
      + 'WebGLRenderer (docs/three.md: what works under which renderer)');
  }
}

export function feedback(mesh, renderer, ids, tangent) {
  refuseWebGPU(renderer, 'has no WebGL 2 transform feedback, which bending on the GPU uses (bake, raycast, vertices)');
  mesh._renderer = renderer;
  const gl = renderer.getContext(), g = mesh.geometry, V = g.getAttribute('position').count;
  const n = ids ? ids.length : mesh.count;
  const program = feedbackProgram(mesh, gl, tangent, mesh.axis.axes ? mesh.axis.axes.count : 0, Boolean(mesh._wind));
  const buffers = [];
  const upload = (array) => {
    const b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
    buffers.push(b);
    return b;
  };
  const vao = gl.createVertexArray();
  gl.bindVertexArray(vao);
  const bind = (name, array, size, divisor, stride = 0, offset = 0, column = 0) => {
    const at = gl.getAttribLocation(program, name);
    if (at < 0) return;
    gl.bindBuffer(gl.ARRAY_BUFFER, array);
    gl.enableVertexAttribArray(at + column);
    gl.vertexAttribPointer(at + column, size, gl.FLOAT, false, stride, offset);
    gl.vertexAttribDivisor(at + column, divisor);
  };
  // per instance: the attribute arrays as they are (all), or the rows of `ids` gathered
  const rows = (array, size) => {
    if (!ids) return array.subarray(0, size * n);
    const out = new Float32Array(size * n);
    ids.forEach((id, k) => out.set(array.subarray(size * id, size * (id + 1)), size * k));
    return out;
  };
  if (mesh.axis.axes) bind('axialAxis', upload(plainArray(g.getAttribute('axialAxis'))), 1, 0);
  bind('position', upload(plainArray(g.getAttribute('position'))), 3, 0);
  bind('normal', upload(plainArray(g.getAttribute('normal'))), 3, 0);
  if (tangent) bind('tangent', upload(plainArray(g.getAttribute('tangent'))), 4, 0);
  const a = mesh._cpuAttributes || g.attributes; // a generated mesh draws from GPU-written copies of these
  for (const { name, size } of ATTRIBUTES) bind(name, upload(rows(a[name].array, size)), size, 1);
  const mats = upload(rows(mesh.instanceMatrix.array, 16));
  for (let c = 0; c < 4; c++) bind('instanceMatrix', mats, 4, 1, 64, 16 * c, c);
  bind('axialId', upload(ids ? Float32Array.from(ids) : Float32Array.from({ length: n }, (_, i) => i)), 1, 1);
  gl.useProgram(program);
  // the mesh's uniforms, by their own names and types (no second naming of them here): the axis, a
  // tree's axes and offsets texture, the wind at this moment
  for (const [name, { value }] of Object.entries(mesh.axialUniforms)) setUniform(gl, renderer, program, name, value);
  const out = (size) => {
    const b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, n * V * size * 4, gl.STATIC_DRAW);
    return b;
  };
  const outputs = [out(3), out(3), ...(tangent ? [out(4)] : [])];
  gl.bindBuffer(gl.ARRAY_BUFFER, null); // a buffer bound elsewhere may not be written by the feedback
  const tf = gl.createTransformFeedback();
  gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, tf);
  outputs.forEach((b, i) => gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, i, b));
  gl.enable(gl.RASTERIZER_DISCARD);
  gl.beginTransformFeedback(gl.POINTS);
  gl.drawArraysInstanced(gl.POINTS, 0, V, n); // instance-major: instance k's vertices at k V
  gl.endTransformFeedback();
  gl.disable(gl.RASTERIZER_DISCARD);
  outputs.forEach((b, i) => gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, i, null));
  gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
  gl.deleteTransformFeedback(tf);
  gl.bindVertexArray(null);
  gl.deleteVertexArray(vao);
  buffers.forEach((b) => gl.deleteBuffer(b));
  return { gl, outputs };
}

function feedbackProgram(mesh, gl, tangent, axes = 0, wind = false) {
  const key = `${tangent ? 'tangent' : 'plain'}:${axes}:${wind ? 'wind' : ''}`;
  mesh._programs = mesh._programs || {};
  if (mesh._programs[key] && mesh._programs[key].gl === gl) return mesh._programs[key].program;
  const vs = `#version 300 es
precision highp float;
precision highp int;
${tangent ? '#define USE_TANGENT' : ''}
${axes ? `#define AXIAL_AXES ${axes}` : ''}
${wind ? '#define AXIAL_WIND 1' : ''}
${mesh.defines.AXIAL_POSITION_IDS ? '#define AXIAL_POSITION_IDS 1' : ''}
#define AXIAL_ID int(axialId + 0.5)
in vec3 position;
in vec3 normal;
in vec4 tangent;
in mat4 instanceMatrix;
in float axialId;           // the instance's index (the instances drawn may be a selection)
${UNIFORMS.replace(/attribute /g, 'in ')}
${AXIAL_GLSL}
${WIND_GLSL}
${TREE_STORAGE}
out vec3 axialOutPosition;
out vec3 axialOutNormal;
out vec4 axialOutTangent;
void main() {
${BEND}
mat4 m = instanceMatrix;
axialOutPosition = (m * vec4(axialV, 1.0)).xyz;
axialOutNormal = normalize(mat3(m) * axialN);
axialOutTangent = vec4(normalize(mat3(m) * axialT), tangent.w);
gl_Position = vec4(0.0);
}`;
  const varyings = ['axialOutPosition', 'axialOutNormal', ...(tangent ? ['axialOutTangent'] : [])];
  const program = feedbackLink(gl, vs, varyings, gl.SEPARATE_ATTRIBS, 'bake');
  mesh._programs[key] = { gl, program };
  return program;
}

/**
 * A transform-feedback program of WebGL 2 (the module's raw passes: the bend's, the generator's):
 * vertex shader `vs` (its own #version line), a fragment shader that writes nothing (or `fs`: a pass
 * that draws, `varyings` then []), `varyings` captured in `mode`.  A compile or link error is an
 * AxialError that names the pass (`what`).
 */
export function feedbackLink(gl, vs, varyings, mode, what,
  fs = '#version 300 es\nprecision highp float;\nout vec4 color;\nvoid main() { color = vec4(0.0); }') {
  const shader = (type, text) => {
    const sh = gl.createShader(type);
    gl.shaderSource(sh, text);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new AxialError(`${what}: the shader did not compile: ${gl.getShaderInfoLog(sh)}`);
    return sh;
  };
  const program = gl.createProgram();
  gl.attachShader(program, shader(gl.VERTEX_SHADER, vs));
  gl.attachShader(program, shader(gl.FRAGMENT_SHADER, fs));
  gl.transformFeedbackVaryings(program, varyings, mode);
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new AxialError(`${what}: the program did not link: ${gl.getProgramInfoLog(program)}`);
  return program;
}


/** Set uniform `name` of `program` from a three.js uniform value: a number, a Vector2/3, a Matrix3 or
 * an array of them, a Float32Array / Int32Array, or a texture (three uploads it; unit 0). */
function setUniform(gl, renderer, program, name, value) {
  const at = gl.getUniformLocation(program, name);
  if (at === null || value === null || value === undefined) return;
  if (value.isTexture) {
    renderer.initTexture(value);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, renderer.properties.get(value).__webglTexture);
    gl.uniform1i(at, 0);
  } else if (value.isMatrix3) {
    gl.uniformMatrix3fv(at, false, value.elements);
  } else if (Array.isArray(value) && value.length && value[0].isMatrix3) {
    const all = new Float32Array(9 * value.length);
    value.forEach((m, j) => all.set(m.elements, 9 * j));
    gl.uniformMatrix3fv(at, false, all);
  } else if (value.isVector3) {
    gl.uniform3f(at, value.x, value.y, value.z);
  } else if (value.isVector2) {
    gl.uniform2f(at, value.x, value.y);
  } else if (value instanceof Int32Array) {
    gl.uniform1iv(at, value);
  } else if (value instanceof Float32Array) {
    gl.uniform1fv(at, value);
  } else if (typeof value === 'number') {
    gl.uniform1f(at, value);
  } else {
    throw new AxialError(`bake: uniform ${name}: a value of a kind this pass does not set`);
  }
}
