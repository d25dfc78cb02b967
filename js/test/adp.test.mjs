// node --test: the .adp parser and the CPU side of the bend against what the
// Python library makes of the same files (fixtures: tools/make_js_fixtures.py).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { parseADP, AxialError, crc32, recordLayout, childTexels, texelRows, AXES_ROW } from '../src/core/adp.js';
import { resolveAxis, instanceMatrices, bentRadii } from '../src/core/bend.js';

const dir = new URL('./fixtures/', import.meta.url);
const expected = JSON.parse(readFileSync(new URL('expected.json', dir), 'utf8'));
const load = (name) => readFileSync(new URL(`${name}.adp`, dir));
const names = Object.keys(expected);

test('the fixtures cover both encodings, versions 1-3, a chosen frame and several axes', () => {
  const e = Object.values(expected);
  assert.deepEqual(new Set(e.map((x) => x.encoding)), new Set(['float32', 'quantized']));
  for (const n of [16, 19, 22]) assert.ok(e.some((x) => x.numbersPerInstance === n), `${n} numbers`);
  assert.ok(e.some((x) => x.axes && x.axes.count > 1), 'several axes');
  assert.ok(e.some((x) => x.axis.index === -1), 'a chosen frame');
});

for (const name of names) {
  const want = expected[name];
  test(`parseADP ${name}: header and decoded numbers as Python reads them`, () => {
    const p = parseADP(load(name), name);
    assert.equal(p.count, want.count);
    assert.equal(p.numbersPerInstance, want.numbersPerInstance);
    assert.equal(p.encoding, want.encoding);
    assert.equal(p.axes, want.axes ? want.axes.count : 1);
    assert.equal(p.fingerprint, want.fingerprint);
    assert.equal(p.data.length, want.count * want.numbersPerInstance);
    want.data.flat().forEach((v, i) => assert.ok(Math.abs(p.data[i] - v) <= 1e-6 * Math.max(1, Math.abs(v)), `${name} number ${i}: ${p.data[i]} vs ${v}`));
    if (want.axes) assert.equal(p.axis, 4);
    else if (want.axis.index === -1) assert.equal(p.axis, 3);
    else assert.equal(p.axis, want.axis.index);
    assert.ok(Math.abs(p.length - want.axis.length) < 1e-9 * want.axis.length);
  });

  test(`placement ${name}: instanceMatrices = T(p) R S(s) as the Python library places them`, () => {
    const p = parseADP(load(name), name);
    const mats = instanceMatrices(p.data, recordLayout(p.numbersPerInstance, p.axes), p.count, new Float32Array(16 * p.count));
    want.matrices.flat().forEach((v, k) => assert.ok(Math.abs(mats[k] - v) < 1e-5 * Math.max(1, Math.abs(v)),
      `${name} instance ${Math.floor(k / 16)} element ${k % 16}: ${mats[k]} vs ${v}`));
  });

  test(`bounds ${name}: every vertex axialdeform.deform bends lies in its instance's placed sphere`, () => {
    const p = parseADP(load(name), name);
    const positions = Float32Array.from(want.positions.flat());
    const axis = resolveAxis({ axis: want.axis, axes: want.axes || null }, p, positions);
    const layout = recordLayout(p.numbersPerInstance, p.axes);
    const { center, radius } = bentRadii(positions, axis, p.data, layout, p.count);
    const mats = instanceMatrices(p.data, layout, p.count, new Float32Array(16 * p.count));
    for (let i = 0; i < p.count; i++) {
      const m = mats.subarray(16 * i, 16 * i + 16), s = Math.hypot(m[0], m[1], m[2]);
      const c = [0, 1, 2].map((r) => m[r] * center[0] + m[4 + r] * center[1] + m[8 + r] * center[2] + m[12 + r]);
      for (const w of want.world[i]) {
        const d = Math.hypot(w[0] - c[0], w[1] - c[1], w[2] - c[2]);
        assert.ok(d <= radius[i] * s * (1 + 1e-6), `${name} instance ${i}: a bent vertex at ${d} outside ${radius[i] * s}`);
      }
    }
  });
}

