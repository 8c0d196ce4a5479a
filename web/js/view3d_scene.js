// Builders for the 3-D panel's scene (three.js, world = board frame, z up, metres). Every size and place comes
// from the server (GET /api/view3d/scene's workcell, telemetry, the calibration), none is written here.

import * as THREE from "three";
import { STLLoader } from "three/addons/loaders/STLLoader.js";
import URDFLoader from "urdf-loader";

const BOARD_COLOR = 0x2f6b3a;
const LINE_COLOR = 0xd8e4d8;
const GEOMETRIES = new Map(); // mesh url → Promise<BufferGeometry>, shared by every arm figure (measured, goal, ...)

/** The geometry of a binary STL, parsed once per url: from `buffers` (url → Promise<ArrayBuffer>) or fetched. */
function stlGeometry(url, buffers) {
  if (!GEOMETRIES.has(url)) {
    const buffer = buffers?.get(url) ?? fetch(url).then((r) => {
      if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
      return r.arrayBuffer();
    });
    GEOMETRIES.set(url, buffer.then((data) => new STLLoader().parse(data)));
  }
  return GEOMETRIES.get(url);
}

/** One arm drawn from the server's URDF: the measured arm now, a goal arm later (a second instance, ghosted). */
export class ArmFigure {
  /** highlight: {links, color}: those links (their own visuals, not the links after them) drawn opaque in color. */
  constructor(arm, { opacity = 1.0, color = null, onLoad = null, meshBuffers = null, highlight = null } = {}) {
    this.arm = arm;
    const manager = new THREE.LoadingManager();
    manager.onLoad = () => {
      this.styleMaterials(opacity, color);
      if (highlight) for (const link of highlight.links) this.paintLink(link, highlight.color);
      this.loaded = true;
      onLoad?.(this);
    };
    const loader = new URDFLoader(manager);
    loader.parseVisual = true;
    loader.parseCollision = false;
    loader.loadMeshCb = (url, loadingManager, material, done) => {
      loadingManager.itemStart(url);
      stlGeometry(url, meshBuffers)
        .then((geometry) => done(new THREE.Mesh(geometry, material)))
        .catch((error) => done(null, error))
        .finally(() => loadingManager.itemEnd(url));
    };
    this.robot = loader.parse(arm.urdf, "");
    this.loaded = false;
    // An arm without mesh files has nothing for the manager to wait for.
    if (!arm.urdf.includes("<mesh")) queueMicrotask(() => manager.onLoad());
  }

  styleMaterials(opacity, color) {
    this.robot.traverse((node) => {
      if (!node.isMesh) return;
      const material = node.material.clone();
      if (color !== null) material.color = new THREE.Color(color);
      material.transparent = opacity < 1.0;
      material.opacity = opacity;
      material.depthWrite = opacity >= 1.0;
      node.material = material;
    });
  }

  /** The meshes of one link, not those of the links after it (a child joint ends the walk). */
  linkMeshes(name) {
    const meshes = [];
    const walk = (node) => {
      for (const child of node.children) {
        if (child.isURDFJoint) continue;
        if (child.isMesh) meshes.push(child);
        walk(child);
      }
    };
    const link = this.robot.links[name];
    if (link) walk(link);
    return meshes;
  }

  paintLink(name, color) {
    for (const mesh of this.linkMeshes(name)) {
      const material = mesh.material.clone();
      material.color = new THREE.Color(color);
      material.transparent = false;
      material.opacity = 1.0;
      material.depthWrite = true;
      mesh.material = material;
    }
  }

  /** Joint angles (radians, the arm's joint order) and, for fingers, the gripper's pad span width_m. */
  setJoints(jointsRad, gripperWidthM) {
    const names = this.arm.joint_names;
    for (let i = 0; i < names.length && i < jointsRad.length; i += 1) this.robot.setJointValue(names[i], jointsRad[i]);
    const fingers = this.arm.fingers;
    if (fingers && Number.isFinite(gripperWidthM)) {
      const offsetM = gripperWidthM / 2 + fingers.pad_thickness_m; // each finger's offset from the centre line
      for (const joint of fingers.joints) this.robot.setJointValue(joint, offsetM);
    }
  }

  /** World position of the tool point [x, y, z] (metres). */
  toolPosition() {
    const link = this.robot.links[this.arm.tool_link];
    link.updateWorldMatrix(true, false);
    const p = new THREE.Vector3().setFromMatrixPosition(link.matrixWorld);
    return [p.x, p.y, p.z];
  }
}

function lineSegments(points, color, opacity = 1.0) {
  const geometry = new THREE.BufferGeometry().setFromPoints(points.map((p) => new THREE.Vector3(...p)));
  const material = new THREE.LineBasicMaterial({ color, transparent: opacity < 1, opacity });
  return new THREE.LineSegments(geometry, material);
}

