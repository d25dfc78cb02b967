// core/gltf.js -- the glTF plugin under any renderer: GLTFLoader reads the AXIALDEFORM_bend extension
// (docs/gltf/AXIALDEFORM_bend) and every instanced node that carries it becomes a mesh of the renderer's
// entry (webgl/gltf.js, webgpu.js: AxialGLTFPlugin) with the file's materials:
//     const loader = new GLTFLoader();
//     loader.register((parser) => new AxialGLTFPlugin(parser));

import * as THREE from 'three';
import { AxialError, checkNumbers } from './adp.js';
import { FRAME_TOLERANCE, GLTF_INSTANCE_TYPES, MAX_AXES, WIDTHS } from './record.js';

const [WIDTH, EXTENDED_WIDTH, TINTED_WIDTH] = WIDTHS; // 16, 19, 22 numbers: record.js's levels
import { checkRecipe, maxTiles, tileSize } from './generate.js';
import { MAX_MAP_TEXELS, MAX_SLOTS, checkSlots, checkUniforms, optionalNumbers } from './limits.js';

/** The extension's name. */
export const EXTENSION = 'AXIALDEFORM_bend';

const COMPONENT_BYTES = { 5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4 };
const TYPE_SIZES = { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 };

function attributeType(name) {
  const child = /^_AXIAL_A[1-9][0-9]*(_D12|_D34|_D5)$/.exec(name);
  return child ? GLTF_INSTANCE_TYPES[`_AXIAL${child[1]}`] : GLTF_INSTANCE_TYPES[name];
}

/** An instance attribute's accessor as axialdeform's Python reader takes it (core/io/glb.read_accessor):
 * a known component type and type, a bufferView in range, aligned, inside its view and buffer. */
function checkAccessor(json, a, name, where) {
  const acc = json.accessors[a], views = json.bufferViews || [], buffers = json.buffers || [];
  const bytes = COMPONENT_BYTES[acc.componentType], size = TYPE_SIZES[acc.type];
  if (!bytes || !size || acc.bufferView === undefined) {
    throw new AxialError(`${where}: ${name}: unsupported accessor (${brief(acc.type)} of component type ${brief(acc.componentType)}, bufferView ${brief(acc.bufferView)})`);
  }
  if (!Number.isInteger(acc.bufferView) || acc.bufferView < 0 || acc.bufferView >= views.length) {
    throw new AxialError(`${where}: ${name}: accessor ${a} bufferView: expected 0..${views.length - 1}, found ${brief(acc.bufferView)}`);
  }
  const view = views[acc.bufferView] || {};
  const viewStart = view.byteOffset || 0, offset = acc.byteOffset || 0, stride = view.byteStride || bytes * size;
  const buffer = buffers[view.buffer];
  if (![viewStart, offset, stride, view.byteLength].every((x) => Number.isInteger(x) && x >= 0) || !buffer) {
    throw new AxialError(`${where}: ${name}: accessor ${a}: expected whole byte offsets and lengths and a buffer`);
  }
  if ((viewStart + offset) % bytes || stride % bytes) {
    throw new AxialError(`${where}: ${name}: accessor ${a} byteOffset: expected a multiple of ${bytes} (the component's size), found ${viewStart + offset}`);
  }
  const need = viewStart + offset + (acc.count ? (acc.count - 1) * stride + bytes * size : 0);
  if (need > viewStart + view.byteLength || need > buffer.byteLength) {
    throw new AxialError(`${where}: ${name}: accessor ${a} runs past its bufferView (truncated file?)`);
  }
  const type = attributeType(name);
  if (type && acc.type !== type) throw new AxialError(`${where}: ${name}: expected ${type}, found ${brief(acc.type)}`);
}

/** The attributes a node's extension needs, and the record width they hold, as Python reads them:
 * 22 numbers with _COLOR_0, 19 with SCALE or _AXIAL_TWIST_TAPER, else 16; the child axes' three each. */
