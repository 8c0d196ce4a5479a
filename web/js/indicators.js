// The top bar's link indicators: connected or reconnecting, the video's frame rate and its latency (the median
// of the last 30 frames, capture to arrival on the server's clock).

import { RateMeter } from "./stream.js";

const $ = (id) => document.getElementById(id);
const LATENCY_SAMPLES = 30;

export class LinkIndicators {
  /** serverNowS(): the server's clock (the Stream's estimate), for the frames' latency. */
  constructor({ serverNowS }) {
    this.serverNowS = serverNowS;
    this.fps = new RateMeter(2.0);
    this.latencyMs = [];
  }

  /** A video frame arrived (its header's capture_time_s gives the latency). */
  onFrame(header) {
    const nowS = performance.now() / 1000;
    this.fps.tick(nowS);
    if (Number.isFinite(header.capture_time_s)) {
      this.latencyMs.push((this.serverNowS() - header.capture_time_s) * 1000);
      if (this.latencyMs.length > LATENCY_SAMPLES) this.latencyMs.shift();
    }
  }

  render(connected) {
    $("ind-conn").dataset.ok = String(connected);
    $("conn-text").textContent = connected ? "connected" : "reconnecting";
    const fps = this.fps.rate(performance.now() / 1000);
    $("fps").textContent = fps.toFixed(1);
    if (this.latencyMs.length) {
      const sorted = [...this.latencyMs].sort((a, b) => a - b);
      $("latency").textContent = Math.max(0, sorted[Math.floor(sorted.length / 2)]).toFixed(0);
    } else {
      $("latency").textContent = "—";
    }
  }
}
