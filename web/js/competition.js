// The competition panel: choose an autonomous job and level (the list comes from GET /api/auto/jobs),
// load its scene from a seed (simulation), start, cancel, a running timer, progress, the plan drawn on
// the live view (next block → its destination) and, at the end, the judge's score with its breakdown.

import { worldToTopdownPx } from "./geometry.js";
import { cameraModel, worldToCameraPx } from "./projection.js";

const $ = (id) => document.getElementById(id);
const TIMER_INTERVAL_MS = 100;
const PLAN_COLOR = "#ffd166";
const SCORE_ATTEMPTS = 5; // the server scores a run the moment it ends; retries cover a slow answer
const SCORE_RETRY_MS = 1000;

/** Seconds → "m:ss.s". */
export function fmtClock(seconds) {
  if (!Number.isFinite(seconds) || seconds < 0) return "0:00.0";
  const minutes = Math.floor(seconds / 60);
  const rest = seconds - minutes * 60;
  return `${minutes}:${rest.toFixed(1).padStart(4, "0")}`;
}

/** A parameter input's value as the JSON type the job declares; undefined when left empty. */
export function paramValue(type, input) {
  if (type === "bool") return input.checked;
  const text = input.value.trim();
  if (text === "") return undefined;
  if (type === "int" || type === "float") {
    const value = Number(text);
    if (!Number.isFinite(value) || (type === "int" && !Number.isInteger(value))) throw new Error(`${input.dataset.param} must be ${type}`);
    return value;
  }
  if (type === "str") return text;
  try {
    return JSON.parse(text);
  } catch {
    throw new Error(`${input.dataset.param} must be JSON (${type})`);
  }
}

/** A job's <option>: one the station's workcell cannot run is disabled, its reason shown beside it. */
export function jobOption(job) {
  if (job.available !== false) return new Option(job.name, job.name);
  const option = new Option(`${job.name} (not on this workcell)`, job.name);
  option.disabled = true;
  option.title = job.unavailable_reason || "not available on this workcell";
  return option;
}

export class CompetitionPanel {
  /** api: Api; live: LiveView (the plan is drawn as one of its overlays); log: EventLog; serverNowS(): server clock. */
  constructor({ api, live, log, serverNowS }) {
    this.api = api;
    this.live = live;
    this.log = log;
    this.serverNowS = serverNowS;
    this.jobs = [];
    this.backend = null;
    this.camera = null; // cameraModel() of the calibration
    this.job = null; // the autonomous job shown (running or last ended)
    this.scoredJobId = null;
    this.score = null;
    this.plan = null; // {blockPx, targetPx} in camera pixels (targetPx null when not projectable)
    this.timer = null;
    live.overlays.push((view) => this.drawPlan(view));
  }

  start() {
    $("comp-job").addEventListener("change", () => this.showJob());
    $("btn-comp-start").addEventListener("click", () => this.startJob());
    $("btn-comp-cancel").addEventListener("click", () => this.cancelJob());
    $("btn-comp-scene").addEventListener("click", () => this.loadScene());
    this.loadJobs();
  }

  async loadJobs() {
    try {
      this.jobs = (await this.api.get("/api/auto/jobs")).data || [];
    } catch (e) {
      this.log.error("autonomous jobs", e);
      return;
    }
    const select = $("comp-job");
    const previous = select.value;
    select.replaceChildren(...this.jobs.map((job) => jobOption(job)));
    const available = this.jobs.filter((job) => job.available !== false);
    select.value = (available.find((job) => job.name === previous) || available[0] || { name: "" }).name;
    this.showUnavailable();
    this.showJob();
  }

  /** Under the summary: the jobs this station's workcell cannot run, each with what it lacks. */
  showUnavailable() {
    let list = $("comp-unavailable");
    if (!list) {
      list = document.createElement("ul");
      list.id = "comp-unavailable";
      list.className = "comp-unavailable";
      $("comp-summary").after(list);
    }
    const missing = this.jobs.filter((job) => job.available === false);
    list.replaceChildren(...missing.map((job) => {
      const item = document.createElement("li");
      item.dataset.job = job.name;
      item.textContent = `${job.name}: not on this workcell, ${job.unavailable_reason || "not available"}`;
      return item;
    }));
    list.hidden = missing.length === 0;
  }

