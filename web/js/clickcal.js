// Calibration by clicking known points (no tags needed): the operator picks a world point (a board grid
// corner offered from the workcell grid the server sent in its hello, or x, y typed in mm), clicks where it
// is on the video, repeats (>= 4, spread out), and fits: the station solves the homography and the camera
// pose (POST /api/calibrate/points) and answers with the reprojection error and each point's residual,
// shown here with the points. A refused fit (too few, collinear, off the board, inconsistent) is shown
// with the station's reason; the station keeps its old calibration. Also: the self-recalibration toggle
// (PUT /api/calibration/settings) and the calibration's trust state from the status.

import { fmtMm } from "./geometry.js";
import { appendRows } from "./panels.js";

export const MIN_POINTS = 4;
const MAX_POINTS = 200;

/** The board grid's x and y values (metres) from the hello's workcell, or null when it has none. */
export function gridAxes(workcell) {
  const grid = workcell && workcell.board && workcell.board.grid;
  if (!grid || !(grid.step_m > 0) || !Array.isArray(grid.x_m) || !Array.isArray(grid.y_m)) return null;
  const axis = ([a, b]) => {
    const values = [];
    for (let i = 0; a + i * grid.step_m <= b + 1e-9; i += 1) values.push(Number((a + i * grid.step_m).toFixed(6)));
    return values;
  };
  return { xs: axis(grid.x_m), ys: axis(grid.y_m) };
}

/** "x, y" or "x, y, z" in millimetres → {worldM} in metres, or {error}. */
export function parseTypedMm(text) {
  const parts = String(text || "").split(/[\s,;]+/).filter((p) => p.length);
  if (parts.length < 2 || parts.length > 3) return { error: `type x, y (or x, y, z) in mm, got "${text}"` };
  const mm = parts.map(Number);
  if (!mm.every(Number.isFinite)) return { error: `"${text}" is not two or three numbers (mm)` };
  return { worldM: mm.map((v) => v / 1000) };
}

/** '' when world point xy lies on the hello's board, else why not. */
export function offBoardReason(workcell, worldM) {
  const board = workcell && workcell.board;
  if (!board) return "";
  const [x0, x1] = board.x_range_m;
  const [y0, y1] = board.y_range_m;
  const [x, y] = worldM;
  const tol = 1e-3;
  if (x >= x0 - tol && x <= x1 + tol && y >= y0 - tol && y <= y1 + tol) return "";
  return `(${fmtMm(x)}, ${fmtMm(y)}) mm is off the board (x ${fmtMm(x0)} to ${fmtMm(x1)}, y ${fmtMm(y0)} to ${fmtMm(y1)} mm)`;
}

const $ = (id) => document.getElementById(id);

export class ClickCalibration {
  /** api: Api; live: LiveView (its canvas is clicked, its overlays draw the points); log: EventLog;
   * afterChange(): re-applies the allowed commands (Fit is disabled below MIN_POINTS points). */
  constructor({ api, live, log, afterChange = () => {} }) {
    this.afterChange = afterChange; // called when Fit may be enabled again (enough points)
    this.api = api;
    this.live = live;
    this.log = log;
    this.workcell = null;
    this.points = []; // {pixel: [u, v] camera px, worldM: [x, y] or [x, y, z], residualPx}
    this.active = false;
    this.busy = false;
    live.canvas.addEventListener("click", (e) => this.onCanvasClick(e));
    live.overlays.push((view) => this.draw(view));
    $("btn-clickcal-undo").addEventListener("click", () => this.undo());
    $("btn-clickcal-clear").addEventListener("click", () => this.clear());
    $("btn-clickcal-fit").addEventListener("click", () => this.fit());
    $("self-recal").addEventListener("change", (e) => this.setSelfRecalibrate(e.target.checked));
    this.render();
  }

  /** The hello's workcell: offers its grid corners as world points. */
  setWorkcell(workcell) {
    this.workcell = workcell || null;
    const axes = gridAxes(this.workcell);
    for (const [id, values] of [["clickcal-x", axes ? axes.xs : []], ["clickcal-y", axes ? axes.ys : []]]) {
      const select = $(id);
      const kept = select.value;
      select.replaceChildren(...values.map((v) => new Option(fmtMm(v), String(v))));
      if (values.map(String).includes(kept)) select.value = kept;
    }
  }