function checkAttributes(ext, names, where) {
  const k = ext.axes ? ext.axes.count : 1, base = ext.numbersPerInstance - 10 * (k - 1);
  const need = ['_AXIAL_D12', '_AXIAL_D34', '_AXIAL_D5'];
  for (let j = 1; j < k; j++) need.push(`_AXIAL_A${j}_D12`, `_AXIAL_A${j}_D34`, `_AXIAL_A${j}_D5`);
  const missing = need.filter((a) => !names.includes(a));
  if (!names.includes('_AXIAL_ANGLES') && !names.includes('ROTATION')) missing.push('_AXIAL_ANGLES (or ROTATION)');
  if (missing.length) throw new AxialError(`${where}: ${EXTENSION} needs the instance attributes ${missing.join(', ')}`);
  const held = names.includes('_COLOR_0') ? TINTED_WIDTH
    : names.includes('SCALE') || names.includes('_AXIAL_TWIST_TAPER') ? EXTENDED_WIDTH : WIDTH;
  if (held !== base) {
    throw new AxialError(`${where}: ${EXTENSION}: numbersPerInstance: ${ext.numbersPerInstance}, but the instance attributes hold ${held + 10 * (k - 1)} numbers an instance`);
  }
}


/** GLTFLoader plugin: EXT_mesh_gpu_instancing nodes with AXIALDEFORM_bend load bent, as meshes of class
 * `Mesh` (AxialInstancedMesh of a renderer's entry; a generated node as one made from its recipe). */
export class AxialGLTFPluginBase {
  /** `options.maxSlots`: the most slots a generated node may hold (limits.js's MAX_SLOTS; a file asking
   * for more is refused in one line before anything is allocated). */
  constructor(parser, options, Mesh) {
    this.parser = parser;
    this.options = options || {};
    this.name = EXTENSION;
    /** @type {any} the entry's mesh class */
    this.Mesh = Mesh;
  }

  /** Before GLTFLoader reads anything of the file: every node's AXIALDEFORM_bend and the instance
   * accessors it relies on are checked (indices in range, counts whole and equal, at most 64 axes'
   * worth of attributes), so a broken file is an AxialError naming the node and the field, not a
   * TypeError or RangeError from inside the loader, nor an allocation sized by the file. */
  beforeRoot() {
    const json = this.parser.json, nodes = json.nodes || [], accessors = json.accessors || [];
    nodes.forEach((def, i) => {
      const ext = def && def.extensions && def.extensions[EXTENSION];
      if (!ext) return;
      const where = `node ${i} (${def.name || 'unnamed'})`;
      checkBendExtension(ext, where, this.options);
      const inst = def.extensions.EXT_mesh_gpu_instancing;
      const attrs = inst && inst.attributes;
      if (!attrs || typeof attrs !== 'object') throw new AxialError(`${where}: ${EXTENSION} without EXT_mesh_gpu_instancing attributes`);
      const names = Object.keys(attrs);
      if (names.length > 16 + 3 * MAX_AXES) {
        throw new AxialError(`${where}: EXT_mesh_gpu_instancing attributes: ${names.length} of them; expected at most ${MAX_AXES} axes' worth`);
      }
      let count = null;
      for (const name of names) {
        const a = attrs[name];
        if (!Number.isInteger(a) || a < 0 || a >= accessors.length) {
          throw new AxialError(`${where}: EXT_mesh_gpu_instancing attributes ${name}: expected an accessor index 0..${accessors.length - 1}, found ${brief(a)}`);
        }
        const c = accessors[a] && accessors[a].count;
        if (!Number.isInteger(c) || c < 0 || c > 2147483647) {
          throw new AxialError(`${where}: ${name}: accessor ${a} count: expected a whole number 0..2147483647, found ${brief(c)}`);
        }
        if (count !== null && c !== count) {
          throw new AxialError(`${where}: EXT_mesh_gpu_instancing attributes have different counts (${count} and ${c}); expected one count`);
        }
        count = c;
        checkAccessor(json, a, name, where);
      }
      checkAttributes(ext, names, where);
      for (const key of ['heights', 'density', 'children']) { // the generated form's maps: FLOAT SCALAR, cols x rows
        const m = ext.generate && ext.generate[key];
        if (!m) continue;
        if (!Number.isInteger(m.accessor) || m.accessor < 0 || m.accessor >= accessors.length) {
          throw new AxialError(`${where}: ${EXTENSION} generate ${key} accessor: expected 0..${accessors.length - 1}, found ${brief(m.accessor)}`);
        }
        const acc = accessors[m.accessor];
        if (acc.type !== 'SCALAR' || acc.componentType !== 5126 || acc.count !== m.cols * m.rows) {
          throw new AxialError(`${where}: ${EXTENSION} generate ${key}: expected a FLOAT SCALAR accessor of ${m.cols} x ${m.rows}`);
        }
        checkAccessor(json, m.accessor, `generate ${key}`, where);
      }
    });
    return null;
  }