  /** The chosen job, when the station's workcell can run it (the others are listed disabled). */
  selected() {
    return this.jobs.find((job) => job.name === $("comp-job").value && job.available !== false) || null;
  }

  /** Levels, summary, parameter inputs and scene row of the chosen job. */
  showJob() {
    const job = this.selected();
    const level = $("comp-level");
    const previous = level.value;
    level.replaceChildren(...(job ? job.levels : []).map((n) => new Option(`L${n}`, String(n))));
    if ([...level.options].some((o) => o.value === previous)) level.value = previous;
    level.disabled = !job || job.levels.length === 0;
    $("comp-summary").textContent = job ? job.summary + (job.time_limit_s ? ` · limit ${job.time_limit_s} s` : "") : "";
    const params = $("comp-params");
    params.replaceChildren(...(job ? job.params : []).map((p) => this.paramField(p)));
    params.hidden = !job || job.params.length === 0;
    this.showSceneRow();
  }

  paramField(param) {
    const label = document.createElement("label");
    const input = document.createElement("input");
    input.dataset.param = param.name;
    input.dataset.type = param.type;
    if (param.type === "bool") input.type = "checkbox";
    else if (param.type === "int" || param.type === "float") {
      input.type = "number";
      input.step = param.type === "int" ? "1" : "any";
    } else {
      input.type = "text";
      input.placeholder = param.type === "str" ? "" : `JSON ${param.type}`;
    }
    label.append(`${param.name} `, input);
    return label;
  }

  showSceneRow() {
    const job = this.selected();
    $("comp-scene-row").hidden = this.backend !== "sim" || !job || !job.scene;
  }

  setBackend(backend) {
    this.backend = backend;
    this.showSceneRow();
  }

  setCalibration(calibration) {
    this.camera = cameraModel(calibration);
  }

  /** Telemetry: follow the running autonomous job (whoever started it), score it when it ends. */
  onStatus(status) {
    const job = status.job;
    const known = job && this.jobs.some((j) => j.name === job.name);
    $("comp-hint").textContent = status.calibrated ? "" : "calibrate the camera first";
    if (!known) return;
    if (!this.job || this.job.id !== job.id) {
      this.score = null;
      this.scoredJobId = null;
      this.renderScore();
    }
    this.job = job;
    this.renderProgress();
    this.updatePlan();
    if (job.state === "running") this.runTimer();
    else {
      this.stopTimer();
      if (this.scoredJobId !== job.id) this.fetchScore(job);
    }
  }

  // ---- commands -----------------------------------------------------------------------------
  async startJob() {
    const job = this.selected();
    if (!job) return;
    const body = { job: job.name };
    if (job.levels.length) body.level = Number($("comp-level").value);
    try {
      const params = {};
      $("comp-params").querySelectorAll("input[data-param]").forEach((input) => {
        const value = paramValue(input.dataset.type, input);
        if (value !== undefined) params[input.dataset.param] = value;
      });
      if (Object.keys(params).length) body.params = params;
      const result = await this.api.post("/api/auto", body);
      this.job = result.job;
      this.score = null;
      this.scoredJobId = null;
      this.renderScore();
      this.renderProgress();
      this.runTimer();
    } catch (e) {
      this.log.error(`start ${job.name}`, e);
    }
  }

  async cancelJob() {
    try {
      await this.api.cancelJob();
    } catch (e) {
      this.log.error("cancel", e);
    }
  }

  async loadScene() {
    const job = this.selected();
    if (!job) return;
    const level = job.levels.length ? Number($("comp-level").value) : 1;
    const seed = Math.max(0, Math.round(Number($("comp-seed").value) || 0));
    try {
      const result = await this.api.simScene(job.name, level, seed);
      this.log.add("info", `scene ${job.name} L${level} seed ${seed}: ${result.objects} objects`);
    } catch (e) {
      this.log.error("load scene", e);
    }
  }

