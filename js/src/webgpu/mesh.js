// webgpu/mesh.js -- axialdeform-three/webgpu's AxialInstancedMesh (webgpu.js, the entry, documents it):
// the core mesh (core/mesh.js: record, bounds, wind) as 'axialdeform-three''s, but the bend is a node function on position and normal
// (nodes.js: glsl/axial.glsl as generated node functions) set as the material's positionNode, so three's shadow passes
// bend too; bake and raycasting bend by a compute pass (compute.js) read back asynchronously.

import * as THREE from 'three/webgpu';
import {
  Fn, attribute, instancedDynamicBufferAttribute, positionGeometry, normalGeometry, tangentGeometry, normalLocal,
  tangentLocal, instanceIndex, varyingProperty, reference, uniform, int, uint, float,
} from 'three/tsl';
import { AxialError } from '../core/adp.js';
import { WIND_UNIFORMS } from '../core/record.js';
import { AxialMeshCore } from '../core/mesh.js';
import { attachBake, unbake } from '../core/baked.js';
import { rayCandidates, intersectBent } from '../core/raycast.js';
import { GPUCulling } from './cull.js';
import { GeneratedStorage } from './generate.js';
import { bendAsync, releaseCompute } from './compute.js';
import { switches } from './tsl_runtime.js';
import { updateVariant, watchVariant } from '../core/variant.js';
import {
  axialBend, axialBendTangent, axialPlace, axialPlaceDirection, axialWind, axialWindPush, axialTreeWorld, axialJacobianTimes, axialPositionId,
} from './nodes.js';


// the classic materials WebGPURenderer converts, and their node twins (three's own NodeLibrary pairs)
const NODE_TWINS = ['MeshBasicMaterial', 'MeshLambertMaterial', 'MeshPhongMaterial', 'MeshStandardMaterial',
  'MeshPhysicalMaterial', 'MeshToonMaterial', 'MeshNormalMaterial', 'MeshMatcapMaterial'];

// the oldest three this entry draws right with: r171 to r181 bind the views of one instanced
// interleaved buffer at the wrong offsets (every instance misplaced; measured with r171, r175, r178,
// r181), r182 and r183 lose the shadow of instances after an update (measured)
const MIN_REVISION = 184;


/**
 * A THREE.InstancedMesh of `record.count` instances of `geometry`, each bent by its own numbers, for
 * WebGPURenderer: the arguments of axialdeform-three's AxialInstancedMesh; `material` a node material
 * (MeshStandardNodeMaterial, ...) or a classic one (turned into its node twin).  The bend is the
 * material's positionNode (with the exact normal and tangent), so shadows are bent too.  With {generate:
 * recipe} in place of the record, a generated layer: its tiles made by a compute pass (generate.js).
 */
export class AxialInstancedMesh extends AxialMeshCore {
  /** @type {any} GPU culling and levels of detail (cull.js), or null */
  _culling = null;

  constructor(geometry, material, record, options = {}) {
    if (!(Number(THREE.REVISION) >= MIN_REVISION)) {
      throw new AxialError(`AxialInstancedMesh (axialdeform-three/webgpu): three r${THREE.REVISION} is older than r${MIN_REVISION}, `
        + 'the first this entry draws right with; update three, or use \'axialdeform-three\' with WebGLRenderer');
    }
    super(geometry, material, record, options);
    if (this.recipe) this._part = new GeneratedStorage(this, options); // a generated layer: made by a compute pass
    watchVariant(this, () => this._rebend()); // the positionNode of what the instances use (core/variant.js)
  }

  _generatesWith(renderer) {
    return Boolean(renderer && renderer.isWebGPURenderer);
  }

  /** The instances' records (Float32Array, rows of numbersPerInstance): a generated layer's kept ones read back
   * from the GPU, as the Python library's generate_tiles gives them for `tiles` (tools and tests; drawing needs
   * none); otherwise the record's. */
  async recordsAsync(renderer = null) {
    return this.recipe ? this._part.recordsAsync(renderer) : this.data.slice(0, this.count * this.layout.numbersPerInstance);
  }

