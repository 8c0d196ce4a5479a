// The gripper's goal marker in the 3-D panel (issue 22 item 3): a ball the operator drags (three.js TransformControls,
// translate) to where the gripper should go, and turns (*Turn*: the same controls in rotate mode, two rings) to the
// gripper's yaw (the ring about the vertical: the fingers' closing axis' heading) and pitch (the ring about the
// horizontal axis across the arm's vertical plane: the approach axis below the horizontal, the station's pitch). An
// arrow shows the approach axis, a bar the closing axis. When a drag ends, onMoved(positionM, angles) hands the
// position (and, after a turn, {pitchRad, yawRad}) to the Go to panel, which asks the station for the move's own check
// (IK and safety, nothing moves) and shows the answer here: the goal arm at the solution's joints, see-through green,
// or none (the reason is in the panel).

import * as THREE from "three";
import { TransformControls } from "three/addons/controls/TransformControls.js";

const MARKER_RADIUS_M = 0.012;
const MARKER_COLOR = 0x4caf50;
const ARROW_LENGTH_M = 0.07;
const ALONG_VIEW_COS = 0.9; // an axis this close to the view direction gets no handle (its drag would run away)

/** An angle in (-π, π]. */
function wrapped(angle) {
  return Math.atan2(Math.sin(angle), Math.cos(angle));
}

