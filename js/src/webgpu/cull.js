// cull.js -- GPU culling and level of detail for axialdeform-three/webgpu's AxialInstancedMesh under
// WebGPURenderer's WebGPU backend: a compute pass a frame, one invocation a block of 64 instances near each
// other (core/cull.js's blocks, made on the CPU when the instances change), tests the block's sphere against
// the camera's frustum: a block outside is done, a block wholly inside takes every instance, and in a block
// the frustum cuts each instance's bend-aware bounding sphere (the one the mesh's CPU bounds and the Python
// library's culling use: the base mesh's sphere grown by the sum of the largest offsets, through the
// instance's matrix, grown by the wind's reach) is tested.  Each instance taken gets its level by distance
// and its id appended to that level's list, counting into the indirect draw arguments; each level draws its
// list with one indirect draw.  The CPU sets six planes and a camera position, zeroes the counts (20 bytes a
// level uploaded) and dispatches one pass -- none when the camera, the mesh and its instances are where the
// last pass saw them (its lists still stand).

import * as THREE from 'three/webgpu';
import { Fn, If, Loop, storage, uniform, uniformArray, instanceIndex, uint, int, atomicAdd, dot, bool } from 'three/tsl';
import { AxialError } from '../core/adp.js';
import { InstanceBlocks, BLOCK } from '../core/cull.js';

const _inv = new THREE.Matrix4();

/**
 * GPU culling of `mesh` (an AxialInstancedMesh of axialdeform-three/webgpu) in `levels`:
 * [{geometry, distance}] by increasing distance (an instance whose bounding sphere's centre is nearer
 * than `distance` to the camera is drawn with that level's geometry; beyond the last, not at all;
 * default: the mesh's own geometry at any distance).  Every level's geometry carries the attributes the
 * bend reads (position, normal; _axial_axis for several axes).
 */
