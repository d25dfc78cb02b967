// webgpu/generate.js -- generated layers under three's WebGPURenderer (axialdeform-three/webgpu): the part of
// an AxialInstancedMesh made with {generate: recipe} that makes its instances (the recipe, tiles, bounds:
// core/generate.js).  A tile's instances are made by a compute pass of glsl/generate.glsl as generated node
// functions (generate_nodes.js) -- what the tests hold to the Python library -- straight into a storage
// buffer the materials' positionNode reads (webgpu/mesh.js's layout:
// d12, d34, (d5, tw, tp), (angles, 0), the instance matrix's columns, the tint); a tree's child-axis
// offsets into a second one.  No record reaches the CPU to draw and none is uploaded: per tile set, the
// tiles' coordinates go up and the count of kept instances comes back, asynchronously.  A dropped slot
// has a zero matrix (its triangles collapse to a point), as under WebGL.  Storage buffers in the vertex
// stage: WebGPURenderer's WebGPU backend (its WebGL 2 fallback is refused in words).

import * as THREE from 'three/webgpu';
import { Fn, If, instanceIndex, storage, uniform, uint, int, ivec2, vec4, atomicAdd, atomicStore } from 'three/tsl';
import { AxialError, AXES_ROW, texelRows } from '../core/adp.js';
import { unbake } from '../core/baked.js';
import { ATTRIBUTES, SLOT } from '../core/record.js';
import { tilesWithin, maxTiles, slotRows, adoptSlotRecords, GENERATED_FLOATS } from '../core/generate.js';
import { recipeNodes, axialGenerate, axialGenerateChild, axialGenKey } from './generate_nodes.js';
import { axialRotation } from './nodes.js';

const WEBGPU_DEFAULT_BINDING = 134217728; // maxStorageBufferBindingSize a device has unless asked for more

/** A ground map ({data: Float32Array, cols, rows}) as a float texture read by textureLoad (1 x 1 where none). */
function mapTexture(m, key) {
  m = m || { data: new Float32Array(1), cols: 1, rows: 1 };
  if (!(m.data instanceof Float32Array) || m.data.length !== m.cols * m.rows) {
    throw new AxialError(`AxialInstancedMesh: maps.${key}: expected {data: Float32Array of cols x rows, cols, rows}`);
  }
  const tex = new THREE.DataTexture(m.data, m.cols, m.rows, THREE.RedFormat, THREE.FloatType);
  tex.minFilter = tex.magFilter = THREE.NearestFilter;
  tex.needsUpdate = true;
  return tex;
}

/**
 * The WebGPURenderer part of a generated layer (an AxialInstancedMesh of axialdeform-three/webgpu made with
 * {generate: recipe}; core/generate.js holds the recipe, tiles and bounds): the tiles' instances are made by a
 * compute pass into the buffer the materials read; the mesh's `kept` (how many of the `count` slots are kept) is
 * read back asynchronously: null until its `counted` (a promise) resolves.  The mesh's `recordsAsync()` reads the
 * kept records back; raycastAsync and bakeAsync read the tile set back once.
 */
