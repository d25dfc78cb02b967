// webgl/tiles.js -- a generated layer's tiles on the GPU in a WebGL 2 context (docs/generate.md).
// TileGenerator runs glsl/generate.glsl -- the very GLSL the Python library runs -- by transform feedback:
// every tile's m^2 slots (23 float32: the 22-number record, then kept) into one GL buffer.  TileAttributes
// turns that buffer, still on the GPU, into the instanced attributes three.js draws from (the bend's
// numbers, instanceMatrix, instanceColor) and a tree's child-axis texels (glsl/generate_axes.vert drawn
// into the mesh's offsets texture): no record reaches the CPU and none is uploaded.  WebGL 2 has no
// geometry shader to drop the slots a tile does not keep, so every slot is drawn and a dropped one has a
// zero instanceMatrix (its triangles collapse to a point: no pixel).  The count kept is one pixel read
// back (each kept slot adds 1 to a 1 x 1 float target) where the context can blend float targets.

import * as THREE from 'three';
import { AxialError, AXES_ROW } from '../core/adp.js';
import { AXIAL_GLSL, WIND_GLSL, GENERATE_GLSL, GENERATE_VERT, GENERATE_CHILDREN_VERT, GENERATE_AXES_VERT,
  GENERATE_AXES_FRAG, SLOT_GLSL } from './glsl.js';
import { SLOT as SLOT_TABLE, RECIPE_FIELDS } from '../core/record.js';
import { GENERATED_FLOATS } from '../core/generate.js';
import { refuseWebGPU, feedbackLink } from './feedback.js';

const VARYINGS = SLOT_TABLE.groups.map((_, k) => `g_${k}`);
const CHILD_VARYINGS = Array.from({ length: SLOT_TABLE.childVectors }, (_, k) => `c_${k}`);
const HEAD = '#version 300 es\nprecision highp float;\nprecision highp int;\n';
// the gl.uniform* suffix of a recipe field's GLSL type (its base: f, i, ui)
const UNIFORM_KIND = { float: 'f', vec2: 'f', vec3: 'f', vec4: 'f', int: 'i', ivec2: 'i', uint: 'ui' };

/**
 * glsl/generate.glsl in a WebGL 2 context by transform feedback: `make(tiles)` writes each tile's m^2
 * instances (GENERATED_FLOATS float32 each) into one GL buffer, tile after tile, and leaves them there
 * (TileAttributes draws from them); `run(tiles)` reads them back (tests, tools, raycasting);
 * `runChildren(tiles)` a mesh of several axes' child offsets, read back (10 a child axis, generate_children.vert).
 * `maps`: {heights, density, children}: the ground maps, each {data: Float32Array (rows of cols), cols,
 * rows}, as the uniforms place them, and the child axes' table (K - 1 rows of 26: amp_j, P_j).
 */
