// limits.js -- what a generated layer's recipe may ask for, checked from the recipe alone before an array
// is allocated or a pass dispatched (docs/generate.md, "Bounds"): the same bounds as
// axialdeform.core.generate (tests/app/test_generate_limits.py holds the numbers equal), so the Python
// library and this module give one verdict for one file.

import { AxialError } from './adp.js';
import { RECIPE, RECIPE_KINDS } from './record.js';

/** The most cells a tile may have (m^2). */
export const MAX_TILE_SLOTS = 1 << 20;
/** The most slots a generated mesh holds (the tiles within reach; a tree's slots count each axis); the
 * option `maxSlots` of a generated AxialInstancedMesh and AxialGLTFPlugin raises (or lowers) it. */
export const MAX_SLOTS = 1 << 22;
/** The most numbers a ground map (a height or density map) or a child-axis table may hold (4096^2). */
export const MAX_MAP_TEXELS = 1 << 24;
/** The largest bend amplitude and scale, in axis lengths. */
export const MAX_BEND = 100;
/** The world ends WORLD_CELLS cells from the origin along x and z (float32 keeps the grid to c / 128). */
export const WORLD_CELLS = 1 << 16;

const num = (v) => typeof v === 'number' && Number.isFinite(v);
const json = (v) => { try { return String(JSON.stringify(v)).slice(0, 80); } catch { return String(v).slice(0, 80); } };
function bad(field, expected, value) {
  throw new AxialError(`generate: ${field}: expected ${expected}, found ${json(value)}`);
}

const numbers = (v, n) => Array.isArray(v) && v.length === n && v.every(num);

/** Whether `v` is a value of recipe-key kind `kind` (record.js's RECIPE_KINDS): the rule of
 * axialdeform.core.recipe.accepts, kind by kind. */
export function accepts(kind, v) {
  switch (kind) {
    case 'positive': return num(v) && v > 0;
    case 'nonnegative': return num(v) && v >= 0;
    case 'below_one': return num(v) && v >= 0 && v < 1;
    case 'amount': return num(v) && v >= 0 && v <= 1;
    case 'seed': return Number.isInteger(v) && v >= 0 && v < 2 ** 32;
    case 'count': return Number.isInteger(v) && v >= 1 && v <= 256;
    case 'levels': { const b = Array.isArray(v) ? v : [v]; return b.length > 0 && b.every((x) => num(x) && x >= 0); }
    case 'rgb': return numbers(v, 3) && v.every((x) => x >= 0 && x <= 1);
    case 'anchor': return RECIPE_KINDS.anchor.words.includes(v);
    case 'quartiles': case 'octiles': return numbers(v, kind === 'quartiles' ? 3 : 4) && v[0] > 0 && v.every((x, i) => !i || v[i - 1] <= x);
    default: break;
  }
  const pair = numbers(v, 2) && v[0] <= v[1];
  if (kind === 'scale') return pair && v[0] > 0;
  if (kind === 'degrees') return pair && v[0] >= 0 && v[1] <= 90;
  if (kind === 'share') return pair && v[0] >= 0 && v[1] <= 1;
  return pair; // span
}

/** The generator's numbers a generated form may leave out (keys its first version did not carry), at their
 * values when the key is not given (axialdeform.core.recipe.optional_numbers). */
export function optionalNumbers() {
  return Object.fromEntries(RECIPE.filter((k) => k.uniform && !k.requiredJson).map((k) => [k.uniform, structuredClone(k.uniformDefault)]));
}

/** The generator's numbers recipe `r` (checked) passes into unchanged (axialdeform.core.recipe.passed_through):
 * a key the JSON form carries, its value (or its number's default when null); any other, its default. */
export function passedThrough(r) {
  return Object.fromEntries(RECIPE.filter((k) => k.uniform).map((k) => {
    const v = k.json && r[k.name] !== null && r[k.name] !== undefined ? r[k.name] : k.uniformDefault;
    return [k.uniform, structuredClone(v)];
  }));
}

/** The world's edge E = WORLD_CELLS c (world units) of a recipe whose cell side is `cell`. */
export const worldEdge = (cell) => WORLD_CELLS * cell;

