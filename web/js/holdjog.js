// Hold-to-run joint jog: the arm moves only while a button (mouse, pen or finger) or a key is held. The jog
// starts with POST /api/arm/jog (one joint at the chosen speed) and is kept going by websocket heartbeats every
// HEARTBEAT_MS; the station brakes jog_hold_s after the last one (its deadman), so a hung page or a dropped
// connection stops the arm by itself. Released, left, cancelled, the page blurred or hidden, the stream closed,
// an e-stop: the page stops sending heartbeats and asks the station to ramp down at once (a zero jog).
// Keys: hold 1–6 for joint +, Shift+1–6 for joint −; a focused hold button also runs while Space/Enter is held.
// Key auto-repeat is ignored (one jog per press, held until the key is released). A jog that ran out while still
// held (the page or the station too busy to beat in time: the deadman tripped; telemetry says at rest) is sent
// again.

const HEARTBEAT_MS = 50; // 4 heartbeats per 0.2 s hold: one lost or late heartbeat does not stop a held jog
const FALLBACK_TOP_RAD_S = 0.5; // a station that does not serve jog_max_speed_rad_s
const FALLBACK_HOLD_S = 0.2;
const RESEND_AFTER_MS = 150; // at rest this long past the hold after the last send, while held: sent again

/** The jog a key asks for: {joint, sign} (joint index from 0) or null; digits 1–9 by their physical key. */
export function keyToHold(event, jointCount) {
  if (event.ctrlKey || event.metaKey || event.altKey) return null;
  const match = /^Digit([1-9])$/.exec(event.code || "");
  if (!match) return null;
  const joint = Number(match[1]) - 1;
  return joint < jointCount ? { joint, sign: event.shiftKey ? -1 : 1 } : null;
}

/** The velocity vector of a hold: `sign` × top speed on `joint`, zeros elsewhere (rad/s, joint_names order). */
export function holdVelocity(jointCount, joint, sign, topRadS) {
  const velocity = new Array(jointCount).fill(0);
  velocity[joint] = sign * topRadS[joint];
  return velocity;
}

export class HoldJog {
  /** api: Api; stream: Stream (heartbeats); log: EventLog; canJog(): the station allows a jog for this page now;
   * typing(target): a key press belongs to a form field. */
  constructor({ api, stream, log, canJog, typing, root, speed }) {
    this.api = api;
    this.stream = stream;
    this.log = log;
    this.canJog = canJog;
    this.typing = typing;
    this.root = root;
    this.speed = speed;
    this.names = [];
    this.topRadS = [];
    this.maxRadS = null;
    this.holdS = FALLBACK_HOLD_S;
    this.resent = 0; // jogs sent again after one ran out while held (for the tests)
    this.inFlight = 0; // jog requests sent and not answered yet
    this.active = null; // {joint, sign, how, button, key}
    this.timer = null;
    this.queue = Promise.resolve(); // jog requests one after another: a stop is never overtaken by its start
    document.addEventListener("keydown", (e) => this.onKeyDown(e));
    document.addEventListener("keyup", (e) => this.onKeyUp(e));
    window.addEventListener("blur", () => this.stop("the page lost focus"));
    window.addEventListener("pagehide", () => this.stop("the page closed"));
    document.addEventListener("visibilitychange", () => {
      if (document.visibilityState !== "visible") this.stop("the page was hidden");
    });
  }

  /** The station's jog limits (hello.limits): the top speed at 100 %. */
  setLimits(limits) {
    if (limits && Number.isFinite(limits.jog_max_speed_rad_s)) this.maxRadS = limits.jog_max_speed_rad_s;
    if (limits && Number.isFinite(limits.jog_hold_s)) this.holdS = limits.jog_hold_s;
    this.topRadS = this.topSpeeds(this.velocityLimits || []);
  }

  topSpeeds(velocityLimits) {
    const cap = this.maxRadS ?? FALLBACK_TOP_RAD_S;
    return this.names.map((_, i) => Math.min(cap, Number.isFinite(velocityLimits[i]) ? velocityLimits[i] : cap));
  }

  /** One row per joint of the arm the server runs: its name and a − and + hold button. */
  build(names, velocityLimits) {
    this.stop("the arm changed");
    this.names = names || [];
    this.velocityLimits = velocityLimits || [];
    this.topRadS = this.topSpeeds(this.velocityLimits);
    this.root.replaceChildren();
    this.names.forEach((name, joint) => {
      const label = document.createElement("span");
      label.textContent = `${joint + 1} ${name}`;
      this.root.append(label, this.button(name, joint, -1), this.button(name, joint, 1));
    });
  }

