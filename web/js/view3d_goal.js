// The gripper's goal marker in the 3-D panel (issue 22 item 3): a ball the operator drags (three.js TransformControls,
// translate) to where the gripper should go. When a drag ends, onMoved(positionM) hands its position to the Go to
// panel, which asks the station for the move's own check (IK and safety, nothing moves) and shows the answer here:
// the goal arm at the solution's joints, see-through green, or none (the reason is in the panel).

import * as THREE from "three";
import { TransformControls } from "three/addons/controls/TransformControls.js";

const MARKER_RADIUS_M = 0.012;
const MARKER_COLOR = 0x4caf50;
const ALONG_VIEW_COS = 0.9; // an axis this close to the view direction gets no handle (its drag would run away)

export class GoalMarker {
  /** view: the View3D (its scene, camera, canvas, orbit controls and addArm); onMoved(positionM) after each drag. */
  constructor(view, onMoved) {
    this.view = view;
    this.onMoved = onMoved;
    this.marker = new THREE.Mesh(new THREE.SphereGeometry(MARKER_RADIUS_M, 16, 12),
      new THREE.MeshLambertMaterial({ color: MARKER_COLOR }));
    this.marker.name = "goal marker";
    this.controls = new TransformControls(view.camera, view.renderer.domElement);
    this.controls.enabled = false; // until shown: its handles, never placed, would take clicks around the origin
    this.controls.setMode("translate");
    this.controls.attach(this.marker);
    this.controls.addEventListener("change", () => view.invalidate());
    this.controls.addEventListener("dragging-changed", (e) => {
      view.controls.enabled = !e.value; // the orbit waits while the marker is dragged
      if (!e.value) this.onMoved(this.positionM());
    });
    this.solution = null; // the goal arm (ArmFigure) of the last checked position
    this.shown = false;
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
    return this.shown && (this.controls.axis !== null || this.controls.dragging);
  }

  positionM() {
    return this.marker.position.toArray();
  }

  /** Show the marker at positionM (m), or hide it (null), with any goal arm shown for it. */
  show(positionM) {
    const scene = this.view.scene;
    if (positionM) {
      this.marker.position.set(...positionM);
      if (!this.shown) scene.add(this.marker, this.controls.getHelper());
      this.shown = true;
      this.controls.enabled = true;
      this.fitToView();
    } else {
      scene.remove(this.marker, this.controls.getHelper());
      this.shown = false;
      this.controls.enabled = false;
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
