// adp.js -- the binary parameter file (.adp, docs/parameter-files.md): parse,
// check (size, CRC-32, header fields), decode.  The checks and their order
// follow axialdeform.core.io.adp.read_binary_header / decode_binary.

import { RECORD, WIDTHS, MAX_AXES } from './record.js';

/** The error of every check in this package: a message naming the file, the field and what was expected. */
export class AxialError extends Error {
  constructor(message) {
    super(message);
    this.name = 'AxialError';
  }
}

const MAGIC = [0x89, 0x41, 0x44, 0x50, 0x0d, 0x0a, 0x1a, 0x0a];
/** Bytes of the header, before the numbers. */
export const HEADER_BYTES = 96;
/** Numbers per instance of each file version (one axis): 16; 19 (+ s tw tp); 22 (+ tr tg tb). */
export const NUMBERS_OF_VERSION = Object.freeze(Object.fromEntries(WIDTHS.map((w, level) => [level + 1, w])));
export { MAX_AXES };

let crcTable = null;

/** CRC-32 (zlib's polynomial) of a Uint8Array. */
export function crc32(bytes) {
  if (crcTable === null) {
    crcTable = new Uint32Array(256);
    for (let n = 0; n < 256; n++) {
      let c = n;
      for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
      crcTable[n] = c >>> 0;
    }
  }
  let crc = 0xffffffff;
  for (let i = 0; i < bytes.length; i++) crc = crcTable[(crc ^ bytes[i]) & 0xff] ^ (crc >>> 8);
  return (crc ^ 0xffffffff) >>> 0;
}

/** Bytes as Python writes them (b'\\x89ADP\\r\\n...'): the messages are the Python reader's, word for word. */
function pyBytes(bytes) {
  const named = { 9: '\\t', 10: '\\n', 13: '\\r', 39: "\\'", 92: '\\\\' };
  return `b'${Array.from(bytes, (b) => named[b] ?? (b >= 32 && b < 127 ? String.fromCharCode(b) : `\\x${b.toString(16).padStart(2, '0')}`)).join('')}'`;
}

/** Lower-case hex of a Uint8Array. */
export function hex(bytes) {
  return Array.from(bytes, (b) => b.toString(16).padStart(2, '0')).join('');
}

function toArrayBuffer(input) {
  if (input instanceof ArrayBuffer) return input;
  if (ArrayBuffer.isView(input)) return input.buffer.slice(input.byteOffset, input.byteOffset + input.byteLength);
  throw new AxialError(`parseADP: expected an ArrayBuffer or a typed array, found ${input === null ? 'null' : typeof input}`);
}

/**
 * Parse an .adp parameter file.
 *
 * Returns {name, version, encoding ('float32' | 'quantized'), count,
 * numbersPerInstance, axes (K), axis (-1 none recorded, 0/1/2 x/y/z, 3 a chosen
 * frame, 4 several axes), lo, length, fingerprint (hex, '' when none
 * recorded), frameDigest (hex), data (Float32Array, count x numbersPerInstance,
 * decoded), values and qtable (the stored numbers: float32, or uint16 and their
 * per-column [min..., step...] table)}.  Throws AxialError naming what is wrong
 * for a truncated, corrupt (CRC-32) or unknown file.
 */
