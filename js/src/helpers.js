// axialdeform-three/helpers: the parts the product (index.js) is built from -- the record's columns
// (record.js, generated from the Python library), the .adp parser's checks, the axis and bounds
// maths, the shader patch, the wind, the glTF plugin's steps, and a generated layer's brush -- for tools, tests and apps.
export { crc32, dequantize, recordLayout, column, childTexels, texelRows, hex, NUMBERS_OF_VERSION, HEADER_BYTES,
  MAX_AXES, AXES_ROW } from './adp.js';
export { RECORD, WIDTHS, ATTRIBUTES, WIND, WIND_UNIFORMS, FRAME_TOLERANCE, RECIPE, RECIPE_KINDS } from './record.js';
export { stillWindUniforms } from './wind.js';
export { alignedFrame, resolveAxis, instanceMatrices, bentRadii } from './bend.js';
export { injectBend } from './shader.js';
export { fromInstancedMesh, recordFromInstancedMesh, checkBendExtension } from './gltf.js';
export { TileGenerator, checkRecipe, recipeUniforms, tilesAround } from './generate.js';
export { RECIPE_FIELDS } from './glsl.js';
export { AxialBrush, MASK_SIZE } from './brush.js';
