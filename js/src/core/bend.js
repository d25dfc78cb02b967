// bend.js -- the parts of the method the CPU needs in a three.js app: the
// control axis as the shader wants it, each instance's rigid placement (its
// instanceMatrix, W = R (s V'') + p with R = Rz Ry Rx) and a bounding sphere
// that holds every bent instance (three's frustum culling).  The bend itself
// runs only on the GPU, in glsl/axial.glsl (src/webgl/glsl.js): drawing, baking and
// raycasting all use it; docs/method.md states the conventions.

import { AxialError, fieldName } from './adp.js';
import { DRAWABLE_MAGNITUDE } from './record.js';

/** The rows e_a, e_u, e_v of the aligned axis x (0), y (1) or z (2): offsets go to the two other
 * coordinates in increasing order. */
export function alignedFrame(index) {
  const e = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  const other = [0, 1, 2].filter((c) => c !== index);
  return [e[index], e[other[0]], e[other[1]]];
}

function mul(f, v) { // F v, F as rows
  return [f[0][0] * v[0] + f[0][1] * v[1] + f[0][2] * v[2],
    f[1][0] * v[0] + f[1][1] * v[1] + f[1][2] * v[2],
    f[2][0] * v[0] + f[2][1] * v[1] + f[2][2] * v[2]];
}

/**
 * The base mesh's control axis as the shader wants it: {frame (rows e_a, e_u, e_v), lo, length,
 * center (the axis line: 2 numbers across the axis), axes (null, or a tree's {count, frames, lo,
 * length, parents})}.  `spec`: the AXIALDEFORM_bend extension's object, or a node's
 * userData.axialdeform.axis (`{index, lo, length, frame?}`), or null: then the header of the
 * record (an aligned axis x, y, z) and the geometry's box give it.
 */
export function resolveAxis(spec, record, positions) {
  let frame, lo, length, center = null, axes = null;
  if (spec && spec.axes) {
    const a = spec.axes;
    axes = { count: a.count ?? a.frames.length, frames: a.frames, lo: a.lo, length: a.length, parents: a.parents,
      anchors: a.anchors || null };
    if (!Array.isArray(axes.lo) || axes.lo.length !== axes.count || axes.parents.length !== axes.count) {
      throw new AxialError(`axes: expected ${axes.count} frames, lo, length and parents`);
    }
  }
  const ax = spec ? (spec.axis || spec) : null;
  if (ax && (ax.frame || Number.isInteger(ax.index))) {
    frame = ax.frame || alignedFrame(ax.index);
    if (!ax.frame && (ax.index < 0 || ax.index > 2)) throw new AxialError(`axis: index ${ax.index} without a frame`);
    lo = ax.lo; length = ax.length; center = ax.center || ax.line || null;
  } else if (axes) {
    frame = axes.frames[0]; lo = axes.lo[0]; length = axes.length[0];
  } else {
    if (!record || record.axis < 0 || record.axis > 2) {
      throw new AxialError(`${record ? record.name : 'record'}: made for ${record && record.axis === 4 ? 'several axes' : 'a chosen axis frame'}` +
        '; pass {axis} (the mesh\'s frame, lo, length: the GLB\'s extras or AXIALDEFORM_bend) to AxialInstancedMesh');
    }
    frame = alignedFrame(record.axis); lo = record.lo; length = record.length;
  }
  if (!(length > 0) || !Number.isFinite(lo)) throw new AxialError(`axis: expected a length > 0 and a finite lo, found ${length}, ${lo}`);
  if (center === null) { // the box centre across the axis, in the frame's coordinates
    const b = localBox(positions, frame);
    center = [(b[1] + b[4]) / 2, (b[2] + b[5]) / 2];
  }
  return { frame, lo, length, center, axes };
}

/** [min x y z, max x y z] of F v over the vertices (Float32Array of 3 n). */
function localBox(positions, frame) {
  const b = [Infinity, Infinity, Infinity, -Infinity, -Infinity, -Infinity];
  for (let i = 0; i < positions.length; i += 3) {
    const l = mul(frame, [positions[i], positions[i + 1], positions[i + 2]]);
    for (let c = 0; c < 3; c++) { if (l[c] < b[c]) b[c] = l[c]; if (l[c] > b[3 + c]) b[3 + c] = l[c]; }
  }
  return b;
}

/** Column-major 4x4 of W = R (s V) + p for every instance: R = Rz(rz) Ry(ry) Rx(rx). Writes into
 * `out` (Float32Array of 16 count, e.g. an InstancedMesh's instanceMatrix.array) from `first`. */
export function instanceMatrices(data, layout, count, out, first = 0) {
  const f = layout.numbersPerInstance;
  for (let i = first; i < first + count; i++) {
    const r = i * f, o = i * 16;
    const cx = Math.cos(data[r + layout.angles]), sx = Math.sin(data[r + layout.angles]);
    const cy = Math.cos(data[r + layout.angles + 1]), sy = Math.sin(data[r + layout.angles + 1]);
    const cz = Math.cos(data[r + layout.angles + 2]), sz = Math.sin(data[r + layout.angles + 2]);
    const s = layout.scale === null ? 1 : data[r + layout.scale];
    // columns of R (axial_rotation in glsl/axial.glsl), times s
    out[o] = s * cz * cy; out[o + 1] = s * sz * cy; out[o + 2] = -s * sy; out[o + 3] = 0;
    out[o + 4] = s * (cz * sy * sx - sz * cx); out[o + 5] = s * (sz * sy * sx + cz * cx); out[o + 6] = s * cy * sx; out[o + 7] = 0;
    out[o + 8] = s * (cz * sy * cx + sz * sx); out[o + 9] = s * (sz * sy * cx - cz * sx); out[o + 10] = s * cy * cx; out[o + 11] = 0;
    out[o + 12] = data[r + layout.position]; out[o + 13] = data[r + layout.position + 1];
    out[o + 14] = data[r + layout.position + 2]; out[o + 15] = 1;
  }
  return out;
}

