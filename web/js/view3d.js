// The 3-D panel (loaded on first open, so the page without it never fetches three.js): the arm at its measured
// joints from telemetry, the board with its grid, tags and places, detected blocks (and, in the simulation,
// ground truth), the calibrated camera's frustum and the gripper's recent path. Orbit / pan / zoom with the
// mouse, preset views Top, Front, Camera. Geometry comes from GET /api/view3d/scene and the calibration.
// It renders only when something changed (the arm, the blocks, the view, a layer), so an idle panel costs no frames,
// and at most MAX_FPS frames a second.

import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import {
  ArmFigure,
  BoxSet,
  PointCloud,
  Trail,
  buildFrustum,
  buildWorkcell,
  cameraPreset,
  detectionBoxes,
  truthBoxes,
} from "./view3d_scene.js";
import { GoalMarker } from "./view3d_goal.js";
import { ProgramFigures } from "./view3d_program.js";

const TRUTH_POLL_MS = 500;
const POINTS_POLL_MS = 1000;
const REFUSED_COLOR = 0xe53935; // the part of the arm a refused plan would crash
const COMMANDED_COLOR = 0x42a5f5; // the commanded arm during a repeat
// At most this many 3-D frames a second (a little above telemetry's 30 Hz, so each message still gets its own frame):
// a continuous orbit asked for one every display frame (60/s), and on a machine without a GPU each software-rendered
// frame took CPU from the video's decode and from the simulated camera (bench/view3d.py: the video's rate orbiting).
const MAX_FPS = 36;
const PICK_MAX_DRAG_PX = 5; // a press and release closer than this is a click (a pick), farther an orbit
const BOARD_PLANE = new THREE.Plane(new THREE.Vector3(0, 0, 1), 0); // the board's top, z = 0 in the world

export class View3D {
  /** root: the panel element (holds a .view3d-canvas-wrap and the controls); serverNowS: the server clock;
   * onPick(positionM, waypoint): a click (not a drag) on a detected block (its top's centre) or on the board (z = 0,
   * else null), and the index of the shown program waypoint whose see-through arm it hit (-1: none);
   * onGoal(positionM, angles): the goal marker (view3d_goal.js) was dragged there (angles: {pitchRad, yawRad} after a
   * turn of its rings, else null). */
  constructor({ root, api, prefetched = null, serverNowS = () => Date.now() / 1000, onPick = () => {}, onGoal = () => {} }) {
    this.root = root;
    this.onPick = onPick;
    this.onGoal = onGoal;
    this.goal = null; // GoalMarker, once the scene is up
    this.commandedArm = null; // ArmFigure of the commanded joints during a repeat (showCommanded)
    this.api = api;
    this.prefetched = prefetched; // view3d_prefetch.js: the scene and mesh files, already on their way
    this.serverNowS = serverNowS;
    this.wrap = root.querySelector(".view3d-canvas-wrap");
    this.dirty = true;
    this.maxFps = MAX_FPS; // the cap on frames drawn a second (the bench compares it with none: Infinity)
    this.nextFrameMs = 0; // the earliest time (performance.now) the next frame may be drawn
    this.arm = null; // ArmFigure of the measured arm
    this.workcell = null;
    this.calibration = null;
    this.pendingTelemetry = null; // newest telemetry not yet drawn
    this.truthTimer = null;
    // Figures the bench and the tests read: frames drawn, time of the first frame with the arm,
    // per-frame telemetry delays (ms from the server's time_s, and from the message's arrival).
    this.stats = { frames: 0, armFirstFrameMs: null, telemetryDelayMs: [], arrivalDelayMs: [], renderMs: [] };
    this.lastDrawn = null; // {time_s, joints_rad, tool_m} of the telemetry in the last frame
    this.planShown = null; // {id, goal: ArmFigure, path: THREE.Line} of the plan drawn (showPlan)
    this.refusalShown = null; // {part, links, atQRad, figure: ArmFigure} of a refused plan drawn (showRefusal)
  }