  /** A node-material clone of `material` whose positionNode bends this mesh's instances. */
  bendMaterial(material, clone = true) {
    if (!material || !material.isMaterial) throw new AxialError('AxialInstancedMesh: expected a THREE.Material');
    if (this._ownShader && clone) return material;
    let m;
    if (material.isNodeMaterial) {
      if (material.positionNode) {
        throw new AxialError(`AxialInstancedMesh: ${material.type} has a positionNode of its own; the bend sets the `
          + 'position (and the normal) of every vertex, so it would replace yours: give the material without it, or '
          + 'build your own from the exported nodes (axialdeform-three/webgpu nodes) with options.ownShader');
      }
      m = material.clone();
    } else if (NODE_TWINS.includes(material.type)) {
      const Twin = THREE[material.type.replace('Material', 'NodeMaterial')];
      m = new Twin();
      for (const key in material) { // as three's NodeLibrary.fromMaterial, keeping the twin's own identity
        if (key === 'uuid' || key === 'type' || key === '_listeners' || key.startsWith('is')) continue;
        m[key] = material[key];
      }
    } else {
      throw new AxialError(`AxialInstancedMesh: ${material.type} cannot be bent under WebGPURenderer: expected a node `
        + `material (MeshStandardNodeMaterial, ...) or one of ${NODE_TWINS.join(', ')}`);
    }
    m.positionNode = this._positionNode();
    m.needsUpdate = true;
    return m;
  }

  /** WebGPURenderer's shadow passes take the material's positionNode: no materials of our own. */
  _makeShadowMaterials() {
    return [];
  }

  _checkRenderer(renderer) {
    if (!renderer || !renderer.isWebGPURenderer) {
      throw new AxialError('AxialInstancedMesh (axialdeform-three/webgpu) bends in node materials, which only three\'s '
        + 'WebGPURenderer draws; with WebGLRenderer import AxialInstancedMesh from \'axialdeform-three\' instead');
    }
  }

  /** The uniforms of the bend as nodes (made once; the wind's read this mesh's axialUniforms). */
  _nodes() {
    if (this._uniformNodes) return this._uniformNodes;
    const ax = this.axis, u = {
      frame: { ea: uniform(new THREE.Vector3(...ax.frame[0])), eu: uniform(new THREE.Vector3(...ax.frame[1])),
        ev: uniform(new THREE.Vector3(...ax.frame[2])) },
      lo: uniform(ax.lo), len: uniform(ax.length), center: uniform(new THREE.Vector2(...ax.center)), axes: null,
    };
    if (ax.axes) { // the axes texture: a row an axis, (e_a, lo), (e_u, len), (e_v, anchor), (parent, 0, 0, 0)
      const k = ax.axes.count, data = new Float32Array(k * 16);
      for (let j = 0; j < k; j++) {
        const f = ax.axes.frames[j], a = ax.axes.anchors ? ax.axes.anchors[j] : 0;
        data.set([...f[0], ax.axes.lo[j], ...f[1], ax.axes.length[j], ...f[2], a, ax.axes.parents[j], 0, 0, 0], 16 * j);
      }
      const tex = new THREE.DataTexture(data, 4, k, THREE.RGBAFormat, THREE.FloatType);
      tex.minFilter = tex.magFilter = THREE.NearestFilter;
      tex.needsUpdate = true;
      u.axes = { count: k, tex, children: this._childTexels || this.axialUniforms.axialChildren.value };
    }
    this._uniformNodes = u;
    return u;
  }

  _windNodes() {
    const u = this.axialUniforms; // {dir, strength, gust, cycles, wavenumber}: record.js's WIND_UNIFORMS
    return Object.fromEntries(WIND_UNIFORMS.map((w) => [w.name, reference('value', w.type, u[w.three])]));
  }

  /**
   * The bend of vertex (v, n, tangent or null, axis b) of instance `inst` (index id): {v, n, t} in
   * this mesh's space (W = R (s V'') + p), the one composition the draw and the compute pass share.
   */
  _bend(inst, id, v, n, tangent, b, variant = null) {
    // the draw's variant (core/variant.js): the generated functions leave the turn out while switches say so
    switches.AXIAL_NO_TURN = Boolean(variant && variant.noTurn);
    try {
      return this._bendNodes(inst, id, v, n, tangent, b, Boolean(variant && variant.rigid));
    } finally {
      switches.AXIAL_NO_TURN = false;
    }
  }

