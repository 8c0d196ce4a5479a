// The control lease in the top bar: who holds it, a "Take control" button (POST /api/control/take), and a
// toast for this page when another controller takes it over. One controller at a time; e-stop needs none.

const $ = (id) => document.getElementById(id);

export class ControlLease {
  /** api: Api (its controller name is this page's); log: EventLog; onChange(): re-apply button states. */
  constructor({ api, log, onChange }) {
    this.api = api;
    this.log = log;
    this.onChange = onChange || (() => {});
    this.holder = undefined; // undefined: not known yet; null: free
    $("btn-take-control").addEventListener("click", () => this.take());
  }

  get me() {
    return this.api.controller;
  }

  /** True when this page may command: it holds the lease, or the lease is free (the first command takes it). */
  get mine() {
    return this.holder === null || this.holder === undefined || this.holder === this.me;
  }

  render(status) {
    const holder = status.controller ?? null;
    const previous = this.holder;
    this.holder = holder;
    const label = $("control-holder");
    label.dataset.holder = holder ?? "";
    label.dataset.mine = String(holder === this.me);
    label.textContent = holder === null ? "control free" : holder === this.me ? `you control (${holder})` : `controlled by ${holder}`;
    const button = $("btn-take-control");
    button.hidden = !this.api.canControl;
    button.disabled = !this.api.canControl || holder === this.me;
    if (previous === this.me && holder !== null && holder !== this.me) {
      this.log.toast("warn", "control taken", `'${holder}' took control of the station; press Take control to take it back`);
    }
    if (previous !== holder) this.onChange();
  }

  async take() {
    try {
      const status = await this.api.takeControl();
      this.log.add("info", `you took control (${this.me})`);
      if (status) this.render(status);
    } catch (e) {
      this.log.error("take control", e);
    }
  }
}
