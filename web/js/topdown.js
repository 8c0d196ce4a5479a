// What the page draws itself on the top-down warp (the server draws overlays on the camera views only):
// the board grid, the calibration tags and the detections, all placed from world coordinates the server
// sent (the hello's workcell, the telemetry's detections). Label size follows the canvas size.

import { blockEdgeM, worldToTopdownPx } from "./geometry.js";

/** Font size (px) of labels on a canvas `width` pixels wide: readable when the canvas is scaled down. */
export function labelFontPx(width) {
  return Math.max(14, Math.round(width / 55));
}

/** The grid points of the workcell's board (hello workcell.board.grid) as dots. */
export function drawTopdownGrid(ctx, canvas, bounds, workcell) {
  const grid = workcell && workcell.board && workcell.board.grid;
  if (!bounds || !grid || !(grid.step_m > 0)) return 0;
  const [x0, x1] = grid.x_m;
  const [y0, y1] = grid.y_m;
  let count = 0;
  ctx.save();
  ctx.fillStyle = "#00ff66";
  for (let x = x0; x <= x1 + 1e-9; x += grid.step_m) {
    for (let y = y0; y <= y1 + 1e-9; y += grid.step_m) {
      const p = worldToTopdownPx(x, y, canvas.width, canvas.height, bounds);
      ctx.fillRect(p.u - 2, p.v - 2, 4, 4);
      count += 1;
    }
  }
  ctx.restore();
  return count;
}

/** The calibration tags (hello workcell.board_tags) as outlined squares with their ids. */
export function drawTopdownTags(ctx, canvas, bounds, workcell) {
  const tags = workcell && workcell.board_tags;
  if (!bounds || !tags || !tags.centres_m) return 0;
  const pxPerM = canvas.width / (bounds.xMax - bounds.xMin);
  const half = ((tags.size_m || 0.025) * pxPerM) / 2 + 3;
  ctx.save();
  ctx.strokeStyle = "#00ff66";
  ctx.lineWidth = 2;
  ctx.font = `bold ${labelFontPx(canvas.width)}px sans-serif`;
  ctx.fillStyle = "#00ff66";
  const entries = Object.entries(tags.centres_m);
  for (const [id, [x, y]] of entries) {
    const p = worldToTopdownPx(x, y, canvas.width, canvas.height, bounds);
    ctx.strokeRect(p.u - half, p.v - half, 2 * half, 2 * half);
    ctx.fillText(`tag ${id}`, p.u + half + 3, p.v + half);
  }
  ctx.restore();
  return entries.length;
}

/** Detections outlined like the block (edge from the workcell), with colour + size labels that do not overlap. */
export function drawTopdownDetections(ctx, canvas, bounds, workcell, detections, hoverIndex) {
  if (!bounds) return [];
  const pxPerM = canvas.width / (bounds.xMax - bounds.xMin);
  const fontPx = labelFontPx(canvas.width);
  const placed = [];
  ctx.save();
  ctx.lineWidth = 2;
  ctx.font = `bold ${fontPx}px sans-serif`;
  detections.forEach((det, i) => {
    if (!Array.isArray(det.position_m)) return;
    const p = worldToTopdownPx(det.position_m[0], det.position_m[1], canvas.width, canvas.height, bounds);
    const edge = blockEdgeM(workcell, det.size) ?? blockEdgeM(workcell, "large");
    if (edge === null) return;
    const half = (edge * pxPerM) / 2 + 4;
    ctx.strokeStyle = i === hoverIndex ? "#ffffff" : "#00e5ff";
    ctx.save();
    ctx.translate(p.u, p.v);
    ctx.rotate(-(det.yaw_rad || 0)); // world yaw is counter-clockwise; image v grows downwards
    ctx.strokeRect(-half, -half, 2 * half, 2 * half);
    ctx.restore();
    const text = `${det.color || "?"} ${det.size || ""}`.trim();
    const box = placeLabel(placed, p.u, p.v, half, ctx.measureText(text).width + 8, fontPx + 6);
    placed.push(box);
    ctx.fillStyle = "rgba(0, 0, 0, 0.7)";
    ctx.fillRect(box.x, box.y, box.w, box.h);
    ctx.fillStyle = "#00e5ff";
    ctx.fillText(text, box.x + 4, box.y + box.h - 5);
  });
  ctx.restore();
  return placed;
}

/** A label box {x, y, w, h} next to a marker at (u, v) of half-size `half` that overlaps none of `placed`. */
export function placeLabel(placed, u, v, half, w, h) {
  const candidates = [
    [u + half + 2, v - half - h], [u + half + 2, v + half], [u - half - 2 - w, v - half - h],
    [u - half - 2 - w, v + half], [u - w / 2, v - half - h - 2], [u - w / 2, v + half + 2],
  ];
  for (let ring = 0; ring < 6; ring += 1) {
    for (const [x, y0] of candidates) {
      const y = y0 + (y0 < v ? -ring * h : ring * h);
      const box = { x, y, w, h };
      if (!placed.some((b) => overlaps(b, box))) return box;
    }
  }
  return { x: candidates[0][0], y: candidates[0][1], w, h };
}

export function overlaps(a, b) {
  return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}
