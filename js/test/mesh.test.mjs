// node --test: AxialInstancedMesh and the plugin's record without a GL context (three from
// js/node_modules, a devDependency): what they build from a record, and what they refuse.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import * as THREE from 'three';
import { parseADP, AxialInstancedMesh, AxialError, AxialGLTFPlugin } from '../src/index.js';
import { uses } from '../src/core/variant.js';
import { recordLayout } from '../src/core/adp.js';
import { recordFromInstancedMesh, fromInstancedMesh, injectBend, checkBendExtension } from '../src/helpers.js';

const dir = new URL('./fixtures/', import.meta.url);
const expected = JSON.parse(readFileSync(new URL('expected.json', dir), 'utf8'));
const record = (name) => parseADP(readFileSync(new URL(`${name}.adp`, dir)), name);

function geometryOf(name) { // the fixture's vertices as a point soup with normals
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(expected[name].positions.flat()), 3));
  g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(3 * expected[name].positions.length).fill(0.5), 3));
  if (expected[name].vertexAxis) g.setAttribute('_axial_axis', new THREE.BufferAttribute(Float32Array.from(expected[name].vertexAxis), 1));
  return g;
}
const spec = (name) => ({ axis: expected[name].axis, axes: expected[name].axes || null });

test('the mesh places every instance as Python does and its bounds hold every vertex Python bends', () => {
  for (const name of Object.keys(expected)) {
    const mesh = new AxialInstancedMesh(geometryOf(name), new THREE.MeshStandardMaterial(), record(name), { axis: spec(name) });
    assert.equal(mesh.count, expected[name].count);
    expected[name].matrices.flat().forEach((v, k) => assert.ok(Math.abs(mesh.instanceMatrix.array[k] - v) < 1e-5 * Math.max(1, Math.abs(v))));
    const v = new THREE.Vector3(), box = new THREE.Box3();
    for (let i = 0; i < mesh.count; i++) {
      for (const w of expected[name].world[i]) {
        v.set(...w);
        assert.ok(mesh.boundingSphere.containsPoint(v), `${name}: the bounding sphere misses a bent vertex`);
        assert.ok(mesh.getInstanceBoundingSphere(i).containsPoint(v), `${name}: instance ${i}'s sphere`);
        assert.ok(mesh.getInstanceBoundingBox(i, box).expandByScalar(1e-6).containsPoint(v), `${name}: instance ${i}'s box`);
      }
    }
    mesh.dispose();
  }
});

test('setParams writes in place and refuses what does not fit', () => {
  const r = record('stone16');
  const mesh = new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), r, { capacity: 5 });
  const d12 = mesh.geometry.getAttribute('axialD12');
  const before = d12.array;
  const row = r.data.slice(0, 16);
  row[0] = 0.25;
  mesh.setParams(row, { first: 4 });
  assert.equal(mesh.count, 5);
  assert.equal(d12.array, before); // no reallocation
  assert.equal(d12.array[16], 0.25);
  assert.throws(() => mesh.setParams(row, { first: 5 }), (e) => e instanceof AxialError && /capacity of 5/.test(e.message));
  assert.throws(() => mesh.setParams(record('stone19')), /19 numbers an instance, but this mesh was made for 16/);
  const bad = row.slice(); bad[3] = NaN;
  assert.throws(() => mesh.setParams(bad), /number 3: not finite/);
});

test('setParams replaces the instances (the count may shrink); updateParams updates a range and its bounds only', () => {
  const r = record('stone16');
  const mesh = new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), r, { capacity: 5 });
  assert.equal(mesh.count, r.count);
  mesh.setParams(r.data.subarray(0, 16));
  assert.equal(mesh.count, 1); // replaced: one instance drawn, the others gone
  const one = mesh.boundingSphere.clone();
  mesh.setParams(r);
  assert.equal(mesh.count, r.count);
  assert.ok(mesh.boundingSphere.containsPoint(one.center));
  // updateParams: only the range's bounds are computed (the other instances' are not asked for)
  const far = r.data.slice(0, 16);
  far[11] += 50; // instance 4 far away along y
  const asked = [];
  const bound = mesh.getInstanceBoundingBox.bind(mesh);
  mesh.getInstanceBoundingBox = (i, target) => { asked.push(i); return bound(i, target); };
  mesh.updateParams(far, 4);
  assert.deepEqual(asked, [4]);
  assert.equal(mesh.count, 5);
  const placed = mesh.getInstanceBoundingSphere(4);
  assert.ok(mesh.boundingSphere.center.distanceTo(placed.center) + placed.radius <= mesh.boundingSphere.radius + 1e-5);
  assert.ok(mesh.boundingBox.containsBox(mesh.getInstanceBoundingBox(4)));
  assert.throws(() => mesh.updateParams(far, 5), /capacity of 5/);
});