export class GPUCulling {
  constructor(mesh, levels = null) {
    levels = levels || [{ geometry: mesh.geometry, distance: Infinity }];
    if (!Array.isArray(levels) || levels.length === 0 || levels.length > 8) {
      throw new AxialError('setGPUCulling: levels: expected 1 to 8 {geometry, distance} by increasing distance');
    }
    levels.forEach((l, k) => {
      if (!l || !l.geometry || !l.geometry.isBufferGeometry || !l.geometry.getAttribute('position') || !l.geometry.getAttribute('normal')) {
        throw new AxialError(`setGPUCulling: levels[${k}].geometry: expected a BufferGeometry with position and normal`);
      }
      if (!(l.distance > 0) || (k > 0 && !(l.distance > levels[k - 1].distance))) {
        throw new AxialError(`setGPUCulling: levels[${k}].distance: expected a number > 0, larger than the level before, found ${l.distance}`);
      }
      if (mesh.axis.axes && !l.geometry.getAttribute('axialAxis') && !l.geometry.getAttribute('_axial_axis')) {
        throw new AxialError(`setGPUCulling: levels[${k}].geometry: a mesh of several axes needs each vertex's axis (_axial_axis)`);
      }
    });
    this.mesh = mesh;
    const cap = mesh.capacity, L = levels.length, nb = Math.ceil(cap / BLOCK);
    this.capacity = cap;
    this.blocks = new InstanceBlocks(mesh);
    // storage: the instances' packed numbers (the same array as the vertex buffer's), their spheres without the
    // wind and scales (the blocks' arrays: the wind's reach, grow x scale, is added in the pass), each level's
    // visible ids, the indirect draw arguments (5 numbers a level)
    this.instancesAttr = new THREE.StorageBufferAttribute(mesh._packed.array, 4);
    this.boundsAttr = new THREE.StorageBufferAttribute(this.blocks.spheres, 4);
    this.scalesAttr = new THREE.StorageBufferAttribute(this.blocks.scales, 1);
    this.orderAttr = new THREE.StorageBufferAttribute(this.blocks.order, 1); // the instances block after block
    this.blocksAttr = new THREE.StorageBufferAttribute(this.blocks.blocks, 4); // (centre, radius), (scale, first, end, 0)
    this.idsAttr = new THREE.StorageBufferAttribute(new Uint32Array(cap * L), 1);
    const args = new Uint32Array(5 * L);
    levels.forEach((l, k) => { args[5 * k] = l.geometry.index ? l.geometry.index.count : l.geometry.getAttribute('position').count; });
    this.argsAttr = new THREE.IndirectStorageBufferAttribute(args, 5);
    const counts = storage(this.argsAttr, 'uint', 5 * L).toAtomic();
    const bounds = storage(this.boundsAttr, 'vec4', cap).toReadOnly(), scales = storage(this.scalesAttr, 'float', cap).toReadOnly();
    const order = storage(this.orderAttr, 'uint', cap).toReadOnly(), blocks = storage(this.blocksAttr, 'vec4', 2 * nb).toReadOnly();
    const ids = storage(this.idsAttr, 'uint', cap * L);
    this.planes = uniformArray(Array.from({ length: 6 }, () => new THREE.Vector4()), 'vec4');
    this.eye = uniform(new THREE.Vector3());
    this.blockCount = uniform(0, 'uint');
    this.grow = uniform(0);
    this.distances = levels.map((l) => uniform(Number.isFinite(l.distance) ? l.distance : 3.4e38));
    const planeTest = (c, r) => { // [outside some plane, cut by some plane] of a sphere (c, r)
      let out = null, cut = null;
      for (let p = 0; p < 6; p++) {
        const plane = this.planes.element(int(p)), d = dot(plane.xyz, c).add(plane.w);
        const o = d.lessThan(r.negate()), k = d.lessThan(r);
        out = out ? out.or(o) : o;
        cut = cut ? cut.or(k) : k;
      }
      return [out, cut];
    };
    this.cull = Fn(() => {
      const b = instanceIndex.toVar();
      If(b.lessThan(this.blockCount), () => {
        const head = blocks.element(b.mul(uint(2))).toVar(), tail = blocks.element(b.mul(uint(2)).add(uint(1))).toVar();
        const [out, cut] = planeTest(head.xyz, head.w.add(this.grow.mul(tail.x)));
        const whole = cut.not().toVar();
        If(out.not(), () => {
          Loop({ start: int(tail.y), end: int(tail.z), type: 'int', condition: '<' }, ({ i: j }) => {
            const i = order.element(j).toVar(), s = bounds.element(i).toVar();
            const inside = bool(whole).or(planeTest(s.xyz, s.w.add(this.grow.mul(scales.element(i))))[0].not());
            If(inside, () => {
              const d = s.xyz.sub(this.eye).length().toVar();
              const level = int(L).toVar();
              for (let k = L - 1; k >= 0; k--) If(d.lessThan(this.distances[k]), () => { level.assign(int(k)); });
              If(level.lessThan(int(L)), () => {
                const slot = atomicAdd(counts.element(uint(level).mul(uint(5)).add(uint(1))), uint(1)).toVar();
                ids.element(uint(level).mul(uint(cap)).add(slot)).assign(i);
              });
            });
          });
        });
      });
    })().compute(nb);
    // the levels: one plain mesh each, drawing its list of ids by one indirect draw
    const idsRead = storage(this.idsAttr, 'uint', cap * L).toReadOnly();
    const instances = storage(this.instancesAttr, 'vec4', this.instancesAttr.count).toReadOnly();
    this.levels = levels.map((l, k) => {
      const g = new THREE.BufferGeometry();
      if (l.geometry.index) g.setIndex(l.geometry.index);
      for (const [name, attr] of Object.entries(l.geometry.attributes)) {
        if (name === '_axial_axis') g.setAttribute('axialAxis', attr);
        else if (!name.startsWith('axial') || name === 'axialAxis') g.setAttribute(name, attr);
      }
      for (const grp of l.geometry.groups) g.addGroup(grp.start, grp.count, grp.materialIndex);
      g.setIndirect(this.argsAttr, 20 * k);
      const culled = { ids: idsRead, level: k, capacity: cap, stride: mesh._packed.stride, instances, geometry: g };
      const materials = (Array.isArray(mesh.material) ? mesh.material : [mesh.material]).map((m) => {
        const c = m.clone();
        c.positionNode = mesh._positionNode(culled);
        return c;
      });
      const drawn = new THREE.Mesh(g, Array.isArray(mesh.material) ? materials : materials[0]);
      drawn.name = `${mesh.name || 'axial'} (GPU-culled level ${k})`;
      drawn.frustumCulled = false; // each instance is culled on the GPU
      drawn.castShadow = mesh.castShadow;
      drawn.receiveShadow = mesh.receiveShadow;
      drawn.raycast = () => {}; // the instanced mesh answers
      drawn.userData.culled = culled;
      return drawn;
    });
    // the pass runs before the first level is drawn, for the camera drawing it
    this.levels[0].onBeforeRender = (renderer, scene, camera) => this.frame(renderer, camera);
    this.updateBounds(0, mesh.count);
  }

