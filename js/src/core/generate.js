// core/generate.js -- generated layers (docs/generate.md) under any renderer: the recipe's checks, its
// uniforms, the tiles around a point (axialdeform.core.generate's conventions), the slots read back as
// records, the bounds from the recipe alone, and what makes an AxialInstancedMesh a generated layer
// ({generate: recipe} in place of its record: generatedBase, adoptGenerated).  The instances are made on the
// GPU by glsl/generate.glsl: WebGL 2 transform feedback (webgl/generate.js, webgl/tiles.js) or a WebGPU
// compute pass of its node functions (webgpu/generate.js).

import * as THREE from 'three';
import { AxialError } from './adp.js';
import { plainArray } from './baked.js';
import { WIDTHS, RECIPE, RECIPE_KINDS, SLOT } from './record.js';
import { MAX_SLOTS, accepts, checkAnchor, checkRecipeBounds, checkSlots, optionalNumbers, passedThrough, worldEdge } from './limits.js';

const JSON_KEYS = RECIPE.filter((k) => k.json);

/** Numbers an instance the generator writes (the slot, glsl/slot.glsl): the 22-number record (the 16, s, tw,
 * tp, the tint), then 1 (kept) or 0 (dropped by the ground maps and bands). */
export const GENERATED_FLOATS = SLOT.floats;
const NO_BAND = 3.0e38;
const _eye = new THREE.Vector3();
const BINOMIAL = [1, 4, 6, 4, 1];

const bad = (field, expected, value) => { throw new AxialError(`generate: ${field}: expected ${expected}, found ${JSON.stringify(value)}`); };
const num = (v) => typeof v === 'number' && Number.isFinite(v);

/** Python's round(): half to even (m must be the Python library's for the same recipe). */
function roundHalfEven(x) {
  const f = Math.floor(x), d = x - f;
  if (d > 0.5) return f + 1;
  if (d < 0.5) return f;
  return f % 2 === 0 ? f : f + 1;
}

/** [m, cell]: cells a side of a tile, m = max(1, round(T sqrt(rate))), and the cell's side T / m. */
export function tileSize(recipe) {
  const m = Math.max(1, roundHalfEven(recipe.tile * Math.sqrt(recipe.rate)));
  return [m, recipe.tile / m];
}

/**
 * A recipe checked as axialdeform.core.generate.Generate checks it (a scene file's [layer.generate]): the keys
 * record.js's RECIPE marks json, each by its kind, with their defaults, and reach (default 3 tiles).
 * Returns a new object with the defaults filled in.
 */
export function checkRecipe(recipe) {
  if (!recipe || typeof recipe !== 'object') throw new AxialError('generate: expected a recipe object {rate, tile, ...}');
  const r = { ...Object.fromEntries(JSON_KEYS.filter((k) => !k.required).map((k) => [k.name, structuredClone(k.default)])), ...recipe };
  const keys = [...JSON_KEYS.map((k) => k.name), 'reach'];
  for (const k of Object.keys(r)) {
    if (![...keys, 'extent'].includes(k)) throw new AxialError(`generate: ${k}: not a key of a recipe (${keys.join(', ')})`);
  }
  for (const k of JSON_KEYS) {
    if (!(k.default === null && r[k.name] === null) && !accepts(k.kind, r[k.name])) bad(k.name, RECIPE_KINDS[k.kind].expected, r[k.name]);
  }
  const cell = tileSize(r)[1];
  if (r.min_distance >= cell) bad('min_distance', `less than the cell side 1/sqrt(rate) = ${cell.toPrecision(6)}`, r.min_distance);
  const clumped = r.clump_cells > 1 || r.clump_radius > 0;
  if (clumped && r.min_distance > 0) bad('min_distance', '0 with clumps (clump_cells, clump_radius: instances of a clump stand anywhere in it)', r.min_distance);
  if (r.clump_radius > worldEdge(cell)) bad('clump_radius', `at most the world's edge, ${worldEdge(cell).toPrecision(6)}`, r.clump_radius);
  if (r.clump_core_radius > r.clump_radius) bad('clump_core_radius', `at most clump_radius, ${Number(r.clump_radius.toPrecision(6))} (the core lies within the clump)`, r.clump_core_radius);
  if (r.reach === undefined) r.reach = 3 * r.tile;
  if (!(num(r.reach) && r.reach > 0)) bad('reach', 'a finite number > 0', r.reach);
  checkRecipeBounds(r, ...tileSize(r));
  return r;
}

/** Numbers a record (record.js's levels): tinted with a tint, extended with a scale, twist or taper. */
export function recipeWidth(recipe) {
  return WIDTHS[recipe.tint !== null ? 2 : recipe.scale !== null || recipe.twist > 0 || recipe.taper > 0 ? 1 : 0];
}

