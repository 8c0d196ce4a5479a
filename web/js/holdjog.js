// Hold-to-run jog: the arm moves only while a button (mouse, pen or finger) or a key is held. A joint hold turns one
// joint; a Cartesian hold (x, y, z) moves the gripper point along that world axis keeping its pitch and yaw. Both go
// over the websocket: a `jog` or `jog_cartesian` message starts it (the station answers with a jog_reply: a refusal
// ends the hold and says why), heartbeats every HEARTBEAT_MS keep it going, and the station brakes jog_hold_s after
// the last one (its deadman), so a hung page or a dropped connection stops the arm by itself. Released, left,
// cancelled, the page blurred or hidden, the stream closed, an e-stop: the page stops beating and sends `jog_stop`, so
// the arm ramps down at once. Messages of one session are handled in order: a stop never overtakes its start.
// Keys: hold 1–6 for joint +, Shift+1–6 for joint −; X, Y, Z for the gripper along +x, +y, +z, Shift+X/Y/Z along −;
// a focused hold button also runs while Space/Enter is held. Key auto-repeat is ignored (one jog per press, held
// until the key is released). A jog that ran out while still held (the page or the station too busy to beat in
// time: the deadman tripped; telemetry says at rest) is sent again.

const HEARTBEAT_MS = 50; // 4 heartbeats per 0.2 s hold: one lost or late heartbeat does not stop a held jog
const FALLBACK_TOP_RAD_S = 0.5; // a station that does not serve jog_max_speed_rad_s
const FALLBACK_HOLD_S = 0.2;
const RESEND_AFTER_MS = 150; // at rest this long past the hold after the last send, while held: sent again
const REPLY_TIMEOUT_MS = 5000; // a jog the station has not answered by then is given up (the deadman stops it anyway)
const AXES = ["x", "y", "z"];

/** The hold a key asks for: {kind: "joint", joint, sign} (digits 1–9 by their physical key, joint from 0),
 * {kind: "cartesian", axis, sign} (X, Y, Z when `cartesian`), or null. */
export function keyToHold(event, jointCount, cartesian = false) {
  if (event.ctrlKey || event.metaKey || event.altKey) return null;
  const sign = event.shiftKey ? -1 : 1;
  const digit = /^Digit([1-9])$/.exec(event.code || "");
  if (digit) {
    const joint = Number(digit[1]) - 1;
    return joint < jointCount ? { kind: "joint", joint, sign } : null;
  }
  const letter = /^Key([XYZ])$/.exec(event.code || "");
  return letter && cartesian ? { kind: "cartesian", axis: letter[1].toLowerCase(), sign } : null;
}

/** The velocity vector of a hold: `sign` × top speed on `joint`, zeros elsewhere (rad/s, joint_names order). */
export function holdVelocity(jointCount, joint, sign, topRadS) {
  const velocity = new Array(jointCount).fill(0);
  velocity[joint] = sign * topRadS[joint];
  return velocity;
}

/** The data-hold name of a hold: "0+" (joint 1 +), "x-" (gripper along −x). */
export function holdName(hold) {
  return `${hold.kind === "cartesian" ? hold.axis : hold.joint}${hold.sign > 0 ? "+" : "-"}`;
}

