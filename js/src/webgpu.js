// webgpu.js -- axialdeform-three for three's WebGPURenderer (three/webgpu, three r184 or later: its
// WebGPU backend and its WebGL 2 fallback) and node materials:
//
//     import { AxialInstancedMesh, AxialGLTFPlugin } from 'axialdeform-three/webgpu';
//
// The same classes as 'axialdeform-three' (the record, the bounds, the wind, the tint, trees of
// several axes, a chosen frame, generated layers), but the bend is a node function on position and
// normal (glsl/axial.glsl as node functions, generated into glsl_nodes.js) set as the material's positionNode, so three's shadow
// passes bend too; classic materials are turned into their node twins as WebGPURenderer itself does.
// Bending on the GPU for bake and raycasting is a compute pass (WebGPU compute; transform feedback
// under the WebGL 2 backend, three's choice) running the same node functions, read back
// asynchronously (webgpu/mesh.js, webgpu/compute.js).  A generated layer's instances are made by a compute
// pass of glsl/generate.glsl as generated node functions (generate_nodes.js) (webgpu/generate.js: WebGPU backend).

import { AxialError, parseADP } from './core/adp.js';
import { AxialGLTFPluginBase, EXTENSION } from './core/gltf.js';
import { AxialInstancedMesh } from './webgpu/mesh.js';
import { AxialBrush } from './core/brush.js';

export { AxialError, parseADP, EXTENSION, AxialInstancedMesh, AxialBrush };
export * as nodes from './webgpu/nodes.js';
export * as generateNodes from './webgpu/generate_nodes.js';

/** GLTFLoader plugin (AXIALDEFORM_bend) making axialdeform-three/webgpu's AxialInstancedMesh (a node in the
 * generated form: one made from its recipe).  Imports no WebGL file of this module. */
export class AxialGLTFPlugin extends AxialGLTFPluginBase {
  constructor(parser, options = {}) {
    super(parser, options, AxialInstancedMesh);
  }
}
