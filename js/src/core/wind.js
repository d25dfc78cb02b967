// wind.js -- the wind of glsl/wind.glsl (docs/wind.md) for a mesh: checked settings, the uniforms it
// moves, and how far it can move a vertex (the bounds grow by it).  Its defaults are record.js's,
// which come from axialdeform.core.wind.

import * as THREE from 'three';
import { AxialError } from './adp.js';
import { WIND, WIND_UNIFORMS } from './record.js';

/** {strength, gustiness, frequency, wavelength} of a user's wind ({direction, strength, ...}), each
 * checked, the defaults filled in; null for no wind (none, or strength 0). */
export function checkWind(wind) {
  if (!(wind && wind.strength > 0)) return null;
  const num = (x, what) => {
    if (!(Number.isFinite(x) && x >= 0)) throw new AxialError(`setWind: ${what}: expected a finite number >= 0, found ${x}`);
    return x;
  };
  const d = wind.direction || [1, 0, 0], n = Math.hypot(d[0], d[1], d[2]);
  if (!(n > 0 && Number.isFinite(n))) throw new AxialError(`setWind: direction: expected 3 finite numbers, not all zero, found ${d}`);
  return { direction: [d[0] / n, d[1] / n, d[2] / n], strength: num(wind.strength, 'strength'),
    gustiness: num(wind.gustiness ?? WIND.gustiness, 'gustiness'), frequency: num(wind.frequency ?? WIND.frequency, 'frequency'),
    wavelength: num(wind.wavelength ?? WIND.wavelength, 'wavelength') };
}

const VALUE = { float: () => 0, vec2: () => new THREE.Vector2(), vec3: () => new THREE.Vector3(1, 0, 0) };

/** The wind's uniforms ({axialWindDir: {value}, ...}: record.js's WIND_UNIFORMS), still (strength 0). */
export function stillWindUniforms() {
  return Object.fromEntries(WIND_UNIFORMS.map((w) => [w.three, { value: VALUE[w.type]() }]));
}

/** Set the wind's uniforms in `uniforms` (made where missing: the same objects from then on); the cycles are
 * the clock's (windCycles). */
export function setWindUniforms(uniforms, wind) {
  const values = { dir: wind.direction, strength: wind.strength, gust: wind.gustiness,
    wavenumber: wind.wavelength > 0 ? 1 / wind.wavelength : 0 };
  for (const w of WIND_UNIFORMS) {
    const u = (uniforms[w.three] ||= { value: VALUE[w.type]() });
    if (w.name in values) u.value = typeof u.value === 'number' ? values[w.name] : u.value.fromArray(values[w.name]);
  }
}

const CYCLES = WIND_UNIFORMS.find((w) => w.name === 'cycles').three;

/** The wind's clock at `t` seconds set in `uniforms` (its cycles uniform). */
export function setWindClock(uniforms, wind, t) {
  windCycles(wind, t, uniforms[CYCLES].value);
}

/** The wind's clock at `t` seconds: (frac(f t), frac(harmonic f t)), as axialdeform.core.wind. */
export function windCycles(wind, t, target) {
  const f = wind.frequency, frac = (x) => x - Math.floor(x);
  return target.set(frac(f * t), frac(WIND.harmonic * f * t));
}

/** How far the wind can move a vertex: a tip by at most strength L (1 + gustiness), every axis of a
 * tree by its own L (`lengths`); a vertex moves by its own chain only (axis, parent, ..., root), so a
 * tree's reach is its longest chain's (axialdeform.core.bounds.wind_reach); without `parents`, the sum. */
export function windReach(wind, lengths, parents = null) {
  if (!wind) return 0;
  let most = lengths.reduce((t, x) => t + x, 0);
  if (parents && parents.length === lengths.length) {
    const chain = [];
    for (let k = 0; k < lengths.length; k++) chain.push(lengths[k] + (k > 0 ? chain[parents[k]] : 0));
    most = Math.max(...chain);
  }
  return wind.strength * (1 + wind.gustiness) * most;
}
