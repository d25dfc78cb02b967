// widget.js -- the anywidget front end of axialdeform.widget.SceneWidget: the
// same page code (app.js) as the exported page, loaded from the model's
// _sources by loadModules (loader.js, prepended to this text by Python).
const bytesOf = (v) => (v instanceof DataView ? v.buffer.slice(v.byteOffset, v.byteOffset + v.byteLength)
  : v instanceof ArrayBuffer ? v : new Uint8Array(v).buffer);

export default {
  async render({ model, el }) {
    const { lib, app, urls } = await loadModules(model.get('_sources'));
    const report = (status) => { model.set('status', status); model.save_changes(); };
    const view = app.mount(el, lib, { config: model.get('config'), glb: bytesOf(model.get('mesh_glb')),
      adp: bytesOf(model.get('params_adp')) });
    view.ready.then((r) => report({ ready: true, instances: r.instances }),
      (e) => report({ ready: false, error: e.message }));
    const onParams = () => view.setParams(bytesOf(model.get('params_adp')), 'parameters')
      .then((r) => report({ ready: true, instances: r ? r.instances : 0 }), (e) => report({ ready: false, error: e.message }));
    model.on('change:params_adp', onParams);
    return () => {
      model.off('change:params_adp', onParams);
      view.dispose();
      urls.forEach((u) => URL.revokeObjectURL(u));
    };
  },
};
