// Starts what the 3-D panel needs the moment it is opened, before its module (and three.js) has loaded: the
// scene description and the arm's mesh files, fetched in parallel with the modules, whose import graph is
// flattened by modulepreload links (else each import is found only after its parent has loaded). Tiny and free
// of three.js, so the page without the panel loads nothing of it.

const MODULES = [
  "/js/view3d.js",
  "/js/view3d_scene.js",
  "/node_modules/three/build/three.module.js",
  "/node_modules/three/build/three.core.js",
  "/node_modules/three/examples/jsm/controls/OrbitControls.js",
  "/node_modules/three/examples/jsm/loaders/STLLoader.js",
  "/node_modules/urdf-loader/src/URDFLoader.js",
  "/node_modules/urdf-loader/src/URDFClasses.js",
];

/** {scene: Promise of GET /api/view3d/scene, meshes: Promise of Map url → Promise<ArrayBuffer>}. */
export function prefetchView3d(api, doc = document) {
  for (const href of MODULES) {
    if (doc.querySelector(`link[rel='modulepreload'][href='${href}']`)) continue;
    const link = doc.createElement("link");
    link.rel = "modulepreload";
    link.href = href;
    doc.head.appendChild(link);
  }
  const scene = api.get("/api/view3d/scene");
  const meshes = scene.then((description) => {
    const urls = description.arm?.mesh_urls || [];
    return new Map(urls.map((url) => [url, fetch(url).then((r) => {
      if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
      return r.arrayBuffer();
    })]));
  });
  meshes.catch(() => {}); // the panel reports a failure when it awaits the scene
  return { scene, meshes };
}
