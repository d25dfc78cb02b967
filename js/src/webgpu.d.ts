// Types of axialdeform-three/webgpu: the module's classes for three's WebGPURenderer (three r184+).
import type { BufferGeometry, Raycaster, Intersection } from 'three';
import type { Material } from 'three';
import type { AxialGLTFPlugin as WebGLAxialGLTFPlugin, ADPRecord, InstanceRecord, GeneratedRecord, AxialInstancedMeshOptions }
  from './index';
import { AxialMeshCore } from './helpers';

export { AxialError, parseADP, EXTENSION } from './index';
/** The brush of a generated layer's mask (the same as axialdeform-three/helpers'): paints this entry's generated AxialInstancedMesh. */
export { AxialBrush } from './helpers';

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
export class AxialInstancedMesh extends AxialMeshCore {
  constructor(geometry: BufferGeometry, material: Material | Material[], record: ADPRecord | InstanceRecord | GeneratedRecord,
    options?: AxialInstancedMeshOptions);
  /** A generated layer: the count of the last tiles kept, once read back (`kept` is null until then). */
  readonly counted: Promise<number | null>;
  /** The instances' records: a generated layer's kept ones read back from the GPU (a compute pass), as the Python
   * library's generate_tiles gives them; otherwise the record's. */
  recordsAsync(renderer?: unknown): Promise<Float32Array>;
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

/** GLTFLoader plugin (AXIALDEFORM_bend) making this entry's AxialInstancedMesh (a generated node's made from its recipe). */
export class AxialGLTFPlugin extends WebGLAxialGLTFPlugin {
  constructor(parser: import('three/addons/loaders/GLTFLoader.js').GLTFParser, options?: { maxSlots?: number });
}

/** The bend as three.js node functions (glsl/axial.glsl and glsl/wind.glsl, generated at build). */
export const nodes: Record<string, (...args: any[]) => any>;
/** A generated layer's instance as three.js node functions (glsl/generate.glsl, generated at build). */
export const generateNodes: Record<string, (...args: any[]) => any>;
