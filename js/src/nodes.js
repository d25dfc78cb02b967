// nodes.js -- the bend as three.js node functions (TSL), for WebGPURenderer (three/webgpu, both its
// WebGPU and WebGL 2 backends) and its node materials.  A line-for-line port of glsl/axial.glsl and
// glsl/wind.glsl: the same function names (camelCase), the same order of operations, the same
// conventions (docs/method.md).  GLSL cannot be included in a node material's WGSL, so this port is
// the one hand-written copy of the maths in the module; the tests hold it to axialdeform.deform on
// every feature (one axis, a chosen frame, twist, taper, scale, several axes with anchors, the wind)
// through bakeAsync's compute pass, which runs these very functions (tests/web/test_webgpu.py).
//
// Values: an instance is {d12, d34, d5, position, angles, scale, twist, taper} of nodes; a frame is
// {ea, eu, ev} (its rows: local coordinates F v = (ea.v, eu.v, ev.v), axis first).

import {
  If, Loop, float, int, uint, vec2, vec3, vec4, clamp, normalize, cross, dot, max, select, textureLoad, ivec2, round,
  floatBitsToUint,
} from 'three/tsl';

/**
 * (cos x, sin x) to float32's own accuracy on every GPU: WGSL's sin and cos need only be within 2^-11
 * of the truth (SwiftShader's are ~1e-4 off), which would bend a twisted instance by 1e-4 L.  Cody-Waite
 * reduction by pi/2 (two constants), Taylor polynomials on [-pi/4, pi/4] (truncation < 4e-10), the
 * quadrant applied exactly.  `x` a float node or a vec3 node (component by component).
 */
export function axialCosSin(x) {
  const q = round(x.mul(0.6366197723675814)).toVar();
  const r = x.sub(q.mul(1.5707963705062866)).sub(q.mul(-4.371139000186243e-8)).toVar();
  const r2 = r.mul(r).toVar();
  const s = r.mul(r2.mul(r2.mul(r2.mul(r2.mul(1.0 / 362880).sub(1.0 / 5040)).add(1.0 / 120)).sub(1.0 / 6)).add(1));
  const c = r2.mul(r2.mul(r2.mul(r2.mul(r2.mul(-1.0 / 3628800).add(1.0 / 40320)).sub(1.0 / 720)).add(1.0 / 24)).sub(0.5)).add(1);
  const m = q.sub(q.div(4).floor().mul(4)).toVar(); // the quadrant, 0..3
  const odd = m.equal(1).or(m.equal(3)), neg = m.greaterThanEqual(1.5);
  const cs = select(odd, s, c), sn = select(odd, c, s);
  return { cos: select(m.equal(1).or(m.equal(2)), cs.negate(), cs).toVar(), sin: select(neg, sn.negate(), sn).toVar() };
}

/** F v: the local coordinates (axis first) of v in frame f. */
export function axialLocal(f, v) {
  return vec3(dot(f.ea, v), dot(f.eu, v), dot(f.ev, v));
}

/** F^T x: local coordinates back to model space. */
export function axialBack(f, x) {
  return f.ea.mul(x.x).add(f.eu.mul(x.y)).add(f.ev.mul(x.z));
}

/** The displacement D(t) = sum B4_i(t) d_{i+1} (axial_curve). */
export function axialCurve(t, d12, d34, d5) {
  const s = float(1).sub(t).toVar();
  const d1 = d12.xy, d2 = d12.zw, d3 = d34.xy, d4 = d34.zw;
  return d1.mul(s.mul(s).mul(s).mul(s))
    .add(d2.mul(float(4).mul(t).mul(s).mul(s).mul(s)))
    .add(d3.mul(float(6).mul(t).mul(t).mul(s).mul(s)))
    .add(d4.mul(float(4).mul(t).mul(t).mul(t).mul(s)))
    .add(d5.mul(t.mul(t).mul(t).mul(t)));
}

/** The slope D'(t) (axial_slope). */
export function axialSlope(t, d12, d34, d5) {
  const s = float(1).sub(t).toVar();
  const d1 = d12.xy, d2 = d12.zw, d3 = d34.xy, d4 = d34.zw;
  return d2.sub(d1).mul(s.mul(s).mul(s))
    .add(d3.sub(d2).mul(float(3).mul(t).mul(s).mul(s)))
    .add(d4.sub(d3).mul(float(3).mul(t).mul(t).mul(s)))
    .add(d5.sub(d4).mul(t.mul(t).mul(t)))
    .mul(4);
}

