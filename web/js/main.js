// Page controller: connects the stream, the REST client and the panels; one dispatch on message type.

import { Api, adoptToken, dropToken } from "./api.js";
import { renderCalibrationState, untrustedReason } from "./calstate.js";
import { ClickCalibration } from "./clickcal.js";
import { GrabDropClicks } from "./clicktargets.js";
import { ColorCalibration } from "./colors.js";
import { CompetitionPanel } from "./competition.js";
import { ControlLease } from "./control.js";
import { EstopButton } from "./estop.js";
import { applyMovingTimeLimits, emptyDetectionsReason, readMovingTimeS } from "./inputs.js";
import { IntrinsicsPanel } from "./intrinsics.js";
import { HoldJog } from "./holdjog.js";
import { LinkIndicators } from "./indicators.js";
import { CartesianJog, typingIn } from "./jog.js";
import { LiveView } from "./liveview.js";
import { applyNoArm } from "./noarm.js";
import { EventLog } from "./log.js";
import { HistoryPanel } from "./history.js";
import { ReachOverlay } from "./reach.js";
import { SpeedOverride } from "./speed.js";
import { TagListPanel } from "./taglist.js";
import {
  JointSliders,
  applyAllowed,
  highlightDetectionRow,
  renderArm,
  renderCalibration,
  renderDetections,
  renderReadouts,
  renderStatus,
} from "./panels.js";
import { ProgramPathOverlay } from "./path.js";
import { JointPlot } from "./plot.js";
import { RepeatPanel } from "./repeat.js";
import { ReachState } from "./reachstate.js";
import { ScenePicker } from "./simscene.js";
import { Stream } from "./stream.js";
import { TargetPanel } from "./target.js";
import { PreviewSetting } from "./preview_setting.js";
import { TeachPanel } from "./teach.js";
import { TorqueButton } from "./torque.js";
import { RecordingPanel } from "./recording.js";
import { prefetchView3d } from "./view3d_prefetch.js";
import { COMMANDS, LAYERS, VIEWS } from "./wire_types.js";

const $ = (id) => document.getElementById(id);
const TERMINAL_JOB_STATES = new Set(["succeeded", "failed", "cancelled"]);

