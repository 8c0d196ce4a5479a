// The reach state before a click (issue 21): in Click-grab and Click-drop mode, the point under the resting
// pointer is checked as the command would plan it (POST /api/grab/check, /api/drop/check; nothing moves) and the
// verdict is shown on the view: what the click would do, or why it would be refused and what to do instead
// ('out of the arm's reach ...: click a spot nearer the arm'). Checked once the pointer rests (REST_MS), one check
// in flight, the newest point wins; 'checking…' meanwhile (a numeric-IK arm takes seconds to refuse a point).

const REST_MS = 250;

export class ReachState {
  /** api: Api; el: the verdict's element (over the view, out of the layout's flow). */
  constructor({ api, el }) {
    this.api = api;
    this.el = el;
    this.pending = null;
    this.busy = false;
    this.seq = 0;
    this.timer = null;
  }

  /** The pointer rests on `target` ({u, v} or {position_m}) in `mode`; null target or another mode: nothing shown. */
  show(mode, target) {
    this.seq += 1;
    this.pending = null;
    clearTimeout(this.timer);
    if (!target || (mode !== "grab" && mode !== "drop")) {
      this.el.hidden = true;
      delete this.el.dataset.ok;
      return;
    }
    this.pending = { mode, target, seq: this.seq };
    this.timer = setTimeout(() => this.pump(), REST_MS);
  }

  pump() {
    if (this.busy || !this.pending) return;
    const { mode, target, seq } = this.pending;
    this.pending = null;
    this.busy = true;
    this.el.hidden = false;
    this.el.dataset.ok = "checking";
    this.el.textContent = `checking the ${mode} here…`;
    this.api
      .post(`/api/${mode}/check`, target)
      .then((r) => this.render(seq, true, r.detail))
      .catch((e) => this.render(seq, false, e.message))
      .finally(() => {
        this.busy = false;
        this.pump();
      });
  }

  render(seq, ok, text) {
    if (seq !== this.seq) return; // the pointer moved on
    this.el.hidden = false;
    this.el.dataset.ok = String(ok);
    this.el.textContent = ok ? `✓ click to ${text}` : `✗ ${text}`;
  }
}
