// The History panel: the station's event log as kept in its database (GET /api/history/events: text, level and time
// range; newest first), exportable as CSV or JSON, and past job runs (GET /api/history/jobs) with their scores and
// breakdowns. It asks the server, so it survives a page reload and a server restart. Absurd ranges come back as the
// server's 422 message, shown in the panel.

const $ = (id) => document.getElementById(id);
const SHOWN = 200;

/** Seconds since 1970 of a datetime-local value (the page's local time), null when empty, NaN when unreadable. */
export function localInputToS(value) {
  if (!value) return null;
  const ms = new Date(value).getTime();
  return Number.isFinite(ms) ? ms / 1000 : NaN;
}

/** "YYYY-MM-DD hh:mm:ss" in local time. */
export function fmtTime(timeS) {
  const d = new Date(timeS * 1000);
  const p = (n) => String(n).padStart(2, "0");
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
}

function cell(text) {
  return Object.assign(document.createElement("td"), { textContent: text });
}

export class HistoryPanel {
  constructor({ api, log }) {
    this.api = api;
    this.log = log;
    this.searches = 0;
    $("btn-history-search").addEventListener("click", () => this.search());
    $("history-text").addEventListener("keydown", (e) => { if (e.key === "Enter") this.search(); });
    $("history-level").addEventListener("change", () => this.search());
    $("history-panel").addEventListener("toggle", () => { if ($("history-panel").open) this.search(); });
  }

  /** The query string of the panel's fields (format added by the caller), or throws with what is wrong. */
  query(extra = {}) {
    const params = new URLSearchParams();
    const text = $("history-text").value.trim();
    if (text) params.set("text", text);
    const level = $("history-level").value;
    if (level) params.set("level", level);
    for (const [id, name] of [["history-from", "from_s"], ["history-to", "to_s"]]) {
      const value = localInputToS($(id).value);
      if (value === null) continue;
      params.set(name, String(value)); // NaN goes to the server, which says what is wrong
    }
    for (const [key, value] of Object.entries(extra)) params.set(key, value);
    return params;
  }

  async search() {
    const events = this.query({ limit: String(SHOWN) });
    const jobs = this.query({ limit: "50" });
    jobs.delete("level");
    this.exportLinks();
    const error = $("history-error");
    try {
      const [found, runs] = await Promise.all([
        this.api.get(`/api/history/events?${events}`),
        this.api.get(`/api/history/jobs?${jobs}`),
      ]);
      error.hidden = true;
      this.renderEvents(found.data);
      this.renderJobs(runs.data);
    } catch (e) {
      error.hidden = false;
      error.textContent = e.message;
      $("history-events").replaceChildren();
      $("history-jobs").replaceChildren();
      $("history-count").textContent = "";
    }
    this.searches += 1;
    $("history-panel").dataset.searches = String(this.searches);
  }

  exportLinks() {
    const all = this.query({ limit: "5000" });
    all.set("format", "csv");
    $("history-export-csv").href = `/api/history/events?${all}`;
    all.set("format", "json");
    all.set("download", "true");
    $("history-export-json").href = `/api/history/events?${all}`;
  }

  renderEvents(rows) {
    $("history-count").textContent = `${rows.length}${rows.length >= SHOWN ? "+" : ""} events`;
    $("history-events").replaceChildren(...rows.map((e) => {
      const row = document.createElement("tr");
      row.dataset.level = e.level;
      row.append(cell(fmtTime(e.time_s)), cell(e.level), cell(e.message));
      return row;
    }));
  }

  renderJobs(rows) {
    $("history-jobs").replaceChildren(...rows.map((job) => {
      const row = document.createElement("tr");
      row.dataset.state = job.state;
      const took = Number.isFinite(job.finished_s) ? `${(job.finished_s - job.started_s).toFixed(1)} s` : "—";
      const score = job.score && Number.isFinite(job.score.points) ? `${job.score.points} / ${job.score.max_points}` : "—";
      const detail = cell("");
      const breakdown = (job.score && Array.isArray(job.score.breakdown)) ? job.score.breakdown : [];
      if (breakdown.length) {
        const more = document.createElement("details");
        more.append(Object.assign(document.createElement("summary"), { textContent: "breakdown" }));
        const list = document.createElement("ul");
        list.className = "history-breakdown";
        list.append(...breakdown.map((rule) => Object.assign(document.createElement("li"), {
          textContent: `${rule.rule}: ${rule.points}${rule.detail ? ` (${rule.detail})` : ""}`,
        })));
        more.append(list);
        detail.append(more);
      } else {
        detail.textContent = job.message || "";
      }
      row.append(cell(fmtTime(job.started_s)), cell(job.name), cell(job.state), cell(took), cell(score), detail);
      return row;
    }));
  }
}