class App {
  constructor() {
    this.api = new Api(adoptToken());
    this.log = new EventLog($("event-log"), $("toasts"));
    this.status = null;
    this.connected = false;
    this.canControl = false;
    this.helloSeen = false;
    this.view = "color";
    this.layers = ["tags", "detections"];
    this.reportedJobs = new Set();
    this.trackedJob = null;
    this.detections = [];
    this.hoverDetection = -1;
    this.detectionsKey = "";
    this.sliders = new JointSliders($("joint-sliders"), (q) => this.sendJoints(q)); // built from the hello's arm
    this.plot = new JointPlot($("joint-plot"));
    this.jog = new CartesianJog({
      api: this.api,
      run: (a, c) => this.run(a, c),
      canJog: () => !$("btn-send-joints").disabled && (this.status?.allowed_commands || []).includes("jog"),
      moveOrPlan: (...args) => this.previewSetting.moveOrPlan(...args),
    });
    this.repeat = new RepeatPanel({ api: this.api, run: (a, c) => this.run(a, c), log: this.log,
                                    moveOrPlan: (...args) => this.previewSetting.moveOrPlan(...args) });
    this.teach = new TeachPanel({
      api: this.api,
      run: (a, c) => this.run(a, c),
      log: this.log,
      status: () => this.status,
      onRepeat: (program) => this.repeat.start(program),
      afterChange: () => this.refreshAllowed(),
      onPath: (path) => this.programPath.set(path),
      onProgram: (waypoints) => { this.programShown = waypoints; this.view3d?.program.show(waypoints); },
      onWaypointSelected: (index) => this.view3d?.program.select(index),
    });
    this.lease = new ControlLease({ api: this.api, log: this.log, onChange: () => this.refreshAllowed() });
    this.intrinsics = new IntrinsicsPanel({ root: $("intrinsics-panel"), api: this.api, log: this.log });
    this.torque = new TorqueButton({ button: $("btn-torque"), run: (a, c) => this.run(a, c), api: this.api });
    this.recording = new RecordingPanel({ api: this.api, run: (a, c) => this.run(a, c), root: $("recording-panel") });
    this.reach = new ReachState({ api: this.api, el: $("reach-state") });
    this.live = new LiveView({
      canvas: $("live"),
      wrap: $("view-wrap"),
      placeholder: $("view-placeholder"),
      hoverLabel: $("hover-world"),
      api: this.api,
      onTarget: (t) => this.clicks.clickTarget(t),
      onHoverTarget: (mode, target) => this.reach.show(mode, target),
      onHoverDetection: (i) => {
        this.hoverDetection = i;
        highlightDetectionRow(i);
      },
    });
    this.programPath = new ProgramPathOverlay(this.live);
    this.previewSetting = new PreviewSetting({ box: $("preview-moves"), preview: () => this.target.preview });
    this.clicks = new GrabDropClicks({ api: this.api, run: (a, c) => this.run(a, c), log: this.log, live: this.live, status: () => this.status,
                                       moveOrPlan: (...args) => this.previewSetting.moveOrPlan(...args) });
    this.clickcal = new ClickCalibration({ api: this.api, live: this.live, log: this.log, afterChange: () => this.refreshAllowed() });
    this.colors = new ColorCalibration({ root: $("colors-panel"), api: this.api, live: this.live, log: this.log });
    this.stream = new Stream({
      token: this.api.token,
      handlers: {
        onOpen: () => this.onOpen(),
        onClose: () => this.onClose(),
        onFrame: ({ header, bitmap }) => this.onFrame(header, bitmap),
        onMessage: (msg) => this.onMessage(msg),
        onError: (e) => this.log.add("warn", `stream: ${e.message}`),
        onTokenRejected: (reason) => this.tokenRejected(reason),
      },
    });
    this.link = new LinkIndicators({ serverNowS: () => this.stream.serverNowS() });
    this.estopButton = new EstopButton({ api: this.api, stream: this.stream, log: this.log });
    this.simScene = new ScenePicker({ api: this.api, run: (a, c) => this.run(a, c) });
    this.holdJog = new HoldJog({
      api: this.api,
      stream: this.stream,
      log: this.log,
      root: $("hold-jog"),
      speed: $("hold-speed"),
      typing: typingIn,
      canJog: () => this.connected && (this.status?.allowed_commands || []).includes("jog") && !$("btn-send-joints").disabled,
    });
    this.target = new TargetPanel({ api: this.api, run: (a, c) => this.run(a, c), status: () => this.status,
                                    openView3d: () => this.openView3d(), view3d: () => this.view3d,
                                    previewOn: () => this.previewSetting.on });
    this.competition = new CompetitionPanel({
      api: this.api,
      live: this.live,
      log: this.log,
      serverNowS: () => this.stream.serverNowS(),
    });
    this.speed = new SpeedOverride({ api: this.api, run: (a, c) => this.run(a, c) });
    this.history = new HistoryPanel({ api: this.api, log: this.log });
    this.tags = new TagListPanel({ api: this.api });
    this.reachOverlay = new ReachOverlay({ live: this.live, api: this.api, log: this.log });
    this.unknownWireNames = App.unknownWireNames;
    window.armlab = this; // handle for operators' devtools and the browser tests
  }

  /** Names in the page's markup that the wire protocol does not know (a stale page); [] when in sync. */
  static unknownWireNames(root = document) {
    const check = (selector, key, known) =>
      [...root.querySelectorAll(selector)].map((el) => el.dataset[key]).filter((name) => !known.includes(name));
    return [
      ...check("[data-command]", "command", COMMANDS),
      ...check("[data-view]", "view", VIEWS),
      ...check("[data-layer]", "layer", LAYERS),
    ];
  }

  start() {
    this.live.layers = this.layers;
    // The top bar's height, for the single-column layout's sticky video (it sits right under the bar).
    const topbar = document.querySelector(".topbar");
    new ResizeObserver(() => document.documentElement.style.setProperty("--topbar-h", `${topbar.offsetHeight}px`)).observe(topbar);
    const unknown = App.unknownWireNames();
    if (unknown.length) this.log.add("error", `page out of date with the server protocol: ${unknown.join(", ")}`);
    this.bindControls();
    this.stream.setView(this.view, this.layers);
    this.stream.connect();
    this.refreshAllowed();
    this.api.calibration().then((c) => this.showCalibration(c)).catch(() => {});
    this.competition.start();
    this.refreshPrograms();
    setInterval(() => this.updateIndicators(), 500);
    $("control-mode").textContent = this.api.canControl ? "control" : "view only";
    this.log.add("info", this.api.canControl ? "page loaded with a control token" : "page loaded view-only (no token)");
  }

