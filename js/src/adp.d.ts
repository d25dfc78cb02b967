// Type declarations of axialdeform-three/adp: the .adp parameter file's parser and its checks (adp.js).
export { AxialError, parseADP } from './index.js';
export { crc32, hex, dequantize, recordLayout, column, texelRows, childTexels, NUMBERS_OF_VERSION, HEADER_BYTES, MAX_AXES,
  AXES_ROW } from './helpers.js';

/** The name of record column `col` (d1u, ..., px, ...; a tree's child axes numbered after axis 0's). */
export function fieldName(col: number, axes?: number): string;
/** Throw an AxialError for the first number of `data` the record refuses, as Python's reader does. */
export function checkNumbers(data: Float32Array, fields: number, axes: number, name: string): void;
