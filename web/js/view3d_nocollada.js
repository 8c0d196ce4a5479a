// Stands in for three's ColladaLoader, which urdf-loader imports (index.html's import map points it here): the
// station's arms ship binary STL only (config/arm_meshes/), so the Collada parser (~120 kB) is never fetched.
export class ColladaLoader {
  load(url, _onLoad, _onProgress, onError) {
    onError?.(new Error(`${url}: Collada meshes are not served; the 3-D panel loads STL`));
  }
}
