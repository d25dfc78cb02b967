// instance_cull.js -- per-instance frustum culling of AxialInstancedMesh under three's WebGLRenderer: before
// each draw (the camera's, and each shadow map's) the CPU tests every instance's bend-aware bounding sphere
// (the one the mesh's bounds use: the base mesh's sphere grown by the bend, through the instance's matrix,
// grown by the wind's reach) against the frustum in the mesh's own space, writes the ids of those inside to
// an instanced index attribute (4 bytes an instance drawn, uploaded just before the draw) and draws that
// many.  The vertex shader (shader.js, AXIAL_CULLED) reads each drawn instance's numbers and matrix from a
// float texture by its id, so nothing else moves a frame.  The instanced attributes stay: raycasting and
// bake() read them (feedback.js).

import * as THREE from 'three';
import { AxialError } from '../core/adp.js';
import { CULL_TEXELS, CULL_WIDTH } from './shader.js';

// an instance's texels: d12, d34, (d5, tw, tp), (angles, -), the matrix's three rows, (tint, -)
const WIDTH = CULL_WIDTH;
const BLOCK = 64; // instances a block
const _m = new THREE.Matrix4(), _frustum = new THREE.Frustum(), _s = new THREE.Sphere();

class InstanceCulling {
  constructor(mesh, renderer) {
    const gl = renderer.getContext();
    this.mesh = mesh;
    this.gl = gl;
    const cap = mesh.capacity, rows = Math.ceil((cap * CULL_TEXELS) / WIDTH);
    this.texture = new THREE.DataTexture(new Float32Array(WIDTH * rows * 4), WIDTH, rows, THREE.RGBAFormat, THREE.FloatType);
    this.texture.minFilter = this.texture.magFilter = THREE.NearestFilter;
    this.ids = new Float32Array(cap);
    this.spheres = new Float32Array(4 * cap); // each instance's centre (mesh space) and radius without the wind
    this.scales = new Float32Array(cap); // and its scale: the wind's reach grows its radius by it
    this.buffer = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
    gl.bufferData(gl.ARRAY_BUFFER, this.ids.byteLength, gl.DYNAMIC_DRAW);
    // three binds a GLBufferAttribute by its buffer; marked instanced, it gets the divisor (as @three.ez/instanced-mesh does)
    const attr = new THREE.GLBufferAttribute(this.buffer, gl.FLOAT, 1, 4, cap);
    Object.assign(attr, { isInstancedBufferAttribute: true, meshPerAttribute: 1 });
    this.attribute = attr;
    this.drawn = 0;
    this.total = 0;
    // blocks of BLOCK instances near each other (sorted along a Morton curve of their centres), each with a
    // sphere holding its instances': a frame tests the blocks, then the instances of those the frustum cuts
    this.order = new Uint32Array(cap);
    this.blockOf = new Uint32Array(cap);
    this.blocks = new Float32Array(5 * Math.ceil(cap / BLOCK)); // centre, radius, largest scale
    this.sorted = -1; // the count the order was made for (-1: none)
    this.dirty = new Set(); // blocks whose instances changed since
    this.fill(0, mesh.count);
  }

  /** Instances first .. first + n - 1 into the texture and the spheres (after the mesh wrote them). */
  fill(first, n) {
    const mesh = this.mesh, tex = this.texture.image.data, a = mesh.geometry.attributes, M = mesh.instanceMatrix.array;
    const color = mesh.instanceColor ? mesh.instanceColor.array : null;
    for (let i = first; i < first + n; i++) {
      const o = i * CULL_TEXELS * 4;
      tex.set(a.axialD12.array.subarray(4 * i, 4 * i + 4), o);
      tex.set(a.axialD34.array.subarray(4 * i, 4 * i + 4), o + 4);
      tex.set(a.axialD5.array.subarray(2 * i, 2 * i + 2), o + 8);
      tex.set(a.axialTwistTaper.array.subarray(2 * i, 2 * i + 2), o + 10);
      tex.set(a.axialAngles.array.subarray(3 * i, 3 * i + 3), o + 12);
      for (let r = 0; r < 3; r++) for (let c = 0; c < 4; c++) tex[o + 16 + 4 * r + c] = M[16 * i + 4 * c + r]; // rows of M
      if (color) tex.set(color.subarray(3 * i, 3 * i + 3), o + 28);
      this.scales[i] = mesh._stillSphere(i, _s);
      _s.center.toArray(this.spheres, 4 * i);
      this.spheres[4 * i + 3] = _s.radius;
    }
    this.texture.needsUpdate = true;
    if (first === 0 && n === mesh.count) this.sorted = -1; // all of them: sort again
    else if (this.sorted >= 0) for (let i = first; i < Math.min(first + n, this.sorted); i++) this.dirty.add(this.blockOf[i]);
  }