export class GeneratedStorage {
  /** @param {any} mesh @param {any} options the mesh's (maxStorageBufferBindingSize) */
  constructor(mesh, options) {
    this.mesh = mesh;
    const cap = mesh.capacity, K = mesh.layout.axes, stride = mesh.layout.tint !== null ? 36 : 32;
    // the largest storage buffer, checked before any is allocated (the device's own limit again at the first draw)
    const limit = options.maxStorageBufferBindingSize ?? WEBGPU_DEFAULT_BINDING;
    const bytes = Math.max(cap * stride, K > 1 ? cap * (K - 1) * 12 : 0, cap * GENERATED_FLOATS) * 4;
    if (bytes > limit) {
      throw new AxialError(`AxialInstancedMesh: ${cap} slots (the tiles of ${mesh.recipe.tile} within a reach of ${mesh.recipe.reach}) `
        + `need a storage buffer of ${bytes} bytes, above maxStorageBufferBindingSize ${limit} (WebGPU's default); give a smaller `
        + 'reach, or the option maxStorageBufferBindingSize with the limit the renderer was given (new WebGPURenderer({ '
        + 'requiredLimits: { maxStorageBufferBindingSize: adapter.limits.maxStorageBufferBindingSize } }))');
    }
    mesh.kept = null;
    mesh.counted = Promise.resolve(null);
    /** @type {any} */ this.madeBy = null; /** @type {any} */ this.kernels = null; /** @type {any} */ this.textures = null;
    // the GPU's buffers: the drawn instances, the child axes' offsets (3 texels an axis), the slots as
    // records (read back when asked), the tiles' coordinates, the count kept
    this.drawnAttr = new THREE.StorageBufferAttribute(new Float32Array(cap * stride), 4);
    this.kidsAttr = K > 1 ? new THREE.StorageBufferAttribute(new Float32Array(cap * (K - 1) * 12), 4) : null;
    /** @type {any} */ this.slotsAttr = null;
    this.tilesAttr = new THREE.StorageBufferAttribute(new Int32Array(2 * maxTiles(mesh.recipe.tile, mesh.recipe.reach)), 2);
    this.countAttr = new THREE.StorageBufferAttribute(new Uint32Array(4), 1);
    mesh._storage = { instances: storage(this.drawnAttr, 'vec4', cap * stride / 4).toReadOnly(), stride };
    if (K > 1) {
      const kids = storage(this.kidsAttr, 'vec4', cap * (K - 1) * 3).toReadOnly();
      mesh._childTexels = (i) => kids.element(i);
    }
    this.slotCount = uniform(0, 'uint');
    // the materials read the instances from the storage buffer (the positionNode made again)
    mesh._positions = new Map();
    mesh._uniformNodes = null;
    const node = mesh._positionNode();
    (Array.isArray(mesh.material) ? mesh.material : [mesh.material]).forEach((m) => { m.positionNode = node; m.needsUpdate = true; });
  }

  /** The compute passes (made once): reset the count, make the drawn instances, the child axes' offsets, the slots. */
  _makeKernels() {
    if (this.kernels) return this.kernels;
    const r = recipeNodes(this.mesh.generatorUniforms);
    this.textures = ['heights', 'density', 'children'].map((k) => mapTexture(this.mesh.maps[k], k));
    const maps = { heights: this.textures[0], density: this.textures[1], children: this.textures[2] };
    const cap = this.mesh.capacity, K = this.mesh.layout.axes, stride = this.mesh._storage.stride, tinted = stride === 36;
    const tiles = storage(this.tilesAttr, 'ivec2', this.tilesAttr.count).toReadOnly();
    const counter = storage(this.countAttr, 'uint', 4).toAtomic();
    const drawn = storage(this.drawnAttr, 'vec4', cap * stride / 4);
    const n = this.slotCount, per = r.m.mul(r.m);
    const where = (slot) => { // slot -> (tile, i)
      const t = int(slot).div(per).toVar();
      return { tile: ivec2(tiles.element(t)).toVar(), i: int(slot).sub(t.mul(per)).toVar() };
    };
    const reset = Fn(() => { atomicStore(counter.element(uint(0)), uint(0)); })().compute(1);
    const make = Fn(() => {
      const slot = instanceIndex.toVar();
      If(slot.lessThan(n), () => {
        const { tile, i } = where(slot);
        const g = axialGenerate(r, maps, tile, i);
        const kept = g.kept.greaterThan(0.5).toVar();
        const o = slot.mul(uint(stride / 4)).toVar(), at = (k) => drawn.element(o.add(uint(k)));
        at(0).assign(g.d12);
        at(1).assign(g.d34);
        at(2).assign(vec4(g.d5, g.extra.y, g.extra.z));
        at(3).assign(vec4(g.angles, 0.0));
        const rot = axialRotation(g.angles);
        for (let c = 0; c < 3; c++) at(4 + c).assign(vec4(rot[c].mul(g.extra.x), 0.0));
        at(7).assign(vec4(g.position, 1.0));
        If(kept.not(), () => {
          for (let c = 0; c < 3; c++) at(4 + c).assign(vec4(0.0));
          at(7).assign(vec4(0.0, 0.0, 0.0, 1.0));
        });
        if (tinted) at(8).assign(vec4(g.tint, 0.0));
        If(kept, () => { atomicAdd(counter.element(uint(0)), uint(1)); });
      });
    })().compute(cap);
    const passes = [reset, make];
    if (K > 1) {
      const kids = storage(this.kidsAttr, 'vec4', cap * (K - 1) * 3);
      passes.push(Fn(() => { // one invocation a child axis of a slot
        const k = instanceIndex.toVar(), slot = k.div(uint(K - 1)).toVar();
        If(slot.lessThan(n), () => {
          const j = int(k.sub(slot.mul(uint(K - 1)))).add(1).toVar();
          const { tile, i } = where(slot);
          const d = axialGenerateChild(axialGenKey(r.seed, tile), i, j, maps.children);
          const o = k.mul(uint(3)).toVar();
          kids.element(o).assign(vec4(d[0], d[1]));
          kids.element(o.add(uint(1))).assign(vec4(d[2], d[3]));
          kids.element(o.add(uint(2))).assign(vec4(d[4], 0.0, 0.0));
        });
      })().compute(cap * (K - 1)));
    }
    this.kernels = { passes, slots: null, r, maps, where };
    return this.kernels;
  }