/** The board (its rectangle), its grid, the calibration tags and the places, from the workcell. */
export function buildWorkcell(workcell) {
  const group = new THREE.Group();
  group.name = "workcell";
  const [x0, x1] = workcell.board.x_range_m;
  const [y0, y1] = workcell.board.y_range_m;
  const board = new THREE.Mesh(
    new THREE.PlaneGeometry(x1 - x0, y1 - y0),
    new THREE.MeshLambertMaterial({ color: BOARD_COLOR }),
  );
  board.position.set((x0 + x1) / 2, (y0 + y1) / 2, -0.0005);
  board.name = "board";
  group.add(board);
  const grid = workcell.board.grid;
  const segments = [];
  const lift = 0.0005;
  for (let x = grid.x_m[0]; x <= grid.x_m[1] + 1e-9; x += grid.step_m) segments.push([x, y0, lift], [x, y1, lift]);
  for (let y = grid.y_m[0]; y <= grid.y_m[1] + 1e-9; y += grid.step_m) segments.push([x0, y, lift], [x1, y, lift]);
  const gridLines = lineSegments(segments, LINE_COLOR, 0.35);
  gridLines.name = "grid";
  group.add(gridLines);
  const tagSize = workcell.board_tags.size_m;
  for (const [id, [x, y]] of Object.entries(workcell.board_tags.centres_m)) {
    const tag = new THREE.Mesh(new THREE.PlaneGeometry(tagSize, tagSize), new THREE.MeshBasicMaterial({ color: 0x111111 }));
    tag.position.set(x, y, 0.001);
    tag.name = `tag ${id}`;
    const border = new THREE.Mesh(
      new THREE.PlaneGeometry(tagSize * 1.5, tagSize * 1.5),
      new THREE.MeshBasicMaterial({ color: 0xffffff }),
    );
    border.position.set(x, y, 0.0008);
    group.add(border, tag);
  }
  for (const [name, [x, y]] of Object.entries(workcell.places_m || {})) {
    const ring = new THREE.Mesh(
      new THREE.RingGeometry(0.018, 0.022, 32),
      new THREE.MeshBasicMaterial({ color: 0xffd54a, side: THREE.DoubleSide }),
    );
    ring.position.set(x, y, 0.0012);
    ring.name = `place ${name}`;
    group.add(ring);
  }
  const box = workcell.gripper_box_m;
  if (box) {
    const size = [0, 1, 2].map((i) => box.max_m[i] - box.min_m[i]);
    const edges = new THREE.LineSegments(
      new THREE.EdgesGeometry(new THREE.BoxGeometry(...size)),
      new THREE.LineBasicMaterial({ color: 0xba68c8, transparent: true, opacity: 0.7 }),
    );
    edges.position.set(...[0, 1, 2].map((i) => (box.max_m[i] + box.min_m[i]) / 2));
    edges.name = "gripper box";
    group.add(edges);
  }
  return group;
}

/** Boxes for objects: [{position_m (centre), yaw_rad, size_m [x, y, z], color}]; wire: outlines only. */
export class BoxSet {
  constructor(name, { wire = false } = {}) {
    this.group = new THREE.Group();
    this.group.name = name;
    this.wire = wire;
    this.key = "";
  }

  set(boxes) {
    const key = JSON.stringify(boxes.map((b) => [b.color, ...b.position_m.map((v) => v.toFixed(3)), b.yaw_rad.toFixed(2)])); // mm, ~0.6 deg
    if (key === this.key) return false;
    this.key = key;
    for (const child of [...this.group.children]) {
      this.group.remove(child);
      child.geometry.dispose();
      child.material.dispose();
    }
    for (const box of boxes) {
      const geometry = new THREE.BoxGeometry(...box.size_m);
      const color = new THREE.Color(box.color || "gray");
      const mesh = this.wire
        ? new THREE.LineSegments(new THREE.EdgesGeometry(geometry), new THREE.LineBasicMaterial({ color }))
        : new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color }));
      if (this.wire) geometry.dispose();
      mesh.position.set(...box.position_m);
      if (box.quat_wxyz) {
        const [w, x, y, z] = box.quat_wxyz;
        mesh.quaternion.set(x, y, z, w);
      } else {
        mesh.rotation.z = box.yaw_rad;
      }
      this.group.add(mesh);
    }
    return true;
  }
}

/** Detections (telemetry) as boxes: the edge of their size from the workcell, the centre below the top face. */
export function detectionBoxes(detections, workcell) {
  return detections.map((d) => {
    const edge = workcell.block_edges_m[d.size] ?? Math.max(d.height_m, 0.01);
    const height = d.height_m > 0 ? Math.min(d.height_m, edge) : edge;
    const [x, y, z] = d.position_m;
    return { position_m: [x, y, z - height / 2], yaw_rad: d.yaw_rad, size_m: [edge, edge, height], color: d.color };
  });
}

