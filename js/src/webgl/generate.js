// webgl/generate.js -- a generated layer under WebGLRenderer (docs/generate.md): instances made on the GPU
// from a recipe, tile by tile around a point, by glsl/generate.glsl (the GLSL the Python library runs) by
// WebGL 2 transform feedback (tiles.js), drawn from the buffers the GPU wrote; none is read back to draw.
// The recipe, its tiles and bounds: core/generate.js.

import * as THREE from 'three';
import { ATTRIBUTES } from '../core/record.js';
import { worldEdge } from '../core/limits.js';
import { generatedBase, adoptGenerated, tilesAround, tileSize, slotRows, recipeBounds, setDensityOf } from '../core/generate.js';
import { AxialInstancedMesh } from './mesh.js';
import { TileGenerator, TileAttributes } from './tiles.js';

const _eye = new THREE.Vector3();

/**
 * A generated layer as one three.js object: an AxialInstancedMesh whose instances are made on the GPU
 * from `recipe` (checkRecipe) in the tiles within `recipe.reach` of a point.  Call
 * `update(renderer, point)` before rendering (e.g. with OrbitControls' target): it makes the tiles
 * when the set within reach changes and lets far ones go, so the instances held stay bounded.
 * options: AxialInstancedMesh's, and `axis` (default: the mesh's longest extent, as axialdeform's), `uniforms`
 * (generate.glsl's numbers as the Python library gave them; default: recipeUniforms, the flat ground), `maps`
 * (the ground maps those uniforms place: TileGenerator's) and `autoUpdate` (make the tiles around the camera's
 * position by itself, without calling update: what the glTF plugin's meshes do; they are drawn from the second
 * frame on, the first telling it the renderer and camera).  Its frustum culling is off: its tiles are around
 * the camera.  `tiles`: the tiles held ([[tx, tz], ...], nearest first), their instances in that order, m^2
 * each; `kept`: how many of the `count` slots drawn are kept (the rest collapse to a point).
 */
export class AxialGeneratedMesh extends AxialInstancedMesh {
  /** @type {any} */ recipe; /** @type {any} */ generatorUniforms; /** @type {any} */ maps; /** @type {any} */ tiles;
  /** @type {any} */ _key; /** @type {any} */ _drawnBy; /** @type {any} */ _slots; /** @type {any} */ timing;
  /** @type {boolean} */ autoUpdate; /** @type {number} */ kept; // set by adoptGenerated and update

  constructor(geometry, material, recipe, options = {}) {
    const base = generatedBase(geometry, recipe, options, 'AxialGeneratedMesh');
    super(geometry, material, base.record, base.options);
    adoptGenerated(this, base, options, (renderer) => renderer.isWebGLRenderer, true);
  }

  updateMatrixWorld(force) {
    super.updateMatrixWorld(force);
    const d = this._drawnBy;
    if (this.autoUpdate && d) this.update(d.renderer, d.camera.getWorldPosition(_eye));
  }

  /** Make the tiles within reach of `point` ({x, z}: a Vector3) if they changed; returns whether they did.
   * The GPU writes them where three draws from (tiles.js): every slot of the tiles drawn (`count`), the
   * ones a tile does not keep collapsed to a point; `kept` says how many are kept. */
  update(renderer, point) {
    const tiles = tilesAround(this.recipe.tile, point.x, point.z, this.recipe.reach, worldEdge(tileSize(this.recipe)[1]));
    const key = tiles.map((t) => t.join(',')).sort().join(';');
    if (key === this._key && this._generator && this._generator.renderer === renderer) return false;
    if (!this._generator || this._generator.renderer !== renderer) this._start(renderer);
    const t0 = performance.now(), gen = this._generator, n = tiles.length * gen.count;
    const slots = gen.make(tiles);
    const children = this.axis.axes ? this.axialUniforms.axialChildren.value : null;
    this._gpu.write(slots, n, tiles, children);
    if (children && !this._gpu.drawsTexels) this._uploadTexels(tiles, n, children);
    Object.assign(this, { tiles, _key: key, _slots: slots, _materialized: false, count: n, boundingSphere: null, boundingBox: null });
    const kept = this._gpu.kept(slots, n);
    this.kept = kept !== null ? kept : this._slotRecords(false).n;
    /** The last tiles' cost: the GPU passes and the one pixel of the count read back. */
    this.timing = { instances: this.kept, slots: n, generateMs: performance.now() - t0 };
    this.dispatchEvent(/** @type {any} */ ({ type: 'paramschange', first: 0, count: n }));
    return true;
  }

