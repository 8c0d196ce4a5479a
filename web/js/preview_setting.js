// "Preview before moving" (issue 22): a page setting, kept in this browser, that makes every manual move (click-grab,
// click-drop, Go, Go to joints, Send joints, Home, Sleep, jog steps, Repeat, a paused repeat's Step) plan without moving (?plan_only=true) and wait for Execute
// in the Go to panel (plan_preview.js), the goal arm and path drawn in the 3-D view.

const KEY = "armlab.previewMoves";

export class PreviewSetting {
  /** box: the checkbox; preview(): the PlanPreview that shows plans. */
  constructor({ box, preview }) {
    this.box = box;
    this.preview = preview;
    this.box.checked = localStorage.getItem(KEY) === "1";
    this.box.addEventListener("change", () => localStorage.setItem(KEY, this.box.checked ? "1" : "0"));
  }

  get on() {
    return this.box.checked;
  }

  /** send() at once, or with the setting on the plan of the same move (path, body: its REST route and body). */
  moveOrPlan(action, path, body, send) {
    return this.on ? this.preview().make(action, path, body) : send();
  }
}