/** Ground-truth objects (GET /api/sim/truth): body centre, quaternion, their dimensions or the block edge. */
export function truthBoxes(objects, workcell) {
  return objects.map((o) => {
    const edge = workcell.block_edges_m[o.size] ?? 0.03;
    const size = Array.isArray(o.dimensions_m) ? o.dimensions_m : [edge, edge, edge];
    return { position_m: o.position_m, yaw_rad: o.yaw_rad ?? 0, quat_wxyz: o.quat_wxyz, size_m: size, color: o.color };
  });
}

/** The calibrated camera: its frustum from the optical centre to where the image corners meet the board (z = 0). */
export function buildFrustum(calibration) {
  const T = calibration.T_world_camera;
  const K = calibration.K;
  const centre = [T[0][3], T[1][3], T[2][3]];
  const corners = [
    [0, 0],
    [calibration.width, 0],
    [calibration.width, calibration.height],
    [0, calibration.height],
  ].map(([u, v]) => {
    const ray = [(u - K[0][2]) / K[0][0], (v - K[1][2]) / K[1][1], 1]; // camera frame
    const world = [0, 1, 2].map((r) => T[r][0] * ray[0] + T[r][1] * ray[1] + T[r][2] * ray[2]);
    const s = world[2] < -1e-6 ? -centre[2] / world[2] : 0.5; // to the board, else half a metre
    return [0, 1, 2].map((r) => centre[r] + s * world[r]);
  });
  const segments = [];
  for (let i = 0; i < 4; i += 1) segments.push(centre, corners[i], corners[i], corners[(i + 1) % 4]);
  const frustum = lineSegments(segments, 0x4fc3f7, 0.8);
  frustum.name = "frustum";
  return frustum;
}

/** The calibrated camera's pose and field of view for a THREE.PerspectiveCamera (OpenCV axes → three's). */
export function cameraPreset(calibration) {
  const T = calibration.T_world_camera;
  const col = (c) => new THREE.Vector3(T[0][c], T[1][c], T[2][c]);
  const position = col(3);
  const forward = col(2); // OpenCV +z looks forward; +y is down in the image
  const up = col(1).negate();
  const fovDeg = THREE.MathUtils.radToDeg(2 * Math.atan(calibration.height / 2 / calibration.K[1][1]));
  return { position, target: position.clone().add(forward.multiplyScalar(0.5)), up, fovDeg };
}

/** The gripper's recent path: a line through the last `capacity` tool positions. */
export class Trail {
  constructor(capacity = 600) {
    this.capacity = capacity;
    this.positions = new Float32Array(capacity * 3);
    this.count = 0;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(this.positions, 3));
    geometry.setDrawRange(0, 0);
    this.line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: 0xff7043 }));
    this.line.name = "trail";
    this.line.frustumCulled = false;
  }

  push([x, y, z]) {
    if (this.count > 0) {
      const i = (this.count - 1) * 3;
      const dx = x - this.positions[i];
      const dy = y - this.positions[i + 1];
      const dz = z - this.positions[i + 2];
      if (dx * dx + dy * dy + dz * dz < 1e-6) return false; // still: nothing new to draw
    }
    if (this.count === this.capacity) {
      this.positions.copyWithin(0, 3);
      this.count -= 1;
    }
    this.positions.set([x, y, z], this.count * 3);
    this.count += 1;
    const geometry = this.line.geometry;
    geometry.attributes.position.needsUpdate = true;
    geometry.setDrawRange(0, this.count);
    return true;
  }
}

/** The depth image as coloured points (GET /api/view3d/points: float32 xyz × N, then uint8 rgb × N). */
export class PointCloud {
  constructor() {
    this.geometry = new THREE.BufferGeometry();
    this.points = new THREE.Points(this.geometry, new THREE.PointsMaterial({ size: 4, sizeAttenuation: false, vertexColors: true }));
    this.points.name = "points";
    this.points.frustumCulled = false;
    this.inFlight = false;
  }

  /** Fetch the newest cloud (one request at a time); resolves true once drawn anew. */
  async refresh(stepPx = 8) {
    if (this.inFlight) return false;
    this.inFlight = true;
    try {
      const response = await fetch(`/api/view3d/points?step_px=${stepPx}`, { cache: "no-store" });
      if (!response.ok) return false;
      const count = Number(response.headers.get("X-Points"));
      const data = await response.arrayBuffer();
      if (!Number.isFinite(count) || data.byteLength !== count * 15) return false;
      const xyz = new Float32Array(data, 0, count * 3);
      const rgb = new Uint8Array(data, count * 12, count * 3);
      this.geometry.setAttribute("position", new THREE.BufferAttribute(xyz, 3));
      this.geometry.setAttribute("color", new THREE.BufferAttribute(rgb, 3, true));
      this.count = count;
      return true;
    } catch {
      return false;
    } finally {
      this.inFlight = false;
    }
  }
}
