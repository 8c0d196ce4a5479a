// The simulation's scene picker (the sim panel): shows the scene loaded now and loads a chosen event, level and
// seed.

const $ = (id) => document.getElementById(id);

export class ScenePicker {
  /** api: Api; run(action, call): the page's REST runner. */
  constructor({ api, run }) {
    this.api = api;
    this.run = run;
  }

  /** The scene picker shows the scene loaded now (GET /api/sim/scene): event, level, seed. */
  async refresh() {
    let scene;
    try {
      scene = await this.api.get("/api/sim/scene");
    } catch {
      return;
    }
    const known = scene.event && [...$("sim-event").options].some((o) => o.value === scene.event);
    if (known) {
      $("sim-event").value = scene.event;
      $("sim-level").value = String(scene.level);
      $("sim-seed").value = String(scene.seed);
    }
    $("sim-current").textContent = scene.event ? `now: ${scene.event} L${scene.level} seed ${scene.seed}` : `now: custom (${scene.objects} objects)`;
    $("sim-current").dataset.scene = scene.event ? `${scene.event}/${scene.level}/${scene.seed}` : "custom";
  }

  /** The Load button: the chosen event, level and seed. */
  bind() {
    $("btn-sim-scene").addEventListener("click", () => {
      const event = $("sim-event").value;
      const level = Number($("sim-level").value);
      const seed = Math.round(Number($("sim-seed").value) || 0);
      this.run(`scene ${event} L${level} seed ${seed}`, () => this.api.simScene(event, level, seed));
    });
  }
}