/**
 * Bounding spheres (model space, before the rigid part) of every bent instance: a point on axis 0's
 * line, c, and radius = max |v - c| max(1, |1 - tp|) + the sum over the axes of max |d_i| (the Bézier
 * curve lies in its control points' hull; twist turns about the line; taper scales across it).
 * Returns {center: [x, y, z], radius: Float32Array(count), grow} (the centre is the same for all);
 * `grow` (when given, Float32Array) gets the sum of the max |d_i|: no vertex moves farther (without
 * twist and taper), so the base box grown by it holds the bent instance.
 */
export function bentRadii(positions, axis, data, layout, count, first = 0, out = null, grow = null) {
  const f0 = axis.frames ? axis.frames[0] : axis.frame;
  const mid = axis.lo + axis.length / 2;
  const c = [0, 1, 2].map((q) => f0[0][q] * mid + f0[1][q] * axis.center[0] + f0[2][q] * axis.center[1]);
  let r0 = 0;
  for (let v = 0; v < positions.length; v += 3) {
    const dx = positions[v] - c[0], dy = positions[v + 1] - c[1], dz = positions[v + 2] - c[2];
    r0 = Math.max(r0, dx * dx + dy * dy + dz * dz);
  }
  r0 = Math.sqrt(r0);
  const k = axis.axes ? axis.axes.count : 1, f = layout.numbersPerInstance;
  const radius = out || new Float32Array(first + count);
  for (let i = first; i < first + count; i++) {
    const r = i * f;
    const tp = layout.taper === null ? 0 : data[r + layout.taper];
    let d = 0;
    for (let j = 0; j < k; j++) {
      let m = 0;
      for (let q = 0; q < 5; q++) {
        const u = data[r + 10 * j + 2 * q], v = data[r + 10 * j + 2 * q + 1];
        m = Math.max(m, u * u + v * v);
      }
      m = Math.sqrt(m);
      d += m;
    }
    radius[i] = r0 * Math.max(1, Math.abs(1 - tp)) + d;
    if (grow) grow[i] = d;
  }
  return { center: c, radius, grow };
}

/** `data` as the checked rows of `mesh` (an AxialInstancedMesh): a Float32Array of whole rows, finite, drawable,
 * fitting its capacity from `first`. */
export function checkRows(mesh, data, first, where) {
  let rows = data;
  const L = mesh.layout, f = L.numbersPerInstance;
  if (rows && rows.data && Number.isInteger(rows.count)) {
    if (rows.numbersPerInstance !== f) {
      throw new AxialError(`${rows.name || 'record'}: ${rows.numbersPerInstance} numbers an instance, but this mesh was made for ${f}`);
    }
    rows = rows.data.subarray(0, rows.count * f);
  }
  if (!(rows instanceof Float32Array) || rows.length % f !== 0) {
    throw new AxialError(`${where}: expected a Float32Array of rows of ${f} numbers`);
  }
  const n = rows.length / f;
  if (!Number.isInteger(first) || first < 0 || first + n > mesh.capacity) {
    throw new AxialError(`${where}: instances ${first} to ${first + n - 1} do not fit a capacity of ${mesh.capacity}`);
  }
  const placed = 10 * L.axes + 3; // every axis's offsets, then the position: what the picture projects
  for (let i = 0; i < rows.length; i++) {
    if (!Number.isFinite(rows[i])) throw new AxialError(`${where}: instance ${first + Math.floor(i / f)}, number ${i % f}: not finite`);
    if (i % f < placed && Math.abs(rows[i]) > DRAWABLE_MAGNITUDE) {
      throw new AxialError(`${where}: instance ${first + Math.floor(i / f)}, field ${fieldName(i % f, L.axes)} = ${rows[i]}; expected at most ${DRAWABLE_MAGNITUDE} in magnitude to draw it (float32 cannot project it)`);
    }
  }
  return rows;
}

/** Each vertex's axes (_AXIAL_AXIS): one whole number a vertex, its axis b or, blending two chains, b + 64 b1 +
 * 4096 q (q / 2047 the second chain's weight; docs/method.md, "Blended vertices"), both axes below `axes`. */
export function checkVertexCodes(codes, axes, count) {
  if (codes.length !== count) {
    throw new AxialError(`AxialInstancedMesh: _AXIAL_AXIS: expected one number a vertex (${count}), found ${codes.length}`);
  }
  for (let i = 0; i < codes.length; i++) {
    const c = codes[i];
    if (!(Number.isInteger(c) && c >= 0 && c < 8388608 && c % 64 < axes && Math.floor(c / 64) % 64 < axes)) {
      throw new AxialError(`AxialInstancedMesh: _AXIAL_AXIS: vertex ${i}: expected an axis of 0..${axes - 1}, or b + 64 b1 + 4096 q `
        + `(both axes below ${axes}, below 2^23), found ${c}`);
    }
  }
}
