// core/cull.js -- what per-instance culling is under any renderer: every instance's bend-aware bounding sphere
// without the wind (the one the mesh's bounds use: the base mesh's sphere grown by the bend, through the
// instance's matrix) and its scale (the wind's reach grows the radius by it), the instances in blocks of BLOCK
// near each other (sorted along a Morton curve of their centres), each block with a sphere holding its
// instances'.  A frame tests the blocks, takes a block wholly inside as it is, and tests the instances of the
// blocks the frustum cuts: on the CPU under WebGLRenderer (webgl/instance_cull.js, visible() below), in a
// compute pass under WebGPU (webgpu/cull.js: one invocation a block).

import * as THREE from 'three';

/** Instances a block. */
export const BLOCK = 64;
const _s = new THREE.Sphere(), _m = new THREE.Matrix4(), _frustum = new THREE.Frustum();

export class InstanceBlocks {
  /** @param {any} mesh an AxialMeshCore */
  constructor(mesh) {
    const cap = mesh.capacity;
    this.mesh = mesh;
    this.spheres = new Float32Array(4 * cap); // each instance's centre (mesh space) and radius without the wind
    this.scales = new Float32Array(cap); // and its scale: the wind's reach grows its radius by it
    this.order = new Uint32Array(cap); // the instances block after block
    this.blockOf = new Uint32Array(cap);
    this.blocks = new Float32Array(8 * Math.ceil(cap / BLOCK)); // centre, radius, largest scale, first, end, 0, 0
    this.sorted = -1; // the count the order was made for (-1: none)
    this.dirty = new Set(); // blocks whose instances changed since
  }

  /** Instances first .. first + n - 1's spheres (after the mesh wrote them). */
  fill(first, n) {
    const mesh = this.mesh;
    for (let i = first; i < first + n; i++) {
      this.scales[i] = mesh._stillSphere(i, _s);
      _s.center.toArray(this.spheres, 4 * i);
      this.spheres[4 * i + 3] = _s.radius;
    }
    if (first === 0 && n === mesh.count) this.sorted = -1; // all of them: sort again
    else if (this.sorted >= 0) for (let i = first; i < Math.min(first + n, this.sorted); i++) this.dirty.add(this.blockOf[i]);
  }

  /** The blocks made for the mesh's count (sorted again when it changed, the changed blocks' spheres made
   * again); returns whether any changed. */
  refresh() {
    const n = this.mesh.count, changed = this.sorted !== n || this.dirty.size > 0;
    if (this.sorted !== n) this._sort();
    for (const b of this.dirty) this._blockSphere(b);
    this.dirty.clear();
    return changed;
  }

  /** How many blocks the mesh's instances fill. */
  get count() {
    return Math.ceil(this.sorted / BLOCK);
  }

  /** The instances in blocks along a Morton curve of their centres over the two widest axes of their box (a
   * 30-bit key an instance, ordered by two passes of a radix sort: ties keep their ids' order). */
  _sort() {
    const n = this.mesh.count, s = this.spheres, lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < n; i++) for (let c = 0; c < 3; c++) { lo[c] = Math.min(lo[c], s[4 * i + c]); hi[c] = Math.max(hi[c], s[4 * i + c]); }
    const [u, v] = [0, 1, 2].sort((a, b) => (hi[b] - lo[b]) - (hi[a] - lo[a]));
    const spread = (x) => { // the 15 bits of x to the even bits of 30
      x = (x | (x << 8)) & 0x00ff00ff; x = (x | (x << 4)) & 0x0f0f0f0f;
      x = (x | (x << 2)) & 0x33333333; return (x | (x << 1)) & 0x55555555;
    };
    const keys = new Uint32Array(n), su = 32767 / ((hi[u] - lo[u]) || 1), sv = 32767 / ((hi[v] - lo[v]) || 1);
    for (let i = 0; i < n; i++) {
      keys[i] = spread(Math.round((s[4 * i + u] - lo[u]) * su)) + 2 * spread(Math.round((s[4 * i + v] - lo[v]) * sv));
    }
    let from = new Uint32Array(n), to = new Uint32Array(n);
    for (let i = 0; i < n; i++) from[i] = i;
    for (const shift of [0, 15]) {
      const counts = new Uint32Array(32769);
      for (let k = 0; k < n; k++) counts[((keys[from[k]] >>> shift) & 32767) + 1]++;
      for (let d = 1; d <= 32768; d++) counts[d] += counts[d - 1];
      for (let k = 0; k < n; k++) to[counts[(keys[from[k]] >>> shift) & 32767]++] = from[k];
      [from, to] = [to, from];
    }
    this.order.set(from);
    for (let k = 0; k < n; k++) this.blockOf[from[k]] = Math.floor(k / BLOCK);
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
    this.blocks.set([c[0], c[1], c[2], r, sc, start, end, 0], 8 * b);
  }

  /** The six planes (a, b, c, d: inside where a x + b y + c z + d >= 0) of `camera`'s frustum in the mesh's space. */
  planes(camera) {
    _m.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).multiply(this.mesh.matrixWorld);
    return /** @type {any} */ (_frustum).setFromProjectionMatrix(_m, camera.coordinateSystem, camera.reversedDepth).planes;
  }

  /** The ids of the instances whose spheres (grown by the wind's reach) `camera` sees into `ids`; returns how many. */
  visible(camera, ids) {
    this.refresh();
    const n = this.mesh.count, s = this.spheres, sc = this.scales, o = this.order, B = this.blocks;
    const grow = this.mesh._windGrow || 0;
    const p = this.planes(camera).flatMap((q) => [q.normal.x, q.normal.y, q.normal.z, q.constant]);
    let k = 0;
    for (let b = 0, nb = Math.ceil(n / BLOCK); b < nb; b++) {
      const x = B[8 * b], y = B[8 * b + 1], z = B[8 * b + 2], R = B[8 * b + 3] + grow * B[8 * b + 4];
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
    return k;
  }
}
