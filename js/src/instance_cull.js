// instance_cull.js -- per-instance frustum culling of AxialInstancedMesh under three's WebGLRenderer: before
// each draw (the camera's, and each shadow map's) the CPU tests every instance's bend-aware bounding sphere
// (the one the mesh's bounds use: the base mesh's sphere grown by the bend, through the instance's matrix,
// grown by the wind's reach) against the frustum in the mesh's own space, writes the ids of those inside to
// an instanced index attribute (4 bytes an instance drawn, uploaded just before the draw) and draws that
// many.  The vertex shader (shader.js, AXIAL_CULLED) reads each drawn instance's numbers and matrix from a
// float texture by its id, so nothing else moves a frame.  The instanced attributes stay: raycasting and
// bake() read them (feedback.js).

import * as THREE from 'three';
import { AxialError } from './adp.js';
import { CULL_TEXELS, CULL_WIDTH } from './shader.js';

// an instance's texels: d12, d34, (d5, tw, tp), (angles, -), the matrix's three rows, (tint, -)
const WIDTH = CULL_WIDTH;
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
    this.spheres = new Float32Array(4 * cap); // centre (mesh space), radius, then the scale the wind's reach grows by
    this.scales = new Float32Array(cap);
    this.buffer = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
    gl.bufferData(gl.ARRAY_BUFFER, this.ids.byteLength, gl.DYNAMIC_DRAW);
    // three binds a GLBufferAttribute by its buffer; marked instanced, it gets the divisor (as @three.ez/instanced-mesh does)
    const attr = new THREE.GLBufferAttribute(this.buffer, gl.FLOAT, 1, 4, cap);
    Object.assign(attr, { isInstancedBufferAttribute: true, meshPerAttribute: 1 });
    this.attribute = attr;
    this.drawn = 0;
    this.total = 0;
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
      const m = _m.fromArray(M, 16 * i), s = m.getMaxScaleOnAxis();
      _s.center.fromArray(mesh._center).applyMatrix4(m);
      this.spheres.set([_s.center.x, _s.center.y, _s.center.z, mesh._radii[i] * s], 4 * i);
      this.scales[i] = s;
    }
    this.texture.needsUpdate = true;
  }

  /** Before a draw by `camera`: the instances inside its frustum become the ones drawn (the mesh's count). */
  before(camera) {
    const mesh = this.mesh, n = mesh.count, s = this.spheres, sc = this.scales, ids = this.ids;
    const grow = mesh._windGrow || 0;
    _m.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).multiply(mesh.matrixWorld);
    const p = _frustum.setFromProjectionMatrix(_m).planes.flatMap((q) => [q.normal.x, q.normal.y, q.normal.z, q.constant]);
    let k = 0;
    for (let i = 0; i < n; i++) {
      const x = s[4 * i], y = s[4 * i + 1], z = s[4 * i + 2], r = -(s[4 * i + 3] + grow * sc[i]);
      if (p[0] * x + p[1] * y + p[2] * z + p[3] < r || p[4] * x + p[5] * y + p[6] * z + p[7] < r
        || p[8] * x + p[9] * y + p[10] * z + p[11] < r || p[12] * x + p[13] * y + p[14] * z + p[15] < r
        || p[16] * x + p[17] * y + p[18] * z + p[19] < r || p[20] * x + p[21] * y + p[22] * z + p[23] < r) continue;
      ids[k++] = i;
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
    if (mesh.isAxialGeneratedMesh) {
      throw new AxialError('setInstanceCulling: a generated mesh holds the tiles around its camera, made on the GPU (no CPU copy to cull)');
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
