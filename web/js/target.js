// Type a target: the gripper's x, y, z (mm), pitch and yaw (degrees; empty = the station chooses), or every
// joint (degrees), and Go. Each Go is read strictly (text, NaN or an empty field is refused here, nothing sent),
// then checked by the station (POST /api/arm/pose/check or /api/arm/joints/check: the move's own IK and safety
// checks, nothing moves) and only then sent; a refusal is shown next to the form with its reason.

import { readMovingTimeS } from "./inputs.js";
import { PlanPreview } from "./plan_preview.js";

const $ = (id) => document.getElementById(id);
const NUMBER = /^[+-]?(\d+\.?\d*|\.\d+)$/;
const DEG = Math.PI / 180;

/** A typed number: {ok, value} (null when empty and optional) or {ok: false, message} naming the field. */
export function readNumber(text, label, { optional = false } = {}) {
  const typed = String(text ?? "").trim();
  if (typed === "") return optional ? { ok: true, value: null } : { ok: false, message: `${label}: type a number` };
  if (!NUMBER.test(typed)) return { ok: false, message: `${label}: '${typed.slice(0, 20)}' is not a number` };
  return { ok: true, value: Number(typed) };
}

/** The pose form's request body (SI units) or {message}. */
export function readPoseForm(values) {
  const body = { position_m: [] };
  for (const axis of ["x", "y", "z"]) {
    const read = readNumber(values[axis], `${axis} (mm)`);
    if (!read.ok) return { message: read.message };
    body.position_m.push(read.value / 1000);
  }
  for (const [key, field] of [["pitch", "pitch_rad"], ["yaw", "yaw_rad"]]) {
    const read = readNumber(values[key], `${key} (°)`, { optional: true });
    if (!read.ok) return { message: read.message };
    if (read.value !== null) body[field] = read.value * DEG;
  }
  return { body };
}

export class TargetPanel {
  /** api: Api; run(action, call): the page's REST runner (logs, toasts); status(): the last telemetry;
   * openView3d() / view3d(): the 3-D panel (opened / if loaded) where a plan is drawn (plan_preview.js); previewOn():
   * the "preview before moving" setting (Go then plans, as Plan does). */
  constructor({ api, run, status, openView3d = async () => null, view3d = () => null, previewOn = () => false }) {
    this.api = api;
    this.run = run;
    this.status = status;
    this.names = [];
    this.view3d = view3d;
    this.preview = new PlanPreview({ api, run, show: (state, text) => this.show(state, text), openView3d, view3d });
    $("btn-target-go").addEventListener("click", () => this.goPose(previewOn()));
    $("btn-joints-go").addEventListener("click", () => this.goJoints(previewOn()));
    $("btn-target-plan").addEventListener("click", () => this.goPose(true));
    $("btn-joints-plan").addEventListener("click", () => this.goJoints(true));
    $("btn-target-here").addEventListener("click", () => this.fillFromArm());
    $("target-form").addEventListener("submit", (e) => e.preventDefault());
  }

  /** One degree field per joint of the arm the server runs. */
  setJointNames(names) {
    this.names = names || [];
    const root = $("target-joints");
    root.replaceChildren();
    this.names.forEach((name, i) => {
      const label = document.createElement("label");
      label.textContent = `${name} `;
      const input = document.createElement("input");
      Object.assign(input, { type: "text", className: "num", inputMode: "decimal", id: `target-joint-${i}` });
      input.setAttribute("aria-label", `${name} (degrees)`);
      label.append(input, "°");
      root.append(label);
    });
  }

  /** The fields from where the arm is now (pose and joints), to edit from. */
  fillFromArm() {
    const s = this.status();
    if (!s) return;
    const pose = s.gripper_pose;
    if (pose) {
      ["x", "y", "z"].forEach((axis, i) => { $(`target-${axis}`).value = (pose.position_m[i] * 1000).toFixed(1); });
      $("target-pitch").value = (pose.pitch_rad / DEG).toFixed(1);
      $("target-yaw").value = (pose.yaw_rad / DEG).toFixed(1);
    }
    (s.joints_rad || []).forEach((q, i) => {
      const input = $(`target-joint-${i}`);
      if (input) input.value = (q / DEG).toFixed(1);
    });
  }

