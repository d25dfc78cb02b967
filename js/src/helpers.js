// axialdeform-three/helpers: the parts the product (index.js) is built from -- the record's columns
// (core/record.js, generated from the Python library), the .adp parser's checks, the axis and bounds
// maths, the shader patch, the wind, the glTF plugin's steps, and a generated layer's brush -- for tools, tests and apps.
export { crc32, dequantize, recordLayout, column, childTexels, texelRows, hex, NUMBERS_OF_VERSION, HEADER_BYTES,
  MAX_AXES, AXES_ROW } from './core/adp.js';
export { RECORD, WIDTHS, ATTRIBUTES, WIND, WIND_UNIFORMS, FRAME_TOLERANCE, RECIPE, RECIPE_KINDS, RECIPE_FIELDS } from './core/record.js';
export { stillWindUniforms } from './core/wind.js';
export { alignedFrame, resolveAxis, instanceMatrices, bentRadii } from './core/bend.js';
export { injectBend } from './webgl/shader.js';
export { recordFromInstancedMesh, checkBendExtension } from './core/gltf.js';
export { fromInstancedMesh } from './webgl/gltf.js';
export { checkRecipe, recipeUniforms, tilesAround } from './core/generate.js';
export { TileGenerator } from './webgl/tiles.js';
export { AxialBrush, MASK_SIZE } from './core/brush.js';
export { AxialMeshCore } from './core/mesh.js';
