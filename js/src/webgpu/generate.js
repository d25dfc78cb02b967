// webgpu/generate.js -- generated layers under three's WebGPURenderer (axialdeform-three/webgpu): the
// WebGL entry's AxialGeneratedMesh for node materials (the recipe, tiles, bounds: core/generate.js).  A tile's instances are made by a
// compute pass of glsl/generate.glsl as generated node functions (generate_nodes.js) -- what the tests hold to the Python
// library -- straight into a storage buffer the materials' positionNode reads (webgpu/mesh.js's layout:
// d12, d34, (d5, tw, tp), (angles, 0), the instance matrix's columns, the tint); a tree's child-axis
// offsets into a second one.  No record reaches the CPU to draw and none is uploaded: per tile set, the
// tiles' coordinates go up and the count of kept instances comes back, asynchronously.  A dropped slot
// has a zero matrix (its triangles collapse to a point), as under WebGL.  Storage buffers in the vertex
// stage: WebGPURenderer's WebGPU backend (its WebGL 2 fallback is refused in words).

import * as THREE from 'three/webgpu';
import { Fn, If, instanceIndex, storage, uniform, uint, int, ivec2, vec4, atomicAdd, atomicStore } from 'three/tsl';
import { AxialError, AXES_ROW, texelRows } from '../core/adp.js';
import { AxialInstancedMesh } from './mesh.js';
import { unbake } from '../core/baked.js';
import { ATTRIBUTES, SLOT } from '../core/record.js';
import { generatedBase, adoptGenerated, tilesAround, maxTiles, slotRows, recipeBounds, tileSize, GENERATED_FLOATS, setDensityOf }
  from '../core/generate.js';
import { worldEdge } from '../core/limits.js';
import { recipeNodes, axialGenerate, axialGenerateChild, axialGenKey } from './generate_nodes.js';
import { axialRotation } from './nodes.js';

const WEBGPU_DEFAULT_BINDING = 134217728; // maxStorageBufferBindingSize a device has unless asked for more

const _eye = new THREE.Vector3();

/** A ground map ({data: Float32Array, cols, rows}) as a float texture read by textureLoad (1 x 1 where none). */
function mapTexture(m, key) {
  m = m || { data: new Float32Array(1), cols: 1, rows: 1 };
  if (!(m.data instanceof Float32Array) || m.data.length !== m.cols * m.rows) {
    throw new AxialError(`AxialGeneratedMesh: maps.${key}: expected {data: Float32Array of cols x rows, cols, rows}`);
  }
  const tex = new THREE.DataTexture(m.data, m.cols, m.rows, THREE.RedFormat, THREE.FloatType);
  tex.minFilter = tex.magFilter = THREE.NearestFilter;
  tex.needsUpdate = true;
  return tex;
}

/**
 * A generated layer under WebGPURenderer (its WebGPU backend): the arguments, `update`, `tiles`,
 * `autoUpdate` and bounds of the WebGL module's AxialGeneratedMesh, with node materials.  The tiles'
 * instances are made by a compute pass into the buffer the materials read; `kept` (how many of the
 * `count` slots are kept) is read back asynchronously: null until `counted` (a promise) resolves.
 * `recordsAsync()` reads the kept records back; raycastAsync and bakeAsync read the tile set back once.
 */
export class AxialGeneratedMesh extends AxialInstancedMesh {
  /** @type {any} */ recipe; /** @type {any} */ generatorUniforms; /** @type {any} */ maps; /** @type {any} */ tiles;
  /** @type {any} */ _key; /** @type {any} */ _drawnBy; /** @type {any} */ _slots; /** @type {any} */ timing;
  /** @type {boolean} */ autoUpdate; /** @type {number} */ kept; /** @type {any} */ _madeBy; // set by adoptGenerated, update

