// variant.js -- what a mesh's instances use, so that the shader variant drawing them leaves out the rest
// (glsl/axial.glsl's AXIAL_NO_TURN: no twist or taper; AXIAL_NO_BEND: no offset either, only the rigid part):
// the same pictures without the vertex work.  WebGL builds its materials with these defines; WebGPU's
// positionNode leaves the bend out under AXIAL_NO_BEND and builds the generated node functions with the turn
// switched off under AXIAL_NO_TURN (tsl_runtime.js's switches; its compute passes build them whole).  A
// record of 16 numbers has no turn; a record whose every instance's offsets, twist and taper are zero does
// not bend, unless a wind moves its control points.  setParams scans every instance; updateParams only the
// rows it writes, and turns a feature back on when one of them uses it (never off: the next setParams does).
// A generated layer (its records made on the GPU) and a mesh whose materials bend themselves (ownShader)
// keep every feature.

/**
 * Whether rows first .. first + n - 1 of `data` (records of `layout`: adp.js's recordLayout) use the turn (a
 * twist or taper) and the bend (an offset of any axis, or the turn).
 * @param {Float32Array} data @param {any} layout @param {number} first @param {number} n
 * @returns {{turn: boolean, bend: boolean}}
 */
export function uses(data, layout, first, n) {
  const f = layout.numbersPerInstance, offsets = 10 * layout.axes;
  const turns = [layout.twist, layout.taper].filter((c) => c !== null);
  let turn = false, bend = false;
  for (let i = first; i < first + n && !turn; i++) {
    const r = i * f;
    for (const c of turns) turn = turn || data[r + c] !== 0;
    for (let c = 0; c < offsets && !bend; c++) bend = data[r + c] !== 0;
  }
  return { turn, bend: bend || turn };
}

/**
 * After rows first .. first + n - 1 of `mesh` were written (`all`: they are its every instance, as setParams
 * writes them; none: the wind changed), set `mesh.defines`' AXIAL_NO_TURN and AXIAL_NO_BEND, and mark its
 * materials for a rebuild where one changed; returns whether one did.
 * @param {any} mesh @param {number} [first] @param {number} [n] @param {boolean} [all] @returns {boolean}
 */
export function updateVariant(mesh, first = 0, n = 0, all = false) {
  if (mesh.recipe || mesh._ownShader) return false;
  const u = uses(mesh.data, mesh.layout, first, n), had = mesh._uses || { turn: true, bend: true };
  mesh._uses = all ? u : { turn: had.turn || u.turn, bend: had.bend || u.bend };
  const d = mesh.defines, before = Object.keys(d).sort().join();
  const set = (name, on) => { if (on) d[name] = '1'; else delete d[name]; };
  set('AXIAL_NO_TURN', !mesh._uses.turn);
  set('AXIAL_NO_BEND', !mesh._uses.bend && !('AXIAL_WIND' in d));
  if (before === Object.keys(d).sort().join()) return false;
  mesh._allMaterials().forEach((m) => { m.needsUpdate = true; });
  return true;
}

/**
 * Keep `mesh`'s variant to what its instances use from now on: for the instances it holds, and after every
 * setParams / updateParams (its 'paramschange' events); `changed` runs when the variant changed (a renderer
 * that builds more than the materials' defines from it).
 * @param {any} mesh @param {() => void} [changed]
 */
export function watchVariant(mesh, changed = () => {}) {
  if (updateVariant(mesh, 0, mesh.count, true)) changed();
  mesh.addEventListener('paramschange', (/** @type {any} */ e) => {
    if (updateVariant(mesh, e.first, e.count, e.first === 0 && e.count === mesh.count)) changed();
  });
}
