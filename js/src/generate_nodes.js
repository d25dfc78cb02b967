// generate_nodes.js -- glsl/generate.glsl as three.js node functions (TSL), for three's WebGPURenderer:
// a generated layer's instance, a pure function of (the recipe, its seed, the tile, the index), run by a
// compute pass (generated_webgpu.js).  A line-for-line port, as nodes.js is of glsl/axial.glsl: the same
// function names (camelCase), the same order of operations, the same conventions (docs/generate.md);
// the tests hold it to axialdeform.core.generate (hash bit-exact, numbers to float32 rounding).
//
// `r`: the recipe's numbers as nodes (recipeNodes: generate.glsl's AxialRecipe, the booleans plain
// JavaScript: they choose the code), `maps`: {heights, density, children} -- float textures (texel (col,
// row), red channel) read by textureLoad.

import {
  If, float, int, uint, vec2, vec3, vec4, abs, sqrt, inverseSqrt, floor, clamp, min, select, textureLoad, ivec2,
  uniform,
} from 'three/tsl';
import { Vector2, Vector3, Vector4 } from 'three/webgpu';
import { axialWindHash } from './nodes.js';

/** generate.glsl's AxialRecipe from generatorUniforms (generate.js's recipeUniforms, or the Python
 * library's): every number a uniform node, the booleans has_heights, has_density, d_wrap plain (they
 * choose the code). */
export function recipeNodes(u) {
  const v2 = (a) => uniform(new Vector2(a[0], a[1]));
  return {
    seed: uniform(u.seed, 'uint'), m: uniform(u.m, 'int'), cell: uniform(u.cell), jitter: uniform(u.jitter),
    bend: uniform(u.bend), scale: v2(u.scale), twist: uniform(u.twist), taper: uniform(u.taper),
    anchor_y: uniform(u.anchor_y), anchor_w: uniform(new Vector4(...u.anchor_w)), anchor_w4: uniform(u.anchor_w4),
    tint: uniform(u.tint), tint_color: uniform(new Vector3(...u.tint_color)), h_lo: v2(u.h_lo), h_inv: v2(u.h_inv),
    h_size: v2(u.h_size), d_lo: v2(u.d_lo), d_inv: v2(u.d_inv), d_size: v2(u.d_size), altitude: v2(u.altitude),
    slope_tan2: v2(u.slope_tan2), choice: v2(u.choice), lift: v2(u.lift), align: uniform(u.align),
    anchor_xz: v2(u.anchor_xz),
    has_heights: Boolean(u.has_heights), has_density: Boolean(u.has_density), d_wrap: Boolean(u.d_wrap),
  };
}

/** (cos x, sin x) to float32 rounding on every GPU (axial_gen_cos_sin): reduction by pi/2 (two
 * constants), Taylor polynomials on [-pi/4, pi/4], the quadrant applied exactly. */
export function axialGenCosSin(x) {
  const q = floor(x.mul(0.6366197723675814).add(0.5)).toVar();
  const r = x.sub(q.mul(1.5707963705062866)).sub(q.mul(-4.371139000186243e-8)).toVar();
  const r2 = r.mul(r).toVar();
  const s = r.mul(r2.mul(r2.mul(r2.mul(r2.mul(1.0 / 362880.0).sub(1.0 / 5040.0)).add(1.0 / 120.0)).sub(1.0 / 6.0)).add(1.0));
  const c = r2.mul(r2.mul(r2.mul(r2.mul(r2.mul(-1.0 / 3628800.0).add(1.0 / 40320.0)).sub(1.0 / 720.0)).add(1.0 / 24.0)).sub(0.5)).add(1.0);
  const m = q.sub(floor(q.mul(0.25)).mul(4.0)).toVar();
  const odd = m.equal(1.0).or(m.equal(3.0));
  const cs = select(odd, s, c).toVar(), sn = select(odd, c, s).toVar();
  return vec2(select(m.equal(1.0).or(m.equal(2.0)), cs.negate(), cs), select(m.greaterThanEqual(1.5), sn.negate(), sn)).toVar();
}

/** atan2(y, x) to a few float32 ulps on every GPU (axial_gen_atan2: Cephes' atanf). */
export function axialGenAtan2(y, x) {
  const ax = abs(x).toVar(), ay = abs(y).toVar();
  const out = float(0).toVar();
  If(ax.notEqual(0.0).or(ay.notEqual(0.0)), () => {
    const swap = ay.greaterThan(ax).toVar();
    const t = select(swap, ax.div(ay), ay.div(ax)).toVar();
    const base = float(0).toVar();
    If(t.greaterThan(0.41421356237309503), () => {
      base.assign(0.7853981633974483);
      t.assign(t.sub(1.0).div(t.add(1.0)));
    });
    const z = t.mul(t).toVar();
    const a = float(8.05374449538e-2).mul(z).sub(1.38776856032e-1).mul(z).add(1.99777106478e-1).mul(z).sub(3.33329491539e-1)
      .mul(z).mul(t).add(t).add(base).toVar();
    If(swap, () => { a.assign(float(1.5707963267948966).sub(a)); });
    If(x.lessThan(0.0), () => { a.assign(float(3.141592653589793).sub(a)); });
    out.assign(select(y.lessThan(0.0), a.negate(), a));
  });
  return out;
}

