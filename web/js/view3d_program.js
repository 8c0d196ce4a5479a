// Teach in 3-D (issue 22 item 4): the selected program's waypoints as see-through arms along the gripper's path
// through them (the server's gripper_position_m of each waypoint); the waypoint selected in the table stands out, and a
// click on a waypoint's arm (pickAt) chooses its row in the table.

import * as THREE from "three";

const MAX_ARMS = 24; // a long program shows its first waypoints as arms (the path line shows them all)
const WAYPOINT = { opacity: 0.15, color: 0x9575cd };
const SELECTED = { opacity: 0.5, color: 0xffca28 };

export class ProgramFigures {
  /** view: the View3D (addArm / removeArm, its scene). */
  constructor(view) {
    this.view = view;
    this.waypoints = [];
    this.arms = []; // ArmFigure per shown waypoint
    this.line = null;
    this.selected = -1;
  }

  /** The program's waypoints ({joints_rad, gripper_position_m}), or none (null / []). */
  show(waypoints) {
    this.clear();
    this.waypoints = Array.isArray(waypoints) ? waypoints : [];
    if (!this.waypoints.length || !this.view.armDescription) return;
    this.arms = this.waypoints.slice(0, MAX_ARMS).map((w) => this.arm(w, WAYPOINT));
    const points = this.waypoints.map((w) => w.gripper_position_m);
    if (points.every(Array.isArray)) {
      this.line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(points.map((p) => new THREE.Vector3(...p))),
        new THREE.LineDashedMaterial({ color: WAYPOINT.color, dashSize: 0.01, gapSize: 0.006 }));
      this.line.computeLineDistances();
      this.view.scene.add(this.line);
    }
    this.view.invalidate();
  }

  arm(waypoint, style) {
    const figure = this.view.addArm(style);
    figure.setJoints(waypoint.joints_rad, null);
    return figure;
  }

  /** The waypoint (0-based index) whose arm the ray (a THREE.Raycaster) meets nearest, else -1. */
  pickAt(raycaster) {
    let best = { index: -1, distance: Infinity };
    this.arms.forEach((figure, index) => {
      const [hit] = raycaster.intersectObject(figure.robot, true);
      if (hit && hit.distance < best.distance) best = { index, distance: hit.distance };
    });
    return best.index;
  }

  /** Waypoint index (0-based) drawn as selected; -1: none. */
  select(index) {
    const restyle = (i, style) => {
      if (i < 0 || i >= this.arms.length) return;
      this.view.removeArm(this.arms[i]);
      this.arms[i] = this.arm(this.waypoints[i], style);
    };
    if (index === this.selected) return;
    restyle(this.selected, WAYPOINT);
    this.selected = index;
    restyle(index, SELECTED);
    this.view.invalidate();
  }

  clear() {
    for (const figure of this.arms) this.view.removeArm(figure);
    this.arms = [];
    this.selected = -1;
    if (this.line) {
      this.view.scene.remove(this.line);
      this.line.geometry.dispose();
      this.line.material.dispose();
      this.line = null;
    }
    this.view.invalidate();
  }
}