test("a user's onBeforeRender runs beside the mesh's own, which keeps the renderer for raycasting", () => {
  const mesh = new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), record('stone16'));
  const calls = [];
  mesh.onBeforeRender = (renderer, scene) => calls.push([renderer, scene]);
  const renderer = { fake: true };
  mesh.onBeforeRender(renderer, 'scene');
  assert.deepEqual(calls, [[renderer, 'scene']]);
  assert.equal(mesh._renderer, renderer);
});

test('the mesh refuses a geometry without normals, a frame it was not given, a tree without or with bad vertex axes', () => {
  const g = geometryOf('stone16');
  g.deleteAttribute('normal');
  assert.throws(() => new AxialInstancedMesh(g, new THREE.MeshBasicMaterial(), record('stone16')), /position and normal/);
  assert.throws(() => new AxialInstancedMesh(geometryOf('framed'), new THREE.MeshBasicMaterial(), record('framed')),
    /chosen axis frame.*pass \{axis\}/);
  const tree = geometryOf('tree');
  tree.deleteAttribute('_axial_axis');
  assert.throws(() => new AxialInstancedMesh(tree, new THREE.MeshBasicMaterial(), record('tree'), { axis: spec('tree') }),
    /each vertex's axis/);
  assert.throws(() => new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), record('tree'), { axis: spec('stone16') }),
    /10 axes an instance, but the mesh has 1/);
  // each vertex's code: an axis, or b + 64 b1 + 4096 q for a vertex blending two chains (docs/method.md)
  const codes = Float32Array.from(expected.tree.vertexAxis);
  codes[0] = 3 + 64 * 7 + 4096 * 1000; // a blend of axes 3 and 7: taken
  const blended = geometryOf('tree');
  blended.setAttribute('_axial_axis', new THREE.BufferAttribute(codes, 1));
  new AxialInstancedMesh(blended, new THREE.MeshBasicMaterial(), record('tree'), { axis: spec('tree') }).dispose();
  for (const [bad, why] of [[3 + 64 * 12, /vertex 0: expected an axis of 0\.\.9/], [10, /found 10/], [2.5, /found 2\.5/],
    [2 ** 23, /below 2\^23/]]) {
    codes[0] = bad;
    const g2 = geometryOf('tree');
    g2.setAttribute('_axial_axis', new THREE.BufferAttribute(codes, 1));
    assert.throws(() => new AxialInstancedMesh(g2, new THREE.MeshBasicMaterial(), record('tree'), { axis: spec('tree') }), why);
  }
});

