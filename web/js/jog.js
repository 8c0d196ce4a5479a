// Cartesian jog of the gripper through POST /api/arm/step (the station keeps pitch and yaw and moves along
// the asked axis, or refuses with the reason): the panel's buttons and the keyboard. Arrow keys move in x/y,
// PageUp/PageDown in z, Shift+Up/Down pitch and Shift+Left/Right wrist roll; one step per key press. While a
// form field has the focus the keys are its own (a joint slider's arrows move that joint): the key hint says
// which the keys do now.

const $ = (id) => document.getElementById(id);
const ROTATION_STEP_DEG = 5;

/** The step a key asks for: {axis, sign} or null. */
export function keyToStep(event) {
  if (event.ctrlKey || event.metaKey || event.altKey) return null;
  if (event.shiftKey) {
    return { ArrowUp: { axis: "pitch", sign: -1 }, ArrowDown: { axis: "pitch", sign: 1 },
      ArrowLeft: { axis: "roll", sign: -1 }, ArrowRight: { axis: "roll", sign: 1 } }[event.key] || null;
  }
  return { ArrowUp: { axis: "y", sign: 1 }, ArrowDown: { axis: "y", sign: -1 }, ArrowLeft: { axis: "x", sign: -1 },
    ArrowRight: { axis: "x", sign: 1 }, PageUp: { axis: "z", sign: 1 }, PageDown: { axis: "z", sign: -1 } }[event.key] || null;
}

/** True when a key press belongs to a form field (typing), not to the page's shortcuts. */
export function typingIn(target) {
  const tag = target && target.tagName;
  return tag === "INPUT" || tag === "TEXTAREA" || tag === "SELECT" || Boolean(target && target.isContentEditable);
}

export const JOG_KEYS_HINT = "keys: ← → ↑ ↓ x/y, PgUp/PgDn z, Shift+arrows pitch/roll";

/** What the keys do with `target` focused: the jog's hint, or the field's own use of them. */
export function keyHint(target) {
  if (!typingIn(target)) return JOG_KEYS_HINT;
  const slider = target.type === "range" && target.closest && target.closest("#joint-sliders");
  if (slider) {
    const joint = target.id.replace(/^slider-/, "");
    return `keys: ← → ↑ ↓ move ${joint} (its slider has the focus); click the view to jog with them again`;
  }
  return "keys: the focused field takes them; click the view to jog with them again";
}

export class CartesianJog {
  /** api: Api; run(action, call): the page's REST runner; canJog(): whether the station allows a jog now;
   * moveOrPlan(action, path, body, send): send() now, or with "preview before moving" on the step's plan. */
  constructor({ api, run, canJog, moveOrPlan = (action, path, body, send) => send() }) {
    this.api = api;
    this.run = run;
    this.canJog = canJog;
    this.moveOrPlan = moveOrPlan;
    this.busy = false;
    document.querySelectorAll("[data-jog]").forEach((b) =>
      b.addEventListener("click", () => this.step(b.dataset.jog.slice(0, -1), b.dataset.jog.endsWith("+") ? 1 : -1)));
    document.addEventListener("keydown", (e) => this.onKey(e));
    const hint = () => this.showHint(document.activeElement);
    document.addEventListener("focusin", hint);
    document.addEventListener("focusout", () => setTimeout(hint, 0)); // activeElement is the next one only then
  }

  showHint(target) {
    const el = $("jog-keys");
    if (!el) return;
    el.textContent = keyHint(target);
    el.dataset.keys = typingIn(target) ? (target.type === "range" ? "slider" : "field") : "jog";
  }

  onKey(event) {
    if (typingIn(event.target) || document.querySelector("dialog[open]")) return;
    const step = keyToStep(event);
    if (!step) return;
    event.preventDefault(); // arrows and page keys would scroll the page
    if (event.repeat || !this.canJog()) return;
    this.step(step.axis, step.sign);
  }

  /** One step along axis x|y|z (the chosen mm) or pitch|roll (5°) at the chosen speed. */
  async step(axis, sign) {
    if (this.busy) return null;
    this.busy = true;
    const speed = Number($("jog-speed").value) || 100;
    const body = { axis, speed_percent: speed };
    if ("xyz".includes(axis)) body.distance_m = sign * Number($("jog-step").value);
    else body.angle_rad = (sign * ROTATION_STEP_DEG * Math.PI) / 180;
    const action = `jog ${axis}${sign > 0 ? "+" : "−"}`;
    try {
      return await this.moveOrPlan(`plan ${action}`, "/api/arm/step", body, () => this.run(action, () => this.api.step(body)));
    } finally {
      this.busy = false;
    }
  }
}
