// core/baked.js -- a mesh's instances drawn from vertices bent once (by WebGL 2 transform feedback,
// webgl/bake.js, or a WebGPU compute pass, webgpu/mesh.js's bakeAsync) as one plain child mesh, until
// they move again.

import * as THREE from 'three';

/** A vertex attribute as a tight float32 array (interleaved, integer or normalized ones unpacked). */
export function plainArray(attr) {
  if (!attr.isInterleavedBufferAttribute && attr.array instanceof Float32Array) return attr.array;
  const out = new Float32Array(attr.count * attr.itemSize);
  for (let i = 0; i < attr.count; i++) for (let c = 0; c < attr.itemSize; c++) out[i * attr.itemSize + c] = attr.getComponent(i, c);
  return out;
}


/**
 * Draw `mesh`'s instances from bent vertices (`bent`: {position, normal, tangent?} attributes of
 * count x V vertices, instance by instance) as one plain child mesh, hiding the bent draw: every
 * other attribute repeated, indices offset, the tint a colour a vertex.  `release` frees what made
 * `bent` (unbake calls it).  Shared by WebGL 2's bake and WebGPU's bakeAsync.
 */
export function attachBake(mesh, bent, release) {
  const g = mesh.geometry, n = mesh.count, V = g.getAttribute('position').count;
  const baked = new THREE.BufferGeometry();
  for (const [name, attr] of Object.entries(bent)) if (attr) baked.setAttribute(name, attr);
  const source = mesh._sourceMaterials;
  const tinted = mesh.layout.tint !== null;
  const vertexColors = (Array.isArray(source) ? source : [source]).some((m) => m.vertexColors);
  if (tinted) { // each instance's tint times the vertex colour (where the material uses one): a colour a vertex
    const base = vertexColors && g.getAttribute('color') ? plainArray(g.getAttribute('color')) : null;
    const k = base ? g.getAttribute('color').itemSize : 3, tint = mesh.instanceColor.array;
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
  // the index lives on the GPU only: three drops its copy once uploaded (raycasting is the instanced mesh's)
  baked.setIndex(new THREE.BufferAttribute(all, 1).onUpload(function drop() { this.array = null; }));
  baked.boundingSphere = mesh.boundingSphere.clone();
  baked.boundingBox = mesh.boundingBox.clone();
  const materials = Array.isArray(source) ? source.map((m) => m.clone()) : source.clone();
  if (tinted) (Array.isArray(materials) ? materials : [materials]).forEach((m) => { m.vertexColors = true; });
  const drawn = new THREE.Mesh(baked, materials);
  drawn.name = `${mesh.name || 'axial'} (baked)`;
  drawn.castShadow = mesh.castShadow;
  drawn.receiveShadow = mesh.receiveShadow;
  drawn.raycast = () => {}; // the instanced mesh's raycast answers, with instanceId
  mesh.add(drawn);
  mesh._baked = { mesh: drawn, release, bent };
  mesh.setBendVisible(false);
  return drawn;
}


/** Go back to bending every frame (frees the baked geometry). */
export function unbake(mesh) {
  if (!mesh._baked) return mesh;
  const { mesh: drawn, release } = mesh._baked;
  mesh.remove(drawn);
  drawn.geometry.dispose();
  (Array.isArray(drawn.material) ? drawn.material : [drawn.material]).forEach((m) => m.dispose());
  release();
  mesh._baked = null;
  mesh.setBendVisible(true);
  return mesh;
}