  async start() {
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0x1d2126);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(0.4, -0.6, 1.5);
    scene.add(sun);
    this.scene = scene;
    this.renderer = new THREE.WebGLRenderer({ antialias: false, powerPreference: "low-power" });
    this.renderer.setPixelRatio(1);
    this.wrap.appendChild(this.renderer.domElement);
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.01, 20);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => {
      this.goal?.fitToView();
      this.invalidate();
    });
    this.bindPicking(this.renderer.domElement);
    this.resize();
    new ResizeObserver(() => this.resize()).observe(this.wrap);

    const description = await (this.prefetched?.scene ?? this.api.get("/api/view3d/scene"));
    const meshBuffers = this.prefetched ? await this.prefetched.meshes : new Map();
    this.workcell = description.workcell;
    const workcell = buildWorkcell(this.workcell);
    this.board = workcell.getObjectByName("board");
    this.gripperBox = workcell.getObjectByName("gripper box");
    scene.add(workcell);
    this.detections = new BoxSet("detections");
    this.truth = new BoxSet("truth", { wire: true });
    this.trail = new Trail();
    this.cloud = new PointCloud();
    scene.add(this.detections.group, this.truth.group, this.trail.line, this.cloud.points);
    this.setPreset("front");
    if (description.arm) {
      this.armDescription = description.arm;
      this.arm = new ArmFigure(description.arm, { meshBuffers, onLoad: () => this.invalidate() });
      scene.add(this.arm.robot);
      this.root.querySelector("[data-view3d-credit]").textContent = description.arm.meshes
        ? `${description.arm.name}: meshes ${description.arm.meshes.source} (${description.arm.meshes.licence})`
        : `${description.arm.name}: the simulation's shapes`;
    }
    this.goal = new GoalMarker(this, (positionM, angles) => this.onGoal(positionM, angles));
    this.program = new ProgramFigures(this);
    this.bindControls();
    if (this.calibration) this.setCalibration(this.calibration);
    this.loop = () => {
      this.frame();
      this.raf = requestAnimationFrame(this.loop);
    };
    this.raf = requestAnimationFrame(this.loop);
  }

  /** Another arm from the same URDF (a goal arm, a plan's waypoint): see-through, in its own colour, sharing the
   * measured arm's parsed meshes; pose it with figure.setJoints(q) then invalidate(); removeArm(figure) drops it. */
  addArm({ opacity = 0.35, color = 0xff9800, highlight = null } = {}) {
    const figure = new ArmFigure(this.armDescription, { opacity, color, highlight, onLoad: () => this.invalidate() });
    this.scene.add(figure.robot);
    return figure;
  }

  removeArm(figure) {
    this.scene.remove(figure.robot);
    this.invalidate();
  }

  /** A plan (plan_preview.js): the goal arm, see-through, and the gripper's path; replaces the one shown. */
  showPlan(plan) {
    this.clearPlan();
    if (!this.armDescription) return;
    const goal = this.addArm();
    goal.setJoints(plan.goal_q_rad, null);
    const points = plan.gripper_path_m.map(([x, y, z]) => new THREE.Vector3(x, y, z));
    const path = new THREE.Line(new THREE.BufferGeometry().setFromPoints(points),
      new THREE.LineBasicMaterial({ color: 0xff9800 }));
    this.scene.add(path);
    this.planShown = { id: plan.plan_id, goal, path };
    this.invalidate();
  }

  /** A plan refused as unsafe: the arm, see-through, at the joints where it would fail (atQRad), the part's links
   * (the server's part_links: a link, the fingers, the palm) in red; replaces any plan or refusal shown. */
  showRefusal({ part, atQRad }) {
    this.clearPlan();
    const links = this.armDescription?.part_links?.[part];
    if (!links || !Array.isArray(atQRad)) return;
    const figure = this.addArm({ opacity: 0.3, color: 0x9e9e9e, highlight: { links, color: REFUSED_COLOR } });
    figure.setJoints(atQRad, null);
    this.refusalShown = { part, links, atQRad, figure };
    this.invalidate();
  }

  /** During a repeat, the commanded arm (the servos' reference) see-through beside the measured one; none (null)
   * otherwise. True if the drawing changed. */
  showCommanded(qRad) {
    if (!Array.isArray(qRad) || !this.armDescription) {
      if (!this.commandedArm) return false;
      this.removeArm(this.commandedArm);
      this.commandedArm = null;
      return true;
    }
    this.commandedArm ??= this.addArm({ opacity: 0.3, color: COMMANDED_COLOR });
    this.commandedArm.setJoints(qRad, null);
    return true;
  }

  clearPlan() {
    if (this.refusalShown) {
      this.removeArm(this.refusalShown.figure);
      this.refusalShown = null;
    }
    if (!this.planShown) return;
    this.removeArm(this.planShown.goal);
    this.scene.remove(this.planShown.path);
    this.planShown.path.geometry.dispose();
    this.planShown.path.material.dispose();
    this.planShown = null;
    this.invalidate();
  }

  /** A left click that does not drag (the orbit's drags do) picks the world point under it (pickAt). */
  bindPicking(element) {
    let pressed = null;
    element.addEventListener("pointerdown", (e) => {
      pressed = e.button === 0 && !this.goal?.active ? { x: e.clientX, y: e.clientY } : null; // the marker's handles drag it
    });
    element.addEventListener("pointerup", (e) => {
      const start = pressed;
      pressed = null;
      if (!start || e.button !== 0 || Math.hypot(e.clientX - start.x, e.clientY - start.y) > PICK_MAX_DRAG_PX) return;
      const positionM = this.pickAt(e.clientX, e.clientY);
      const waypoint = this.program?.pickAt(this.rayAt(e.clientX, e.clientY)) ?? -1;
      if (positionM || waypoint >= 0) this.onPick(positionM, waypoint);
    });
  }

  /** The ray from the camera through a page point. */
  rayAt(clientX, clientY) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
    const raycaster = new THREE.Raycaster();
    raycaster.setFromCamera(ndc, this.camera);
    return raycaster;
  }

  /** The world point (m) under a page point: the top centre of the nearest detected block the ray meets, else
   * where it meets the board (z = 0); null off the board's plane. */
  pickAt(clientX, clientY) {
    const raycaster = this.rayAt(clientX, clientY);
    const [hit] = raycaster.intersectObjects(this.detections.group.children, false);
    if (hit) {
      const box = hit.object;
      return [box.position.x, box.position.y, box.position.z + box.geometry.parameters.depth / 2];
    }
    const onBoard = raycaster.ray.intersectPlane(BOARD_PLANE, new THREE.Vector3());
    return onBoard ? [onBoard.x, onBoard.y, 0] : null;
  }

  /** The page point where a world point (m) is drawn (tests and the bench click there). */
  clientPointOf(positionM) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const p = new THREE.Vector3(...positionM).project(this.camera);
    return [r.left + ((p.x + 1) / 2) * r.width, r.top + ((1 - p.y) / 2) * r.height];
  }

  bindControls() {
    for (const button of this.root.querySelectorAll("[data-view3d-preset]")) {
      button.addEventListener("click", () => this.setPreset(button.dataset.view3dPreset));
    }
    for (const box of this.root.querySelectorAll("[data-view3d-layer]")) {
      box.addEventListener("change", () => this.applyLayers());
    }
    const expand = this.root.querySelector("[data-view3d-expand]");
    expand?.addEventListener("click", () => this.expand(expand.getAttribute("aria-pressed") !== "true"));
    const goalBox = this.root.querySelector("[data-view3d-goal]");
    goalBox?.addEventListener("change", () => this.goal.show(goalBox.checked ? this.arm?.toolPosition() ?? [0.2, 0.1, 0.1] : null,
      Number.isFinite(this.gripperPose?.pitch_rad) ? { pitchRad: this.gripperPose.pitch_rad, yawRad: this.gripperPose.yaw_rad } : null));
    const turnBox = this.root.querySelector("[data-view3d-goal-turn]");
    turnBox?.addEventListener("change", () => this.goal.setTurning(turnBox.checked));
    this.applyLayers();
  }

  /** As tall as the view column (scrolled to), or back under the video; the canvas follows (ResizeObserver). */
  expand(on) {
    const button = this.root.querySelector("[data-view3d-expand]");
    button?.setAttribute("aria-pressed", String(on));
    button?.classList.toggle("on", on);
    this.root.classList.toggle("expanded", on);
    if (on) this.root.scrollIntoView({ block: "start" });
  }

  layerOn(name) {
    const box = this.root.querySelector(`[data-view3d-layer='${name}']`);
    return box ? box.checked && !box.disabled : false;
  }

  applyLayers() {
    this.detections.group.visible = this.layerOn("blocks");
    this.trail.line.visible = this.layerOn("path");
    if (this.gripperBox) this.gripperBox.visible = this.layerOn("box");
    if (this.frustum) this.frustum.visible = this.layerOn("frustum");
    this.cloud.points.visible = this.layerOn("points");
    this.board.visible = !this.cloud.points.visible; // the points show the board; both would fight for the same pixels
    this.truthTimer = this.poll(this.truthTimer, this.layerOn("truth"), () => this.pollTruth(), TRUTH_POLL_MS);
    this.pointsTimer = this.poll(this.pointsTimer, this.cloud.points.visible, () => this.pollPoints(), POINTS_POLL_MS);
    this.truth.group.visible = this.layerOn("truth");
    this.invalidate();
  }

  /** A timer calling fn every periodMs while on (and once at once), cleared when off; returns the timer. */
  poll(timer, on, fn, periodMs) {
    if (on && !timer) {
      fn();
      return setInterval(fn, periodMs);
    }
    if (!on && timer) clearInterval(timer);
    return on ? timer : null;
  }

  async pollPoints() {
    if (!this.root.hidden && (await this.cloud.refresh())) this.invalidate();
  }

  async pollTruth() {
    try {
      const truth = await this.api.get("/api/sim/truth");
      if (this.truth.set(truthBoxes(truth.objects || [], this.workcell))) this.invalidate();
    } catch {
      // not a simulation, or the server is away: nothing to draw
    }
  }

  /** The backend ("sim" or "real"): the ground-truth toggle exists only in the simulation. */
  setBackend(backend) {
    const box = this.root.querySelector("[data-view3d-layer='truth']");
    if (!box) return;
    box.disabled = backend !== "sim";
    box.closest("label").hidden = backend !== "sim";
    if (this.detections) this.applyLayers();
  }

  setCalibration(calibration) {
    this.calibration = calibration;
    if (!this.scene) return;
    if (this.frustum) this.scene.remove(this.frustum);
    this.frustum = null;
    const ok = calibration?.calibrated && calibration.T_world_camera && calibration.K;
    this.root.querySelector("[data-view3d-preset='camera']").disabled = !ok;
    if (ok) {
      this.frustum = buildFrustum(calibration);
      this.frustum.visible = this.layerOn("frustum");
      this.scene.add(this.frustum);
    }
    this.invalidate();
  }

  setPreset(name) {
    const cell = this.workcell;
    const [x0, x1] = cell.board.x_range_m;
    const [y0, y1] = cell.board.y_range_m;
    const centre = new THREE.Vector3((x0 + x1) / 2, (y0 + y1) / 2, 0);
    const span = Math.max(x1 - x0, y1 - y0);
    this.camera.up.set(0, 0, 1);
    this.camera.fov = 45;
    if (name === "top") {
      this.camera.position.set(centre.x, centre.y - 0.001, 1.25 * span);
      this.camera.up.set(0, 1, 0);
    } else if (name === "camera" && this.calibration?.T_world_camera) {
      const preset = cameraPreset(this.calibration);
      this.camera.position.copy(preset.position);
      this.camera.up.copy(preset.up);
      this.camera.fov = preset.fovDeg;
      centre.copy(preset.target);
    } else {
      this.camera.position.set(centre.x, y0 - 0.9 * span, 0.55 * span);
      centre.z = 0.1;
    }
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.goal?.fitToView();
    this.preset = name;
    this.invalidate();
  }

  resize() {
    const width = Math.max(1, this.wrap.clientWidth);
    const height = Math.max(1, this.wrap.clientHeight);
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.invalidate();
  }

  invalidate() {
    this.dirty = true;
  }

  /** Telemetry (main.js calls this on every message): applied at the next animation frame, newest wins. */
  onTelemetry(status) {
    this.pendingTelemetry = { status, arrivedMs: performance.now() };
  }

  /** Pose the arm, move the path and the blocks to a telemetry message; true if anything drawn changed. */
  applyTelemetry({ status }) {
    let changed = false;
    this.gripperPose = status.gripper_pose ?? null;
    if (this.arm && Array.isArray(status.joints_rad)) {
      const width = status.gripper?.width_m;
      const last = this.lastDrawn;
      const same = last && last.width_m === width && last.joints_rad.length === status.joints_rad.length
        && last.joints_rad.every((v, i) => Math.abs(v - status.joints_rad[i]) < 1e-6);
      if (!same) {
        this.arm.setJoints(status.joints_rad, width);
        const tool = this.arm.toolPosition();
        this.trail.push(tool);
        this.lastDrawn = { time_s: status.time_s, joints_rad: status.joints_rad, width_m: width, tool_m: tool };
        changed = true;
      }
    }
    changed = this.showCommanded(status.state === "repeat" ? status.commanded_joints_rad : null) || changed;
    if (Array.isArray(status.detections) && this.workcell) {
      changed = this.detections.set(detectionBoxes(status.detections, this.workcell)) || changed;
    }
    return changed;
  }

  frame() {
    if (this.root.hidden) return;
    const started = performance.now();
    const intervalMs = 1000 / this.maxFps;
    if (started < this.nextFrameMs - 1) return; // the cap: the telemetry and the change wait for the next frame
    const pending = this.pendingTelemetry;
    this.pendingTelemetry = null;
    const moved = pending ? this.applyTelemetry(pending) : false;
    if (!moved && !this.dirty) return; // nothing new: no frame (telemetry repeats itself while the arm is still)
    this.renderer.render(this.scene, this.camera);
    this.dirty = false;
    this.nextFrameMs = Math.max(this.nextFrameMs, started - intervalMs) + intervalMs; // on average maxFps, not beyond
    const doneMs = performance.now();
    this.stats.frames += 1;
    this.stats.renderMs.push(doneMs - started);
    if (this.stats.armFirstFrameMs === null && this.arm?.loaded) this.stats.armFirstFrameMs = doneMs;
    if (moved && Number.isFinite(pending.status.time_s)) {
      this.stats.telemetryDelayMs.push((this.serverNowS() - pending.status.time_s) * 1000);
      this.stats.arrivalDelayMs.push(doneMs - pending.arrivedMs);
    }
    for (const list of [this.stats.telemetryDelayMs, this.stats.arrivalDelayMs, this.stats.renderMs]) {
      if (list.length > 600) list.splice(0, list.length - 600);
    }
  }

  show(visible) {
    this.root.hidden = !visible;
    if (visible) {
      this.resize();
      this.invalidate();
    }
  }
}
