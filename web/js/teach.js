// The teach panel: record (button or R key), undo, save; the draft and saved programs as waypoint tables
// (joints in degrees, gripper, dwell, move time) that can be edited in place, reordered, deleted, set to the
// current pose, gone to; rename, duplicate, delete, export. Every edit is one PATCH of the whole program
// (the server checks it against the limits and the table before storing anything).

import { typingIn } from "./jog.js";
import { StepTree } from "./steps.js";

const $ = (id) => document.getElementById(id);
const DEG = 180 / Math.PI;

function cell(tr, content) {
  const td = tr.insertCell();
  if (content instanceof Node) td.append(content);
  else td.textContent = content;
  return td;
}

function smallButton(text, title, onClick, command) {
  const b = document.createElement("button");
  Object.assign(b, { type: "button", className: "btn small", textContent: text, title });
  if (command) b.dataset.command = command;
  b.addEventListener("click", onClick);
  return b;
}

/** Waypoint as sent back in a PATCH (the request model's fields only). */
function toRequest(w) {
  const out = { joints_rad: w.joints_rad.map(Number), gripper: w.gripper, dwell_s: Number(w.dwell_s) || 0 };
  if (Number.isFinite(w.moving_time_s) && w.moving_time_s > 0) out.moving_time_s = w.moving_time_s;
  return out;
}

export class TeachPanel {
  /** api: Api; run(action, call); log: EventLog; status(): the newest status; onRepeat(program): start a repeat. */
  constructor({ api, run, log, status, onRepeat, afterChange, onPath, onProgram, onWaypointSelected }) {
    this.api = api;
    this.run = run;
    this.log = log;
    this.status = status;
    this.onRepeat = onRepeat;
    this.afterChange = afterChange || (() => {});
    this.onPath = onPath || (() => {}); // the selected program's path (or null) for the live view
    this.onProgram = onProgram || (() => {}); // the selected program's waypoints (or null) for the 3-D view
    this.onWaypointSelected = onWaypointSelected || (() => {}); // a table row chosen (its index), for the 3-D view
    this.programs = [];
    this.selectedId = null;
    this.jointNames = [];
    this.bind();
    this.stepTree = new StepTree({ patch: (p, body, action) => this.patch(p, body, action), log, selected: () => this.selected });
  }

  bind() {
    const on = (id, fn) => $(id).addEventListener("click", fn);
    on("btn-teach-start", () => this.run("teach start", () => this.api.teachStart()).then(() => this.refreshDraft()));
    on("btn-teach-record", () => this.record());
    on("btn-teach-undo", () => this.run("undo waypoint", () => this.api.teachUndo()).then(() => this.refreshDraft()));
    on("btn-teach-stop", () => this.save());
    on("btn-teach-exit", () => this.run("leave teach (the draft is kept)", () => this.api.teachExit()).then(() => this.showRecording(false)));
    on("btn-teach-continuous", () => this.toggleContinuous());
    on("btn-programs-refresh", () => this.refresh());
    on("btn-program-rename", () => this.rename());
    on("btn-program-duplicate", () => this.duplicate());
    on("btn-program-delete", () => this.remove());
    on("btn-program-gripper", () => this.insertGripperStep());
    document.addEventListener("keydown", (e) => {
      if ((e.key === "r" || e.key === "R") && !e.ctrlKey && !e.metaKey && !e.altKey && !typingIn(e.target)
          && !$("btn-teach-record").disabled) {
        e.preventDefault();
        this.record();
      }
    });
  }

  setJointNames(names) {
    if (Array.isArray(names)) this.jointNames = names;
  }

  async record() {
    const dwellS = Number($("teach-dwell").value);
    const body = Number.isFinite(dwellS) && dwellS > 0 ? { dwell_s: dwellS } : undefined;
    const r = await this.run("record waypoint", () => this.api.teachRecord(body));
    if (r) this.refreshDraft();
    return r;
  }