/** The axis axialdeform gives a mesh by default: its longest bounding-box extent (ties: x, y, z). */
export function autoAxis(positions) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    const c = i % 3;
    if (positions[i] < lo[c]) lo[c] = positions[i];
    if (positions[i] > hi[c]) hi[c] = positions[i];
  }
  let index = 0;
  for (let c = 1; c < 3; c++) if (hi[c] - lo[c] > hi[index] - lo[index]) index = c;
  return { index, lo: lo[index], length: hi[index] - lo[index] };
}

/**
 * The numbers generate.glsl's AxialRecipe takes (axialdeform.core.generate.recipe_uniforms): from the
 * recipe, the base mesh's positions (Float32Array of 3 n) and its resolved axis ({frame, lo, length}).
 * The anchor is the centre of the mesh's lowest bounding-box face (up = y), its place on the axis t_a.
 */
export function recipeUniforms(recipe, positions, axis) {
  const [m, cell] = tileSize(recipe);
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    const c = i % 3;
    if (positions[i] < lo[c]) lo[c] = positions[i];
    if (positions[i] > hi[c]) hi[c] = positions[i];
  }
  // as numpy does it on the float32 positions: the sum rounded to float32, then halved
  const a = [Math.fround(lo[0] + hi[0]) / 2, lo[1], Math.fround(lo[2] + hi[2]) / 2];
  const e = axis.frame[0];
  const along = e[0] * a[0] + e[1] * a[1] + e[2] * a[2];
  const t = Math.min(1, Math.max(0, (along - axis.lo) / axis.length));
  const w = BINOMIAL.map((b, i) => Math.fround(b * t ** i * (1 - t) ** (4 - i)));
  const bend = Array.isArray(recipe.bend) ? recipe.bend[0] : recipe.bend;
  return { ...passedThrough(recipe), m, cell, jitter: 1 - recipe.min_distance / cell, bend: bend * axis.length,
    anchor_y: lo[1], anchor_w: w.slice(0, 4), anchor_w4: w[4],
    // no ground maps: the flat ground y = 0, no density map, no bands (the Python library's maps come
    // with its uniforms: a generated AxialInstancedMesh's options.uniforms and options.maps)
    has_heights: false, h_lo: [0, 0], h_inv: [1, 1], h_size: [0, 0], has_density: false, d_lo: [0, 0], d_inv: [1, 1],
    d_size: [0, 0], d_wrap: false, altitude: [-NO_BAND, NO_BAND], slope_tan2: [0, NO_BAND], anchor_xz: [a[0], a[2]] };
}

/** [[tx, tz], ...]: the tiles any point of which lies within `reach` of (x, z), nearest first
 * (axialdeform.core.generate.tiles_around); with `edge` (the world's, worldEdge) only the tiles wholly in
 * [-edge, edge]^2: beyond it none. */
export function tilesAround(tile, x, z, reach, edge = Infinity) {
  const out = [], first = Math.ceil(-edge / tile), last = Math.floor(edge / tile) - 1;
  if (!(Number.isFinite(x) && Number.isFinite(z) && reach >= 0)) return out;
  const span = (v) => [Math.max(first, Math.floor((v - reach) / tile)), Math.min(last, Math.floor((v + reach) / tile))];
  const [x0, x1] = span(x), [z0, z1] = span(z);
  for (let tx = x0; tx <= x1; tx++) {
    for (let tz = z0; tz <= z1; tz++) {
      const nx = Math.min(Math.max(x, tx * tile), (tx + 1) * tile), nz = Math.min(Math.max(z, tz * tile), (tz + 1) * tile);
      const d = Math.hypot(nx - x, nz - z);
      if (d <= reach) out.push([tx, tz, d]);
    }
  }
  out.sort((p, q) => p[2] - q[2] || p[0] - q[0] || p[1] - q[1]);
  return out.map(([tx, tz]) => [tx, tz]);
}

/** The most tiles tilesAround can return for `reach` (a generated mesh's capacity in tiles). */
export function maxTiles(tile, reach) {
  const k = Math.ceil((2 * reach) / tile) + 1;
  return k * k;
}

/**
 * Slots as records: `raw` the generator's slots (GENERATED_FLOATS each: TileGenerator.run's order), `kids`
 * the child axes' offsets (10 (K - 1) a slot) or null: {rows (one a slot, zeros where dropped; or only the
 * kept ones with `compact`), kept (a flag a slot), n (the kept)}: axis 0's offsets, the child axes', the rest.
 */
