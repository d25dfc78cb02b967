// axialdeform-three: thousands of individually bent instances of one mesh in
// three.js -- axialdeform's axial deformation (docs/method.md) inside your own
// materials, lights, shadows and controls.  The product; the parts it is built from
// are on the sub-path 'axialdeform-three/helpers'.
export { AxialError, parseADP } from './adp.js';
export { AxialInstancedMesh } from './mesh.js';
export { AxialGLTFPlugin, EXTENSION } from './gltf.js';
export { AxialGeneratedMesh } from './generate.js';
export { AXIAL_GLSL, WIND_GLSL } from './glsl.js';
