// The Recording panel: the Record button starts and stops an MCAP recording of the station (POST
// /api/recordings/start|stop) and shows its duration and size while it runs (GET /api/recordings, polled once a
// second only while recording); the newest recordings are listed with their download links.

const POLL_MS = 1000;
const LISTED = 5;

/** "12.3 MB" / "850 kB" from bytes. */
export function fmtBytes(bytes) {
  if (!Number.isFinite(bytes)) return "—";
  if (bytes >= 1e9) return `${(bytes / 1e9).toFixed(2)} GB`;
  if (bytes >= 1e6) return `${(bytes / 1e6).toFixed(1)} MB`;
  return `${Math.round(bytes / 1e3)} kB`;
}

/** "m:ss" (or "h:mm:ss") from seconds. */
export function fmtDuration(seconds) {
  const total = Math.max(0, Math.floor(Number(seconds) || 0));
  const h = Math.floor(total / 3600), m = Math.floor((total % 3600) / 60), s = total % 60;
  const mm = h ? String(m).padStart(2, "0") : String(m);
  return `${h ? `${h}:` : ""}${mm}:${String(s).padStart(2, "0")}`;
}

export class RecordingPanel {
  /** api: Api; run(action, call): the page's REST runner (logs errors); root: the panel element. */
  constructor({ api, run, root = document }) {
    this.api = api;
    this.run = run;
    this.button = root.querySelector("#btn-record");
    this.statusEl = root.querySelector("#rec-status");
    this.listEl = root.querySelector("#rec-list");
    this.folderEl = root.querySelector("#rec-folder");
    this.active = null;
    this.timer = null;
    this.button.disabled = !api.canControl;
    if (!api.canControl) this.button.title = "needs the control token";
    this.button.addEventListener("click", () => this.toggle());
    this.refresh();
  }

  async toggle() {
    const recording = Boolean(this.active);
    const result = await this.run(recording ? "stop recording" : "record",
      () => this.api.post(recording ? "/api/recordings/stop" : "/api/recordings/start"));
    if (result?.recording) this.active = result.recording.state === "recording" ? result.recording : null;
    await this.refresh();
  }

  async refresh() {
    let listing;
    try {
      listing = await this.api.get("/api/recordings");
    } catch {
      return; // the station is away; the next click or poll tries again
    }
    this.render(listing);
  }

  /** Show a GET /api/recordings answer; poll while a recording runs. */
  render(listing) {
    this.active = listing.active || null;
    const on = Boolean(this.active);
    this.button.dataset.recording = String(on);
    this.button.textContent = on ? "■ Stop" : "● Record";
    this.statusEl.textContent = on
      ? `REC ${fmtDuration(this.active.duration_s)} · ${fmtBytes(this.active.size_bytes)}`
      : `${listing.count} recording(s), ${fmtBytes(listing.total_bytes)} of ${fmtBytes(listing.budget_bytes)}`;
    this.statusEl.dataset.recording = String(on);
    this.folderEl.textContent = listing.directory || "";
    this.listEl.replaceChildren(...listing.data.filter((item) => item.state !== "recording").slice(0, LISTED).map((item) => {
      const li = document.createElement("li");
      const link = document.createElement("a");
      link.href = `/api/recordings/${encodeURIComponent(item.id)}`;
      link.download = `${item.id}.mcap`;
      link.textContent = item.label || item.id;
      const note = item.truncated ? " (cut short)" : item.state === "damaged" ? " (damaged)" : "";
      li.append(link, ` ${fmtDuration(item.duration_s)} · ${fmtBytes(item.size_bytes)}${note}`);
      li.title = [`states: ${(item.states || []).join(", ") || "—"}`, `jobs: ${item.jobs.join(", ") || "—"}`,
        item.stop_reason ? `ended: ${item.stop_reason}` : ""].filter(Boolean).join("\n");
      return li;
    }));
    clearTimeout(this.timer);
    this.timer = on ? setTimeout(() => this.refresh(), POLL_MS) : null;
  }
}