export function slotRows(raw, kids, layout, compact) {
  const G = GENERATED_FLOATS, all = raw.length / G;
  const f = layout.numbersPerInstance, c = 10 * (layout.axes - 1), kept = new Uint8Array(all);
  let n = 0;
  for (let i = 0; i < all; i++) if (raw[i * G + G - 1] > 0.5) { kept[i] = 1; n++; }
  const rows = new Float32Array((compact ? n : all) * f);
  for (let i = 0, k = 0; i < all; i++) {
    if (!kept[i] && compact) continue;
    const r = f * (compact ? k++ : i);
    if (!kept[i]) continue;
    rows.set(raw.subarray(i * G, i * G + 10), r);
    if (kids) rows.set(kids.subarray(i * c, (i + 1) * c), r + 10);
    rows.set(raw.subarray(i * G + 10, i * G + f - c), r + 10 + c);
  }
  return { rows, kept, n };
}

/**
 * A generated mesh's boundingBox and boundingSphere before its records are read back: a box holding
 * every instance its tiles can make, found from the recipe alone (the ground's height range, the base
 * mesh's farthest vertex, the bend's and the child axes' reach, the scale, the lift).
 */
export function recipeBounds(mesh) {
  const u = mesh.generatorUniforms, T = mesh.recipe.tile, xs = mesh.tiles.map((t) => t[0]), zs = mesh.tiles.map((t) => t[1]);
  if (mesh._far === undefined) { // once: the ground's height range, the farthest vertex from the origin, the child axes' reach
    const heights = u.has_heights && mesh.maps.heights ? mesh.maps.heights.data : [0];
    let lo = Infinity, hi = -Infinity;
    for (const h of heights) { lo = Math.min(lo, h); hi = Math.max(hi, h); }
    mesh._ground = [lo, hi];
    const p = plainArray(mesh.geometry.getAttribute('position')), c = mesh.maps.children;
    mesh._far = 0;
    for (let i = 0; i < p.length; i += 3) mesh._far = Math.max(mesh._far, Math.hypot(p[i], p[i + 1], p[i + 2]));
    mesh._kids = 0;
    for (let j = 0; c && j < c.rows; j++) {
      let most = 0;
      for (let a = 0; a < 5; a++) most = Math.max(most, [0, 1, 2, 3, 4].reduce((acc, b) => acc + Math.abs(c.data[26 * j + 1 + 5 * a + b]), 0));
      mesh._kids += Math.SQRT2 * Math.abs(c.data[26 * j]) * most;
    }
  }
  const s = Math.max(...u.scale), reach = s * (mesh._far + 2 * Math.SQRT2 * Math.abs(u.bend) + mesh._kids + Math.abs(u.anchor_y));
  const [h0, h1] = mesh._ground;
  const across = reach + ((u.clump_cells ?? 1) > 1 || (u.clump_radius ?? 0) > 0 ? u.clump_cells * u.cell + u.clump_radius : 0); // clumps
  mesh.boundingBox = new THREE.Box3(new THREE.Vector3(Math.min(...xs) * T - across, h0 + u.lift[0] - reach, Math.min(...zs) * T - across),
    new THREE.Vector3((Math.max(...xs) + 1) * T + across, h1 + u.lift[1] + reach, (Math.max(...zs) + 1) * T + across));
  mesh.boundingSphere = mesh.boundingBox.getBoundingSphere(mesh.boundingSphere || new THREE.Sphere());
}

/** What a generated mesh's base constructor takes: {r (the recipe checked), positions, record (no
 * instances: the GPU draws them), options (capacity 1: the CPU copies grow only when a raycast or bake
 * asks for the records)}; `who` names the class in errors. */
export function generatedBase(geometry, recipe, options, who) {
  const r = checkRecipe(recipe);
  const position = geometry && geometry.isBufferGeometry ? geometry.getAttribute('position') : null;
  if (!position) throw new AxialError(`${who}: expected a THREE.BufferGeometry with positions`);
  const positions = plainArray(position);
  const spec = options.axis || autoAxis(positions);
  const axes = spec.axes ? spec.axes.count : 1; // a mesh of several axes: 10 more numbers a child axis
  checkSlots(maxTiles(r.tile, r.reach), tileSize(r)[0], axes, options.maxSlots ?? MAX_SLOTS); // before any array
  if (options.uniforms) checkAnchor(options.uniforms, positions, (spec.axis || spec).length);
  const record = { count: 0, numbersPerInstance: recipeWidth(r) + 10 * (axes - 1), axes, data: new Float32Array(0) };
  return { r, positions, record, options: { ...options, axis: spec, capacity: 1 } };
}

/**
 * The generated layer `mesh` (an AxialInstancedMesh just made from generatedBase's `base`): its capacity in
 * slots, recipe, generator's numbers, maps, tiles, and the hook of autoUpdate (`drawsOn`: whether a renderer
 * is the one its entry generates with).  Each entry's mesh then adds its renderer's part (`mesh._part`).
 */