test('childTexels: the child axes\' offsets of a tree, three RGBA texels an axis', () => {
  const p = parseADP(load('tree'), 'tree');
  const rows = texelRows(p.count, p.axes);
  const texels = childTexels(p.data, p.fields, p.axes, 0, p.count, new Float32Array(rows * AXES_ROW * 4));
  assert.equal(rows, 1);
  // child axis 1 of instance 0: the record's columns 10..19, in three texels (d5 in the third's xy)
  for (let c = 0; c < 10; c++) assert.equal(texels[c], p.data[10 + c]);
  assert.equal(texels[10], 0);
  // instance 1's child axis 2: texels from ((1 * 9) + 1) * 3
  for (let c = 0; c < 10; c++) assert.equal(texels[((1 * 9) + 1) * 12 + c], p.data[p.fields + 20 + c]);
});
function corrupt(name, edit) {
  const b = new Uint8Array(load(name));
  edit(b, new DataView(b.buffer));
  return b.buffer;
}
const fixCrc = (b, v) => v.setUint32(b.length - 4, crc32(b.subarray(0, b.length - 4)), true);

const bad = {
  'truncated': [() => load('stone16').subarray(0, 50), /stone16: truncated: 50 bytes/],
  'cut short': [() => load('stone16').subarray(0, 200), /count: the header declares 3 instances \(292 bytes\), but the file has 200 bytes \(truncated\?\)/],
  'too long': [() => Buffer.concat([load('stone16'), Buffer.alloc(4)]), /count: the header declares 3 instances \(292 bytes\), but the file has 296 bytes$/],
  'magic': [() => corrupt('stone16', (b) => { b[1] = 0x42; }), /magic: expected b'\\x89ADP\\r\\n\\x1a\\n', found b'\\x89BDP\\r\\n\\x1a\\n'; not a binary parameter file/],
  'checksum': [() => corrupt('stone16', (b) => { b[120] ^= 1; }), /checksum: stored CRC-32 [0-9a-f]{8}, computed [0-9a-f]{8}; the file is corrupt/],
  'version': [() => corrupt('stone16', (b, v) => { v.setUint16(8, 9, true); fixCrc(b, v); }), /version: expected 1 \(16 numbers\), 2 \(19 numbers\), 3 \(22 numbers\), found 9/],
  'encoding': [() => corrupt('stone16', (b, v) => { v.setUint16(10, 7, true); fixCrc(b, v); }), /encoding: expected 0 \(float32\) or 1 \(uint16-quantized\), found 7/],
  'axes': [() => corrupt('stone16', (b, v) => { v.setUint32(28, 99, true); fixCrc(b, v); }), /axes: expected 1 to 64 axes, found 99/],
  'axis': [() => corrupt('stone16', (b, v) => { v.setInt8(24, 9); fixCrc(b, v); }), /axis: expected -1, 0, 1, 2, 3/],
  'not finite': [() => corrupt('stone16', (b, v) => { v.setFloat32(96, NaN, true); fixCrc(b, v); }), /instance 0, field d1u: expected a finite number, found nan/],
};
for (const [what, [make, message]] of Object.entries(bad)) {
  test(`parseADP refuses a file: ${what}`, () => {
    assert.throws(() => parseADP(make(), what === 'truncated' || what === 'cut short' ? 'stone16' : 'f.adp'),
      (err) => err instanceof AxialError && err instanceof Error && message.test(err.message));
  });
}

test('parseADP takes an ArrayBuffer, a typed array or a Node Buffer, and refuses other things', () => {
  const buf = load('stone16');
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  assert.equal(parseADP(ab).count, 3);
  assert.equal(parseADP(new Uint8Array(ab)).count, 3);
  assert.throws(() => parseADP('text'), /expected an ArrayBuffer or a typed array/);
});

test('recordLayout: columns of 16, 19, 22 numbers and of several axes', () => {
  assert.deepEqual([recordLayout(16).position, recordLayout(16).angles, recordLayout(16).scale], [10, 13, null]);
  assert.deepEqual([recordLayout(22).scale, recordLayout(22).twist, recordLayout(22).tint], [16, 17, 19]);
  const t = recordLayout(16 + 90, 10);
  assert.deepEqual([t.position, t.angles], [100, 103]);
  assert.throws(() => recordLayout(17), /expected 16, 19 or 22 numbers/);
});

test('the same bytes get the same answer as Python: the shared corpus js/test/cases/adp', () => {
  const dir = new URL('./cases/adp/', import.meta.url);
  const verdicts = JSON.parse(readFileSync(new URL('verdicts.json', dir), 'utf8'));
  const differ = [];
  for (const [name, want] of Object.entries(verdicts)) {
    let got = 'ok';
    try {
      parseADP(readFileSync(new URL(name, dir)), name);
    } catch (e) {
      if (!(e instanceof AxialError)) throw e;
      got = e.message;
    }
    if (got !== want) differ.push(`${name}: Python: ${want} | JavaScript: ${got}`);
  }
  assert.deepEqual(differ, []);
  assert.ok(Object.values(verdicts).filter((v) => v !== 'ok').length > 30); // the corpus really refuses
});
