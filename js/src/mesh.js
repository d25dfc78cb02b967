// mesh.js -- AxialInstancedMesh: a THREE.InstancedMesh whose instances are bent,
// each along its own Bézier control axis, by glsl/axial.glsl injected into the
// user's own material (onBeforeCompile), so maps, lights, shadows, fog and tone
// mapping stay three.js's.  The rigid part of every instance (rotation, scale,
// position) is its instanceMatrix; the bend's numbers are instanced attributes.

import * as THREE from 'three';
import { AxialError, recordLayout, childTexels, texelRows, AXES_ROW } from './adp.js';
import { AXIAL_GLSL, WIND_GLSL } from './glsl.js';
import { resolveAxis, instanceMatrices, bentRadii } from './bend.js';

const UNIFORMS = `
#ifndef AXIAL_ID
#define AXIAL_ID gl_InstanceID
#endif
uniform mat3 axialFrame;
uniform float axialLo;
uniform float axialLen;
uniform vec2 axialCenter;
#ifdef AXIAL_AXES
uniform mat3 axialFrames[AXIAL_AXES];
uniform float axialLos[AXIAL_AXES];
uniform float axialLens[AXIAL_AXES];
uniform int axialParents[AXIAL_AXES];
uniform sampler2D axialChildren;
attribute float axialAxis;
#endif
#ifdef AXIAL_WIND
uniform vec3 axialWindDir;
uniform float axialWindStrength;
uniform float axialWindGust;
uniform vec2 axialWindCycles;
uniform float axialWindWavenumber;
attribute vec3 axialAngles;
#endif
attribute vec4 axialD12;
attribute vec4 axialD34;
attribute vec2 axialD5;
attribute vec2 axialTwistTaper;
`;

// the bend of this vertex, before three's chunks: model space, the instance's rigid part
// is instanceMatrix (three applies it in project_vertex, worldpos_vertex, defaultnormal_vertex)
const BEND = `
  vec3 axialV, axialN, axialT = vec3(1.0, 0.0, 0.0);
  {
    AxialInstance axialInst = AxialInstance(axialD12, axialD34, axialD5, vec3(0.0), vec3(0.0), 1.0,
                                            axialTwistTaper.x, axialTwistTaper.y);
    vec3 axialPush = vec3(0.0);
#ifdef AXIAL_WIND
    if (axialWindStrength != 0.0) {  // glsl/wind.glsl: the wind moves the control points
      AxialInstance axialPlaced = axialInst;
      axialPlaced.position = instanceMatrix[3].xyz;
      axialPlaced.angles = axialAngles;
#ifdef AXIAL_AXES
      axialPush = axial_wind_push(axialPlaced, uint(AXIAL_ID), 1.0, axialWindDir, axialWindStrength,
                                  axialWindGust, axialWindCycles, axialWindWavenumber);
#endif
      axialInst = axial_wind(axialPlaced, uint(AXIAL_ID), axialFrame, axialLen, axialWindDir, axialWindStrength,
                             axialWindGust, axialWindCycles, axialWindWavenumber);
      axialInst.position = vec3(0.0);  // the rigid part stays instanceMatrix's
      axialInst.angles = vec3(0.0);
    }
#endif
#ifdef AXIAL_AXES
    mat3 axialJac;
    axial_tree_world(position, normal, int(axialAxis + 0.5), axialFrames, axialLos, axialLens, axialParents,
                     axialCenter, axialInst, axialChildren, AXIAL_ID, axialPush, axialV, axialN, axialJac);
#ifdef USE_TANGENT
    axialT = axialJac * tangent.xyz;
#endif
#else
    axial_bend(position, normal, axialFrame, axialLo, axialLen, axialCenter, axialInst, axialV, axialN);
#ifdef USE_TANGENT
    axialT = transpose(axialFrame) * axial_bend_tangent(axialFrame * position, axialFrame * tangent.xyz, 0,
                                                        axialLo, axialLen, axialCenter, axialInst);
#endif
#endif
  }
`;

/** A vertex attribute as a tight float32 array (interleaved, integer or normalized ones unpacked). */
function plainArray(attr) {
  if (!attr.isInterleavedBufferAttribute && attr.array instanceof Float32Array) return attr.array;
  const out = new Float32Array(attr.count * attr.itemSize);
  for (let i = 0; i < attr.count; i++) for (let c = 0; c < attr.itemSize; c++) out[i * attr.itemSize + c] = attr.getComponent(i, c);
  return out;
}

