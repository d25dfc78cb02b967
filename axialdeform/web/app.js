// app.js -- the axialdeform scene in WebGL 2 with three.js, shared by the
// exported page (folder or single file) and the notebook widget.
//
// Nothing here is deformation maths: the vertex and fragment shaders arrive
// in the scene's config, assembled at export time from the package's
// glsl/axial.glsl, quantized.glsl, scene.vert, scene.frag and lighting.glsl
// (axialdeform/web/__init__.py).  This file parses the binary parameter file
// (.adp, docs/parameter-files.md) with its CRC-32 verified and the base mesh's
// fingerprint compared, and feeds the numbers to those shaders unchanged.
//
// The module imports nothing: the caller passes three.js in
// (lib = {THREE, OrbitControls, GLTFLoader}).

export class SceneError extends Error {}

const MAGIC = [0x89, 0x41, 0x44, 0x50, 0x0d, 0x0a, 0x1a, 0x0a];
const HEADER = 96;
// version 1: 16 numbers per instance; version 2: 19 (extended: s tw tp)
const FIELDS_OF_VERSION = { 1: 16, 2: 19 };

let crcTable = null;

/** CRC-32 (zlib's polynomial) of a Uint8Array. */
export function crc32(bytes) {
  if (crcTable === null) {
    crcTable = new Uint32Array(256);
    for (let n = 0; n < 256; n++) {
      let c = n;
      for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
      crcTable[n] = c >>> 0;
    }
  }
  let crc = 0xffffffff;
  for (let i = 0; i < bytes.length; i++) crc = crcTable[(crc ^ bytes[i]) & 0xff] ^ (crc >>> 8);
  return (crc ^ 0xffffffff) >>> 0;
}

function hex(bytes) {
  return Array.from(bytes, (b) => b.toString(16).padStart(2, '0')).join('');
}

/** Parse an .adp parameter file; the checks and their order follow
 * axialdeform.core.params.read_binary_header / decode_binary. */
export function parseAdp(buffer, name) {
  const bytes = new Uint8Array(buffer);
  const view = new DataView(buffer);
  const fail = (what) => { throw new SceneError(`${name}: ${what}`); };
  if (bytes.length < HEADER + 4) fail(`truncated: ${bytes.length} bytes, shorter than the 96-byte header and the 4-byte checksum`);
  if (MAGIC.some((b, i) => bytes[i] !== b)) fail('not an axialdeform parameter file (magic bytes differ)');
  const version = view.getUint16(8, true);
  const fields = FIELDS_OF_VERSION[version];
  if (!fields) fail(`version: expected 1 or 2, found ${version} (written by a newer axialdeform?)`);
  const encoding = view.getUint16(10, true);
  if (encoding !== 0 && encoding !== 1) fail(`encoding: expected 0 (float32) or 1 (quantized), found ${encoding}`);
  const headerSize = view.getUint32(12, true);
  if (headerSize !== HEADER) fail(`header size: expected 96, found ${headerSize}`);
  const count64 = view.getBigUint64(16, true);
  const each = encoding === 1 ? 2 * fields : 4 * fields;
  const table = encoding === 1 ? 8 * fields : 0;
  const expected = BigInt(HEADER + table + 4) + count64 * BigInt(each);
  if (BigInt(bytes.length) !== expected) {
    const why = BigInt(bytes.length) < expected ? 'truncated' : 'too long';
    fail(`${why}: ${bytes.length} bytes, but a count of ${count64} instances needs ${expected}`);
  }
  const count = Number(count64);
  const stored = view.getUint32(bytes.length - 4, true);
  const computed = crc32(bytes.subarray(0, bytes.length - 4));
  if (stored !== computed) {
    fail(`checksum: wrong CRC-32 (stored ${stored.toString(16).padStart(8, '0')}, computed ` +
         `${computed.toString(16).padStart(8, '0')}): the file is corrupt`);
  }
  const axis = view.getInt8(24);
  if (axis < -1 || axis > 2) fail(`axis: expected -1, 0, 1 or 2, found ${axis}`);
  const lo = view.getFloat64(32, true);
  const length = view.getFloat64(40, true);
  const fingerprint = bytes.slice(48, 80);
  let qtable = null;
  let values;
  if (encoding === 1) {
    qtable = new Float32Array(buffer.slice(HEADER, HEADER + table));
    values = new Uint16Array(buffer.slice(HEADER + table, HEADER + table + count * each));
    if (!qtable.every(Number.isFinite)) fail('quantization table: a number is not finite');
  } else {
    values = new Float32Array(buffer.slice(HEADER, HEADER + count * each));
    if (!values.every(Number.isFinite)) fail('values: a number is not finite (NaN or infinity)');
  }
  return { name, version, fields, encoding, count, axis, lo, length, fingerprint, qtable, values };
}

