// The torque button: it shows the motors' state (the station's torque_enabled), not the action, and
// asks before torque off while the arm is raised (it falls under gravity unless held).

import { askConfirm } from "./confirm.js";
import { fmtMm } from "./geometry.js";

/** Gripper height (m) above which the arm counts as raised: it would fall if limp. */
const RAISED_Z_M = 0.03;

export class TorqueButton {
  /** button: the <button>; run(action, call): the page's REST runner; api: Api. */
  constructor({ button, run, api }) {
    this.button = button;
    this.run = run;
    this.api = api;
    this.status = null;
    button.addEventListener("click", () => this.toggle());
  }

  /** Show the torque state from a status/telemetry message. */
  render(status) {
    this.status = status;
    const on = status.torque_enabled !== false;
    this.button.dataset.torque = on ? "on" : "off";
    this.button.textContent = on ? "Torque: on" : "Torque: OFF";
    this.button.title = on ? "Motors hold the arm. Click to switch torque off (limp)." : "Arm is limp. Click to switch torque on (hold).";
    this.button.setAttribute("aria-pressed", String(on));
  }

  async toggle() {
    const on = !this.status || this.status.torque_enabled !== false;
    if (!on) {
      await this.run("torque on", () => this.api.torque(true));
      return;
    }
    const zM = this.status?.gripper_pose?.position_m?.[2];
    const raised = !Number.isFinite(zM) || zM > RAISED_Z_M;
    const inTeach = this.status?.state === "teach";
    if (raised || !inTeach) {
      const where = Number.isFinite(zM) ? `the gripper is ${fmtMm(zM)} mm above the board` : "its height is unknown";
      const yes = await askConfirm({
        title: "Torque off?",
        text: `The arm goes limp and falls under gravity unless you hold it (${where}). Hold the arm, then confirm.`,
        ok: "Torque off",
      });
      if (!yes) return;
    }
    await this.run("torque off", () => this.api.torque(false, true));
  }
}
