// core/raycast.js -- three's raycasting against a mesh's bent instances: the instances whose bounding
// sphere the ray meets are bent on the GPU (WebGL 2: webgl/raycast.js; WebGPU: webgpu/mesh.js's compute
// pass) and their triangles tested one by one.

import * as THREE from 'three';

const _sphere = new THREE.Sphere();

/** The instances whose bounding sphere (world) the ray meets. */
export function rayCandidates(mesh, raycaster) {
  if (mesh.count === 0) return [];
  if (mesh.boundingSphere === null) mesh.computeBoundingSphere();
  const sphere = new THREE.Sphere().copy(mesh.boundingSphere).applyMatrix4(mesh.matrixWorld);
  if (!raycaster.ray.intersectsSphere(sphere)) return [];
  const ids = [];
  for (let i = 0; i < mesh.count; i++) {
    if (raycaster.ray.intersectsSphere(mesh.getInstanceBoundingSphere(i, _sphere).applyMatrix4(mesh.matrixWorld))) ids.push(i);
  }
  return ids;
}

/** Intersect the ray with instances `ids` bent as `bent` (Float32Array: V xyz a vertex, `stride`
 * numbers a vertex, instance after instance, in the mesh's space); hits carry instanceId. */
export function intersectBent(mesh, raycaster, intersects, ids, bent, stride = 3) {
  const V = mesh.geometry.getAttribute('position').count;
  if (!mesh._rayMesh) {
    const g = new THREE.BufferGeometry();
    if (mesh.geometry.index) g.setIndex(mesh.geometry.index);
    for (const grp of mesh.geometry.groups) g.addGroup(grp.start, grp.count, grp.materialIndex);
    g.drawRange = mesh.geometry.drawRange;
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * V), 3));
    mesh._rayMesh = new THREE.Mesh(g, mesh.material);
  }
  const probe = mesh._rayMesh, found = [], attr = probe.geometry.getAttribute('position');
  probe.material = mesh.material;
  probe.matrixWorld.copy(mesh.matrixWorld); // the bent positions are placed already (the rigid part)
  ids.forEach((id, k) => {
    if (stride === 3) attr.array.set(bent.subarray(k * V * 3, (k + 1) * V * 3));
    else for (let v = 0; v < V; v++) for (let c = 0; c < 3; c++) attr.array[3 * v + c] = bent[(k * V + v) * stride + c];
    probe.geometry.boundingSphere = null;
    probe.geometry.boundingBox = null;
    found.length = 0;
    probe.raycast(raycaster, found);
    for (const hit of found) { hit.instanceId = id; hit.object = mesh; intersects.push(hit); }
  });
}
