// webgl/mesh.js -- AxialInstancedMesh for three's WebGLRenderer: the core mesh (core/mesh.js: record,
// bounds, wind) whose instances glsl/axial.glsl bends, injected into the user's own material (shader.js),
// so maps, lights, shadows, fog and tone mapping stay three.js's.  Bake and raycast bend by WebGL 2
// transform feedback (feedback.js); per-instance culling: instance_cull.js.

import * as THREE from 'three';
import { AxialError } from '../core/adp.js';
import { AxialMeshCore } from '../core/mesh.js';
import { injectBend } from './shader.js';
import { feedback, refuseWebGPU, refuseNodeMaterial, UNBENT_DRAW } from './feedback.js';
import { bake } from './bake.js';
import { raycast } from './raycast.js';
import { setInstanceCulling, cullingHooks } from './instance_cull.js';
import { GeneratedTiles } from './generate.js';
import { updateVariant, watchVariant } from '../core/variant.js';

/**
 * A THREE.InstancedMesh of `record.count` instances of `geometry`, each bent by its own numbers.
 *
 * record: parseADP's result, or {count, numbersPerInstance, data (Float32Array), axes?, axis?, lo?,
 * length?}.  options.axis: the mesh's control axis where the record's header does not say it all
 * (a chosen frame, several axes: the GLB's AXIALDEFORM_bend or extras.axialdeform); options.capacity:
 * room for more instances than the record has (setParams may grow count up to it); options.ownShader:
 * the materials bend themselves (a ShaderMaterial including AXIAL_GLSL that reads this mesh's
 * attributes axialD12, axialD34, axialD5, axialTwistTaper, axialAngles, axialAxis, instanceMatrix).  The
 * material(s) are cloned and given the bend; shadows and raycasting use the bent shape.  With {generate:
 * recipe} in place of the record, a generated layer (core/mesh.js says its options): its tiles made by WebGL 2
 * transform feedback (generate.js), drawn from the buffers the GPU wrote.
 */
export class AxialInstancedMesh extends AxialMeshCore {
  constructor(geometry, material, record, options = {}) {
    super(geometry, material, record, options);
    cullingHooks(this);
    if (this.recipe) this._part = new GeneratedTiles(this); // a generated layer's instances: made by WebGL 2 transform feedback
    watchVariant(this); // the shader variant of what the instances use (core/variant.js)
  }

  setWind(wind) {
    super.setWind(wind);
    updateVariant(this); // a wind moves the control points of unbent instances too
    return this;
  }

  _generatesWith(renderer) {
    return Boolean(renderer && renderer.isWebGLRenderer);
  }

  /** The instances' records (Float32Array, rows of numbersPerInstance): a generated layer's kept ones read back
   * from the GPU, as the Python library's generate_tiles gives them for `tiles` (tools and tests; drawing needs
   * none); otherwise the record's. */
  records() {
    return this.recipe ? this._part.records() : this.data.slice(0, this.count * this.layout.numbersPerInstance);
  }

  /** The bent materials of three's shadow passes (customDepthMaterial, customDistanceMaterial). */
  _makeShadowMaterials() {
    return [this.bendMaterial(new THREE.MeshDepthMaterial({ depthPacking: THREE.RGBADepthPacking }), false),
      this.bendMaterial(new THREE.MeshDistanceMaterial(), false)];
  }

  /** Throws where `renderer` cannot draw this mesh bent (WebGPURenderer: axialdeform-three/webgpu). */
  _checkRenderer(renderer) {
    refuseWebGPU(renderer, UNBENT_DRAW);
  }

  _beforeDraw(camera) {
    if (this._culling && !this._baked) this._culling.before(camera); // the instances in this camera's view
  }

  /** A clone of `material` (three's built-ins: Basic, Lambert, Phong, Standard, Physical, Toon,
   * Depth, Distance, ...) whose vertex shader bends this mesh's instances. */
  bendMaterial(material, clone = true) {
    if (!material || !material.isMaterial) throw new AxialError('AxialInstancedMesh: expected a THREE.Material');
    if (material.isNodeMaterial) refuseNodeMaterial(material);
    if (this._ownShader && clone) return material;
    if (material.isShaderMaterial) {
      throw new AxialError('AxialInstancedMesh: a ShaderMaterial has no three.js chunks to bend; include the exported AXIAL_GLSL in it yourself');
    }
    const m = clone ? material.clone() : material;
    const uniforms = this.axialUniforms, defines = this.defines, name = m.name || m.type;
    const before = material.onBeforeCompile;
    m.onBeforeCompile = (shader, renderer) => {
      if (before && before !== THREE.Material.prototype.onBeforeCompile) before.call(m, shader, renderer);
      Object.assign(shader.uniforms, uniforms); // the same objects: updates need no recompile
      shader.defines = { ...(shader.defines || {}), ...defines };
      shader.vertexShader = injectBend(shader.vertexShader, name);
    };
    const key = material.customProgramCacheKey.bind(material);
    m.customProgramCacheKey = () => `axialdeform:${Object.entries(defines).sort().join(';')}:${key()}`;
    m.needsUpdate = true;
    return m;
  }

  _write(rows, first) {
    super._write(rows, first);
    if (this._culling) this._culling.fill(first, rows.length / this.layout.numbersPerInstance);
  }

  /** Cull each instance by its bend-aware sphere before every draw under `renderer` (a WebGLRenderer), so a
   * camera draws only the instances it sees (instance_cull.js); null: draw them all again. */
  setInstanceCulling(renderer) {
    setInstanceCulling(this, renderer);
    return this;
  }

  /**
   * three's raycasting, against each instance's bent triangles (intersections carry instanceId).
   * The instances whose bounding sphere the ray meets are bent on the GPU by the same shader code
   * (raycast.js), so the mesh must have been drawn (or baked) once.
   */
  raycast(raycaster, intersects) {
    if (this.recipe) this._part.materialize(); // a generated layer's records read back once a tile set
    raycast(this, raycaster, intersects);
  }

  /**
   * Bend every instance ONCE on the GPU (WebGL 2 transform feedback, the same glsl/axial.glsl) and
   * draw the result as plain geometry from then on: for instances that do not move, the frames cost
   * what a baked mesh costs, while the file stays 40 bytes an instance (bake.js).  setParams()
   * (animation) and setWind() go back to bending every frame; call bake() again when the instances
   * rest.  Returns true when baked (false: no instances, a wind, an own shader, no WebGL 2).
   */
  bake(renderer) {
    if (this.recipe) this._part.materialize();
    return bake(this, renderer);
  }

  /** One transform-feedback pass over instances `ids` (null: all): feedback.js. */
  _feedback(renderer, ids, tangent) {
    return feedback(this, renderer, ids, tangent);
  }

  /** Frees this mesh's GPU buffers, its materials (the clones), shadow materials and texture;
   * the user's geometry and materials stay theirs. */
  dispose() {
    if (this._culling) this._culling.dispose();
    if (this._programs) Object.values(this._programs).forEach(({ gl, program }) => gl.deleteProgram(program));
    this._programs = null;
    return super.dispose();
  }
}
