// core/mesh.js -- AxialMeshCore: what an axialdeform mesh is under any renderer: a THREE.InstancedMesh of
// one geometry whose instances are each bent along their own Bezier control axis -- the record, its
// attributes and instance matrices (record.js's ATTRIBUTES), the tint, a tree's child-axis texels, the
// bend-aware bounds, setParams/updateParams, the wind's state.  How the bend is drawn is the renderer's
// part: webgl/mesh.js (glsl/axial.glsl injected into classic materials) and webgpu/mesh.js (node
// functions as the material's positionNode) each subclass it with bendMaterial, their shadow materials,
// their renderer check, bake and raycast.

import * as THREE from 'three';
import { AxialError, recordLayout, childTexels, texelRows, column, AXES_ROW } from './adp.js';
import { ATTRIBUTES } from './record.js';
import { resolveAxis, instanceMatrices, bentRadii, checkRows, checkVertexCodes } from './bend.js';
import { checkWind, setWindClock, setWindUniforms, windReach } from './wind.js';
import { unbake } from './baked.js';
import { generatedBase, adoptGenerated, setDensityOf, recipeBounds } from './generate.js';

// scratch objects of the bounds (no allocation per instance)
const _m = new THREE.Matrix4(), _s = new THREE.Sphere(), _b = new THREE.Box3(), _v = new THREE.Vector3();

/**
 * A THREE.InstancedMesh of `record.count` instances of `geometry`, each bent by its own numbers (the
 * renderer-agnostic part: use webgl/mesh.js's or webgpu/mesh.js's AxialInstancedMesh).
 *
 * record: parseADP's result, or {count, numbersPerInstance, data (Float32Array), axes?, axis?, lo?,
 * length?}.  options.axis: the mesh's control axis where the record's header does not say it all
 * (a chosen frame, several axes: the GLB's AXIALDEFORM_bend or extras.axialdeform); options.capacity:
 * room for more instances than the record has (setParams may grow count up to it); options.ownShader:
 * the materials bend themselves (a ShaderMaterial including AXIAL_GLSL that reads this mesh's
 * attributes axialD12, axialD34, axialD5, axialTwistTaper, axialAngles, axialAxis, instanceMatrix).  The
 * material(s) are cloned and given the bend; shadows and raycasting use the bent shape.
 *
 * A generated layer: record {generate: recipe} (a scene file's [layer.generate]; checkRecipe) -- its instances
 * made on the GPU from the recipe in the tiles within reach of a point (update(renderer, point), or
 * options.autoUpdate: around the camera); options.uniforms and options.maps: the generator's numbers and the
 * ground maps as the Python library gives them (default: recipeUniforms, the flat ground); options.maxSlots.
 */