  /** The pass that writes the slots as records (GENERATED_FLOATS each, generate.vert's order), made when first asked. */
  _slotsKernel() {
    const k = this._makeKernels();
    if (k.slots) return k.slots;
    const cap = this.mesh.capacity, G = GENERATED_FLOATS;
    this.slotsAttr = new THREE.StorageBufferAttribute(new Float32Array(cap * G), 1);
    const out = storage(this.slotsAttr, 'float', cap * G);
    k.slots = Fn(() => {
      const slot = instanceIndex.toVar();
      If(slot.lessThan(this.slotCount), () => {
        const { tile, i } = k.where(slot);
        const g = axialGenerate(k.r, k.maps, tile, i);
        const o = slot.mul(uint(G)).toVar();
        SLOT.values.forEach(([name, c], k) => out.element(o.add(uint(k))).assign(c ? g[name][c] : g[name]));
      });
    })().compute(cap);
    return k.slots;
  }

  _check(renderer) {
    if (!renderer || !renderer.isWebGPURenderer) {
      throw new AxialError('AxialInstancedMesh (axialdeform-three/webgpu): a generated layer expected three\'s WebGPURenderer; with WebGLRenderer '
        + 'import AxialInstancedMesh from \'axialdeform-three\' instead');
    }
    if (!renderer._initialized) throw new AxialError('AxialInstancedMesh: the renderer is not ready: await renderer.init() first');
    if (!renderer.backend.isWebGPUBackend) {
      throw new AxialError('AxialInstancedMesh (axialdeform-three/webgpu): a generated layer\'s instances are read from storage buffers '
        + 'in the vertex stage, which WebGPURenderer\'s WebGL 2 fallback has not; draw with its WebGPU backend, or use '
        + 'AxialInstancedMesh from \'axialdeform-three\' with WebGLRenderer (WebGL 2 transform feedback)');
    }
    // every slot within reach in one storage buffer: WebGPU binds at most maxStorageBufferBindingSize bytes
    const limit = renderer.backend.device.limits.maxStorageBufferBindingSize;
    const bytes = Math.max(this.drawnAttr.array.byteLength, this.kidsAttr ? this.kidsAttr.array.byteLength : 0,
      this.mesh.capacity * GENERATED_FLOATS * 4);
    if (bytes > limit) {
      throw new AxialError(`AxialInstancedMesh: ${this.mesh.capacity} slots (the tiles of ${this.mesh.recipe.tile} within a reach of `
        + `${this.mesh.recipe.reach}) need a storage buffer of ${bytes} bytes, above this device's maxStorageBufferBindingSize `
        + `(${limit}); ask the adapter for more (new WebGPURenderer({ requiredLimits: { maxStorageBufferBindingSize: `
        + 'adapter.limits.maxStorageBufferBindingSize } }), as examples/web/generated-webgpu.html does) or give a smaller reach');
    }
  }