test('the plugin reads the record back from GLTFLoader\'s instanced mesh, and refuses a broken extension', () => {
  const r = record('stone19');
  const n = r.count, f = r.numbersPerInstance, g = geometryOf('stone19');
  const inst = new THREE.InstancedMesh(g, new THREE.MeshBasicMaterial(), n);
  const cols = (first, size) => new THREE.BufferAttribute(Float32Array.from({ length: n * size }, (_, k) => r.data[Math.floor(k / size) * f + first + (k % size)]), size);
  g.setAttribute('_AXIAL_D12', cols(0, 4)); g.setAttribute('_AXIAL_D34', cols(4, 4)); g.setAttribute('_AXIAL_D5', cols(8, 2));
  g.setAttribute('_AXIAL_ANGLES', cols(13, 3)); g.setAttribute('_AXIAL_TWIST_TAPER', cols(17, 2));
  const m = new THREE.Matrix4(), q = new THREE.Quaternion(), e = new THREE.Euler();
  for (let i = 0; i < n; i++) {
    e.set(r.data[i * f + 13], r.data[i * f + 14], r.data[i * f + 15], 'ZYX'); // R = Rz Ry Rx
    const s = r.data[i * f + 16];
    inst.setMatrixAt(i, m.compose(new THREE.Vector3(...r.data.slice(i * f + 10, i * f + 13)), q.setFromEuler(e), new THREE.Vector3(s, s, s)));
  }
  const ext = { numbersPerInstance: f, axis: expected.stone19.axis };
  const back = recordFromInstancedMesh(inst, ext);
  for (let k = 0; k < n * f; k++) assert.ok(Math.abs(back.data[k] - r.data[k]) < 1e-5, `number ${k % f} of ${Math.floor(k / f)}`);
  const bent = fromInstancedMesh(inst, ext);
  assert.ok(bent.isAxialInstancedMesh && bent.count === n);
  assert.throws(() => fromInstancedMesh(inst, { numbersPerInstance: f }, 'node 0 (stones)'), /node 0 \(stones\): AXIALDEFORM_bend: axis: expected an object/);
  // a file with ROTATION alone (what the plugin passes: the file's TRANSLATION and SCALE): the same rotations
  const angles = g.getAttribute('_AXIAL_ANGLES');
  g.deleteAttribute('_AXIAL_ANGLES');
  const raw = { TRANSLATION: cols(10, 3), SCALE: new THREE.BufferAttribute(Float32Array.from({ length: 3 * n }, (_, k) => r.data[Math.floor(k / 3) * f + 16]), 3) };
  const fromQ = recordFromInstancedMesh(inst, ext, 'node 0', raw);
  const R = (d, i) => new THREE.Matrix4().makeRotationFromEuler(new THREE.Euler(d[i * f + 13], d[i * f + 14], d[i * f + 15], 'ZYX')).elements;
  for (let i = 0; i < n; i++) R(fromQ.data, i).forEach((v, k) => assert.ok(Math.abs(v - R(r.data, i)[k]) < 1e-5, `instance ${i}`));
  g.setAttribute('_AXIAL_ANGLES', angles);
  g.deleteAttribute('_AXIAL_D34');
  assert.throws(() => recordFromInstancedMesh(inst, ext, 'node 3'), /node 3: AXIALDEFORM_bend needs the instance attributes _AXIAL_D34/);
});