  /** Instances first .. first + count - 1 changed: their spheres and the blocks' (core/cull.js), for the pass. */
  updateBounds(first, count) {
    this._lastView = null; // the next frame culls again
    this.blocks.fill(first, count);
    this.boundsAttr.needsUpdate = true;
    this.scalesAttr.needsUpdate = true;
    this.instancesAttr.needsUpdate = true;
  }

  /** The frame's pass: the camera's planes and position in the mesh's space, the counts zeroed, one dispatch. */
  frame(renderer, camera) {
    const mesh = this.mesh;
    if (!renderer.backend || !renderer.backend.isWebGPUBackend) {
      throw new AxialError('setGPUCulling: GPU culling reads storage buffers in the vertex stage, which WebGPURenderer\'s '
        + 'WebGL 2 fallback has not; draw with the WebGPU backend, or turn it off (mesh.setGPUCulling(false))');
    }
    if (this.blocks.refresh()) { this.orderAttr.needsUpdate = true; this.blocksAttr.needsUpdate = true; }
    this.blocks.planes(camera).forEach((p, k) => this.planes.array[k].set(p.normal.x, p.normal.y, p.normal.z, p.constant));
    _inv.copy(mesh.matrixWorld).invert();
    this.eye.value.setFromMatrixPosition(camera.matrixWorld).applyMatrix4(_inv);
    this.blockCount.value = this.blocks.count;
    this.grow.value = mesh._windGrow || 0;
    // the same view of the same instances as the last pass (a camera at rest): its lists and counts still stand
    const e = this.eye.value, view = [...this.planes.array.flatMap((p) => [p.x, p.y, p.z, p.w]), e.x, e.y, e.z,
      this.blockCount.value, this.grow.value].join();
    if (view === this._lastView) return;
    this._lastView = view;
    // the counts start at 0: the arguments uploaded again (20 bytes a level) before the pass counts into them
    for (let k = 1; k < this.argsAttr.array.length; k += 5) this.argsAttr.array[k] = 0;
    this.argsAttr.needsUpdate = true;
    renderer.compute(this.cull);
  }

  /** The levels' materials' positionNode again (the wind came or went). */
  rebend() {
    for (const drawn of this.levels) {
      const node = this.mesh._positionNode(drawn.userData.culled);
      (Array.isArray(drawn.material) ? drawn.material : [drawn.material]).forEach((m) => { m.positionNode = node; m.needsUpdate = true; });
    }
  }

  dispose() {
    for (const drawn of this.levels) {
      drawn.geometry.dispose();
      (Array.isArray(drawn.material) ? drawn.material : [drawn.material]).forEach((m) => m.dispose());
    }
    this.cull.dispose();
  }
}