  button(name, joint, sign) {
    const b = document.createElement("button");
    Object.assign(b, { type: "button", className: "btn hold", textContent: sign > 0 ? "+" : "−" });
    b.dataset.command = "jog";
    b.dataset.hold = `${joint}${sign > 0 ? "+" : "-"}`;
    b.title = `hold to move ${name} ${sign > 0 ? "+" : "−"} (key ${sign > 0 ? "" : "Shift+"}${joint + 1})`;
    b.setAttribute("aria-label", `hold: ${name} ${sign > 0 ? "plus" : "minus"}`);
    b.addEventListener("pointerdown", (e) => {
      if (e.button !== 0 || b.disabled) return;
      e.preventDefault(); // no text selection, no focus-scroll; touch-action: none keeps the finger from scrolling
      this.start(joint, sign, { how: e.pointerType || "pointer", button: b, pointerId: e.pointerId });
    });
    const release = (e) => {
      if (this.active && this.active.button === b && (e.pointerId === undefined || e.pointerId === this.active.pointerId)) {
        this.stop(e.type === "pointerup" ? "released" : `pointer ${e.type.replace("pointer", "")}`);
      }
    };
    for (const type of ["pointerup", "pointercancel", "pointerleave"]) b.addEventListener(type, release);
    b.addEventListener("contextmenu", (e) => e.preventDefault()); // a long touch would open the menu and cancel the hold
    b.addEventListener("keydown", (e) => {
      if ((e.key === " " || e.key === "Enter") && !e.repeat && !b.disabled) {
        e.preventDefault();
        this.start(joint, sign, { how: "key", button: b, key: e.code });
      } else if (e.key === " " || e.key === "Enter") {
        e.preventDefault(); // auto-repeat: the held jog goes on, nothing new is sent
      }
    });
    b.addEventListener("click", (e) => e.preventDefault());
    return b;
  }

  onKeyDown(event) {
    if (this.typing(event.target) || document.querySelector("dialog[open]")) return;
    const hold = keyToHold(event, this.names.length);
    if (!hold) return;
    event.preventDefault();
    if (event.repeat || this.active) return; // auto-repeat is not a new jog
    const button = this.root.querySelector(`[data-hold="${hold.joint}${hold.sign > 0 ? "+" : "-"}"]`);
    if (button && button.disabled) return;
    this.start(hold.joint, hold.sign, { how: "key", button, key: event.code });
  }

  onKeyUp(event) {
    if (this.active && this.active.key && (event.code === this.active.key || event.key === "Shift")) this.stop("key released");
  }

  get speedPercent() {
    const value = Number(this.speed.value);
    return Number.isFinite(value) ? Math.min(100, Math.max(10, value)) : 100;
  }

  /** Start holding `joint` in direction `sign`; nothing when a hold is already on or the station does not allow it. */
  start(joint, sign, { how, button, key, pointerId }) {
    if (this.active || !this.canJog() || !this.stream.isOpen) return;
    const active = { joint, sign, how, button, key, pointerId, sent: false };
    active.velocity = holdVelocity(this.names.length, joint, sign, this.topRadS);
    active.speedPercent = this.speedPercent;
    active.label = `hold ${this.names[joint] || `joint ${joint + 1}`} ${sign > 0 ? "+" : "−"}`;
    this.active = active;
    if (button) button.classList.add("held");
    this.root.dataset.holding = `${joint}${sign > 0 ? "+" : "-"}`;
    this.enqueue(async () => {
      if (this.active !== active) return; // released before it was sent: nothing to stop either
      active.sent = true;
      if (!(await this.sendJog(active))) return;
      active.started = true;
      this.timer = setInterval(() => this.beat(), HEARTBEAT_MS);
    });
  }

  /** POST the held jog; false (and the hold ended) when the station refuses it. */
  async sendJog(active) {
    active.sentMs = performance.now();
    this.inFlight += 1;
    try {
      await this.api.jog(active.velocity, active.speedPercent);
    } catch (e) {
      this.log.error(active.label, e);
      if (this.active === active) this.finish();
      return false;
    } finally {
      this.inFlight -= 1;
    }
    return this.active === active; // released while it was on its way: the queued stop follows
  }

  beat() {
    if (this.active && !this.stream.send({ type: "heartbeat" })) this.stop("connection lost");
  }

  /** Telemetry: a held jog the station reports at rest well after it was sent ran out (its heartbeats reached a
   * busy station too late): sent again while the button is still held. */
  onStatus(status) {
    const active = this.active;
    if (!active || !active.started || status.moving || performance.now() - active.sentMs < this.holdS * 1000 + RESEND_AFTER_MS) return;
    this.resend(active);
  }

  resend(active) {
    this.resent += 1;
    active.sentMs = performance.now();
    this.enqueue(() => (this.active === active ? this.sendJog(active) : null));
  }

  /** Stop holding: no more heartbeats, and a zero jog so the arm ramps down now (it would after jog_hold_s anyway). */
  stop(reason) {
    const active = this.active;
    if (!active) return;
    this.finish();
    this.lastStop = reason;
    if (!active.sent) return;
    // At once when no jog is on its way; else right after it (sent at once, a busy station could apply it before
    // the jog still on its way, which would then move the arm again).
    const zeroJog = () => this.api.jog(new Array(this.names.length).fill(0), 100).catch(() => null);
    if (this.inFlight === 0) zeroJog();
    else this.enqueue(zeroJog);
  }

  finish() {
    clearInterval(this.timer);
    this.timer = null;
    if (this.active && this.active.button) this.active.button.classList.remove("held");
    this.active = null;
    delete this.root.dataset.holding;
  }

  enqueue(task) {
    this.queue = this.queue.then(task, task);
    return this.queue;
  }
}
