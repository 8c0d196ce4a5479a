// The station's global speed override in the top bar: every motion (jobs, manual moves, repeats) runs at it. The
// slider follows the status (speed_percent) unless it is being dragged; a change is sent to PUT /api/speed (the
// repeat panel's slider sets the same override).

const $ = (id) => document.getElementById(id);

export class SpeedOverride {
  /** api: Api; run(action, call): the page's REST runner (logs errors and toasts refusals). */
  constructor({ api, run }) {
    this.api = api;
    this.run = run;
    this.input = $("speed-override");
    this.out = $("speed-override-out");
    this.shown = null;
    this.input.addEventListener("input", () => { this.out.textContent = `${this.input.value} %`; });
    this.input.addEventListener("change", () => this.set(Number(this.input.value)));
  }

  /** Send a new override; the status brings back what the station took. */
  async set(speedPercent) {
    const answer = await this.run(`speed override ${speedPercent} %`, () => this.api.request("PUT", "/api/speed", { speed_percent: speedPercent }));
    if (answer) this.show(answer.speed_percent, true);
    else if (this.shown !== null) this.show(this.shown, true); // refused: back to the station's
  }

  /** Show the station's override (from the status); a slider being dragged keeps its value unless forced. */
  show(speedPercent, force = false) {
    if (!Number.isFinite(speedPercent)) return;
    this.shown = speedPercent;
    this.input.closest(".speed-override").dataset.speed = String(speedPercent);
    if (!force && document.activeElement === this.input) return;
    this.input.value = String(speedPercent);
    this.out.textContent = `${Math.round(speedPercent)} %`;
  }

  setDisabled(disabled) {
    this.input.disabled = disabled;
  }
}