  _bendNodes(inst, id, v, n, tangent, b, rigid) {
    const u = this._nodes();
    let moved = inst, push = null;
    if (this._wind) {
      const w = this._windNodes();
      const phaseId = this.defines.AXIAL_POSITION_IDS ? axialPositionId(inst.position) : id; // a generated mesh's: where it stands
      if (u.axes) push = axialWindPush(inst, phaseId, float(1), w);
      moved = axialWind(inst, phaseId, u.frame, u.len, w);
    }
    let bent, tan = null;
    if (rigid) { // no instance bends and no wind blows (core/variant.js): the rigid part alone
      bent = { v, n };
      tan = tangent;
    } else if (u.axes) {
      bent = axialTreeWorld(v, n, b, u.axes.count, u.axes.tex, u.center, moved, u.axes.children, int(id), push);
      if (tangent) tan = axialJacobianTimes(bent.jac, tangent);
    } else {
      bent = axialBend(v, n, u.frame, u.lo, u.len, u.center, moved);
      if (tangent) tan = axialBendTangent(v, tangent, u.frame, u.lo, u.len, u.center, moved);
    }
    const placed = axialPlace(bent.v, bent.n, inst);
    const t = tan ? axialPlaceDirection(placed.rot, tan) : null;
    return { v: placed.v, n: placed.n, t };
  }

  /**
   * The materials' positionNode (one for every material of the mesh; made again when the wind comes
   * or goes).  `culled`: {ids, level, capacity, instances, geometry} -- a level of GPU culling
   * (cull.js): the instance is the level's visible id number instanceIndex, its numbers read from the
   * packed buffer as storage; otherwise the packed buffer is an instanced vertex buffer.
   */
  _positionNode(culled = null) {
    const wind = Boolean(this._wind), variant = { rigid: 'AXIAL_NO_BEND' in this.defines, noTurn: 'AXIAL_NO_TURN' in this.defines };
    this._positions = this._positions || new Map();
    const key = culled ? culled.level : -1, known = this._positions.get(key);
    if (known && known.wind === wind && known.variant.rigid === variant.rigid && known.variant.noTurn === variant.noTurn) return known.node;
    const g = culled ? culled.geometry : this.geometry, hasTangent = Boolean(g.getAttribute('tangent'));
    // the rigid part is placed by the bend (inst.matrix), not by three's instancing, which runs before
    // the positionNode in some versions (r187) and after it in others (r171): three instances an
    // InstancedMesh by its matrices only when they are an InstancedBufferAttribute, so they are a
    // plain one here over the same array (the bounds, raycasting and the compute pass read it)
    if (/** @type {any} */ (this.instanceMatrix).isInstancedBufferAttribute) {
      this.instanceMatrix = new THREE.BufferAttribute(this.instanceMatrix.array, 16).setUsage(THREE.DynamicDrawUsage);
    }
    const node = Fn(() => {
      let q, id;
      if (culled) {
        id = culled.ids.element(instanceIndex.add(uint(culled.level * culled.capacity))).toVar();
        const base = id.mul(uint(culled.stride / 4)).toVar();
        q = (k) => culled.instances.element(base.add(uint(k)));
      } else if (this._storage) { // the instances a compute pass wrote (webgpu/generate.js), the same layout
        id = instanceIndex;
        const base = id.mul(uint(this._storage.stride / 4)).toVar(), instances = this._storage.instances;
        q = (k) => instances.element(base.add(uint(k)));
      } else {
        const packed = this._packed;
        id = instanceIndex;
        q = (k) => instancedDynamicBufferAttribute(packed, 'vec4', packed.stride, 4 * k);
      }
      const i2 = q(2), matrix = [4, 5, 6, 7].map((k) => q(k).xyz);
      const inst = { d12: q(0), d34: q(1), d5: i2.xy, twist: i2.z, taper: i2.w, angles: q(3).xyz, position: matrix[3], matrix };
      const b = this.axis.axes ? int(attribute('axialAxis', 'float').add(0.5)) : null;
      const r = this._bend(inst, id, positionGeometry, normalGeometry, hasTangent ? tangentGeometry.xyz : null, b, variant);
      normalLocal.assign(r.n);
      if (r.t) tangentLocal.assign(r.t);
      // the tint: the varying three's materials multiply their colour by (its instancing sets it otherwise)
      if (this.instanceColor) varyingProperty('vec3', 'vInstanceColor').assign(q(8).xyz);
      return r.v;
    })();
    this._positions.set(key, { wind, variant, node });
    return node;
  }

