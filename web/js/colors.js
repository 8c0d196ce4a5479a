// Colour calibration (issue 17 item 2): in the "Name colour" click mode the operator picks a colour name
// and clicks a block's top on the video; the station measures that face in its newest frame against the
// board's grey and uses the sample at once (POST /api/colors/samples). The panel lists the samples in
// use and resets to the defaults (DELETE /api/colors/samples). A refusal (unknown name, a grey face,
// outside the image) is shown with the station's reason; its colour model is then unchanged.

/** A CSS colour showing a board-normalised CIELAB [L, a, b] on a mid-grey board (for swatches). */
export function labToCss(lab) {
  if (!Array.isArray(lab) || lab.length !== 3 || !lab.every(Number.isFinite)) return "";
  const [L, a, b] = lab;
  const fy = (L + 16) / 116;
  const fx = fy + a / 500;
  const fz = fy - b / 200;
  const d = 6 / 29;
  const inv = (t) => (t > d ? t ** 3 : 3 * d * d * (t - 4 / 29));
  const [X, Y, Z] = [inv(fx) * 0.9505, inv(fy), inv(fz) * 1.089];
  const lin = [
    3.2406 * X - 1.5372 * Y - 0.4986 * Z,
    -0.9689 * X + 1.8758 * Y + 0.0415 * Z,
    0.0557 * X - 0.204 * Y + 1.057 * Z,
  ].map((c) => Math.min(1, Math.max(0, c * 0.43))); // the board (reflectance 0.5) shown at ~mid-grey
  const srgb = lin.map((c) => Math.round(255 * (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055)));
  return `rgb(${srgb.join(",")})`;
}

export class ColorCalibration {
  /** root: an empty element for the panel; api: the page's Api; live: LiveView (its canvas is clicked); log: EventLog. */
  constructor({ root, api, live, log }) {
    this.api = api;
    this.live = live;
    this.log = log;
    this.active = false;
    this.busy = false;
    this.info = null;
    root.innerHTML = `
      <h2>Colours <small id="colors-summary">—</small></h2>
      <p class="intr-line" id="colors-hint">Choose "Name colour" above, pick the colour, then click a block's top on the video.</p>
      <div class="btn-row">
        <label>Colour <select id="colors-name" aria-label="colour of the block to click"></select></label>
        <button class="btn small" id="btn-colors-reset" data-command="calibrate" type="button">Reset to defaults</button>
      </div>
      <p class="intr-line" id="colors-message" role="status"></p>
      <ol id="colors-samples" class="intr-views"></ol>`;
    this.$ = (id) => root.querySelector(`#${id}`);
    this.$("btn-colors-reset").addEventListener("click", () => this.reset());
    live.canvas.addEventListener("click", (e) => this.onCanvasClick(e));
    this.refresh();
  }

  /** Click mode "color" on or off (the click-mode buttons). */
  setActive(active) {
    this.active = active;
    this.$("colors-hint").dataset.active = String(active);
  }

  async refresh() {
    try {
      this.info = await this.api.get("/api/colors");
    } catch (e) {
      this.$("colors-summary").textContent = `unavailable: ${e.message}`;
      return;
    }
    this.render(this.info);
  }

  render(info) {
    const select = this.$("colors-name");
    const kept = select.value;
    select.replaceChildren(...info.names.map((name) => new Option(name.replace("_", " "), name)));
    if (info.names.includes(kept)) select.value = kept;
    this.$("colors-summary").textContent = info.samples.length ? `${info.samples.length} station sample(s)` : "defaults";
    this.$("colors-samples").replaceChildren(...info.samples.map((s) => {
      const item = document.createElement("li");
      const swatch = document.createElement("span");
      swatch.className = "swatch";
      swatch.style.background = labToCss(s.lab);
      item.append(swatch, ` ${s.name} at (${Math.round(s.u)}, ${Math.round(s.v)}) · Lab ${s.lab.map((x) => x.toFixed(0)).join(" ")}`);
      return item;
    }));
  }

  async onCanvasClick(event) {
    if (!this.active || this.busy) return;
    const px = this.live.pointerToPx(event);
    if (!px) return;
    if (this.live.view() !== "color") {
      this.show("click the block on the Video view (the depth and top-down views are not the camera image)", true);
      return;
    }
    const color = this.$("colors-name").value;
    const body = { u: px.camera.u, v: px.camera.v, color };
    this.busy = true;
    try {
      const answer = await this.api.post("/api/colors/samples", body);
      const before = answer.reading_before.name;
      this.show(`${color} at (${body.u.toFixed(0)}, ${body.v.toFixed(0)}): in use (read ${before} before)`, false);
      this.log.add("info", `colour sample: ${color} (read ${before} before)`);
    } catch (e) {
      this.show(`refused: ${e.message}; the colours in use are unchanged`, true);
    } finally {
      this.busy = false;
      await this.refresh();
    }
  }

  async reset() {
    try {
      await this.api.request("DELETE", "/api/colors/samples");
      this.show("reset to the default colours", false);
    } catch (e) {
      this.show(`reset refused: ${e.message}`, true);
    }
    await this.refresh();
  }

  show(message, refused) {
    this.$("colors-message").textContent = message;
    this.$("colors-message").dataset.refused = String(refused);
  }
}