  async afterRoot(gltf) {
    const parser = this.parser, nodes = parser.json.nodes || [];
    const swaps = [];
    gltf.scene.traverse((object) => {
      const assoc = parser.associations.get(object);
      if (!assoc || assoc.nodes === undefined) return;
      const def = nodes[assoc.nodes];
      const ext = def && def.extensions && def.extensions[EXTENSION];
      if (!ext) return;
      const parts = object.isInstancedMesh ? [object] : object.children.filter((c) => c.isInstancedMesh);
      if (!parts.length) throw new AxialError(`node ${assoc.nodes} (${def.name || 'unnamed'}): ${EXTENSION} without EXT_mesh_gpu_instancing`);
      swaps.push({ object, parts, ext, where: `node ${assoc.nodes} (${def.name || 'unnamed'})` });
    });
    for (const { object, parts, ext, where } of swaps) {
      // the placement as the file holds it (three folds TRANSLATION, ROTATION, SCALE into matrices):
      // the position from TRANSLATION, the scale s from SCALE; the rotation from _AXIAL_ANGLES
      const attrs = nodes[parser.associations.get(object).nodes].extensions.EXT_mesh_gpu_instancing.attributes;
      const raw = {};
      for (const name of ['TRANSLATION', 'SCALE']) {
        if (attrs[name] !== undefined) raw[name] = await parser.getDependency('accessor', attrs[name]);
      }
      // the generated form: the node's instances made from its recipe around the camera ({generate: recipe})
      let maps = null;
      if (ext.generate) {
        maps = {};
        for (const key of ['heights', 'density', 'children']) {
          const m = ext.generate[key];
          if (m) maps[key] = { data: (await parser.getDependency('accessor', m.accessor)).array, cols: m.cols, rows: m.rows };
        }
      }
      for (const part of parts) {
        const bent = maps ? fromGenerated(part, ext, maps, this.Mesh, this.options) : fromInstancedMesh(part, ext, where, raw, this.Mesh);
        if (part === object) {
          const parent = object.parent;
          parent.add(bent);
          parent.remove(object);
        } else {
          object.add(bent);
          object.remove(part);
        }
        parser.associations.set(bent, parser.associations.get(part) || {});
      }
    }
  }
}

/** The record of an InstancedMesh GLTFLoader made from EXT_mesh_gpu_instancing with the _AXIAL_*
 * attributes, as AxialInstancedMesh takes it; `ext` the node's AXIALDEFORM_bend. */