  /** Trajectory mode: the station records the pose at the chosen rate while it changes, until stopped. */
  async toggleContinuous() {
    const button = $("btn-teach-continuous");
    const recording = button.dataset.recording === "true";
    if (recording) {
      const r = await this.run("stop recording", () => this.api.post("/api/teach/continuous/stop"));
      this.showRecording(false);
      if (r) this.log.add("info", `recorded ${r.recorded} waypoints continuously`);
      this.refreshDraft();
      return;
    }
    const rateHz = Number($("teach-rate").value);
    if (!(rateHz > 0)) {
      this.log.toast("error", "record continuously", `rate '${$("teach-rate").value}' is not a number of Hz`);
      return;
    }
    if (await this.run(`record at ${rateHz} Hz`, () => this.api.post("/api/teach/continuous", { rate_hz: rateHz }))) this.showRecording(true);
  }

  showRecording(on) {
    clearInterval(this.draftTimer);
    if (on) this.draftTimer = setInterval(() => this.refreshDraft(), 1000); // the table follows the recording
    const button = $("btn-teach-continuous");
    button.dataset.recording = String(on);
    button.textContent = on ? "Stop recording" : "Start recording";
    button.classList.toggle("warn", on);
  }

  async save() {
    const name = $("teach-name").value.trim();
    if (!name) {
      this.log.toast("error", "teach", "give the program a name first");
      return;
    }
    const saved = await this.run(`save program '${name}'`, () => this.api.teachStop(name));
    this.showRecording(false);
    if (saved) {
      this.selectedId = saved.id;
      $("draft-table").replaceChildren();
      await this.refresh();
    }
  }

  async refreshDraft() {
    try {
      const draft = await this.api.teachDraft();
      this.renderTable($("draft-table"), draft.waypoints || [], null);
    } catch {
      /* not teaching: no draft to show */
    }
  }

  async refresh() {
    this.listError = null;
    try {
      const payload = await this.api.programs();
      this.programs = payload.data || [];
      this.others = payload.others || [];
      this.skipped = payload.skipped || [];
    } catch (error) {
      this.programs = [];
      this.others = [];
      this.skipped = [];
      this.listError = error && error.message ? error.message : String(error);
    }
    this.renderList();
    this.renderOthers();
    this.renderEditor();
    this.afterChange();
  }

  get selected() {
    return this.programs.find((p) => p.id === this.selectedId) || null;
  }

  /** Programs of other arms or workcells in the same database, and rows left out: said, never hidden. */
  renderOthers() {
    const p = $("program-others");
    const parts = [];
    const count = (this.others || []).reduce((sum, o) => sum + o.count, 0);
    if (count) {
      const whose = this.others.map((o) => `${o.count} of ${o.arm || "an arm with other joints"}${o.workcell ? ` (${o.workcell})` : ""}`);
      parts.push(`${count} program${count === 1 ? "" : "s"} of other arms not shown: ${whose.join(", ")}`);
    }
    if ((this.skipped || []).length) parts.push(`${this.skipped.length} damaged left out (see the log)`);
    p.textContent = parts.join("; ");
    p.hidden = !parts.length;
    this.loggedSkips = this.loggedSkips || new Set();
    for (const line of this.skipped || []) {
      if (!this.loggedSkips.has(line)) this.log.add("warn", line);
      this.loggedSkips.add(line);
    }
  }

  renderList() {
    const ul = $("program-list");
    if (!this.programs.length) {
      const li = document.createElement("li");
      const small = document.createElement("small");
      small.textContent = this.listError ? `programs could not be read: ${this.listError}` : "no programs yet for this arm";
      if (this.listError) small.classList.add("error");
      li.append(small);
      ul.replaceChildren(li);
      return;
    }
    ul.replaceChildren(...this.programs.map((p) => {
      const li = document.createElement("li");
      li.dataset.programId = String(p.id);
      li.classList.toggle("selected", p.id === this.selectedId);
      const name = document.createElement("span");
      name.textContent = p.name;
      name.addEventListener("click", () => this.select(p.id));
      const small = document.createElement("small");
      small.textContent = `${p.waypoints.length} wp`;
      li.append(name, small, smallButton("Edit", "show and edit the waypoints", () => this.select(p.id)),
        smallButton("Repeat", "repeat with the cycles and speed above", () => this.onRepeat(p), "repeat"));
      return li;
    }));
  }