  async fetchScore(job) {
    this.scoredJobId = job.id;
    const spec = this.jobs.find((j) => j.name === job.name);
    if (this.backend !== "sim" || !spec || !spec.scored) {
      $("comp-score").dataset.state = "none";
      $("comp-score-points").textContent = spec && !spec.scored ? "no score for this job" : "scored in the simulation only";
      return;
    }
    for (let attempt = 1; ; attempt += 1) {
      try {
        const result = await this.api.get("/api/auto/score");
        if (result.job_id !== job.id) return; // a job started elsewhere, not over this server's API
        if (result.final || attempt >= SCORE_ATTEMPTS) {
          this.score = result;
          this.renderScore();
          return;
        }
      } catch (e) {
        if (attempt >= SCORE_ATTEMPTS) {
          this.log.error("score", e);
          this.score = { score: null, note: `no score: ${e.message}` };
          this.renderScore();
          return;
        }
      }
      await new Promise((resolve) => setTimeout(resolve, SCORE_RETRY_MS));
      if (this.scoredJobId !== job.id) return; // another job took over meanwhile
    }
  }

  // ---- rendering ----------------------------------------------------------------------------
  runTimer() {
    if (this.timer) return;
    this.timer = setInterval(() => this.renderTimer(), TIMER_INTERVAL_MS);
    this.renderTimer();
  }

  stopTimer() {
    clearInterval(this.timer);
    this.timer = null;
    this.renderTimer();
  }

  renderTimer() {
    const job = this.job;
    if (!job) return;
    const end = job.state === "running" || !Number.isFinite(job.finished_s) ? this.serverNowS() : job.finished_s;
    const elapsed = Math.max(0, end - job.started_s);
    const el = $("comp-timer");
    el.textContent = fmtClock(elapsed);
    el.dataset.seconds = elapsed.toFixed(1);
    el.dataset.running = String(job.state === "running");
  }

  renderProgress() {
    const job = this.job;
    const task = (job && job.extra && job.extra.task) || null;
    $("comp-state").textContent = job ? `${job.detail || job.name}: ${job.state}` : "no job yet";
    $("comp-state").dataset.state = job ? job.state : "none";
    $("comp-done").textContent = task ? `${task.done} / ${task.done + task.left}` : "—";
    $("comp-attempts").textContent = task ? String(task.attempts) : "—";
    $("comp-failures").textContent = task ? String(task.failures.length) : "—";
    $("comp-step").textContent = task ? task.step : job ? job.message : "";
    $("comp-failure-list").replaceChildren(
      ...(task ? task.failures : []).map((text) => Object.assign(document.createElement("li"), { textContent: text })),
    );
  }

  renderScore() {
    const box = $("comp-score");
    const body = $("comp-breakdown");
    const result = this.score;
    if (!result || !result.score) {
      box.dataset.state = result ? "none" : "";
      $("comp-score-points").textContent = result ? result.note || "no score" : "";
      $("comp-score-meta").textContent = "";
      body.replaceChildren();
      return;
    }
    const s = result.score;
    box.dataset.state = s.full ? "full" : "partial";
    $("comp-score-points").textContent = `${s.points} / ${s.max_points}`;
    const within = s.within_limit ? "within" : "over";
    const note = result.note ? ` · ${result.note}` : "";
    const ended = this.job && (this.job.state === "cancelled" || this.job.state === "failed") ? this.job.state : "";
    if (ended) { // a job stopped early: say so and what it did, not 'within the limit'
      const task = this.job.extra && this.job.extra.task;
      const done = task ? `${task.done} of ${task.done + task.left} blocks done` : "";
      $("comp-score-points").textContent = `${s.points} / ${s.max_points} · ${ended}`;
      $("comp-score-meta").textContent = `${ended} after ${result.sim_time_s.toFixed(1)} s simulated${done ? `: ${done}` : ""}; `
        + `the points are for what stands on the board now. Start it again to finish${note}`;
    } else {
      $("comp-score-meta").textContent = `simulated ${result.sim_time_s.toFixed(1)} s, ${within} the ${s.time_limit_s} s limit${s.full ? " · full points" : ""}${note}`;
    }
    body.replaceChildren(
      ...s.breakdown.map((rule) => {
        const row = document.createElement("tr");
        const cells = [rule.rule, String(rule.points), rule.detail + (rule.object_ids.length ? ` (${rule.object_ids.join(", ")})` : "")];
        row.append(...cells.map((text) => Object.assign(document.createElement("td"), { textContent: text })));
        row.dataset.points = String(rule.points);
        return row;
      }),
    );
  }