  show(state, text) {
    const out = $("target-result");
    out.dataset.state = state;
    out.textContent = text;
    out.hidden = false;
  }

  movingTime() {
    const time = readMovingTimeS($("jog-time"));
    if (!time.ok) this.show("refused", time.message);
    return time;
  }

  /** The pose form as typed: readPoseForm's {body} or {message}. */
  typedPose() {
    return readPoseForm({
      x: $("target-x").value, y: $("target-y").value, z: $("target-z").value,
      pitch: $("target-pitch").value, yaw: $("target-yaw").value,
    });
  }

  /** The 3-D view's goal marker was dragged to positionM: its x, y, z into the fields (pitch and yaw as typed, or
   * after a turn of its rings angles' {pitchRad, yawRad}), then the station's check of that pose (nothing moves); the
   * solution drawn as the marker's goal arm, or the reason. */
  async goalMoved(positionM, angles = null) {
    positionM.forEach((v, i) => { $(`target-${"xyz"[i]}`).value = (v * 1000).toFixed(1); });
    if (angles) {
      $("target-pitch").value = (angles.pitchRad / DEG).toFixed(1);
      $("target-yaw").value = (angles.yawRad / DEG).toFixed(1);
    }
    const read = this.typedPose();
    const goal = this.view3d()?.goal;
    if (read.message) {
      goal?.showSolution(null);
      return this.show("refused", `goal marker: ${read.message}`);
    }
    const where = read.body.position_m.map((v) => (v * 1000).toFixed(0)).join(", ");
    try {
      const checked = await this.api.checkPose(read.body);
      goal?.showSolution(checked.q_rad);
      return this.show("checked", `goal ${where} mm: reachable (${checked.duration_s.toFixed(1)} s from here); Plan or Go moves there`);
    } catch (e) {
      goal?.showSolution(null);
      return this.show("refused", `goal ${where} mm: no way there: ${e.message}`);
    }
  }

  /** Go (or, with planOnly, plan without moving: plan_preview.js) to the typed pose. */
  goPose(planOnly = false) {
    const read = this.typedPose();
    if (read.message) return Promise.resolve(this.show("refused", `not sent: ${read.message}`));
    const time = this.movingTime();
    if (!time.ok) return Promise.resolve();
    const body = { ...read.body };
    if (time.valueS !== undefined) body.moving_time_s = time.valueS;
    const where = read.body.position_m.map((v) => (v * 1000).toFixed(0)).join(", ");
    if (planOnly) return this.preview.make(`plan ${where} mm`, "/api/arm/pose", body);
    return this.checkedGo(`go to ${where} mm`, () => this.api.checkPose(body), () => this.api.post("/api/arm/pose", body));
  }

  goJoints(planOnly = false) {
    const q = [];
    for (let i = 0; i < this.names.length; i += 1) {
      const read = readNumber($(`target-joint-${i}`).value, `${this.names[i]} (°)`);
      if (!read.ok) return Promise.resolve(this.show("refused", `not sent: ${read.message}`));
      q.push(read.value * DEG);
    }
    const time = this.movingTime();
    if (!time.ok) return Promise.resolve();
    const body = { q_rad: q };
    if (time.valueS !== undefined) body.moving_time_s = time.valueS;
    if (planOnly) return this.preview.make("plan joints", "/api/arm/joints", body);
    return this.checkedGo("go to joints", () => this.api.checkJoints(body), () => this.api.post("/api/arm/joints", body));
  }

  /** Check, then send; the outcome (or the reason of a refusal) shown in place. */
  async checkedGo(action, check, send) {
    if (this.busy) return;
    this.busy = true;
    try {
      this.show("checking", `${action}: checking…`);
      let checked;
      try {
        checked = await check();
      } catch (e) {
        this.show("refused", `${action}: refused: ${e.message}`);
        return;
      }
      let failure = null;
      const result = await this.run(action, () => send().catch((e) => { failure = e; throw e; }));
      if (result) this.show("sent", `${action}: moving (${checked.duration_s.toFixed(1)} s)`);
      else this.show("refused", `${action}: refused: ${failure ? failure.message : "no answer"}`);
    } finally {
      this.busy = false;
    }
  }
}