export class GoalMarker {
  /** view: the View3D (its scene, camera, canvas, orbit controls, addArm and measured arm); onMoved(positionM, angles)
   * after each drag (angles: {pitchRad, yawRad} after a turn, else null: pitch and yaw as typed). */
  constructor(view, onMoved) {
    this.view = view;
    this.onMoved = onMoved;
    this.marker = new THREE.Mesh(new THREE.SphereGeometry(MARKER_RADIUS_M, 16, 12),
      new THREE.MeshLambertMaterial({ color: MARKER_COLOR }));
    this.marker.name = "goal marker";
    // The turn handles: `frame` at the marker, its x axis along the arm's vertical plane (away from the base axis),
    // `turn` in it at rest (identity) between drags; a drag of its y ring is a pitch change, of its z ring a yaw change.
    this.frame = new THREE.Group();
    this.turn = new THREE.Object3D();
    this.frame.add(this.turn);
    this.pose = { pitchRad: Math.PI / 2, yawRad: 0 }; // the goal's pitch and yaw the arrow shows
    this.turnStart = null; // the pose when a turn began
    this.arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), ARROW_LENGTH_M, MARKER_COLOR);
    this.closing = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
      new THREE.LineBasicMaterial({ color: 0xffffff }));

    this.controls = this.makeControls("translate", this.marker);
    this.controls.addEventListener("objectChange", () => this.placeFrame());
    this.rotator = this.makeControls("rotate", this.turn);
    this.rotator.setSpace("local");
    this.rotator.showX = false; // no roll: the station's pose has none
    this.rotator.showE = false;
    this.rotator.showXYZE = false;
    this.rotator.addEventListener("objectChange", () => this.turned());
    this.turning = false; // the rotate handles are the ones shown (else the translate ones)
    this.solution = null; // the goal arm (ArmFigure) of the last checked position
    this.shown = false;
  }

  makeControls(mode, object) {
    const controls = new TransformControls(this.view.camera, this.view.renderer.domElement);
    controls.enabled = false; // until shown: its handles, never placed, would take clicks around the origin
    controls.setMode(mode);
    controls.attach(object);
    controls.addEventListener("change", () => this.view.invalidate());
    controls.addEventListener("dragging-changed", (e) => {
      this.view.controls.enabled = !e.value; // the orbit waits while the marker is dragged
      if (mode === "rotate") this.turnStart = e.value ? { ...this.pose } : null;
      if (e.value) return;
      if (mode === "rotate") {
        this.turn.quaternion.identity(); // the handles back at rest; the pose keeps the turn
        this.onMoved(this.positionM(), { ...this.pose });
      } else {
        this.onMoved(this.positionM(), null);
      }
    });
    return controls;
  }

  /** Handles only for the axes across the view: looking down, x and y (the board's plane); from the front, x and z.
   * (An axis pointing at the viewer is a handle under the centre whose drag runs off along the view.) */
  fitToView() {
    const view = new THREE.Vector3();
    this.view.camera.getWorldDirection(view);
    this.controls.showX = Math.abs(view.x) < ALONG_VIEW_COS;
    this.controls.showY = Math.abs(view.y) < ALONG_VIEW_COS;
    this.controls.showZ = Math.abs(view.z) < ALONG_VIEW_COS;
  }

  /** True while the pointer is on one of the marker's handles (a click there is not a pick on the board). */
  get active() {
    const on = (c) => c.enabled && (c.axis !== null || c.dragging);
    return this.shown && (on(this.controls) || on(this.rotator));
  }

  positionM() {
    return this.marker.position.toArray();
  }

  /** The base axis' world position (the first joint's origin on the measured arm: the server's URDF). */
  baseM() {
    const arm = this.view.arm;
    const name = this.view.armDescription?.joint_names?.[0];
    const joint = arm && name ? arm.robot.joints[name] : null;
    return joint ? joint.getWorldPosition(new THREE.Vector3()) : new THREE.Vector3();
  }

  /** The turn frame at the marker, its x axis away from the base axis in the board's plane; the arrow redrawn. */
  placeFrame() {
    const base = this.baseM();
    const p = this.marker.position;
    this.frame.position.copy(p);
    this.frame.rotation.set(0, 0, Math.atan2(p.y - base.y, p.x - base.x));
    this.frame.updateMatrixWorld(true);
    this.drawPose();
  }

  /** During a turn: the ring dragged (the rotate controls' axis) and its angle so far give the new pitch or yaw. */
  turned() {
    if (!this.turnStart) return;
    const x = new THREE.Vector3(1, 0, 0).applyQuaternion(this.turn.quaternion);
    if (this.rotator.axis === "Y") this.pose.pitchRad = wrapped(this.turnStart.pitchRad + Math.atan2(-x.z, x.x));
    if (this.rotator.axis === "Z") this.pose.yawRad = wrapped(this.turnStart.yawRad + Math.atan2(x.y, x.x));
    this.drawPose();
  }

  /** The approach axis (arrow) at the pose's pitch in the frame's vertical plane; the closing axis (bar) at its yaw. */
  drawPose() {
    const { pitchRad, yawRad } = this.pose;
    const along = new THREE.Vector3(Math.cos(pitchRad), 0, -Math.sin(pitchRad)).applyQuaternion(this.frame.quaternion);
    this.arrow.position.copy(this.marker.position);
    this.arrow.setDirection(along);
    const half = new THREE.Vector3(Math.cos(yawRad), Math.sin(yawRad), 0).multiplyScalar(ARROW_LENGTH_M / 2);
    const p = this.marker.position;
    this.closing.geometry.setFromPoints([p.clone().sub(half), p.clone().add(half)]);
    this.view.invalidate();
  }

  /** Turn handles (true) or move handles (false). */
  setTurning(on) {
    this.turning = Boolean(on);
    if (this.shown) this.show(this.positionM(), null);
  }

  /** Show the marker at positionM (m), its arrow at pose ({pitchRad, yawRad}; null: as it was), or hide it (null),
   * with any goal arm shown for it. */
  show(positionM, pose = null) {
    const scene = this.view.scene;
    scene.remove(this.marker, this.frame, this.arrow, this.closing, this.controls.getHelper(), this.rotator.getHelper());
    this.controls.enabled = false;
    this.rotator.enabled = false;
    if (positionM) {
      this.marker.position.set(...positionM);
      if (pose) this.pose = { pitchRad: pose.pitchRad, yawRad: pose.yawRad };
      const active = this.turning ? this.rotator : this.controls;
      scene.add(this.marker, this.frame, this.arrow, this.closing, active.getHelper());
      active.enabled = true;
      this.shown = true;
      this.placeFrame();
      this.fitToView();
    } else {
      this.shown = false;
      this.showSolution(null);
    }
    this.view.invalidate();
  }

  /** The goal arm at qRad (the station's solution for the marker), or none (null: no solution). */
  showSolution(qRad) {
    if (this.solution) this.view.removeArm(this.solution);
    this.solution = null;
    if (qRad && this.view.armDescription) {
      this.solution = this.view.addArm({ opacity: 0.35, color: MARKER_COLOR });
      this.solution.setJoints(qRad, null);
    }
    this.view.invalidate();
  }
}
