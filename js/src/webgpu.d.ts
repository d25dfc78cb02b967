// Types of axialdeform-three/webgpu: the module's classes for three's WebGPURenderer (three r184+).
import type { BufferGeometry, Raycaster, Intersection } from 'three';
import type { Material } from 'three';
import type { AxialGLTFPlugin as WebGLAxialGLTFPlugin, GenerateRecipe, GeneratorUniforms, AxialGeneratedMeshOptions, ADPRecord,
  InstanceRecord, AxialInstancedMeshOptions, DensityGrid } from './index';
import { AxialMeshCore } from './helpers';

export { AxialError, parseADP, EXTENSION } from './index';
/** The brush of a generated layer's mask (the same as axialdeform-three/helpers'): paints this entry's AxialGeneratedMesh. */
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
  constructor(geometry: BufferGeometry, material: Material | Material[], record: ADPRecord | InstanceRecord,
    options?: AxialInstancedMeshOptions);
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

/**
 * A generated layer under WebGPURenderer's WebGPU backend: its tiles' instances made by a compute pass of
 * glsl/generate.glsl as generated node functions, into the storage buffer the materials read.
 */
export class AxialGeneratedMesh extends AxialInstancedMesh {
  constructor(geometry: BufferGeometry, material: Material | Material[], recipe: GenerateRecipe,
    options?: AxialGeneratedMeshOptions);
  readonly isAxialGeneratedMesh: true;
  readonly recipe: Required<GenerateRecipe>;
  readonly generatorUniforms: GeneratorUniforms;
  /** The tiles held, nearest first; their instances in that order, m^2 each. */
  readonly tiles: [number, number][];
  /** Make the tiles around the camera by itself, without update(). */
  autoUpdate: boolean;
  /** How many of the `count` slots drawn are kept: null until `counted` resolves (read back asynchronously). */
  readonly kept: number | null;
  /** The count of the last tiles kept, once read back. */
  readonly counted: Promise<number | null>;
  /** The last tiles' cost on the CPU (null before the first). */
  readonly timing: { slots: number; generateMs: number } | null;
  /** Make the tiles within reach of `point` if they changed (one compute dispatch); returns whether they did. */
  update(renderer: unknown, point: { x: number; z: number }): boolean;
  /** The kept instances' records, as the Python library's generate_tiles gives them (read back). */
  recordsAsync(renderer?: unknown): Promise<Float32Array>;
  /** A new density map and where it lies (an AxialBrush's): the tiles are made again at the next update. */
  setDensity(grid: DensityGrid, placement: { d_lo: [number, number]; d_inv: [number, number]; d_wrap?: boolean }): void;
}

/** GLTFLoader plugin (AXIALDEFORM_bend) making this entry's AxialInstancedMesh (AxialGeneratedMesh for the generated form). */
export class AxialGLTFPlugin extends WebGLAxialGLTFPlugin {
  constructor(parser: import('three/addons/loaders/GLTFLoader.js').GLTFParser, options?: { maxSlots?: number });
}

/** The bend as three.js node functions (glsl/axial.glsl and glsl/wind.glsl, generated at build). */
export const nodes: Record<string, (...args: any[]) => any>;
/** A generated layer's instance as three.js node functions (glsl/generate.glsl, generated at build). */
export const generateNodes: Record<string, (...args: any[]) => any>;
