// Rendering of the side panels from server data: status line, joint and gripper readouts, joint
// sliders, detections table, calibration result, programs list, and command-button enabling.

import { labToCss } from "./colors.js";
import { fmtDeg, fmtMm } from "./geometry.js";

const $ = (id) => document.getElementById(id);

const SWATCH = {
  red: "#e5484d", orange: "#f08c2e", yellow: "#f2d13c", green: "#2fbf71", blue: "#3d8bfd", violet: "#9b6bff",
  purple: "#9b6bff",
};

/** Enable exactly the [data-command] buttons whose command the station allows now (and that we may send),
 * except those the page blocks itself (data-blocked: why, e.g. too few click-calibration points). */
export function applyAllowed(root, allowed, canControl) {
  const set = new Set(allowed || []);
  root.querySelectorAll("[data-command]").forEach((el) => {
    const name = el.dataset.command;
    el.disabled = !canControl || !set.has(name) || Boolean(el.dataset.blocked);
  });
}

export function renderStatus(s) {
  const badge = $("state-badge");
  badge.textContent = s.state || "—";
  badge.dataset.state = s.state || "unknown";
  let detail = s.detail || (s.state === "idle" ? "ready" : "");
  if (s.moving) detail += detail ? " · moving" : "moving";
  if (s.controller) detail += ` · by ${s.controller}`;
  $("status-detail").textContent = detail;
  const job = s.job;
  const line = $("job-line");
  if (job && job.state === "running") {
    line.hidden = false;
    $("job-name").textContent = `${job.name}${job.message ? ": " + job.message : ""}`;
    $("job-progress").value = Number.isFinite(job.progress) ? job.progress : 0;
  } else {
    line.hidden = true;
  }
  const halted = s.state === "estop" || s.state === "fault";
  $("halt-banner").hidden = !halted;
  if (halted) {
    $("halt-title").textContent = s.state === "estop" ? "E-STOP LATCHED" : "FAULT";
    $("halt-text").textContent = haltText(s.detail);
  }
  const warning = $("camera-warning");
  warning.hidden = !s.camera_warning;
  warning.textContent = s.camera_warning ? `⚠ ${s.camera_warning[0].toUpperCase()}${s.camera_warning.slice(1)}` : "";
  $("backend").textContent = s.backend ? `backend: ${s.backend}` : "—";
  $("backend").title = s.controller ? `last commanded by: ${s.controller}` : "Device backend";
}

/** The banner's sentence: the station's reason, capitalised and ended, then what to do (once). */
export function haltText(detail) {
  const reason = String(detail || "").trim().replace(/[.:;,\s]+$/, "");
  const said = reason ? `${reason[0].toUpperCase()}${reason.slice(1)}.` : "Motion halted.";
  return /reset/i.test(reason) ? said : `${said} Press Reset when it is safe.`;
}

/** Joint table (deg) and the gripper pose/width readout. */
export function renderReadouts(s) {
  const names = s.joint_names || [];
  const table = $("joint-readout");
  if (table.rows.length !== names.length) {
    table.replaceChildren();
    names.forEach((n) => {
      const tr = table.insertRow();
      tr.insertCell().textContent = n;
      tr.insertCell().textContent = "—";
    });
  }
  (s.joints_rad || []).forEach((q, i) => {
    if (table.rows[i]) table.rows[i].cells[1].textContent = `${fmtDeg(q)}°`;
  });
  const gp = s.gripper_pose;
  const g = s.gripper || {};
  const parts = [];
  if (gp && Array.isArray(gp.position_m)) {
    parts.push(`xyz ${gp.position_m.map(fmtMm).join(" ")} mm`);
    parts.push(`pitch ${fmtDeg(gp.pitch_rad, 0)}° yaw ${fmtDeg(gp.yaw_rad, 0)}°`);
  }
  if (document.body.dataset.gripperType === "suction") {  // a cup has no width: its vacuum instead
    if (g.command) parts.push(g.command === "grasp" ? "vacuum on" : "vacuum off");
  } else if (Number.isFinite(g.width_m)) {
    parts.push(`width ${(g.width_m * 1000).toFixed(1)} mm`);
  }
  if (g.holding !== undefined) parts.push(g.holding ? "holding" : "empty");
  $("pose-readout").textContent = parts.length ? parts.join(" · ") : "gripper —";
  $("pose-readout").dataset.holding = String(Boolean(g.holding));
}

/** Joint sliders; they follow the arm unless the operator touched one in the last 3 s. */
export class JointSliders {
  constructor(container, onRelease) {
    this.container = container;
    this.onRelease = onRelease;
    this.inputs = [];
    this.touchedMs = 0;
    this.names = [];
  }

  /** One slider per joint the server named (hello arm / status joint_names), over its limits (rad). */
  build(names, limitsRad) {
    this.names = names;
    this.container.replaceChildren();
    this.inputs = names.map((name, i) => {
      const lim = limitsRad[i].map((r) => (r * 180) / Math.PI);
      const label = document.createElement("label");
      label.textContent = name;
      const input = document.createElement("input");
      Object.assign(input, { type: "range", min: lim[0], max: lim[1], step: 0.5, value: 0 });
      input.id = `slider-${name}`;
      label.htmlFor = input.id;
      const out = document.createElement("output");
      out.textContent = "0.0°";
      input.addEventListener("input", () => {
        this.touchedMs = performance.now();
        out.textContent = `${Number(input.value).toFixed(1)}°`;
      });
      input.addEventListener("change", () => {
        this.touchedMs = performance.now();
        this.onRelease(this.valuesRad());
      });
      this.container.append(label, input, out);
      return { input, out };
    });
  }

