// The Board tags panel: each board tag of the current calibration (GET /api/calibration/tags): id, where it is on the
// board (world, mm), its reprojection error at calibration and its drift in the newest frame (px), whether it is seen.
// Refreshed when the panel opens and whenever a calibration arrives.

const $ = (id) => document.getElementById(id);

const fmt = (value, digits) => (Number.isFinite(value) ? value.toFixed(digits) : "—");

export class TagListPanel {
  constructor({ api }) {
    this.api = api;
    $("tags-panel").addEventListener("toggle", () => { if ($("tags-panel").open) this.refresh(); });
  }

  async refresh() {
    let tags;
    try {
      tags = await this.api.get("/api/calibration/tags");
    } catch (e) {
      $("tags-summary").textContent = e.message;
      return;
    }
    this.render(tags);
  }

  /** A calibration arrived (websocket or REST): the errors changed. */
  onCalibration() {
    if ($("tags-panel").open) this.refresh();
  }

  render(tags) {
    const rms = tags.reprojection_error_px;
    $("tags-summary").textContent = tags.calibrated ? `${tags.count} tags · RMS ${fmt(rms, 2)} px` : `${tags.count} tags · not calibrated`;
    $("tags-body").replaceChildren(...tags.data.map((tag) => {
      const row = document.createElement("tr");
      row.dataset.tagId = String(tag.id);
      const cells = [String(tag.id), fmt(tag.position_m[0] * 1000, 1), fmt(tag.position_m[1] * 1000, 1),
        fmt(tag.reprojection_error_px, 2), fmt(tag.drift_px, 2), tag.seen_now ? "yes" : "no"];
      row.append(...cells.map((text) => Object.assign(document.createElement("td"), { textContent: text })));
      return row;
    }));
    $("tags-panel").dataset.rows = String(tags.data.length);
  }
}
