// Grab and drop from the live view: a click on the video (or on a detection's row) sends one grab or drop (or, with
// "preview before moving" on, plans it and waits for Execute), refused on the page while the calibration is not trusted.

import { untrustedReason } from "./calstate.js";

export class GrabDropClicks {
  /** api: Api; run(action, call): the page's REST runner; log: EventLog; live: LiveView; status(): the newest status;
   * moveOrPlan(action, path, body, send): send() now, or the plan of it with the preview setting on. */
  constructor({ api, run, log, live, status, moveOrPlan = (action, path, body, send) => send() }) {
    this.moveOrPlan = moveOrPlan;
    this.api = api;
    this.run = run;
    this.log = log;
    this.live = live;
    this.status = status;
    this.pending = false;
  }

  /** One grab/drop per target: a double-click's second click, or a click while the last is pending, sends nothing. */
  clickTarget(t) {
    if (this.pending) return;
    this.pending = true;
    this.clickTargetNow(t).finally(() => { this.pending = false; });
  }

  clickTargetNow(t) {
    if (this.refusedUntrusted(t.mode)) return Promise.resolve(null);
    const body = t.positionM ? { position_m: t.positionM } : { u: t.u, v: t.v };
    const where = t.positionM ? t.positionM.map((v) => Math.round(v * 1000)).join(", ") + " mm" : `pixel (${t.u.toFixed(0)}, ${t.v.toFixed(0)})`;
    if (t.mode === "grab" || t.mode === "drop") {
      const send = () => this.run(`${t.mode} at ${where}`, () => this.api[t.mode](body));
      return this.moveOrPlan(`${t.mode} at ${where}`, `/api/${t.mode}`, body, send);
    }
    return Promise.resolve(null);
  }

  /** True (and the reason logged) when a grab or drop must not go: the calibration is not trusted. */
  refusedUntrusted(mode) {
    const reason = (mode === "grab" || mode === "drop") && untrustedReason(this.status());
    if (reason) this.log.toast("error", `${mode} refused`, reason);
    return Boolean(reason);
  }

  detectionClicked(d) {
    if (this.live.mode === "grab" && Array.isArray(d.position_m) && !this.refusedUntrusted("grab")) {
      const action = `grab ${d.color || ""} block ${d.id ?? ""}`;
      const body = { position_m: d.position_m };
      this.moveOrPlan(action, "/api/grab", body, () => this.run(action, () => this.api.grab(body)));
    }
  }
}
