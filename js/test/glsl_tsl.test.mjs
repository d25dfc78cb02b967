// node --test: the node functions are GENERATED from glsl/ (build.mjs, glsl_tsl.mjs), and a change of a
// formula in glsl/ that is not built again is caught: `build.mjs --check` run on a copy with an edited GLSL.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, mkdtempSync, mkdirSync, copyFileSync, writeFileSync, rmSync } from 'node:fs';
import { join } from 'node:path';
import { tmpdir } from 'node:os';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { emitTsl, GlslError } from '../glsl_tsl.mjs';
import { generateNodes } from '../build.mjs';

const js = fileURLToPath(new URL('..', import.meta.url));
const glsl = join(js, '..', 'glsl');
const read = (name) => readFileSync(join(glsl, name), 'utf8');

test('src/webgpu/glsl_nodes.js, glsl_wind_nodes.js and glsl_generate_nodes.js are what glsl/ gives', () => {
  const want = generateNodes(read('axial.glsl'), read('wind.glsl'), read('generate.glsl'));
  for (const [file, text] of [['glsl_nodes.js', want.nodes], ['glsl_wind_nodes.js', want.wind], ['glsl_generate_nodes.js', want.generate]]) {
    assert.equal(readFileSync(join(js, 'src', 'webgpu', file), 'utf8'), text, file);
  }
});

test('build.mjs --check fails on a copy whose glsl/ changed a formula, and passes once built', () => {
  const root = mkdtempSync(join(tmpdir(), 'axd-drift-'));
  try {
    for (const d of ['webgl', 'webgpu']) mkdirSync(join(root, 'js', 'src', d), { recursive: true });
    mkdirSync(join(root, 'glsl'));
    for (const f of ['build.mjs', 'glsl_tsl.mjs']) copyFileSync(join(js, f), join(root, 'js', f));
    for (const f of ['webgl/glsl.js', 'webgpu/glsl_nodes.js', 'webgpu/glsl_wind_nodes.js', 'webgpu/glsl_generate_nodes.js']) {
      copyFileSync(join(js, 'src', f), join(root, 'js', 'src', f));
    }
    for (const f of ['axial.glsl', 'wind.glsl', 'generate.glsl', 'generate.vert', 'generate_children.vert',
      'generate_axes.vert', 'generate_axes.frag', 'slot.glsl']) copyFileSync(join(glsl, f), join(root, 'glsl', f));
    const check = () => spawnSync(process.execPath, [join(root, 'js', 'build.mjs'), '--check'], { encoding: 'utf8' });
    assert.equal(check().status, 0, check().stderr);
    const curve = read('axial.glsl');
    const edited = curve.replace('(4.0 * t * s * s * s) * d2', '(4.5 * t * s * s * s) * d2');
    assert.notEqual(edited, curve, 'the formula to edit is in axial.glsl');
    writeFileSync(join(root, 'glsl', 'axial.glsl'), edited);
    const stale = check();
    assert.equal(stale.status, 1);
    assert.match(stale.stderr, /glsl_nodes\.js differs/);
    const built = spawnSync(process.execPath, [join(root, 'js', 'build.mjs')], { encoding: 'utf8' });
    assert.equal(built.status, 0, built.stderr);
    assert.equal(check().status, 0);
    assert.match(readFileSync(join(root, 'js', 'src', 'webgpu', 'glsl_nodes.js'), 'utf8'), /float\(4\.5\)\.mul\(t\)/);
  } finally {
    rmSync(root, { recursive: true, force: true });
  }
});

const emit = (text, only) => emitTsl([{ name: 'x.glsl', text }], { only });

