// World → camera pixels through the station's calibration (GET /api/calibration or the websocket's
// "calibration" message): T_world_camera (camera → world), K and OpenCV distortion. Pure functions.

/** The calibration's camera model {R, t, K, dist}, or null when it is missing or malformed. */
export function cameraModel(calibration) {
  const c = calibration || {};
  const T = c.T_world_camera;
  const K = c.K;
  if (!c.calibrated || !Array.isArray(T) || T.length < 3 || !Array.isArray(K) || K.length !== 3) return null;
  const rows = T.slice(0, 3);
  if (!rows.every((r) => Array.isArray(r) && r.length === 4 && r.every(Number.isFinite))) return null;
  if (!K.every((r) => Array.isArray(r) && r.length === 3 && r.every(Number.isFinite))) return null;
  const R = rows.map((r) => r.slice(0, 3)); // camera axes in world coordinates (columns)
  const t = rows.map((r) => r[3]); // camera centre in the world
  const dist = Array.isArray(c.dist) ? c.dist.filter(Number.isFinite) : [];
  return { R, t, K, dist };
}

/**
 * Camera pixel {u, v} of world point pointM = [x, y, z] (metres) for `model` (cameraModel()), with
 * OpenCV's k1 k2 p1 p2 k3 distortion; null behind the camera or without a model.
 */
export function worldToCameraPx(pointM, model) {
  if (!model || !Array.isArray(pointM) || pointM.length < 3 || !pointM.every(Number.isFinite)) return null;
  const { R, t, K, dist } = model;
  const d = [pointM[0] - t[0], pointM[1] - t[1], pointM[2] - t[2]];
  // p_camera = R^T (p_world - t)
  const x = R[0][0] * d[0] + R[1][0] * d[1] + R[2][0] * d[2];
  const y = R[0][1] * d[0] + R[1][1] * d[1] + R[2][1] * d[2];
  const z = R[0][2] * d[0] + R[1][2] * d[1] + R[2][2] * d[2];
  if (!(z > 1e-6)) return null;
  let a = x / z;
  let b = y / z;
  const [k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0] = dist;
  const r2 = a * a + b * b;
  const radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
  const ad = a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a);
  const bd = b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b;
  a = ad;
  b = bd;
  return { u: K[0][0] * a + K[0][1] * b + K[0][2], v: K[1][1] * b + K[1][2] };
}