// scratch objects of the bounds (no allocation per instance)
const _m = new THREE.Matrix4(), _s = new THREE.Sphere(), _b = new THREE.Box3();

function replaceOnce(text, what, by, where) {
  if (!text.includes(what)) throw new AxialError(`${where}: its vertex shader has no ${what} to bend`);
  return text.replace(what, by);
}

/** Inject the bend into a vertex shader of three's built-in materials (the text onBeforeCompile gets). */
export function injectBend(vertexShader, where = 'material') {
  let vs = replaceOnce(vertexShader, 'void main() {', `${UNIFORMS}\n${AXIAL_GLSL}\n${WIND_GLSL}\nvoid main() {\n${BEND}`, where);
  if (vs.includes('#include <beginnormal_vertex>')) {
    vs = vs.replace('#include <beginnormal_vertex>',
      'vec3 objectNormal = axialN;\n#ifdef USE_TANGENT\n\tvec3 objectTangent = axialT;\n#endif');
  }
  return replaceOnce(vs, '#include <begin_vertex>',
    'vec3 transformed = axialV;\n#ifdef USE_ALPHAHASH\n\tvPosition = vec3( position );\n#endif', where);
}


/**
 * A THREE.InstancedMesh of `record.count` instances of `geometry`, each bent by its own numbers.
 *
 * record: parseADP's result, or {count, numbersPerInstance, data (Float32Array), axes?, axis?, lo?,
 * length?}.  options.axis: the mesh's control axis where the record's header does not say it all
 * (a chosen frame, several axes: the GLB's AXIALDEFORM_bend or extras.axialdeform); options.capacity:
 * room for more instances than the record has (setParams may grow count up to it); options.ownShader:
 * the materials bend themselves (a ShaderMaterial including AXIAL_GLSL that reads this mesh's
 * attributes axialD12, axialD34, axialD5, axialTwistTaper, axialAngles, axialAxis, instanceMatrix).
 * The material(s) are cloned and given the bend; shadows (customDepthMaterial,
 * customDistanceMaterial) and raycasting use the bent shape.
 */
