// REST client for the station: carries the control token and the page's controller name, and turns
// error bodies into ApiError. The token is read from the page URL once, kept in sessionStorage and
// removed from the address bar. The controller name (the control lease's holder name, also sent on the
// websocket) is ?controller= if given, else a name of this tab's own, kept for reloads.

const TOKEN_KEY = "armlab.token";
const CONTROLLER_KEY = "armlab.controller";
const CONTROLLER_NAME = /^[A-Za-z0-9_.:-]{1,64}$/;

/** An HTTP error with the server's code and human message (see the wire protocol's error body); an unsafe
 * motion's refusal also names the part (`part`) and the joints where it happens (`atQRad`, or null). */
export class ApiError extends Error {
  constructor(status, code, message, allowed, { part = null, atQRad = null } = {}) {
    super(message);
    this.name = "ApiError";
    this.status = status;
    this.code = code;
    this.allowed = allowed || [];
    this.part = typeof part === "string" ? part : null;
    this.atQRad = Array.isArray(atQRad) && atQRad.every(Number.isFinite) ? atQRad : null;
  }
}

/** Take `token` from the URL (then strip it from the address bar), else from sessionStorage. */
export function adoptToken(win = window) {
  const url = new URL(win.location.href);
  const fromUrl = url.searchParams.get("token");
  if (fromUrl) {
    win.sessionStorage.setItem(TOKEN_KEY, fromUrl);
    url.searchParams.delete("token");
    win.history.replaceState(null, "", url.pathname + url.search + url.hash);
  }
  return win.sessionStorage.getItem(TOKEN_KEY) || null;
}

/** This tab's controller name: ?controller= (then stripped from the address bar), else the stored one,
 * else a new "ui-xxxxxx". The REST calls and the websocket of the page carry it. */
export function adoptController(win = window) {
  const url = new URL(win.location.href);
  const fromUrl = url.searchParams.get("controller");
  if (fromUrl && CONTROLLER_NAME.test(fromUrl)) {
    win.sessionStorage.setItem(CONTROLLER_KEY, fromUrl);
  }
  if (fromUrl !== null) {
    url.searchParams.delete("controller");
    win.history.replaceState(null, "", url.pathname + url.search + url.hash);
  }
  let name = win.sessionStorage.getItem(CONTROLLER_KEY);
  if (!name || !CONTROLLER_NAME.test(name)) {
    name = `ui-${Math.random().toString(16).slice(2, 8)}`;
    win.sessionStorage.setItem(CONTROLLER_KEY, name);
  }
  return name;
}

/** Parse an error response into an ApiError, tolerating bodies that are not the documented shape. */
async function toApiError(response) {
  let body = null;
  try {
    body = await response.json();
  } catch {
    body = null;
  }
  const err = body && typeof body === "object" ? body.error || body : {};
  let message = err.message || (typeof err.detail === "string" ? err.detail : "");
  if (!message && Array.isArray(err.detail)) {
    message = err.detail.map((d) => `${(d.loc || []).join(".")}: ${d.msg}`).join("; ");
  }
  if (!message) message = `${response.status} ${response.statusText}`;
  return new ApiError(response.status, err.code || String(response.status), message, err.allowed,
    { part: err.part, atQRad: err.at_q_rad });
}

/** Forget a token the server refused, so a reload does not reuse it. */
export function dropToken(win = window) {
  win.sessionStorage.removeItem(TOKEN_KEY);
}

/** A small REST client bound to one token; every method returns parsed JSON or throws ApiError. */
export class Api {
  constructor(token, base = "", controller = adoptController()) {
    this.token = token;
    this.base = base;
    this.controller = controller;
  }

  get canControl() {
    return Boolean(this.token);
  }

  async request(method, path, body) {
    const headers = { Accept: "application/json", "X-Armlab-Controller": this.controller };
    if (this.token) headers.Authorization = `Bearer ${this.token}`;
    const init = { method, headers };
    if (body !== undefined) {
      headers["Content-Type"] = "application/json";
      init.body = JSON.stringify(body);
    }
    let response;
    try {
      response = await fetch(this.base + path, init);
    } catch (e) {
      throw new ApiError(0, "network", `Server unreachable (${e.message})`);
    }
    if (!response.ok) throw await toApiError(response);
    if (response.status === 204) return null;
    const text = await response.text();
    return text ? JSON.parse(text) : null;
  }

  get(path) { return this.request("GET", path); }
  post(path, body) { return this.request("POST", path, body === undefined ? {} : body); }

  status() { return this.get("/api/status"); }
  calibration() { return this.get("/api/calibration"); }
  programs() { return this.get("/api/programs"); }
  estop() { return this.post("/api/estop"); }
  takeControl() { return this.post("/api/control/take"); }
  releaseControl() { return this.post("/api/control/release"); }
  heartbeat() { return this.post("/api/heartbeat"); }
  step(body) { return this.post("/api/arm/step", body); }
  jog(velocityRadS, speedPercent = 100) { return this.post("/api/arm/jog", { velocity_rad_s: velocityRadS, speed_percent: speedPercent }); }
  checkPose(body) { return this.post("/api/arm/pose/check", body); }
  checkJoints(body) { return this.post("/api/arm/joints/check", body); }
  reset() { return this.post("/api/reset"); }
  home() { return this.post("/api/arm/home"); }
  sleep() { return this.post("/api/arm/sleep"); }
  joints(qRad, movingTimeS) { return this.post("/api/arm/joints", { q_rad: qRad, moving_time_s: movingTimeS }); }
  pose(positionM, pitchRad, yawRad, movingTimeS) {
    const body = { position_m: positionM };
    if (Number.isFinite(pitchRad)) body.pitch_rad = pitchRad;
    if (Number.isFinite(yawRad)) body.yaw_rad = yawRad;
    if (Number.isFinite(movingTimeS)) body.moving_time_s = movingTimeS;
    return this.post("/api/arm/pose", body);
  }
  torque(enabled, confirm = false) { return this.post("/api/arm/torque", confirm ? { enabled, confirm } : { enabled }); }
  gripper(action) { return this.post("/api/gripper", { action }); }
  calibrate() { return this.post("/api/calibrate"); }
  calibrateArm() { return this.post("/api/calibrate/arm"); }
  pixelToWorld(u, v) { return this.post("/api/pixel-to-world", { u, v }); }
  grab(target) { return this.post("/api/grab", target); }
  drop(target) { return this.post("/api/drop", target); }
  teachStart() { return this.post("/api/teach/start"); }
  teachRecord(body) { return this.post("/api/teach/record", body); }
  teachUndo() { return this.post("/api/teach/undo"); }
  teachDraft() { return this.get("/api/teach/draft"); }
  updateProgram(id, body) { return this.request("PATCH", `/api/programs/${encodeURIComponent(id)}`, body); }
  duplicateProgram(id) { return this.post(`/api/programs/${encodeURIComponent(id)}/duplicate`); }
  deleteProgram(id) { return this.request("DELETE", `/api/programs/${encodeURIComponent(id)}`); }
  teachStop(name) { return this.post("/api/teach/stop", { name }); }
  teachExit() { return this.post("/api/teach/exit"); }
  repeat(programId, cycles, speedPercent = 100) {
    return this.post(`/api/programs/${encodeURIComponent(programId)}/repeat`, { cycles, speed_percent: speedPercent });
  }
  cancelJob() { return this.post("/api/jobs/cancel"); }
  simScene(event, level, seed) { return this.post("/api/sim/scene", { event, level, seed }); }
}
