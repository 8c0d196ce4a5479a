// The live view: draws streamed frames on the canvas with client-side markers (hovered detection,
// last click target), reports the world point under the cursor, and turns clicks into targets.

import { cameraModel, worldToCameraPx } from "./projection.js";
import { drawTopdownDetections, drawTopdownGrid, drawTopdownTags } from "./topdown.js";
import {
  boardBoundsFromWorkcell,
  elementToImagePx,
  fmtMm,
  frameToCameraPx,
  nearestDetection,
  topdownPxToWorld,
  worldToTopdownPx,
} from "./geometry.js";

const HOVER_INTERVAL_MS = 80;
const PICK_RADIUS_PX = 40;

export class LiveView {
  /**
   * canvas: the <canvas>; hoverLabel: element for "x y z mm"; api: Api (pixel-to-world);
   * onTarget({mode, u, v, positionM}) is called for clicks in grab/drop mode;
   * onHoverDetection(index) highlights a row of the detections list.
   */
  constructor({ canvas, wrap, placeholder, hoverLabel, api, onTarget, onHoverDetection, onHoverTarget }) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.wrap = wrap;
    this.placeholder = placeholder;
    this.hoverLabel = hoverLabel;
    this.api = api;
    this.onTarget = onTarget;
    this.onHoverDetection = onHoverDetection || (() => {});
    this.onHoverTarget = onHoverTarget || (() => {}); // (mode, target | null): the point the pointer reads now
    this.mode = "inspect";
    this.layers = [];
    this.calibrated = false;
    this.header = null;
    this.bitmap = null;
    this.detections = [];
    this.hoverDetection = -1;
    this.marker = null; // {u, v, label, color} in frame pixels (camera views) or world (topdown)
    this.hoverPending = null;
    this.hoverSeq = 0; // pointer events so far: an answer is shown only for the newest
    this.hoverBusy = false;
    this.hoverTimer = null;
    this.framesDrawn = 0;
    this.overlays = []; // functions (liveView) => void drawn over every frame (e.g. the competition plan)
    this.workcell = null; // WorkcellInfo from the server's hello: board bounds, block sizes
    this.boardBounds = null;
    this.cameraModel = null; // from the calibration: world → camera pixels (top-down hover reads z there)
    canvas.addEventListener("mousemove", (e) => this.onMove(e));
    canvas.addEventListener("mouseleave", () => this.onLeave());
    canvas.addEventListener("click", (e) => this.onClick(e));
  }

  setMode(mode) {
    this.mode = mode;
    this.wrap.dataset.mode = mode;
  }

  /** The workcell geometry the server sent in its hello (WorkcellInfo). */
  setWorkcell(workcell) {
    this.workcell = workcell || null;
    this.boardBounds = boardBoundsFromWorkcell(this.workcell);
  }

  /** The top-down warp's bounds: the workcell's board, which the server's warp fills (null before the hello). */
  topdownBounds() {
    return this.boardBounds;
  }

  /** untrusted: seen through a camera the calibration no longer fits; each is marked so on the view. */
  setDetections(detections, untrusted = false) {
    this.detections = Array.isArray(detections) ? detections : [];
    this.detectionsUntrusted = Boolean(untrusted);
    this.canvas.dataset.detections = untrusted ? "untrusted" : "trusted";
  }

  /** Draw one decoded frame and the client-side markers; resolves when drawn (then the frame is acked). */
  drawFrame(header, bitmap) {
    if (this.canvas.width !== bitmap.width || this.canvas.height !== bitmap.height) {
      this.canvas.width = bitmap.width;
      this.canvas.height = bitmap.height;
    }
    this.header = header;
    this.bitmap?.close?.();
    this.bitmap = bitmap;
    this.redraw();
    this.framesDrawn += 1;
    this.placeholder.hidden = true;
    this.canvas.dataset.frames = String(this.framesDrawn);
    this.canvas.dataset.view = header.view || "color";
  }

  redraw() {
    const { ctx, canvas } = this;
    if (this.bitmap) ctx.drawImage(this.bitmap, 0, 0, canvas.width, canvas.height);
    const scale = canvas.width / 1280;
    if (this.hoverDetection >= 0 && this.view() !== "topdown") {
      const det = this.detections[this.hoverDetection];
      const c = det && this.cameraToFramePx(det.center_px);
      if (c) this.ring(c.u, c.v, 26 * Math.max(scale, 0.5), "#ffffff");
    }
    if (this.view() === "topdown") this.drawTopdownLayers();
    else if (this.detectionsUntrusted && this.layers.includes("detections")) this.markUntrusted(Math.max(scale, 0.5));
    if (this.marker) {
      const p = this.markerFramePx(this.marker);
      if (p) this.cross(p.u, p.v, this.marker.color, this.marker.label, Math.max(scale, 0.5));
    }
    for (const draw of this.overlays) draw(this);
  }

  /** The page's own overlays on the top-down warp: the layers the operator ticked (the server draws them on camera views). */
  drawTopdownLayers() {
    const b = this.topdownBounds();
    if (this.layers.includes("grid")) drawTopdownGrid(this.ctx, this.canvas, b, this.workcell);
    if (this.layers.includes("tags")) drawTopdownTags(this.ctx, this.canvas, b, this.workcell);
    if (this.layers.includes("detections")) {
      drawTopdownDetections(this.ctx, this.canvas, b, this.workcell, this.detections, this.hoverDetection);
    }
  }

  /** The calibration (for projecting world points into the camera image); null/uncalibrated clears it. */
  setCalibration(calibration) {
    this.cameraModel = cameraModel(calibration);
  }

  /** The view the shown frame really is: the server falls back to colour for top-down until calibrated. */
  view() {
    const v = (this.header && this.header.view) || "color";
    return v === "topdown" && !this.calibrated ? "color" : v;
  }

  /** Size of the camera image the server's pixel coordinates refer to. */
  cameraSize() {
    const h = this.header || {};
    return {
      w: h.camera_width || h.source_width || h.width || this.canvas.width,
      h: h.camera_height || h.source_height || h.height || this.canvas.height,
    };
  }

  cameraToFramePx(centerPx) {
    if (!Array.isArray(centerPx) || centerPx.length < 2) return null;
    const cam = this.cameraSize();
    return { u: (centerPx[0] * this.canvas.width) / cam.w, v: (centerPx[1] * this.canvas.height) / cam.h };
  }

  markerFramePx(marker) {
    if (this.view() === "topdown") {
      if (!marker.positionM) return null;
      return worldToTopdownPx(marker.positionM[0], marker.positionM[1], this.canvas.width, this.canvas.height, this.topdownBounds());
    }
    return marker.cameraPx ? this.cameraToFramePx(marker.cameraPx) : null;
  }

  /** A struck-through "not trusted" tag on each detection: the calibration no longer fits the camera. */
  markUntrusted(s) {
    const { ctx } = this;
    ctx.save();
    ctx.font = `bold ${Math.round(14 * s)}px sans-serif`;
    for (const det of this.detections) {
      const c = this.cameraToFramePx(det.center_px);
      if (!c) continue;
      this.ring(c.u, c.v, 22 * s, "#ff9f1a");
      ctx.strokeStyle = "#ff9f1a";
      ctx.lineWidth = 2 * s;
      ctx.beginPath();
      ctx.moveTo(c.u - 16 * s, c.v + 16 * s);
      ctx.lineTo(c.u + 16 * s, c.v - 16 * s);
      ctx.stroke();
      ctx.fillStyle = "#ff9f1a";
      ctx.fillText("not trusted", c.u - 36 * s, c.v + 38 * s);
    }
    ctx.restore();
  }

  ring(u, v, r, color) {
    const { ctx } = this;
    ctx.save();
    ctx.strokeStyle = color;
    ctx.lineWidth = 2;
    ctx.setLineDash([5, 4]);
    ctx.beginPath();
    ctx.arc(u, v, r, 0, 2 * Math.PI);
    ctx.stroke();
    ctx.restore();
  }

  cross(u, v, color, label, s) {
    const { ctx } = this;
    ctx.save();
    ctx.strokeStyle = color;
    ctx.lineWidth = 3 * s;
    ctx.beginPath();
    ctx.moveTo(u - 14 * s, v);
    ctx.lineTo(u + 14 * s, v);
    ctx.moveTo(u, v - 14 * s);
    ctx.lineTo(u, v + 14 * s);
    ctx.stroke();
    if (label) {
      ctx.font = `${Math.round(16 * s)}px sans-serif`;
      ctx.fillStyle = color;
      ctx.fillText(label, u + 16 * s, v - 10 * s);
    }
    ctx.restore();
  }

  /** Pointer → {frame px, camera px} or null when outside the image. */
  pointerToPx(event) {
    if (!this.header) return null;
    const rect = this.canvas.getBoundingClientRect();
    const p = elementToImagePx(
      event.clientX - rect.left,
      event.clientY - rect.top,
      rect.width,
      rect.height,
      this.canvas.width,
      this.canvas.height,
    );
    if (!p) return null;
    const cam = this.cameraSize();
    const c = frameToCameraPx(p.u, p.v, this.canvas.width, this.canvas.height, cam.w, cam.h);
    return { frame: p, camera: c };
  }

  onLeave() {
    this.onHoverTarget(this.mode, null);
    this.hoverSeq += 1;
    this.hoverPending = null;
    this.setHoverDetection(-1);
    this.hoverLabel.textContent = "x — y — z — mm";
    this.hoverLabel.title = "World coordinates under the cursor";
    this.hoverLabel.dataset.hidden = "false";
  }

  setHoverDetection(index) {
    if (index === this.hoverDetection) return;
    this.hoverDetection = index;
    this.onHoverDetection(index);
  }

  onMove(event) {
    this.hoverSeq += 1; // a server answer for an earlier pointer position (or view) is dropped
    const px = this.pointerToPx(event);
    if (!px) {
      this.onLeave();
      return;
    }
    if (this.view() === "topdown") {
      const w = topdownPxToWorld(px.frame.u, px.frame.v, this.canvas.width, this.canvas.height, this.topdownBounds());
      if (!w) return;
      const world = this.detections.map((d) => ({ center_px: d.position_m ? [d.position_m[0], d.position_m[1]] : null }));
      this.setHoverDetection(nearestDetection(world, w[0], w[1], 0.03));
      // x, y at once; z (and the camera pixel and depth) from the server at the camera pixel that sees this point.
      this.showWorld([w[0], w[1], NaN], null);
      const cam = worldToCameraPx(w, this.cameraModel);
      if (!cam) return;
      this.hoverPending = { u: cam.u, v: cam.v, xyM: [w[0], w[1]], seq: this.hoverSeq };
      this.pumpHover();
      return;
    }
    this.setHoverDetection(nearestDetection(this.detections, px.camera.u, px.camera.v, PICK_RADIUS_PX));
    this.hoverPending = { u: px.camera.u, v: px.camera.v, seq: this.hoverSeq };
    this.pumpHover();
  }

  /** At most one pixel-to-world request in flight (read-only, no token needed); the newest pointer wins. */
  pumpHover() {
    if (this.hoverBusy || this.hoverTimer || !this.hoverPending) return;
    const { u, v, xyM, seq } = this.hoverPending;
    const view = this.view();
    this.hoverPending = null;
    this.hoverBusy = true;
    this.api
      .pixelToWorld(u, v)
      .then((r) => {
        // On the top-down view the board point under the pointer keeps its x, y; the server gives z there.
        // An answer for a point the pointer has left is dropped when it is of another view, of the top-down
        // view (x, y are shown at once), or when the newer point's request is waiting to go.
        const stale = seq !== this.hoverSeq && (view !== this.view() || xyM || this.hoverPending);
        if (stale) return;
        const position = xyM ? [xyM[0], xyM[1], r.position_m[2]] : r.position_m;
        this.showWorld(position, r.on, { u, v, depthMm: r.depth_mm });
        this.onHoverTarget(this.mode, xyM ? { position_m: position } : { u, v });
      })
      .catch((e) => {
        if (seq !== this.hoverSeq) return;
        delete this.hoverLabel.dataset.positionM;
        this.onHoverTarget(this.mode, null);
        // pixel-to-world is read-only: its one 409 is a spot hidden by the arm that changed since it was seen (the
        // station never shows a remembered depth older than the last change there). Say so, never an old number.
        const hidden = e.status === 409 && e.code === "wrong_state";
        this.hoverLabel.dataset.hidden = String(hidden);
        this.hoverLabel.title = e.message;
        this.hoverLabel.textContent = e.code === "not_calibrated" ? "calibrate to read world mm"
          : hidden ? "x — y — z unknown: hidden by the arm, changed since seen (Sleep to look)" : e.message;
      })
      .finally(() => {
        this.hoverBusy = false;
        this.hoverTimer = setTimeout(() => {
          this.hoverTimer = null;
          this.pumpHover();
        }, HOVER_INTERVAL_MS);
      });
  }

  /** The readout: camera pixel u, v and its raw depth (when known), then the world point in mm. */
  showWorld(positionM, on, pixel = null) {
    if (!Array.isArray(positionM)) return;
    const [x, y, z] = positionM;
    let text = "";
    if (pixel) {
      const depth = Number.isFinite(pixel.depthMm) ? (pixel.depthMm > 0 ? `${Math.round(pixel.depthMm)} mm` : "none") : "—";
      text = `u ${Math.round(pixel.u)} v ${Math.round(pixel.v)} depth ${depth} · `;
      this.hoverLabel.dataset.pixel = JSON.stringify([pixel.u, pixel.v, pixel.depthMm ?? null]);
    } else {
      delete this.hoverLabel.dataset.pixel;
    }
    this.hoverLabel.textContent = `${text}x ${fmtMm(x)}  y ${fmtMm(y)}  z ${fmtMm(z)} mm${on ? ` (${on})` : ""}`;
    this.hoverLabel.title = this.hoverLabel.textContent; // the full line where the fixed-width box cuts it
    this.hoverLabel.dataset.hidden = "false";
    this.hoverLabel.dataset.positionM = JSON.stringify(positionM);
  }

  onClick(event) {
    if (this.mode !== "grab" && this.mode !== "drop") return;
    if (event.detail > 1) return; // the second click of a double-click: one target only
    const px = this.pointerToPx(event);
    if (!px) return;
    const color = this.mode === "grab" ? "#2fbf71" : "#e0a030";
    const label = this.mode === "grab" ? "grab" : "drop";
    if (this.view() === "topdown") {
      const positionM = topdownPxToWorld(px.frame.u, px.frame.v, this.canvas.width, this.canvas.height, this.topdownBounds());
      if (!positionM) return;
      this.marker = { positionM, color, label };
      this.onTarget({ mode: this.mode, positionM });
    } else {
      this.marker = { cameraPx: [px.camera.u, px.camera.v], color, label };
      this.onTarget({ mode: this.mode, u: px.camera.u, v: px.camera.v });
    }
    this.redraw();
  }

  clearMarker() {
    this.marker = null;
    this.redraw();
  }
}