  select(id) {
    this.selectedId = id;
    this.renderList();
    this.renderEditor();
    this.afterChange();
  }

  renderEditor() {
    const p = this.selected;
    $("program-editor").hidden = !p;
    this.showPath(p);
    if (!p) return;
    $("program-name").value = p.name;
    $("program-export-csv").href = `/api/programs/${p.id}/export?format=csv`;
    $("program-export-json").href = `/api/programs/${p.id}/export?format=json`;
    $("program-export-bag").href = `/api/programs/${p.id}/export?format=rosbag2`;
    this.stepTree.render(p);
    // a program with steps: the table is its expanded sequence, read-only (edit the steps above)
    this.renderTable($("program-table"), p.waypoints, p.steps ? null : p);
    $("program-expanded-note").hidden = !p.steps;
  }

  /** Hand the program's gripper points (the server's gripper_position_m of each waypoint) to the live view. */
  showPath(p) {
    this.onProgram(p ? p.waypoints : null);
    const points = p ? p.waypoints.map((w) => w.gripper_position_m) : [];
    this.onPath(points.length && points.every(Array.isArray) ? { points_m: points, gripper: p.waypoints.map((w) => w.gripper) } : null);
  }

  selectRow(row) {
    for (const other of row.parentElement.querySelectorAll("tr.selected")) other.classList.remove("selected");
    row.classList.add("selected");
    this.onWaypointSelected(Number(row.dataset.index));
  }

  /** Choose waypoint `index` (0-based) of the program shown (a click on its arm in the 3-D view): its row stands out,
   * scrolled into view. */
  selectWaypoint(index) {
    const row = $("program-table").querySelector(`tbody tr[data-index='${index}']`);
    if (!row) return;
    this.selectRow(row);
    row.scrollIntoView({ block: "nearest" });
  }

  /** A waypoint table; with `program` its cells are editable and rows carry actions. */
  renderTable(table, waypoints, program) {
    const names = this.jointNames.length ? this.jointNames : (waypoints[0]?.joints_rad || []).map((_, i) => `q${i + 1}`);
    table.replaceChildren();
    const head = table.createTHead().insertRow();
    ["#", ...names.map((n) => `${n}°`), "gripper", "dwell s", "time s", ""].forEach((h) => { head.insertCell().textContent = h; });
    const body = table.createTBody();
    body.addEventListener("click", (e) => { // a row chosen: it stands out here and in the 3-D view
      const row = e.target.closest("tr[data-index]");
      if (row) this.selectRow(row);
    });
    waypoints.forEach((w, i) => {
      const tr = body.insertRow();
      tr.dataset.index = String(i);
      cell(tr, String(i + 1));
      w.joints_rad.forEach((q, j) => cell(tr, program ? this.input((q * DEG).toFixed(1), (v) => this.edit(i, (x) => { x.joints_rad[j] = v / DEG; }), `q${j}`) : (q * DEG).toFixed(1)));
      if (program) {
        const select = document.createElement("select");
        select.dataset.field = "gripper";
        ["release", "grasp"].forEach((g) => select.add(new Option(g, g, false, g === w.gripper)));
        select.addEventListener("change", () => this.edit(i, (x) => { x.gripper = select.value; }));
        cell(tr, select);
      } else {
        cell(tr, w.gripper);
      }
      cell(tr, program ? this.input(String(w.dwell_s ?? 0), (v) => this.edit(i, (x) => { x.dwell_s = v; }), "dwell") : String(w.dwell_s ?? 0));
      const t = w.moving_time_s ?? "";
      cell(tr, program ? this.input(String(t), (v) => this.edit(i, (x) => { x.moving_time_s = v > 0 ? v : null; }), "time", true) : String(t || "auto"));
      if (program) {
        const actions = document.createElement("span");
        actions.className = "wp-actions";
        actions.append(
          smallButton("↑", "move up", () => this.move(i, -1)),
          smallButton("↓", "move down", () => this.move(i, 1)),
          smallButton("set", "set to the current pose", () => this.setToCurrent(i)),
          smallButton("go", "go to this waypoint", () => this.goTo(w), "move_joints"),
          smallButton("✕", "delete this waypoint", () => this.deleteRow(i)),
        );
        cell(tr, actions);
      } else {
        cell(tr, "");
      }
    });
  }

