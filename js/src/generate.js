// generate.js -- generated layers in three.js (docs/generate.md): instances made on the GPU from a
// recipe, tile by tile around a point, by glsl/generate.glsl -- the very GLSL the Python library runs
// (axialdeform.gl.generate), here by WebGL 2 transform feedback.  The records are read back once
// per tile set (the mesh's instance matrices, bounds and raycasting are on the CPU); 0 bytes an
// instance travel.  Conventions: the numpy reference axialdeform.core.generate.

import * as THREE from 'three';
import { AxialError } from './adp.js';
import { AXIAL_GLSL, WIND_GLSL, GENERATE_GLSL, GENERATE_VERT, GENERATE_CHILDREN_VERT } from './glsl.js';
import { AxialInstancedMesh } from './mesh.js';
import { refuseWebGPU, plainArray, feedbackLink } from './feedback.js';

/** Numbers an instance the pass writes: the 22-number record (the 16, s, tw, tp, the tint), then 1 (kept)
 * or 0 (dropped by the ground maps and bands): generate.vert's outputs, in order. */
export const GENERATED_FLOATS = 23;
const VARYINGS = ['g_d12', 'g_d34', 'g_d5_px_py', 'g_pz_angles', 'g_extra', 'g_tint'];
const CHILD_VARYINGS = Array.from({ length: 15 }, (_, k) => `c_${k}`);
const NO_BAND = 3.0e38;
const _eye = new THREE.Vector3();
const BINOMIAL = [1, 4, 6, 4, 1];

function bad(field, expected, value) {
  throw new AxialError(`generate: ${field}: expected ${expected}, found ${JSON.stringify(value)}`);
}
const num = (v) => typeof v === 'number' && Number.isFinite(v);

/** Python's round(): half to even (m must be the Python library's for the same recipe). */
function roundHalfEven(x) {
  const f = Math.floor(x), d = x - f;
  if (d > 0.5) return f + 1;
  if (d < 0.5) return f;
  return f % 2 === 0 ? f : f + 1;
}

/** [m, cell]: cells a side of a tile, m = max(1, round(T sqrt(rate))), and the cell's side T / m. */
export function tileSize(recipe) {
  const m = Math.max(1, roundHalfEven(recipe.tile * Math.sqrt(recipe.rate)));
  return [m, recipe.tile / m];
}

/**
 * A recipe checked as axialdeform.core.generate.Generate checks it (a scene file's [layer.generate]):
 * {rate, tile = 16, min_distance = 0, seed = 0, bend = 0.1, scale = null ([lo, hi]), twist = 0,
 * taper = 0, reach = 3 tile}.  Returns a new object with the defaults filled in.
 */
