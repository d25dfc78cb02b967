// Type declarations of axialdeform-three (the module is plain ES2020 JavaScript).
import * as THREE from 'three';
import type { GLTFLoaderPlugin, GLTFParser, GLTF } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { AxialMeshCore } from './helpers';

/** The error of every check in the package: its message names the file, the field and what was expected. */
export class AxialError extends Error {}

/** A parsed .adp parameter file (parseADP). */
export interface ADPRecord {
  name: string;
  version: 1 | 2 | 3;
  encoding: 'float32' | 'quantized';
  count: number;
  /** 16, 19 or 22, plus 10 per axis after the first. */
  numbersPerInstance: number;
  fields: number;
  /** K: axes per instance (1 unless the mesh has several axes). */
  axes: number;
  /** -1 none recorded, 0/1/2 the aligned axis x/y/z, 3 a chosen frame, 4 several axes. */
  axis: number;
  lo: number;
  length: number;
  /** SHA-256 hex of the base mesh the numbers were made for ('' when none recorded). */
  fingerprint: string;
  fingerprintBytes: Uint8Array;
  frameDigest: string;
  frameDigestBytes: Uint8Array;
  /** The stored numbers: float32, or uint16 with `qtable` ([min..., step...], 2 numbersPerInstance). */
  values: Float32Array | Uint16Array;
  qtable: Float32Array | null;
  /** count x numbersPerInstance numbers, decoded. */
  readonly data: Float32Array;
}

/** The minimum AxialInstancedMesh needs: numbers, row by row. */
export interface InstanceRecord {
  name?: string;
  count: number;
  numbersPerInstance: number;
  data: Float32Array;
  axes?: number;
  axis?: number;
  lo?: number;
  length?: number;
}

export interface RecordLayout {
  axes: number; level: 0 | 1 | 2; numbersPerInstance: number; base: 16 | 19 | 22;
  position: number; angles: number; scale: number | null; twist: number | null; taper: number | null; tint: number | null;
}

export type Rows3 = [number[], number[], number[]];

/** A control axis: the frame's rows e_a, e_u, e_v, lo, length, the axis line `center` (across). */
export interface AxisSpec {
  frame?: Rows3;
  index?: 0 | 1 | 2 | -1;
  lo: number;
  length: number;
  center?: [number, number];
}

/** Several axes in a hierarchy (a tree). */
export interface AxesSpec {
  count: number;
  frames: Rows3[];
  lo: number[];
  length: number[];
  parents: number[];
}

/** The AXIALDEFORM_bend extension object (docs/gltf/AXIALDEFORM_bend). */
export interface BendExtension {
  numbersPerInstance: number;
  axis: Required<Pick<AxisSpec, 'frame' | 'lo' | 'length' | 'center'>>;
  axes?: AxesSpec;
  fingerprint?: string;
}

export interface ResolvedAxis {
  frame: Rows3; lo: number; length: number; center: [number, number]; axes: AxesSpec | null;
}

export function parseADP(input: ArrayBuffer | ArrayBufferView, name?: string): ADPRecord;

/** A wind (docs/wind.md): strength is the tip displacement in units of the axis length. */
export interface WindSpec {
  direction: [number, number, number];
  strength: number;
  gustiness?: number;
  frequency?: number;
  wavelength?: number;
}

export interface AxialInstancedMeshOptions {
  /** The mesh's axis where the record's header does not say it all (a chosen frame, several axes). */
  axis?: { axis?: AxisSpec; axes?: AxesSpec | null } | AxisSpec;
  /** Room for more instances than the record has. */
  capacity?: number;
  /** The materials bend themselves (ShaderMaterials including AXIAL_GLSL): used as given. */
  ownShader?: boolean;
  /** Each vertex's axis (several axes), if the geometry has no `_axial_axis` attribute: a whole number, or for a
   * vertex blending two axes' chains `b + 64 b1 + 4096 q` (its axis b, a second axis b1, weight q / 2047). */
  vertexAxis?: ArrayLike<number> | THREE.BufferAttribute;
  /** A generated layer ({generate: recipe}): generate.glsl's numbers as the Python library gave them (default: recipeUniforms). */
  uniforms?: GeneratorUniforms;
  /** A generated layer: the ground maps the uniforms place. */
  maps?: GroundMaps;
  /** A generated layer: make the tiles around the camera's position just before each draw (the glTF plugin's meshes). */
  autoUpdate?: boolean;
  /** A generated layer: the most slots the tiles within reach may hold, each axis counted (default 4 194 304). */
  maxSlots?: number;
  /** A generated layer under WebGPU: the renderer's maxStorageBufferBindingSize, checked before any buffer is
   * allocated (default 134 217 728). */
  maxStorageBufferBindingSize?: number;
}

/** A THREE.InstancedMesh whose instances are each bent along their own Bézier control axis, under
 * WebGLRenderer (the bend injected into classic materials; axialdeform-three/webgpu for WebGPURenderer). */
export class AxialInstancedMesh extends AxialMeshCore {
  constructor(geometry: THREE.BufferGeometry, material: THREE.Material | THREE.Material[],
    record: ADPRecord | InstanceRecord | GeneratedRecord, options?: AxialInstancedMeshOptions);
  /** The instances' records: a generated layer's kept ones read back from the GPU, as the Python library's
   * generate_tiles gives them; otherwise the record's. */
  records(): Float32Array;
  /** Cull each instance by its bend-aware bounding sphere before every draw (the camera's and each shadow
   * map's) under `renderer`; null: draw them all. */
  setInstanceCulling(renderer: THREE.WebGLRenderer | null): this;
  /** Bend once on the GPU (transform feedback) and draw plain geometry; false where it keeps bending. */
  bake(renderer: THREE.WebGLRenderer): boolean;
}

