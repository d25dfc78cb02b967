// widget.js -- the anywidget front end of axialdeform.widget.SceneWidget: the
// same page code (app.js) as the exported page, loaded from the model's
// _sources by loadModules (loader.js, prepended to this text by Python).
/* global loadModules */ // from loader.js, prepended by Python
const bytesOf = (v) => (v instanceof DataView ? v.buffer.slice(v.byteOffset, v.byteOffset + v.byteLength)
  : v instanceof ArrayBuffer ? v : new Uint8Array(v).buffer);

// three.js and app.js are imported ONCE per browser page, shared by every view of every
// SceneWidget (a notebook shows a widget again, re-runs its cell, shows several): one copy
// of three.js, not one per view.  Keyed by the sources' text, so two axialdeform versions
// on one page each get their own.
const LOADED = (globalThis.__axialdeformModules ??= new Map());

function modules(sources) {
  const key = [...['three', 'orbit', 'gltf', 'bgu', 'app'].map((k) => sources[k]),
    ...Object.values(sources.module || {})].join('\u0000');
  if (!LOADED.has(key)) {
    const loading = loadModules(sources).then(({ lib, app, urls }) => {
      urls.forEach((u) => URL.revokeObjectURL(u)); // imported: the module map keeps them
      return { lib, app };
    });
    loading.catch(() => LOADED.delete(key)); // a failed load is tried again by the next view
    LOADED.set(key, loading);
  }
  return LOADED.get(key);
}

export default {
  async render({ model, el }) {
    const { lib, app } = await modules(model.get('_sources'));
    // keys pressed while the picture has focus are the picture's: JupyterLab (lumino) runs no
    // shortcut for a key whose target carries this attribute (without it, 'd d' on a focused
    // picture deleted the cell); lumino looks at the target first, so it goes on what takes focus
    const ownKeys = (e) => e.target.setAttribute('data-lm-suppress-shortcuts', 'true');
    el.addEventListener('focusin', ownKeys);
    const report = (status) => { model.set('status', status); model.save_changes(); };
    // a scene of several layers brings every file by name; one mesh, its GLB and .adp
    const files = model.get('files') || {};
    // the brush's masks (M) go to Python, which saves each beside the scene file (SceneWidget._on_mask)
    const onMask = (layer, file, png) => model.send({ type: 'mask', layer, file }, undefined, [png.buffer]);
    const view = app.mount(el, lib, Object.keys(files).length
      ? { config: model.get('config'), files: Object.fromEntries(Object.entries(files).map(([k, v]) => [k, bytesOf(v)])) }
      : { config: model.get('config'), glb: bytesOf(model.get('mesh_glb')), adp: bytesOf(model.get('params_adp')) },
    { onMask });
    el.axialdeformView = view; // scripts and tests: paint(), mask(), saveMasks()
    view.ready.then((r) => report({ ready: true, instances: r.instances }),
      (e) => report({ ready: false, error: e.message }));
    const onParams = () => view.setParams(bytesOf(model.get('params_adp')), 'parameters')
      .then((r) => { view.refit(model.get('config')); return r; })
      .then((r) => report({ ready: true, instances: r ? r.instances : 0 }), (e) => report({ ready: false, error: e.message }));
    model.on('change:params_adp', onParams);
    return () => {
      model.off('change:params_adp', onParams);
      el.removeEventListener('focusin', ownKeys);
      const canvas = el.querySelector('canvas');
      view.dispose();
      // a view that goes gives its WebGL context back now, not at garbage collection: a notebook
      // re-running a cell would otherwise reach Chromium's 16 live contexts and lose the oldest
      const gl = canvas && (canvas.getContext('webgl2') || canvas.getContext('webgl'));
      const lose = gl && gl.getExtension('WEBGL_lose_context');
      if (lose) lose.loseContext();
    };
  },
};
