// webgl/bake.js -- bend a mesh's instances ONCE (feedback.js) and draw the result as plain geometry
// (core/baked.js) until they move again.

import * as THREE from 'three';
import { feedback, refuseWebGPU } from './feedback.js';
import { attachBake, unbake } from '../core/baked.js';

/**
 * Bend every instance ONCE on the GPU (WebGL 2 transform feedback, the same glsl/axial.glsl) and
 * draw the result as plain geometry from then on: for instances that do not move, the frames cost
 * what a baked mesh costs, while the file stays 40 bytes an instance.  The bent positions and
 * normals stay on the GPU (GLBufferAttributes of a child mesh, with the un-bent clones of the
 * materials; a tint becomes a colour a vertex); raycasting and the bounds stay the instanced mesh's.
 * setParams() (animation) and setWind() go back to bending every frame; call bake() again when
 * the instances rest.  Returns true when baked (false: no instances, a wind, an own shader).
 */
export function bake(mesh, renderer) {
  unbake(mesh);
  if (mesh.count === 0 || mesh._wind || mesh._ownShader) return false;
  refuseWebGPU(renderer, 'has no WebGL 2 transform feedback, which bake uses');
  const gl = renderer.getContext();
  if (typeof WebGL2RenderingContext === 'undefined' || !(gl instanceof WebGL2RenderingContext)) return false;
  const n = mesh.count, V = mesh.geometry.getAttribute('position').count;
  const tangent = mesh.geometry.getAttribute('tangent');
  const { outputs } = feedback(mesh, renderer, null, Boolean(tangent));
  renderer.resetState(); // three's cached GL state: we bound our own program, VAO and buffers
  attachBake(mesh, {
    position: new THREE.GLBufferAttribute(outputs[0], gl.FLOAT, 3, 4, n * V),
    normal: new THREE.GLBufferAttribute(outputs[1], gl.FLOAT, 3, 4, n * V),
    tangent: tangent ? new THREE.GLBufferAttribute(outputs[2], gl.FLOAT, 4, 4, n * V) : null,
  }, () => outputs.forEach((b) => gl.deleteBuffer(b)));
  return true;
}