export function recordFromInstancedMesh(mesh, ext, where = 'node', raw = null) {
  const g = mesh.geometry, n = mesh.count, f = ext.numbersPerInstance, k = ext.axes ? ext.axes.count : 1;
  const base = f - 10 * (k - 1);
  const need = ['_AXIAL_D12', '_AXIAL_D34', '_AXIAL_D5'];
  if (!raw) need.push('_AXIAL_ANGLES');
  if (base >= EXTENDED_WIDTH && !raw) need.push('_AXIAL_TWIST_TAPER');
  for (let j = 1; j < k; j++) need.push(`_AXIAL_A${j}_D12`, `_AXIAL_A${j}_D34`, `_AXIAL_A${j}_D5`);
  const missing = need.filter((a) => !g.getAttribute(a));
  if (missing.length) throw new AxialError(`${where}: ${EXTENSION} needs the instance attributes ${missing.join(', ')}`);
  const data = new Float32Array(n * f);
  const m = mesh.instanceMatrix.array;
  const copy = (name, size, col) => {
    const a = g.getAttribute(name);
    for (let i = 0; i < n; i++) for (let c = 0; c < size; c++) data[i * f + col + c] = a.getComponent(i, c);
  };
  copy('_AXIAL_D12', 4, 0); copy('_AXIAL_D34', 4, 4); copy('_AXIAL_D5', 2, 8);
  for (let j = 1; j < k; j++) { copy(`_AXIAL_A${j}_D12`, 4, 10 * j); copy(`_AXIAL_A${j}_D34`, 4, 10 * j + 4); copy(`_AXIAL_A${j}_D5`, 2, 10 * j + 8); }
  const rest = 10 * k;
  if (g.getAttribute('_AXIAL_ANGLES')) {
    copy('_AXIAL_ANGLES', 3, rest + 3);
  } else { // ROTATION alone: the angles of R = Rz Ry Rx (three's Euler order 'ZYX'), as Python's reader does
    const mat = new THREE.Matrix4(), rot = new THREE.Matrix4(), e = new THREE.Euler(), p = new THREE.Vector3();
    const q = new THREE.Quaternion(), s = new THREE.Vector3();
    for (let i = 0; i < n; i++) {
      mat.fromArray(m, 16 * i).decompose(p, q, s);
      e.setFromRotationMatrix(rot.makeRotationFromQuaternion(q), 'ZYX');
      data[i * f + rest + 3] = e.x; data[i * f + rest + 4] = e.y; data[i * f + rest + 5] = e.z;
    }
  }
  if (raw) { // the file's own TRANSLATION (absent: 0) and SCALE (absent: 1; uniform, as Python takes it)
    const t = raw.TRANSLATION, s = raw.SCALE;
    for (let i = 0; i < n; i++) {
      for (let c = 0; c < 3; c++) data[i * f + rest + c] = t ? t.getComponent(i, c) : 0;
      if (base < EXTENDED_WIDTH) continue;
      const x = s ? s.getComponent(i, 0) : 1;
      if (s && !(s.getComponent(i, 1) === x && s.getComponent(i, 2) === x)) {
        throw new AxialError(`${where}: SCALE: expected a uniform scale (VEC3 with three equal components) per instance`);
      }
      data[i * f + rest + 6] = x;
    }
  } else {
    for (let i = 0; i < n; i++) { // position: TRANSLATION, the matrix's last column; s: the first column's length
      data[i * f + rest] = m[16 * i + 12]; data[i * f + rest + 1] = m[16 * i + 13]; data[i * f + rest + 2] = m[16 * i + 14];
      if (base >= EXTENDED_WIDTH) data[i * f + rest + 6] = Math.hypot(m[16 * i], m[16 * i + 1], m[16 * i + 2]);
    }
  }
  if (base >= EXTENDED_WIDTH && g.getAttribute('_AXIAL_TWIST_TAPER')) copy('_AXIAL_TWIST_TAPER', 2, rest + 7);
  if (base >= TINTED_WIDTH) {
    if (!mesh.instanceColor) throw new AxialError(`${where}: ${TINTED_WIDTH} numbers an instance need _COLOR_0 (the tint)`);
    for (let i = 0; i < n; i++) for (let c = 0; c < 3; c++) data[i * f + rest + 9 + c] = mesh.instanceColor.array[3 * i + c];
  }
  checkNumbers(data, f, k, where); // finite, a scale > 0, a taper < 1, a tint in 0..1: as every reader checks
  return { name: where, count: n, numbersPerInstance: f, axes: k, data };
}


/** A value for a message, bounded (a file's array of a million items is not copied into it). */
function brief(value) {
  if (Array.isArray(value) && value.length > 8) return `[${value.slice(0, 8).map(brief).join(', ')}, ... (${value.length} items)]`;
  if (Array.isArray(value)) return `[${value.map(brief).join(', ')}]`;
  const text = JSON.stringify(value);
  return text === undefined ? String(value) : text.length > 80 ? `${text.slice(0, 80)}...` : text;
}

function numbers(value, count, where, positive = false) {
  const ok = Array.isArray(value) && value.length === count &&
    value.every((x) => typeof x === 'number' && Number.isFinite(x) && (!positive || x > 0));
  if (!ok) {
    throw new AxialError(`${where}: expected ${count} finite${positive ? ' positive' : ''} number(s), found ${brief(value)}`);
  }
  return value;
}