export class TileGenerator {
  constructor(renderer, uniforms, maps = {}) {
    refuseWebGPU(renderer, 'has no WebGL 2 transform feedback, which the generator runs by');
    this.renderer = renderer;
    const gl = (this.gl = renderer.getContext());
    if (typeof WebGL2RenderingContext === 'undefined' || !(gl instanceof WebGL2RenderingContext)) {
      throw new AxialError('TileGenerator: the generator needs a WebGL 2 context');
    }
    this.uniforms = uniforms;
    this.count = uniforms.m * uniforms.m;
    this.program = this._program(GENERATE_VERT, VARYINGS);
    this.vao = gl.createVertexArray();
    this.buffers = {};
    // the maps as float32 textures read by texelFetch (a 1 x 1 stand-in where none)
    this.textures = ['heights', 'density', 'children'].map((key) => {
      const m = maps[key] || { data: new Float32Array(1), cols: 1, rows: 1 };
      if (!(m.data instanceof Float32Array) || m.data.length !== m.cols * m.rows) {
        throw new AxialError(`generate: maps.${key}: expected {data: Float32Array of cols x rows, cols, rows}`);
      }
      const t = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, m.cols, m.rows, 0, gl.RED, gl.FLOAT, m.data);
      for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
      gl.bindTexture(gl.TEXTURE_2D, null);
      return t;
    });
    this.childCount = maps.children ? maps.children.rows : 0;
    this.childProgram = this.childCount ? this._program(GENERATE_CHILDREN_VERT, CHILD_VARYINGS) : null;
    renderer.resetState();
  }

  /** A new density map ({data, cols, rows}; the uniforms that place it are the mesh's, shared). */
  setDensity(grid) {
    const gl = this.gl;
    gl.bindTexture(gl.TEXTURE_2D, this.textures[1]);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, grid.cols, grid.rows, 0, gl.RED, gl.FLOAT, grid.data);
    gl.bindTexture(gl.TEXTURE_2D, null);
    this.renderer.resetState();
  }

  _program(main, varyings) {
    return feedbackLink(this.gl, HEAD + AXIAL_GLSL + WIND_GLSL + GENERATE_GLSL + main, varyings,
      this.gl.INTERLEAVED_ATTRIBS, 'generate');
  }

  /** The recipe's uniforms and the maps (units 0, 1, 2) on `p`, the program in use. */
  setUniforms(p) {
    const gl = this.gl, u = this.uniforms;
    const at = (name) => gl.getUniformLocation(p, name);
    for (const [name, type] of RECIPE_FIELDS) { // generate.glsl's AxialRecipe: generate.vert's u_<name>
      const v = u[name], where = at(`u_${name}`);
      if (type === 'bool') gl.uniform1i(where, v ? 1 : 0);
      else gl[`uniform${Array.isArray(v) ? v.length : 1}${UNIFORM_KIND[type]}v`](where, Array.isArray(v) ? v : [v]);
    }
    gl.uniform1i(at('u_children_n'), this.childCount);
    this.textures.forEach((t, unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.uniform1i(at(['u_heights', 'u_density', 'u_children'][unit]), unit);
    });
  }

  /** One transform-feedback draw of `program` for each of `jobs` ({tile, first}), `floats` a vertex, into
   * one GL buffer (grown as needed), left on the GPU: {buffer, bytes}.  Leaves three's GL state reset. */
  _pass(program, jobs, floats) {
    const gl = this.gl, each = this.count * floats * 4, bytes = jobs.length * each;
    let buffer = this.buffers[floats];
    if (!buffer || buffer.bytes < bytes) {
      if (buffer) gl.deleteBuffer(buffer.gl);
      buffer = this.buffers[floats] = { gl: gl.createBuffer(), bytes: Math.max(bytes, 4) };
      gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, buffer.gl);
      gl.bufferData(gl.TRANSFORM_FEEDBACK_BUFFER, buffer.bytes, gl.DYNAMIC_COPY);
      gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, null);
    }
    if (!bytes) return { buffer: buffer.gl, bytes };
    gl.useProgram(program);
    this.setUniforms(program);
    gl.bindVertexArray(this.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
    const tf = gl.createTransformFeedback();
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, tf);
    gl.enable(gl.RASTERIZER_DISCARD);
    const tileAt = gl.getUniformLocation(program, 'u_tile'), firstAt = gl.getUniformLocation(program, 'u_first');
    jobs.forEach(({ tile, first }, k) => {
      gl.uniform2i(tileAt, tile[0], tile[1]);
      if (firstAt !== null) gl.uniform1i(firstAt, first);
      gl.bindBufferRange(gl.TRANSFORM_FEEDBACK_BUFFER, 0, buffer.gl, k * each, each);
      gl.beginTransformFeedback(gl.POINTS);
      gl.drawArrays(gl.POINTS, 0, this.count);
      gl.endTransformFeedback();
    });
    gl.disable(gl.RASTERIZER_DISCARD);
    gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
    gl.deleteTransformFeedback(tf);
    gl.bindVertexArray(null);
    this.renderer.resetState();
    return { buffer: buffer.gl, bytes };
  }

  /** A buffer make() left on the GPU, read back (a Float32Array). */
  read({ buffer, bytes }) {
    const gl = this.gl, out = new Float32Array(bytes / 4);
    if (!bytes) return out;
    gl.bindBuffer(gl.COPY_READ_BUFFER, buffer);
    gl.getBufferSubData(gl.COPY_READ_BUFFER, 0, out);
    gl.bindBuffer(gl.COPY_READ_BUFFER, null);
    return out;
  }

  /** The instances of `tiles` ([[tx, tz], ...]) into a GL buffer that stays on the GPU: {buffer, bytes},
   * tiles.length m^2 slots of GENERATED_FLOATS, tile after tile, cell order. */
  make(tiles) {
    return this._pass(this.program, tiles.map((tile) => ({ tile })), GENERATED_FLOATS);
  }

  /** make(tiles), read back: a Float32Array of tiles.length m^2 rows of GENERATED_FLOATS, tile after tile,
   * cell order (instance i of a tile in cell (i mod m, i div m)), each ending in its kept flag. */
  run(tiles) {
    return this.read(this.make(tiles));
  }

  /** A mesh of several axes: the child offsets of `tiles`' instances, 10 (K - 1) a row in run's order. */
  runChildren(tiles) {
    const passes = Math.ceil(this.childCount / 6), n = tiles.length * this.count, w = 10 * this.childCount;
    const jobs = [];
    for (let p = 0; p < passes; p++) for (const tile of tiles) jobs.push({ tile, first: 6 * p + 1 });
    const raw = this.read(this._pass(this.childProgram, jobs, 60)), out = new Float32Array(n * w);
    for (let p = 0; p < passes; p++) { // pass p holds axes 6p+1 .. 6p+6 of every instance
      const width = Math.min(60, w - 60 * p);
      for (let i = 0; i < n; i++) out.set(raw.subarray((p * n + i) * 60, (p * n + i) * 60 + width), i * w + 60 * p);
    }
    return out;
  }

  dispose() {
    const gl = this.gl;
    if (!gl) return;
    Object.values(this.buffers).forEach((b) => gl.deleteBuffer(b.gl));
    this.textures.forEach((t) => gl.deleteTexture(t));
    gl.deleteVertexArray(this.vao);
    gl.deleteProgram(this.program);
    if (this.childProgram) gl.deleteProgram(this.childProgram);
    this.gl = null;
  }
}