  /** The instances in blocks along a Morton curve of their centres over the two widest axes of their box. */
  _sort() {
    const n = this.mesh.count, s = this.spheres, lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < n; i++) for (let c = 0; c < 3; c++) { lo[c] = Math.min(lo[c], s[4 * i + c]); hi[c] = Math.max(hi[c], s[4 * i + c]); }
    const [u, v] = [0, 1, 2].sort((a, b) => (hi[b] - lo[b]) - (hi[a] - lo[a]));
    const idBits = Math.max(1, Math.ceil(Math.log2(n + 1))), bits = Math.min(15, Math.floor((52 - idBits) / 2));
    const cells = 2 ** bits - 1, keys = new Float64Array(n);
    const spread = (x) => { let k = 0; for (let b = 0; b < bits; b++) k += ((x >> b) & 1) * 2 ** (2 * b); return k; };
    for (let i = 0; i < n; i++) {
      const a = Math.round(((s[4 * i + u] - lo[u]) / ((hi[u] - lo[u]) || 1)) * cells);
      const b = Math.round(((s[4 * i + v] - lo[v]) / ((hi[v] - lo[v]) || 1)) * cells);
      keys[i] = (spread(a) + 2 * spread(b)) * 2 ** idBits + i;
    }
    keys.sort();
    for (let k = 0; k < n; k++) {
      const i = keys[k] % 2 ** idBits;
      this.order[k] = i;
      this.blockOf[i] = Math.floor(k / BLOCK);
    }
    this.sorted = n;
    this.dirty.clear();
    for (let b = 0; b < Math.ceil(n / BLOCK); b++) this._blockSphere(b);
  }

  /** Block b's sphere: its instances' box's centre, the radius that holds their spheres, their largest scale. */
  _blockSphere(b) {
    const s = this.spheres, o = this.order, start = b * BLOCK, end = Math.min(start + BLOCK, this.sorted);
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    let r = 0, sc = 0;
    for (let k = start; k < end; k++) for (let c = 0; c < 3; c++) {
      lo[c] = Math.min(lo[c], s[4 * o[k] + c]);
      hi[c] = Math.max(hi[c], s[4 * o[k] + c]);
    }
    const c = [0, 1, 2].map((a) => (lo[a] + hi[a]) / 2);
    for (let k = start; k < end; k++) {
      const i = o[k];
      r = Math.max(r, Math.hypot(s[4 * i] - c[0], s[4 * i + 1] - c[1], s[4 * i + 2] - c[2]) + s[4 * i + 3]);
      sc = Math.max(sc, this.scales[i]);
    }
    this.blocks.set([c[0], c[1], c[2], r, sc], 5 * b);
  }

  /** Before a draw by `camera`: the instances inside its frustum become the ones drawn (the mesh's count). */
  before(camera) {
    const mesh = this.mesh, n = mesh.count, s = this.spheres, sc = this.scales, ids = this.ids, o = this.order, B = this.blocks;
    if (this.sorted !== n) this._sort();
    for (const b of this.dirty) this._blockSphere(b);
    this.dirty.clear();
    const grow = mesh._windGrow || 0;
    _m.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).multiply(mesh.matrixWorld);
    const p = _frustum.setFromProjectionMatrix(_m).planes.flatMap((q) => [q.normal.x, q.normal.y, q.normal.z, q.constant]);
    let k = 0;
    for (let b = 0, nb = Math.ceil(n / BLOCK); b < nb; b++) {
      const x = B[5 * b], y = B[5 * b + 1], z = B[5 * b + 2], R = B[5 * b + 3] + grow * B[5 * b + 4];
      let cut = false, out = false;
      for (let q = 0; q < 24; q += 4) {
        const d = p[q] * x + p[q + 1] * y + p[q + 2] * z + p[q + 3];
        if (d < -R) { out = true; break; }
        if (d < R) cut = true;
      }
      if (out) continue;
      const end = Math.min((b + 1) * BLOCK, n);
      if (!cut) { // wholly inside: every instance of the block
        for (let j = b * BLOCK; j < end; j++) ids[k++] = o[j];
        continue;
      }
      for (let j = b * BLOCK; j < end; j++) {
        const i = o[j], x = s[4 * i], y = s[4 * i + 1], z = s[4 * i + 2], r = -(s[4 * i + 3] + grow * sc[i]);
        if (p[0] * x + p[1] * y + p[2] * z + p[3] < r || p[4] * x + p[5] * y + p[6] * z + p[7] < r
          || p[8] * x + p[9] * y + p[10] * z + p[11] < r || p[12] * x + p[13] * y + p[14] * z + p[15] < r
          || p[16] * x + p[17] * y + p[18] * z + p[19] < r || p[20] * x + p[21] * y + p[22] * z + p[23] < r) continue;
        ids[k++] = i;
      }
    }
    const gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
    if (k > 0) gl.bufferSubData(gl.ARRAY_BUFFER, 0, ids, 0, k);
    this.total = n;
    this.drawn = k;
    mesh.count = k;
  }

  /** After the draw: the mesh holds all its instances again. */
  after() {
    this.mesh.count = this.total;
  }

  dispose() {
    this.gl.deleteBuffer(this.buffer);
    this.texture.dispose();
  }
}

