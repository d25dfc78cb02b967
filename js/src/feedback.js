// feedback.js -- the one raw WebGL 2 pass of the module: a mesh's BEND (the materials' vertex code,
// glsl/axial.glsl) run by transform feedback over some or all of its instances, their placed
// positions, normals (and tangents) captured in GL buffers.  bake() draws from them, raycast()
// reads them back: there is no CPU copy of the Bézier maths.

import { AxialError } from './adp.js';
import { AXIAL_GLSL, WIND_GLSL } from './glsl.js';
import { ATTRIBUTES } from './record.js';
import { UNIFORMS, BEND } from './shader.js';

/** A vertex attribute as a tight float32 array (interleaved, integer or normalized ones unpacked). */
export function plainArray(attr) {
  if (!attr.isInterleavedBufferAttribute && attr.array instanceof Float32Array) return attr.array;
  const out = new Float32Array(attr.count * attr.itemSize);
  for (let i = 0; i < attr.count; i++) for (let c = 0; c < attr.itemSize; c++) out[i * attr.itemSize + c] = attr.getComponent(i, c);
  return out;
}


/**
 * One transform-feedback pass of the mesh's BEND (the materials' vertex code) over instances
 * `ids` (null: all): their placed positions, normals (and tangents) in new GL buffers, instance
 * after instance.  Leaves GL state changed: the caller resets three's (renderer.resetState()).
 */
export function feedback(mesh, renderer, ids, tangent) {
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
  const a = g.attributes;
  for (const { name, size } of ATTRIBUTES) bind(name, upload(rows(a[name].array, size)), size, 1);
  const mats = upload(rows(mesh.instanceMatrix.array, 16));
  for (let c = 0; c < 4; c++) bind('instanceMatrix', mats, 4, 1, 64, 16 * c, c);
  bind('axialId', upload(ids ? Float32Array.from(ids) : Float32Array.from({ length: n }, (_, i) => i)), 1, 1);
  gl.useProgram(program);
  const u = mesh.axialUniforms;
  const loc = (name) => gl.getUniformLocation(program, name);
  gl.uniformMatrix3fv(loc('axialFrame'), false, u.axialFrame.value.elements);
  gl.uniform1f(loc('axialLo'), u.axialLo.value);
  gl.uniform1f(loc('axialLen'), u.axialLen.value);
  gl.uniform2f(loc('axialCenter'), u.axialCenter.value.x, u.axialCenter.value.y);
  if (mesh.axis.axes) { // several axes: every axis's frame, lo, L, parent, and the child offsets' texture
    const k = mesh.axis.axes.count, frames = new Float32Array(9 * k);
    u.axialFrames.value.forEach((m, j) => frames.set(m.elements, 9 * j));
    gl.uniformMatrix3fv(loc('axialFrames'), false, frames);
    gl.uniform1fv(loc('axialLos'), u.axialLos.value);
    gl.uniform1fv(loc('axialLens'), u.axialLens.value);
    gl.uniform1iv(loc('axialParents'), u.axialParents.value);
    renderer.initTexture(u.axialChildren.value); // uploaded by three: its GL texture, on unit 0
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, renderer.properties.get(u.axialChildren.value).__webglTexture);
    gl.uniform1i(loc('axialChildren'), 0);
  }
  if (mesh._wind) { // the wind at mesh moment, as the materials sway the instances
    const w = (name) => u[name].value;
    gl.uniform3f(loc('axialWindDir'), w('axialWindDir').x, w('axialWindDir').y, w('axialWindDir').z);
    gl.uniform1f(loc('axialWindStrength'), w('axialWindStrength'));
    gl.uniform1f(loc('axialWindGust'), w('axialWindGust'));
    gl.uniform2f(loc('axialWindCycles'), w('axialWindCycles').x, w('axialWindCycles').y);
    gl.uniform1f(loc('axialWindWavenumber'), w('axialWindWavenumber'));
  }
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
#define AXIAL_ID int(axialId + 0.5)
${AXIAL_GLSL}
${WIND_GLSL}
in vec3 position;
in vec3 normal;
in vec4 tangent;
in mat4 instanceMatrix;
in float axialId;           // the instance's index (the instances drawn may be a selection)
${UNIFORMS.replace(/attribute /g, 'in ')}
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
  const fs = '#version 300 es\nprecision highp float;\nout vec4 color;\nvoid main() { color = vec4(0.0); }';
  const shader = (type, text) => {
    const sh = gl.createShader(type);
    gl.shaderSource(sh, text);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new AxialError(`bake: the shader did not compile: ${gl.getShaderInfoLog(sh)}`);
    return sh;
  };
  const program = gl.createProgram();
  gl.attachShader(program, shader(gl.VERTEX_SHADER, vs));
  gl.attachShader(program, shader(gl.FRAGMENT_SHADER, fs));
  const varyings = ['axialOutPosition', 'axialOutNormal', ...(tangent ? ['axialOutTangent'] : [])];
  gl.transformFeedbackVaryings(program, varyings, gl.SEPARATE_ATTRIBS);
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new AxialError(`bake: the program did not link: ${gl.getProgramInfoLog(program)}`);
  mesh._programs[key] = { gl, program };
  return program;
}