/** The twist and taper of the cross-section at t (axial_turn): {k, c, s, rw}. */
export function axialTurn(t, w, inst) {
  const k = float(1).sub(inst.taper.mul(t)).toVar();
  // an instance without twist (most) skips the sine and cosine: exactly c = 1, s = 0, rw = w
  const c = float(1).toVar(), s = float(0).toVar(), rw = vec2(w).toVar();
  If(inst.twist.notEqual(0), () => {
    const cs = axialCosSin(inst.twist.mul(t));
    c.assign(cs.cos);
    s.assign(cs.sin);
    rw.assign(vec2(c.mul(w.x).sub(s.mul(w.y)), s.mul(w.x).add(c.mul(w.y))));
  });
  return { k, c, s, rw };
}

/** g = D'(t) + k tw Rot(w turned by 90 degrees) - tp Rot w (axial_turn_rate). */
export function axialTurnRate(slope, k, rw, inst) {
  return slope.add(vec2(rw.y.negate(), rw.x).mul(k.mul(inst.twist)).sub(rw.mul(inst.taper)));
}

/** Bend model-space v and unit n along one axis of frame f (axial_bend with a frame): {v, n}. */
export function axialBend(v, n, f, lo, len, center, inst) {
  const l = axialLocal(f, v).toVar(), ln = axialLocal(f, n).toVar();
  const t = clamp(l.x.sub(lo).div(len), 0, 1).toVar();
  const disp = axialCurve(t, inst.d12, inst.d34, inst.d5);
  const slope = axialSlope(t, inst.d12, inst.d34, inst.d5);
  const w = l.yz.sub(center).toVar();
  const { k, c, s, rw } = axialTurn(t, w, inst);
  const moved = axialBack(f, vec3(0, rw.mul(k).sub(w).add(disp)));
  const nw = ln.yz;
  const g = axialTurnRate(slope, k, rw, inst).toVar();
  const across = vec2(c.mul(nw.x).sub(s.mul(nw.y)), s.mul(nw.x).add(c.mul(nw.y))).toVar();
  const along = k.mul(ln.x).sub(dot(g, across).div(len));
  return { v: v.add(moved), n: axialBack(f, normalize(vec3(along, across))) };
}

/** The model-space part of a tangent through the bend (axial_bend_tangent with a frame; not normalised). */
export function axialBendTangent(v, tangent, f, lo, len, center, inst) {
  const l = axialLocal(f, v).toVar(), lt = axialLocal(f, tangent).toVar();
  const t = clamp(l.x.sub(lo).div(len), 0, 1).toVar();
  const { k, c, s, rw } = axialTurn(t, l.yz.sub(center), inst);
  const g = axialTurnRate(axialSlope(t, inst.d12, inst.d34, inst.d5), k, rw, inst);
  const tw = lt.yz;
  const across = vec2(c.mul(tw.x).sub(s.mul(tw.y)), s.mul(tw.x).add(c.mul(tw.y))).mul(k).add(g.mul(lt.x.div(len)));
  return axialBack(f, vec3(lt.x, across));
}

/** The columns of R = Rz(rz) Ry(ry) Rx(rx) (axial_rotation). */
export function axialRotation(r) {
  const cx = axialCosSin(r.x), cy = axialCosSin(r.y), cz = axialCosSin(r.z);
  const c = vec3(cx.cos, cy.cos, cz.cos).toVar(), s = vec3(cx.sin, cy.sin, cz.sin).toVar();
  return [
    vec3(c.z.mul(c.y), s.z.mul(c.y), s.y.negate()).toVar(),
    vec3(c.z.mul(s.y).mul(s.x).sub(s.z.mul(c.x)), s.z.mul(s.y).mul(s.x).add(c.z.mul(c.x)), c.y.mul(s.x)).toVar(),
    vec3(c.z.mul(s.y).mul(c.x).add(s.z.mul(s.x)), s.z.mul(s.y).mul(c.x).sub(c.z.mul(s.x)), c.y.mul(c.x)).toVar(),
  ];
}

const times = (cols, x) => cols[0].mul(x.x).add(cols[1].mul(x.y)).add(cols[2].mul(x.z));
const timesT = (cols, x) => vec3(dot(cols[0], x), dot(cols[1], x), dot(cols[2], x));

/** The rigid part: W = R (s V'') + p, normal R n'' (axial_place): {v, n, rot (columns of R or s R)}.
 * With inst.matrix (the columns of s R and p, made on the CPU in double precision as three's
 * instanceMatrix is), the matrix places; without it, R comes from inst.angles here. */
