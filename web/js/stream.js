// Websocket link to the server: decodes binary frames and JSON messages, acks drawn frames
// (the server sends the next frame only after the ack: newest wins), and reconnects on a timer.

import { adoptController } from "./api.js";

const RECONNECT_MIN_S = 0.5;
const RECONNECT_MAX_S = 5.0;
const WS_WRONG_TOKEN = 4401; // close code of /ws when ?token= does not match

/** Split a binary frame message: [uint32 LE header length N][N bytes JSON header][JPEG bytes]. */
export function parseFrameMessage(buffer) {
  if (!(buffer instanceof ArrayBuffer) || buffer.byteLength < 4) {
    throw new Error("frame message shorter than its 4-byte header length");
  }
  const headerLength = new DataView(buffer).getUint32(0, true);
  if (4 + headerLength > buffer.byteLength) {
    throw new Error(`frame header length ${headerLength} exceeds message size ${buffer.byteLength}`);
  }
  const headerText = new TextDecoder().decode(new Uint8Array(buffer, 4, headerLength));
  const header = JSON.parse(headerText);
  const jpeg = new Uint8Array(buffer, 4 + headerLength);
  return { header, jpeg };
}

/** Frames-per-second over a sliding window of draw times (seconds). */
export class RateMeter {
  constructor(windowS = 2.0) {
    this.windowS = windowS;
    this.timesS = [];
  }
  tick(nowS) {
    this.timesS.push(nowS);
    while (this.timesS.length && nowS - this.timesS[0] > this.windowS) this.timesS.shift();
  }
  rate(nowS) {
    const recent = this.timesS.filter((t) => nowS - t <= this.windowS);
    if (recent.length < 2) return 0;
    const spanS = recent[recent.length - 1] - recent[0];
    return spanS > 0 ? (recent.length - 1) / spanS : 0;
  }
}

/**
 * One reconnecting websocket. Handlers: onOpen(), onClose(), onFrame({header, bitmap}) → Promise that
 * resolves once drawn, onMessage(msg) for JSON messages, onTokenRejected(reason) when the server
 * refuses the control token (the stream then reconnects view-only). After a frame is drawn it is acked.
 */
export class Stream {
  constructor({ token, handlers, win = window }) {
    this.token = token;
    this.handlers = handlers;
    this.win = win;
    this.ws = null;
    this.retryS = RECONNECT_MIN_S;
    this.closedByUser = false;
    this.viewMessage = null;
    this.clockOffsetS = null; // server_time − local_time, see observeServerTime()
    this.timer = null;
  }

  get isOpen() {
    return this.ws !== null && this.ws.readyState === WebSocket.OPEN;
  }

  url() {
    const proto = this.win.location.protocol === "https:" ? "wss:" : "ws:";
    const query = this.token
      ? `?token=${encodeURIComponent(this.token)}&controller=${encodeURIComponent(adoptController(this.win))}`
      : "";
    return `${proto}//${this.win.location.host}/ws${query}`;
  }

  connect() {
    this.closedByUser = false;
    let ws;
    try {
      ws = new WebSocket(this.url());
    } catch (e) {
      this.scheduleReconnect();
      return;
    }
    ws.binaryType = "arraybuffer";
    this.ws = ws;
    ws.onopen = () => {
      this.retryS = RECONNECT_MIN_S;
      if (this.viewMessage) this.send(this.viewMessage);
      this.handlers.onOpen?.();
    };
    ws.onmessage = (event) => this.dispatch(event.data);
    ws.onclose = (event) => {
      if (this.ws === ws) this.ws = null;
      if (event.code === WS_WRONG_TOKEN && this.token) {
        // The server refused our token: continue as a view-only stream rather than retrying it forever.
        this.token = null;
        this.retryS = RECONNECT_MIN_S;
        this.handlers.onTokenRejected?.(event.reason);
      }
      this.handlers.onClose?.();
      if (!this.closedByUser) this.scheduleReconnect();
    };
    ws.onerror = () => {
      // onclose follows; reconnection happens there.
    };
  }

  scheduleReconnect() {
    if (this.timer) return;
    const delayS = this.retryS;
    this.retryS = Math.min(RECONNECT_MAX_S, this.retryS * 2);
    this.timer = this.win.setTimeout(() => {
      this.timer = null;
      this.connect();
    }, delayS * 1000);
  }

  close() {
    this.closedByUser = true;
    if (this.timer) this.win.clearTimeout(this.timer);
    this.timer = null;
    this.ws?.close();
  }

  send(message) {
    if (!this.isOpen) return false;
    this.ws.send(JSON.stringify(message));
    return true;
  }

  /** Choose the view and server-drawn overlay layers; remembered and re-sent after a reconnect. */
  setView(view, layers) {
    this.viewMessage = { type: "view", view, layers };
    this.send(this.viewMessage);
  }

  /**
   * Track server_time − local_time. Each sample (server send time − local receive time) is at most
   * the true offset (transit takes ≥ 0 s), so the largest sample since the hello is the tightest.
   */
  observeServerTime(serverTimeS, restart) {
    const sample = serverTimeS - Date.now() / 1000;
    this.clockOffsetS = restart || this.clockOffsetS === null ? sample : Math.max(this.clockOffsetS, sample);
  }

  /** Local estimate of the server clock, for capture-to-screen latency. */
  serverNowS() {
    return Date.now() / 1000 + (this.clockOffsetS ?? 0);
  }

  async dispatch(data) {
    if (typeof data === "string") {
      let msg;
      try {
        msg = JSON.parse(data);
      } catch {
        return;
      }
      const sentS = msg.type === "hello" ? msg.server_time_s : msg.type === "telemetry" ? msg.time_s : undefined;
      if (Number.isFinite(sentS)) this.observeServerTime(sentS, msg.type === "hello");
      this.handlers.onMessage?.(msg);
      return;
    }
    let parsed;
    try {
      parsed = parseFrameMessage(data);
    } catch (e) {
      this.handlers.onError?.(e);
      return;
    }
    const { header, jpeg } = parsed;
    try {
      const bitmap = await createImageBitmap(new Blob([jpeg], { type: "image/jpeg" }));
      await this.handlers.onFrame?.({ header, bitmap });
    } catch (e) {
      this.handlers.onError?.(e);
    } finally {
      // Ack even a frame that failed to decode, or the server would never send another.
      this.send({ type: "ack", seq: header.seq });
    }
  }
}