  input(value, onCommit, field, allowEmpty = false) {
    const input = document.createElement("input");
    Object.assign(input, { type: "text", value, className: "num wp-input" });
    input.inputMode = "decimal";
    input.dataset.field = field;
    input.addEventListener("change", () => {
      const text = input.value.trim();
      const v = text === "" && allowEmpty ? 0 : Number(text);
      if (text === "" && !allowEmpty) return this.refusal(input, "a number is needed");
      if (!/^[-+]?(\d+\.?\d*|\.\d+)$/.test(text) && !(allowEmpty && text === "")) return this.refusal(input, `'${text}' is not a number`);
      onCommit(v);
      return null;
    });
    return input;
  }

  refusal(input, message) {
    this.log.toast("error", "edit waypoint", message);
    this.renderEditor();
    return null;
  }

  /** PATCH the selected program with waypoint i changed by `change` (a copy); the table shows what the server stored. */
  async edit(i, change) {
    const p = this.selected;
    const waypoints = p.waypoints.map((w) => ({ ...w, joints_rad: [...w.joints_rad] }));
    change(waypoints[i]);
    await this.patch(p, { waypoints: waypoints.map(toRequest) }, `edit waypoint ${i + 1}`);
  }

  async patch(p, body, action) {
    const updated = await this.run(`${action} of '${p.name}'`, () => this.api.updateProgram(p.id, body));
    const index = this.programs.findIndex((x) => x.id === p.id);
    if (updated && index >= 0) this.programs[index] = updated;
    this.renderList();
    this.renderEditor();
    this.afterChange();
    return updated;
  }

  move(i, delta) {
    const p = this.selected;
    const j = i + delta;
    if (j < 0 || j >= p.waypoints.length) return;
    const w = p.waypoints.map(toRequest);
    [w[i], w[j]] = [w[j], w[i]];
    this.patch(p, { waypoints: w }, `move waypoint ${i + 1}`);
  }

  deleteRow(i) {
    const p = this.selected;
    if (p.waypoints.length <= 1) {
      this.log.toast("error", "edit", "a program keeps at least one waypoint: delete the program instead");
      return;
    }
    this.patch(p, { waypoints: p.waypoints.filter((_, k) => k !== i).map(toRequest) }, `delete waypoint ${i + 1}`);
  }

  setToCurrent(i) {
    const q = this.status()?.joints_rad;
    if (!Array.isArray(q)) return;
    this.edit(i, (x) => { x.joints_rad = [...q]; });
  }

  goTo(w) {
    const time = Number($("jog-time").value);
    this.run("go to waypoint", () => this.api.joints(w.joints_rad, Number.isFinite(time) && time > 0 ? time : undefined));
  }

  /** A gripper step after the last waypoint: the same pose with the gripper toggled. */
  insertGripperStep() {
    const p = this.selected;
    if (p.steps) return this.stepTree.addAfter({ kind: "gripper", action: p.waypoints.at(-1).gripper === "grasp" ? "open" : "close" }, "add a gripper step");
    const last = p.waypoints[p.waypoints.length - 1];
    const step = { ...last, joints_rad: [...last.joints_rad], gripper: last.gripper === "grasp" ? "release" : "grasp", dwell_s: 0 };
    this.patch(p, { waypoints: [...p.waypoints, step].map(toRequest) }, "insert a gripper step");
  }

  rename() {
    const name = $("program-name").value.trim();
    if (name) this.patch(this.selected, { name }, "rename");
  }

  async duplicate() {
    const copy = await this.run(`duplicate '${this.selected.name}'`, () => this.api.duplicateProgram(this.selected.id));
    if (copy) {
      this.selectedId = copy.id;
      await this.refresh();
    }
  }

  async remove() {
    const p = this.selected;
    if (await this.run(`delete '${p.name}'`, () => this.api.deleteProgram(p.id))) {
      this.selectedId = null;
      await this.refresh();
    }
  }
}