/** Turn per-instance culling of `mesh` on for `renderer` (a WebGLRenderer: WebGL 2), or off (null). */
export function setInstanceCulling(mesh, renderer) {
  if (mesh._culling) {
    mesh._culling.dispose();
    mesh.geometry.deleteAttribute('axialIndex');
    mesh._culling = null;
    delete mesh.defines.AXIAL_CULLED;
  }
  if (renderer) {
    if (mesh.recipe) {
      throw new AxialError('setInstanceCulling: a generated layer holds the tiles around its camera, made on the GPU (no CPU copy to cull)');
    }
    if (!renderer.isWebGLRenderer || !renderer.capabilities.isWebGL2) {
      throw new AxialError('setInstanceCulling: expected a WebGLRenderer on WebGL 2 (WebGPURenderer: axialdeform-three/webgpu\'s setGPUCulling)');
    }
    const c = (mesh._culling = new InstanceCulling(mesh, renderer));
    mesh.geometry.setAttribute('axialIndex', c.attribute);
    mesh.axialUniforms.axialInstances = { value: c.texture };
    mesh.defines.AXIAL_CULLED = '1';
    mesh.frustumCulled = true;
  }
  mesh._allMaterials().forEach((m) => { m.needsUpdate = true; });
}

/** The hooks of culling, composed with a user's own (assigning onAfterRender, onBeforeShadow or onAfterShadow
 * sets theirs, which runs after ours): each draw of a camera or a shadow map culls for it. */
export function cullingHooks(mesh) {
  const wrap = (name, ours) => {
    let user = null;
    const hook = (...args) => {
      if (mesh._culling && !mesh._baked) ours(mesh._culling, ...args);
      if (user) user.apply(mesh, args);
    };
    Object.defineProperty(mesh, name, { get: () => hook, set: (fn) => { user = fn; }, configurable: true });
  };
  wrap('onAfterRender', (c) => c.after());
  wrap('onBeforeShadow', (c, _renderer, _object, _camera, shadowCamera) => c.before(shadowCamera));
  wrap('onAfterShadow', (c) => c.after());
}
