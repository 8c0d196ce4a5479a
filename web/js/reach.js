// The reach overlay: where this arm's gripper reaches on the board (GET /api/reach, computed once by the server from
// the arm model's IK over a board grid): green cells top-down, amber only tilted, nothing out of reach. Drawn on the
// camera views through the calibration (each cell's corners on the board plane) and on the top-down view; toggled by
// the Reach checkbox, fetched on first use.

import { worldToTopdownPx } from "./geometry.js";
import { worldToCameraPx } from "./projection.js";

const $ = (id) => document.getElementById(id);
const FILL = { T: "rgba(40, 200, 90, 0.28)", t: "rgba(240, 170, 30, 0.30)" };

export class ReachOverlay {
  constructor({ live, api, log }) {
    this.live = live;
    this.api = api;
    this.log = log;
    this.reach = null;
    this.on = false;
    this.loading = null;
    live.overlays.push(() => this.draw());
    $("layer-reach").addEventListener("change", () => this.toggle($("layer-reach").checked));
  }

  async toggle(on) {
    this.on = on;
    if (on && !this.reach) {
      this.live.canvas.dataset.reach = "loading";
      this.loading = this.loading || this.api.get("/api/reach").then((reach) => { this.reach = reach; })
        .catch((e) => { this.log.add("warn", `reach overlay: ${e.message}`); })
        .finally(() => { this.loading = null; });
      await this.loading;
    }
    this.live.canvas.dataset.reach = this.on && this.reach ? "shown" : "hidden";
    this.live.redraw();
  }

  toCanvas(x, y) {
    const live = this.live;
    if (live.view() === "topdown") return worldToTopdownPx(x, y, live.canvas.width, live.canvas.height, live.topdownBounds());
    const cam = worldToCameraPx([x, y, 0], live.cameraModel);
    return cam ? live.cameraToFramePx([cam.u, cam.v]) : null;
  }

  draw() {
    if (!this.on || !this.reach) return;
    const { ctx } = this.live;
    const { x0_m: x0, y0_m: y0, step_m: step, rows } = this.reach;
    const h = step / 2;
    let drawn = 0;
    ctx.save();
    rows.forEach((row, j) => {
      for (let i = 0; i < row.length; i += 1) {
        const fill = FILL[row[i]];
        if (!fill) continue;
        const x = x0 + i * step, y = y0 + j * step;
        const corners = [[x - h, y - h], [x + h, y - h], [x + h, y + h], [x - h, y + h]].map(([cx, cy]) => this.toCanvas(cx, cy));
        if (corners.some((c) => !c)) continue;
        ctx.fillStyle = fill;
        ctx.beginPath();
        corners.forEach((c, k) => (k ? ctx.lineTo(c.u, c.v) : ctx.moveTo(c.u, c.v)));
        ctx.closePath();
        ctx.fill();
        drawn += 1;
      }
    });
    ctx.restore();
    this.live.canvas.dataset.reachCells = String(drawn);
  }
}