function frameRows(value, where) {
  if (!Array.isArray(value) || value.length !== 3) {
    throw new AxialError(`${where}: expected 3 rows of 3 numbers (e_a, e_u, e_v), found ${brief(value)}`);
  }
  const f = value.map((row) => numbers(row, 3, where));
  let err = 0;
  for (let i = 0; i < 3; i++) {
    for (let j = 0; j < 3; j++) {
      err = Math.max(err, Math.abs(f[i][0] * f[j][0] + f[i][1] * f[j][1] + f[i][2] * f[j][2] - (i === j ? 1 : 0)));
    }
  }
  if (!(err <= FRAME_TOLERANCE)) throw new AxialError(`${where}: the frame is not orthogonal (|F·Fᵀ − I| = ${err.toPrecision(3)}); expected orthonormal rows`);
  return f;
}

/**
 * Check a node's AXIALDEFORM_bend object against docs/gltf/AXIALDEFORM_bend (the rules its schema
 * says and those it cannot: a tree's parents before their children, orthonormal finite frames,
 * lengths > 0, the numbers per instance matching the axes, at most 64 axes) before anything is sized
 * by it; an AxialError naming the node and the field, as axialdeform's Python reader does.
 */
export function checkBendExtension(ext, where = 'node', options = {}) {
  const at = `${where}: ${EXTENSION}`;
  if (!ext || typeof ext !== 'object' || Array.isArray(ext)) throw new AxialError(`${at}: expected an object`);
  const f = ext.numbersPerInstance, axes = ext.axes;
  if (axes !== undefined && (!axes || typeof axes !== 'object' || Array.isArray(axes))) {
    throw new AxialError(`${at}: axes: expected an object (count, parents, frames, lo, length), found ${brief(axes)}`);
  }
  const k = axes === undefined ? 1 : axes.count;
  if (!Number.isInteger(k) || k < 2 && axes != null || k > MAX_AXES) {
    throw new AxialError(`${at}: axes count: expected 2 to ${MAX_AXES} axes, found ${brief(k)}`);
  }
  if (!Number.isInteger(f) || !WIDTHS.includes(f - 10 * (k - 1))) {
    throw new AxialError(`${at}: numbersPerInstance: expected ${WIDTHS.join(', ')} plus 10 per axis after the first (${k} axes), found ${brief(f)}`);
  }
  const axis = ext.axis;
  if (!axis || typeof axis !== 'object') throw new AxialError(`${at}: axis: expected an object with frame, lo, length and center`);
  frameRows(axis.frame, `${at}: axis frame`);
  numbers([axis.lo], 1, `${at}: axis lo`);
  numbers([axis.length], 1, `${at}: axis length`, true);
  numbers(axis.center, 2, `${at}: axis center`);
  if (ext.fingerprint !== undefined && !(typeof ext.fingerprint === 'string' && /^[0-9a-f]{64}$/.test(ext.fingerprint))) {
    throw new AxialError(`${at}: fingerprint: expected 64 lower-case hex digits (SHA-256), found ${brief(ext.fingerprint)}`);
  }
  if (ext.generate !== undefined) checkGenerated(ext.generate, at, k, ext.axis.length, options.maxSlots ?? MAX_SLOTS);
  if (k > 1) {
    const p = axes.parents;
    if (!Array.isArray(p) || p.length !== k || p[0] !== -1 || p.some((x, i) => i > 0 && !(Number.isInteger(x) && x >= 0 && x < i))) {
      throw new AxialError(`${at}: axes: parents: expected -1 for axis 0 and a parent p < k for every axis k (no cycle, no forward or negative parent), found ${brief(p)}`);
    }
    if (!Array.isArray(axes.frames) || axes.frames.length !== k) throw new AxialError(`${at}: axes frames: expected ${k} frames`);
    axes.frames.forEach((fr, j) => frameRows(fr, `${at}: axes frames[${j}]`));
    numbers(axes.lo, k, `${at}: axes lo`);
    numbers(axes.length, k, `${at}: axes length`, true);
    if (axes.anchors !== undefined && !(Array.isArray(axes.anchors) && axes.anchors.length === k
        && axes.anchors.every((t) => typeof t === 'number' && t >= 0 && t <= 1))) {
      throw new AxialError(`${at}: axes anchors: expected ${k} numbers in 0..1 (t on each axis's own length), found ${brief(axes.anchors)}`);
    }
  }
  return ext;
}