test('injectBend replaces three\'s begin chunks and refuses a shader without them', () => {
  const vs = 'void main() {\n#include <beginnormal_vertex>\n#include <begin_vertex>\n}';
  const out = injectBend(vs);
  assert.match(out, /vec3 transformed = axialV;/);
  assert.match(out, /vec3 objectNormal = axialN;/);
  assert.match(out, /void axial_bend\(/);
  assert.throws(() => injectBend('void main() { gl_Position = vec4(0.0); }', 'MyMaterial'), /MyMaterial: its vertex shader has no #include <begin_vertex>/);
});

test('the axis a base mesh GLB records in extras.axialdeform (userData) is enough: a frame, a tree', () => {
  // what encode_base_mesh writes into the node's extras (index -1 with a frame; a tree's axes)
  const framed = expected.framed.axis;
  const userFramed = { axis: { index: -1, name: 'frame', lo: framed.lo, length: framed.length, frame: framed.frame } };
  const a = new AxialInstancedMesh(geometryOf('framed'), new THREE.MeshBasicMaterial(), record('framed'), { axis: userFramed });
  assert.deepEqual(a.axis.center.map((c) => Math.round(c * 1e4)), framed.center.map((c) => Math.round(c * 1e4)));
  const t = expected.tree;
  const userTree = { axis: { index: t.axis.index, name: 'y', lo: t.axis.lo, length: t.axis.length },
    axes: { count: t.axes.count, names: [], parents: t.axes.parents, frames: t.axes.frames, lo: t.axes.lo, length: t.axes.length } };
  const b = new AxialInstancedMesh(geometryOf('tree'), new THREE.MeshBasicMaterial(), record('tree'), { axis: userTree });
  assert.equal(b.axis.axes.count, 10);
});

test('the plugin refuses every broken extension of the shared corpus (js/test/cases/bend-cases.json), naming the field', () => {
  const { cases } = JSON.parse(readFileSync(new URL('./cases/bend-cases.json', import.meta.url), 'utf8'));
  const valid = { numbersPerInstance: 16, axis: { frame: expected.stone16.axis.frame, lo: expected.stone16.axis.lo,
    length: expected.stone16.axis.length, center: expected.stone16.axis.center } };
  assert.ok(checkBendExtension(structuredClone(valid), 'node 0'));
  for (const c of cases) {
    const ext = structuredClone(valid);
    let at = ext;
    for (const key of c.path.slice(0, -1)) at = at[key];
    if (c.delete) delete at[c.path.at(-1)]; else at[c.path.at(-1)] = c.value;
    assert.throws(() => checkBendExtension(ext, 'node 0'), (e) => e instanceof AxialError &&
      e.message.startsWith('node 0: AXIALDEFORM_bend: ') && e.message.includes(c.expect), JSON.stringify(c));
  }
  // a tree's rules: parents before their children, at most 64 axes, the numbers matching the axes
  const tree = { ...structuredClone(valid), numbersPerInstance: 36,
    axes: { count: 3, parents: [-1, 2, 1], frames: [valid.axis.frame, valid.axis.frame, valid.axis.frame], lo: [0, 0, 0], length: [1, 1, 1] } };
  assert.throws(() => checkBendExtension(tree, 'n'), /axes: parents: expected -1 for axis 0/);
  tree.axes.parents = [-1, 0, 1];
  assert.equal(checkBendExtension(tree, 'n'), tree);
  assert.throws(() => checkBendExtension({ ...tree, axes: { ...tree.axes, count: 1e6 } }, 'n'), /axes count: expected 2 to 64 axes, found 1000000/);
  assert.throws(() => checkBendExtension({ ...tree, numbersPerInstance: 16 }, 'n'), /numbersPerInstance/);
});

test('the plugin checks the extension and its instance accessors before GLTFLoader reads them (beforeRoot)', () => {
  const valid = { numbersPerInstance: 16, axis: { frame: expected.stone16.axis.frame, lo: expected.stone16.axis.lo,
    length: expected.stone16.axis.length, center: expected.stone16.axis.center } };
  const types = { TRANSLATION: 'VEC3', _AXIAL_D12: 'VEC4', _AXIAL_D34: 'VEC4', _AXIAL_D5: 'VEC2', _AXIAL_ANGLES: 'VEC3' };
  const names = Object.keys(types);
  // one accessor an attribute (in this order), each in its own 1 000-byte view of one buffer
  const file = (attrs, counts, ext = valid, change = () => {}) => {
    const json = {
      buffers: [{ byteLength: 1000 * names.length }],
      bufferViews: names.map((_, k) => ({ buffer: 0, byteOffset: 1000 * k, byteLength: 1000 })),
      accessors: counts.map((count, k) => ({ count, type: types[names[k]] || 'VEC4', componentType: 5126, bufferView: k })),
      nodes: [{ name: 'stones', mesh: 0, extensions: { EXT_mesh_gpu_instancing: { attributes: attrs }, AXIALDEFORM_bend: ext } }] };
    change(json);
    return { json };
  };
  const all = Object.fromEntries(names.map((name, k) => [name, k]));
  const run = (parser) => new AxialGLTFPlugin(parser).beforeRoot();
  assert.equal(run(file(all, [5, 5, 5, 5, 5])), null);
  assert.throws(() => run(file({ ...all, _AXIAL_D12: 7 }, [5, 5, 5, 5, 5])), /node 0 \(stones\): EXT_mesh_gpu_instancing attributes _AXIAL_D12: expected an accessor index 0..4, found 7/);
  assert.throws(() => run(file(all, [5, -2, 5, 5, 5])), /_AXIAL_D12: accessor 1 count: expected a whole number/);
  assert.throws(() => run(file(all, [5, 2 ** 33, 5, 5, 5])), /accessor 1 count: expected a whole number 0..2147483647, found 8589934592/);
  assert.throws(() => run(file(all, [5, 6, 5, 5, 5])), /different counts \(5 and 6\)/);
  assert.throws(() => run(file({ TRANSLATION: 0 }, [5], { ...valid, axis: { ...valid.axis, frame: [[1, 0], [0, 1]] } })), /node 0 \(stones\): AXIALDEFORM_bend: axis frame: expected 3 rows/);
  const many = Object.fromEntries(Array.from({ length: 300 }, (_, k) => [`_AXIAL_A${k}_D12`, 0]));
  assert.throws(() => run(file(many, [5])), /300 of them; expected at most 64 axes' worth/);
  // the accessors themselves, as Python's reader takes them (what three would throw a TypeError or RangeError on)
  const bad = (change) => () => run(file(all, [5, 5, 5, 5, 5], valid, change));
  assert.throws(bad((j) => { j.accessors[1].bufferView = 99; }), /_AXIAL_D12: accessor 1 bufferView: expected 0..4, found 99/);
  assert.throws(bad((j) => { delete j.accessors[1].bufferView; }), /_AXIAL_D12: unsupported accessor/);
  assert.throws(bad((j) => { j.accessors[1].byteOffset = 3; }), /accessor 1 byteOffset: expected a multiple of 4/);
  assert.throws(bad((j) => { j.accessors[1].byteOffset = 2 ** 31; }), /accessor 1 runs past its bufferView/);
  assert.throws(bad((j) => { j.accessors[1].type = 'SCALAR'; }), /_AXIAL_D12: expected VEC4, found "SCALAR"/);
  assert.throws(bad((j) => { j.accessors[1].componentType = 0; }), /_AXIAL_D12: unsupported accessor/);
  // the attributes the numbers per instance need, and no more than they hold
  assert.throws(() => run(file({ TRANSLATION: 0, _AXIAL_D12: 1, _AXIAL_D34: 2, _AXIAL_D5: 3 }, [5, 5, 5, 5])), /needs the instance attributes _AXIAL_ANGLES/);
  assert.throws(() => run(file(all, [5, 5, 5, 5, 5], { ...valid, numbersPerInstance: 19 })), /numbersPerInstance: 19, but the instance attributes hold 16/);
});

test('never a silent unbent picture: node materials and WebGPURenderer are refused in words', () => {
  // what three/webgpu sets on its renderer and its node materials (isWebGPURenderer, isNodeMaterial)
  const node = Object.assign(new THREE.MeshStandardMaterial(), { isNodeMaterial: true, type: 'MeshStandardNodeMaterial' });
  assert.throws(() => new AxialInstancedMesh(geometryOf('stone16'), node, record('stone16'), { axis: spec('stone16') }),
    (e) => e instanceof AxialError && /MeshStandardNodeMaterial is a node material .*onBeforeCompile.*unbent.*WebGLRenderer/.test(e.message));
  const mesh = new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshStandardMaterial(), record('stone16'), { axis: spec('stone16') });
  const webgpu = { isWebGPURenderer: true, getContext: () => null };
  assert.throws(() => mesh.onBeforeRender(webgpu, new THREE.Scene(), new THREE.PerspectiveCamera()),
    (e) => e instanceof AxialError && /WebGPURenderer .*unbent.*WebGLRenderer/.test(e.message));
  assert.throws(() => mesh.onBeforeRender(webgpu), /WebGPURenderer/, 'every frame, not once: the picture never draws unbent');
  assert.throws(() => mesh.bake(webgpu), /WebGPURenderer .*has no WebGL 2 transform feedback, which bake uses.*WebGLRenderer/);
  let seen = null;
  mesh.onBeforeRender = (r) => { seen = r; }; // a user's own hook still runs under WebGLRenderer
  const webgl = { isWebGLRenderer: true };
  mesh.onBeforeRender(webgl);
  assert.equal(seen, webgl);
  mesh.dispose();
});

test('a generated layer is the same mesh made from {generate: recipe}: its recipe, room and refusals', async () => {
  const { AxialBrush } = await import('../src/helpers.js');
  const recipe = { rate: 1, tile: 8, reach: 20, tint: 0.1 };
  const mesh = new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), { generate: recipe });
  assert.equal(mesh.constructor, AxialInstancedMesh);
  assert.equal(mesh.recipe.rate, 1);
  assert.equal(mesh.recipe.min_distance, 0); // the defaults filled in
  assert.equal(mesh.layout.numbersPerInstance, 22); // a tint: the tinted record
  assert.equal(mesh.capacity, 36 * 64); // the most tiles within reach (6 x 6) of 8 x 8 cells
  assert.equal(mesh.count, 0);
  assert.deepEqual(Array.from(mesh.records()), []); // nothing made before update
  assert.equal(mesh.defines.AXIAL_POSITION_IDS, '1');
  assert.throws(() => mesh.setParams(new Float32Array(22)), (e) => e instanceof AxialError && /made from its recipe/.test(e.message));
  assert.throws(() => mesh.updateParams(new Float32Array(22), 0), /setParams|updateParams/);
  assert.throws(() => mesh.setInstanceCulling({ isWebGLRenderer: true, capabilities: { isWebGL2: true } }), /generated layer/);
  assert.throws(() => new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), { generate: { rate: -1, tile: 8 } }),
    (e) => e instanceof AxialError && /rate/.test(e.message));
  assert.throws(() => new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(),
    { generate: { rate: 1, tile: 8, clump_cells: 3, clump_radius: 2, clump_core: 0.3, clump_core_radius: 2.5 } }),
  (e) => e instanceof AxialError && e.message.includes('clump_core_radius: expected at most clump_radius, 2 (the core lies within the clump), found 2.5'));
  const brush = new AxialBrush(mesh, { area: [0, 0, 10, 10] });
  assert.equal(brush.mesh, mesh);
  mesh.dispose();
  mesh.dispose(); // safe twice
  // a mesh of records is no generated layer: its records are its own, update and the brush refused
  const plain = new AxialInstancedMesh(geometryOf('stone16'), new THREE.MeshBasicMaterial(), record('stone16'));
  assert.equal(plain.recipe, null);
  assert.deepEqual(Array.from(plain.records()), Array.from(record('stone16').data));
  assert.throws(() => plain.update(null, { x: 0, z: 0 }), (e) => e instanceof AxialError && /not a generated layer/.test(e.message));
  assert.throws(() => new AxialBrush(plain, { area: [0, 0, 10, 10] }), /expected a generated layer/);
});

