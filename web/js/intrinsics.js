// The Intrinsics panel: a guided checkerboard capture (issue 11 item 4). Start, capture views from the
// live camera (the station refuses a view with no board, a blurry one or a duplicate, saying why),
// see which image regions the views cover and each view's error, solve, accept. Everything it shows
// comes from GET /api/intrinsics (the board, limits and grid are the server's config).

const COVER_RGB = [46, 160, 90]; // a covered cell; deeper with more views

function fmt(x, digits = 1) {
  return Number.isFinite(x) ? x.toFixed(digits) : "—";
}

export class IntrinsicsPanel {
  /** root: an empty element to build the panel in; api: the page's Api; log: its EventLog. */
  constructor({ root, api, log }) {
    this.api = api;
    this.log = log;
    this.info = null;
    root.innerHTML = `
      <h2>Intrinsics <small id="intr-source">—</small></h2>
      <div class="intr-line" id="intr-values">—</div>
      <p class="intr-note" id="intr-note" hidden></p>
      <div class="btn-row">
        <button class="btn" id="btn-intr-start" data-command="calibrate" type="button">Start capture</button>
        <button class="btn primary" id="btn-intr-capture" type="button" disabled>Capture view</button>
        <button class="btn" id="btn-intr-solve" type="button" disabled>Solve</button>
        <button class="btn" id="btn-intr-accept" type="button" disabled>Accept</button>
        <button class="btn ghost" id="btn-intr-cancel" type="button" disabled>Cancel</button>
      </div>
      <div id="intr-session" hidden>
        <p class="intr-line" id="intr-hint"></p>
        <div id="intr-progress">0 views</div>
        <canvas id="intr-coverage" width="256" height="144" title="image regions the kept views cover"></canvas>
        <p class="intr-line" id="intr-message" role="status"></p>
        <ol id="intr-views" class="intr-views" start="0"></ol>
        <div class="intr-line" id="intr-solution"></div>
      </div>`;
    this.$ = (id) => root.querySelector(`#${id}`);
    const on = (id, label, call) => this.$(id).addEventListener("click", () => this.act(label, call));
    on("btn-intr-start", "start capture", () => this.api.post("/api/intrinsics/session"));
    on("btn-intr-capture", "capture view", () => this.api.post("/api/intrinsics/capture"));
    on("btn-intr-solve", "solve", () => this.api.post("/api/intrinsics/solve"));
    on("btn-intr-accept", "accept", () => this.api.post("/api/intrinsics/accept"));
    on("btn-intr-cancel", "cancel capture", () => this.api.request("DELETE", "/api/intrinsics/session"));
    this.$("intr-views").addEventListener("click", (event) => {
      const index = event.target?.dataset?.deleteView;
      if (index !== undefined) this.act(`delete view ${index}`, () => this.api.request("DELETE", `/api/intrinsics/views/${index}`));
    });
    this.refresh();
  }

  /** Run one call; a refusal (no board, blurry, duplicate, too few views, error too high) is shown in the panel. */
  async act(label, call) {
    this.$("intr-message").textContent = `${label}…`;
    let message = "";
    try {
      await call();
      message = `${label}: ok`;
    } catch (e) {
      message = `${label} refused: ${e.message}`;
      this.log.add("warn", `intrinsics ${message}`);
    }
    await this.refresh();
    this.$("intr-message").textContent = message;
    this.$("intr-message").dataset.refused = String(message.includes("refused"));
  }

  async refresh() {
    try {
      this.info = await this.api.get("/api/intrinsics");
    } catch (e) {
      this.$("intr-values").textContent = `intrinsics unavailable: ${e.message}`;
      return;
    }
    this.render(this.info);
  }

  render(info) {
    const k = info.intrinsics;
    this.$("intr-source").textContent = `${info.source} · ${info.camera}`;
    this.$("intr-values").textContent =
      `fx ${fmt(k.fx)} fy ${fmt(k.fy)} cx ${fmt(k.cx)} cy ${fmt(k.cy)} px` + (info.rms_px != null ? ` · RMS ${fmt(info.rms_px, 3)} px` : "");
    this.$("intr-note").hidden = !info.note;
    this.$("intr-note").textContent = info.note || "";
    const s = info.session;
    this.$("intr-session").hidden = !s;
    this.$("btn-intr-capture").disabled = !s;
    this.$("btn-intr-solve").disabled = !s || s.views.length < s.min_views;
    this.$("btn-intr-accept").disabled = !s || !s.solution;
    this.$("btn-intr-cancel").disabled = !s;
    if (!s) return;
    const [cols, rows] = s.target.inner_corners;
    this.$("intr-hint").textContent = `Hold the ${cols}×${rows}-corner board (${fmt(1000 * s.target.square_m, 0)} mm squares) ` +
      "whole and still at a new place or tilt, then Capture view; fill the image.";
    this.$("intr-progress").textContent =
      `${s.views.length}/${s.min_views} views · coverage ${Math.round(100 * s.coverage_fraction)} %`;
    this.drawCoverage(s);
    const list = this.$("intr-views");
    list.replaceChildren(...s.views.map((v) => {
      const item = document.createElement("li");
      item.textContent = `edges ${fmt(v.edge_width_px, 2)} px · error ${v.error_px == null ? "—" : fmt(v.error_px, 3) + " px"} `;
      const drop = document.createElement("button");
      drop.className = "btn small ghost";
      drop.type = "button";
      drop.textContent = "Delete";
      drop.dataset.deleteView = String(v.index);
      item.append(drop);
      return item;
    }));
    const sol = s.solution;
    this.$("intr-solution").textContent = sol
      ? `solved: fx ${fmt(sol.fx)} fy ${fmt(sol.fy)} cx ${fmt(sol.cx)} cy ${fmt(sol.cy)} px · RMS ${fmt(sol.rms_px, 3)} px`
      : "";
  }

  /** The image as a grid: cells shaded by how many views reach them, each view's outline on top. */
  drawCoverage(s) {
    const canvas = this.$("intr-coverage");
    const ctx = canvas.getContext("2d");
    const [w, h] = s.image_size;
    const [cols, rows] = s.grid;
    canvas.height = Math.round((canvas.width * h) / w);
    const cw = canvas.width / cols;
    const ch = canvas.height / rows;
    ctx.fillStyle = "#222";
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    const most = Math.max(1, ...s.coverage.flat());
    s.coverage.forEach((row, r) => row.forEach((count, c) => {
      if (!count) return;
      const a = 0.35 + 0.65 * (count / most);
      ctx.fillStyle = `rgba(${COVER_RGB.join(",")},${a.toFixed(2)})`;
      ctx.fillRect(c * cw + 1, r * ch + 1, cw - 2, ch - 2);
    }));
    ctx.strokeStyle = "#fff";
    ctx.lineWidth = 1;
    for (const v of s.views) {
      ctx.beginPath();
      v.outline_px.forEach(([u, vv], i) => ctx[i ? "lineTo" : "moveTo"]((u * canvas.width) / w, (vv * canvas.height) / h));
      ctx.closePath();
      ctx.stroke();
    }
    canvas.dataset.covered = String(s.coverage.flat().filter((n) => n > 0).length);
  }
}
