// loader.js -- load the vendored three.js modules and app.js from their TEXT
// (single-file page, notebook widget): each becomes a blob: module URL and the
// imports between them ('three', '../utils/BufferGeometryUtils.js') are pointed
// at those URLs.  The folder page imports the same files through an import map.
//
// sources = {three, orbit, gltf, bgu, app, module: {'core/record.js': text, ...}}: the text of each module, the
// module's files in the order of their imports.

export async function loadModules(sources) {
  const urls = [];
  const url = (text) => {
    const u = URL.createObjectURL(new Blob([text], { type: 'text/javascript' }));
    urls.push(u);
    return u;
  };
  const three = url(sources.three);
  const fromThree = (text) => text.replace(/from\s*(['"])three\1/g, `from '${three}'`);
  const bgu = url(fromThree(sources.bgu));
  const gltf = url(fromThree(sources.gltf).replace(/(['"])\.\.\/utils\/BufferGeometryUtils\.js\1/g, `'${bgu}'`));
  const orbit = url(fromThree(sources.orbit));
  // the npm module axialdeform-three (js/src), file by file in the order the page gives them (Python's
  // MODULE_FILES: each after the files it imports; names relative to js/src, 'core/adp.js'): each file's
  // relative imports ('./mesh.js', '../core/adp.js') and 'three' pointed at the URLs made before it
  const mod = {};
  const resolve = (from, spec) => {
    const parts = from.split('/').slice(0, -1);
    for (const p of spec.split('/')) if (p === '..') parts.pop(); else if (p !== '.') parts.push(p);
    return parts.join('/');
  };
  for (const name of Object.keys(sources.module)) {
    const text = fromThree(sources.module[name]).replace(/(['"])(\.\.?\/[\w./]+\.js)\1/g,
      (whole, _q, spec) => (mod[resolve(name, spec)] ? `'${mod[resolve(name, spec)]}'` : whole));
    mod[name] = url(text);
  }
  const app = url(sources.app.replace(/from\s*(['"])axialdeform-three\1/g, `from '${mod['index.js']}'`)
    .replace(/from\s*(['"])axialdeform-three\/helpers\1/g, `from '${mod['helpers.js']}'`));
  const [THREE, o, g, a] = await Promise.all([import(three), import(orbit), import(gltf), import(app)]);
  return { lib: { THREE, OrbitControls: o.OrbitControls, GLTFLoader: g.GLTFLoader }, app: a, urls };
}
