// webgl/generate.js -- a generated layer under WebGLRenderer (docs/generate.md): instances made on the GPU
// from a recipe, tile by tile around a point, by glsl/generate.glsl (the GLSL the Python library runs) by
// WebGL 2 transform feedback (tiles.js), drawn from the buffers the GPU wrote; none is read back to draw.
// The recipe, its tiles and bounds: core/generate.js.

import * as THREE from 'three';
import { AXES_ROW, texelRows } from '../core/adp.js';
import { ATTRIBUTES } from '../core/record.js';
import { tilesWithin, slotRows, adoptSlotRecords } from '../core/generate.js';
import { TileGenerator, TileAttributes } from './tiles.js';

/**
 * The WebGLRenderer part of a generated layer (an AxialInstancedMesh made with {generate: recipe}; core/generate.js
 * holds the recipe, tiles and bounds): the tiles' instances made by WebGL 2 transform feedback (tiles.js) straight
 * into the attributes three draws from; the records read back only when asked (records(), raycast, bake).
 */
export class GeneratedTiles {
  /** @param {any} mesh */
  constructor(mesh) {
    this.mesh = mesh;
    /** @type {any} */ this.generator = null; /** @type {any} */ this.gpu = null; /** @type {any} */ this.slots = null;
    if (mesh.layout.axes > 1) { // the child axes' texture the draw reads, sized for every slot (the GPU draws its texels)
      const old = mesh.axialUniforms.axialChildren.value, rows = texelRows(mesh.capacity, mesh.layout.axes);
      const tex = new THREE.DataTexture(new Float32Array(rows * AXES_ROW * 4), AXES_ROW, rows, THREE.RGBAFormat, THREE.FloatType);
      tex.minFilter = tex.magFilter = THREE.NearestFilter;
      tex.needsUpdate = true; // its storage: three allocates it at the first upload
      mesh.axialUniforms.axialChildren.value = tex;
      old.dispose();
    }
  }

  /** The mesh's update: the GPU writes the tiles' slots where three draws from (every slot of the tiles drawn:
   * `count`; the ones a tile does not keep collapse to a point; `kept` says how many are kept). */
  update(renderer, point) {
    const mesh = this.mesh, { tiles, key } = tilesWithin(mesh, point);
    if (key === mesh._key && this.generator && this.generator.renderer === renderer) return false;
    if (!this.generator || this.generator.renderer !== renderer) this._start(renderer);
    const t0 = performance.now(), gen = this.generator, n = tiles.length * gen.count;
    const slots = gen.make(tiles);
    const children = mesh.axis.axes ? mesh.axialUniforms.axialChildren.value : null;
    this.gpu.write(slots, n, tiles, children);
    if (children && !this.gpu.drawsTexels) this._uploadTexels(tiles, n, children);
    this.slots = slots;
    Object.assign(mesh, { tiles, _key: key, _materialized: false, count: n, boundingSphere: null, boundingBox: null });
    const kept = this.gpu.kept(slots, n);
    mesh.kept = kept !== null ? kept : this._slotRecords(false).n;
    /** The last tiles' cost: the GPU passes and the one pixel of the count read back. */
    mesh.timing = { instances: mesh.kept, slots: n, generateMs: performance.now() - t0 };
    mesh.dispatchEvent(/** @type {any} */ ({ type: 'paramschange', first: 0, count: n }));
    return true;
  }

  /** The mesh's setDensity: the generator takes the new map. */
  densityChanged(grid) {
    if (this.generator) this.generator.setDensity(grid);
  }

  /** The generator and the GPU's attributes for `renderer`; three draws from those (the CPU copies stay
   * for what needs the records there: raycasting, bake, the bounds, read back when asked). */
  _start(renderer) {
    const mesh = this.mesh;
    if (this.generator) { this.generator.dispose(); this.gpu.dispose(); }
    this.generator = new TileGenerator(renderer, mesh.generatorUniforms, mesh.maps);
    const names = [...ATTRIBUTES.map((a) => a.name), 'instanceMatrix', ...(mesh.layout.tint !== null ? ['instanceColor'] : [])];
    this.gpu = new TileAttributes(renderer, this.generator, mesh.capacity, names, mesh.layout.axes);
    mesh._cpuAttributes = mesh._cpuAttributes || Object.fromEntries(ATTRIBUTES.map((a) => [a.name, mesh.geometry.getAttribute(a.name)]));
    for (const [name, attr] of Object.entries(this.gpu.attributes)) mesh.geometry.setAttribute(name, attr);
  }

  /** Where a context cannot draw into float textures: the child axes' texels read back and uploaded. */
  _uploadTexels(tiles, n, texture) {
    const kids = this.generator.runChildren(tiles), c = 10 * (this.mesh.layout.axes - 1), out = texture.image.data;
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
    const gen = this.generator, mesh = this.mesh;
    if (!this.slots) return { rows: new Float32Array(0), kept: new Uint8Array(0), n: 0 };
    return slotRows(gen.read(this.slots), mesh.layout.axes > 1 ? gen.runChildren(mesh.tiles) : null, mesh.layout, compact);
  }

  /** The kept instances' records, read back from the GPU (the mesh's records()). */
  records() {
    return this._slotRecords(true).rows;
  }

  /** The records on the CPU, one a slot (what raycasting, bake and the bounds read), read back once a tile set
   * into CPU copies grown to the slots drawn; then the bounds made from them. */
  materialize() {
    const mesh = this.mesh;
    if (mesh._materialized || !this.slots) return;
    const { rows, kept } = this._slotRecords(false);
    adoptSlotRecords(mesh, rows, kept, (n) => { // the CPU copies (three draws from the GPU's attributes)
      for (const a of ATTRIBUTES) mesh._cpuAttributes[a.name] = new THREE.InstancedBufferAttribute(new Float32Array(n * a.size), a.size);
      mesh.instanceMatrix = new THREE.InstancedBufferAttribute(new Float32Array(n * 16), 16);
      if (mesh.instanceColor) mesh.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(n * 3), 3);
    });
  }

  dispose() {
    if (this.generator) { this.generator.dispose(); this.gpu.dispose(); }
    this.generator = null;
  }
}