export function checkRecipe(recipe) {
  if (!recipe || typeof recipe !== 'object') throw new AxialError('generate: expected a recipe object {rate, tile, ...}');
  const r = { tile: 16, min_distance: 0, seed: 0, bend: 0.1, scale: null, twist: 0, taper: 0, tint: null,
    tint_color: [1, 1, 1], ...recipe };
  for (const k of Object.keys(r)) {
    if (!['rate', 'tile', 'min_distance', 'seed', 'bend', 'scale', 'twist', 'taper', 'tint', 'tint_color', 'reach',
      'extent'].includes(k)) {
      throw new AxialError(`generate: ${k}: not a key of a recipe (rate, tile, min_distance, seed, bend, scale, twist, taper, tint, tint_color, reach)`);
    }
  }
  for (const k of ['rate', 'tile']) if (!(num(r[k]) && r[k] > 0)) bad(k, 'a finite number > 0', r[k]);
  if (!(Number.isInteger(r.seed) && r.seed >= 0 && r.seed < 2 ** 32)) bad('seed', 'an integer 0 .. 4294967295', r.seed);
  for (const k of ['min_distance', 'twist', 'taper']) if (!(num(r[k]) && r[k] >= 0)) bad(k, 'a finite number >= 0', r[k]);
  // one amplitude, or one per level of a mesh of several axes (the generator's own numbers hold them)
  const bends = Array.isArray(r.bend) ? r.bend : [r.bend];
  if (!bends.length || !bends.every((b) => num(b) && b >= 0)) bad('bend', 'a finite number >= 0, or one per level', r.bend);
  if (r.taper >= 1) bad('taper', 'a number in [0, 1)', r.taper);
  const cell = tileSize(r)[1];
  if (r.min_distance >= cell) bad('min_distance', `less than the cell side 1/sqrt(rate) = ${cell.toPrecision(6)}`, r.min_distance);
  if (r.scale !== null && !(Array.isArray(r.scale) && r.scale.length === 2 && r.scale.every((x) => num(x) && x > 0) &&
    r.scale[0] <= r.scale[1])) bad('scale', '[lo, hi] with 0 < lo <= hi', r.scale);
  if (r.tint !== null && !(num(r.tint) && r.tint >= 0 && r.tint <= 1)) bad('tint', 'an amount in [0, 1]', r.tint);
  if (!(Array.isArray(r.tint_color) && r.tint_color.length === 3 && r.tint_color.every((x) => num(x) && x >= 0 && x <= 1))) {
    bad('tint_color', 'three linear RGB numbers in [0, 1]', r.tint_color);
  }
  if (r.reach === undefined) r.reach = 3 * r.tile;
  if (!(num(r.reach) && r.reach > 0)) bad('reach', 'a finite number > 0', r.reach);
  return r;
}

/** Numbers a record: 22 with a tint, 19 with a scale, twist or taper, else 16. */
export function recipeWidth(recipe) {
  if (recipe.tint !== null) return 22;
  return recipe.scale !== null || recipe.twist > 0 || recipe.taper > 0 ? 19 : 16;
}

/** The axis axialdeform gives a mesh by default: its longest bounding-box extent (ties: x, y, z). */
export function autoAxis(positions) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    const c = i % 3;
    if (positions[i] < lo[c]) lo[c] = positions[i];
    if (positions[i] > hi[c]) hi[c] = positions[i];
  }
  let index = 0;
  for (let c = 1; c < 3; c++) if (hi[c] - lo[c] > hi[index] - lo[index]) index = c;
  return { index, lo: lo[index], length: hi[index] - lo[index] };
}

/**
 * The numbers generate.glsl's AxialRecipe takes (axialdeform.core.generate.recipe_uniforms): from the
 * recipe, the base mesh's positions (Float32Array of 3 n) and its resolved axis ({frame, lo, length}).
 * The anchor is the centre of the mesh's lowest bounding-box face (up = y), its place on the axis t_a.
 */
export function recipeUniforms(recipe, positions, axis) {
  const [m, cell] = tileSize(recipe);
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    const c = i % 3;
    if (positions[i] < lo[c]) lo[c] = positions[i];
    if (positions[i] > hi[c]) hi[c] = positions[i];
  }
  // as numpy does it on the float32 positions: the sum rounded to float32, then halved
  const a = [Math.fround(lo[0] + hi[0]) / 2, lo[1], Math.fround(lo[2] + hi[2]) / 2];
  const e = axis.frame[0];
  const along = e[0] * a[0] + e[1] * a[1] + e[2] * a[2];
  const t = Math.min(1, Math.max(0, (along - axis.lo) / axis.length));
  const w = BINOMIAL.map((b, i) => Math.fround(b * t ** i * (1 - t) ** (4 - i)));
  const [s0, s1] = recipe.scale || [1, 1];
  const bend = Array.isArray(recipe.bend) ? recipe.bend[0] : recipe.bend;
  return { seed: recipe.seed, m, cell, jitter: 1 - recipe.min_distance / cell, bend: bend * axis.length,
    scale: [s0, s1], twist: recipe.twist, taper: recipe.taper, anchor_y: lo[1], anchor_w: w.slice(0, 4), anchor_w4: w[4],
    tint: recipe.tint || 0, tint_color: recipe.tint_color.slice(),
    // no ground maps: the flat ground y = 0, no density map, no bands (the Python library's maps come
    // with its uniforms: AxialGeneratedMesh's options.uniforms and options.maps)
    has_heights: false, h_lo: [0, 0], h_inv: [1, 1], h_size: [0, 0], has_density: false, d_lo: [0, 0], d_inv: [1, 1],
    d_size: [0, 0], d_wrap: false, altitude: [-NO_BAND, NO_BAND], slope_tan2: [0, NO_BAND], choice: [0, 1],
    lift: [0, 0], align: 0, anchor_xz: [a[0], a[2]] };
}

