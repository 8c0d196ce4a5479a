// A taught program's path on the live view: the gripper point of each waypoint (the server's
// gripper_position_m, forward kinematics of its joints) projected through the calibration on the camera views, or placed by
// x, y on the top-down view; numbered dots joined in order, gripper steps marked.

import { worldToTopdownPx } from "./geometry.js";
import { worldToCameraPx } from "./projection.js";

const PATH_COLOR = "#ff4fd8";

export class ProgramPathOverlay {
  constructor(live) {
    this.live = live;
    this.path = null;
    live.overlays.push(() => this.draw());
  }

  /** Show `path` ({points_m, gripper}) or nothing (null). */
  set(path) {
    this.path = path && Array.isArray(path.points_m) && path.points_m.length ? path : null;
    this.live.canvas.dataset.pathPoints = String(this.path ? this.path.points_m.length : 0);
    this.live.redraw();
  }

  /** Canvas pixel of a world point on the shown view, or null (no calibration, behind the camera). */
  toCanvas(pointM) {
    const live = this.live;
    if (live.view() === "topdown") {
      return worldToTopdownPx(pointM[0], pointM[1], live.canvas.width, live.canvas.height, live.topdownBounds());
    }
    const cam = worldToCameraPx(pointM, live.cameraModel);
    return cam ? live.cameraToFramePx([cam.u, cam.v]) : null;
  }

  draw() {
    if (!this.path) return;
    const { ctx, canvas } = this.live;
    const points = this.path.points_m.map((p) => this.toCanvas(p));
    const r = Math.max(6, canvas.width / 160);
    ctx.save();
    ctx.strokeStyle = PATH_COLOR;
    ctx.fillStyle = PATH_COLOR;
    ctx.lineWidth = Math.max(2, canvas.width / 500);
    ctx.setLineDash([8, 5]);
    ctx.beginPath();
    let started = false;
    points.forEach((p) => {
      if (!p) return;
      if (started) ctx.lineTo(p.u, p.v);
      else ctx.moveTo(p.u, p.v);
      started = true;
    });
    ctx.stroke();
    ctx.setLineDash([]);
    ctx.font = `bold ${Math.round(r * 2)}px sans-serif`;
    points.forEach((p, i) => {
      if (!p) return;
      ctx.beginPath();
      ctx.arc(p.u, p.v, r, 0, 2 * Math.PI);
      if (this.path.gripper[i] === "grasp") ctx.fill();
      else ctx.stroke();
      ctx.fillText(String(i + 1), p.u + r + 2, p.v - r);
    });
    ctx.restore();
  }
}