  /** Make the tiles within reach of `point` ({x, z}) if they changed (one compute dispatch of every slot);
   * returns whether they did.  `kept` is null until the count read back (`counted`) resolves. */
  update(renderer, point) {
    this._check(renderer);
    const { tiles, key } = tilesWithin(this.mesh, point);
    if (key === this.mesh._key && this.madeBy === renderer) return false;
    if (this.mesh._baked) unbake(this.mesh);
    const t0 = performance.now(), m = this.mesh.generatorUniforms.m, n = tiles.length * m * m;
    const { passes } = this._makeKernels();
    this.tilesAttr.array.set(tiles.flat());
    this.tilesAttr.needsUpdate = true;
    this.slotCount.value = n;
    renderer.compute(passes);
    this.madeBy = renderer;
    Object.assign(this.mesh, { tiles, _key: key, _materialized: false, count: n, kept: null, boundingSphere: null, boundingBox: null });
    const made = key;
    this.mesh.counted = renderer.getArrayBufferAsync(this.countAttr).then((b) => {
      const kept = new Uint32Array(b)[0];
      if (this.mesh._key === made) this.mesh.kept = kept;
      return kept;
    });
    // a renderer disposed before the read resolved rejects it: said to whoever awaits `counted`, never an uncaught error
    this.mesh.counted.catch(() => {});
    /** The last tiles' cost on the CPU (the dispatch; the GPU runs on). */
    this.mesh.timing = { slots: n, generateMs: performance.now() - t0 };
    this.mesh.dispatchEvent(/** @type {any} */ ({ type: 'paramschange', first: 0, count: n }));
    return true;
  }

  /** The slots read back as records (slotRows), by the slots pass and the child axes' buffer. */
  async _rowsAsync(renderer, compact) {
    if (!this.madeBy) return { rows: new Float32Array(0), kept: new Uint8Array(0), n: 0 };
    renderer = renderer || this.madeBy;
    renderer.compute(this._slotsKernel());
    const n = this.mesh.count, G = GENERATED_FLOATS, K = this.mesh.layout.axes;
    const raw = new Float32Array(await renderer.getArrayBufferAsync(this.slotsAttr)).subarray(0, n * G);
    let kids = null;
    if (K > 1) {
      const texels = new Float32Array(await renderer.getArrayBufferAsync(this.kidsAttr)), c = 10 * (K - 1);
      kids = new Float32Array(n * c);
      for (let a = 0; a < n * (K - 1); a++) kids.set(texels.subarray(12 * a, 12 * a + 10), 10 * a);
    }
    return slotRows(raw, kids, this.mesh.layout, compact);
  }

  /** The kept instances' records, read back from the GPU (the mesh's recordsAsync()). */
  async recordsAsync(renderer = null) {
    return (await this._rowsAsync(renderer, true)).rows;
  }

  /** The records on the CPU, one a slot (what raycastAsync, bakeAsync and the bounds read): read back once a tile set. */
  async materializeAsync(renderer) {
    if (this.mesh._materialized || !this.madeBy) return;
    const mesh = this.mesh, key = mesh._key, { rows, kept } = await this._rowsAsync(renderer, false);
    if (mesh._key !== key) return;
    adoptSlotRecords(mesh, rows, kept, (n) => { // the CPU copies (the draw reads the GPU's buffers)
      for (const a of ATTRIBUTES) mesh.geometry.setAttribute(a.name, new THREE.InstancedBufferAttribute(new Float32Array(n * a.size), a.size));
      mesh.instanceMatrix = new THREE.BufferAttribute(new Float32Array(n * 16), 16);
      if (mesh.instanceColor) mesh.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(n * 3), 3);
      mesh._packed = null;
      if (mesh.layout.axes > 1) { // the child offsets' texture
        const texels = texelRows(n, mesh.layout.axes), old = mesh.axialUniforms.axialChildren.value;
        mesh.axialUniforms.axialChildren.value = new THREE.DataTexture(new Float32Array(texels * AXES_ROW * 4), AXES_ROW, texels,
          THREE.RGBAFormat, THREE.FloatType);
        old.dispose();
      }
    });
  }

  /** The mesh's setDensity: the compute passes are made again from the new map at the next update, which makes
   * the tiles again. */
  densityChanged() {
    this._releaseKernels();
  }

  _releaseKernels() {
    if (!this.kernels) return;
    this.kernels.passes.forEach((p) => p.dispose());
    if (this.kernels.slots) this.kernels.slots.dispose();
    this.textures.forEach((t) => t.dispose());
    this.kernels = null;
  }

  dispose() {
    this._releaseKernels();
  }
}