// a slot's numbers as the passes below read them: the inputs a_k and slot_<output> (slot.glsl)
const SLOT = `#define AXIAL_SLOT_READ 1\n${SLOT_GLSL}`;
/** The instanced attributes three draws, each its own GL buffer written from the slots: name, floats an
 * instance, the outputs' code (t_0 .. t_3: vec4 each, or one of `size` floats).  A dropped slot's
 * instanceMatrix is zero but for its 1 at (3, 3): every vertex lands on one point. */
const OUTPUTS = [
  { name: 'axialD12', size: 4, code: 't_0 = slot_d12;' },
  { name: 'axialD34', size: 4, code: 't_0 = slot_d34;' },
  { name: 'axialD5', size: 2, code: 't_0 = slot_d5;' },
  { name: 'axialAngles', size: 3, code: 't_0 = slot_angles;' },
  { name: 'axialTwistTaper', size: 2, code: 't_0 = slot_extra.yz;' },
  { name: 'instanceColor', size: 3, code: 't_0 = slot_tint;' },
  { name: 'instanceMatrix', size: 16, code: `mat3 r = slot_kept > 0.5 ? axial_rotation(slot_angles) * slot_extra.x : mat3(0.0);
    t_0 = vec4(r[0], 0.0); t_1 = vec4(r[1], 0.0); t_2 = vec4(r[2], 0.0);
    t_3 = slot_kept > 0.5 ? vec4(slot_position, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);` },
];

/** A GL buffer of three's as an instanced attribute (three's GLBufferAttribute, flagged instanced as
 * @three.ez/instanced-mesh's GLInstancedBufferAttribute does: WebGLBindingStates then sets its divisor). */
function instanced(buffer, size, capacity) {
  const attr = /** @type {any} */ (new THREE.GLBufferAttribute(buffer, 0x1406 /* FLOAT */, size, 4, capacity));
  attr.isInstancedBufferAttribute = true;
  attr.meshPerAttribute = 1;
  return attr;
}

/**
 * The instanced attributes of `capacity` slots on the GPU (`names`: which of axialD12, axialD34, axialD5,
 * axialAngles, axialTwistTaper, instanceColor, instanceMatrix), `attributes[name]` three's attribute of
 * each; `write(slots, n, tiles, children)` fills the first `n` from a slots buffer (TileGenerator.make),
 * and a tree's child-axis texels into `children` (three's DataTexture, AXES_ROW texels a row) from the
 * generator's table.  Leaves three's GL state reset.
 */