  follow(jointsRad, force = false) {
    if (!Array.isArray(jointsRad)) return;
    if (!force && performance.now() - this.touchedMs < 3000) return;
    this.inputs.forEach(({ input, out }, i) => {
      if (!Number.isFinite(jointsRad[i]) || (!force && document.activeElement === input)) return;
      const deg = (jointsRad[i] * 180) / Math.PI;
      input.value = deg;
      out.textContent = `${deg.toFixed(1)}°`;
    });
  }

  valuesRad() {
    return this.inputs.map(({ input }) => (Number(input.value) * Math.PI) / 180);
  }

  setDisabled(disabled) {
    this.inputs.forEach(({ input }) => { input.disabled = disabled; });
  }
}

/** The arm and gripper the server runs (hello arm): gripper button labels follow the gripper type. */
export function renderArm(arm) {
  const suction = arm.gripper_type === "suction";
  document.body.dataset.gripperType = arm.gripper_type;
  $("btn-open").textContent = suction ? "Vacuum off" : "Open";
  $("btn-close").textContent = suction ? "Vacuum on" : "Close";
  $("arm-name").textContent = arm.has_arm === false ? "none" : `${arm.name} · ${arm.joint_names.length} joints · ${suction ? "suction cup" : "fingers"}`;
}

/** Detections table; rows carry data-index so hovering on the canvas can highlight one. */
export function renderDetections(detections, hoverIndex, onRowClick, why = "", untrusted = false) {
  const body = $("det-body");
  const list = Array.isArray(detections) ? detections : [];
  $("det-count").textContent = untrusted && list.length ? `${list.length} · not trusted` : String(list.length);
  $("det-count").title = untrusted ? "seen through a camera the calibration no longer fits: positions may be wrong" : "";
  if (!list.length) {
    const tr = document.createElement("tr");
    tr.className = "det-empty";
    const td = tr.insertCell();
    td.colSpan = 7;
    td.textContent = why || "no blocks in view";
    body.replaceChildren(tr);
    return;
  }
  const rows = list.map((d, i) => {
    const tr = document.createElement("tr");
    tr.dataset.index = String(i);
    tr.className = [i === hoverIndex ? "hover" : "", untrusted ? "untrusted" : ""].join(" ").trim();
    const p = d.position_m || [];
    const sw = `<span class="swatch" style="background:${SWATCH[d.color] || labToCss(d.color_lab) || "#888"}"></span>`; // unknown: as measured
    const size = d.size || (d.is_cube === false ? "other" : "");
    const level = d.stack_level > 1 ? ` L${d.stack_level}` : "";
    const cells = [String(d.id ?? i), `${sw}${escapeHtml(d.color || "?")}`, escapeHtml(size + level),
      fmtMm(p[0]), fmtMm(p[1]), fmtMm(p[2]), fmtDeg(d.yaw_rad, 0)];
    tr.innerHTML = cells.map((c) => `<td>${c}</td>`).join("");
    tr.addEventListener("click", () => onRowClick(d, i));
    return tr;
  });
  body.replaceChildren(...rows);
}

export function highlightDetectionRow(index) {
  document.querySelectorAll("#det-body tr").forEach((tr) => {
    tr.classList.toggle("hover", Number(tr.dataset.index) === index);
  });
}

/** The key figures of the latest calibration. */
export function renderCalibration(c) {
  const ok = Boolean(c && c.calibrated); // the badge says the status's state (calstate.js), with the trust
  const dl = $("calib-result");
  dl.replaceChildren();
  if (!ok) return;
  const rows = [];
  if (Number.isFinite(c.reprojection_error_px)) rows.push(["reprojection", `${c.reprojection_error_px.toFixed(2)} px`]);
  if (Array.isArray(c.camera_position_m)) rows.push(["camera at", `${c.camera_position_m.map(fmtMm).join(" ")} mm`]);
  if (Number.isFinite(c.depth_check_error_m)) rows.push(["depth check", `${(c.depth_check_error_m * 1000).toFixed(1)} mm`]);
  if (Array.isArray(c.tags)) rows.push(["tags", String(c.tags.length)]);
  if (Array.isArray(c.grid_points_px)) rows.push(["grid points", String(c.grid_points_px.length)]);
  if (c.time) rows.push(["at", typeof c.time === "number" ? new Date(c.time * 1000).toTimeString().slice(0, 8) : String(c.time)]);
  appendRows(dl, rows);
}

/** Append a <dt>key</dt><dd data-key="key">value</dd> pair to the <dl> for each [key, value] row. */
export function appendRows(dl, rows) {
  for (const [k, v] of rows) {
    const dt = document.createElement("dt");
    dt.textContent = k;
    const dd = document.createElement("dd");
    dd.textContent = v;
    dd.dataset.key = k;
    dl.append(dt, dd);
  }
}

function escapeHtml(s) {
  return String(s).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
}
