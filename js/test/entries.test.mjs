// node --test: each entry of the package loads only its own renderer's files -- the WebGPU entry no file of
// src/webgl/ (no WebGL code, no GLSL text it never runs), the WebGL entry none of src/webgpu/ -- and every
// file an entry reaches exists: the import graph read from the sources.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, existsSync } from 'node:fs';
import { dirname, join, relative, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const src = fileURLToPath(new URL('../src/', import.meta.url));

/** Every file of this package `entry` (relative to src/) imports, directly or not (relative to src/). */
export function reached(entry) {
  const seen = new Set(), todo = [resolve(src, entry)];
  while (todo.length) {
    const file = todo.pop(), rel = relative(src, file).split('\\').join('/');
    if (seen.has(rel)) continue;
    assert.ok(existsSync(file), `${rel}: imported but missing`);
    seen.add(rel);
    const text = readFileSync(file, 'utf8');
    for (const m of text.matchAll(/(?:from|import)\s*['"](\.\.?\/[^'"]+)['"]/g)) todo.push(join(dirname(file), m[1]));
  }
  return [...seen].sort();
}

test('the WebGPU entry imports no WebGL file of the module', () => {
  const files = reached('webgpu.js');
  assert.ok(files.includes('webgpu/mesh.js') && files.includes('core/mesh.js'), files.join(', '));
  assert.deepEqual(files.filter((f) => f.startsWith('webgl/')), []);
});

test('the WebGL entries import no WebGPU file of the module', () => {
  for (const entry of ['index.js', 'helpers.js']) {
    const files = reached(entry);
    assert.ok(files.includes('webgl/mesh.js') && files.includes('core/mesh.js'), files.join(', '));
    assert.deepEqual(files.filter((f) => f.startsWith('webgpu')), [], entry);
  }
});

test('the package\'s sub-paths point at files that exist, each with its types', () => {
  const pkg = JSON.parse(readFileSync(new URL('../package.json', import.meta.url), 'utf8'));
  for (const [path, e] of Object.entries(pkg.exports)) {
    for (const key of ['import', 'types']) assert.ok(existsSync(join(src, '..', e[key])), `${path}: ${key} ${e[key]} is missing`);
  }
});
