// axialdeform-three: thousands of individually bent instances of one mesh in
// three.js -- axialdeform's axial deformation (docs/method.md) inside your own
// materials, lights, shadows and controls, under WebGLRenderer.  The product; the parts
// it is built from are on the sub-path 'axialdeform-three/helpers', the same classes for
// WebGPURenderer on 'axialdeform-three/webgpu'.
export { AxialError, parseADP } from './core/adp.js';
export { AxialInstancedMesh } from './webgl/mesh.js';
export { AxialGLTFPlugin } from './webgl/gltf.js';
export { EXTENSION } from './core/gltf.js';
export { AXIAL_GLSL, WIND_GLSL } from './webgl/glsl.js';