  /**
   * The record's numbers as attributes (the base's), and every number the bend reads packed into ONE
   * instanced vertex buffer (WebGPU allows 8 vertex buffers; a textured tree would need 10 apart):
   * 32 floats an instance (36 tinted) -- d12, d34, (d5, tw, tp), (angles, 0), the instance matrix's
   * four columns, (tint, 0) -- read as the vec4 attributes axialInstance0 .. 8.
   */
  _write(rows, first) {
    super._write(rows, first);
    const n = rows.length / this.layout.numbersPerInstance, a = this.geometry.attributes;
    const stride = this.instanceColor ? 36 : 32;
    if (!this._packed) {
      this._packed = new THREE.InstancedInterleavedBuffer(new Float32Array(this.capacity * stride), stride, 1)
        .setUsage(THREE.DynamicDrawUsage);
    }
    const packed = this._packed, out = packed.array, m = this.instanceMatrix.array;
    for (let i = first; i < first + n; i++) {
      const o = i * stride;
      for (let c = 0; c < 4; c++) { out[o + c] = a.axialD12.array[4 * i + c]; out[o + 4 + c] = a.axialD34.array[4 * i + c]; }
      out[o + 8] = a.axialD5.array[2 * i]; out[o + 9] = a.axialD5.array[2 * i + 1];
      out[o + 10] = a.axialTwistTaper.array[2 * i]; out[o + 11] = a.axialTwistTaper.array[2 * i + 1];
      for (let c = 0; c < 3; c++) out[o + 12 + c] = a.axialAngles.array[3 * i + c];
      for (let c = 0; c < 16; c++) out[o + 16 + c] = m[16 * i + c];
      if (this.instanceColor) for (let c = 0; c < 3; c++) out[o + 32 + c] = this.instanceColor.array[3 * i + c];
    }
    if (packed.clearUpdateRanges) packed.addUpdateRange(first * stride, n * stride);
    packed.needsUpdate = true;
    if (this._culling) this._culling.updateBounds(first, n);
  }

  /**
   * GPU culling and level of detail (WebGPU backend): `false` turns it off; `true` culls the mesh's own
   * geometry; `{levels: [{geometry, distance}, ...]}` by increasing distance draws each visible instance
   * with the first level nearer than its distance (none beyond the last).  A compute pass a frame tests
   * every instance's bend-aware bounding sphere against the frustum and writes indirect draw
   * arguments: the CPU's work a frame does not grow with the count (cull.js).
   * @param {boolean | {levels: {geometry: any, distance: number}[]}} [options]
   */
  setGPUCulling(options = true) {
    if (options && this.recipe) {
      throw new AxialError('setGPUCulling: a generated layer draws every slot of the tiles within reach; its culling is the reach');
    }
    if (this._culling) {
      this._culling.levels.forEach((m) => this.remove(m));
      this._culling.dispose();
      this._culling = null;
      this.setBendVisible(true);
    }
    for (const key of [...(this._positions || new Map()).keys()]) if (key >= 0) this._positions.delete(key);
    if (!options) return this;
    if (this._baked) unbake(this);
    this._culling = new GPUCulling(this, options === true ? null : options.levels);
    this._culling.levels.forEach((m) => this.add(m));
    this.setBendVisible(false);
    return this;
  }

  /** Whether instances are culled on the GPU (setGPUCulling). */
  get gpuCulled() {
    return Boolean(this._culling);
  }

  setWind(wind) {
    const was = Boolean(this._wind);
    super.setWind(wind);
    if (updateVariant(this) || Boolean(this._wind) !== was) this._rebend(); // a wind moves unbent instances too
    return this;
  }