export function parseADP(input, name = 'parameters') {
  const buffer = toArrayBuffer(input);
  const bytes = new Uint8Array(buffer);
  const view = new DataView(buffer);
  const fail = (what) => { throw new AxialError(`${name}: ${what}`); };
  // the checks, their order and their words are axialdeform.core.io.adp.read_binary_header's
  const head = bytes.subarray(0, MAGIC.length);
  if (head.some((b, i) => b !== MAGIC[i])) {
    fail(`magic: expected ${pyBytes(MAGIC)}, found ${pyBytes(head)}; not a binary parameter file (the text form uses .txt, .csv, .dat)`);
  }
  if (bytes.length < HEADER_BYTES + 4) fail(`truncated: ${bytes.length} bytes, expected at least ${HEADER_BYTES + 4} (header + checksum)`);
  const version = view.getUint16(8, true);
  if (!NUMBERS_OF_VERSION[version]) {
    fail(`version: expected ${Object.entries(NUMBERS_OF_VERSION).map(([v, w]) => `${v} (${w} numbers)`).join(', ')}, found ${version} (written by a newer axialdeform?)`);
  }
  const encoding = view.getUint16(10, true);
  if (encoding !== 0 && encoding !== 1) fail(`encoding: expected 0 (float32) or 1 (uint16-quantized), found ${encoding}`);
  const headerSize = view.getUint32(12, true);
  if (headerSize !== HEADER_BYTES) fail(`header size: expected ${HEADER_BYTES}, found ${headerSize}`);
  // several axes: K at offset 28 (0 in one-axis files), 10 more numbers per child axis
  const axes = Math.max(1, view.getUint32(28, true));
  if (axes > MAX_AXES) fail(`axes: expected 1 to ${MAX_AXES} axes, found ${axes}`);
  const fields = NUMBERS_OF_VERSION[version] + 10 * (axes - 1);
  const count64 = view.getBigUint64(16, true);
  const each = encoding === 1 ? 2 * fields : 4 * fields;
  const table = encoding === 1 ? 8 * fields : 0;
  const expected = BigInt(HEADER_BYTES + table + 4) + count64 * BigInt(each);
  if (BigInt(bytes.length) !== expected) {
    fail(`count: the header declares ${count64} instances (${expected} bytes), but the file has ${bytes.length} bytes` +
         (BigInt(bytes.length) < expected ? ' (truncated?)' : ''));
  }
  const count = Number(count64);
  const stored = view.getUint32(bytes.length - 4, true);
  const computed = crc32(bytes.subarray(0, bytes.length - 4));
  if (stored !== computed) {
    fail(`checksum: stored CRC-32 ${stored.toString(16).padStart(8, '0')}, computed ${computed.toString(16).padStart(8, '0')}; the file is corrupt`);
  }
  const axis = view.getInt8(24);
  if (axis < -1 || axis > 4) fail(`axis: expected -1, 0, 1, 2, 3 (a chosen frame) or 4 (several axes), found ${axis}`);
  if ((axis === 4) !== (axes > 1)) fail(`axis: expected 4 (several axes) exactly when the file has more than one axis, found ${axis} with ${axes}`);
  const lo = view.getFloat64(32, true);
  const length = view.getFloat64(40, true);
  const fingerprintBytes = bytes.slice(48, 80);
  const frameDigest = bytes.slice(80, 96); // a chosen frame's or a tree's digest (zero for x, y, z)
  let qtable = null;
  let values;
  if (encoding === 1) {
    qtable = new Float32Array(buffer.slice(HEADER_BYTES, HEADER_BYTES + table));
    values = new Uint16Array(buffer.slice(HEADER_BYTES + table, HEADER_BYTES + table + count * each));
  } else {
    values = new Float32Array(buffer.slice(HEADER_BYTES, HEADER_BYTES + count * each));
  }
  // the numbers as axialdeform.core.params.as_params checks them: finite (a quantized table may decode
  // to infinity), a scale > 0, a taper < 1, a tint in 0..1 -- the same bytes get the same answer
  const data = encoding === 0 ? values : dequantize(values, qtable, fields);
  checkNumbers(data, fields, axes, name);
  return {
    name, version, encoding: encoding === 1 ? 'quantized' : 'float32', count, numbersPerInstance: fields,
    fields, axes, axis, lo, length,
    fingerprint: fingerprintBytes.some((b) => b !== 0) ? hex(fingerprintBytes) : '',
    fingerprintBytes, frameDigest: hex(frameDigest), frameDigestBytes: frameDigest, values, qtable,
    /** Float32Array (count x numbersPerInstance): the numbers, decoded (min + q step where quantized). */
    data,
  };
}

const COLUMNS = RECORD.flatMap((f) => f.columns);

/** The name of column `col` of a record of `axes` axes (axialdeform.core.record.record_fields). */
export function fieldName(col, axes = 1) {
  const child = 10 * (axes - 1);
  if (col < 10) return COLUMNS[col];
  if (col < 10 + child) return `a${Math.floor((col - 10) / 10) + 1}.${COLUMNS[(col - 10) % 10]}`;
  return COLUMNS[col - child];
}