/** The generated form's object: a recipe (checkRecipe), the generator's numbers, the maps' shapes. */
function checkGenerated(gen, at, k, axisLength, maxSlots) {
  if (!gen || typeof gen !== 'object' || Array.isArray(gen)) throw new AxialError(`${at}: generate: expected an object (recipe, uniforms)`);
  if (k > 1 && !(gen.children && gen.children.cols === 26 && gen.children.rows === k - 1)) {
    throw new AxialError(`${at}: generate children: a node of ${k} axes needs its child-axis table (${k - 1} rows of 26), found ${brief(gen.children)}`);
  }
  let r;
  try {
    r = checkRecipe(gen.recipe);
  } catch (err) {
    throw new AxialError(`${at}: generate recipe: ${err.message.replace(/^generate: /, '')}`);
  }
  const u = gen.uniforms && typeof gen.uniforms === 'object' && !Array.isArray(gen.uniforms) ? { ...optionalNumbers(), ...gen.uniforms } : gen.uniforms;
  if (!u || typeof u !== 'object' || Array.isArray(u)) {
    throw new AxialError(`${at}: generate uniforms: expected generate.glsl's numbers (seed, m, cell, ...), found ${brief(u)}`);
  }
  for (const key of ['heights', 'density', 'children']) {
    const m = gen[key];
    if (m !== undefined && !(m && Number.isInteger(m.cols) && m.cols > 0 && Number.isInteger(m.rows) && m.rows > 0
        && m.cols * m.rows <= MAX_MAP_TEXELS)) {
      throw new AxialError(`${at}: generate ${key}: expected {accessor, cols, rows} of at most ${MAX_MAP_TEXELS} numbers, found ${brief(m)}`);
    }
  }
  try {
    checkUniforms(u, r, axisLength, { heights: gen.heights, density: gen.density }, ...tileSize(r));
    checkSlots(maxTiles(r.tile, r.reach), tileSize(r)[0], k, maxSlots);
  } catch (err) {
    throw new AxialError(`${at}: ${err.message}`);
  }
}

/** A generated layer (`Mesh` made from {generate: recipe}) in place of GLTFLoader's InstancedMesh of a generated node: its recipe, the
 * generator's numbers the file holds, the ground maps; the tiles within reach of the camera, made
 * before it is drawn (autoUpdate). */
function fromGenerated(mesh, ext, maps, Mesh, options = {}) {
  const g = mesh.geometry;
  return adopt(mesh, ext, new Mesh(g, mesh.material, { generate: ext.generate.recipe }, {
    ...options, axis: { axis: ext.axis, axes: ext.axes || null }, uniforms: ext.generate.uniforms, maps, autoUpdate: true,
    vertexAxis: g.getAttribute('_axial_axis') || undefined,
  }));
}

/** `made` takes GLTFLoader's mesh's place: its name, transform, user data (and the extension), shadows. */
function adopt(mesh, ext, made) {
  made.name = mesh.name;
  made.position.copy(mesh.position); made.quaternion.copy(mesh.quaternion); made.scale.copy(mesh.scale);
  made.userData = { ...mesh.userData, [EXTENSION]: ext };
  made.castShadow = mesh.castShadow; made.receiveShadow = mesh.receiveShadow;
  return made;
}

/** A `Mesh` (an entry's AxialInstancedMesh) in place of GLTFLoader's InstancedMesh (same geometry, material,
 * name, transform). */
export function fromInstancedMesh(mesh, ext, where, raw, Mesh) {
  checkBendExtension(ext, where);
  const record = recordFromInstancedMesh(mesh, ext, where, raw);
  const g = mesh.geometry;
  return adopt(mesh, ext, new Mesh(g, mesh.material, record, {
    axis: { axis: ext.axis, axes: ext.axes || null },
    vertexAxis: g.getAttribute('_axial_axis') || undefined,
  }));
}