  constructor(geometry, material, recipe, options = {}) {
    const base = generatedBase(geometry, recipe, options, 'AxialGeneratedMesh');
    super(geometry, material, base.record, base.options);
    adoptGenerated(this, base, options, (renderer) => renderer.isWebGPURenderer, false);
    const cap = this.capacity, K = this.layout.axes, stride = this.layout.tint !== null ? 36 : 32;
    // the largest storage buffer, checked before any is allocated (the device's own limit again at the first draw)
    const limit = options.maxStorageBufferBindingSize ?? WEBGPU_DEFAULT_BINDING;
    const bytes = Math.max(cap * stride, K > 1 ? cap * (K - 1) * 12 : 0, cap * GENERATED_FLOATS) * 4;
    if (bytes > limit) {
      throw new AxialError(`AxialGeneratedMesh: ${cap} slots (the tiles of ${this.recipe.tile} within a reach of ${this.recipe.reach}) `
        + `need a storage buffer of ${bytes} bytes, above maxStorageBufferBindingSize ${limit} (WebGPU's default); give a smaller `
        + 'reach, or the option maxStorageBufferBindingSize with the limit the renderer was given (new WebGPURenderer({ '
        + 'requiredLimits: { maxStorageBufferBindingSize: adapter.limits.maxStorageBufferBindingSize } }))');
    }
    this.kept = null;
    this.counted = Promise.resolve(null);
    // the GPU's buffers: the drawn instances, the child axes' offsets (3 texels an axis), the slots as
    // records (read back when asked), the tiles' coordinates, the count kept
    this._drawnAttr = new THREE.StorageBufferAttribute(new Float32Array(cap * stride), 4);
    this._kidsAttr = K > 1 ? new THREE.StorageBufferAttribute(new Float32Array(cap * (K - 1) * 12), 4) : null;
    this._slotsAttr = null;
    this._tilesAttr = new THREE.StorageBufferAttribute(new Int32Array(2 * maxTiles(this.recipe.tile, this.recipe.reach)), 2);
    this._countAttr = new THREE.StorageBufferAttribute(new Uint32Array(4), 1);
    this._storage = { instances: storage(this._drawnAttr, 'vec4', cap * stride / 4).toReadOnly(), stride };
    if (K > 1) {
      const kids = storage(this._kidsAttr, 'vec4', cap * (K - 1) * 3).toReadOnly();
      this._childTexels = (i) => kids.element(i);
    }
    this._slotCount = uniform(0, 'uint');
    this._kernels = null;
    // the materials read the instances from the storage buffer (the positionNode made again)
    this._positions = new Map();
    this._uniformNodes = null;
    const node = this._positionNode();
    (Array.isArray(this.material) ? this.material : [this.material]).forEach((m) => { m.positionNode = node; m.needsUpdate = true; });
  }

  updateMatrixWorld(force) {
    super.updateMatrixWorld(force);
    const d = this._drawnBy;
    if (this.autoUpdate && d) this.update(d.renderer, d.camera.getWorldPosition(_eye));
  }

  /** The compute passes (made once): reset the count, make the drawn instances, the child axes' offsets, the slots. */
  _makeKernels() {
    if (this._kernels) return this._kernels;
    const r = (this._recipeNodes = recipeNodes(this.generatorUniforms));
    this._textures = ['heights', 'density', 'children'].map((k) => mapTexture(this.maps[k], k));
    const maps = { heights: this._textures[0], density: this._textures[1], children: this._textures[2] };
    const cap = this.capacity, K = this.layout.axes, stride = this._storage.stride, tinted = stride === 36;
    const tiles = storage(this._tilesAttr, 'ivec2', this._tilesAttr.count).toReadOnly();
    const counter = storage(this._countAttr, 'uint', 4).toAtomic();
    const drawn = storage(this._drawnAttr, 'vec4', cap * stride / 4);
    const n = this._slotCount, per = r.m.mul(r.m);
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
      const kids = storage(this._kidsAttr, 'vec4', cap * (K - 1) * 3);
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
    this._kernels = { passes, slots: null, r, maps, where };
    return this._kernels;
  }