  // ---- stream -------------------------------------------------------------------------------
  tokenRejected(reason) {
    this.api.token = null;
    dropToken();
    this.canControl = false;
    $("control-mode").textContent = "view only";
    this.log.toast("error", "control token rejected", `${reason || "wrong control token"}: continuing view-only`);
    this.refreshAllowed();
  }

  onOpen() {
    this.connected = true;
    this.log.add("info", "connected to the station");
    this.updateIndicators();
  }

  onClose() {
    this.holdJog.onClosed();
    if (this.connected) this.log.add("warn", "connection lost; reconnecting…");
    this.connected = false;
    this.updateIndicators();
    this.refreshAllowed();
  }

  onFrame(header, bitmap) {
    this.live.drawFrame(header, bitmap);
    this.link.onFrame(header);
  }

  onMessage(msg) {
    switch (msg.type) {
      case "hello":
        this.helloSeen = true;
        applyMovingTimeLimits($("jog-time"), msg.limits);
        this.holdJog.setLimits(msg.limits);
        this.holdLimits = msg.limits || null;
        this.live.setWorkcell(msg.workcell);
        this.clickcal.setWorkcell(msg.workcell);
        this.setArm(msg.arm);
        this.competition.setBackend(msg.backend);
        this.backend = msg.backend;
        this.view3d?.setBackend(msg.backend);
        this.canControl = Boolean(msg.can_control) && this.api.canControl;
        $("control-mode").textContent = this.canControl ? "control" : "view only";
        $("sim-panel").hidden = msg.backend !== "sim";
        if (msg.backend === "sim") this.simScene.refresh();
        this.refreshAllowed();
        break;
      case "telemetry":
        this.onTelemetry(msg);
        break;
      case "event":
        this.log.add(msg.level || "info", msg.message || "", msg.time_s);
        if (msg.kind === "scene") this.simScene.refresh();
        break;
      case "calibration":
        this.showCalibration(msg);
        break;
      case "jog_reply":
        this.holdJog.onReply(msg);
        break;
      case "error":
        this.log.error("command", msg.error || msg);
        break;
      default:
        break;
    }
  }

  /** Sliders, readouts, plot and teach table from the arm the server runs (its joint names and limits). */
  setArm(arm) {
    renderArm(arm);
    applyNoArm(document, arm);
    this.sliders.build(arm.joint_names, arm.joint_limits_rad);
    this.plot.setJoints(arm.joint_names, arm.joint_limits_rad);
    this.teach.setJointNames(arm.joint_names);
    this.holdJog.build(arm.joint_names, arm.velocity_limits_rad_s);
    this.target.setJointNames(arm.joint_names);
    if (this.status) this.sliders.follow(this.status.joints_rad, true);
  }

  onTelemetry(s) {
    const previous = this.status;
    this.status = s;
    this.estopButton.onStatus(s);
    if (s.state === "estop" || s.state === "fault") this.holdJog.stop(`state ${s.state}`);
    else this.holdJog.onStatus(s);
    renderStatus(s);
    renderCalibrationState(s);
    renderReadouts(s);
    this.clickcal.onStatus(s);
    this.torque.render(s);
    this.lease.render(s);
    this.repeat.onStatus(s);
    this.speed.show(s.speed_percent);
    if (previous && previous.state !== s.state && s.state === "teach") this.teach.refreshDraft();
    if (!previous || (previous.joint_names || []).join() !== (s.joint_names || []).join()) {
      if (s.joint_names) this.sliders.build(s.joint_names, s.joint_limits_rad);
      this.plot.setJoints(s.joint_names, s.joint_limits_rad);
      this.teach.setJointNames(s.joint_names);
      this.sliders.follow(s.joints_rad, true);
    } else {
      this.sliders.follow(s.joints_rad);
    }
    this.plot.push(s.time_s, s.joints_rad);
    $("sim-panel").hidden = s.backend !== "sim";
    if (previous && previous.state !== s.state) {
      this.log.add(s.state === "estop" || s.state === "fault" ? "error" : "info", `state: ${previous.state} → ${s.state}`);
    }
    if (previous && previous.calibrated !== s.calibrated && s.calibrated) {
      this.api.calibration().then((c) => this.showCalibration(c)).catch(() => {});
    }
    this.live.calibrated = Boolean(s.calibrated);
    $("view-select").querySelector("[data-view='topdown']").disabled = !s.calibrated;
    if (Array.isArray(s.detections)) this.setDetections(s.detections);
    this.watchJob(s.job);
    this.view3d?.onTelemetry(s);
    this.competition.onStatus(s);
    this.refreshAllowed();
  }