export function adoptGenerated(mesh, base, options, drawsOn) {
  const { r, positions } = base, [m] = tileSize(r), axes = mesh.layout.axes;
  mesh.capacity = maxTiles(r.tile, r.reach) * m * m;
  mesh.recipe = r;
  mesh.generatorUniforms = options.uniforms ? { ...optionalNumbers(), ...options.uniforms } : recipeUniforms(r, positions, mesh.axis);
  mesh.maps = options.maps || {};
  if (axes > 1 && !(mesh.maps.children && mesh.maps.children.rows === axes - 1 && mesh.maps.children.cols === 26)) {
    throw new AxialError(`AxialInstancedMesh: a generated layer of ${axes} axes needs options.maps.children (${axes - 1} rows of 26: `
      + 'each child axis\'s amplitude and joint projection, as axialdeform web and export write them)');
  }
  if (mesh.generatorUniforms.m !== m) throw new AxialError(`AxialInstancedMesh: uniforms.m is ${mesh.generatorUniforms.m}, the recipe's ${m}`);
  Object.assign(mesh, { tiles: [], _key: null, _part: null, timing: null, kept: 0, frustumCulled: false,
    autoUpdate: Boolean(options.autoUpdate), _drawnBy: null, _materialized: false });
  // its slots change as tiles come and go: the wind's phases hash where the instances stand (glsl/wind.glsl's
  // axial_position_id), as the Python library draws a generated layer
  mesh.defines.AXIAL_POSITION_IDS = '1';
  // autoUpdate: each draw says which renderer and camera (the base mesh's hook, then ours, then a
  // user's own, which assigning onBeforeRender sets); the tiles are made when the next render updates
  // the world's matrices, before three uploads the instances (made in onBeforeRender, they would be
  // drawn a frame late), the very first ones at once
  const baseHook = mesh.onBeforeRender;
  let userHook = null;
  const hook = (renderer, scene, camera, ...rest) => {
    baseHook(renderer, scene, camera, ...rest);
    if (mesh.autoUpdate && drawsOn(renderer)) {
      const first = mesh._drawnBy === null;
      mesh._drawnBy = { renderer, camera };
      if (first) mesh.update(renderer, camera.getWorldPosition(_eye));
    }
    if (userHook) userHook.call(mesh, renderer, scene, camera, ...rest);
  };
  Object.defineProperty(mesh, 'onBeforeRender', { get: () => hook, set: (fn) => { userHook = fn; }, configurable: true });
}

/** A generated layer's slots read back (slotRows' `rows` and `kept`, one a slot) as its CPU copy of the records
 * (what raycasting, bake and the bounds read): `grow(n)` gives the renderer's arrays room for n instances where
 * the mesh holds fewer; a dropped slot gets a zero matrix and radius; then the bounds made from them. */
export function adoptSlotRecords(mesh, rows, kept, grow) {
  const n = kept.length;
  if (mesh._radii.length < n) {
    mesh.data = new Float32Array(n * mesh.layout.numbersPerInstance);
    mesh._radii = new Float32Array(n);
    mesh._grow = new Float32Array(n);
    grow(n);
  }
  mesh._materialized = true;
  mesh._write(rows, 0);
  const m = mesh.instanceMatrix.array;
  kept.forEach((k, i) => { if (!k) { m.fill(0, 16 * i, 16 * i + 16); m[16 * i + 15] = 1; mesh._radii[i] = 0; } });
  mesh.computeBoundingSphere();
}

/** The tiles within reach of `point` ({x, z}) of a generated layer, and their key (the same set, the same key). */
export function tilesWithin(mesh, point) {
  const tiles = tilesAround(mesh.recipe.tile, point.x, point.z, mesh.recipe.reach, worldEdge(tileSize(mesh.recipe)[1]));
  return { tiles, key: tiles.map((t) => t.join(',')).sort().join(';') };
}

/** A generated layer's new density map `grid` ({data: Float32Array, cols, rows}: grey levels in 0..1) and where it
 * lies (`placement`: {d_lo, d_inv, d_wrap}, as the Python library's GroundMaps): its maps and the generator's
 * numbers (an AxialBrush's; the renderer's part then takes the map); the tiles are made again on the next update. */
export function setDensityOf(mesh, grid, placement) {
  if (!(grid && grid.data instanceof Float32Array && grid.data.length === grid.cols * grid.rows)) {
    bad('setDensity', '{data: Float32Array of cols x rows, cols, rows}', grid && grid.cols);
  }
  mesh.maps = { ...mesh.maps, density: grid };
  Object.assign(mesh.generatorUniforms, { has_density: true, d_size: [grid.cols, grid.rows], ...placement, d_wrap: !!placement.d_wrap });
  mesh._key = null;
}