export class AxialInstancedMesh extends THREE.InstancedMesh {
  constructor(geometry, material, record, options = {}) {
    if (!geometry || !geometry.isBufferGeometry) throw new AxialError('AxialInstancedMesh: expected a THREE.BufferGeometry');
    if (!record || !Number.isInteger(record.count) || !record.data) {
      throw new AxialError('AxialInstancedMesh: expected a record ({count, numbersPerInstance, data}: parseADP\'s result)');
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
      this.vertexAxis = va.isBufferAttribute ? va.array : va;
      own.setAttribute('axialAxis', va.isBufferAttribute ? va : new THREE.BufferAttribute(Float32Array.from(va), 1));
    } else {
      this.vertexAxis = null;
    }
    this.data = new Float32Array(capacity * this.layout.numbersPerInstance);
    const inst = (size) => new THREE.InstancedBufferAttribute(new Float32Array(capacity * size), size).setUsage(THREE.DynamicDrawUsage);
    own.setAttribute('axialD12', inst(4));
    own.setAttribute('axialD34', inst(4));
    own.setAttribute('axialD5', inst(2));
    own.setAttribute('axialTwistTaper', inst(2));
    own.setAttribute('axialAngles', inst(3)); // the wind's push needs R^T dir (the rest of R is instanceMatrix)
    this.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    if (this.layout.tint !== null) this.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(capacity * 3), 3);
    const ax = this.axis;
    this.axialUniforms = {
      axialFrame: { value: new THREE.Matrix3().set(...ax.frame.flat()) }, // set() takes rows: frame * v = F v
      axialLo: { value: ax.lo }, axialLen: { value: ax.length },
      axialCenter: { value: new THREE.Vector2(ax.center[0], ax.center[1]) },
    };
    this.defines = {};
    if (ax.axes) {
      this.defines.AXIAL_AXES = String(ax.axes.count);
      Object.assign(this.axialUniforms, {
        axialFrames: { value: ax.axes.frames.map((f) => new THREE.Matrix3().set(...f.flat())) },
        axialLos: { value: Float32Array.from(ax.axes.lo) },
        axialLens: { value: Float32Array.from(ax.axes.length) },
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
    this._shadowMaterials = [
      this.bendMaterial(new THREE.MeshDepthMaterial({ depthPacking: THREE.RGBADepthPacking }), false),
      this.bendMaterial(new THREE.MeshDistanceMaterial(), false)];
    [this.customDepthMaterial, this.customDistanceMaterial] = this._shadowMaterials;
    this.count = 0;
    this.setParams(record);
    this._renderer = null; // the last renderer that drew this mesh: raycasting bends on its GPU
    this.onBeforeRender = (renderer) => { this._renderer = renderer; };
  }

  /** A clone of `material` (three's built-ins: Basic, Lambert, Phong, Standard, Physical, Toon,
   * Depth, Distance, ...) whose vertex shader bends this mesh's instances. */
  bendMaterial(material, clone = true) {
    if (!material || !material.isMaterial) throw new AxialError('AxialInstancedMesh: expected a THREE.Material');
    if (this._ownShader && clone) return material;
    if (material.isShaderMaterial) {
      throw new AxialError('AxialInstancedMesh: a ShaderMaterial has no three.js chunks to bend; include the exported AXIAL_GLSL in it yourself');
    }
    const m = clone ? material.clone() : material;
    const uniforms = this.axialUniforms, defines = this.defines, name = m.name || m.type;
    const before = material.onBeforeCompile;
    m.onBeforeCompile = (shader, renderer) => {
      if (before && before !== THREE.Material.prototype.onBeforeCompile) before.call(m, shader, renderer);
      Object.assign(shader.uniforms, uniforms); // the same objects: updates need no recompile
      shader.defines = { ...(shader.defines || {}), ...defines };
      shader.vertexShader = injectBend(shader.vertexShader, name);
    };
    const key = material.customProgramCacheKey.bind(material);
    m.customProgramCacheKey = () => `axialdeform:${defines.AXIAL_AXES || 1}:${defines.AXIAL_WIND ? 'wind' : ''}:${key()}`;
    m.needsUpdate = true;
    return m;
  }

  /**
   * Set instances' numbers in place (no reallocation): `data` (Float32Array, rows of
   * numbersPerInstance, or a parsed record) for instances first .. first + rows - 1; the
   * mesh's count becomes at least first + rows (at most its capacity).  Only the changed range is
   * uploaded (addUpdateRange); the bounding sphere is recomputed.
   */
  setParams(data, { first = 0 } = {}) {
    let rows = data;
    if (rows && rows.data && Number.isInteger(rows.count)) {
      if (rows.numbersPerInstance !== this.layout.numbersPerInstance) {
        throw new AxialError(`${rows.name || 'record'}: ${rows.numbersPerInstance} numbers an instance, but this mesh was made for ${this.layout.numbersPerInstance}`);
      }
      rows = rows.data.subarray(0, rows.count * this.layout.numbersPerInstance);
    }
    const f = this.layout.numbersPerInstance;
    if (!(rows instanceof Float32Array) || rows.length % f !== 0) {
      throw new AxialError(`setParams: expected a Float32Array of rows of ${f} numbers`);
    }
    const n = rows.length / f;
    if (!Number.isInteger(first) || first < 0 || first + n > this.capacity) {
      throw new AxialError(`setParams: instances ${first} to ${first + n - 1} do not fit a capacity of ${this.capacity}`);
    }
    for (let i = 0; i < rows.length; i++) {
      if (!Number.isFinite(rows[i])) throw new AxialError(`setParams: instance ${first + Math.floor(i / f)}, number ${i % f}: not finite`);
    }
    if (this._baked) this.unbake(); // moving instances bend every frame again
    this.data.set(rows, first * f);
    const L = this.layout, a = this.geometry.attributes;
    const d12 = a.axialD12.array, d34 = a.axialD34.array, d5 = a.axialD5.array, tt = a.axialTwistTaper.array;
    for (let i = first; i < first + n; i++) {
      const r = i * f;
      for (let c = 0; c < 4; c++) { d12[4 * i + c] = this.data[r + c]; d34[4 * i + c] = this.data[r + 4 + c]; }
      d5[2 * i] = this.data[r + 8]; d5[2 * i + 1] = this.data[r + 9];
      for (let c = 0; c < 3; c++) a.axialAngles.array[3 * i + c] = this.data[r + L.angles + c];
      tt[2 * i] = L.twist === null ? 0 : this.data[r + L.twist];
      tt[2 * i + 1] = L.taper === null ? 0 : this.data[r + L.taper];
      if (L.tint !== null) for (let c = 0; c < 3; c++) this.instanceColor.array[3 * i + c] = this.data[r + L.tint + c];
    }
    instanceMatrices(this.data, L, n, this.instanceMatrix.array, first);
    const range = (attr, size) => {
      if (attr.clearUpdateRanges) attr.addUpdateRange(first * size, n * size);
      attr.needsUpdate = true;
    };
    range(a.axialD12, 4); range(a.axialD34, 4); range(a.axialD5, 2); range(a.axialTwistTaper, 2); range(a.axialAngles, 3);
    range(this.instanceMatrix, 16);
    if (this.instanceColor) range(this.instanceColor, 3);
    if (this.axis.axes) {
      const tex = this.axialUniforms.axialChildren.value;
      childTexels(this.data, f, this.axis.axes.count, first, n, tex.image.data);
      tex.needsUpdate = true;
    }
    const pos = this.geometry.getAttribute('position').array;
    this._center = bentRadii(pos, this.axis, this.data, L, n, first, this._radii, this._grow).center;
    this.count = Math.max(this.count, first + n);
    this.boundingSphere = null;
    this.boundingBox = null;
    this.computeBoundingSphere();
    this.dispatchEvent({ type: 'paramschange', first, count: n });
    return this;
  }

  /**
   * The wind of glsl/wind.glsl (docs/wind.md): {direction: [x, y, z] (world), strength (tip
   * displacement in units of L), gustiness = 0.6, frequency = 0.5 (gust cycles a second),
   * wavelength = 0 (world units between gust fronts; 0: none)}, or null for none.  It moves the
   * control points in the vertex shader from uniforms alone; setTime(t) moves its clock.
   */
  setWind(wind) {
    const on = Boolean(wind && wind.strength > 0);
    if (on) {
      const d = wind.direction || [1, 0, 0], n = Math.hypot(d[0], d[1], d[2]);
      const num = (x, what) => {
        if (!(Number.isFinite(x) && x >= 0)) throw new AxialError(`setWind: ${what}: expected a finite number >= 0, found ${x}`);
        return x;
      };
      if (!(n > 0 && Number.isFinite(n))) throw new AxialError(`setWind: direction: expected 3 finite numbers, not all zero, found ${d}`);
      this._wind = { strength: num(wind.strength, 'strength'), gustiness: num(wind.gustiness ?? 0.6, 'gustiness'),
        frequency: num(wind.frequency ?? 0.5, 'frequency'), wavelength: num(wind.wavelength ?? 0, 'wavelength') };
      const u = this.axialUniforms;
      Object.assign(u, {
        axialWindDir: u.axialWindDir || { value: new THREE.Vector3() },
        axialWindStrength: u.axialWindStrength || { value: 0 }, axialWindGust: u.axialWindGust || { value: 0 },
        axialWindCycles: u.axialWindCycles || { value: new THREE.Vector2() },
        axialWindWavenumber: u.axialWindWavenumber || { value: 0 },
      });
      u.axialWindDir.value.set(d[0] / n, d[1] / n, d[2] / n);
      u.axialWindStrength.value = this._wind.strength;
      u.axialWindGust.value = this._wind.gustiness;
      u.axialWindWavenumber.value = this._wind.wavelength > 0 ? 1 / this._wind.wavelength : 0;
      this.setTime(this._time || 0);
      if (this._baked) this.unbake(); // swaying instances bend every frame
    } else {
      this._wind = null;
    }
    // the wind moves a tip by at most strength L (1 + gustiness), every axis of a tree by its own L
    const lens = this.axis.axes ? this.axis.axes.length : [this.axis.length];
    this._windGrow = on ? this._wind.strength * (1 + this._wind.gustiness) * lens.reduce((t, x) => t + x, 0) : 0;
    this.boundingSphere = null;
    this.computeBoundingSphere();
    if (on !== Boolean(this.defines.AXIAL_WIND)) {
      if (on) this.defines.AXIAL_WIND = '1'; else delete this.defines.AXIAL_WIND;
      this._allMaterials().forEach((m) => { m.needsUpdate = true; });
    }
    return this;
  }

  /** The wind's clock, in seconds: cycles = (frac(f t), frac(2.31 f t)) as axialdeform.core.wind. */
  setTime(t) {
    if (!Number.isFinite(t)) throw new AxialError(`setTime: expected a finite number of seconds, found ${t}`);
    this._time = t;
    if (this._wind) {
      const f = this._wind.frequency, frac = (x) => x - Math.floor(x);
      this.axialUniforms.axialWindCycles.value.set(frac(f * t), frac(2.31 * f * t));
    }
    return this;
  }

  _allMaterials() {
    return [...(Array.isArray(this.material) ? this.material : [this.material]), ...this._shadowMaterials];
  }

  /** The sphere (this mesh's space) of instance i bent and placed. */
  getInstanceBoundingSphere(i, target = new THREE.Sphere()) {
    const m = _m.fromArray(this.instanceMatrix.array, 16 * i);
    target.center.fromArray(this._center).applyMatrix4(m);
    target.radius = (this._radii[i] + (this._windGrow || 0)) * m.getMaxScaleOnAxis();
    return target;
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

  /**
   * three's raycasting, against each instance's bent triangles (intersections carry instanceId).
   * The instances whose bounding sphere the ray meets are bent on the GPU by the same shader code
   * (one transform-feedback pass, read back), so the mesh must have been drawn (or baked) once.
   */
  raycast(raycaster, intersects) {
    if (this.count === 0) return;
    if (this.boundingSphere === null) this.computeBoundingSphere();
    const sphere = new THREE.Sphere().copy(this.boundingSphere).applyMatrix4(this.matrixWorld);
    if (!raycaster.ray.intersectsSphere(sphere)) return;
    const ids = [];
    for (let i = 0; i < this.count; i++) {
      if (raycaster.ray.intersectsSphere(this.getInstanceBoundingSphere(i, _s).applyMatrix4(this.matrixWorld))) ids.push(i);
    }
    if (!ids.length) return;
    if (!this._renderer) {
      throw new AxialError('raycast: the bend runs on the GPU; draw the mesh once (or bake it) before raycasting');
    }
    const V = this.geometry.getAttribute('position').count;
    const { gl, outputs } = this._feedback(this._renderer, ids, false);
    const bent = new Float32Array(ids.length * V * 3);
    gl.bindBuffer(gl.ARRAY_BUFFER, outputs[0]);
    gl.getBufferSubData(gl.ARRAY_BUFFER, 0, bent);
    gl.bindBuffer(gl.ARRAY_BUFFER, null);
    outputs.forEach((b) => gl.deleteBuffer(b));
    this._renderer.resetState();
    if (!this._rayMesh) {
      const g = new THREE.BufferGeometry();
      if (this.geometry.index) g.setIndex(this.geometry.index);
      for (const grp of this.geometry.groups) g.addGroup(grp.start, grp.count, grp.materialIndex);
      g.drawRange = this.geometry.drawRange;
      g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * V), 3));
      this._rayMesh = new THREE.Mesh(g, this.material);
    }
    const mesh = this._rayMesh, found = [], attr = mesh.geometry.getAttribute('position');
    mesh.material = this.material;
    mesh.matrixWorld.copy(this.matrixWorld); // the captured positions are placed already (instanceMatrix)
    ids.forEach((id, k) => {
      attr.array.set(bent.subarray(k * V * 3, (k + 1) * V * 3));
      mesh.geometry.boundingSphere = null;
      mesh.geometry.boundingBox = null;
      found.length = 0;
      mesh.raycast(raycaster, found);
      for (const hit of found) { hit.instanceId = id; hit.object = this; intersects.push(hit); }
    });
  }