/** GLTFLoader plugin: `loader.register((parser) => new AxialGLTFPlugin(parser))`. */
export class AxialGLTFPlugin implements GLTFLoaderPlugin {
  /** `options.maxSlots`: the most slots a generated node may hold (default 4 194 304). */
  constructor(parser: GLTFParser, options?: { maxSlots?: number });
  readonly name: 'AXIALDEFORM_bend';
  parser: GLTFParser;
  /** Checks every AXIALDEFORM_bend and its instance accessors before the loader reads them. */
  beforeRoot(): null;
  afterRoot(gltf: GLTF): Promise<void>;
}
export const EXTENSION: 'AXIALDEFORM_bend';

/** The text of axialdeform's glsl/axial.glsl (axial_bend, axial_place, axial_tree_world ...). */
export const AXIAL_GLSL: string;
/** The text of axialdeform's glsl/wind.glsl (axial_wind, axial_wind_push), to include after AXIAL_GLSL. */
export const WIND_GLSL: string;

/** A generated layer's recipe (a scene file's [layer.generate]; docs/generate.md). */
export interface GenerateRecipe {
  // GenerateRecipe: ---- written by tools/make_tables.py from axialdeform/core/recipe.py: edit the table, then rerun it ----
  /** Instances per square unit of ground (before the density map). */
  rate: number;
  /** The side of a tile (world units); default 16. */
  tile?: number;
  /** The guaranteed distance between any two instances (< 1/sqrt(rate)); default 0. */
  min_distance?: number;
  /** The seed of every random number; default 0. */
  seed?: number;
  /** Offsets in [-bend L, bend L]; a mesh of several axes: one amplitude per level of its hierarchy, the last for any deeper level; default 0.1. */
  bend?: number | number[];
  /** A uniform scale drawn in [lo, hi] (19 numbers an instance). */
  scale?: [number, number] | null;
  /** A twist drawn in [-twist, twist] radians; default 0. */
  twist?: number;
  /** A taper drawn in [0, taper]; default 0. */
  taper?: number;
  /** Each instance's colour tint_color (1 - tint u): shades of tint_color (22 numbers). */
  tint?: number | null;
  /** Linear RGB: the brightest tint; default [1, 1, 1]. */
  tint_color?: [number, number, number];
  /** How far each colour channel's u goes its own way (0: one u, the tint keeps tint_color's hue; 1: one u each); default 0. */
  tint_hue?: number;
  /** The turn about up drawn in [lo, hi] radians; default [0, 6.283185307179586]. */
  yaw?: [number, number];
  /** Clumps: 8 parents to every clump_cells x clump_cells cells, anywhere in them; each instance picks one (1 and clump_radius 0: no clumps); default 1. */
  clump_cells?: number;
  /** Clumps: each instance uniform in a disc of this radius around its parent (world units; no min_distance then); default 0. */
  clump_radius?: number;
  /** Clumps: the share of each clump's instances that stand in its core (where u25 < clump_core); default 0. */
  clump_core?: number;
  /** Clumps: the core's radius, at most clump_radius (world units): its instances uniform in a disc of this radius around the parent; default 0. */
  clump_core_radius?: number;
  /** The scale at u13 = 1/4, 1/2, 3/4: drawn piecewise linear through [lo, q1, q2, q3, hi] (a learned distribution of sizes; none: uniform in scale's [lo, hi]). */
  scale_quartiles?: [number, number, number] | null;
  /** With scale_quartiles, the scale at u13 = 1/8, 3/8, 5/8, 7/8 too: piecewise linear through nine knots (none: through five). */
  scale_octiles?: [number, number, number, number] | null;
  // GenerateRecipe: ---- end of what tools/make_tables.py writes ----
  /** The tiles within this distance of the point are made (default 3 tiles). */
  reach?: number;
}

/** generate.glsl's AxialRecipe numbers (axialdeform.core.generate.recipe_uniforms). */
export interface GeneratorUniforms {
  // GeneratorUniforms: ---- written by tools/make_tables.py from axialdeform/core/recipe.py: edit the table, then rerun it ----
  seed: number;
  m: number;
  cell: number;
  jitter: number;
  bend: number;
  scale: [number, number];
  scale_mid: [number, number, number];
  scale_odd: [number, number, number, number];
  twist: number;
  taper: number;
  anchor_y: number;
  anchor_w: [number, number, number, number];
  anchor_w4: number;
  tint: number;
  tint_color: [number, number, number];
  tint_hue: number;
  has_heights: boolean;
  h_lo: [number, number];
  h_inv: [number, number];
  h_size: [number, number];
  has_density: boolean;
  d_lo: [number, number];
  d_inv: [number, number];
  d_size: [number, number];
  d_wrap: boolean;
  altitude: [number, number];
  slope_tan2: [number, number];
  choice: [number, number];
  lift: [number, number];
  align: number;
  anchor_xz: [number, number];
  yaw: [number, number];
  clump_cells: number;
  clump_radius: number;
  clump_core: number;
  clump_core_radius: number;
  // GeneratorUniforms: ---- end of what tools/make_tables.py writes ----
}

/** A ground map's pixels: float32, row after row. */
export interface GroundMap { data: Float32Array; cols: number; rows: number }
/** The ground maps the uniforms place: the terrain's heights, the density map. */
export interface GroundMaps { heights?: GroundMap; density?: GroundMap }

/** In place of the record: a generated layer, its instances made on the GPU from `generate` (a scene file's
 * [layer.generate]) in the tiles within reach of a point (update, or autoUpdate). */
export interface GeneratedRecord { generate: GenerateRecipe }

/** Grey levels in 0..1, rows of `cols`, the first row at the low z. */
export interface DensityGrid { data: Float32Array; cols: number; rows: number }
