// Compiled (tsc --noEmit) by tests/web/test_three.py: the declarations describe the README's usage.
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { AxialGLTFPlugin, AxialInstancedMesh, parseADP, AxialError, type ADPRecord } from 'axialdeform-three';
import { recordLayout, WIND, checkRecipe, tilesAround, RECIPE_FIELDS } from 'axialdeform-three/helpers';
import { crc32, fieldName } from 'axialdeform-three/adp';
import { AXIAL_GLSL } from 'axialdeform-three/glsl';
import { AxialInstancedMesh as WebGPUAxialInstancedMesh, type AxialBent } from 'axialdeform-three/webgpu';

export async function usage(buffer: ArrayBuffer, geometry: THREE.BufferGeometry): Promise<THREE.Object3D> {
  const loader = new GLTFLoader();
  loader.register((parser) => new AxialGLTFPlugin(parser));
  const gltf = await loader.loadAsync('stones.glb');
  const record: ADPRecord = parseADP(buffer, 'stones.adp');
  const stones = new AxialInstancedMesh(geometry, new THREE.MeshStandardMaterial(), record, { capacity: 2 * record.count });
  stones.setParams(record.data.subarray(0, record.numbersPerInstance), { first: 3 });
  stones.updateParams(record.data.subarray(0, record.numbersPerInstance), 1);
  const n: number = stones.count + stones.layout.numbersPerInstance + recordLayout(16).level + WIND.frequency
    + crc32(new Uint8Array(4)) + fieldName(0).length + AXIAL_GLSL.length + RECIPE_FIELDS.length
    + tilesAround(checkRecipe({ rate: 1, tile: 8, reach: 20 }).tile, 0, 0, 20).length;
  const hits = new THREE.Raycaster().intersectObject(stones);
  if (hits.length && hits[0].instanceId !== undefined && n > 0) stones.dispose();
  try { parseADP(new Uint8Array(4)); } catch (e) { if (e instanceof AxialError) console.log(e.message); }
  stones.setWind({ direction: [1, 0, 0], strength: 0.2 }).setTime(1.5);
  const baked: boolean = stones.bake(new THREE.WebGLRenderer());
  if (baked) stones.unbake();
  gltf.scene.add(stones);
  return gltf.scene;
}

// axialdeform-three/webgpu: the same mesh for WebGPURenderer, its asynchronous GPU reads and culling
export async function webgpu(geometry: THREE.BufferGeometry, record: ADPRecord, renderer: unknown): Promise<number> {
  const stones = new WebGPUAxialInstancedMesh(geometry, new THREE.MeshStandardMaterial(), record);
  stones.setGPUCulling({ levels: [{ geometry, distance: 50 }] });
  const bent: AxialBent = await stones.bendAsync(renderer, [0, 1]);
  const hits = await stones.raycastAsync(new THREE.Raycaster(), renderer);
  const baked: boolean = await stones.setGPUCulling(false).bakeAsync(renderer);
  return bent.positions.length + hits.length + (baked ? 1 : 0) + (stones.gpuCulled ? 1 : 0);
}

// a generated layer under WebGPURenderer: the tiles around a point by a compute pass, read back asynchronously
export async function generatedWebGPU(geometry: THREE.BufferGeometry, renderer: unknown): Promise<number> {
  const stones = new WebGPUAxialInstancedMesh(geometry, new THREE.MeshStandardMaterial(), { generate: { rate: 1, tile: 8, reach: 20 } },
    { maxSlots: 1e6 });
  const made: boolean = stones.update(renderer, new THREE.Vector3(0, 0, 0));
  const kept = await stones.counted;
  const records: Float32Array = await stones.recordsAsync();
  const hits = await stones.raycastAsync(new THREE.Raycaster(), renderer);
  return (made ? 1 : 0) + (kept ?? 0) + records.length + hits.length + stones.tiles.length;
}

// a generated layer under WebGLRenderer: the same mesh class, its instances made from a recipe by transform feedback
export function generatedWebGL(geometry: THREE.BufferGeometry, renderer: THREE.WebGLRenderer): number {
  const stones = new AxialInstancedMesh(geometry, new THREE.MeshStandardMaterial(), { generate: { rate: 1, tile: 8 } },
    { autoUpdate: false });
  const made: boolean = stones.update(renderer, new THREE.Vector3(0, 0, 0));
  const records: Float32Array = stones.records();
  return (made ? 1 : 0) + (stones.kept ?? 0) + records.length + (stones.recipe ? stones.recipe.rate : 0);
}
