// A program's step tree in the teach panel (the tree a pendant shows): waypoints, waits, gripper steps,
// loops of N and labelled groups, indented by nesting. Tick top-level steps, then wrap them in a loop or a
// group, or add a wait or a gripper step after them. Every change is one PATCH of the whole tree
// (`steps`); the server checks it (loop 1-1000, at most 4 deep, at most 1000 waypoints expanded) and
// the table below shows the flat sequence repeat runs.

const $ = (id) => document.getElementById(id);
const DEG = 180 / Math.PI;

/** A step as sent back in a PATCH (the request models' fields only). */
export function stepRequest(s) {
  const kind = s.kind || "waypoint";
  if (kind === "wait") return { kind, seconds: Number(s.seconds) };
  if (kind === "gripper") return { kind, action: s.action };
  if (kind === "loop") return { kind, count: Number(s.count), body: s.body.map(stepRequest) };
  if (kind === "group") return { kind, label: s.label, body: s.body.map(stepRequest) };
  const out = { joints_rad: s.joints_rad.map(Number), gripper: s.gripper, dwell_s: Number(s.dwell_s) || 0 };
  if (Number.isFinite(s.moving_time_s) && s.moving_time_s > 0) out.moving_time_s = s.moving_time_s;
  return out;
}

function describe(s) {
  const kind = s.kind || "waypoint";
  if (kind === "wait") return `wait ${s.seconds} s`;
  if (kind === "gripper") return `gripper ${s.action}`;
  if (kind === "loop") return `loop × ${s.count}`;
  if (kind === "group") return `group “${s.label}”`;
  const dwell = s.dwell_s ? `, dwell ${s.dwell_s} s` : "";
  return `waypoint [${s.joints_rad.map((q) => (q * DEG).toFixed(0)).join(", ")}]° ${s.gripper}${dwell}`;
}

export class StepTree {
  /** patch(program, body, action): PATCH and redraw; log: EventLog; selected(): the program being edited. */
  constructor({ patch, log, selected }) {
    this.patch = patch;
    this.log = log;
    this.selected = selected;
    this.tickedSet = new Set(); // top-level step indices ticked (kept across redraws of the same program)
    this.tickedOf = null;
    const on = (id, fn) => $(id).addEventListener("click", fn);
    on("btn-step-wait", () => this.addAfter({ kind: "wait", seconds: Number($("step-wait-s").value) }, "add a wait"));
    on("btn-step-close", () => this.addAfter({ kind: "gripper", action: "close" }, "add a gripper close"));
    on("btn-step-open", () => this.addAfter({ kind: "gripper", action: "open" }, "add a gripper open"));
    on("btn-step-loop", () => this.wrap((body) => ({ kind: "loop", count: Number($("step-loop-count").value), body }), "loop"));
    on("btn-step-group", () => this.wrap((body) => ({ kind: "group", label: $("step-group-label").value.trim(), body }), "group"));
    on("btn-step-unwrap", () => this.unwrap());
    on("btn-step-delete", () => this.remove());
  }

  /** The selected program's steps: its tree, or its waypoints (a flat program). */
  steps(p) {
    return (p.steps || p.waypoints).map(stepRequest);
  }

  ticked() {
    return [...this.tickedSet].sort((a, b) => a - b);
  }

  render(p) {
    const key = p ? `${p.id}:${p.updated_s}` : null;
    if (key !== this.tickedOf) this.tickedSet.clear(); // another program, or this one changed
    this.tickedOf = key;
    $("program-steps").replaceChildren(...(p ? this.items(p.steps || p.waypoints, true) : []));
  }

  items(steps, top) {
    return steps.map((s, i) => {
      const li = document.createElement("li");
      li.dataset.kind = s.kind || "waypoint";
      const label = document.createElement("label");
      if (top) {
        const box = document.createElement("input");
        Object.assign(box, { type: "checkbox", title: "select this step" });
        box.dataset.index = String(i);
        box.checked = this.tickedSet.has(i);
        box.addEventListener("change", () => { if (box.checked) this.tickedSet.add(i); else this.tickedSet.delete(i); });
        label.append(box);
      }
      const text = document.createElement("span");
      text.textContent = describe(s);
      label.append(text);
      li.append(label);
      if (Array.isArray(s.body)) {
        const ol = document.createElement("ol");
        ol.className = "step-body";
        ol.append(...this.items(s.body, false));
        li.append(ol);
      }
      return li;
    });
  }

  send(steps, action) {
    const p = this.selected();
    return this.patch(p, { steps }, action);
  }

  /** Add `step` after the last ticked top-level step (or at the end). */
  addAfter(step, action) {
    const p = this.selected();
    const steps = this.steps(p);
    const ticked = this.ticked();
    const at = ticked.length ? Math.max(...ticked) + 1 : steps.length;
    steps.splice(at, 0, step);
    return this.send(steps, action);
  }

  /** Wrap the ticked top-level steps (from the first to the last ticked) in a loop or a group. */
  wrap(make, what) {
    const ticked = this.ticked();
    if (!ticked.length) {
      this.log.toast("error", what, "tick the steps to put in it first");
      return null;
    }
    const steps = this.steps(this.selected());
    const first = Math.min(...ticked);
    const last = Math.max(...ticked);
    steps.splice(first, last - first + 1, make(steps.slice(first, last + 1)));
    return this.send(steps, `${what} steps ${first + 1}-${last + 1}`);
  }

  /** Replace each ticked loop or group by its body. */
  unwrap() {
    const ticked = new Set(this.ticked());
    const steps = this.steps(this.selected()).flatMap((s, i) => (ticked.has(i) && Array.isArray(s.body) ? s.body : [s]));
    return this.send(steps, "unwrap");
  }

  remove() {
    const ticked = new Set(this.ticked());
    const steps = this.steps(this.selected()).filter((_, i) => !ticked.has(i));
    if (!steps.length) {
      this.log.toast("error", "delete steps", "a program keeps at least one waypoint: delete the program instead");
      return null;
    }
    return this.send(steps, "delete steps");
  }
}