/** The bounds of a recipe already checked for types (checkRecipe): its tile's cells, bend, scale, reach. */
export function checkRecipeBounds(r, m, cell) {
  if (!(r.tile * Math.sqrt(r.rate) < 4 * Math.sqrt(MAX_TILE_SLOTS)) || m * m > MAX_TILE_SLOTS) {
    const blame = r.rate * 32 * 32 <= MAX_TILE_SLOTS ? 'tile' : 'rate';
    bad(blame, `a tile of at most ${MAX_TILE_SLOTS} cells (rate x tile^2 = ${(r.rate * r.tile * r.tile).toPrecision(6)}): a smaller tile or a lower rate`, r[blame]);
  }
  for (const b of Array.isArray(r.bend) ? r.bend : [r.bend]) if (b > MAX_BEND) bad('bend', `at most ${MAX_BEND} (axis lengths)`, r.bend);
  if (r.scale !== null && r.scale[1] > MAX_BEND) bad('scale', `[lo, hi] with hi at most ${MAX_BEND}`, r.scale);
  const q = r.scale_quartiles;
  if (q && (r.scale === null || q[0] < r.scale[0] || q[2] > r.scale[1])) bad('scale_quartiles', "three numbers within scale's [lo, hi] (and a scale beside them)", q);
  const o = r.scale_octiles, knots = o && q ? [r.scale[0], o[0], q[0], o[1], q[1], o[2], q[2], o[3], r.scale[1]] : null;
  if (o && !(knots && knots.every((x, i) => !i || knots[i - 1] <= x))) bad('scale_octiles', "four numbers between scale_quartiles' (and scale's), beside them", o);
  const E = worldEdge(cell);
  if (r.reach !== undefined && !(num(r.reach) && r.reach > 0 && r.reach <= 2 * E)) {
    bad('reach', `a distance > 0 and at most the world's width ${(2 * E).toPrecision(6)}`, r.reach);
  }
}

/** The slots `tiles` tiles of m^2 cells hold, each of `axes` axes, or an AxialError above `maxSlots`. */
export function checkSlots(tiles, m, axes = 1, maxSlots = MAX_SLOTS, what = 'reach') {
  const slots = tiles * m * m;
  if (!(Number.isInteger(maxSlots) && maxSlots >= 1)) throw new AxialError(`maxSlots: expected a whole number >= 1, found ${json(maxSlots)}`);
  if (slots * axes > maxSlots) {
    throw new AxialError(`generate: ${what}: ${tiles} tiles of ${m * m} cells = ${slots}${axes > 1 ? ` x ${axes} axes` : ''} slots; `
      + `expected at most ${maxSlots} (a smaller reach, a lower rate, or raise the option maxSlots)`);
  }
  return slots;
}

const F32_MAX = 3.4028234663852886e38;
const pair = (v, test = num) => Array.isArray(v) && v.length === 2 && v.every(test);
const close = (a, b) => Math.abs(a - b) <= 1e-6 * Math.max(1, Math.abs(b));

/**
 * The generated form's `uniforms` (generate.glsl's numbers, axialdeform.core.generate.recipe_uniforms)
 * held to its recipe `r` (checked), the node's axis length and its maps' shapes ({heights, density}:
 * {cols, rows} or undefined): what follows from the recipe must equal it, the rest be finite and in range.
 * Returns nothing; throws an AxialError naming the first uniform that is off.
 */
