// The live view: draws streamed frames on the canvas with client-side markers (hovered detection,
// last click target), reports the world point under the cursor, and turns clicks into targets.

import {
  blockEdgeM,
  boardBoundsFromWorkcell,
  boundsFromHeader,
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
  constructor({ canvas, wrap, placeholder, hoverLabel, api, onTarget, onHoverDetection }) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.wrap = wrap;
    this.placeholder = placeholder;
    this.hoverLabel = hoverLabel;
    this.api = api;
    this.onTarget = onTarget;
    this.onHoverDetection = onHoverDetection || (() => {});
    this.mode = "inspect";
    this.layers = [];
    this.calibrated = false;
    this.header = null;
    this.bitmap = null;
    this.detections = [];
    this.hoverDetection = -1;
    this.marker = null; // {u, v, label, color} in frame pixels (camera views) or world (topdown)
    this.hoverPending = null;
    this.hoverBusy = false;
    this.hoverTimer = null;
    this.framesDrawn = 0;
    this.overlays = []; // functions (liveView) => void drawn over every frame (e.g. the competition plan)
    this.workcell = null; // WorkcellInfo from the server's hello: board bounds, block sizes
    this.boardBounds = null;
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

  /** The top-down warp's bounds: the frame header's if it has them, else the workcell's board (null before the hello). */
  topdownBounds() {
    return boundsFromHeader(this.header, this.boardBounds);
  }

  setDetections(detections) {
    this.detections = Array.isArray(detections) ? detections : [];
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
    if (this.view() === "topdown" && this.layers.includes("detections")) this.drawTopdownDetections();
    if (this.marker) {
      const p = this.markerFramePx(this.marker);
      if (p) this.cross(p.u, p.v, this.marker.color, this.marker.label, Math.max(scale, 0.5));
    }
    for (const draw of this.overlays) draw(this);
  }

  /** The view the shown frame really is: the server falls back to colour for top-down until calibrated. */
  /**
   * The server draws overlays on the camera views only; on the top-down warp the page marks the
   * detections itself from their world positions (outline sized like the block, colour + size label).
   */
  drawTopdownDetections() {
    const { ctx, canvas } = this;
    const b = this.topdownBounds();
    if (!b) return;
    const pxPerM = canvas.width / (b.xMax - b.xMin);
    ctx.save();
    ctx.lineWidth = 2;
    ctx.font = `bold ${Math.max(12, Math.round(canvas.width / 60))}px sans-serif`;
    this.detections.forEach((det, i) => {
      if (!Array.isArray(det.position_m)) return;
      const p = worldToTopdownPx(det.position_m[0], det.position_m[1], canvas.width, canvas.height, b);
      const edge = blockEdgeM(this.workcell, det.size) ?? blockEdgeM(this.workcell, "large");
      if (edge === null) return;
      const half = (edge * pxPerM) / 2 + 4;
      ctx.strokeStyle = i === this.hoverDetection ? "#ffffff" : "#00e5ff";
      ctx.save();
      ctx.translate(p.u, p.v);
      ctx.rotate(-(det.yaw_rad || 0)); // world yaw is counter-clockwise; image v grows downwards
      ctx.strokeRect(-half, -half, 2 * half, 2 * half);
      ctx.restore();
      const label = `${det.color || "?"} ${det.size || ""}`.trim();
      ctx.fillStyle = "#000000";
      ctx.fillText(label, p.u + half + 3, p.v - half + 1);
      ctx.fillStyle = "#00e5ff";
      ctx.fillText(label, p.u + half + 2, p.v - half);
    });
    ctx.restore();
  }

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
    this.hoverPending = null;
    this.setHoverDetection(-1);
    this.hoverLabel.textContent = "x — y — z — mm";
  }

  setHoverDetection(index) {
    if (index === this.hoverDetection) return;
    this.hoverDetection = index;
    this.onHoverDetection(index);
  }

  onMove(event) {
    const px = this.pointerToPx(event);
    if (!px) {
      this.onLeave();
      return;
    }
    if (this.view() === "topdown") {
      const w = topdownPxToWorld(px.frame.u, px.frame.v, this.canvas.width, this.canvas.height, this.topdownBounds());
      if (!w) return;
      this.showWorld(w, "board");
      const world = this.detections.map((d) => ({ center_px: d.position_m ? [d.position_m[0], d.position_m[1]] : null }));
      this.setHoverDetection(nearestDetection(world, w[0], w[1], 0.03));
      return;
    }
    this.setHoverDetection(nearestDetection(this.detections, px.camera.u, px.camera.v, PICK_RADIUS_PX));
    this.hoverPending = px.camera;
    this.pumpHover();
  }

  /** At most one pixel-to-world request in flight (read-only, no token needed); the newest pointer wins. */
  pumpHover() {
    if (this.hoverBusy || this.hoverTimer || !this.hoverPending) return;
    const { u, v } = this.hoverPending;
    this.hoverPending = null;
    this.hoverBusy = true;
    this.api
      .pixelToWorld(u, v)
      .then((r) => this.showWorld(r.position_m, r.on))
      .catch((e) => {
        delete this.hoverLabel.dataset.positionM;
        this.hoverLabel.textContent = e.code === "not_calibrated" ? "calibrate to read world mm" : e.message;
      })
      .finally(() => {
        this.hoverBusy = false;
        this.hoverTimer = setTimeout(() => {
          this.hoverTimer = null;
          this.pumpHover();
        }, HOVER_INTERVAL_MS);
      });
  }

  showWorld(positionM, on) {
    if (!Array.isArray(positionM)) return;
    const [x, y, z] = positionM;
    this.hoverLabel.textContent = `x ${fmtMm(x)}  y ${fmtMm(y)}  z ${fmtMm(z)} mm${on ? ` (${on})` : ""}`;
    this.hoverLabel.dataset.positionM = JSON.stringify(positionM);
  }

  onClick(event) {
    if (this.mode !== "grab" && this.mode !== "drop") return;
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