  /** A new density map for the recipe ({data: Float32Array, cols, rows}: grey levels in 0..1) and where it lies
   * ({d_lo, d_inv, d_wrap}, as the Python library's GroundMaps): an AxialBrush's; the tiles are made again on
   * the next update. */
  setDensity(grid, placement) {
    setDensityOf(this, grid, placement);
    if (this._generator) this._generator.setDensity(grid);
  }

  /** The generator and the GPU's attributes for `renderer`; three draws from those (the CPU copies stay
   * for what needs the records there: raycasting, bake, the bounds, read back when asked). */
  _start(renderer) {
    if (this._generator) { this._generator.dispose(); this._gpu.dispose(); }
    this._generator = new TileGenerator(renderer, this.generatorUniforms, this.maps);
    const names = [...ATTRIBUTES.map((a) => a.name), 'instanceMatrix', ...(this.layout.tint !== null ? ['instanceColor'] : [])];
    this._gpu = new TileAttributes(renderer, this._generator, this.capacity, names, this.layout.axes);
    this._cpuAttributes = this._cpuAttributes || Object.fromEntries(ATTRIBUTES.map((a) => [a.name, this.geometry.getAttribute(a.name)]));
    for (const [name, attr] of Object.entries(this._gpu.attributes)) this.geometry.setAttribute(name, attr);
  }

  /** Where a context cannot draw into float textures: the child axes' texels read back and uploaded. */
  _uploadTexels(tiles, n, texture) {
    const kids = this._generator.runChildren(tiles), c = 10 * (this.layout.axes - 1), out = texture.image.data;
    for (let i = 0; i < n; i++) {
      for (let j = 0; j < c / 10; j++) {
        const at = (i * (c / 10) + j) * 12, from = i * c + 10 * j;
        out.set(kids.subarray(from, from + 10), at);
        out[at + 10] = out[at + 11] = 0;
      }
    }
    texture.needsUpdate = true;
  }

  /** The slots read back as records (slotRows). */
  _slotRecords(compact) {
    const gen = this._generator;
    if (!this._slots) return { rows: new Float32Array(0), kept: new Uint8Array(0), n: 0 };
    return slotRows(gen.read(this._slots), this.layout.axes > 1 ? gen.runChildren(this.tiles) : null, this.layout, compact);
  }

  /** The kept instances' records (Float32Array, rows of numbersPerInstance), as the Python library's
   * generate_tiles gives them for `tiles`: read back from the GPU (tools and tests; drawing needs none). */
  records() {
    return this._slotRecords(true).rows;
  }

  /** The records on the CPU, one a slot (what raycasting, bake and the bounds read), read back once a tile set
   * into CPU copies grown to the slots drawn. */
  _materialize() {
    if (this._materialized || !this._slots) return;
    this._materialized = true;
    const { rows, kept } = this._slotRecords(false), n = kept.length;
    if (this._radii.length < n) {
      this.data = new Float32Array(n * this.layout.numbersPerInstance);
      this._radii = new Float32Array(n);
      this._grow = new Float32Array(n);
      for (const a of ATTRIBUTES) this._cpuAttributes[a.name] = new THREE.InstancedBufferAttribute(new Float32Array(n * a.size), a.size);
      this.instanceMatrix = new THREE.InstancedBufferAttribute(new Float32Array(n * 16), 16);
      if (this.instanceColor) this.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(n * 3), 3);
    }
    this._write(rows, 0);
    const m = this.instanceMatrix.array;
    kept.forEach((k, i) => { if (!k) { m.fill(0, 16 * i, 16 * i + 16); m[16 * i + 15] = 1; this._radii[i] = 0; } });
  }

  /** Before the records are read back (raycast, bake): recipeBounds; then the instances'. */
  computeBoundingSphere() {
    if (!this._slots || this._materialized) return super.computeBoundingSphere();
    recipeBounds(this);
  }

  raycast(raycaster, intersects) {
    this._fromRecords();
    return super.raycast(raycaster, intersects);
  }

  bake(renderer) {
    this._fromRecords();
    return super.bake(renderer);
  }

  /** The records read back (once a tile set) and the bounds made from them. */
  _fromRecords() {
    if (!this._slots || this._materialized) return;
    this._materialize();
    this.computeBoundingSphere();
  }

  dispose() {
    if (this._generator) { this._generator.dispose(); this._gpu.dispose(); }
    this._generator = null;
    return super.dispose();
  }
}
