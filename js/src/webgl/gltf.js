// webgl/gltf.js -- AxialGLTFPlugin for WebGLRenderer: GLTFLoader reads the AXIALDEFORM_bend extension
// (core/gltf.js) and every instanced node that carries it becomes an AxialInstancedMesh (a generated node one
// made from its recipe) with the file's materials:
//     const loader = new GLTFLoader();
//     loader.register((parser) => new AxialGLTFPlugin(parser));

import { AxialGLTFPluginBase, fromInstancedMesh as fromInstanced } from '../core/gltf.js';
import { AxialInstancedMesh } from './mesh.js';

/** GLTFLoader plugin: EXT_mesh_gpu_instancing nodes with AXIALDEFORM_bend load bent. */
export class AxialGLTFPlugin extends AxialGLTFPluginBase {
  /** `options.maxSlots`: the most slots a generated node may hold (limits.js's MAX_SLOTS; a file asking
   * for more is refused in one line before anything is allocated). */
  constructor(parser, options = {}) {
    super(parser, options, AxialInstancedMesh);
  }
}

/** An AxialInstancedMesh (or `Mesh`) in place of GLTFLoader's InstancedMesh (same geometry, material, name, transform). */
export function fromInstancedMesh(mesh, ext, where = 'node', raw = null, Mesh = AxialInstancedMesh) {
  return fromInstanced(mesh, ext, where, raw, Mesh);
}
