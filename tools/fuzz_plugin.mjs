// The npm module's side of tools/fuzz_specs.py: every GLB named on stdin (one path a line) goes
// through three's GLTFLoader with AxialGLTFPlugin registered; one JSON line per file:
//   {"file", "verdict": ok | refused | crash | garbage, "detail"}
// ok: loaded, and every bent mesh has finite bounds; refused: an AxialError naming the node;
// garbage: loaded with bounds that are not finite, or an instanced node of the extension left unbent;
// crash: any other error.  Before each file a line {"start": NAME} (a run that dies names its file).
//   node tools/fuzz_plugin.mjs JS_SRC < list.txt      (JS_SRC: the module's src folder)
import { readFileSync } from 'node:fs';
import { basename, dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '..');
const three = join(root, 'js', 'node_modules', 'three');
// the same module instances the plugin's own `import 'three'` resolves to
await import(pathToFileURL(join(three, 'build', 'three.module.js')).href);
const { GLTFLoader } = await import(pathToFileURL(join(three, 'examples', 'jsm', 'loaders', 'GLTFLoader.js')).href);
const mod = await import(pathToFileURL(join(resolve(process.argv[2]), 'index.js')).href);

function load(buffer) {
  const loader = new GLTFLoader();
  loader.register((parser) => new mod.AxialGLTFPlugin(parser));
  return new Promise((ok, fail) => loader.parse(buffer, '', ok, fail));
}

function verdictOf(gltf) {
  let bent = 0, instanced = 0;
  let bad = null;
  gltf.scene.traverse((o) => {
    if (o.isInstancedMesh) instanced++;
    if (!o.isAxialInstancedMesh) return;
    bent++;
    const s = o.boundingSphere || (o.computeBoundingSphere(), o.boundingSphere);
    if (!s || !Number.isFinite(s.radius) || ![s.center.x, s.center.y, s.center.z].every(Number.isFinite)) {
      bad = `${o.name || 'a mesh'}: bounds that are not finite`;
    }
  });
  if (bad) return ['garbage', bad];
  if (!bent && instanced) return ['garbage', 'an instanced node of the extension was loaded unbent'];
  return ['ok', `${bent} bent meshes`];
}

const files = readFileSync(0, 'utf8').split('\n').filter(Boolean);
for (const file of files) {
  const name = basename(file);
  process.stdout.write(JSON.stringify({ start: name }) + '\n');
  let verdict;
  try {
    const data = readFileSync(file);
    verdict = verdictOf(await load(data.buffer.slice(data.byteOffset, data.byteOffset + data.byteLength)));
  } catch (e) {
    const message = String(e && e.message).split('\n')[0].slice(0, 300);
    verdict = e instanceof mod.AxialError ? ['refused', message] : ['crash', `${e && e.name}: ${message}`];
  }
  process.stdout.write(JSON.stringify({ file: name, verdict: verdict[0], detail: verdict[1] }) + '\n');
}