async function sha256(bytes) {
  if (!(globalThis.crypto && globalThis.crypto.subtle)) return null;
  return new Uint8Array(await globalThis.crypto.subtle.digest('SHA-256', bytes));
}

/** SHA-256 of the mesh's positions (float32 LE) and triangles (uint32 LE),
 * as BaseMesh.fingerprint; null where WebCrypto is unavailable (a page served
 * to another machine over plain http is not a secure context). */
export async function meshFingerprint(geometry) {
  const pos = geometry.getAttribute('position').array;
  const index = Uint32Array.from(geometry.index.array);
  const all = new Uint8Array(pos.byteLength + index.byteLength);
  all.set(new Uint8Array(pos.buffer, pos.byteOffset, pos.byteLength), 0);
  all.set(new Uint8Array(index.buffer), pos.byteLength);
  return sha256(all);
}

/** The mesh check of axialdeform.core.params.check_mesh. */
function checkMesh(p, cfg, actual) {
  const axisNames = ['x', 'y', 'z'];
  if (p.fingerprint.some((b) => b !== 0)) {
    const want = actual ? hex(actual) : cfg.mesh.fingerprint;
    if (hex(p.fingerprint) !== want) {
      throw new SceneError(`${p.name}: made for a different base mesh (fingerprint ${hex(p.fingerprint).slice(0, 16)}, ` +
        `expected ${want.slice(0, 16)} of ${cfg.mesh.name}); export it with the mesh it was made for`);
    }
  }
  if (p.axis >= 0 && p.axis !== cfg.mesh.axis) {
    throw new SceneError(`${p.name}: made for a mesh whose control axis is ${axisNames[p.axis]}, ` +
      `but ${cfg.mesh.name}'s is ${axisNames[cfg.mesh.axis]}`);
  }
}

function el(tag, cls, parent) {
  const e = document.createElement(tag);
  e.className = cls;
  parent.appendChild(e);
  return e;
}

/**
 * Draw the scene into `root`.
 * scene = {config, glb: ArrayBuffer, adp: ArrayBuffer}
 * Returns {ready: Promise<{instances}> (first frame drawn; rejects with the
 * message shown), setParams(ArrayBuffer, name), dispose()}.
 */