  /** The materials' positionNode made again (the wind came or went, the variant changed). */
  _rebend() {
    if (this._culling) this._culling.rebend();
    const node = this._positionNode();
    (Array.isArray(this.material) ? this.material : [this.material]).forEach((m) => {
      if (!this._ownShader) m.positionNode = node;
      m.needsUpdate = true;
    });
  }

  /**
   * Bend instances `ids` (null: all) on the GPU by a compute pass of the same node functions the
   * materials draw with, and read them back: {ids, V, positions, normals, tangents} (Float32Array, 4
   * numbers a vertex, instance after instance, in this mesh's space).  `renderer`: the
   * WebGPURenderer (default: the last one that drew this mesh).  compute.js.
   */
  bendAsync(renderer = this._renderer, ids = null) {
    return bendAsync(this, renderer, ids);
  }

  /**
   * Bend every instance ONCE (bendAsync's compute pass) and draw the result as plain geometry until
   * the instances move (setParams, updateParams, setWind go back to bending every frame).  Resolves
   * true when baked (false: no instances, or a wind).  Raycasting then answers synchronously from
   * the baked vertices.
   */
  async bakeAsync(renderer = this._renderer) {
    if (this.recipe) await this._part.materializeAsync(renderer || this._part.madeBy); // the tile set read back once
    if (this._culling) throw new AxialError('bakeAsync: the mesh is culled on the GPU; mesh.setGPUCulling(false) first');
    unbake(this);
    if (this.count === 0 || this._wind || this._ownShader) return false;
    const r = await this.bendAsync(renderer);
    const total = this.count * r.V;
    const xyz = (src, k) => {
      const o = new Float32Array(total * k);
      for (let i = 0; i < total; i++) for (let c = 0; c < k; c++) o[i * k + c] = src[4 * i + c];
      return o;
    };
    attachBake(this, {
      position: new THREE.BufferAttribute(xyz(r.positions, 3), 3),
      normal: new THREE.BufferAttribute(xyz(r.normals, 3), 3),
      tangent: r.tangents ? new THREE.BufferAttribute(xyz(r.tangents, 4), 4) : null,
    }, () => {});
    this._baked.positions = r.positions;
    return true;
  }

  /** @param {any} [renderer] @returns {boolean} */
  // eslint-disable-next-line no-unused-vars
  bake(renderer) {
    throw new AxialError('bake: under WebGPURenderer the GPU is read back asynchronously: await mesh.bakeAsync(renderer)');
  }

  /**
   * three's raycasting: against the baked vertices where the mesh is baked (bakeAsync); otherwise
   * WebGPU reads the GPU back only asynchronously, so it warns once and finds nothing -- use
   * raycastAsync.
   */
  raycast(raycaster, intersects) {
    const ids = rayCandidates(this, raycaster);
    if (!ids.length) return;
    if (this._baked && this._baked.positions) {
      const V = this.geometry.getAttribute('position').count, all = this._baked.positions, sub = new Float32Array(ids.length * V * 4);
      ids.forEach((id, k) => sub.set(all.subarray(id * V * 4, (id + 1) * V * 4), k * V * 4));
      intersectBent(this, raycaster, intersects, ids, sub, 4);
      return;
    }
    if (!this._warnedRaycast) {
      console.warn('AxialInstancedMesh (axialdeform-three/webgpu): raycast() cannot read the GPU back synchronously under '
        + 'WebGPURenderer; use await mesh.raycastAsync(raycaster), or bakeAsync() resting instances');
      this._warnedRaycast = true;
    }
  }

  /** The intersections of `raycaster`'s ray with the bent instances (sorted by distance, with instanceId). */
  async raycastAsync(raycaster, renderer = this._renderer) {
    if (this.recipe) await this._part.materializeAsync(renderer || this._part.madeBy);
    const ids = rayCandidates(this, raycaster), hits = [];
    if (!ids.length) return hits;
    const r = await this.bendAsync(renderer, ids);
    intersectBent(this, raycaster, hits, ids, r.positions, 4);
    return hits.sort((a, b) => a.distance - b.distance);
  }

  dispose() {
    this.setGPUCulling(false);
    releaseCompute(this);
    if (this._uniformNodes && this._uniformNodes.axes) this._uniformNodes.axes.tex.dispose();
    return super.dispose();
  }
}
