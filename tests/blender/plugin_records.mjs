// What three.js draws of a GLB: the npm module's AxialGLTFPlugin through three's GLTFLoader, and
// each AxialInstancedMesh's records as JSON ({name, count, numbersPerInstance, data}, one a line).
//   node tests/blender/plugin_records.mjs FILE.glb
import { readFileSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const root = resolve(dirname(fileURLToPath(import.meta.url)), '..', '..');
const three = join(root, 'js', 'node_modules', 'three');
await import(pathToFileURL(join(three, 'build', 'three.module.js')).href);
const { GLTFLoader } = await import(pathToFileURL(join(three, 'examples', 'jsm', 'loaders', 'GLTFLoader.js')).href);
const mod = await import(pathToFileURL(join(root, 'js', 'src', 'index.js')).href);

const data = readFileSync(process.argv[2]);
const loader = new GLTFLoader();
loader.register((parser) => new mod.AxialGLTFPlugin(parser));
const gltf = await new Promise((ok, fail) =>
  loader.parse(data.buffer.slice(data.byteOffset, data.byteOffset + data.byteLength), '', ok, fail));
gltf.scene.traverse((o) => {
  if (!o.isAxialInstancedMesh) return;
  const width = o.layout.numbersPerInstance;
  process.stdout.write(JSON.stringify({ name: o.name, count: o.count, numbersPerInstance: width,
    data: Array.from(o.data.subarray(0, o.count * width)) }) + '\n');
});