  /** The 3-D panel open (a plan to show): resolves to the View3D, or null when it could not load. */
  async openView3d() {
    if ($("btn-view3d").getAttribute("aria-pressed") !== "true") await this.toggleView3d();
    else await this.view3dLoading;
    return this.view3d ?? null;
  }

  /** The 3-D panel: its module (and three.js) loads on first open; later clicks show or hide it. */
  async toggleView3d() {
    const button = $("btn-view3d");
    const open = button.getAttribute("aria-pressed") !== "true";
    button.setAttribute("aria-pressed", String(open));
    button.classList.toggle("on", open);
    if (!this.view3dLoading) {
      const prefetched = prefetchView3d(this.api);
      this.view3dLoading = import("./view3d.js").then(async ({ View3D }) => {
        const view = new View3D({ root: $("view3d-panel"), api: this.api, prefetched, serverNowS: () => this.stream.serverNowS(),
                                  onPick: (positionM, waypoint) => this.picked3d(positionM, waypoint),
                                  onGoal: (positionM, angles) => this.target.goalMoved(positionM, angles) });
        if (this.calibrationShown) view.setCalibration(this.calibrationShown);
        $("view3d-panel").hidden = false;
        await view.start();
        if (this.backend) view.setBackend(this.backend);
        if (this.status) view.onTelemetry(this.status);
        if (this.programShown) view.program.show(this.programShown);
        this.view3d = view;
      }).catch((e) => this.log.add("error", `3-D view: ${e.message}`));
    }
    await this.view3dLoading;
    this.view3d?.show(button.getAttribute("aria-pressed") === "true");
  }

  /** A click in the 3-D view: in Click-grab / Click-drop mode the same grab or drop as a click on the video; else a
   * click on a program waypoint's arm chooses its row in the waypoint table. */
  picked3d(positionM, waypoint = -1) {
    const mode = this.live.mode;
    if ((mode === "grab" || mode === "drop") && positionM) this.clicks.clickTarget({ mode, positionM });
    else if (waypoint >= 0) this.teach.selectWaypoint(waypoint);
    else this.log.toast("info", "3-D view", "choose Click-grab or Click-drop, then click a block or the board here");
  }

  showCalibration(calibration) {
    this.calibrationShown = calibration;
    this.view3d?.setCalibration(calibration);
    renderCalibration(calibration);
    this.live.setCalibration(calibration);
    this.competition.setCalibration(calibration);
    this.tags.onCalibration();
  }

  setDetections(detections) {
    this.detections = detections;
    const untrusted = Boolean(untrustedReason(this.status));
    this.live.setDetections(detections, untrusted);
    const why = emptyDetectionsReason(this.status);
    const key = why + untrusted + JSON.stringify(detections.map((d) => [d.id, d.color, d.size, d.position_m?.map((v) => Math.round(v * 1000))]));
    if (key === this.detectionsKey) return;
    this.detectionsKey = key;
    renderDetections(detections, this.hoverDetection, (d) => this.clicks.detectionClicked(d), why, untrusted);
  }

  /** Report a job's end once, and move the click mode along grab → drop → grab. */
  watchJob(job) {
    if (!job) {
      this.trackedJob = null;
      return;
    }
    if (job.state === "running") {
      this.trackedJob = job.id;
      return;
    }
    if (!TERMINAL_JOB_STATES.has(job.state) || this.reportedJobs.has(job.id)) return;
    this.reportedJobs.add(job.id);
    if (this.reportedJobs.size > 100) this.reportedJobs.delete(this.reportedJobs.values().next().value);
    const wasOurs = this.trackedJob === job.id;
    this.trackedJob = null;
    if (!wasOurs) return;
    // The station's own event already put the outcome in the log; a failure also gets a toast.
    if (job.state === "failed") this.log.toast("error", `${job.name} failed`, job.message || "failed", false);
    if (job.state === "succeeded" && job.name === "grab" && this.live.mode === "grab") this.setMode("drop");
    else if (job.state === "succeeded" && job.name === "drop" && this.live.mode === "drop") this.setMode("grab");
    if (job.state === "succeeded" && job.name === "repeat") this.refreshPrograms();
    if (job.state === "succeeded") this.live.clearMarker();
  }

