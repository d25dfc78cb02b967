// app.js -- the axialdeform scene in WebGL 2 with three.js, shared by the
// exported page (folder or single file) and the notebook widget.
//
// Nothing here is deformation maths: the vertex and fragment shaders arrive
// in the scene's config, assembled at export time from the package's
// glsl/axial.glsl, quantized.glsl, scene.vert, scene.frag and lighting.glsl
// (axialdeform/web/__init__.py).  This file parses the binary parameter file
// (.adp, docs/parameter-files.md) with its CRC-32 verified and the base mesh's
// fingerprint compared, and hands the numbers to an AxialInstancedMesh drawn by those shaders.
//
// It imports the npm module axialdeform-three (which imports 'three'); the caller passes
// three.js in too (lib = {THREE, OrbitControls, GLTFLoader}).

// the npm module axialdeform-three (js/src): its parser reads and checks the .adp files (CRC-32,
// header) and its AxialInstancedMesh holds every layer's instances (attributes, instanceMatrix, a
// tree's offsets texture, bounds for three's culling); the page's own shaders draw them
import { parseADP, AxialError, AxialInstancedMesh } from 'axialdeform-three';
import { hex, stillWindUniforms, AxialBrush } from 'axialdeform-three/helpers';

/** The page's errors (a message shown as it is): the module's AxialError. */
export const SceneError = AxialError;

/** Parse an .adp parameter file (axialdeform-three's parseADP: every check of
 * axialdeform.core.io.adp.read_binary_header / decode_binary, in that order). */
export function parseAdp(buffer, name) {
  return parseADP(buffer, name);
}

async function sha256(bytes) {
  if (!(globalThis.crypto && globalThis.crypto.subtle)) return null;
  return new Uint8Array(await globalThis.crypto.subtle.digest('SHA-256', bytes));
}

/** SHA-256 of the mesh's positions (float32 LE) and triangles (uint32 LE),
 * as BaseMesh.fingerprint; null where WebCrypto is unavailable (a page served
 * to another machine over plain http is not a secure context). */
export async function meshFingerprint(positions, index) {
  const all = new Uint8Array(positions.byteLength + index.byteLength);
  all.set(new Uint8Array(positions.buffer, positions.byteOffset, positions.byteLength), 0);
  all.set(new Uint8Array(index.buffer, index.byteOffset, index.byteLength), positions.byteLength);
  return sha256(all);
}

/** The mesh check of axialdeform.core.params.check_mesh. */
function checkMesh(p, mesh, actual) {
  const axisNames = ['x', 'y', 'z', 'a chosen frame', 'several axes'];
  const meshAxis = mesh.axes ? 4 : (mesh.axis === -1 ? 3 : mesh.axis); // the adp header: 3 a frame, 4 a tree
  if (p.fingerprint) {
    const want = actual ? hex(actual) : mesh.fingerprint;
    if (p.fingerprint !== want) {
      throw new SceneError(`${p.name}: made for a different base mesh (fingerprint ${p.fingerprint.slice(0, 16)}, ` +
        `expected ${want.slice(0, 16)} of ${mesh.name}); export it with the mesh it was made for`);
    }
  }
  if (p.axis >= 0 && (p.axis !== meshAxis || (meshAxis >= 3 && p.frameDigest !== mesh.frame_digest))) {
    throw new SceneError(`${p.name}: made for a mesh whose control axis is ${axisNames[p.axis]}, ` +
      `but ${mesh.name}'s is ${meshAxis === 3 ? 'another frame' : axisNames[meshAxis]}`);
  }
}

function el(tag, cls, parent) {
  const e = document.createElement(tag);
  e.className = cls;
  parent.appendChild(e);
  return e;
}

/** The page's query options: ?t=SECONDS freezes the wind's clock at that
 * time; ?size=WxH keeps the canvas at that size (else the export decides:
 * a fixed size, or the whole window). */
export function pageOptions(search) {
  const q = new URLSearchParams(search || '');
  const out = { windowKeys: true }; // a page of its own: W anywhere toggles wireframe
  if (q.has('t')) {
    const t = Number(q.get('t'));
    if (q.get('t').trim() === '' || !Number.isFinite(t)) throw new SceneError(`?t=${q.get('t')}: expected a time in seconds`);
    out.time = t;
  }
  if (q.has('size')) {
    const m = /^(\d{1,5})x(\d{1,5})$/.exec(q.get('size'));
    if (!m || +m[1] < 1 || +m[2] < 1) throw new SceneError(`?size=${q.get('size')}: expected WIDTHxHEIGHT in pixels`);
    out.size = [+m[1], +m[2]];
  }
  if (q.has('walk')) { // ?walk=DX,DZ: the camera and its target move that much a frame (a generated world's tiles follow)
    const w = (q.get('walk') || '').split(',').map((x) => (x.trim() === '' ? NaN : Number(x)));
    if (w.length !== 2 || !w.every(Number.isFinite)) throw new SceneError(`?walk=${q.get('walk')}: expected DX,DZ in world units a frame`);
    out.walk = w;
  }
  return out;
}

