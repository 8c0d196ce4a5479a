// The E-STOP button and the Escape key: the stop goes over the websocket on the press itself, with REST as the
// fallback (and the only way while the stream is down).

const $ = (id) => document.getElementById(id);
const ESTOP_REST_FALLBACK_MS = 300;
const ESTOP_PRESS_CLICK_MS = 2000; // the click ending an e-stop press (it stopped on the press) sends nothing more

export class EstopButton {
  /** api: Api; stream: the page's Stream; log: EventLog. */
  constructor({ api, stream, log }) {
    this.api = api;
    this.stream = stream;
    this.log = log;
    this.seen = false; // telemetry showed estop since the last E-STOP press
    this.pressedMs = undefined;
  }

  /** Telemetry: note that the station reported estop (the REST fallback is then not needed). */
  onStatus(s) {
    if (s.state === "estop") this.seen = true;
  }

  estop() {
    const sentOverWs = this.stream.send({ type: "command", name: "estop" });
    this.log.add("error", `E-STOP pressed (${sentOverWs ? "websocket" : "REST"})`);
    const viaRest = () => this.api.estop().catch((e) => this.log.error("e-stop", e));
    if (!sentOverWs) {
      viaRest();
      return;
    }
    // Fall back to REST unless the station reported estop since the press (a quick Reset must not re-stop it).
    this.seen = false;
    setTimeout(() => {
      if (!this.seen) viaRest();
    }, ESTOP_REST_FALLBACK_MS);
  }

  /** The button's press and click listeners. */
  bindButton() {
    // E-stop on the press itself (a finger or the mouse going down), not on the release a click waits for: a tap
    // by a second finger while another holds a jog makes no click at all. A click with no press just before it
    // (the keyboard's Enter/Space) stops too.
    $("btn-estop").addEventListener("pointerdown", () => {
      this.pressedMs = performance.now();
      this.estop();
    });
    $("btn-estop").addEventListener("click", () => {
      if (!(performance.now() - (this.pressedMs ?? -Infinity) < ESTOP_PRESS_CLICK_MS)) this.estop();
    });
  }

  /** Escape anywhere on the page stops too. */
  bindKey() {
    document.addEventListener("keydown", (e) => {
      if (e.key === "Escape") {
        e.preventDefault();
        this.estop();
      }
    });
  }
}