  /**
   * Bend every instance ONCE on the GPU (WebGL 2 transform feedback, the same glsl/axial.glsl) and
   * draw the result as plain geometry from then on: for instances that do not move, the frames cost
   * what a baked mesh costs, while the file stays 40 bytes an instance.  The bent positions and
   * normals stay on the GPU (GLBufferAttributes of a child mesh, with the un-bent clones of the
   * materials; a tint becomes a colour a vertex); raycasting and the bounds stay this mesh's.
   * setParams() (animation) and setWind() go back to bending every frame; call bake() again when
   * the instances rest.  Returns true when baked (false: no instances, a wind, an own shader).
   */
  bake(renderer) {
    this.unbake();
    if (this.count === 0 || this._wind || this._ownShader) return false;
    const gl = renderer.getContext();
    if (typeof WebGL2RenderingContext === 'undefined' || !(gl instanceof WebGL2RenderingContext)) return false;
    const g = this.geometry, n = this.count, V = g.getAttribute('position').count;
    const tangent = g.getAttribute('tangent');
    const { outputs } = this._feedback(renderer, null, Boolean(tangent));
    renderer.resetState(); // three's cached GL state: we bound our own program, VAO and buffers

    // the plain geometry: captured positions and normals, every other attribute repeated, indices offset
    const baked = new THREE.BufferGeometry();
    baked.setAttribute('position', new THREE.GLBufferAttribute(outputs[0], gl.FLOAT, 3, 4, n * V));
    baked.setAttribute('normal', new THREE.GLBufferAttribute(outputs[1], gl.FLOAT, 3, 4, n * V));
    if (tangent) baked.setAttribute('tangent', new THREE.GLBufferAttribute(outputs[2], gl.FLOAT, 4, 4, n * V));
    const source = this._sourceMaterials;
    const tinted = this.layout.tint !== null;
    const vertexColors = (Array.isArray(source) ? source : [source]).some((m) => m.vertexColors);
    if (tinted) { // each instance's tint times the vertex colour (where the material uses one): a colour a vertex
      const base = vertexColors && g.getAttribute('color') ? plainArray(g.getAttribute('color')) : null;
      const k = base ? g.getAttribute('color').itemSize : 3, tint = this.instanceColor.array;
      const colors = new Float32Array(n * V * k);
      for (let i = 0; i < n; i++) {
        for (let v = 0; v < V; v++) {
          const at = (i * V + v) * k;
          for (let c = 0; c < 3; c++) colors[at + c] = tint[3 * i + c] * (base ? base[v * k + c] : 1);
          if (k === 4) colors[at + 3] = base[v * 4 + 3];
        }
      }
      baked.setAttribute('color', new THREE.BufferAttribute(colors, k));
    }
    for (const [name, attr] of Object.entries(g.attributes)) {
      if (['position', 'normal', 'tangent'].includes(name) || name.startsWith('axial') || name.startsWith('_axial') ||
          attr.isInstancedBufferAttribute || (tinted && name === 'color')) continue;
      const src = plainArray(attr), k = attr.itemSize, rep = new src.constructor(src.length * n);
      for (let i = 0; i < n; i++) rep.set(src, i * src.length);
      baked.setAttribute(name, new THREE.BufferAttribute(rep, k, attr.normalized));
    }
    const index = g.index ? g.index.array : Uint32Array.from({ length: V }, (_, i) => i);
    const groups = g.groups.length ? g.groups : [{ start: 0, count: index.length, materialIndex: 0 }];
    const all = new Uint32Array(groups.reduce((t, gr) => t + Math.min(gr.count, index.length - gr.start), 0) * n);
    let at = 0;
    for (const gr of groups) { // each group's triangles of every instance together: one draw per material
      const first = at, end = Math.min(gr.start + gr.count, index.length);
      for (let i = 0; i < n; i++) {
        const off = i * V;
        for (let k = gr.start; k < end; k++) all[at++] = index[k] + off;
      }
      if (g.groups.length) baked.addGroup(first, at - first, gr.materialIndex);
    }
    // the index lives on the GPU only: three drops its copy once uploaded (raycasting is this mesh's)
    baked.setIndex(new THREE.BufferAttribute(all, 1).onUpload(function drop() { this.array = null; }));
    baked.boundingSphere = this.boundingSphere.clone();
    baked.boundingBox = this.boundingBox.clone();
    const materials = Array.isArray(source) ? source.map((m) => m.clone()) : source.clone();
    if (tinted) (Array.isArray(materials) ? materials : [materials]).forEach((m) => { m.vertexColors = true; });
    const mesh = new THREE.Mesh(baked, materials);
    mesh.name = `${this.name || 'axial'} (baked)`;
    mesh.castShadow = this.castShadow;
    mesh.receiveShadow = this.receiveShadow;
    mesh.raycast = () => {}; // this mesh's raycast answers, with instanceId
    this.add(mesh);
    this._baked = { mesh, gl, outputs };
    this.setBendVisible(false);
    return true;
  }