/** The turn of an instance leaning toward the ground's normal (gradient grad) by the fraction r.align,
 * after its turn ry about up (axial_gen_lean): {angles (rx, ry, rz of R = Rz Ry Rx), ay = (R a).y}. */
export function axialGenLean(r, ry, grad) {
  const inv = inverseSqrt(grad.x.mul(grad.x).add(1.0).add(grad.y.mul(grad.y))).toVar();
  const n = vec3(grad.x.negate(), 1.0, grad.y.negate()).mul(inv).toVar();
  const sn = sqrt(n.x.mul(n.x).add(n.z.mul(n.z))).toVar();
  const k = select(sn.greaterThan(1e-12), vec3(n.z, 0.0, n.x.negate()).div(sn), vec3(0.0)).toVar();
  const ta = axialGenCosSin(axialGenAtan2(sn, n.y).mul(r.align));
  const ty = axialGenCosSin(ry);
  // Rt = I + sin K + (1 - cos) K^2 (Rodrigues), its columns; m = Rt Ry, column by column
  const c1 = float(1.0).sub(ta.x).toVar();
  const rt0 = vec3(float(1.0).sub(c1.mul(k.z).mul(k.z)), ta.y.mul(k.z), c1.mul(k.x).mul(k.z)).toVar();
  const rt1 = vec3(ta.y.negate().mul(k.z), float(1.0).sub(c1.mul(k.x.mul(k.x).add(k.z.mul(k.z)))), ta.y.mul(k.x)).toVar();
  const rt2 = vec3(c1.mul(k.x).mul(k.z), ta.y.negate().mul(k.x), float(1.0).sub(c1.mul(k.x).mul(k.x))).toVar();
  const m0 = rt0.mul(ty.x).add(rt2.mul(ty.y.negate())).toVar();
  const m1 = rt1;
  const m2 = rt0.mul(ty.y).add(rt2.mul(ty.x)).toVar();
  const cy = sqrt(m0.x.mul(m0.x).add(m0.y.mul(m0.y))).toVar();
  const pitch = axialGenAtan2(m0.z.negate(), cy);
  const angles = vec3(0).toVar();
  If(cy.lessThan(1e-9), () => {
    angles.assign(vec3(axialGenAtan2(m2.y.negate(), m1.y), pitch, 0.0));
  }).Else(() => {
    angles.assign(vec3(axialGenAtan2(m1.z, m2.z), pitch, axialGenAtan2(m0.y, m0.x)));
  });
  const ay = m0.y.mul(r.anchor_xz.x).add(m1.y.mul(r.anchor_y)).add(m2.y.mul(r.anchor_xz.y));
  return { angles, ay };
}

const red = (tex, c) => textureLoad(tex, c).x;

/** The ground's height at xz on the height map's triangles (axial_gen_height): {h, grad, inside}. */
export function axialGenHeight(r, heights, xz) {
  const size = ivec2(r.h_size).toVar();
  const g = xz.sub(r.h_lo).mul(r.h_inv).toVar();
  const last = vec2(size.sub(ivec2(1))).toVar();
  const inside = g.x.greaterThanEqual(0.0).and(g.y.greaterThanEqual(0.0)).and(g.x.lessThanEqual(last.x))
    .and(g.y.lessThanEqual(last.y)).toVar();
  g.assign(clamp(g, vec2(0.0), last));
  const c = min(ivec2(floor(g)), size.sub(ivec2(2))).toVar();
  const f = g.sub(vec2(c)).toVar();
  const h00 = red(heights, c).toVar(), h01 = red(heights, c.add(ivec2(1, 0))).toVar();
  const h10 = red(heights, c.add(ivec2(0, 1))).toVar(), h11 = red(heights, c.add(ivec2(1, 1))).toVar();
  const h = float(0).toVar(), grad = vec2(0).toVar();
  If(f.x.add(f.y).lessThanEqual(1.0), () => {
    grad.assign(vec2(h01.sub(h00), h10.sub(h00)).mul(r.h_inv));
    h.assign(h00.add(f.x.mul(h01.sub(h00))).add(f.y.mul(h10.sub(h00))));
  }).Else(() => {
    grad.assign(vec2(h11.sub(h10), h11.sub(h01)).mul(r.h_inv));
    h.assign(h11.add(float(1.0).sub(f.x).mul(h10.sub(h11))).add(float(1.0).sub(f.y).mul(h01.sub(h11))));
  });
  return { h, grad, inside };
}

/** The density map's nearest pixel under xz, clamped at its edges or repeated (axial_gen_density). */
export function axialGenDensity(r, density, xz) {
  const size = ivec2(r.d_size).toVar();
  const c = ivec2(floor(xz.sub(r.d_lo).mul(r.d_inv))).toVar();
  if (r.d_wrap) c.assign(c.mod(size).add(size).mod(size));
  else c.assign(clamp(c, ivec2(0), size.sub(ivec2(1))));
  return red(density, c);
}