export function mount(root, lib, scene) {
  const { THREE, OrbitControls, GLTFLoader } = lib;
  const cfg = scene.config;
  const [W, H] = cfg.size;
  root.classList.add('axd-root');
  const stage = el('div', 'axd-stage', root);
  stage.style.width = `${W}px`;
  stage.style.height = `${H}px`;
  stage.style.position = 'relative';
  stage.style.background = `rgb(${cfg.background.map((c) => Math.round(c * 255)).join(',')})`;
  const message = el('div', 'axd-message', stage);
  message.setAttribute('role', 'alert');
  message.hidden = true;
  const status = el('div', 'axd-status', root);
  status.textContent = 'loading…';

  let renderer = null, controls = null, material = null, geometry = null, fingerprint = null;
  let disposed = false;
  const state = { count: 0 };

  function showError(err) {
    const text = err instanceof SceneError ? err.message : `error: ${err && err.message ? err.message : err}`;
    message.textContent = text;
    message.hidden = false;
    status.textContent = 'nothing drawn';
    if (renderer) renderer.domElement.style.visibility = 'hidden';
    return text;
  }

  function instanceAttributes(p) {
    // the file's records, as they are, in one interleaved instanced buffer
    const buf = new THREE.InstancedInterleavedBuffer(p.values, p.fields, 1);
    const f = p.fields;
    if (p.encoding === 1) {
      const parts = [['i_q0', 4, 0], ['i_q1', 4, 4], ['i_q2', 4, 8], ['i_q3', 4, 12]];
      if (f === 19) parts.push(['i_q4', 3, 16]);
      for (const [n, size, off] of parts) {
        const a = new THREE.InterleavedBufferAttribute(buf, size, off, false);
        a.gpuType = THREE.IntType; // uvecN in the shader: vertexAttribIPointer
        geometry.setAttribute(n, a);
      }
      const u = material.uniforms;
      u.u_qmin.value = p.qtable.slice(0, 16);
      u.u_qstep.value = p.qtable.slice(f, f + 16);
      if (f === 19) {
        u.u_qmin_extra.value = new THREE.Vector3().fromArray(p.qtable, 16);
        u.u_qstep_extra.value = new THREE.Vector3().fromArray(p.qtable, 19 + 16);
      }
    } else {
      const parts = [['i_d12', 4, 0], ['i_d34', 4, 4], ['i_d5', 2, 8], ['i_position', 3, 10], ['i_angles', 3, 13]];
      if (f === 19) parts.push(['i_extra', 3, 16]);
      for (const [n, size, off] of parts) geometry.setAttribute(n, new THREE.InterleavedBufferAttribute(buf, size, off, false));
    }
  }

  function variant(p) {
    return (p.encoding === 1 ? 'quantized' : 'float') + (p.fields === 19 ? '_extended' : '');
  }

  function makeMaterial(key) {
    const sh = cfg.shaders[key];
    const v3 = (a) => new THREE.Vector3().fromArray(a);
    // three.js writes the version line itself (glslVersion), then its own defines
    const body = (src) => src.replace(/^#version 300 es\n/, '');
    return new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: body(sh.vertex),
      fragmentShader: body(sh.fragment),
      side: cfg.cull_back_faces ? THREE.FrontSide : THREE.DoubleSide,
      uniforms: {
        u_view: { value: null }, u_proj: { value: null },
        u_axis: { value: cfg.mesh.axis }, u_lo: { value: cfg.mesh.lo }, u_len: { value: cfg.mesh.length },
        u_center: { value: new THREE.Vector2().fromArray(cfg.mesh.center) },
        u_qmin: { value: new Float32Array(16) }, u_qstep: { value: new Float32Array(16) },
        u_qmin_extra: { value: new THREE.Vector3() }, u_qstep_extra: { value: new THREE.Vector3() },
        u_mode: { value: cfg.mode_index }, u_color: { value: v3(cfg.color) }, u_line_color: { value: v3(cfg.line_color) },
        u_light_dir: { value: v3(cfg.light_dir) }, u_up: { value: v3(cfg.up) }, u_eye: { value: new THREE.Vector3() },
        u_ambient: { value: cfg.ambient },
      },
    });
  }

  async function prepare(adp, name) {
    const p = parseAdp(adp, name);
    checkMesh(p, cfg, fingerprint);
    if (!cfg.shaders[variant(p)]) {
      throw new SceneError(`${name}: ${p.fields}-number instances, but this page was exported without their shader`);
    }
    return p;
  }

  let currentVariant = null;
  let mesh = null;

  function apply(p) {
    if (variant(p) !== currentVariant) {
      const old = material;
      material = makeMaterial(variant(p));
      if (old) {
        for (const k of ['u_view', 'u_proj', 'u_eye']) material.uniforms[k].value = old.uniforms[k].value;
        old.dispose();
      }
      if (mesh) mesh.material = material;
      currentVariant = variant(p);
      // attributes of the other layout go
      for (const n of Object.keys(geometry.attributes)) if (n.startsWith('i_')) geometry.deleteAttribute(n);
    }
    instanceAttributes(p);
    geometry.instanceCount = p.count;
    state.count = p.count;
  }

  const ready = (async () => {
    const gltf = await new Promise((resolve, reject) => new GLTFLoader().parse(scene.glb, '', resolve, (e) =>
      reject(new SceneError(`${cfg.mesh.file}: not a readable glTF binary (${e && e.message ? e.message : e})`))));
    let base = null;
    gltf.scene.traverse((o) => { if (!base && o.isMesh) base = o.geometry; });
    if (!base || !base.index) throw new SceneError(`${cfg.mesh.file}: holds no indexed triangle mesh`);
    fingerprint = await meshFingerprint(base);
    if (fingerprint && hex(fingerprint) !== cfg.mesh.fingerprint) {
      throw new SceneError(`${cfg.mesh.file}: not the base mesh this page was exported with (fingerprint ` +
        `${hex(fingerprint).slice(0, 16)}, expected ${cfg.mesh.fingerprint.slice(0, 16)})`);
    }
    const p = await prepare(scene.adp, cfg.params_file);

    geometry = new THREE.InstancedBufferGeometry();
    geometry.setIndex(base.index);
    geometry.setAttribute('in_position', base.getAttribute('position'));
    geometry.setAttribute('in_normal', base.getAttribute('normal'));
    apply(p);

    THREE.ColorManagement.enabled = false; // colours are written as render's, unconverted
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    if (!renderer.capabilities.isWebGL2) throw new SceneError('this browser has no WebGL 2');
    renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setSize(W, H);
    renderer.setClearColor(new THREE.Color(...cfg.background), 1);
    let shaderError = null;
    renderer.debug.onShaderError = (gl, program, vs, fs) => {
      const log = [gl.getShaderInfoLog(vs), gl.getShaderInfoLog(fs), gl.getProgramInfoLog(program)]
        .filter((x) => x && x.trim()).join(' ').trim();
      shaderError = `the shaders did not compile in this browser: ${log || 'no log'}`;
    };
    renderer.domElement.classList.add('axd-canvas');
    stage.insertBefore(renderer.domElement, message);

    const c = cfg.camera;
    const camera = new THREE.PerspectiveCamera(c.fovy, W / H, c.near, c.far);
    camera.up.fromArray(c.up);
    camera.position.fromArray(c.eye);
    camera.lookAt(new THREE.Vector3().fromArray(c.target));
    camera.updateMatrixWorld();
    // depth range while orbiting: the exported near/far keep their distances
    // from the target (the scene's radius), so zooming never clips the scene
    const d0 = camera.position.distanceTo(new THREE.Vector3().fromArray(c.target));
    const reach = c.far - d0;
    controls = new OrbitControls(camera, renderer.domElement);
    controls.target.fromArray(c.target);
    controls.addEventListener('change', () => {
      const d = camera.position.distanceTo(controls.target);
      camera.far = d + reach;
      camera.near = Math.max(d - reach, camera.far * 1e-4);
      camera.updateProjectionMatrix();
    });
    controls.update();
    camera.near = c.near; camera.far = c.far; camera.updateProjectionMatrix();

    material.uniforms.u_view.value = camera.matrixWorldInverse;
    material.uniforms.u_proj.value = camera.projectionMatrix;
    material.uniforms.u_eye.value = camera.position;
    mesh = new THREE.Mesh(geometry, material);
    mesh.frustumCulled = false; // the bounds of the base mesh are not those of the bent instances
    const world = new THREE.Scene();
    world.add(mesh);

    let frames = 0, since = performance.now(), fps = 0;
    const fmt = new Intl.NumberFormat('en-US');
    const showStatus = () => {
      status.textContent = `${fmt.format(state.count)} instances · ${fps ? fps.toFixed(fps < 10 ? 1 : 0) : '…'} fps`;
    };
    let first = null, failed = null;
    const drawn = new Promise((resolve, reject) => { first = resolve; failed = reject; });
    renderer.setAnimationLoop(() => {
      if (disposed) return;
      controls.update();
      material.uniforms.u_view.value = camera.matrixWorldInverse;
      material.uniforms.u_proj.value = camera.projectionMatrix;
      material.uniforms.u_eye.value = camera.position;
      renderer.render(world, camera);
      frames += 1;
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
        // the first frame is on screen once the GPU has finished it
        renderer.getContext().finish();
        showStatus();
        first({ instances: state.count });
        first = failed = null;
      }
    });
    return drawn;
  })().catch((err) => {
    const text = showError(err);
    throw new SceneError(text);
  });

  return {
    ready,
    /** Replace the parameters by another .adp (ArrayBuffer); a bad file keeps
     * nothing wrong on screen: the message says why and nothing is drawn. */
    async setParams(adp, name = 'parameters') {
      await ready.catch(() => null);
      if (!geometry) return;
      try {
        const p = await prepare(adp, name);
        apply(p);
        message.hidden = true;
        renderer.domElement.style.visibility = '';
        return { instances: p.count };
      } catch (err) {
        showError(err);
        geometry.instanceCount = 0;
        state.count = 0;
        throw err;
      }
    },
    dispose() {
      disposed = true;
      if (renderer) { renderer.setAnimationLoop(null); renderer.dispose(); }
      if (controls) controls.dispose();
      if (material) material.dispose();
      if (geometry) geometry.dispose();
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