  /** Click mode "points" on or off (the click-mode buttons). */
  setActive(active) {
    this.active = active;
    if (active) $("clickcal").open = true;
    this.render();
  }

  /** Status: the self-recalibration setting and the calibration's trust state. */
  onStatus(s) {
    const box = $("self-recal");
    if (!this.settingSelfRecal) box.checked = Boolean(s.self_recalibrate); // another client may change it
    const state = $("calib-state");
    const text = {
      checking: "restored, checking against the board tags…",
      rejected: "restored calibration not trusted (camera moved): recalibrate",
      trusted: "trusted",
      untrusted: "not trusted (the board tags do not confirm it): grabs and jobs refused; recalibrate",
    }[s.calibration_state] || "";
    state.textContent = text;
    state.dataset.state = s.calibration_state || "none";
    state.hidden = !text;
    const arm = s.arm_calibration;
    const armBadge = $("arm-calib");
    armBadge.hidden = !arm;
    armBadge.dataset.ok = String(Boolean(arm && arm.calibrated));
    armBadge.textContent = arm && arm.calibrated ? `arm calibrated, residual ${Number(arm.residual_mm).toFixed(1)} mm` : "arm not calibrated";
  }

  async setSelfRecalibrate(enabled) {
    this.settingSelfRecal = true;
    try {
      await this.api.request("PUT", "/api/calibration/settings", { self_recalibrate: enabled });
      this.log.add("info", `self-recalibration when idle: ${enabled ? "on" : "off"}`);
    } catch (e) {
      $("self-recal").checked = !enabled;
      this.log.error("self-recalibration setting", e);
    } finally {
      this.settingSelfRecal = false;
    }
  }

  /** The world point the next click stands for: typed (mm) if given, else the chosen grid corner. */
  nextWorld() {
    const typed = $("clickcal-typed").value.trim();
    if (typed) return parseTypedMm(typed);
    const x = Number($("clickcal-x").value);
    const y = Number($("clickcal-y").value);
    if (!Number.isFinite(x) || !Number.isFinite(y)) return { error: "no grid corner to offer yet (waiting for the station's workcell)" };
    return { worldM: [x, y] };
  }

  onCanvasClick(event) {
    if (!this.active || this.busy) return;
    const px = this.live.pointerToPx(event);
    if (!px) return;
    if (this.live.view() !== "color") {
      this.showError("click the points on the Video view (the depth and top-down views are not the camera image)");
      return;
    }
    if (this.points.length >= MAX_POINTS) {
      this.showError(`at most ${MAX_POINTS} points`);
      return;
    }
    const world = this.nextWorld();
    const why = world.error || offBoardReason(this.workcell, world.worldM);
    if (why) {
      this.showError(why);
      return;
    }
    this.points.forEach((p) => delete p.residualPx);
    this.points.push({ pixel: [px.camera.u, px.camera.v], worldM: world.worldM });
    this.showError("");
    $("clickcal-typed").value = "";
    this.render();
    this.live.redraw();
  }

  undo() {
    this.points.pop();
    this.showError("");
    this.render();
    this.live.redraw();
  }

  clear() {
    this.points = [];
    this.showError("");
    $("clickcal-result").replaceChildren();
    this.render();
    this.live.redraw();
  }

  /** Ask the station to fit; show the result and residuals, or its reason for refusing. */
  async fit() {
    if (this.busy) return;
    this.busy = true;
    $("btn-clickcal-fit").dataset.busy = "true";
    const body = { points: this.points.map((p) => ({ pixel: p.pixel, world_m: p.worldM })) };
    try {
      const answer = await this.api.post("/api/calibrate/points?wait=true", body);
      const job = answer.job || {};
      if (job.state === "succeeded" && job.result) {
        const errors = job.result.point_errors_px || [];
        this.points.forEach((p, i) => { p.residualPx = errors[i]; });
        this.showError("");
        this.showResult(job.result);
        this.log.add("info", `click calibration: ${job.message}`);
      } else {
        this.showError(`${job.message || job.state || "the fit failed"}; the old calibration is kept`);
      }
    } catch (e) {
      this.showError(`${e.message || e}; the old calibration is kept`);
    } finally {
      this.busy = false;
      delete $("btn-clickcal-fit").dataset.busy;
      this.render();
      this.live.redraw();
    }
  }