const show = (v) => (Number.isNaN(v) ? 'nan' : v === Infinity ? 'inf' : v === -Infinity ? '-inf' : String(Number(v.toPrecision(9))));

/** Throw an AxialError for the first number of `data` the record refuses, as Python's reader does. */
export function checkNumbers(data, fields, axes, name) {
  for (let i = 0; i < data.length; i++) {
    if (!Number.isFinite(data[i])) {
      throw new AxialError(`${name}: instance ${Math.floor(i / fields)}, field ${fieldName(i % fields, axes)}: expected a finite number, found ${show(data[i])}`);
    }
  }
  const L = recordLayout(fields, axes);
  const rules = [];
  if (L.scale !== null) rules.push([L.scale, (v) => v <= 0, 'a scale s > 0'], [L.taper, (v) => v >= 1, 'a taper tp < 1']);
  if (L.tint !== null) for (let c = 0; c < 3; c++) rules.push([L.tint + c, (v) => v < 0 || v > 1, 'a tint in 0..1 (linear RGB)']);
  for (const [col, bad, what] of rules) {
    for (let i = col; i < data.length; i += fields) {
      if (bad(data[i])) {
        throw new AxialError(`${name}: instance ${Math.floor(i / fields)}, field ${fieldName(col, axes)}: expected ${what}, found ${show(data[i])}`);
      }
    }
  }
}

/** value = min[c] + q * step[c] for every stored uint16 (the quantized encoding). */
export function dequantize(values, qtable, fields) {
  const out = new Float32Array(values.length);
  for (let i = 0; i < values.length; i++) {
    const c = i % fields;
    out[i] = qtable[c] + values[i] * qtable[fields + c];
  }
  return out;
}

const FIELD = Object.fromEntries(RECORD.map((f) => [f.name, f]));

/** The record's columns (docs/parameter-files.md, record.js): numbers per instance -> {axes, level,
 * offsets of axis j (10 numbers at 10 j), position, angles, scale, twist, taper, tint} (indices; null
 * where absent). */
export function recordLayout(numbersPerInstance, axes = 1) {
  const base = numbersPerInstance - 10 * (axes - 1), level = WIDTHS.indexOf(base);
  if (level < 0 || !Number.isInteger(axes) || axes < 1 || axes > MAX_AXES) {
    throw new AxialError(`record: expected ${WIDTHS.slice(0, -1).join(', ')} or ${WIDTHS.at(-1)} numbers an instance plus 10 per child axis, found ${numbersPerInstance} with ${axes} axes`);
  }
  const at = (name) => (FIELD[name].level <= level ? column(FIELD[name].start, axes) : null);
  return { axes, level, numbersPerInstance, base, position: at('position'), angles: at('rotation'),
    scale: at('scale'), twist: at('twist'), taper: at('taper'), tint: at('tint') };
}

/** Where column `start` of axis 0's record (record.js) lies in a record of `axes` axes: the child
 * axes' 10 (K - 1) offsets come after axis 0's ten. */
export function column(start, axes = 1) {
  return start < 10 ? start : start + 10 * (axes - 1);
}

/** Texels a row of the child axes' offsets texture (glsl/axial.glsl's AXIAL_AXES_ROW). */
export const AXES_ROW = 4095;

/** Rows of AXES_ROW texels that the child axes' offsets of `count` instances of `k` axes take. */
export function texelRows(count, k) {
  return Math.max(1, Math.ceil((count * (k - 1) * 3) / AXES_ROW));
}

/** Write the child axes' offsets of instances first .. first + count - 1 (decoded numbers, rows of
 * `fields`, K axes) into `texels` (RGBA32F, three texels a child axis: d1u d1v d2u d2v | d3u d3v
 * d4u d4v | d5u d5v 0 0, instance after instance, as glsl/axial.glsl's axial_child_offsets reads). */
export function childTexels(data, fields, k, first, count, texels) {
  for (let i = first; i < first + count; i++) {
    for (let j = 1; j < k; j++) {
      const at = ((i * (k - 1) + j - 1) * 3) * 4;
      for (let c = 0; c < 10; c++) texels[at + c] = data[i * fields + 10 * j + c];
    }
  }
  return texels;
}