export function axialPlace(bentV, bentN, inst) {
  if (inst.matrix) {
    const m = inst.matrix;
    return { v: times(m, bentV).add(m[3]), n: normalize(times(m, bentN)), rot: m };
  }
  const rot = axialRotation(inst.angles);
  return { v: times(rot, bentV.mul(inst.scale)).add(inst.position), n: times(rot, bentN), rot };
}

// ---- the wind (glsl/wind.glsl) ----

/** PCG hash of an instance index (axial_wind_hash): integer maths, exact on every GPU. */
export function axialWindHash(i) {
  const h = uint(i).mul(uint(747796405)).add(uint(2891336453)).toVar();
  h.assign(h.shiftRight(h.shiftRight(uint(28)).add(uint(4))).bitXor(h).mul(uint(277803737)));
  return h.shiftRight(uint(22)).bitXor(h);
}

/** A generated instance's lasting identity (axial_position_id): the float32 bits of its x and z hashed. */
export function axialPositionId(p) {
  return axialWindHash(floatBitsToUint(p.x).bitXor(axialWindHash(floatBitsToUint(p.z))));
}

/** The instance's phase in [0, 1) (axial_wind_phase). */
export function axialWindPhase(id) {
  return float(axialWindHash(id).shiftRight(uint(8))).mul(1.0 / 16777216.0);
}

/** The wind's push on instance `inst` (index id) in its model frame (axial_wind_push); w: the wind's
 * uniforms {dir, strength, gust, cycles, wavenumber}. */
export function axialWindPush(inst, id, len, w) {
  const ph = axialWindPhase(id).sub(dot(inst.position, w.dir).mul(w.wavenumber)).toVar();
  const wave = axialCosSin(w.cycles.x.add(ph).mul(6.283185307179586)).sin.mul(0.6)
    .add(axialCosSin(w.cycles.y.add(ph.mul(1.7)).mul(6.283185307179586)).sin.mul(0.4));
  const amp = w.strength.mul(len).mul(float(1).add(w.gust.mul(wave)));
  return timesT(axialRotation(inst.angles), w.dir).mul(amp);
}

/** The instance as the wind bends it along frame f (axial_wind): d3 += u/6, d4 += u/2, d5 += u. */
export function axialWind(inst, id, f, len, w) {
  const u = axialLocal(f, axialWindPush(inst, id, len, w)).yz.toVar();
  return { ...inst, d34: inst.d34.add(vec4(u.mul(1.0 / 6.0), u.mul(0.5))), d5: inst.d5.add(u) };
}

// ---- several axes (axial_tree_world) ----

const T_SLACK = 1e-4; // AXIAL_T_SLACK
const AXES_ROW = 4095; // AXIAL_AXES_ROW: texels a row of the child offsets' texture

/** Axis j of the axes texture (rows: (e_a, lo), (e_u, len), (e_v, anchor), (parent, 0, 0, 0)). */
function treeAxis(axesTex, j) {
  const r0 = textureLoad(axesTex, ivec2(0, j)).toVar(), r1 = textureLoad(axesTex, ivec2(1, j)).toVar();
  const r2 = textureLoad(axesTex, ivec2(2, j)).toVar(), r3 = textureLoad(axesTex, ivec2(3, j));
  return { f: { ea: r0.xyz, eu: r1.xyz, ev: r2.xyz }, lo: r0.w, len: r1.w, anchor: r2.w, parent: int(r3.x) };
}

/**
 * The whole map of a K-axis mesh (axial_tree_world): model-space v of axis b (an int node) and n ->
 * {v, n, jac (columns)} in the mesh's space.  children: the child offsets' texture (the mesh's
 * axialChildren) or a function of a texel's index (an int node) giving it (a storage buffer's), id: the instance (int node), wind: the push per unit of axis length (a vec3 node)
 * or null.
 */