export class HoldJog {
  /** api: Api; stream: Stream (jog messages, heartbeats); log: EventLog; canJog(): the station allows a jog for this
   * page now; typing(target): a key press belongs to a form field. */
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
    this.maxMS = null; // the Cartesian jog's top speed (hello.limits.jog_max_speed_m_s); null: no Cartesian holds
    this.holdS = FALLBACK_HOLD_S;
    this.resent = 0; // jogs sent again after one ran out while held (for the tests)
    this.sentJogs = 0; // jog messages sent (for the tests: key auto-repeat sends none)
    this.nextId = 1;
    this.replies = new Map(); // jog message id → {resolve, reject, timer}
    this.active = null; // {hold, how, button, key, pointerId, ...}
    this.timer = null;
    this.queue = Promise.resolve(); // starts one after another
    document.addEventListener("keydown", (e) => this.onKeyDown(e));
    document.addEventListener("keyup", (e) => this.onKeyUp(e));
    window.addEventListener("blur", () => this.stop("the page lost focus"));
    window.addEventListener("pagehide", () => this.stop("the page closed"));
    document.addEventListener("visibilitychange", () => {
      if (document.visibilityState !== "visible") this.stop("the page was hidden");
    });
  }

  /** The station's jog limits (hello.limits): the top speeds at 100 % and the hold. */
  setLimits(limits) {
    if (limits && Number.isFinite(limits.jog_max_speed_rad_s)) this.maxRadS = limits.jog_max_speed_rad_s;
    if (limits && Number.isFinite(limits.jog_hold_s)) this.holdS = limits.jog_hold_s;
    this.maxMS = limits && Number.isFinite(limits.jog_max_speed_m_s) ? limits.jog_max_speed_m_s : null;
    this.topRadS = this.topSpeeds(this.velocityLimits || []);
  }

  topSpeeds(velocityLimits) {
    const cap = this.maxRadS ?? FALLBACK_TOP_RAD_S;
    return this.names.map((_, i) => Math.min(cap, Number.isFinite(velocityLimits[i]) ? velocityLimits[i] : cap));
  }

  /** One row per joint of the arm the server runs (its name and a − and + hold button), then one per world axis
   * the gripper point moves along (when the station serves the Cartesian jog's top speed). */
  build(names, velocityLimits) {
    this.stop("the arm changed");
    this.names = names || [];
    this.velocityLimits = velocityLimits || [];
    this.topRadS = this.topSpeeds(this.velocityLimits);
    this.root.replaceChildren();
    this.names.forEach((name, joint) => {
      const label = document.createElement("span");
      label.textContent = `${joint + 1} ${name}`;
      const title = (sign) => `hold to move ${name} ${sign > 0 ? "+" : "−"} (key ${sign > 0 ? "" : "Shift+"}${joint + 1})`;
      this.root.append(label, ...[-1, 1].map((sign) => this.button({ kind: "joint", joint, sign }, name, title(sign))));
    });
    if (this.maxMS === null || !this.names.length) return;
    for (const axis of AXES) {
      const label = document.createElement("span");
      label.textContent = `gripper ${axis}`;
      const key = axis.toUpperCase();
      const title = (sign) => `hold to move the gripper along ${sign > 0 ? "+" : "−"}${axis}, keeping its pitch and yaw `
        + `(key ${sign > 0 ? "" : "Shift+"}${key})`;
      this.root.append(label, ...[-1, 1].map((sign) => this.button({ kind: "cartesian", axis, sign }, `gripper ${axis}`, title(sign))));
    }
  }

  button(hold, name, title) {
    const b = document.createElement("button");
    const sign = hold.sign > 0 ? "+" : "−";
    Object.assign(b, { type: "button", className: "btn hold", textContent: hold.kind === "cartesian" ? `${hold.axis}${sign}` : sign });
    b.dataset.command = "jog";
    b.dataset.hold = holdName(hold);
    b.title = title;
    b.setAttribute("aria-label", `hold: ${name} ${hold.sign > 0 ? "plus" : "minus"}`);
    b.addEventListener("pointerdown", (e) => {
      if (e.button !== 0 || b.disabled) return;
      e.preventDefault(); // no text selection, no focus-scroll; touch-action: none keeps the finger from scrolling
      this.start(hold, { how: e.pointerType || "pointer", button: b, pointerId: e.pointerId });
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
        this.start(hold, { how: "key", button: b, key: e.code });
      } else if (e.key === " " || e.key === "Enter") {
        e.preventDefault(); // auto-repeat: the held jog goes on, nothing new is sent
      }
    });
    b.addEventListener("click", (e) => e.preventDefault());
    return b;
  }

  onKeyDown(event) {
    if (this.typing(event.target) || document.querySelector("dialog[open]")) return;
    const hold = keyToHold(event, this.names.length, this.maxMS !== null);
    if (!hold) return;
    event.preventDefault();
    if (event.repeat || this.active) return; // auto-repeat is not a new jog
    const button = this.root.querySelector(`[data-hold="${holdName(hold)}"]`);
    if (button && button.disabled) return;
    this.start(hold, { how: "key", button, key: event.code });
  }

  onKeyUp(event) {
    if (this.active && this.active.key && (event.code === this.active.key || event.key === "Shift")) this.stop("key released");
  }

  get speedPercent() {
    const value = Number(this.speed.value);
    return Number.isFinite(value) ? Math.min(100, Math.max(10, value)) : 100;
  }

  /** The websocket message that starts `hold` at `speedPercent` (the station scales the top speed). */
  jogMessage(hold, speedPercent) {
    if (hold.kind === "cartesian") {
      return { type: "jog_cartesian", axis: hold.axis, velocity_m_s: hold.sign * this.maxMS, speed_percent: speedPercent };
    }
    return { type: "jog", velocity_rad_s: holdVelocity(this.names.length, hold.joint, hold.sign, this.topRadS), speed_percent: speedPercent };
  }

  /** Start holding; nothing when a hold is already on or the station does not allow it. */
  start(hold, { how, button, key, pointerId }) {
    if (this.active || !this.canJog() || !this.stream.isOpen) return;
    const active = { hold, how, button, key, pointerId, sent: false };
    active.message = this.jogMessage(hold, this.speedPercent);
    const what = hold.kind === "cartesian" ? `gripper ${hold.axis}` : this.names[hold.joint] || `joint ${hold.joint + 1}`;
    active.label = `hold ${what} ${hold.sign > 0 ? "+" : "−"}`;
    this.active = active;
    if (button) button.classList.add("held");
    this.root.dataset.holding = holdName(hold);
    this.enqueue(async () => {
      if (this.active !== active) return; // released before it was sent: nothing to stop either
      active.sent = true;
      if (!(await this.sendJog(active))) return;
      active.started = true;
      this.timer = setInterval(() => this.beat(), HEARTBEAT_MS);
    });
  }

  /** Send the held jog over the websocket and wait for its jog_reply; false (and the hold ended, with the station's
   * reason) when it is refused or not sent. */
  async sendJog(active) {
    active.sentMs = performance.now();
    try {
      await this.request(active.message);
    } catch (e) {
      this.log.error(active.label, e);
      if (this.active === active) this.finish();
      return false;
    }
    return this.active === active; // released while it was on its way: its stop followed it
  }

  /** Send a jog message with a fresh id; resolves on an ok jog_reply, rejects (an Error with the status and code)
   * on a refusal, a closed connection or no answer in REPLY_TIMEOUT_MS. */
  request(message) {
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      if (!this.stream.send({ ...message, id })) {
        reject(new Error("the connection to the station is closed"));
        return;
      }
      if (message.type !== "jog_stop") this.sentJogs += 1;
      const timer = setTimeout(() => {
        this.replies.delete(id);
        reject(new Error("the station did not answer"));
      }, REPLY_TIMEOUT_MS);
      this.replies.set(id, { resolve, reject, timer });
    });
  }

  /** A jog_reply from the station (main.js routes it here). */
  onReply(reply) {
    const waiting = this.replies.get(reply.id);
    if (!waiting) return;
    this.replies.delete(reply.id);
    clearTimeout(waiting.timer);
    if (reply.ok) {
      waiting.resolve(reply);
    } else {
      const error = new Error(reply.message || `refused (${reply.status_code})`);
      Object.assign(error, { status: reply.status_code, code: reply.code });
      waiting.reject(error);
    }
  }

  /** The websocket closed: its jogs will not be answered (the station's deadman stops the arm). */
  onClosed() {
    this.stop("connection lost");
    for (const [id, waiting] of this.replies) {
      clearTimeout(waiting.timer);
      waiting.reject(new Error("the connection to the station closed"));
      this.replies.delete(id);
    }
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

  /** Stop holding: no more heartbeats, and a jog_stop so the arm ramps down now (it would after jog_hold_s anyway).
   * Sent at once: the station handles this session's messages in order, so it follows a jog still on its way. */
  stop(reason) {
    const active = this.active;
    if (!active) return;
    this.finish();
    this.lastStop = reason;
    if (active.sent) this.request({ type: "jog_stop" }).catch(() => null);
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