export class AxialMeshCore extends THREE.InstancedMesh {
  /** @type {any} */ _baked = null; /** @type {any} */ _rayMesh = null; /** @type {any} */ _cpuAttributes = null; // set later
  /** @type {any} */ _childTexels = null; /** @type {any} */ _storage = null; // (bake.js, raycast.js, generated meshes)
  /** @type {any} */ _culling = null; // each renderer's culling
  // a generated layer's state (core/generate.js's adoptGenerated sets it; the renderer's part: _part)
  /** @type {any[]} */ tiles = []; /** @type {boolean} */ autoUpdate = false; /** @type {any} */ _drawnBy = null;
  /** @type {boolean} */ _materialized = false; /** @type {any} */ _part = null;
  /** @type {any} a generated layer's recipe (checked, defaults filled in); null: the instances are the record's */
  recipe = null;
  constructor(geometry, material, record, options = {}) {
    if (!geometry || !geometry.isBufferGeometry) throw new AxialError('AxialInstancedMesh: expected a THREE.BufferGeometry');
    const base = record && record.generate !== undefined ? generatedBase(geometry, record.generate, options, 'AxialInstancedMesh') : null;
    if (base) ({ record, options } = base); // a generated layer: no instances until its tiles are made
    if (!record || !Number.isInteger(record.count) || !record.data) {
      throw new AxialError('AxialInstancedMesh: expected a record ({count, numbersPerInstance, data}: parseADP\'s result) or '
        + '{generate: recipe}');
    }
    const capacity = Math.max(record.count, options.capacity || 0, 1);
    // our own geometry: the user's attributes (shared, not copied) plus the instances' numbers
    const own = new THREE.BufferGeometry();
    if (geometry.index) own.setIndex(geometry.index);
    for (const [name, attr] of Object.entries(geometry.attributes)) {
      if (!name.startsWith('_AXIAL_')) own.setAttribute(name, attr); // GLTFLoader's copies of the instance data stay behind
    }
    for (const g of geometry.groups) own.addGroup(g.start, g.count, g.materialIndex);
    own.drawRange = { ...geometry.drawRange };
    if (!own.getAttribute('position') || !own.getAttribute('normal')) {
      throw new AxialError('AxialInstancedMesh: the geometry needs position and normal attributes');
    }
    super(own, material, capacity);
    this.isAxialInstancedMesh = true;
    this.type = 'AxialInstancedMesh';
    this.capacity = capacity;
    this.baseGeometry = geometry;
    const axes = record.axes || 1;
    this.layout = recordLayout(record.numbersPerInstance, axes);
    const positions = own.getAttribute('position');
    this.axis = resolveAxis(options.axis || null, record, positions.array);
    const treeCount = this.axis.axes ? this.axis.axes.count : 1;
    if (treeCount !== axes) {
      throw new AxialError(`${record.name || 'record'}: ${axes} axes an instance, but the mesh has ${treeCount}`);
    }
    if (axes > 1) {
      const va = own.getAttribute('axialAxis') || own.getAttribute('_axial_axis') || options.vertexAxis;
      if (!va) throw new AxialError('AxialInstancedMesh: a mesh of several axes needs each vertex\'s axis (_AXIAL_AXIS)');
      checkVertexCodes(va.isBufferAttribute ? va.array : va, axes, positions.count);
      this.vertexAxis = va.isBufferAttribute ? va.array : va;
      own.setAttribute('axialAxis', va.isBufferAttribute ? va : new THREE.BufferAttribute(Float32Array.from(va), 1));
    } else {
      this.vertexAxis = null;
    }
    this.data = new Float32Array(capacity * this.layout.numbersPerInstance);
    // the bend's numbers (record.js's ATTRIBUTES; axialAngles: the wind's push needs R^T dir, the rest of R is instanceMatrix)
    for (const a of ATTRIBUTES) {
      own.setAttribute(a.name, new THREE.InstancedBufferAttribute(new Float32Array(capacity * a.size), a.size)
        .setUsage(THREE.DynamicDrawUsage));
    }
    this.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    if (this.layout.tint !== null) this.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(capacity * 3), 3);
    const ax = this.axis;
    this.axialUniforms = {
      axialFrame: { value: new THREE.Matrix3().fromArray(ax.frame.flat()).transpose() }, // rows: frame * v = F v
      axialLo: { value: ax.lo }, axialLen: { value: ax.length },
      axialCenter: { value: new THREE.Vector2(ax.center[0], ax.center[1]) },
    };
    this.defines = {};
    if (ax.axes) {
      this.defines.AXIAL_AXES = String(ax.axes.count);
      Object.assign(this.axialUniforms, {
        axialFrames: { value: ax.axes.frames.map((f) => new THREE.Matrix3().fromArray(f.flat()).transpose()) },
        axialLos: { value: Float32Array.from(ax.axes.lo) },
        axialLens: { value: Float32Array.from(ax.axes.length) },
        // each child axis's joint (t on its own axis): the wind leaves it; files without them: 0
        axialAnchors: { value: Float32Array.from(ax.axes.anchors || new Array(ax.axes.count).fill(0)) },
        axialParents: { value: Int32Array.from(ax.axes.parents) },
        axialChildren: { value: null },
      });
      // the child axes' offsets: a float texture sized for the capacity, written range by range
      const rows = texelRows(capacity, ax.axes.count);
      const tex = new THREE.DataTexture(new Float32Array(rows * AXES_ROW * 4), AXES_ROW, rows, THREE.RGBAFormat, THREE.FloatType);
      tex.minFilter = tex.magFilter = THREE.NearestFilter;
      this.axialUniforms.axialChildren.value = tex;
    }
    this._radii = new Float32Array(capacity);
    this._grow = new Float32Array(capacity);
    own.computeBoundingBox();
    this._baseBox = own.boundingBox.clone();
    this._center = [0, 0, 0];
    // ownShader: the material(s) bend themselves (a ShaderMaterial that includes AXIAL_GLSL and reads
    // this mesh's attributes, as axialdeform's page does): used as they are, not cloned or injected
    this._ownShader = Boolean(options.ownShader);
    this._sourceMaterials = material; // the user's, un-bent: a bake draws with clones of these
    this.material = Array.isArray(material) ? material.map((m) => this.bendMaterial(m)) : this.bendMaterial(material);
    // the shadow passes draw the bent shape too (three picks these for castShadow)
    this._shadowMaterials = this._makeShadowMaterials();
    if (this._shadowMaterials.length) [this.customDepthMaterial, this.customDistanceMaterial] = this._shadowMaterials;
    this.count = 0;
    this.setParams(record);
    this._renderer = null; // the last renderer that drew this mesh: raycasting bends on its GPU
    // a user's onBeforeRender runs after ours (composed): assigning one does not lose the renderer
    let userHook = null;
    const hook = (renderer, ...rest) => {
      this._checkRenderer(renderer);
      this._renderer = renderer;
      this._beforeDraw(rest[1]);
      if (userHook) userHook.call(this, renderer, ...rest);
    };
    Object.defineProperty(this, 'onBeforeRender', { get: () => hook, set: (fn) => { userHook = fn; }, configurable: true });
    if (base) adoptGenerated(this, base, base.options, (r) => this._generatesWith(r));
  }

  /** A camera is about to draw this mesh (the renderer's part: its culling). */
  // eslint-disable-next-line no-unused-vars
  _beforeDraw(camera) {}

  /** The bent materials of three's shadow passes (customDepthMaterial, customDistanceMaterial): none here.
   * @returns {any[]} */
  _makeShadowMaterials() {
    return [];
  }

  /** Throws where `renderer` cannot draw this mesh bent (each renderer's part says which can). */
  // eslint-disable-next-line no-unused-vars
  _checkRenderer(renderer) {}

  /** A clone of `material` that bends this mesh's instances (each renderer's part makes it).
   * @param {any} material @param {boolean} [clone] @returns {any} */
  // eslint-disable-next-line no-unused-vars
  bendMaterial(material, clone = true) {
    throw new AxialError('AxialMeshCore: use AxialInstancedMesh from axialdeform-three (WebGLRenderer) or axialdeform-three/webgpu');
  }

  /**
   * Replace the instances: `data` (Float32Array of rows of numbersPerInstance, or a parsed record);
   * the count becomes its rows (it may shrink; at most the capacity).  No reallocation: the
   * attributes are written in place and uploaded; the bounds are recomputed.  With `{first}`, the
   * rows update instances first .. first + rows - 1 instead (updateParams).
   */
  setParams(data, options = undefined) {
    if (options && options.first !== undefined) return this.updateParams(data, options.first);
    this._ownInstances('setParams');
    const rows = checkRows(this, data, 0, 'setParams');
    const n = rows.length / this.layout.numbersPerInstance;
    this._write(rows, 0);
    this.count = n;
    this.boundingSphere = null;
    this.boundingBox = null;
    this.computeBoundingSphere();
    this.dispatchEvent(/** @type {any} */ ({ type: 'paramschange', first: 0, count: n }));
    return this;
  }

  /**
   * Update instances start .. start + rows - 1 in place (the count grows to include them, up to
   * the capacity): only that range is uploaded (addUpdateRange) and only its bounds are computed
   * (the mesh's box and sphere grow to hold them; they do not shrink until setParams).
   */
  updateParams(rows, start = 0) {
    this._ownInstances('updateParams');
    rows = checkRows(this, rows, start, 'updateParams');
    const n = rows.length / this.layout.numbersPerInstance;
    this._write(rows, start);
    this.count = Math.max(this.count, start + n);
    if (this.boundingSphere === null || this.boundingBox === null) {
      this.computeBoundingSphere();
    } else {
      for (let i = start; i < start + n; i++) {
        this.boundingBox.union(this.getInstanceBoundingBox(i, _b));
        this.boundingSphere.union(this.getInstanceBoundingSphere(i, _s));
      }
    }
    this.dispatchEvent(/** @type {any} */ ({ type: 'paramschange', first: start, count: n }));
    return this;
  }

  /** Write checked rows into instances first ..: the record, the attributes (uploaded as a range),
   * the instance matrices, the tint, the child axes' texels and the instances' bounds. */
  _write(rows, first) {
    if (this._baked) unbake(this); // moving instances bend every frame again
    const L = this.layout, f = L.numbersPerInstance, n = rows.length / f, a = this._cpuAttributes || this.geometry.attributes;
    this.data.set(rows, first * f);
    const range = (attr, size) => {
      if (attr.clearUpdateRanges) attr.addUpdateRange(first * size, n * size);
      attr.needsUpdate = true;
    };
    for (const at of ATTRIBUTES) {
      const out = a[at.name].array, col = column(at.start, L.axes), has = at.level <= L.level;
      for (let i = first; i < first + n; i++) {
        for (let c = 0; c < at.size; c++) out[at.size * i + c] = has ? this.data[i * f + col + c] : 0;
      }
      range(a[at.name], at.size);
    }
    if (L.tint !== null) {
      for (let i = first; i < first + n; i++) for (let c = 0; c < 3; c++) this.instanceColor.array[3 * i + c] = this.data[i * f + L.tint + c];
      range(this.instanceColor, 3);
    }
    instanceMatrices(this.data, L, n, this.instanceMatrix.array, first);
    range(this.instanceMatrix, 16);
    if (this.axis.axes) {
      const tex = this.axialUniforms.axialChildren.value;
      childTexels(this.data, f, this.axis.axes.count, first, n, tex.image.data);
      tex.needsUpdate = true;
    }
    const pos = this.geometry.getAttribute('position').array;
    this._center = bentRadii(pos, this.axis, this.data, L, n, first, this._radii, this._grow).center;
  }

  /**
   * The wind of glsl/wind.glsl (docs/wind.md): {direction: [x, y, z] (world), strength (tip
   * displacement in units of L), gustiness, frequency (gust cycles a second), wavelength (world
   * units between gust fronts; 0: none)} -- the defaults are axialdeform.Wind's (record.js's WIND)
   * -- or null for none.  It moves the control points in the vertex shader from uniforms alone;
   * setTime(t) moves its clock.
   */
  setWind(wind) {
    this._wind = checkWind(wind);
    const on = this._wind !== null;
    if (on) {
      setWindUniforms(this.axialUniforms, this._wind);
      this.setTime(this._time || 0);
      if (this._baked) unbake(this); // swaying instances bend every frame
    }
    this._windGrow = windReach(this._wind, this.axis.axes?.length ?? [this.axis.length], this.axis.axes?.parents);
    this.boundingSphere = null;
    this.computeBoundingSphere();
    if (on !== Boolean(this.defines.AXIAL_WIND)) {
      if (on) this.defines.AXIAL_WIND = '1'; else delete this.defines.AXIAL_WIND;
      this._allMaterials().forEach((m) => { m.needsUpdate = true; });
    }
    return this;
  }

  /** The wind's clock, in seconds (the cycles as axialdeform.core.wind computes them). */
  setTime(t) {
    if (!Number.isFinite(t)) throw new AxialError(`setTime: expected a finite number of seconds, found ${t}`);
    this._time = t;
    if (this._wind) setWindClock(this.axialUniforms, this._wind, t);
    return this;
  }

  _allMaterials() {
    return [...(Array.isArray(this.material) ? this.material : [this.material]), ...this._shadowMaterials];
  }

  /** The sphere (this mesh's space) of instance i bent and placed. */
  getInstanceBoundingSphere(i, target = new THREE.Sphere()) {
    const scale = this._stillSphere(i, target);
    target.radius += (this._windGrow || 0) * scale;
    return target;
  }

  /** Instance i's sphere without the wind into `target`; returns the instance's scale (the wind's reach grows by it). */
  _stillSphere(i, target) {
    const m = _m.fromArray(this.instanceMatrix.array, 16 * i), scale = m.getMaxScaleOnAxis();
    target.center.fromArray(this._center).applyMatrix4(m);
    target.radius = this._radii[i] * scale;
    return scale;
  }

  /** The box (this mesh's space) of instance i bent and placed: the base box grown by how far the
   * bend can move a vertex, through the instance's matrix (the sphere's box for twist and taper). */
  getInstanceBoundingBox(i, target = new THREE.Box3()) {
    const L = this.layout, r = i * L.numbersPerInstance;
    const twisted = (L.twist !== null && this.data[r + L.twist] !== 0) || (L.taper !== null && this.data[r + L.taper] !== 0);
    if (twisted) {
      const s = this.getInstanceBoundingSphere(i, _s);
      target.min.copy(s.center).subScalar(s.radius);
      target.max.copy(s.center).addScalar(s.radius);
      return target;
    }
    target.copy(this._baseBox).expandByScalar(this._grow[i] + (this._windGrow || 0));
    return target.applyMatrix4(_m.fromArray(this.instanceMatrix.array, 16 * i));
  }

  computeBoundingSphere() {
    if (this.recipe && this.tiles.length && !this._materialized) return recipeBounds(this); // before any record is read back
    const box = new THREE.Box3();
    for (let i = 0; i < this.count; i++) box.union(this.getInstanceBoundingBox(i, _b));
    this.boundingBox = box;
    if (this.boundingSphere === null) this.boundingSphere = new THREE.Sphere();
    if (box.isEmpty()) { this.boundingSphere.makeEmpty(); return; }
    const c = box.getCenter(this.boundingSphere.center);
    let r = 0;
    for (let i = 0; i < this.count; i++) {
      const s = this.getInstanceBoundingSphere(i, _s);
      r = Math.max(r, s.center.distanceTo(c) + s.radius);
    }
    this.boundingSphere.radius = r;
  }

  computeBoundingBox() {
    this.computeBoundingSphere();
  }

  /** A generated layer ({generate: recipe} in place of the record; docs/generate.md): make the tiles within reach of
   * `point` ({x, z}: a Vector3, e.g. OrbitControls' target) on `renderer`'s GPU if they changed; returns whether they
   * did.  Far tiles are let go, so the instances held stay bounded; with options.autoUpdate, around the camera. */
  update(renderer, point) {
    return this._generated('update').update(renderer, point);
  }

  /** A generated layer's new density map ({data: Float32Array, cols, rows}: grey levels in 0..1) and where it lies
   * ({d_lo, d_inv, d_wrap}, as the Python library's GroundMaps): an AxialBrush's; the tiles are made again at the next update. */
  setDensity(grid, placement) {
    const part = this._generated('setDensity');
    setDensityOf(this, grid, placement);
    part.densityChanged(grid);
  }

  updateMatrixWorld(force) {
    super.updateMatrixWorld(force);
    const d = this.recipe && this.autoUpdate ? this._drawnBy : null;
    if (d) this.update(d.renderer, d.camera.getWorldPosition(_v));
  }

  /** The renderer's part of a generated layer (its `_part`, made by each entry's mesh); `what` names the call refused otherwise. */
  _generated(what) {
    if (!this.recipe) throw new AxialError(`${what}: not a generated layer (make one with {generate: recipe} in place of the record)`);
    return this._part;
  }

  /** Throws on a generated layer, whose instances its recipe makes (`what` names the call). */
  _ownInstances(what) {
    if (this.recipe) throw new AxialError(`${what}: a generated layer's instances are made from its recipe on the GPU; set another recipe by making another mesh`);
  }

  /** Whether `renderer` is one this mesh's generated layer is made with (autoUpdate; each renderer's part). */
  // eslint-disable-next-line no-unused-vars
  _generatesWith(renderer) {
    return false;
  }

  /** Go back to bending every frame (frees the baked geometry). */
  unbake() {
    return unbake(this);
  }

  /** Whether the instances are drawn from a bake (bake()) rather than bent every frame. */
  get baked() {
    return Boolean(this._baked);
  }

  setBendVisible(on) {
    (Array.isArray(this.material) ? this.material : [this.material]).forEach((m) => { m.visible = on; });
    this._shadowMaterials.forEach((m) => { m.visible = on; });
  }

  /** Frees this mesh's GPU buffers, its materials (the clones), shadow materials and texture;
   * the user's geometry and materials stay theirs. */
  dispose() {
    if (this._part) this._part.dispose();
    this._part = null;
    unbake(this);
    this.geometry.dispose();
    (Array.isArray(this.material) ? this.material : [this.material]).forEach((m) => m.dispose());
    this._shadowMaterials.forEach((m) => m.dispose());
    if (this.axialUniforms.axialChildren && this.axialUniforms.axialChildren.value) this.axialUniforms.axialChildren.value.dispose();
    if (this._rayMesh) this._rayMesh.geometry.dispose();
    this.dispatchEvent({ type: 'dispose' });
    return this;
  }
}

