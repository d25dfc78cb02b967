// axialdeform-three: thousands of individually bent instances of one mesh in
// three.js -- axialdeform's axial deformation (docs/method.md) inside your own
// materials, lights, shadows and controls.
export { AxialError, parseADP, crc32, dequantize, recordLayout, childTexels, texelRows, hex,
  NUMBERS_OF_VERSION, HEADER_BYTES, MAX_AXES, AXES_ROW } from './adp.js';
export { alignedFrame, resolveAxis, instanceMatrices, bentRadii } from './bend.js';
export { AxialInstancedMesh, injectBend } from './mesh.js';
export { AxialGLTFPlugin, EXTENSION, fromInstancedMesh, recordFromInstancedMesh } from './gltf.js';
export { AXIAL_GLSL, WIND_GLSL } from './glsl.js';