export function checkUniforms(u, r, axisLength, maps, m, cell) {
  const off = (key, expected) => { throw new AxialError(`generate uniforms: ${key}: expected ${expected}, found ${json(u[key])}`); };
  const E = worldEdge(cell), bends = Array.isArray(r.bend) ? r.bend : [r.bend];
  const want = passedThrough(r);
  for (const k of RECIPE) { // the numbers a key goes into unchanged: its value, or (not in the JSON form) its kind's range
    if (!k.uniform) continue;
    const have = u[k.uniform], w = want[k.uniform];
    if (k.json) {
      const same = RECIPE_KINDS[k.kind].shape === 'whole' ? have === w : Array.isArray(w)
        ? Array.isArray(have) && have.length === w.length && have.every((x, i) => num(x) && close(x, w[i])) : num(have) && close(have, w);
      if (!same) off(k.uniform, `the recipe's ${k.name} ${json(w)}`);
    } else if (!accepts(k.kind, have)) {
      off(k.uniform, RECIPE_KINDS[k.kind].expected);
    }
  }
  if (u.m !== m) off('m', `the recipe's ${m} cells a side`);
  if (!(num(u.cell) && close(u.cell, cell))) off('cell', `the recipe's cell side ${cell}`);
  if (!(num(u.jitter) && close(u.jitter, 1 - r.min_distance / cell))) off('jitter', `1 - min_distance / cell = ${1 - r.min_distance / cell}`);
  if (!(num(u.bend) && Math.abs(u.bend) <= bends[0] * axisLength * (1 + 1e-6) + 1e-30)) off('bend', `the recipe's bend times the axis length, ${bends[0] * axisLength}`);
  if (!num(u.anchor_y)) off('anchor_y', 'a finite number');
  if (!(Array.isArray(u.anchor_w) && u.anchor_w.length === 4 && u.anchor_w.every((x) => num(x) && x >= 0 && x <= 1))) off('anchor_w', 'four weights in [0, 1]');
  if (!(num(u.anchor_w4) && u.anchor_w4 >= 0 && u.anchor_w4 <= 1)) off('anchor_w4', 'a weight in [0, 1]');
  if (!pair(u.anchor_xz)) off('anchor_xz', 'two finite numbers');
  for (const [has, key, size, lo, inv] of [['has_heights', 'heights', 'h_size', 'h_lo', 'h_inv'], ['has_density', 'density', 'd_size', 'd_lo', 'd_inv']]) {
    if (typeof u[has] !== 'boolean') off(has, 'true or false');
    const map = maps[key];
    if (u[has] !== Boolean(map)) off(has, map ? `true: the node has a ${key} map` : `false: the node has no ${key} map`);
    if (!pair(u[size], Number.isInteger) || (map ? u[size][0] !== map.cols || u[size][1] !== map.rows : u[size].some((x) => x !== 0))) {
      off(size, map ? `the ${key} map's [cols, rows] = [${map.cols}, ${map.rows}]` : '[0, 0]: no map');
    }
    if (!pair(u[lo], (x) => num(x) && Math.abs(x) <= 2 * E)) off(lo, `two numbers within the world, +-${(2 * E).toPrecision(6)}`);
    if (!pair(u[inv], (x) => num(x) && x > 0 && x <= F32_MAX)) off(inv, 'two float32 numbers > 0');
  }
  if (typeof u.d_wrap !== 'boolean') off('d_wrap', 'true or false');
  if (!(pair(u.altitude, (x) => typeof x === 'number' && Math.abs(x) <= 3.0e38) && u.altitude[0] <= u.altitude[1])) off('altitude', '[lo, hi] with lo <= hi');
  if (!(pair(u.slope_tan2, (x) => typeof x === 'number' && x >= 0 && x <= 3.0e38) && u.slope_tan2[0] <= u.slope_tan2[1])) off('slope_tan2', '[lo, hi] with 0 <= lo <= hi');
  if (Math.max(...u.lift.map(Math.abs)) > E) off('lift', `[lo, hi] within the world's edge +-${E.toPrecision(6)}`);
}

/** The generator's anchor (`anchor_y`, `anchor_xz`) must be one of the base mesh's three anchor points
 * (axialdeform.core.mesh.anchor_point: its bounding box's bottom face centre, its centre, its origin) to
 * 1e-6 of the axis length: what the Python reader holds it to (`positions`: Float32Array of 3 n). */
export function checkAnchor(u, positions, axisLength) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i++) {
    const c = i % 3;
    if (positions[i] < lo[c]) lo[c] = positions[i];
    if (positions[i] > hi[c]) hi[c] = positions[i];
  }
  const mid = [0, 1, 2].map((c) => Math.fround(lo[c] + hi[c]) / 2), tol = 1e-6 * axisLength;
  const fits = (p) => Math.abs(p[0] - u.anchor_xz[0]) <= tol && Math.abs(p[1] - u.anchor_y) <= tol && Math.abs(p[2] - u.anchor_xz[1]) <= tol;
  if (![[mid[0], lo[1], mid[2]], mid, [0, 0, 0]].some(fits)) {
    throw new AxialError('generate uniforms: anchor_y, anchor_xz: expected the base mesh\'s bottom, center or origin');
  }
}