  /** The pass that writes the slots as records (GENERATED_FLOATS each, generate.vert's order), made when first asked. */
  _slotsKernel() {
    const k = this._makeKernels();
    if (k.slots) return k.slots;
    const cap = this.capacity, G = GENERATED_FLOATS;
    this._slotsAttr = new THREE.StorageBufferAttribute(new Float32Array(cap * G), 1);
    const out = storage(this._slotsAttr, 'float', cap * G);
    k.slots = Fn(() => {
      const slot = instanceIndex.toVar();
      If(slot.lessThan(this._slotCount), () => {
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
      throw new AxialError('AxialGeneratedMesh (axialdeform-three/webgpu): expected three\'s WebGPURenderer; with WebGLRenderer '
        + 'import AxialGeneratedMesh from \'axialdeform-three\' instead');
    }
    if (!renderer._initialized) throw new AxialError('AxialGeneratedMesh: the renderer is not ready: await renderer.init() first');
    if (!renderer.backend.isWebGPUBackend) {
      throw new AxialError('AxialGeneratedMesh (axialdeform-three/webgpu): the generated instances are read from storage buffers '
        + 'in the vertex stage, which WebGPURenderer\'s WebGL 2 fallback has not; draw with its WebGPU backend, or use '
        + 'AxialGeneratedMesh from \'axialdeform-three\' with WebGLRenderer (WebGL 2 transform feedback)');
    }
    // every slot within reach in one storage buffer: WebGPU binds at most maxStorageBufferBindingSize bytes
    const limit = renderer.backend.device.limits.maxStorageBufferBindingSize;
    const bytes = Math.max(this._drawnAttr.array.byteLength, this._kidsAttr ? this._kidsAttr.array.byteLength : 0,
      this.capacity * GENERATED_FLOATS * 4);
    if (bytes > limit) {
      throw new AxialError(`AxialGeneratedMesh: ${this.capacity} slots (the tiles of ${this.recipe.tile} within a reach of `
        + `${this.recipe.reach}) need a storage buffer of ${bytes} bytes, above this device's maxStorageBufferBindingSize `
        + `(${limit}); ask the adapter for more (new WebGPURenderer({ requiredLimits: { maxStorageBufferBindingSize: `
        + 'adapter.limits.maxStorageBufferBindingSize } }), as examples/web/generated-webgpu.html does) or give a smaller reach');
    }
  }

  /** Make the tiles within reach of `point` ({x, z}) if they changed (one compute dispatch of every slot);
   * returns whether they did.  `kept` is null until the count read back (`counted`) resolves. */
  update(renderer, point) {
    this._check(renderer);
    const tiles = tilesAround(this.recipe.tile, point.x, point.z, this.recipe.reach, worldEdge(tileSize(this.recipe)[1]));
    const key = tiles.map((t) => t.join(',')).sort().join(';');
    if (key === this._key && this._madeBy === renderer) return false;
    if (this._baked) unbake(this);
    const t0 = performance.now(), m = this.generatorUniforms.m, n = tiles.length * m * m;
    const { passes } = this._makeKernels();
    this._tilesAttr.array.set(tiles.flat());
    this._tilesAttr.needsUpdate = true;
    this._slotCount.value = n;
    renderer.compute(passes);
    Object.assign(this, { tiles, _key: key, _madeBy: renderer, _materialized: false, count: n, kept: null,
      boundingSphere: null, boundingBox: null });
    const made = key;
    this.counted = renderer.getArrayBufferAsync(this._countAttr).then((b) => {
      const kept = new Uint32Array(b)[0];
      if (this._key === made) this.kept = kept;
      return kept;
    });
    // a renderer disposed before the read resolved rejects it: said to whoever awaits `counted`, never an uncaught error
    this.counted.catch(() => {});
    /** The last tiles' cost on the CPU (the dispatch; the GPU runs on). */
    this.timing = { slots: n, generateMs: performance.now() - t0 };
    this.dispatchEvent(/** @type {any} */ ({ type: 'paramschange', first: 0, count: n }));
    return true;
  }

  /** The slots read back as records (slotRows), by the slots pass and the child axes' buffer. */
  async _rowsAsync(renderer, compact) {
    if (!this._madeBy) return { rows: new Float32Array(0), kept: new Uint8Array(0), n: 0 };
    renderer = renderer || this._madeBy;
    renderer.compute(this._slotsKernel());
    const n = this.count, G = GENERATED_FLOATS, K = this.layout.axes;
    const raw = new Float32Array(await renderer.getArrayBufferAsync(this._slotsAttr)).subarray(0, n * G);
    let kids = null;
    if (K > 1) {
      const texels = new Float32Array(await renderer.getArrayBufferAsync(this._kidsAttr)), c = 10 * (K - 1);
      kids = new Float32Array(n * c);
      for (let a = 0; a < n * (K - 1); a++) kids.set(texels.subarray(12 * a, 12 * a + 10), 10 * a);
    }
    return slotRows(raw, kids, this.layout, compact);
  }

  /** The kept instances' records (Float32Array, rows of numbersPerInstance), read back from the GPU, as the
   * Python library's generate_tiles gives them for `tiles` (tools and tests; drawing needs none). */
  async recordsAsync(renderer = null) {
    return (await this._rowsAsync(renderer, true)).rows;
  }

  /** The records on the CPU, one a slot (what raycastAsync, bakeAsync and the bounds read): read back once a tile set. */
  async _materializeAsync(renderer) {
    if (this._materialized || !this._madeBy) return;
    const key = this._key, { rows, kept } = await this._rowsAsync(renderer, false), n = kept.length;
    if (this._key !== key) return;
    if (this._radii.length < n) {
      this.data = new Float32Array(n * this.layout.numbersPerInstance);
      this._radii = new Float32Array(n);
      this._grow = new Float32Array(n);
      for (const a of ATTRIBUTES) this.geometry.setAttribute(a.name, new THREE.InstancedBufferAttribute(new Float32Array(n * a.size), a.size));
      this.instanceMatrix = new THREE.BufferAttribute(new Float32Array(n * 16), 16);
      if (this.instanceColor) this.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(n * 3), 3);
      this._packed = null;
      if (this.layout.axes > 1) { // the CPU's copy of the child offsets (the draw reads the GPU's buffer)
        const rows = texelRows(n, this.layout.axes), old = this.axialUniforms.axialChildren.value;
        this.axialUniforms.axialChildren.value = new THREE.DataTexture(new Float32Array(rows * AXES_ROW * 4), AXES_ROW, rows,
          THREE.RGBAFormat, THREE.FloatType);
        old.dispose();
      }
    }
    this._write(rows, 0);
    const m = this.instanceMatrix.array;
    kept.forEach((k, i) => { if (!k) { m.fill(0, 16 * i, 16 * i + 16); m[16 * i + 15] = 1; this._radii[i] = 0; } });
    this._materialized = true;
    this.computeBoundingSphere();
  }

  /** Before the records are read back: recipeBounds (from the recipe alone); then the instances'. */
  computeBoundingSphere() {
    if (!this._madeBy || this._materialized) return super.computeBoundingSphere();
    recipeBounds(this);
  }

  async raycastAsync(raycaster, renderer = this._madeBy) {
    await this._materializeAsync(renderer);
    return super.raycastAsync(raycaster, renderer);
  }

  async bakeAsync(renderer = this._madeBy) {
    await this._materializeAsync(renderer);
    return super.bakeAsync(renderer);
  }

  setGPUCulling(options = true) {
    if (options) throw new AxialError('setGPUCulling: a generated mesh draws every slot of the tiles within reach; its culling is the reach');
    return super.setGPUCulling(false);
  }

  /** A new density map for the recipe and where it lies (the WebGL entry's setDensity; an AxialBrush's): the
   * compute passes are made again from it at the next update, which makes the tiles again. */
  setDensity(grid, placement) {
    setDensityOf(this, grid, placement);
    this._releaseKernels();
  }

  _releaseKernels() {
    if (!this._kernels) return;
    this._kernels.passes.forEach((p) => p.dispose());
    if (this._kernels.slots) this._kernels.slots.dispose();
    this._textures.forEach((t) => t.dispose());
    this._kernels = null;
  }

  dispose() {
    this._releaseKernels();
    return super.dispose();
  }
}