/** The wind's two cycles at time t, as axialdeform.core.wind.Wind.cycles. */
/**
 * Draw the scene into `root`.
 * scene = {config, files: {name: ArrayBuffer}} (every layer's GLB and .adp),
 * or {config, glb, adp} for a one-layer scene (the widget).
 * options = {time, size, windowKeys} (pageOptions); without windowKeys (the
 * widget, inside a notebook) only a focused picture takes the W key.
 * Returns {ready: Promise<{instances}> (first frame drawn; rejects with the
 * message shown), setParams(ArrayBuffer, name) (the first layer's),
 * setWireframe(on), dispose()}.
 */
export function mount(root, lib, scene, options = {}) {
  const { THREE, OrbitControls, GLTFLoader } = lib;
  const cfg = scene.config;
  const files = scene.files || { [cfg.layers[0].mesh.file]: scene.glb, [cfg.layers[0].params_file]: scene.adp };
  const fixed = Boolean(options.size) || cfg.fixed_size !== false;
  const [W, H] = options.size || cfg.size;
  root.classList.add('axd-root');
  const stage = el('div', 'axd-stage', root);
  if (fixed) {
    stage.style.width = `${W}px`;
    stage.style.height = `${H}px`;
    stage.style.position = 'relative';
  } else {
    root.classList.add('axd-fill');
    stage.style.position = 'fixed';
    stage.style.inset = '0';
  }
  stage.style.background = `rgb(${cfg.look.background.map((c) => Math.round(c * 255)).join(',')})`;
  const message = el('div', 'axd-message', stage);
  message.setAttribute('role', 'alert');
  message.hidden = true;
  const status = el('div', 'axd-status', root);
  const statusText = el('span', 'axd-status-text', status);
  statusText.textContent = 'loading…';
  const toggle = el('button', 'axd-toggle', status);
  toggle.type = 'button';
  toggle.textContent = 'wireframe (W)';
  toggle.setAttribute('aria-pressed', 'false');

  let renderer = null, controls = null, camera = null, world = null, ground = null;
  // depth range while orbiting: near and far keep their distances from the target (`reach`: the scene's
  // radius about it), so zooming never clips the scene
  let reach = 0;
  const fitDepth = () => {
    const d = camera.position.distanceTo(controls.target);
    camera.far = d + reach;
    camera.near = Math.max(d - reach, camera.far * 1e-4);
    camera.updateProjectionMatrix();
  };
  let disposed = false;
  const layers = []; // {cfg, geometry, materials, mesh, fingerprint, variant, uniforms, count}
  const state = { count: 0, frames: 0, wireframe: cfg.mode === 'wireframe' };
  const baseMode = cfg.mode === 'wireframe' ? 0 : cfg.mode_index;
  const v3 = (a) => new THREE.Vector3().fromArray(a);
  const wind = cfg.wind;
  // the wind's clock: ?t= on the page, else the export's --time, else it runs
  const frozen = options.time !== undefined ? options.time : (cfg.time === null || cfg.time === undefined ? undefined : cfg.time);
  // uniforms every layer shares (the same objects: set once a frame)
  const shared = {
    u_view: { value: null }, u_proj: { value: null }, u_eye: { value: new THREE.Vector3() },
    u_mode: { value: state.wireframe ? 2 : baseMode }, u_line_color: { value: v3(cfg.look.line_color) },
    u_line_alpha: { value: 1.0 }, u_light_dir: { value: v3(cfg.look.light_dir) },
    u_light_color: { value: v3(cfg.look.light_color) }, u_sky_color: { value: v3(cfg.look.sky_color) },
    u_bounce_color: { value: v3(cfg.look.ground_color) }, u_up: { value: v3(cfg.up) },
    u_ambient: { value: cfg.look.ambient }, u_instance_base: { value: 0 },
  };
  // a layer without wind: the module's wind uniforms, still (a windy layer's are its mesh's, setWind)
  const still = stillWindUniforms();
  // render's shadow map (cfg.shadow: the key light's camera over the instances and the ground's centre), drawn
  // a frame before the picture, so the wind bends the shadows too; glsl/shadow.glsl samples it (AXIAL_SHADOW)
  const shadow = cfg.shadow ? shadowMap(cfg.shadow) : null;
  const shadowDefines = shadow ? { AXIAL_SHADOW: 1 } : {};

  function shadowMap(s) {
    const depthTarget = (n) => {
      const t = new THREE.WebGLRenderTarget(n, n);
      t.depthTexture = new THREE.DepthTexture(n, n);
      t.depthTexture.compareFunction = THREE.LessEqualCompare; // sampler2DShadow: hardware comparison
      return t;
    };
    const cam = new THREE.Camera(); // the light's: its matrices as render's ShadowMap has them
    cam.matrixAutoUpdate = false;
    cam.matrixWorldAutoUpdate = false;
    cam.matrixWorldInverse.fromArray(s.view);
    cam.matrixWorld.copy(cam.matrixWorldInverse).invert();
    cam.projectionMatrix.fromArray(s.projection);
    cam.projectionMatrixInverse.copy(cam.projectionMatrix).invert();
    const target = depthTarget(s.size);
    return { target, idle: depthTarget(1), cam, uniforms: { u_shadow_map: { value: target.depthTexture },
      u_light_matrix: { value: new THREE.Matrix4().fromArray(s.matrix) }, u_shadow_offset: { value: s.offset },
      u_shadow_texel: { value: 1 / s.size } } };
  }

  function drawShadow() { // the instances' depth from the light, as render's shadow pass draws it (u_mode 0, solid)
    const keep = [shared.u_view.value, shared.u_proj.value, shared.u_mode.value];
    shared.u_view.value = shadow.cam.matrixWorldInverse;
    shared.u_proj.value = shadow.cam.projectionMatrix;
    shared.u_mode.value = 0;
    shadow.uniforms.u_shadow_map.value = shadow.idle.depthTexture; // not the map being drawn (a feedback loop)
    const lines = layers.flatMap((l) => l.materials || []).filter((m) => m.wireframe);
    lines.forEach((m) => { m.wireframe = false; });
    if (ground) ground.visible = false;
    if (!shadow.made) { // three makes a target's depth texture when it is first drawn into: the idle one too
      renderer.setRenderTarget(shadow.idle);
      renderer.clear();
      shadow.made = true;
    }
    renderer.setRenderTarget(shadow.target);
    renderer.clear();
    renderer.render(world, shadow.cam);
    renderer.setRenderTarget(null);
    if (ground) ground.visible = true;
    lines.forEach((m) => { m.wireframe = true; });
    shadow.uniforms.u_shadow_map.value = shadow.target.depthTexture;
    [shared.u_view.value, shared.u_proj.value, shared.u_mode.value] = keep;
  }

  function showError(err) {
    const text = err instanceof SceneError ? err.message : `error: ${err && err.message ? err.message : err}`;
    message.textContent = text;
    message.hidden = false;
    statusText.textContent = 'nothing drawn';
    if (renderer) renderer.domElement.style.visibility = 'hidden';
    return text;
  }

  // three.js writes the version line itself (glslVersion), then its own defines
  const body = (src) => src.replace(/^#version 300 es\n/, '');

  function groundMesh(g) { // render's ground plane (glsl/ground.vert, .frag): a square's 4 corners from gl_VertexID
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(new Float32Array(12), 3)); // unread: the count
    geometry.setIndex([0, 1, 2, 2, 1, 3]); // the triangle strip render draws
    const material = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: body(cfg.shaders.ground.vertex), fragmentShader: body(cfg.shaders.ground.fragment),
      side: THREE.DoubleSide,
      defines: shadowDefines,
      uniforms: { // GroundPlane.render's
        ...(shadow ? shadow.uniforms : {}),
        u_view: shared.u_view, u_proj: shared.u_proj, u_eye: shared.u_eye, u_light_dir: shared.u_light_dir,
        u_light_color: shared.u_light_color, u_sky_color: shared.u_sky_color, u_bounce_color: shared.u_bounce_color,
        u_up: shared.u_up, u_ambient: shared.u_ambient, u_center: { value: v3(g.center) }, u_axis_u: { value: v3(g.axis_u) },
        u_axis_v: { value: v3(g.axis_v) }, u_radius: { value: g.radius }, u_color: { value: v3(g.color) },
        u_background: { value: v3(cfg.look.background) }, u_cell: { value: g.cell },
      },
    });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.frustumCulled = false; // its corners come from gl_VertexID, not the position attribute
    mesh.renderOrder = -1;
    return mesh;
  }

  function variant(layer, p) { // the record's level (its numbers but the child axes') picks the build
    return 'float' + cfg.shader_suffix[String(p.fields - 10 * (p.axes - 1))] +
      (layer.cfg.material ? '_material' : '') + (layer.cfg.mesh.frame ? '_framed' : '');
  }

  function makeMaterials(layer, key) {
    const sh = cfg.shaders[key];
    const lc = layer.cfg;
    return lc.parts.map((part, i) => {
      const tex = layer.textures[i] || {};
      const blend = part.alpha_mode === 2;
      const m = new THREE.RawShaderMaterial({
        glslVersion: THREE.GLSL3,
        // a generated layer's wind phases and shades hash where its instances stand (their slots change
        // as tiles come and go): AXIAL_POSITION_IDS, as the Python library draws it
        defines: { ...(lc.mesh.axes ? { AXIAL_AXES: lc.mesh.axes.count } : {}), ...(lc.generate ? { AXIAL_POSITION_IDS: 1 } : {}),
          ...shadowDefines },
        vertexShader: body(sh.vertex),
        fragmentShader: body(sh.fragment),
        side: lc.cull_back_faces && !part.double_sided ? THREE.FrontSide : THREE.DoubleSide,
        transparent: blend,
        depthWrite: !blend,
        wireframe: state.wireframe,
        uniforms: {
          ...shared, ...layer.uniforms, ...(shadow ? shadow.uniforms : {}),
          // the part's material, as axialdeform.gl.material.GpuMaterials.bind sets it
          u_base_color: { value: new THREE.Vector4().fromArray(part.base_color) },
          u_has_texture: { value: Boolean(part.texture && tex.map) }, u_texture: { value: tex.map || null },
          u_alpha_mode: { value: part.alpha_mode }, u_alpha_cutoff: { value: part.alpha_cutoff },
          u_double_sided: { value: part.lit_two_sided },
          u_has_normal_map: { value: Boolean(part.normal_map && tex.normalMap) },
          u_normal_map: { value: tex.normalMap || null },
        },
      });
      return m;
    });
  }

  async function prepare(layer, adp, name) {
    const whole = parseAdp(adp, name);
    checkMesh(whole, layer.cfg.mesh, layer.fingerprint);
    const want = layer.cfg.mesh.axes ? layer.cfg.mesh.axes.count : 1;
    if (whole.axes !== want) throw new SceneError(`${name}: ${whole.axes} axes an instance, but ${layer.cfg.mesh.name} has ${want}`);
    if (!cfg.shaders[variant(layer, whole)]) {
      throw new SceneError(`${name}: ${whole.fields - 10 * (whole.axes - 1)}-number instances, but this page was exported without their shader`);
    }
    return whole;
  }

  function apply(layer, p) {
    // a new AxialInstancedMesh for the file (its width or count may differ from the last one's); a
    // generated layer's ({generate: recipe}) makes its instances on the GPU from the recipe (countInstances)
    const key = variant(layer, p);
    const materials = makeMaterials(layer, key);
    const gen = layer.cfg.generate;
    const mesh = new AxialInstancedMesh(layer.geometry, materials, gen ? { generate: gen.recipe } : p,
      { axis: layer.axisSpec, ownShader: true, ...(gen ? { uniforms: gen.uniforms, maps: layer.maps } : {}) });
    if (gen && layer.brushGround) layer.brush = new AxialBrush(mesh, layer.brushGround);
    // the module's wind (its bounds grow by the wind's reach, so three culls right)
    if (wind && layer.cfg.wind) {
      mesh.setWind({ direction: wind.direction, strength: wind.strength, gustiness: wind.gustiness,
        frequency: wind.frequency, wavelength: wind.wavenumber > 0 ? 1 / wind.wavenumber : 0 });
    }
    // the axis (frame, lo, L, centre; a tree's axes and offsets texture) and the wind: the mesh's uniforms
    materials.forEach((m) => Object.assign(m.uniforms, still, mesh.axialUniforms));
    mesh.renderOrder = layer.order;
    const old = layer.mesh;
    layer.mesh = mesh;
    layer.materials = materials;
    layer.variant = key;
    layer.count = p.count;
    if (world) {
      if (old) world.remove(old);
      world.add(mesh);
    }
    if (old) old.dispose(); // its geometry's buffers and its materials
    countInstances();
  }

  function countInstances() {
    for (const l of layers) if (l.mesh && l.mesh.recipe) l.count = l.mesh.kept; // its slots drawn: count
    state.count = layers.reduce((a, l) => a + (l.cfg.terrain ? 0 : l.count), 0);
  }

  async function loadLayer(lc) {
    const glb = files[lc.mesh.file];
    if (!glb) throw new SceneError(`${lc.mesh.file}: missing from the page`);
    const gltf = await new Promise((resolve, reject) => new GLTFLoader().parse(glb, '', resolve, (e) =>
      reject(new SceneError(`${lc.mesh.file}: not a readable glTF binary (${e && e.message ? e.message : e})`))));
    const prims = [];
    gltf.scene.traverse((o) => { if (o.isMesh) prims.push(o); });
    if (!prims.length || prims.some((o) => !o.geometry.index)) {
      throw new SceneError(`${lc.mesh.file}: holds no indexed triangle mesh`);
    }
    if (prims.length !== lc.parts.length) {
      throw new SceneError(`${lc.mesh.file}: ${prims.length} primitives, but ${lc.mesh.name} has ${lc.parts.length} parts`);
    }
    // the parts' triangles, in order, are the mesh's triangles
    const total = prims.reduce((a, o) => a + o.geometry.index.count, 0);
    const index = new Uint32Array(total);
    let at = 0;
    for (const o of prims) { index.set(o.geometry.index.array, at); at += o.geometry.index.count; }
    const base = prims[0].geometry;
    const layer = { cfg: lc, geometry: null, materials: null, mesh: null, variant: null, count: 0,
      textures: prims.map((o) => ({ map: o.material.map || null, normalMap: o.material.normalMap || null })) };
    const position = base.getAttribute('position');
    layer.fingerprint = await meshFingerprint(position.array, index);
    if (layer.fingerprint && hex(layer.fingerprint) !== lc.mesh.fingerprint) {
      throw new SceneError(`${lc.mesh.file}: not the base mesh this page was exported with (fingerprint ` +
        `${hex(layer.fingerprint).slice(0, 16)}, expected ${lc.mesh.fingerprint.slice(0, 16)})`);
    }
    // a generated layer has no parameter file: its records' width says its shader build
    const adp = lc.generate ? null : files[lc.params_file];
    if (!adp && !lc.generate) throw new SceneError(`${lc.params_file}: missing from the page`);
    const p = lc.generate ? { fields: lc.generate.width, axes: 1, count: 0 } : await prepare(layer, adp, lc.params_file);
    if (lc.generate) { // its ground maps: float32 pixels, row after row
      layer.maps = {};
      for (const [key, m] of Object.entries(lc.generate.maps || {})) {
        if (!files[m.file] || files[m.file].byteLength !== 4 * m.cols * m.rows) {
          throw new SceneError(`${m.file}: missing from the page or not ${m.cols} x ${m.rows} float32 pixels`);
        }
        layer.maps[key] = { data: new Float32Array(files[m.file].slice(0)), cols: m.cols, rows: m.rows };
      }
      const b = lc.generate.brush; // the brush's ground, the layer's own density map and its saved mask
      if (b) {
        const grid = (m) => (m && files[m.file] && files[m.file].byteLength === 4 * m.cols * m.rows
          ? { data: new Float32Array(files[m.file].slice(0)), cols: m.cols, rows: m.rows } : null);
        layer.brushGround = { area: b.area, wrap: b.wrap, density: grid(b.density), mask: grid(b.mask) };
      }
    }
    const n = position.count;
    const geometry = new THREE.BufferGeometry(); // the base mesh: AxialInstancedMesh adds the instances
    geometry.setIndex(new THREE.BufferAttribute(index, 1));
    geometry.setAttribute('position', position);
    geometry.setAttribute('normal', base.getAttribute('normal'));
    if (lc.mesh.axes) { // several axes: each vertex's axis (the GLB's _AXIAL_AXIS)
      const axisOf = base.getAttribute('_axial_axis');
      if (!axisOf) throw new SceneError(`${lc.mesh.file}: a mesh of ${lc.mesh.axes.count} axes needs _AXIAL_AXIS`);
      geometry.setAttribute('_axial_axis', axisOf);
    }
    if (lc.material) { // defaults where the mesh has none, as axialdeform.gl.material.AppearanceBuffer
      const fill = (size, v) => { const a = new Float32Array(n * size); for (let i = 0; i < a.length; i++) a[i] = v[i % size]; return a; };
      geometry.setAttribute('in_uv', base.getAttribute('uv') || new THREE.BufferAttribute(fill(2, [0, 0]), 2));
      const color = base.getAttribute('color');
      geometry.setAttribute('in_color', color && color.itemSize === 4 ? color : new THREE.BufferAttribute(fill(4, [1, 1, 1, 1]), 4));
      geometry.setAttribute('in_tangent', base.getAttribute('tangent') || new THREE.BufferAttribute(fill(4, [1, 0, 0, 1]), 4));
    }
    lc.parts.forEach((part, i) => geometry.addGroup(part.start * 3, part.count * 3, i));
    layer.geometry = geometry;
    // the control axis, as the module takes it (the same numbers as the uniforms below)
    layer.axisSpec = { axis: { index: lc.mesh.axis, frame: lc.mesh.frame, lo: lc.mesh.lo, length: lc.mesh.length,
      center: lc.mesh.center }, axes: lc.mesh.axes || null };
    // the page's own: the axis as an index (its axis-aligned builds) and the colour; the rest of the
    // axis and the wind are the module mesh's uniforms (apply)
    layer.uniforms = { u_axis: { value: lc.mesh.axis }, u_color: { value: v3(lc.color) } };
    return { layer, p };
  }

  function setWireframe(on) {
    state.wireframe = Boolean(on);
    shared.u_mode.value = state.wireframe ? 2 : baseMode;
    for (const l of layers) for (const m of l.materials || []) { m.wireframe = state.wireframe; m.needsUpdate = true; }
    toggle.setAttribute('aria-pressed', String(state.wireframe));
  }
  // the brush (docs/learn.md, "Set the range"): B on/off (a drag then paints instead of orbiting), E paint or
  // erase, [ and ] the radius, L the next generated layer, M save each painted mask (SCENE-LAYER-mask.png)
  const brush = { on: false, erase: false, radius: 2, at: 0, painted: new Set() };
  const painters = () => layers.filter((l) => l.brush);
  const showBrush = () => {
    const l = painters()[brush.at % Math.max(painters().length, 1)];
    brushText.textContent = brush.on && l ? ` · brush: ${l.cfg.name}, ${brush.erase ? 'erase' : 'paint'}, r = ${brush.radius.toFixed(2)}` : '';
  };
  const paint = (name, x, z, radius = brush.radius, erase = brush.erase) => {
    const l = painters().find((p) => p.cfg.name === name);
    if (!l) throw new SceneError(`brush: ${name}: expected a generated layer (${painters().map((p) => p.cfg.name).join(', ') || 'none'})`);
    const changed = l.brush.stroke(x, z, radius, erase);
    if (changed) brush.painted.add(l);
    return changed;
  };
  const saveMasks = async () => {
    for (const l of brush.painted) {
      const png = await l.brush.png();
      if (options.onMask) { options.onMask(l.cfg.name, l.cfg.generate.brush.file, png); continue; } // the widget: Python saves it
      const a = document.createElement('a');
      a.href = URL.createObjectURL(new Blob([png], { type: 'image/png' }));
      a.download = l.cfg.generate.brush.file;
      a.click();
      setTimeout(() => URL.revokeObjectURL(a.href), 1000);
    }
  };
  const onKey = (e) => {
    if (e.repeat || e.ctrlKey || e.metaKey || e.altKey) return;
    const k = e.key.toLowerCase();
    if (k === 'w') setWireframe(!state.wireframe);
    if (!painters().length) return;
    if (k === 'b') { brush.on = !brush.on; if (controls) controls.enabled = !brush.on; }
    if (k === 'e') brush.erase = !brush.erase;
    if (k === '[' || k === ']') brush.radius *= k === ']' ? 1.25 : 0.8;
    if (k === 'l') brush.at += 1;
    if (k === 'm') saveMasks().catch(showError);
    showBrush();
  };
  const brushText = el('span', 'axd-status-text', status);
  const ray = new THREE.Raycaster();
  const dab = (e) => { // the ground under the pointer: the terrain, or the plane y = 0
    if (!brush.on || !(e.buttons & 1) || !camera) return;
    const r = renderer.domElement.getBoundingClientRect();
    ray.setFromCamera(new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, 1 - ((e.clientY - r.top) / r.height) * 2), camera);
    const ground = layers.filter((l) => l.cfg.terrain && l.mesh).map((l) => l.mesh);
    const hit = ground.length ? ray.intersectObjects(ground, false)[0] : null;
    const at = hit ? hit.point : ray.ray.intersectPlane(new THREE.Plane(new THREE.Vector3(0, 1, 0), 0), new THREE.Vector3());
    const l = painters()[brush.at % painters().length];
    if (at && l) paint(l.cfg.name, at.x, at.z);
  };
  toggle.addEventListener('click', () => setWireframe(!state.wireframe));
  const keyTarget = options.windowKeys ? window : stage;
  if (!options.windowKeys) stage.tabIndex = 0; // click the picture, then W

  const ready = (async () => {
    const loaded = await Promise.all(cfg.layers.map((lc) => loadLayer(lc)));
    loaded.forEach(({ layer, p }, i) => {
      layer.order = i;
      layers.push(layer);
      apply(layer, p);
    });

    THREE.ColorManagement.enabled = false; // colours are written as render's, unconverted
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    if (!renderer.capabilities.isWebGL2) throw new SceneError('this browser has no WebGL 2');
    renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    const sizeNow = () => (fixed ? [W, H] : [Math.max(1, stage.clientWidth), Math.max(1, stage.clientHeight)]);
    let [w, h] = sizeNow();
    renderer.setSize(w, h);
    renderer.setClearColor(new THREE.Color(...cfg.look.background), 1);
    let shaderError = null;
    renderer.debug.onShaderError = (gl, program, vs, fs) => {
      const log = [gl.getShaderInfoLog(vs), gl.getShaderInfoLog(fs), gl.getProgramInfoLog(program)]
        .filter((x) => x && x.trim()).join(' ').trim();
      shaderError = `the shaders did not compile in this browser: ${log || 'no log'}`;
    };
    renderer.domElement.classList.add('axd-canvas');
    stage.insertBefore(renderer.domElement, message);

    const c = cfg.camera;
    // the exported camera frames the scene for the export's aspect; a narrower
    // canvas widens the vertical field of view so the same width stays in view
    const aspect0 = cfg.size[0] / cfg.size[1];
    const fovFor = (aspect) => (aspect >= aspect0 ? c.fovy
      : (2 * Math.atan(Math.tan((c.fovy * Math.PI) / 360) * (aspect0 / aspect)) * 180) / Math.PI);
    camera = new THREE.PerspectiveCamera(fovFor(w / h), w / h, c.near, c.far);
    camera.up.fromArray(c.up);
    camera.position.fromArray(c.eye);
    camera.lookAt(new THREE.Vector3().fromArray(c.target));
    camera.updateMatrixWorld();
    const d0 = camera.position.distanceTo(new THREE.Vector3().fromArray(c.target));
    reach = c.far - d0;
    controls = new OrbitControls(camera, renderer.domElement);
    controls.target.fromArray(c.target);
    controls.addEventListener('change', fitDepth);
    controls.update();
    camera.near = c.near; camera.far = c.far; camera.updateProjectionMatrix();
    let resizer = null;
    if (!fixed) { // the canvas follows the window; the camera's aspect with it
      resizer = new ResizeObserver(() => {
        [w, h] = sizeNow();
        renderer.setSize(w, h);
        camera.aspect = w / h;
        camera.fov = fovFor(camera.aspect);
        camera.updateProjectionMatrix();
      });
      resizer.observe(stage);
    }
    keyTarget.addEventListener('keydown', onKey);
    renderer.domElement.addEventListener('pointerdown', dab);
    renderer.domElement.addEventListener('pointermove', dab);

    shared.u_view.value = camera.matrixWorldInverse;
    shared.u_proj.value = camera.projectionMatrix;
    shared.u_eye.value = camera.position;
    world = new THREE.Scene();
    if (cfg.ground) world.add(ground = groundMesh(cfg.ground)); // render's, under a scene without a terrain
    for (const layer of layers) world.add(layer.mesh);

    let frames = 0, since = performance.now(), fps = 0;
    const t0 = performance.now();
    const fmt = new Intl.NumberFormat('en-US');
    const showStatus = () => {
      statusText.textContent = `${fmt.format(state.count)} instances · ${fps ? fps.toFixed(fps < 10 ? 1 : 0) : '…'} fps` +
        (frozen !== undefined && wind ? ` · t = ${frozen} s` : '');
    };
    let first = null, failed = null;
    const drawn = new Promise((resolve, reject) => { first = resolve; failed = reject; });
    renderer.setAnimationLoop(() => {
      if (disposed) return;
      if (options.walk) { // the camera walks; its target leads the tiles
        const [dx, dz] = options.walk;
        controls.target.x += dx; controls.target.z += dz;
        camera.position.x += dx; camera.position.z += dz;
      }
      controls.update();
      // generated layers: the tiles within reach of the target, made when the set changes
      let made = false;
      for (const l of layers) if (l.mesh && l.mesh.recipe && l.mesh.update(renderer, controls.target)) made = true;
      if (made) countInstances();
      if (wind) {
        const t = frozen !== undefined ? frozen : (performance.now() - t0) / 1000;
        for (const l of layers) if (l.mesh && l.cfg.wind) l.mesh.setTime(t); // the module's clock: its uniforms
      }
      if (shadow) drawShadow();
      renderer.render(world, camera);
      frames += 1;
      state.frames += 1;
      const now = performance.now();
      if (now - since >= 500) {
        fps = (frames * 1000) / (now - since);
        frames = 0;
        since = now;
        showStatus();
      }
      if (shaderError) {
        renderer.setAnimationLoop(null);
        if (failed) failed(new SceneError(shaderError));
        first = failed = null;
        return;
      }
      if (first) {
        // the first frame is drawn once one of its pixels can be read back: readPixels waits for
        // the GPU to finish the frame (gl.finish() in Chromium only flushes: it returned 1.2 to 6 s early)
        const gl = renderer.getContext();
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
        showStatus();
        first({ instances: state.count });
        first = failed = null;
      }
    });
    layers.resizer = resizer;
    return drawn;
  })().catch((err) => {
    const text = showError(err);
    throw new SceneError(text);
  });

  return {
    ready,
    get wireframe() { return state.wireframe; },
    /** What is on screen: canvas size in CSS pixels, the camera's aspect, wireframe or not. */
    info() {
      const size = renderer ? renderer.getSize(new THREE.Vector2()) : { x: 0, y: 0 };
      return { width: size.x, height: size.y, aspect: camera ? camera.aspect : null, fov: camera ? camera.fov : null,
        wireframe: state.wireframe,
        fixed, time: frozen === undefined ? null : frozen };
    },
    setWireframe,
    /** Paint (or erase) a round dab of generated layer `name`'s mask at (x, z) on the ground (world units);
     * whether it changed (the layer's tiles are then made again). */
    paint,
    /** Generated layer `name`'s mask as an 8-bit grey PNG (Uint8Array): SCENE-LAYER-mask.png. */
    async mask(name) {
      const l = painters().find((p) => p.cfg.name === name);
      if (!l) throw new SceneError(`brush: ${name}: expected a generated layer`);
      return l.brush.png();
    },
    /** Save every painted mask: downloads (the page), or to the widget's Python (options.onMask). */
    saveMasks,
    /** Frames drawn so far. */
    get frames() { return state.frames; },
    /** The ground plane's centre and radius, the key light's matrix (null: none drawn) and the camera's depth
     * range ([near, far], the target) now, for tools and tests. */
    get fitted() {
      return { ground: ground ? { center: ground.material.uniforms.u_center.value.toArray(), radius: ground.material.uniforms.u_radius.value } : null,
        light: shadow ? shadow.uniforms.u_light_matrix.value.toArray() : null,
        depth: camera ? [camera.near, camera.far] : null, target: controls ? controls.target.toArray() : null };
    },
    /** Each generated layer's tiles and records now (its name, the tiles nearest the target first,
     * numbers an instance, the last tiles' timing, the kept records in the tiles' order, read back from
     * the GPU; not with {records: false}), for tools and tests. */
    generated({ records = true } = {}) {
      return layers.filter((l) => l.mesh && l.mesh.recipe).map((l) => ({
        name: l.cfg.name, tiles: l.mesh.tiles, width: l.mesh.layout.numbersPerInstance, timing: l.mesh.timing,
        target: controls ? controls.target.toArray() : null,
        data: records ? Array.from(l.mesh.records()) : null })); // read back from the GPU: only when asked
    },
    /** The ground plane and the key light's camera fitted again ({ground, shadow} as the config has them: the
     * widget's Python fits them to new instances), and the camera's depth range widened to `reach` ({center,
     * radius}: the new instances' sphere) where it would cut them; a page drawn without ground or shadow keeps none. */
    refit({ ground: g = null, shadow: s = null, reach: r = null } = {}) {
      if (r && controls) { // new instances farther from the target than the depth range holds: it widens
        const need = controls.target.distanceTo(new THREE.Vector3().fromArray(r.center)) + r.radius;
        if (need > reach) { reach = need; fitDepth(); }
      }
      if (ground && g) {
        const u = ground.material.uniforms;
        u.u_center.value.fromArray(g.center); u.u_axis_u.value.fromArray(g.axis_u); u.u_axis_v.value.fromArray(g.axis_v);
        u.u_radius.value = g.radius;
      }
      if (shadow && s) {
        shadow.cam.matrixWorldInverse.fromArray(s.view);
        shadow.cam.matrixWorld.copy(shadow.cam.matrixWorldInverse).invert();
        shadow.cam.projectionMatrix.fromArray(s.projection);
        shadow.cam.projectionMatrixInverse.copy(shadow.cam.projectionMatrix).invert();
        shadow.uniforms.u_light_matrix.value.fromArray(s.matrix);
        shadow.uniforms.u_shadow_offset.value = s.offset;
      }
    },
    /** Replace the first layer's parameters by another .adp (ArrayBuffer); a
     * bad file keeps nothing wrong on screen: the message says why and nothing is drawn. */
    async setParams(adp, name = 'parameters') {
      await ready.catch(() => null);
      const layer = layers[0];
      if (!layer) return;
      if (layer.cfg.generate) throw new SceneError(`${layer.cfg.name}: a generated layer; its instances come from its recipe, not a parameter file`);
      try {
        const p = await prepare(layer, adp, name);
        apply(layer, p);
        message.hidden = true;
        renderer.domElement.style.visibility = '';
        return { instances: p.count };
      } catch (err) {
        showError(err);
        for (const l of layers) { if (l.mesh) l.mesh.count = 0; l.count = 0; }
        state.count = 0;
        throw err;
      }
    },
    dispose() {
      disposed = true;
      keyTarget.removeEventListener('keydown', onKey);
      if (layers.resizer) layers.resizer.disconnect();
      if (renderer) { renderer.setAnimationLoop(null); renderer.dispose(); }
      if (controls) controls.dispose();
      if (ground) { ground.geometry.dispose(); ground.material.dispose(); }
      if (shadow) { shadow.target.dispose(); shadow.idle.dispose(); }
      for (const l of layers) {
        if (l.mesh) l.mesh.dispose(); // its geometry's buffers, the materials, the offsets texture
        if (l.geometry) l.geometry.dispose();
        l.textures.forEach((t) => { if (t.map) t.map.dispose(); if (t.normalMap) t.normalMap.dispose(); });
      }
      root.replaceChildren();
    },
  };
}

/** Base64 text -> ArrayBuffer. */
export function fromBase64(text) {
  const bin = atob(text.replace(/\s+/g, ''));
  const out = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out.buffer;
}