export class TileAttributes {
  constructor(renderer, generator, capacity, names, axes = 1) {
    const gl = (this.gl = renderer.getContext());
    this.renderer = renderer;
    this.generator = generator;
    this.attributes = {};
    this.passes = OUTPUTS.filter((o) => names.includes(o.name)).map((o) => {
      const vec = o.size >= 4 ? 'vec4' : (o.size === 1 ? 'float' : `vec${o.size}`);
      const outs = Array.from({ length: Math.ceil(o.size / 4) }, (_, k) => `t_${k}`);
      const vs = `${HEAD}${o.name === 'instanceMatrix' ? AXIAL_GLSL : ''}\n${SLOT}${outs.map((t) => `out ${vec} ${t};`).join('\n')}\n`
        + `void main() {\n    ${o.code}\n    gl_Position = vec4(0.0);\n}\n`;
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, capacity * o.size * 4, gl.DYNAMIC_COPY);
      this.attributes[o.name] = instanced(buffer, o.size, capacity);
      return { name: o.name, program: feedbackLink(gl, vs, outs, gl.INTERLEAVED_ATTRIBS, 'generate'), buffer };
    });
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
    this.vao = gl.createVertexArray();
    this.source = null;
    this.axes = axes;
    const floats = Boolean(gl.getExtension('EXT_color_buffer_float')); // float colour targets (three asks for it too)
    if (axes > 1) {
      this.axesProgram = linkDraw(gl, HEAD + '#define AXIAL_SLOT_CELLS 1\n' + AXIAL_GLSL + WIND_GLSL + GENERATE_GLSL
        + GENERATE_AXES_VERT, HEAD + GENERATE_AXES_FRAG);
      this.tileTexture = gl.createTexture();
      this.fbo = gl.createFramebuffer();
      // float colour targets: drawn into only where the context renders to them, else the texels are read
      // back and uploaded (a generated layer's fallback)
      this.drawsTexels = floats;
    }
    this.counts = floats && Boolean(gl.getExtension('EXT_float_blend'));
    if (this.counts) this._countPass();
    renderer.resetState();
  }

  _bindSlots(buffer) {
    const gl = this.gl;
    gl.bindVertexArray(this.vao);
    if (this.source === buffer) return;
    this.source = buffer;
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    SLOT_TABLE.groups.forEach(({ start, size }, at) => {
      gl.enableVertexAttribArray(at);
      gl.vertexAttribPointer(at, size, gl.FLOAT, false, 4 * GENERATED_FLOATS, 4 * start);
    });
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
  }

  /** Every attribute's first `n` slots from `slots` ({buffer}: TileGenerator.make's); a tree's texels. */
  write(slots, n, tiles, children = null) {
    const gl = this.gl;
    this._bindSlots(slots.buffer);
    const tf = gl.createTransformFeedback();
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, tf);
    gl.enable(gl.RASTERIZER_DISCARD);
    for (const p of this.passes) {
      gl.useProgram(p.program);
      gl.bindBufferRange(gl.TRANSFORM_FEEDBACK_BUFFER, 0, p.buffer, 0, n * this.attributes[p.name].itemSize * 4);
      gl.beginTransformFeedback(gl.POINTS);
      gl.drawArrays(gl.POINTS, 0, n);
      gl.endTransformFeedback();
      gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, 0, null);
    }
    gl.disable(gl.RASTERIZER_DISCARD);
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
    gl.deleteTransformFeedback(tf);
    gl.bindVertexArray(null);
    Object.values(this.attributes).forEach((a) => { a.count = n; a.version += 1; });
    if (children && this.drawsTexels) this._texels(tiles, n, children);
    this.renderer.resetState();
  }

  /** generate_axes.vert over the n slots (AXIAL_SLOT_CELLS: the tiles in a small integer texture) into
   * `children`'s GL texture, one point a texel. */
  _texels(tiles, n, children) {
    const gl = this.gl, renderer = this.renderer;
    renderer.initTexture(children);
    const target = renderer.properties.get(children).__webglTexture;
    gl.bindTexture(gl.TEXTURE_2D, this.tileTexture);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RG32I, tiles.length, 1, 0, gl.RG_INTEGER, gl.INT, Int32Array.from(tiles.flat()));
    for (const q of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, q, gl.NEAREST);
    const p = this.axesProgram, at = (name) => gl.getUniformLocation(p, name);
    gl.useProgram(p);
    gl.activeTexture(gl.TEXTURE2);
    gl.bindTexture(gl.TEXTURE_2D, this.generator.textures[2]);
    gl.activeTexture(gl.TEXTURE3);
    gl.bindTexture(gl.TEXTURE_2D, this.tileTexture);
    const { width, height } = children.image;
    gl.uniform1ui(at('u_seed'), this.generator.uniforms.seed);
    gl.uniform1i(at('u_children_n'), this.axes - 1);
    gl.uniform1i(at('u_row'), AXES_ROW);
    gl.uniform2i(at('u_size'), width, height);
    gl.uniform1i(at('u_count'), this.generator.count);
    gl.uniform1i(at('u_children'), 2);
    gl.uniform1i(at('u_tiles'), 3);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.fbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    gl.viewport(0, 0, width, height);
    for (const cap of [gl.BLEND, gl.DEPTH_TEST, gl.CULL_FACE, gl.SCISSOR_TEST, gl.STENCIL_TEST]) gl.disable(cap);
    gl.colorMask(true, true, true, true);
    gl.bindVertexArray(null);
    gl.drawArraysInstanced(gl.POINTS, 0, 3 * (this.axes - 1), n);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, null, 0);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }

  _countPass() {
    const gl = this.gl;
    this.countProgram = linkDraw(gl, `${HEAD}${SLOT}void main() {\n    gl_Position = slot_kept > 0.5 ? vec4(0.0, 0.0, 0.0, 1.0) : vec4(2.0, 2.0, 2.0, 1.0);\n`
      + '    gl_PointSize = 1.0;\n}\n', `${HEAD}out vec4 f_value;\nvoid main() {\n    f_value = vec4(1.0);\n}\n`);
    this.countTexture = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, this.countTexture);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, 1, 1, 0, gl.RGBA, gl.FLOAT, null);
    this.countFbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.countFbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, this.countTexture, 0);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }

  /** How many of the first `n` slots of `slots` are kept: each kept one adds 1 to one float pixel, read
   * back (null where the context cannot blend float targets). */
  kept(slots, n) {
    if (!this.counts) return null;
    const gl = this.gl, out = new Float32Array(4);
    this._bindSlots(slots.buffer);
    gl.useProgram(this.countProgram);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.countFbo);
    gl.viewport(0, 0, 1, 1);
    for (const cap of [gl.DEPTH_TEST, gl.CULL_FACE, gl.SCISSOR_TEST, gl.STENCIL_TEST]) gl.disable(cap);
    gl.colorMask(true, true, true, true);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT);
    gl.enable(gl.BLEND);
    gl.blendEquation(gl.FUNC_ADD);
    gl.blendFunc(gl.ONE, gl.ONE);
    gl.drawArrays(gl.POINTS, 0, n);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.FLOAT, out);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.bindVertexArray(null);
    this.renderer.resetState();
    return Math.round(out[0]);
  }

  dispose() {
    const gl = this.gl;
    if (!gl) return;
    this.passes.forEach((p) => { gl.deleteProgram(p.program); gl.deleteBuffer(p.buffer); });
    gl.deleteVertexArray(this.vao);
    if (this.axesProgram) { gl.deleteProgram(this.axesProgram); gl.deleteTexture(this.tileTexture); gl.deleteFramebuffer(this.fbo); }
    if (this.countProgram) { gl.deleteProgram(this.countProgram); gl.deleteTexture(this.countTexture); gl.deleteFramebuffer(this.countFbo); }
    this.gl = null;
  }
}

/** A vertex + fragment program (a pass that draws: feedbackLink's, nothing captured). */
function linkDraw(gl, vs, fs) {
  return feedbackLink(gl, vs, [], gl.INTERLEAVED_ATTRIBS, 'generate', fs);
}
