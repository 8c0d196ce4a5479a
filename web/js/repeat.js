// Repeat of a taught program: cycles and speed override (changeable while it runs: PATCH /api/jobs/current),
// pause / resume / step / stop, progress (cycle, waypoint, time left) from job.extra.repeat, and the joint
// angles of the last complete cycle (commanded and measured, GET /api/jobs/current/trace) with a CSV download.

const $ = (id) => document.getElementById(id);
const DEG = 180 / Math.PI;
const COLORS = ["#3d8bfd", "#2fbf71", "#e0a030", "#e5484d", "#b07cff", "#4fd1c5"];

/** One line of progress from a RepeatProgress (job.extra.repeat). */
export function progressText(r) {
  if (!r) return "";
  const cycles = r.cycles === null || r.cycles === undefined ? "∞" : r.cycles;
  const left = Number.isFinite(r.time_left_s) ? ` · ${r.time_left_s.toFixed(0)} s left` : "";
  return `${r.paused ? "paused · " : ""}cycle ${r.cycle}/${cycles} · waypoint ${r.waypoint}/${r.waypoints} · ${r.phase} · ${Math.round(r.speed_percent)} %${left}`;
}

export class RepeatPanel {
  /** moveOrPlan(action, path, body, send): send() now, or with "preview before moving" on the repeat's plan. */
  constructor({ api, run, log, moveOrPlan = (action, path, body, send) => send() }) {
    this.api = api;
    this.run = run;
    this.log = log;
    this.moveOrPlan = moveOrPlan;
    this.jobId = null;
    this.cyclesSeen = -1;
    this.plot = null;
    this.plotKey = "";
    const on = (id, fn) => $(id).addEventListener("click", fn);
    on("btn-repeat-pause", () => this.run("pause", () => this.api.post("/api/jobs/pause")));
    on("btn-repeat-resume", () => this.run("resume", () => this.api.post("/api/jobs/resume")));
    // with "preview before moving" on, Step plans the paused job's next step (shown in 3-D) and waits for Execute
    on("btn-repeat-step", () => this.moveOrPlan("plan the next step", "/api/jobs/step", undefined,
      () => this.run("step", () => this.api.post("/api/jobs/step"))));
    on("btn-repeat-stop", () => this.run("stop repeat", () => this.api.cancelJob()));
    const speed = $("repeat-speed");
    speed.addEventListener("input", () => { $("repeat-speed-out").textContent = `${speed.value} %`; });
    speed.addEventListener("change", () => this.speedChanged());
  }

  get speedPercent() {
    return Number($("repeat-speed").value);
  }

  /** Start a repeat of `program` with the panel's cycles (empty = until stopped) and speed. */
  start(program) {
    const text = $("repeat-cycles").value.trim();
    const cycles = text === "" ? null : Math.max(1, Math.round(Number(text)) || 1);
    const path = `/api/programs/${encodeURIComponent(program.id)}/repeat`;
    return this.moveOrPlan(`plan repeat ${program.name}`, path, { cycles, speed_percent: this.speedPercent },
      () => this.run(`repeat ${program.name}`, () => this.api.repeat(program.id, cycles, this.speedPercent)));
  }

  /** The slider sets the station's one speed override (the top bar's), which a running repeat takes (re-planning at
   * it, or refusing it with its reason). Always PUT /api/speed: the page's idea of whether a repeat runs lags the
   * station (a change just after a repeat ended went to the ended job and was refused). */
  speedChanged() {
    this.run(`speed override ${this.speedPercent} %`, () => this.api.request("PUT", "/api/speed", { speed_percent: this.speedPercent }));
  }

  /** Follow the status: progress line, and the cycle plot whenever a cycle completed or the repeat ended. */
  onStatus(s) {
    const speed = $("repeat-speed");
    if (Number.isFinite(s.speed_percent) && document.activeElement !== speed) {
      speed.value = String(s.speed_percent);
      $("repeat-speed-out").textContent = `${Math.round(s.speed_percent)} %`;
    }
    const job = s.job;
    const repeat = job && job.name === "repeat" ? job.extra?.repeat : null;
    const running = Boolean(job && job.name === "repeat" && job.state === "running");
    this.jobId = running ? job.id : null;
    $("repeat-run").dataset.running = String(running);
    $("repeat-progress").textContent = repeat ? progressText(repeat) + (running ? "" : ` · ${job.state}`) : "no repeat yet";
    if (!repeat) return;
    const done = (repeat.last_cycle_times_s || []).length + (repeat.cycle || 0) * 1000 + (running ? 0 : 1e6);
    const key = `${job.id}:${done}`;
    if (key !== this.plotKey && (repeat.cycle > 1 || !running)) {
      this.plotKey = key;
      this.loadTrace();
    }
  }

  async loadTrace() {
    let trace;
    try {
      trace = await this.api.get("/api/jobs/current/trace");
    } catch {
      return;
    }
    if (!trace || !Array.isArray(trace.samples) || !trace.samples.length) return;
    $("cycle-plot-title").textContent = `cycle ${trace.cycle}${trace.complete ? "" : " (running)"}: commanded (solid) and measured (dashed), deg`;
    $("btn-cycle-csv").hidden = false;
    this.draw(trace);
  }

  draw(trace) {
    const names = trace.joint_names;
    const n = names.length;
    const t0 = trace.samples[0][0];
    const columns = [trace.samples.map((r) => r[0] - t0)];
    for (let j = 0; j < n; j += 1) columns.push(trace.samples.map((r) => r[1 + j] * DEG));
    for (let j = 0; j < n; j += 1) columns.push(trace.samples.map((r) => r[1 + n + j] * DEG));
    const container = $("cycle-plot");
    if (typeof window.uPlot !== "function") return;
    this.plot?.destroy();
    const series = [{ label: "t s" },
      ...names.map((name, j) => ({ label: `${name} cmd`, stroke: COLORS[j % COLORS.length], width: 1.5 })),
      ...names.map((name, j) => ({ label: `${name} meas`, stroke: COLORS[j % COLORS.length], width: 1, dash: [4, 3] }))];
    this.plot = new window.uPlot({
      width: Math.max(280, container.clientWidth || 360),
      height: 160,
      legend: { show: false },
      scales: { x: { time: false } },
      axes: [{ stroke: "#8a96a6", grid: { stroke: "#232933" } }, { stroke: "#8a96a6", grid: { stroke: "#232933" }, size: 40 }],
      series,
    }, columns, container);
    container.dataset.samples = String(trace.samples.length);
    const canvas = container.querySelector("canvas");
    if (canvas) {
      $("btn-cycle-png").href = canvas.toDataURL("image/png");
      $("btn-cycle-png").download = `repeat-cycle-${trace.cycle}.png`;
      $("btn-cycle-png").hidden = false;
    }
    container.dataset.cycle = String(trace.cycle);
  }
}
