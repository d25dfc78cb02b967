// Types of axialdeform-three/webgpu: the module's classes for three's WebGPURenderer (three r171+).
import type { BufferGeometry, Raycaster, Intersection } from 'three';
import type { AxialInstancedMesh as WebGLAxialInstancedMesh, AxialGLTFPlugin as WebGLAxialGLTFPlugin } from './index';

export { AxialError, parseADP, EXTENSION } from './index';

/** What bendAsync reads back: 4 numbers a vertex (x, y, z, w), instance after instance, in the mesh's space. */
export interface AxialBent {
  ids: number[];
  V: number;
  positions: Float32Array;
  normals: Float32Array;
  tangents: Float32Array | null;
}

/** A level of GPU culling: instances nearer than `distance` (and farther than the level before) drawn with `geometry`. */
export interface CullingLevel {
  geometry: BufferGeometry;
  distance: number;
}

/** AxialInstancedMesh for WebGPURenderer: the bend is the node material's positionNode. */
export class AxialInstancedMesh extends WebGLAxialInstancedMesh {
  /** GPU culling and level of detail on the WebGPU backend (false: off). */
  setGPUCulling(options?: boolean | { levels: CullingLevel[] }): this;
  /** Whether instances are culled on the GPU. */
  readonly gpuCulled: boolean;
  /** Bend instances `ids` (all when null) by a compute pass and read them back. */
  bendAsync(renderer?: unknown, ids?: ArrayLike<number> | null): Promise<AxialBent>;
  /** Bend once and draw plain geometry until the instances move. */
  bakeAsync(renderer?: unknown): Promise<boolean>;
  /** The ray's intersections with the bent instances, nearest first (with instanceId). */
  raycastAsync(raycaster: Raycaster, renderer?: unknown): Promise<Intersection[]>;
}

/** GLTFLoader plugin (AXIALDEFORM_bend) making this entry's AxialInstancedMesh. */
export class AxialGLTFPlugin extends WebGLAxialGLTFPlugin {}

/** The bend as three.js node functions (the port of glsl/axial.glsl and glsl/wind.glsl). */
export const nodes: Record<string, (...args: any[]) => any>;
