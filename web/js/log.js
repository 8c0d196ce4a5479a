// The event log panel and error toasts. Server events and the page's own actions both land here.

const MAX_LOG_ENTRIES = 300;
const TOAST_TIME_MS = 6000;

function clock(timeS) {
  const d = timeS ? new Date(timeS * 1000) : new Date();
  return d.toTimeString().slice(0, 8);
}

export class EventLog {
  constructor(list, toastBox) {
    this.list = list;
    this.toastBox = toastBox;
  }

  /** Append one line: level info|warn|error, message, optional server time in seconds. */
  add(level, message, timeS) {
    const li = document.createElement("li");
    li.dataset.level = level;
    const t = document.createElement("time");
    t.textContent = clock(timeS);
    const span = document.createElement("span");
    span.textContent = message;
    li.append(t, span);
    const atBottom = this.list.scrollTop + this.list.clientHeight >= this.list.scrollHeight - 4;
    this.list.append(li);
    while (this.list.children.length > MAX_LOG_ENTRIES) this.list.firstChild.remove();
    if (atBottom) this.list.scrollTop = this.list.scrollHeight;
  }

  clear() {
    this.list.replaceChildren();
  }

  /** Show a toast (it goes on click or after 6 s) and, unless logged already, log it. */
  toast(level, title, message, alsoLog = true) {
    const div = document.createElement("div");
    div.className = "toast";
    div.dataset.level = level;
    div.setAttribute("role", level === "error" ? "alert" : "status");
    const b = document.createElement("b");
    b.textContent = title;
    const p = document.createElement("span");
    p.textContent = message;
    div.append(b, p);
    div.addEventListener("click", () => div.remove());
    this.toastBox.append(div);
    setTimeout(() => div.remove(), TOAST_TIME_MS);
    if (alsoLog) this.add(level, `${title}: ${message}`);
  }

  /** Toast an ApiError (or any Error) with the server's own message. */
  error(action, err) {
    let msg = err && err.message ? err.message : String(err);
    if (err && err.allowed && err.allowed.length) msg += ` (allowed now: ${err.allowed.join(", ")})`;
    this.toast("error", `${action} failed`, msg);
  }
}