/** The tile's key (axial_gen_key). */
export function axialGenKey(seed, tile) {
  return axialWindHash(axialWindHash(axialWindHash(uint(tile.x)).bitXor(uint(tile.y))).bitXor(seed)).toVar();
}

/** u_k of instance i, in [0, 1): 24 bits of the hash (axial_gen_u). */
export function axialGenU(key, i, k) {
  return float(axialWindHash(key.bitXor(uint(i).mul(uint(32)).add(uint(k)))).shiftRight(uint(8))).mul(1.0 / 16777216.0);
}

/** Instance i (an int node) of tile `tile` (an ivec2 node), axial_generate: {d12, d34, d5, position,
 * angles, extra (s, tw, tp), tint, kept (1.0 or 0.0)}, nodes. */
export function axialGenerate(r, maps, tile, i) {
  const key = axialGenKey(r.seed, tile);
  const u = Array.from({ length: 22 }, (_, k) => axialGenU(key, i, k).toVar());
  const cx = float(tile.x.mul(r.m).add(i.mod(r.m))), cz = float(tile.y.mul(r.m).add(i.div(r.m)));
  const px = cx.add(0.5).add(r.jitter.mul(u[0].sub(0.5))).mul(r.cell).toVar();
  const pz = cz.add(0.5).add(r.jitter.mul(u[1].sub(0.5))).mul(r.cell).toVar();
  const angles = vec3(0.0, float(6.283185307179586).mul(u[2]), 0.0).toVar();
  const d = [0, 1, 2, 3, 4].map((q) => vec2(r.bend.mul(float(2.0).mul(u[3 + 2 * q]).sub(1.0)),
    r.bend.mul(float(2.0).mul(u[4 + 2 * q]).sub(1.0))).toVar());
  // every control point shifted by D(t_a): the anchor stays where it is put
  const at = d[0].mul(r.anchor_w.x).add(d[1].mul(r.anchor_w.y)).add(d[2].mul(r.anchor_w.z)).add(d[3].mul(r.anchor_w.w))
    .add(d[4].mul(r.anchor_w4)).toVar();
  const s = r.scale.x.add(r.scale.y.sub(r.scale.x).mul(u[13])).toVar();
  const extra = vec3(s, r.twist.mul(float(2.0).mul(u[14]).sub(1.0)), r.taper.mul(u[15]));
  const tint = r.tint_color.mul(float(1.0).sub(r.tint.mul(vec3(u[17], u[18], u[19]))));
  let h = float(0.0), grad = vec2(0.0), inside = null;
  if (r.has_heights) ({ h, grad, inside } = axialGenHeight(r, maps.heights, vec2(px, pz)));
  const t2 = grad.x.mul(grad.x).add(grad.y.mul(grad.y));
  let keep = h.greaterThanEqual(r.altitude.x).and(h.lessThanEqual(r.altitude.y)).and(t2.greaterThanEqual(r.slope_tan2.x))
    .and(t2.lessThanEqual(r.slope_tan2.y)).and(u[20].greaterThanEqual(r.choice.x)).and(u[20].lessThan(r.choice.y));
  if (inside) keep = inside.and(keep);
  if (r.has_density) keep = keep.and(u[16].lessThan(axialGenDensity(r, maps.density, vec2(px, pz))));
  const ay = r.anchor_y.toVar();
  if (r.has_heights) {
    If(r.align.greaterThan(0.0), () => {
      const lean = axialGenLean(r, angles.y, grad);
      angles.assign(lean.angles);
      ay.assign(lean.ay);
    });
  }
  const py = h.sub(ay.mul(s)).add(r.lift.x.add(r.lift.y.sub(r.lift.x).mul(u[21])));
  return { d12: vec4(d[0].sub(at), d[1].sub(at)), d34: vec4(d[2].sub(at), d[3].sub(at)), d5: d[4].sub(at),
    position: vec3(px, py, pz), angles, extra, tint, kept: select(keep, float(1.0), float(0.0)) };
}

/** Child axis j (an int node, 1 .. K-1) of instance i (axial_generate_child): its 5 offsets, vec2 nodes.
 * `children`: K - 1 rows of 26 texels, amp_j then P_j row after row. */
export function axialGenerateChild(key, i, j, children) {
  const kj = axialWindHash(key.add(uint(j))).toVar();
  const row = int(j).sub(1);
  const amp = red(children, ivec2(int(0), row)).toVar();
  const raw = [0, 1, 2, 3, 4].map((q) => vec2(axialGenU(kj, i, uint(2 * q)), axialGenU(kj, i, uint(2 * q + 1))).mul(2.0)
    .sub(1.0).mul(amp).toVar());
  return [0, 1, 2, 3, 4].map((a) => {
    let s = vec2(0.0);
    for (let b = 0; b < 5; b++) s = s.add(raw[b].mul(red(children, ivec2(int(1 + 5 * a + b), row))));
    return s.toVar();
  });
}
