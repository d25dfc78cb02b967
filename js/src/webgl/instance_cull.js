// instance_cull.js -- per-instance frustum culling of AxialInstancedMesh under three's WebGLRenderer: before
// each draw (the camera's, and each shadow map's) the CPU tests the instances' bend-aware bounding spheres
// block by block (core/cull.js) against the frustum in the mesh's own space, writes the ids of those inside to
// an instanced index attribute (4 bytes an instance drawn, uploaded just before the draw) and draws that
// many.  The vertex shader (shader.js, AXIAL_CULLED) reads each drawn instance's numbers and matrix from a
// float texture by its id, so nothing else moves a frame.  The instanced attributes stay: raycasting and
// bake() read them (feedback.js).

import * as THREE from 'three';
import { AxialError } from '../core/adp.js';
import { InstanceBlocks } from '../core/cull.js';
import { CULL_TEXELS, CULL_WIDTH } from './shader.js';

// an instance's texels: d12, d34, (d5, tw, tp), (angles, -), the matrix's three rows, (tint, -)
const WIDTH = CULL_WIDTH;

/** The CPU's culling (core/cull.js's blocks) and what WebGL draws from: the instance texture, the ids' buffer. */
class InstanceCulling extends InstanceBlocks {
  constructor(mesh, renderer) {
    super(mesh);
    const gl = renderer.getContext();
    this.gl = gl;
    const cap = mesh.capacity, rows = Math.ceil((cap * CULL_TEXELS) / WIDTH);
    this.texture = new THREE.DataTexture(new Float32Array(WIDTH * rows * 4), WIDTH, rows, THREE.RGBAFormat, THREE.FloatType);
    this.texture.minFilter = this.texture.magFilter = THREE.NearestFilter;
    this.ids = new Float32Array(cap);
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
    }
    this.texture.needsUpdate = true;
    super.fill(first, n);
  }

  /** Before a draw by `camera`: the instances inside its frustum become the ones drawn (the mesh's count). */
  before(camera) {
    const n = this.mesh.count, k = this.visible(camera, this.ids), gl = this.gl;
    gl.bindBuffer(gl.ARRAY_BUFFER, this.buffer);
    if (k > 0) gl.bufferSubData(gl.ARRAY_BUFFER, 0, this.ids, 0, k);
    this.total = n;
    this.drawn = k;
    this.mesh.count = k;
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