/** [[tx, tz], ...]: the tiles any point of which lies within `reach` of (x, z), nearest first
 * (axialdeform.core.generate.tiles_around). */
export function tilesAround(tile, x, z, reach) {
  const out = [];
  for (let tx = Math.floor((x - reach) / tile); tx <= Math.floor((x + reach) / tile); tx++) {
    for (let tz = Math.floor((z - reach) / tile); tz <= Math.floor((z + reach) / tile); tz++) {
      const nx = Math.min(Math.max(x, tx * tile), (tx + 1) * tile), nz = Math.min(Math.max(z, tz * tile), (tz + 1) * tile);
      const d = Math.hypot(nx - x, nz - z);
      if (d <= reach) out.push([tx, tz, d]);
    }
  }
  out.sort((p, q) => p[2] - q[2] || p[0] - q[0] || p[1] - q[1]);
  return out.map(([tx, tz]) => [tx, tz]);
}

/** The most tiles tilesAround can return for `reach` (a generated mesh's capacity in tiles). */
export function maxTiles(tile, reach) {
  const k = Math.ceil((2 * reach) / tile) + 1;
  return k * k;
}

/**
 * glsl/generate.glsl in a WebGL 2 context by transform feedback: `run(tiles)` writes each tile's m^2
 * instances (GENERATED_FLOATS float32 each) into one GL buffer, tile after tile, and reads them back;
 * `runChildren(tiles)` a mesh of several axes' child offsets (10 a child axis, generate_children.vert).
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

  _program(main, varyings) {
    const head = '#version 300 es\nprecision highp float;\nprecision highp int;\n';
    return feedbackLink(this.gl, head + AXIAL_GLSL + WIND_GLSL + GENERATE_GLSL + main, varyings,
      this.gl.INTERLEAVED_ATTRIBS, 'generate');
  }

  _setUniforms(p) {
    const gl = this.gl, u = this.uniforms;
    const at = (name) => gl.getUniformLocation(p, name);
    gl.uniform1ui(at('u_seed'), u.seed);
    gl.uniform1i(at('u_m'), u.m);
    for (const k of ['cell', 'jitter', 'bend', 'twist', 'taper', 'anchor_y', 'anchor_w4', 'tint', 'align']) gl.uniform1f(at(`u_${k}`), u[k]);
    gl.uniform2f(at('u_scale'), u.scale[0], u.scale[1]);
    gl.uniform4f(at('u_anchor_w'), ...u.anchor_w);
    gl.uniform3f(at('u_tint_color'), ...u.tint_color);
    for (const k of ['has_heights', 'has_density', 'd_wrap']) gl.uniform1i(at(`u_${k}`), u[k] ? 1 : 0);
    for (const k of ['h_lo', 'h_inv', 'd_lo', 'd_inv', 'altitude', 'slope_tan2', 'choice', 'lift', 'anchor_xz']) gl.uniform2f(at(`u_${k}`), u[k][0], u[k][1]);
    for (const k of ['h_size', 'd_size']) gl.uniform2i(at(`u_${k}`), u[k][0], u[k][1]);
    gl.uniform1i(at('u_children_n'), this.childCount);
    this.textures.forEach((t, unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.uniform1i(at(['u_heights', 'u_density', 'u_children'][unit]), unit);
    });
  }

  /** One transform-feedback draw of `program` for each of `jobs` ({tile, first}), `floats` a vertex, into
   * one buffer (grown as needed), read back.  Leaves three's GL state reset. */
  _feedback(program, jobs, floats) {
    const gl = this.gl, each = this.count * floats * 4, bytes = jobs.length * each;
    const out = new Float32Array(bytes / 4);
    if (!bytes) return out;
    let buffer = this.buffers[floats];
    if (!buffer || buffer.bytes < bytes) {
      if (buffer) gl.deleteBuffer(buffer.gl);
      buffer = this.buffers[floats] = { gl: gl.createBuffer(), bytes };
      gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, buffer.gl);
      gl.bufferData(gl.TRANSFORM_FEEDBACK_BUFFER, bytes, gl.DYNAMIC_READ);
      gl.bindBuffer(gl.TRANSFORM_FEEDBACK_BUFFER, null);
    }
    gl.useProgram(program);
    this._setUniforms(program);
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
    gl.bindBuffer(gl.COPY_READ_BUFFER, buffer.gl);
    gl.getBufferSubData(gl.COPY_READ_BUFFER, 0, out);
    gl.bindBuffer(gl.COPY_READ_BUFFER, null);
    gl.bindVertexArray(null);
    this.renderer.resetState();
    return out;
  }

  /** The instances of `tiles` ([[tx, tz], ...]): a Float32Array of tiles.length m^2 rows of GENERATED_FLOATS,
   * tile after tile, cell order (instance i of a tile in cell (i mod m, i div m)), each ending in its
   * kept flag. */
  run(tiles) {
    return this._feedback(this.program, tiles.map((tile) => ({ tile })), GENERATED_FLOATS);
  }

  /** A mesh of several axes: the child offsets of `tiles`' instances, 10 (K - 1) a row in run's order. */
  runChildren(tiles) {
    const passes = Math.ceil(this.childCount / 6), n = tiles.length * this.count, w = 10 * this.childCount;
    const jobs = [];
    for (let p = 0; p < passes; p++) for (const tile of tiles) jobs.push({ tile, first: 6 * p + 1 });
    const raw = this._feedback(this.childProgram, jobs, 60), out = new Float32Array(n * w);
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

/**
 * A generated layer as one three.js object: an AxialInstancedMesh whose instances are made on the GPU
 * from `recipe` (checkRecipe) in the tiles within `recipe.reach` of a point.  Call
 * `update(renderer, point)` before rendering (e.g. with OrbitControls' target): it makes the tiles
 * when the set within reach changes and lets far ones go, so the instances held stay bounded.
 * options: AxialInstancedMesh's, and `axis` (default: the mesh's longest extent, as axialdeform's),
 * `uniforms` (generate.glsl's numbers as the Python library gave them; default: recipeUniforms, the
 * flat ground), `maps` (the ground maps those uniforms place: TileGenerator's) and `autoUpdate` (make
 * the tiles around the camera's position by itself, without calling update: what the glTF plugin's
 * meshes do; they are drawn from the second frame on, the first telling it the renderer and camera).  Its frustum culling is off: its tiles are around the camera.
 */
export class AxialGeneratedMesh extends AxialInstancedMesh {
  constructor(geometry, material, recipe, options = {}) {
    const r = checkRecipe(recipe);
    const position = geometry && geometry.isBufferGeometry ? geometry.getAttribute('position') : null;
    if (!position) throw new AxialError('AxialGeneratedMesh: expected a THREE.BufferGeometry with positions');
    const positions = plainArray(position);
    const [m] = tileSize(r);
    const spec = options.axis || autoAxis(positions);
    const axes = spec.axes ? spec.axes.count : 1; // a mesh of several axes: 10 more numbers a child axis
    super(geometry, material, { count: 0, numbersPerInstance: recipeWidth(r) + 10 * (axes - 1), axes, data: new Float32Array(0) },
      { ...options, axis: spec, capacity: maxTiles(r.tile, r.reach) * m * m });
    this.isAxialGeneratedMesh = true;
    this.type = 'AxialGeneratedMesh';
    this.recipe = r;
    this.generatorUniforms = options.uniforms || recipeUniforms(r, positions, this.axis);
    this.maps = options.maps || {};
    if (axes > 1 && !(this.maps.children && this.maps.children.rows === axes - 1 && this.maps.children.cols === 26)) {
      throw new AxialError(`AxialGeneratedMesh: a mesh of ${axes} axes needs options.maps.children (${axes - 1} rows of 26: each `
        + 'child axis\'s amplitude and joint projection, as axialdeform web and export write them)');
    }
    if (this.generatorUniforms.m !== m) throw new AxialError(`AxialGeneratedMesh: uniforms.m is ${this.generatorUniforms.m}, the recipe's ${m}`);
    /** The tiles held ([[tx, tz], ...], nearest first), their instances in that order, m^2 each. */
    this.tiles = [];
    this._key = null;
    this._generator = null;
    this.timing = null;
    this.frustumCulled = false;
    this.autoUpdate = Boolean(options.autoUpdate);
    // autoUpdate: each draw says which renderer and camera (the base mesh's hook, then ours, then a
    // user's own, which assigning onBeforeRender sets); the tiles are made when the next render updates
    // the world's matrices, before three uploads the instances (made in onBeforeRender, they would be
    // drawn a frame late), the very first ones at once
    const baseHook = this.onBeforeRender;
    let userHook = null;
    this._drawnBy = null;
    const hook = (renderer, scene, camera, ...rest) => {
      baseHook(renderer, scene, camera, ...rest);
      if (this.autoUpdate && renderer.isWebGLRenderer) {
        const first = this._drawnBy === null;
        this._drawnBy = { renderer, camera };
        if (first) this.update(renderer, camera.getWorldPosition(_eye));
      }
      if (userHook) userHook.call(this, renderer, scene, camera, ...rest);
    };
    Object.defineProperty(this, 'onBeforeRender', { get: () => hook, set: (fn) => { userHook = fn; }, configurable: true });
  }

  updateMatrixWorld(force) {
    super.updateMatrixWorld(force);
    const d = this._drawnBy;
    if (this.autoUpdate && d) this.update(d.renderer, d.camera.getWorldPosition(_eye));
  }

  /** Make the tiles within reach of `point` ({x, z}: a Vector3) if they changed; returns whether they did. */
  update(renderer, point) {
    const tiles = tilesAround(this.recipe.tile, point.x, point.z, this.recipe.reach);
    const key = tiles.map((t) => t.join(',')).sort().join(';');
    if (key === this._key && this._generator && this._generator.renderer === renderer) return false;
    if (!this._generator || this._generator.renderer !== renderer) {
      if (this._generator) this._generator.dispose();
      this._generator = new TileGenerator(renderer, this.generatorUniforms, this.maps);
    }
    const t0 = performance.now();
    const raw = this._generator.run(tiles), G = GENERATED_FLOATS;
    const kids = this.layout.axes > 1 ? this._generator.runChildren(tiles) : null;
    const t1 = performance.now();
    // the kept instances' records in order: axis 0's offsets, the child axes' (a tree), the rest
    const f = this.layout.numbersPerInstance, c = 10 * (this.layout.axes - 1), all = raw.length / G;
    let n = 0;
    for (let i = 0; i < all; i++) if (raw[i * G + G - 1] > 0.5) n++;
    const rows = new Float32Array(n * f);
    for (let i = 0, k = 0; i < all; i++) {
      if (!(raw[i * G + G - 1] > 0.5)) continue;
      rows.set(raw.subarray(i * G, i * G + 10), f * k);
      if (kids) rows.set(kids.subarray(i * c, (i + 1) * c), f * k + 10);
      rows.set(raw.subarray(i * G + 10, i * G + f - c), f * k + 10 + c);
      k++;
    }
    this.tiles = tiles;
    this._key = key;
    this.setParams(rows);
    /** The last tiles' cost: the GPU pass with its read-back, and the mesh's own work (matrices, bounds). */
    this.timing = { instances: n, generateMs: t1 - t0, applyMs: performance.now() - t1 };
    return true;
  }

  dispose() {
    if (this._generator) this._generator.dispose();
    this._generator = null;
    return super.dispose();
  }
}
