// webgl/raycast.js -- raycasting under WebGLRenderer: the candidate instances (core/raycast.js) bent by
// one transform-feedback pass (feedback.js), read back, their triangles tested.

import { AxialError } from '../core/adp.js';
import { rayCandidates, intersectBent } from '../core/raycast.js';
import { feedback } from './feedback.js';

/**
 * three's raycasting, against each instance's bent triangles (intersections carry instanceId).
 * The instances whose bounding sphere the ray meets are bent on the GPU by the same shader code
 * (one transform-feedback pass, read back), so the mesh must have been drawn (or baked) once.
 */
export function raycast(mesh, raycaster, intersects) {
  const ids = rayCandidates(mesh, raycaster);
  if (!ids.length) return;
  if (!mesh._renderer) {
    throw new AxialError('raycast: the bend runs on the GPU; draw the mesh once (or bake it) before raycasting');
  }
  const V = mesh.geometry.getAttribute('position').count;
  const { gl, outputs } = feedback(mesh, mesh._renderer, ids, false);
  const bent = new Float32Array(ids.length * V * 3);
  gl.bindBuffer(gl.ARRAY_BUFFER, outputs[0]);
  gl.getBufferSubData(gl.ARRAY_BUFFER, 0, bent);
  gl.bindBuffer(gl.ARRAY_BUFFER, null);
  outputs.forEach((b) => gl.deleteBuffer(b));
  mesh._renderer.resetState();
  intersectBent(mesh, raycaster, intersects, ids, bent);
}
