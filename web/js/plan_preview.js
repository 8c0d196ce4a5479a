// Plan, then execute (issue 22): a typed target planned without moving (?plan_only=true: the station's own checks
// and timing), shown as a see-through goal arm and the gripper's path in the 3-D panel. Execute sends exactly that
// plan (POST /api/plans/{id}/execute); Discard drops it (DELETE). A refused plan, or one gone stale because the arm
// or the scene changed under it, shows the station's reason in place, and nothing moves; a plan refused as unsafe
// draws the arm where it would fail with the offending link or finger in red.

const $ = (id) => document.getElementById(id);

export class PlanPreview {
  /** api: Api; run(action, call): the page's REST runner; show(state, text): the target panel's result line;
   * openView3d(): the 3-D panel, opened if it was not (resolves to the View3D or null); view3d(): the loaded
   * View3D or null (never loads it). */
  constructor({ api, run, show, openView3d, view3d }) {
    this.api = api;
    this.run = run;
    this.show = show;
    this.openView3d = openView3d;
    this.view3d = view3d;
    this.plan = null; // the plan on show: {plan_id, goal_q_rad, gripper_path_m, duration_s, ...}
    $("btn-plan-execute").addEventListener("click", () => this.execute());
    $("btn-plan-discard").addEventListener("click", () => this.discard());
  }

  /** Plan `body` on `path` (a move route) without moving; the plan is drawn and waits for Execute. */
  async make(action, path, body) {
    await this.discard(true);
    this.view3d()?.clearPlan(); // a refusal drawn before
    let plan;
    try {
      plan = await this.api.request("POST", `${path}?plan_only=true`, body);
    } catch (e) {
      const drawn = e.part && e.atQRad ? " (in red in the 3-D view)" : "";
      this.show("refused", `${action}: no plan: ${e.message}${drawn}`);
      if (drawn) {
        const view = await this.openView3d();
        if (view && !this.plan) view.showRefusal({ part: e.part, atQRad: e.atQRad });
      }
      return null;
    }
    this.plan = plan;
    this.show("planned", `${action}: planned, ${plan.duration_s.toFixed(1)} s; nothing moves until Execute`);
    $("plan-text").textContent = `plan ${plan.plan_id.slice(-6)}`;
    $("plan-box").hidden = false;
    const view = await this.openView3d();
    if (view && this.plan === plan) view.showPlan(plan);
    return plan;
  }

  clear() {
    this.plan = null;
    $("plan-box").hidden = true;
    this.view3d()?.clearPlan();
  }

  /** Send the plan on show, exactly as planned; a refusal (stale, another controller) says why. */
  async execute() {
    const plan = this.plan;
    if (!plan) return null;
    this.clear();
    let failure = null;
    const result = await this.run("execute the plan", () =>
      this.api.request("POST", `/api/plans/${encodeURIComponent(plan.plan_id)}/execute`).catch((e) => { failure = e; throw e; }));
    if (result) this.show("sent", `executing the plan (${plan.duration_s.toFixed(1)} s)`);
    else this.show("refused", `the plan was refused: ${failure ? failure.message : "no answer"}`);
    return result;
  }

  /** Drop the plan on show (quiet: when a new plan replaces it). */
  async discard(quiet = false) {
    const plan = this.plan;
    if (!plan) return;
    this.clear();
    try {
      await this.api.request("DELETE", `/api/plans/${encodeURIComponent(plan.plan_id)}`);
    } catch {
      // a plan the station no longer has is gone either way
    }
    if (!quiet) this.show("sent", "plan discarded");
  }
}