  /** The plan in camera pixels: the next block's centre and its destination projected through the calibration. */
  updatePlan() {
    const task = this.job && this.job.state === "running" && this.job.extra && this.job.extra.task;
    const block = task && task.next_block;
    if (!block) {
      this.plan = null;
      return;
    }
    const target = Array.isArray(task.next_target_m) ? worldToCameraPx(task.next_target_m, this.camera) : null;
    this.plan = {
      blockPx: Array.isArray(block.center_px) ? { u: block.center_px[0], v: block.center_px[1] } : null,
      targetPx: target,
      blockM: block.position_m,
      targetM: task.next_target_m,
      label: `${block.color || ""} ${block.size || ""}`.trim(),
    };
  }

  /** LiveView overlay: ring the next block, arrow to its destination, mark the destination. */
  drawPlan(view) {
    const plan = this.plan;
    if (!plan) return;
    let from = null;
    let to = null;
    if (view.view() === "topdown") {
      const b = view.topdownBounds();
      const w = view.canvas.width;
      const h = view.canvas.height;
      if (Array.isArray(plan.blockM)) from = worldToTopdownPx(plan.blockM[0], plan.blockM[1], w, h, b);
      if (Array.isArray(plan.targetM)) to = worldToTopdownPx(plan.targetM[0], plan.targetM[1], w, h, b);
    } else {
      from = plan.blockPx && view.cameraToFramePx([plan.blockPx.u, plan.blockPx.v]);
      to = plan.targetPx && view.cameraToFramePx([plan.targetPx.u, plan.targetPx.v]);
    }
    const { ctx, canvas } = view;
    const s = Math.max(canvas.width / 1280, 0.5); // shapes: frame pixels
    const k = s * Math.min(2, Math.max(1, canvas.width / (canvas.clientWidth || canvas.width))); // text and lines: screen size
    ctx.save();
    ctx.strokeStyle = PLAN_COLOR;
    ctx.fillStyle = PLAN_COLOR;
    ctx.lineWidth = 2.5 * k;
    ctx.font = `bold ${Math.round(14 * k)}px sans-serif`;
    ctx.shadowColor = "rgba(0, 0, 0, 0.8)";
    ctx.shadowBlur = 3 * k;
    if (from) {
      ctx.beginPath();
      ctx.arc(from.u, from.v, 24 * s, 0, 2 * Math.PI);
      ctx.stroke();
      ctx.fillText(`next: ${plan.label}`, from.u + 28 * s, from.v - 20 * s);
    }
    if (to) {
      ctx.strokeRect(to.u - 16 * s, to.v - 16 * s, 32 * s, 32 * s);
      ctx.fillText("place", to.u + 20 * s, to.v + 16 * s + 12 * k);
    }
    if (from && to) {
      const angle = Math.atan2(to.v - from.v, to.u - from.u);
      const length = Math.hypot(to.u - from.u, to.v - from.v);
      if (length > 60 * s) {
        const start = { u: from.u + Math.cos(angle) * 26 * s, v: from.v + Math.sin(angle) * 26 * s };
        const end = { u: to.u - Math.cos(angle) * 20 * s, v: to.v - Math.sin(angle) * 20 * s };
        ctx.setLineDash([10 * k, 7 * k]);
        ctx.beginPath();
        ctx.moveTo(start.u, start.v);
        ctx.lineTo(end.u, end.v);
        ctx.stroke();
        ctx.setLineDash([]);
        ctx.beginPath();
        ctx.moveTo(end.u, end.v);
        ctx.lineTo(end.u - Math.cos(angle - 0.4) * 12 * k, end.v - Math.sin(angle - 0.4) * 12 * k);
        ctx.lineTo(end.u - Math.cos(angle + 0.4) * 12 * k, end.v - Math.sin(angle + 0.4) * 12 * k);
        ctx.closePath();
        ctx.fill();
      }
    }
    ctx.restore();
  }
}