  /** Go back to bending every frame (frees the baked geometry). */
  unbake() {
    if (!this._baked) return this;
    const { mesh, gl, outputs } = this._baked;
    this.remove(mesh);
    mesh.geometry.dispose();
    (Array.isArray(mesh.material) ? mesh.material : [mesh.material]).forEach((m) => m.dispose());
    outputs.forEach((b) => gl.deleteBuffer(b));
    this._baked = null;
    this.setBendVisible(true);
    return this;
  }

  /** Whether the instances are drawn from a bake (bake()) rather than bent every frame. */
  get baked() {
    return Boolean(this._baked);
  }

  setBendVisible(on) {
    (Array.isArray(this.material) ? this.material : [this.material]).forEach((m) => { m.visible = on; });
    this._shadowMaterials.forEach((m) => { m.visible = on; });
  }

  /**
   * One transform-feedback pass of this mesh's BEND (the materials' vertex code) over instances
   * `ids` (null: all): their placed positions, normals (and tangents) in new GL buffers, instance
   * after instance.  Leaves GL state changed: the caller resets three's (renderer.resetState()).
   */
  _feedback(renderer, ids, tangent) {
    this._renderer = renderer;
    const gl = renderer.getContext(), g = this.geometry, V = g.getAttribute('position').count;
    const n = ids ? ids.length : this.count;
    const program = this._feedbackProgram(gl, tangent, this.axis.axes ? this.axis.axes.count : 0, Boolean(this._wind));
    const buffers = [];
    const upload = (array) => {
      const b = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.bufferData(gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
      buffers.push(b);
      return b;
    };
    const vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    const bind = (name, array, size, divisor, stride = 0, offset = 0, column = 0) => {
      const at = gl.getAttribLocation(program, name);
      if (at < 0) return;
      gl.bindBuffer(gl.ARRAY_BUFFER, array);
      gl.enableVertexAttribArray(at + column);
      gl.vertexAttribPointer(at + column, size, gl.FLOAT, false, stride, offset);
      gl.vertexAttribDivisor(at + column, divisor);
    };
    // per instance: the attribute arrays as they are (all), or the rows of `ids` gathered
    const rows = (array, size) => {
      if (!ids) return array.subarray(0, size * n);
      const out = new Float32Array(size * n);
      ids.forEach((id, k) => out.set(array.subarray(size * id, size * (id + 1)), size * k));
      return out;
    };
    if (this.axis.axes) bind('axialAxis', upload(plainArray(g.getAttribute('axialAxis'))), 1, 0);
    bind('position', upload(plainArray(g.getAttribute('position'))), 3, 0);
    bind('normal', upload(plainArray(g.getAttribute('normal'))), 3, 0);
    if (tangent) bind('tangent', upload(plainArray(g.getAttribute('tangent'))), 4, 0);
    const a = g.attributes;
    for (const [name, size] of [['axialD12', 4], ['axialD34', 4], ['axialD5', 2], ['axialTwistTaper', 2], ['axialAngles', 3]]) {
      bind(name, upload(rows(a[name].array, size)), size, 1);
    }
    const mats = upload(rows(this.instanceMatrix.array, 16));
    for (let c = 0; c < 4; c++) bind('instanceMatrix', mats, 4, 1, 64, 16 * c, c);
    bind('axialId', upload(ids ? Float32Array.from(ids) : Float32Array.from({ length: n }, (_, i) => i)), 1, 1);
    gl.useProgram(program);
    const u = this.axialUniforms;
    const loc = (name) => gl.getUniformLocation(program, name);
    gl.uniformMatrix3fv(loc('axialFrame'), false, u.axialFrame.value.elements);
    gl.uniform1f(loc('axialLo'), u.axialLo.value);
    gl.uniform1f(loc('axialLen'), u.axialLen.value);
    gl.uniform2f(loc('axialCenter'), u.axialCenter.value.x, u.axialCenter.value.y);
    if (this.axis.axes) { // several axes: every axis's frame, lo, L, parent, and the child offsets' texture
      const k = this.axis.axes.count, frames = new Float32Array(9 * k);
      u.axialFrames.value.forEach((m, j) => frames.set(m.elements, 9 * j));
      gl.uniformMatrix3fv(loc('axialFrames'), false, frames);
      gl.uniform1fv(loc('axialLos'), u.axialLos.value);
      gl.uniform1fv(loc('axialLens'), u.axialLens.value);
      gl.uniform1iv(loc('axialParents'), u.axialParents.value);
      renderer.initTexture(u.axialChildren.value); // uploaded by three: its GL texture, on unit 0
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, renderer.properties.get(u.axialChildren.value).__webglTexture);
      gl.uniform1i(loc('axialChildren'), 0);
    }
    if (this._wind) { // the wind at this moment, as the materials sway the instances
      const w = (name) => u[name].value;
      gl.uniform3f(loc('axialWindDir'), w('axialWindDir').x, w('axialWindDir').y, w('axialWindDir').z);
      gl.uniform1f(loc('axialWindStrength'), w('axialWindStrength'));
      gl.uniform1f(loc('axialWindGust'), w('axialWindGust'));
      gl.uniform2f(loc('axialWindCycles'), w('axialWindCycles').x, w('axialWindCycles').y);
      gl.uniform1f(loc('axialWindWavenumber'), w('axialWindWavenumber'));
    }
    const out = (size) => {
      const b = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.bufferData(gl.ARRAY_BUFFER, n * V * size * 4, gl.STATIC_DRAW);
      return b;
    };
    const outputs = [out(3), out(3), ...(tangent ? [out(4)] : [])];
    gl.bindBuffer(gl.ARRAY_BUFFER, null); // a buffer bound elsewhere may not be written by the feedback
    const tf = gl.createTransformFeedback();
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, tf);
    outputs.forEach((b, i) => gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, i, b));
    gl.enable(gl.RASTERIZER_DISCARD);
    gl.beginTransformFeedback(gl.POINTS);
    gl.drawArraysInstanced(gl.POINTS, 0, V, n); // instance-major: instance k's vertices at k V
    gl.endTransformFeedback();
    gl.disable(gl.RASTERIZER_DISCARD);
    outputs.forEach((b, i) => gl.bindBufferBase(gl.TRANSFORM_FEEDBACK_BUFFER, i, null));
    gl.bindTransformFeedback(gl.TRANSFORM_FEEDBACK, null);
    gl.deleteTransformFeedback(tf);
    gl.bindVertexArray(null);
    gl.deleteVertexArray(vao);
    buffers.forEach((b) => gl.deleteBuffer(b));
    return { gl, outputs };
  }

  _feedbackProgram(gl, tangent, axes = 0, wind = false) {
    const key = `${tangent ? 'tangent' : 'plain'}:${axes}:${wind ? 'wind' : ''}`;
    this._programs = this._programs || {};
    if (this._programs[key] && this._programs[key].gl === gl) return this._programs[key].program;
    const vs = `#version 300 es
precision highp float;
precision highp int;
${tangent ? '#define USE_TANGENT' : ''}
${axes ? `#define AXIAL_AXES ${axes}` : ''}
${wind ? '#define AXIAL_WIND 1' : ''}
#define AXIAL_ID int(axialId + 0.5)
${AXIAL_GLSL}
${WIND_GLSL}
in vec3 position;
in vec3 normal;
in vec4 tangent;
in mat4 instanceMatrix;
in float axialId;           // the instance's index (the instances drawn may be a selection)
${UNIFORMS.replace(/attribute /g, 'in ')}
out vec3 axialOutPosition;
out vec3 axialOutNormal;
out vec4 axialOutTangent;
void main() {
${BEND}
  mat4 m = instanceMatrix;
  axialOutPosition = (m * vec4(axialV, 1.0)).xyz;
  axialOutNormal = normalize(mat3(m) * axialN);
  axialOutTangent = vec4(normalize(mat3(m) * axialT), tangent.w);
  gl_Position = vec4(0.0);
}`;
    const fs = '#version 300 es\nprecision highp float;\nout vec4 color;\nvoid main() { color = vec4(0.0); }';
    const shader = (type, text) => {
      const sh = gl.createShader(type);
      gl.shaderSource(sh, text);
      gl.compileShader(sh);
      if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new AxialError(`bake: the shader did not compile: ${gl.getShaderInfoLog(sh)}`);
      return sh;
    };
    const program = gl.createProgram();
    gl.attachShader(program, shader(gl.VERTEX_SHADER, vs));
    gl.attachShader(program, shader(gl.FRAGMENT_SHADER, fs));
    const varyings = ['axialOutPosition', 'axialOutNormal', ...(tangent ? ['axialOutTangent'] : [])];
    gl.transformFeedbackVaryings(program, varyings, gl.SEPARATE_ATTRIBS);
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new AxialError(`bake: the program did not link: ${gl.getProgramInfoLog(program)}`);
    this._programs[key] = { gl, program };
    return program;
  }

  /** Frees this mesh's GPU buffers, its materials (the clones), shadow materials and texture;
   * the user's geometry and materials stay theirs. */
  dispose() {
    this.unbake();
    if (this._programs) Object.values(this._programs).forEach(({ gl, program }) => gl.deleteProgram(program));
    this._programs = null;
    this.geometry.dispose();
    (Array.isArray(this.material) ? this.material : [this.material]).forEach((m) => m.dispose());
    this._shadowMaterials.forEach((m) => m.dispose());
    if (this.axialUniforms.axialChildren && this.axialUniforms.axialChildren.value) this.axialUniforms.axialChildren.value.dispose();
    if (this._rayMesh) this._rayMesh.geometry.dispose();
    this.dispatchEvent({ type: 'dispose' });
    return this;
  }
}

