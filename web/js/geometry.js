// Pure view geometry: where a pointer lands in the shown image, and the top-down warp's pixel↔world map.
// No DOM access here, so every function can be checked in isolation. The workcell's geometry (board,
// block sizes) is not written here: the server sends it in the websocket hello (WorkcellInfo).

/**
 * The board's extent {xMin, xMax, yMin, yMax} (world frame, metres) from the workcell the server sent
 * in its hello (WorkcellInfo), or null when it is missing or malformed.
 */
export function boardBoundsFromWorkcell(workcell) {
  const board = workcell && workcell.board;
  const x = board && board.x_range_m;
  const y = board && board.y_range_m;
  if (!(Array.isArray(x) && Array.isArray(y) && x.length === 2 && y.length === 2)) return null;
  if (![...x, ...y].every(Number.isFinite) || !(x[0] < x[1] && y[0] < y[1])) return null;
  return Object.freeze({ xMin: x[0], xMax: x[1], yMin: y[0], yMax: y[1] });
}

/** Cube edge (metres) of a block size ("large", "small") in the hello's workcell, or null if unknown. */
export function blockEdgeM(workcell, size) {
  const edge = workcell && workcell.block_edges_m && workcell.block_edges_m[size];
  return Number.isFinite(edge) && edge > 0 ? edge : null;
}

/**
 * Map a pointer position inside an element (CSS px, origin top-left) to image pixels when an
 * image of imageW×imageH is drawn with `object-fit: contain`. Returns null outside the image.
 */
export function elementToImagePx(xCss, yCss, elementW, elementH, imageW, imageH) {
  if (!(elementW > 0 && elementH > 0 && imageW > 0 && imageH > 0)) return null;
  const scale = Math.min(elementW / imageW, elementH / imageH);
  const shownW = imageW * scale;
  const shownH = imageH * scale;
  const offsetX = (elementW - shownW) / 2;
  const offsetY = (elementH - shownH) / 2;
  const u = (xCss - offsetX) / scale;
  const v = (yCss - offsetY) / scale;
  if (u < 0 || v < 0 || u > imageW || v > imageH) return null;
  return { u, v };
}

/** Inverse of elementToImagePx: image pixels → element CSS px (for placing markers and test clicks). */
export function imagePxToElement(u, v, elementW, elementH, imageW, imageH) {
  const scale = Math.min(elementW / imageW, elementH / imageH);
  const offsetX = (elementW - imageW * scale) / 2;
  const offsetY = (elementH - imageH * scale) / 2;
  return { x: offsetX + u * scale, y: offsetY + v * scale };
}

/** Scale pixels of a (possibly downscaled) streamed frame to the camera's full-resolution pixels. */
export function frameToCameraPx(u, v, frameW, frameH, cameraW, cameraH) {
  const sx = cameraW > 0 ? cameraW / frameW : 1;
  const sy = cameraH > 0 ? cameraH / frameH : 1;
  return { u: u * sx, v: v * sy };
}

/**
 * Top-down warp: the board rectangle `bounds` fills the image, +x to the right, +y up (far edge at
 * the top). Returns the world point (metres, on the board plane z = 0) under image pixel (u, v), or
 * null without bounds.
 */
export function topdownPxToWorld(u, v, imageW, imageH, bounds) {
  if (!bounds) return null;
  const x = bounds.xMin + (u / imageW) * (bounds.xMax - bounds.xMin);
  const y = bounds.yMax - (v / imageH) * (bounds.yMax - bounds.yMin);
  return [x, y, 0];
}

/** Inverse of topdownPxToWorld (z ignored); null without bounds. */
export function worldToTopdownPx(xM, yM, imageW, imageH, bounds) {
  if (!bounds) return null;
  const u = ((xM - bounds.xMin) / (bounds.xMax - bounds.xMin)) * imageW;
  const v = ((bounds.yMax - yM) / (bounds.yMax - bounds.yMin)) * imageH;
  return { u, v };
}

/** Format metres as whole millimetres with a sign, e.g. "+123". */
export function fmtMm(valueM) {
  if (!Number.isFinite(valueM)) return "—";
  const mm = Math.round(valueM * 1000);
  return (mm >= 0 ? "+" : "") + mm;
}

/** Radians → degrees with one decimal. */
export function fmtDeg(valueRad, digits = 1) {
  if (!Number.isFinite(valueRad)) return "—";
  return ((valueRad * 180) / Math.PI).toFixed(digits);
}

/** Index of the detection whose centre is nearest (u, v) within maxDistPx, else -1. */
export function nearestDetection(detections, u, v, maxDistPx) {
  let best = -1;
  let bestD2 = maxDistPx * maxDistPx;
  (detections || []).forEach((det, i) => {
    const c = det.center_px;
    if (!Array.isArray(c) || c.length < 2) return;
    const d2 = (c[0] - u) ** 2 + (c[1] - v) ** 2;
    if (d2 <= bestD2) {
      bestD2 = d2;
      best = i;
    }
  });
  return best;
}