test('the shader variant leaves out what no instance uses: the turn of 16-number records, the bend of unbent ones', () => {
  const f = 16, n = 5, data = new Float32Array(f * n);
  for (let i = 0; i < n; i++) data[i * f + 10] = i; // placed along x, no offset
  const g = new THREE.BoxGeometry(1, 3, 1);
  const rec = { count: n, numbersPerInstance: f, data, axis: 1, lo: -1.5, length: 3 };
  const mesh = new AxialInstancedMesh(g, new THREE.MeshStandardMaterial(), rec);
  const flags = () => ['AXIAL_NO_TURN', 'AXIAL_NO_BEND'].filter((k) => k in mesh.defines).join(',');
  assert.equal(flags(), 'AXIAL_NO_TURN,AXIAL_NO_BEND');
  const key = mesh.material.customProgramCacheKey();
  mesh.setWind({ direction: [1, 0, 0], strength: 0.2 }); // the wind moves unbent instances' control points
  assert.equal(flags(), 'AXIAL_NO_TURN');
  assert.notEqual(mesh.material.customProgramCacheKey(), key);
  mesh.setWind(null);
  assert.equal(flags(), 'AXIAL_NO_TURN,AXIAL_NO_BEND');
  const row = data.slice(2 * f, 3 * f);
  row[4] = 0.3; // one instance bent by updateParams: the bend comes back, and stays until setParams
  mesh.material.needsUpdate = false;
  mesh.updateParams(row, 2);
  assert.equal(flags(), 'AXIAL_NO_TURN');
  assert.ok(mesh.material.version > 0);
  row[4] = 0;
  mesh.updateParams(row, 2);
  assert.equal(flags(), 'AXIAL_NO_TURN');
  mesh.setParams(data);
  assert.equal(flags(), 'AXIAL_NO_TURN,AXIAL_NO_BEND');
  // 19 numbers: the turn is there while an instance twists or tapers
  const ext = new Float32Array(19 * n);
  for (let i = 0; i < n; i++) ext[i * 19 + 16] = 1; // scale 1
  ext[3 * 19 + 18] = 0.2; // one taper
  const m19 = new AxialInstancedMesh(g, new THREE.MeshStandardMaterial(), { ...rec, numbersPerInstance: 19, data: ext });
  assert.ok(!('AXIAL_NO_TURN' in m19.defines) && !('AXIAL_NO_BEND' in m19.defines));
  ext[3 * 19 + 18] = 0;
  m19.setParams(ext);
  assert.ok('AXIAL_NO_TURN' in m19.defines && 'AXIAL_NO_BEND' in m19.defines);
  // several axes: a child axis's offset bends too
  const two = recordLayout(26, 2), rows = new Float32Array(26 * 2);
  assert.deepEqual(uses(rows, two, 0, 2), { turn: false, bend: false });
  rows[26 + 15] = 0.1; // instance 1's child axis, d3v
  assert.deepEqual(uses(rows, two, 0, 2), { turn: false, bend: true });
  assert.deepEqual(uses(rows, two, 0, 1), { turn: false, bend: false });
  mesh.dispose();
  m19.dispose();
});
