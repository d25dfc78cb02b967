// compute.js -- bending on the GPU for axialdeform-three/webgpu (bendAsync, and through it bakeAsync
// and raycastAsync): one compute pass (WebGPU compute; transform feedback under three's WebGL 2
// fallback) running the node functions the materials draw with (nodes.js through the mesh's _bend),
// its inputs in float textures (every backend reads them at any index), read back asynchronously.

import * as THREE from 'three/webgpu';
import { Fn, If, instanceIndex, uniform, textureLoad, ivec2, int, vec4, instancedArray } from 'three/tsl';
import { AxialError } from '../core/adp.js';

// the first three whose WebGL 2 fallback keeps compute passes apart (before it, a second kernel's
// transform feedback could write into another's buffers: measured with r171 to r186)
const COMPUTE_FALLBACK_REVISION = 187;

const ROW = 4096; // texels a row of the compute pass's input textures

function floatTexture(texels) {
  const w = Math.max(1, Math.min(texels, ROW)), h = Math.max(1, Math.ceil(texels / ROW));
  const tex = new THREE.DataTexture(new Float32Array(w * h * 4), w, h, THREE.RGBAFormat, THREE.FloatType);
  tex.minFilter = tex.magFilter = THREE.NearestFilter;
  tex.needsUpdate = true;
  return tex;
}

const texel = (tex, i) => textureLoad(tex, ivec2(i.sub(i.div(int(ROW)).mul(int(ROW))), i.div(int(ROW))));

/** bendAsync of axialdeform-three/webgpu's AxialInstancedMesh (webgpu.js documents it). */
export async function bendAsync(mesh, renderer, ids = null) {
  if (!renderer || !renderer.isWebGPURenderer) {
    throw new AxialError('bendAsync: expected three\'s WebGPURenderer (or draw the mesh once with one first)');
  }
  if (renderer.init && !renderer._initialized) await renderer.init();
  if (!renderer.backend.isWebGPUBackend && Number(THREE.REVISION) < COMPUTE_FALLBACK_REVISION) {
    throw new AxialError(`bendAsync: three r${THREE.REVISION}'s WebGL 2 fallback mixes up the results of compute passes `
      + `(three r${COMPUTE_FALLBACK_REVISION} is the first where it does not); bending on the GPU for bakeAsync and `
      + 'raycastAsync needs WebGPU or a newer three there');
  }
  const g = mesh.geometry, V = g.getAttribute('position').count;
  const list = ids ? Array.from(ids) : Array.from({ length: mesh.count }, (_, i) => i);
  const n = list.length, total = n * V, tangent = g.getAttribute('tangent');
  if (n === 0) return { ids: list, V, positions: new Float32Array(0), normals: new Float32Array(0), tangents: null };
  const pass = computePass(mesh, total, V, Boolean(tangent));
  // inputs: the vertices (w: the vertex's axis; then the normals, the tangents), the instances (8 texels each:
  // d12, d34, (d5, tw, tp), (angles, id), the columns of the instance matrix)
  const pos = g.getAttribute('position'), nrm = g.getAttribute('normal');
  const va = mesh.vertexAxis;
  for (let v = 0; v < V; v++) {
    pass.verts.image.data.set([pos.getX(v), pos.getY(v), pos.getZ(v), va ? va[v] : 0], 4 * v);
    pass.verts.image.data.set([nrm.getX(v), nrm.getY(v), nrm.getZ(v), 0], 4 * (V + v));
    if (tangent) pass.verts.image.data.set([tangent.getX(v), tangent.getY(v), tangent.getZ(v), tangent.getW(v)], 4 * (2 * V + v));
  }
  const a = g.attributes, out = pass.insts.image.data;
  for (let k = 0; k < n; k++) {
    const i = list[k], o = 32 * k;
    out.set(a.axialD12.array.subarray(4 * i, 4 * i + 4), o);
    out.set(a.axialD34.array.subarray(4 * i, 4 * i + 4), o + 4);
    out.set([a.axialD5.array[2 * i], a.axialD5.array[2 * i + 1], a.axialTwistTaper.array[2 * i], a.axialTwistTaper.array[2 * i + 1]], o + 8);
    out.set([...a.axialAngles.array.subarray(3 * i, 3 * i + 3), i], o + 12);
    out.set(mesh.instanceMatrix.array.subarray(16 * i, 16 * i + 16), o + 16);
  }
  pass.verts.needsUpdate = true;
  pass.insts.needsUpdate = true;
  pass.V.value = V;
  pass.n.value = n;
  await renderer.computeAsync(pass.kernel);
  const read = async (buf) => new Float32Array((await renderer.getArrayBufferAsync(buf.value)).slice(0, total * 16));
  return { ids: list, V, positions: await read(pass.outP), normals: await read(pass.outN),
    tangents: tangent ? await read(pass.outT) : null };
}

/** The compute pass of bendAsync for `total` vertices (kept while the size and the wind stay). */
function computePass(mesh, total, V, tangent) {
  const key = `${total}:${V}:${Boolean(mesh._wind)}:${tangent}`;
  if (mesh._compute && mesh._compute.key === key) return mesh._compute;
  releaseCompute(mesh);
  const count = total / V;
  const verts = floatTexture(V * (tangent ? 3 : 2)), insts = floatTexture(8 * count);
  const outP = instancedArray(total, 'vec4'), outN = instancedArray(total, 'vec4');
  const outT = tangent ? instancedArray(total, 'vec4') : null;
  const Vn = uniform(V, 'int'), nn = uniform(count, 'int');
  const kernel = Fn(() => {
    const k = int(instanceIndex).toVar();
    const slot = k.div(Vn).toVar(), vert = k.sub(slot.mul(Vn)).toVar();
    If(slot.lessThan(nn), () => {
      const p = texel(verts, vert).toVar(), nr = texel(verts, vert.add(Vn)).xyz;
      const tg = tangent ? texel(verts, vert.add(Vn.mul(int(2)))) : null;
      const at = slot.mul(int(8)).toVar(), q = (c) => texel(insts, at.add(int(c))).toVar();
      const q2 = q(2), q3 = q(3), matrix = [4, 5, 6, 7].map((c) => q(c).xyz);
      const inst = { d12: q(0), d34: q(1), d5: q2.xy, twist: q2.z, taper: q2.w, angles: q3.xyz, matrix,
        position: matrix[3] };
      const id = int(q3.w);
      const r = mesh._bend(inst, id, p.xyz, nr, tg ? tg.xyz : null,
        mesh.axis.axes ? int(p.w.add(0.5)) : null);
      outP.element(k).assign(vec4(r.v, 1));
      outN.element(k).assign(vec4(r.n, 0));
      if (outT) outT.element(k).assign(vec4(r.t, tg.w));
    });
  })().compute(total);
  mesh._compute = { key, kernel, verts, insts, outP, outN, outT, V: Vn, n: nn };
  return mesh._compute;
}

/** Frees the compute pass's textures. */
export function releaseCompute(mesh) {
  if (!mesh._compute) return;
  mesh._compute.verts.dispose();
  mesh._compute.insts.dispose();
  mesh._compute = null;
}
