// Type declarations of axialdeform-three/helpers: the parts the product is built from (the record's
// columns, the parser's checks, the axis and bounds maths, the shader patch, the glTF plugin's steps).
import * as THREE from 'three';
import type { ADPRecord, AxialInstancedMeshOptions, WindSpec, AxialInstancedMesh, AxisSpec, AxesSpec, BendExtension, InstanceRecord, RecordLayout, ResolvedAxis,
  Rows3, GenerateRecipe, GeneratorUniforms, GroundMaps, GeneratedRecord, DensityGrid } from './index.js';

export function crc32(bytes: Uint8Array): number;
export function hex(bytes: Uint8Array): string;
export function dequantize(values: Uint16Array, qtable: Float32Array, fields: number): Float32Array;
export function recordLayout(numbersPerInstance: number, axes?: number): RecordLayout;
export function texelRows(count: number, axes: number): number;
export function childTexels(data: Float32Array, fields: number, axes: number, first: number, count: number,
  texels: Float32Array): Float32Array;
export const NUMBERS_OF_VERSION: Readonly<Record<1 | 2 | 3, number>>;
export const HEADER_BYTES: 96;
export const MAX_AXES: 64;
export const AXES_ROW: 4095;
export function alignedFrame(index: 0 | 1 | 2): Rows3;
export function resolveAxis(spec: { axis?: AxisSpec; axes?: AxesSpec | null } | AxisSpec | null,
  record: InstanceRecord | null, positions: ArrayLike<number>): ResolvedAxis;
export function instanceMatrices(data: Float32Array, layout: RecordLayout, count: number, out: Float32Array,
  first?: number): Float32Array;
export function bentRadii(positions: ArrayLike<number>, axis: ResolvedAxis, data: Float32Array, layout: RecordLayout,
  count: number, first?: number, out?: Float32Array | null, grow?: Float32Array | null):
  { center: [number, number, number]; radius: Float32Array; grow: Float32Array | null };
/** Inject the bend into the vertex shader text of a three.js built-in material. */
export function injectBend(vertexShader: string, where?: string): string;
/** `raw`: the node's TRANSLATION and SCALE accessors as GLTFLoader reads them (the plugin passes them); without
 * them the position and scale come from the instance matrices. */
export function fromInstancedMesh(mesh: THREE.InstancedMesh, ext: BendExtension, where?: string,
  raw?: { TRANSLATION?: THREE.BufferAttribute; SCALE?: THREE.BufferAttribute } | null): AxialInstancedMesh;
export function recordFromInstancedMesh(mesh: THREE.InstancedMesh, ext: BendExtension, where?: string,
  raw?: { TRANSLATION?: THREE.BufferAttribute; SCALE?: THREE.BufferAttribute } | null): InstanceRecord;
export function column(start: number, axes?: number): number;
/** Check a node's AXIALDEFORM_bend object (throws AxialError naming the node and the field). */
export function checkBendExtension(ext: unknown, where?: string, options?: { maxSlots?: number }): BendExtension;

/** The instance record (generated from axialdeform.core.record): each field's columns, first column, level. */
export const RECORD: ReadonlyArray<{ name: string; columns: string[]; start: number; level: number }>;
export const WIDTHS: readonly number[];
/** The instanced attributes the bend reads: name, first column of axis 0's record, size, level. */
export const ATTRIBUTES: ReadonlyArray<{ name: string; start: number; size: number; level: number }>;
/** The wind's defaults and second harmonic (generated from axialdeform.core.wind). */
export const WIND: Readonly<{ gustiness: number; frequency: number; wavelength: number; harmonic: number }>;
export const FRAME_TOLERANCE: number;
/** The wind's uniforms (axialdeform.core.wind.WIND_UNIFORMS), in the order glsl/wind.glsl's functions take them. */
export const WIND_UNIFORMS: ReadonlyArray<{ name: string; type: 'float' | 'vec2' | 'vec3'; glsl: string; three: string }>;
/** A generated layer's recipe keys (axialdeform.core.recipe.RECIPE). */
export const RECIPE: ReadonlyArray<{ name: string; kind: string; default: unknown; required: boolean; json: boolean;
  requiredJson: boolean; uniform: string | null; uniformDefault: unknown }>;
/** What each kind of recipe key expects. */
export const RECIPE_KINDS: Readonly<Record<string, { expected: string; shape: string; words: string[] }>>;
/** The wind's uniforms, still (strength 0): {axialWindDir: {value}, ...}. */
export function stillWindUniforms(): Record<string, { value: unknown }>;

// generated layers' parts: the recipe's checks and numbers, the tiles, the WebGL 2 generator
/** A recipe checked as the Python library checks it, its defaults filled in. */
export function checkRecipe(recipe: GenerateRecipe): Required<GenerateRecipe>;
/** generate.glsl's numbers from a recipe, the base mesh's positions and its resolved axis. */
export function recipeUniforms(recipe: Required<GenerateRecipe>, positions: Float32Array,
  axis: { frame: Rows3; lo: number; length: number }): GeneratorUniforms;
/** The tiles any point of which lies within `reach` of (x, z), nearest first. */
/** `edge`: the world's edge (no tile beyond it; default none). */
export function tilesAround(tile: number, x: number, z: number, reach: number, edge?: number): [number, number][];