  showResult(result) {
    const rows = [
      ["reprojection", `${Number(result.reprojection_error_px).toFixed(2)} px`],
      ["homography", Number.isFinite(result.homography_error_px) ? `${result.homography_error_px.toFixed(2)} px` : "—"],
      ["camera at", Array.isArray(result.camera_position_m) ? `${result.camera_position_m.map(fmtMm).join(" ")} mm` : "—"],
      ["depth check", Number.isFinite(result.depth_check_error_m) ? `${(result.depth_check_error_m * 1000).toFixed(1)} mm` : "—"],
    ];
    const dl = $("clickcal-result");
    dl.replaceChildren();
    appendRows(dl, rows);
    dl.dataset.result = JSON.stringify(result);
  }

  showError(message) {
    const el = $("clickcal-error");
    el.textContent = message;
    el.hidden = !message;
    if (message) $("clickcal-result").replaceChildren();
  }

  render() {
    const body = $("clickcal-points");
    body.replaceChildren(
      ...this.points.map((p, i) => {
        const tr = document.createElement("tr");
        const residual = Number.isFinite(p.residualPx) ? p.residualPx.toFixed(2) : "—";
        const cells = [String(i + 1), p.pixel[0].toFixed(1), p.pixel[1].toFixed(1), ...p.worldM.slice(0, 2).map(fmtMm), residual];
        cells.forEach((text) => {
          const td = document.createElement("td");
          td.textContent = text;
          tr.append(td);
        });
        return tr;
      }),
    );
    const fit = $("btn-clickcal-fit");
    const tooFew = this.points.length < MIN_POINTS;
    const wasBlocked = Boolean(fit.dataset.blocked);
    fit.textContent = tooFew ? `Fit: click at least ${MIN_POINTS} points` : `Fit ${this.points.length} points`;
    if (tooFew) {
      fit.dataset.blocked = `click at least ${MIN_POINTS} points`; // applyAllowed keeps it disabled
      fit.title = fit.dataset.blocked;
      fit.disabled = true;
    } else {
      delete fit.dataset.blocked;
      fit.title = "";
      if (wasBlocked) this.afterChange(); // the station's allowed commands decide again
    }
    $("clickcal-hint").textContent = this.active
      ? `click the chosen point on the video (${this.points.length} so far, at least ${MIN_POINTS}, spread out)`
      : "choose Click-calibrate above the video to click points";
  }

  /** The clicked points (numbered) and, after a fit, their residuals, on the camera views. */
  draw(view) {
    if (!this.points.length || view.view() === "topdown") return;
    const { ctx, canvas } = view;
    const s = Math.max(canvas.width / 1280, 0.5);
    ctx.save();
    ctx.lineWidth = 2 * s;
    ctx.font = `${Math.round(15 * s)}px sans-serif`;
    this.points.forEach((p, i) => {
      const c = view.cameraToFramePx(p.pixel);
      if (!c) return;
      ctx.strokeStyle = "#ff4fd8";
      ctx.beginPath();
      ctx.arc(c.u, c.v, 7 * s, 0, 2 * Math.PI);
      ctx.moveTo(c.u - 11 * s, c.v);
      ctx.lineTo(c.u + 11 * s, c.v);
      ctx.moveTo(c.u, c.v - 11 * s);
      ctx.lineTo(c.u, c.v + 11 * s);
      ctx.stroke();
      ctx.fillStyle = "#ff4fd8";
      const residual = Number.isFinite(p.residualPx) ? ` (${p.residualPx.toFixed(1)} px)` : "";
      ctx.fillText(`${i + 1}${residual}`, c.u + 10 * s, c.v - 10 * s);
    });
    ctx.restore();
  }
}