export function axialTreeWorld(v, n, b, K, axesTex, center, inst, children, id, wind) {
  const moved = vec3(v).toVar();
  const c0 = vec3(1, 0, 0).toVar(), c1 = vec3(0, 1, 0).toVar(), c2 = vec3(0, 0, 1).toVar();
  If(inst.twist.notEqual(0).or(inst.taper.notEqual(0)), () => { // about axis 0's line, before the displacements
    const a0 = treeAxis(axesTex, int(0)), f0 = a0.f;
    const l = axialLocal(f0, v).toVar();
    const raw = l.x.sub(a0.lo).div(a0.len).toVar();
    const t = clamp(raw, 0, 1);
    const w = l.yz.sub(center).toVar();
    const { k, c, s, rw } = axialTurn(t, w, inst);
    moved.addAssign(axialBack(f0, vec3(0, rw.mul(k).sub(w))));
    const inside = raw.greaterThanEqual(-T_SLACK).and(raw.lessThanEqual(1 + T_SLACK));
    const g = select(inside, axialTurnRate(vec2(0), k, rw, inst).div(a0.len), vec2(0)).toVar();
    // J = F^T jl F: column i is F^T jl (F's column i); jl's columns (1, g), (0, k c, k s), (0, -k s, k c)
    const jl = (x) => vec3(x.x, g.x.mul(x.x).add(k.mul(c).mul(x.y)).sub(k.mul(s).mul(x.z)),
      g.y.mul(x.x).add(k.mul(s).mul(x.y)).add(k.mul(c).mul(x.z)));
    c0.assign(axialBack(f0, jl(vec3(f0.ea.x, f0.eu.x, f0.ev.x))));
    c1.assign(axialBack(f0, jl(vec3(f0.ea.y, f0.eu.y, f0.ev.y))));
    c2.assign(axialBack(f0, jl(vec3(f0.ea.z, f0.eu.z, f0.ev.z))));
  });
  const disp = vec3(0).toVar();
  const j = int(b).toVar();
  Loop(K, () => {
    If(j.greaterThanEqual(int(0)), () => {
      const ax = treeAxis(axesTex, j);
      const d12 = vec4(inst.d12).toVar(), d34 = vec4(inst.d34).toVar(), d5 = vec2(inst.d5).toVar();
      If(j.greaterThan(int(0)), () => {
        const i = id.mul(int(K - 1)).add(j).sub(int(1)).mul(int(3)).toVar();
        if (typeof children === 'function') { // texel i of a storage buffer (a generated mesh's)
          d12.assign(children(i));
          d34.assign(children(i.add(int(1))));
          d5.assign(children(i.add(int(2))).xy);
        } else {
          const at = ivec2(i.sub(i.div(int(AXES_ROW)).mul(int(AXES_ROW))), i.div(int(AXES_ROW))).toVar();
          d12.assign(textureLoad(children, at));
          d34.assign(textureLoad(children, at.add(ivec2(1, 0))));
          d5.assign(textureLoad(children, at.add(ivec2(2, 0))).xy);
        }
        if (wind) {
          const a = ax.anchor.toVar();
          const u = axialLocal(ax.f, wind).yz.mul(ax.len).div(max(a.mul(a), float(1).sub(a).mul(float(1).sub(a)))).toVar();
          d12.addAssign(vec4(u.mul(a.mul(a)), u.mul(a.mul(a).sub(a.mul(0.5)))));
          d34.addAssign(vec4(u.mul(float(1.0 / 6.0).sub(a).add(a.mul(a))), u.mul(float(0.5).sub(a.mul(1.5)).add(a.mul(a)))));
          d5.addAssign(u.mul(float(1).sub(a).mul(float(1).sub(a))));
        }
      });
      // axial_axis_add: the axis's displacement and, where t is not clamped, its Jacobian term
      const raw = axialLocal(ax.f, v).x.sub(ax.lo).div(ax.len).toVar();
      const t = clamp(raw, 0, 1).toVar();
      disp.addAssign(axialBack(ax.f, vec3(0, axialCurve(t, d12, d34, d5))));
      If(raw.greaterThanEqual(-T_SLACK).and(raw.lessThanEqual(1 + T_SLACK)), () => {
        const a = axialBack(ax.f, vec3(0, axialSlope(t, d12, d34, d5).div(ax.len))).toVar();
        c0.addAssign(a.mul(ax.f.ea.x));
        c1.addAssign(a.mul(ax.f.ea.y));
        c2.addAssign(a.mul(ax.f.ea.z));
      });
      j.assign(ax.parent);
    });
  });
  moved.addAssign(disp);
  const cof = cross(c1, c2).mul(n.x).add(cross(c2, c0).mul(n.y)).add(cross(c0, c1).mul(n.z)); // cof(J) n
  return { v: moved, n: normalize(cof), jac: [c0, c1, c2] };
}

/** J x for the tree's Jacobian columns (tangents). */
export function axialJacobianTimes(jac, x) {
  return times(jac, x);
}
