// A station with no arm (`armlab serve --arm none`, perception only): the panels that need the arm
// ([data-arm-panel]) say why they are off, and their arm commands (ARM_COMMANDS) are blocked with that
// reason as the button's tooltip. The server refuses the same commands (409 no_arm); this only says so first.

import { ARM_COMMANDS } from "./wire_types.js";

const BLOCKED = new Set(ARM_COMMANDS);

/** Mark the page for `arm` (the hello's arm): no arm → a note in every arm panel and its buttons blocked. */
export function applyNoArm(root, arm) {
  const noArm = arm && arm.has_arm === false;
  const reason = noArm ? arm.reason || "this station has no arm" : "";
  root.body.dataset.noArm = String(Boolean(noArm));
  root.querySelectorAll("[data-arm-panel]").forEach((panel) => {
    let note = panel.querySelector(":scope > .no-arm-note");
    if (noArm && !note) {
      note = root.createElement("p");
      note.className = "no-arm-note";
      note.setAttribute("role", "note");
      panel.querySelector("h2")?.after(note);
    }
    if (note) {
      note.hidden = !noArm;
      note.textContent = noArm ? `${reason[0].toUpperCase()}${reason.slice(1)}.` : "";
    }
    panel.classList.toggle("no-arm", Boolean(noArm));
  });
  root.querySelectorAll("[data-command]").forEach((el) => {
    if (!BLOCKED.has(el.dataset.command)) return;
    if (noArm) {
      el.dataset.blocked = reason;
      el.title = `Refused: ${reason}`;
    } else if (el.dataset.blocked === el.dataset.noArmReason) {
      delete el.dataset.blocked;
    }
    if (noArm) el.dataset.noArmReason = reason;
  });
}