/** A GL buffer of slots the generator left on the GPU. */
export interface GeneratedSlots { buffer: WebGLBuffer; bytes: number }

/** glsl/generate.glsl by WebGL 2 transform feedback: make(tiles) -> a GL buffer of 23 float32 an instance
 * (the 22-number record, then kept), tile after tile, left on the GPU; run(tiles) reads it back. */
export class TileGenerator {
  constructor(renderer: THREE.WebGLRenderer, uniforms: GeneratorUniforms, maps?: GroundMaps);
  readonly count: number;
  make(tiles: [number, number][]): GeneratedSlots;
  read(slots: GeneratedSlots): Float32Array;
  run(tiles: [number, number][]): Float32Array;
  dispose(): void;
}

/** AxialRecipe's fields (glsl/generate.glsl), [name, GLSL type] in order. */
export const RECIPE_FIELDS: ReadonlyArray<readonly [string, string]>;

/** Pixels a side of a new mask. */
export const MASK_SIZE: number;

/** A generated layer's brush (the Python library's core/brush.py): paint where it grows, or erase. */
export class AxialBrush {
  constructor(mesh: AxialMeshCore, ground: { area: [number, number, number, number]; wrap?: boolean;
    density?: DensityGrid | null; mask?: DensityGrid | null });
  readonly mesh: AxialMeshCore;
  /** The mask painted (1 grows, 0 does not). */
  readonly mask: DensityGrid;
  /** Paint (or erase) a round dab on the ground; whether the mask changed (the tiles are then made again). */
  stroke(x: number, z: number, radius: number, erase?: boolean): boolean;
  /** The density the generator reads: the density map times the mask, on the mask's grid. */
  fold(): Float32Array;
  /** Give the mesh the folded density. */
  apply(): void;
  /** The mask as an 8-bit grey PNG: SCENE-LAYER-mask.png beside a scene file. */
  png(): Promise<Uint8Array>;
}

/** What every axialdeform mesh is under any renderer (both entries' AxialInstancedMesh subclass it): the record,
 * its attributes and instance matrices, the bend-aware bounds, setParams/updateParams, the wind's state. */
export class AxialMeshCore extends THREE.InstancedMesh {
  constructor(geometry: THREE.BufferGeometry, material: THREE.Material | THREE.Material[],
    record: ADPRecord | InstanceRecord | GeneratedRecord, options?: AxialInstancedMeshOptions);
  readonly isAxialInstancedMesh: true;
  /** A generated layer's recipe (checked, its defaults filled in); null: the instances are the record's. */
  readonly recipe: Required<GenerateRecipe> | null;
  /** A generated layer: generate.glsl's numbers. */
  readonly generatorUniforms: GeneratorUniforms;
  /** A generated layer: the tiles held, nearest first; their instances in that order, m^2 each. */
  readonly tiles: [number, number][];
  /** A generated layer: make the tiles around the camera by itself, without update() (drawn from the second frame on). */
  autoUpdate: boolean;
  /** A generated layer: how many of the `count` slots drawn are kept (the dropped ones collapse to a point); under
   * WebGPU null until `counted` resolves. */
  readonly kept: number | null;
  /** A generated layer: the last tiles' cost (null before the first). */
  readonly timing: { instances?: number; slots: number; generateMs: number } | null;
  /** A generated layer: make the tiles within reach of `point` on `renderer`'s GPU if they changed; returns whether they did. */
  update(renderer: unknown, point: { x: number; z: number }): boolean;
  /** A generated layer: a new density map and where it lies (an AxialBrush's); the tiles are made again on the next update. */
  setDensity(grid: DensityGrid, placement: { d_lo: [number, number]; d_inv: [number, number]; d_wrap?: boolean }): void;
  readonly capacity: number;
  readonly layout: RecordLayout;
  readonly axis: ResolvedAxis;
  /** capacity x numbersPerInstance: every instance's numbers (setParams writes here). */
  readonly data: Float32Array;
  /** The uniforms the bent materials share (axialFrame, axialLo, axialLen, axialCenter, ...). */
  readonly axialUniforms: Record<string, THREE.IUniform>;
  baseGeometry: THREE.BufferGeometry;
  bendMaterial<M extends THREE.Material>(material: M, clone?: boolean): M;
  /** Replace the instances (the count may shrink); with {first}: updateParams(data, first). */
  setParams(data: Float32Array | ADPRecord | InstanceRecord, options?: { first?: number }): this;
  /** Update instances start .. in place: only that range is uploaded and bounded. */
  updateParams(rows: Float32Array | ADPRecord | InstanceRecord, start?: number): this;
  getInstanceBoundingSphere(index: number, target?: THREE.Sphere): THREE.Sphere;
  getInstanceBoundingBox(index: number, target?: THREE.Box3): THREE.Box3;
  /** The wind of glsl/wind.glsl (null: none); setTime moves its clock. */
  setWind(wind: WindSpec | null): this;
  setTime(seconds: number): this;
  unbake(): this;
  readonly baked: boolean;
  setBendVisible(on: boolean): void;
  dispose(): this;
}