  refreshAllowed() {
    const allowed = this.connected && this.status ? this.status.allowed_commands : [];
    const control = this.connected && this.api.canControl && (this.helloSeen ? this.canControl : true) && this.lease.mine;
    applyAllowed(document, allowed, control);
    this.sliders.setDisabled(!control || !(allowed || []).includes("move_joints"));
    this.speed.setDisabled(!(this.connected && this.api.canControl));
    // E-stop is never disabled: without a connection it goes over REST.
    $("btn-estop").disabled = false;
  }

  updateIndicators() {
    this.link.render(this.connected);
  }

  // ---- commands ----------------------------------------------------------------------------
  /** Run a REST call, log it, toast the server's message on failure; returns the result or null. */
  async run(action, call) {
    try {
      const result = await call();
      // A job's answer is {job}; a status (which carries the last job too) is a manual command's answer.
      const startedJob = result && result.job && !("state" in result);
      if (startedJob) {
        this.trackedJob = result.job.id; // the station logs the job's start and end itself
      } else {
        this.log.add("info", `${action}: ok`);
      }
      return result;
    } catch (e) {
      this.log.error(action, e);
      return null;
    }
  }

  sendJoints(qRad) {
    const time = readMovingTimeS($("jog-time"));
    if (!time.ok) {
      this.log.toast("error", "move time", time.message);
      return Promise.resolve(null);
    }
    const body = { q_rad: qRad, ...(time.valueS !== undefined ? { moving_time_s: time.valueS } : {}) };
    return this.previewSetting.moveOrPlan("plan joints", "/api/arm/joints", body,
      () => this.run("move joints", () => this.api.joints(qRad, time.valueS)));
  }

  setMode(mode) {
    this.live.setMode(mode);
    this.reach.show(mode, null); // checked again at the pointer's next reading
    this.clickcal.setActive(mode === "points");
    this.colors.setActive(mode === "color");
    document.querySelectorAll("#click-mode button").forEach((b) => b.classList.toggle("on", b.dataset.mode === mode));
    $("live").dataset.mode = mode;
  }

  setView(view) {
    this.view = view;
    document.querySelectorAll("#view-select button").forEach((b) => b.classList.toggle("on", b.dataset.view === view));
    this.stream.setView(this.view, this.layers);
  }

  setLayers() {
    this.layers = [...document.querySelectorAll("[data-layer]")].filter((c) => c.checked).map((c) => c.dataset.layer);
    this.live.layers = this.layers;
    this.stream.setView(this.view, this.layers);
  }

  refreshPrograms() {
    return this.teach.refresh();
  }

  bindControls() {
    const on = (id, fn) => $(id).addEventListener("click", fn);
    this.estopButton.bindButton();
    on("btn-view3d", () => this.toggleView3d());
    if (new URLSearchParams(location.search).get("view3d") === "1") this.toggleView3d();
    this.estopButton.bindKey();
    on("btn-home", () => this.previewSetting.moveOrPlan("plan home", "/api/arm/home", {}, () => this.run("home", () => this.api.home())));
    on("btn-sleep", () => this.previewSetting.moveOrPlan("plan sleep", "/api/arm/sleep", {}, () => this.run("sleep", () => this.api.sleep())));
    on("btn-open", () => this.run("gripper open", () => this.api.gripper("release")));
    on("btn-close", () => this.run("gripper close", () => this.api.gripper("grasp")));
    on("btn-reset", () => this.run("reset", () => this.api.reset()));
    on("btn-calibrate", () => this.run("calibrate", () => this.api.calibrate()));
    on("btn-calibrate-arm", () => this.run("calibrate arm", () => this.api.calibrateArm()));
    on("btn-cancel-job", () => this.run("cancel job", () => this.api.cancelJob()));
    on("btn-send-joints", () => this.sendJoints(this.sliders.valuesRad()));
    on("btn-sliders-from-arm", () => this.status && this.sliders.follow(this.status.joints_rad, true));
    document.querySelectorAll("#click-mode button").forEach((b) => b.addEventListener("click", () => this.setMode(b.dataset.mode)));
    document.querySelectorAll("#view-select button").forEach((b) => b.addEventListener("click", () => this.setView(b.dataset.view)));
    document.querySelectorAll("[data-layer]").forEach((c) => c.addEventListener("change", () => this.setLayers()));
    this.simScene.bind();
    on("btn-clear-log", () => this.log.clear());
  }
}

new App().start();
