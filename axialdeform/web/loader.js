// loader.js -- load the vendored three.js modules and app.js from their TEXT
// (single-file page, notebook widget): each becomes a blob: module URL and the
// imports between them ('three', '../utils/BufferGeometryUtils.js') are pointed
// at those URLs.  The folder page imports the same files through an import map.
//
// sources = {three, orbit, gltf, bgu, app, adp}: the text of each module.
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
  const adp = url(sources.adp); // the npm module's parser (axialdeform-three/adp), imported by app.js
  const app = url(sources.app.replace(/from\s*(['"])axialdeform-three\/adp\1/g, `from '${adp}'`));
  const [THREE, o, g, a] = await Promise.all([import(three), import(orbit), import(gltf), import(app)]);
  return { lib: { THREE, OrbitControls: o.OrbitControls, GLTFLoader: g.GLTFLoader }, app: a, urls };
}
