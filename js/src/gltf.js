// gltf.js -- AxialGLTFPlugin: GLTFLoader reads the AXIALDEFORM_bend extension
// (docs/gltf/AXIALDEFORM_bend) and every instanced node that carries it becomes
// an AxialInstancedMesh with the file's materials:
//     const loader = new GLTFLoader();
//     loader.register((parser) => new AxialGLTFPlugin(parser));

import { AxialError } from './adp.js';
import { AxialInstancedMesh } from './mesh.js';

/** The extension's name. */
export const EXTENSION = 'AXIALDEFORM_bend';


/** GLTFLoader plugin: EXT_mesh_gpu_instancing nodes with AXIALDEFORM_bend load bent. */
export class AxialGLTFPlugin {
  constructor(parser) {
    this.parser = parser;
    this.name = EXTENSION;
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
      for (const part of parts) {
        const bent = fromInstancedMesh(part, ext, where);
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
export function recordFromInstancedMesh(mesh, ext, where = 'node') {
  const g = mesh.geometry, n = mesh.count, f = ext.numbersPerInstance, k = ext.axes ? ext.axes.count : 1;
  const base = f - 10 * (k - 1);
  const need = ['_AXIAL_D12', '_AXIAL_D34', '_AXIAL_D5', '_AXIAL_ANGLES'];
  if (base >= 19) need.push('_AXIAL_TWIST_TAPER');
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
  copy('_AXIAL_ANGLES', 3, rest + 3);
  for (let i = 0; i < n; i++) { // position: TRANSLATION, the matrix's last column; s: the first column's length
    data[i * f + rest] = m[16 * i + 12]; data[i * f + rest + 1] = m[16 * i + 13]; data[i * f + rest + 2] = m[16 * i + 14];
    if (base >= 19) data[i * f + rest + 6] = Math.hypot(m[16 * i], m[16 * i + 1], m[16 * i + 2]);
  }
  if (base >= 19) copy('_AXIAL_TWIST_TAPER', 2, rest + 7);
  if (base >= 22) {
    if (!mesh.instanceColor) throw new AxialError(`${where}: 22 numbers an instance need _COLOR_0 (the tint)`);
    for (let i = 0; i < n; i++) for (let c = 0; c < 3; c++) data[i * f + rest + 9 + c] = mesh.instanceColor.array[3 * i + c];
  }
  return { name: where, count: n, numbersPerInstance: f, axes: k, data };
}

/** An AxialInstancedMesh in place of GLTFLoader's InstancedMesh (same geometry, material, name, transform). */
export function fromInstancedMesh(mesh, ext, where = 'node') {
  if (!ext || !ext.axis || !Number.isInteger(ext.numbersPerInstance)) {
    throw new AxialError(`${where}: ${EXTENSION}: expected "axis" and "numbersPerInstance"`);
  }
  const record = recordFromInstancedMesh(mesh, ext, where);
  const g = mesh.geometry;
  const bent = new AxialInstancedMesh(g, mesh.material, record, {
    axis: { axis: ext.axis, axes: ext.axes || null },
    vertexAxis: g.getAttribute('_axial_axis') || undefined,
  });
  bent.name = mesh.name;
  bent.position.copy(mesh.position); bent.quaternion.copy(mesh.quaternion); bent.scale.copy(mesh.scale);
  bent.userData = { ...mesh.userData, [EXTENSION]: ext };
  bent.castShadow = mesh.castShadow; bent.receiveShadow = mesh.receiveShadow;
  return bent;
}