test('an out parameter is the caller\'s variable; early returns become one result; static conditions choose in JavaScript', () => {
  const out = emit(`
struct S { float a; bool on; };
float f(float x) { if (x > 1.0) return 2.0; return x; }
void g(S s, float x, out float y) { if (s.on) y = f(x); else y = -x; }
void h(float x, out float z) { float w; g(S(1.0, true), x, w); z = w; }`, ['h']);
  assert.match(out, /export function g\(s, x, y\) \{\n {2}if \(s\.on\) \{\n {4}y\.assign\(f\(x\)\);/);
  assert.match(out, /const _result = float\(0\)\.toVar\(\);\n {2}If\(x\.greaterThan\(float\(1\.0\)\), \(\) => \{\n {4}_result\.assign\(float\(2\.0\)\);\n {2}\}\)\.Else/);
  assert.match(out, /const w = float\(0\)\.toVar\(\);\n {2}g\(\{ a: float\(1\.0\), on: true \}, x, w\);\n {2}z\.assign\(w\);/);
});

test('a declared function is a hook: its callers, and theirs, take the program\'s hooks and pass them on', () => {
  const out = emit(`
void storage(int j, out float lo);
float walk(int b) { float lo; storage(b, lo); return lo; }
float twice(int b) { return walk(b) + walk(b + 1); }
float alone(float x) { return x; }`, ['twice', 'alone']);
  assert.match(out, /export function walk\(b, hooks\) \{\n {2}const lo = float\(0\)\.toVar\(\);\n {2}hooks\.storage\(b, lo\);/);
  assert.match(out, /export function twice\(b, hooks\) \{\n {2}return walk\(b, hooks\)\.add\(walk\(b\.add\(int\(1\)\), hooks\)\);/);
  assert.match(out, /export function alone\(x\) \{/);
  assert.doesNotMatch(out, /function storage/);
});

test('a switch keeps both builds of an #ifdef around statements, chosen by the runtime\'s switches as the nodes are built', () => {
  const text = `
float f(float x) {
#ifdef NO_TURN
    return x;
#else
    return x * 2.0;
#endif
}
float g(float x) {
    float y = x;
#ifndef NO_TURN
    y = f(y) + 1.0;
#endif
#ifdef OTHER
    y = y * 3.0;
#endif
    return y;
}`;
  const out = emitTsl([{ name: 'x.glsl', text }], { only: ['g'], switches: ['NO_TURN'] });
  assert.match(out, /import \{ switches \} from '\.\/tsl_runtime\.js';/);
  assert.match(out, /if \(switches\.NO_TURN\) \{\n {4}_result\.assign\(x\);\n {2}\} else \{/);
  assert.match(out, /if \(\(!switches\.NO_TURN\)\) \{\n {4}y\.assign\(f\(y\)\.add\(float\(1\.0\)\)\);/);
  assert.doesNotMatch(out, /OTHER|mul\(float\(3\.0\)\)/); // a define that is no switch: resolved as before
  const plain = emitTsl([{ name: 'x.glsl', text }], { only: ['f', 'g'], defines: { NO_TURN: '' } });
  assert.doesNotMatch(plain, /switches/);
  assert.match(plain, /export function f\(x\) \{\n {2}return x;/);
});

test('a function another emitted module holds is imported from it, an overload by its own name, not emitted again', () => {
  const text = `
float f(float x) { return x; }
float f(vec2 x) { return x.x; }
float g(float x) { return f(x) + f(vec2(x)); }`;
  const names = new Set();
  const first = emitTsl([{ name: 'x.glsl', text }], { only: ['f'], emitted: names });
  assert.deepEqual([...names].sort(), ['f_f', 'f_v2']);
  assert.match(first, /export function f_f\(x\)/);
  const second = emitTsl([{ name: 'x.glsl', text }], { only: ['g'], external: [{ module: './first.js', names: new Set(['f_f']) }] });
  assert.match(second, /import \{ f_f \} from '\.\/first\.js';/);
  assert.doesNotMatch(second, /export function f_f/);
  assert.match(second, /export function f_v2\(x\)/); // the overload the other module lacks
  assert.match(second, /export function g\(x\)/);
});

test('what the emitter does not take is refused with the file and line', () => {
  assert.throws(() => emit('float f(float x) {\n  return sin(x);\n}'), (e) => e instanceof GlslError && /x\.glsl:2: sin\(\)/.test(e.message));
  assert.throws(() => emit('float f(int i) {\n  float a[3];\n  return a[i];\n}'), /x\.glsl:3: an array indexed by a node/);
  assert.throws(() => emit('void f(float x) {\n  x = g(x);\n}'), /x\.glsl:2: g\(\) is neither/);
  assert.throws(() => emit('#define N 3\nfloat f() { return 1.0; }'), /x\.glsl:1: #define is not in the subset/);
});
