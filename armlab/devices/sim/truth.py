"""SimTruth: the simulated workcell's ground-truth queries (for tests, scorers and the judge): the true
gripper point and its recorded path, the objects' poses, the gripper's contacts, the feeder's state,
the true camera. Mixed into SimWorkcell, whose model and data it reads under the workcell's lock; the
devices never see any of it."""

from __future__ import annotations

import mujoco
import numpy as np

from armlab.devices.sim.path import MAX_DURATION_S, PathRecorder
from armlab.devices.sim.suction import lip_touching
from armlab.errors import InvalidInput


class SimTruth:
    """Ground truth of a SimWorkcell (the methods read its _model/_data and scene index under self.lock)."""

    @property
    def rig(self) -> dict | None:
        """The real arm's drawn rig (joint zero offsets, link length changes, base shift and yaw), None when ideal."""
        real = getattr(self._geometry, "real", None)
        return None if real is None else real.rig.to_dict()

    def link_positions(self) -> np.ndarray:
        """The links' true angles against the nominal arm (call under the lock): the motors plus (real arm) the
        rig's zero offsets and the gears' play and deflection. Ideal: the joints."""
        real = getattr(self._geometry, "real", None)
        if real is None:
            return self.arm_positions()
        return self.arm_positions() + real.rig.joint_offset_rad + self._data.qpos[self._gear_qpos]

    def gripper_point_m(self) -> np.ndarray:
        """True world position of the gripper point (for tests and scorers)."""
        with self.lock:
            return self._data.site_xpos[self._gripper_site].copy()

    def gripper_marker_m(self) -> np.ndarray:
        """True world position of the centre of the gripper tag's face (the workcell's gripper.marker), for
        tests of finding the gripper in the camera. ValueError when the workcell has no marker."""
        import mujoco

        with self.lock:
            geom = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_GEOM, "gripper_marker")
            if geom < 0:
                raise ValueError("this workcell has no gripper marker")
            return self._data.geom_xpos[geom] + self._data.geom_xmat[geom].reshape(3, 3)[:, 2] * self._model.geom_size[geom][2]

    def contact_depth_at_mm(self, q_rad, geoms, against=("board", "table")) -> float:
        """How far (mm, > 0 = into) the named geoms of the arm would reach into the `against` geoms with the arm
        standing at joint vector q_rad (the model's other joints at their defaults, a scratch MjData: the running
        simulation is not touched). Ground truth for checks that keep the arm out of the board."""
        geoms, against = set(geoms), set(against)
        data = mujoco.MjData(self._model)
        for name, value in zip(self._geometry.joint_names, np.asarray(q_rad, float)):
            data.qpos[self._model.joint(name).qposadr[0]] = value
        mujoco.mj_forward(self._model, data)
        deepest = 0.0
        for contact in data.contact[: data.ncon]:
            names = {mujoco.mj_id2name(self._model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in (contact.geom1, contact.geom2)}
            if names & geoms and names & against:
                deepest = max(deepest, -float(contact.dist) * 1000.0)
        return deepest

    def start_path_recording(self, period_s: float = 0.05, max_duration_s: float = MAX_DURATION_S) -> None:
        """Record the gripper point every period_s of simulated time from now on (inside the physics
        stepping, so fast mode records too), replacing any earlier recording. Memory is bounded: beyond
        max_duration_s of samples the oldest are dropped."""
        recorder = PathRecorder(period_s, max_duration_s)  # validates before anything changes
        with self.lock:
            recorder.record(float(self._data.time), self._data.site_xpos[self._gripper_site])
            self._path = recorder

    def stop_path_recording(self) -> np.ndarray:
        """Stop recording; returns the samples (as gripper_path())."""
        with self.lock:
            path = self.gripper_path()
            self._path = None
            return path

    def start_joint_recording(self, max_ticks: int = 200_000) -> None:
        """Record the arm at every control tick from now on (simulated time, fast mode too): the servos'
        position and velocity references and the measured positions and velocities, to measure motion on the sim's clock.
        At most max_ticks are kept (then recording stops adding)."""
        if not (isinstance(max_ticks, int) and 0 < max_ticks <= 10_000_000):
            raise InvalidInput(f"max_ticks must be an integer in 1..10000000, got {max_ticks!r}")
        with self.lock:
            self._joint_trace = {"rows": [], "max": max_ticks}

    def stop_joint_recording(self) -> dict[str, np.ndarray]:
        """Stop recording; {"time_s": (N,), "reference_rad", "reference_velocity_rad_s", "position_rad",
        "velocity_rad_s": (N, dof)}."""
        with self.lock:
            trace, self._joint_trace = getattr(self, "_joint_trace", None), None
        rows = np.asarray(trace["rows"] if trace else np.empty((0, 1)), dtype=float)
        dof = (rows.shape[1] - 1) // 4 if rows.size else 0
        column = [1 + k * dof for k in range(5)]
        return {"time_s": rows[:, 0] if rows.size else np.empty(0), "reference_rad": rows[:, column[0] : column[1]],
                "reference_velocity_rad_s": rows[:, column[1] : column[2]], "position_rad": rows[:, column[2] : column[3]],
                "velocity_rad_s": rows[:, column[3] : column[4]]}

    def _record_joints(self) -> None:
        """At a control tick (under the lock): one row of the joint recording, if one runs."""
        trace = getattr(self, "_joint_trace", None)
        if trace is not None and len(trace["rows"]) < trace["max"]:
            trace["rows"].append((float(self._data.time), *self.arm_reference(), *self.arm_reference_velocity(),
                                  *self.arm_positions(), *self.arm_velocities()))

    def gripper_path(self) -> np.ndarray:
        """(N, 4) samples (sim_time_s, x, y, z) of the gripper point, oldest first; (0, 4) if not recording.
        Each sample is gripper_point_m() as it read at that simulated time."""
        with self.lock:
            return self._path.samples() if self._path is not None else np.empty((0, 4))

    def _suction_truth(self) -> dict:
        """Ground truth of the cup (under the lock): the objects the lip touches, what the vacuum holds."""
        data = self._data
        return {
            "left_contacts": [], "right_contacts": [],
            "lip_contacts": lip_touching(self._model, self._data, self._lip_geoms, self._body_to_object),
            "holding_id": self.gripper.holding_id,
            "vacuum": self.gripper.command == "grasp",
            "width_m": 0.0,
            "position_m": data.site_xpos[self._gripper_site].tolist(),
            "quat_wxyz": data.xquat[self._gripper_body].tolist(),
        }

    def feeder_status(self) -> dict | None:
        """to_the_sky feeder: {spot_m, count, fed, remaining}, or None if the scene has no feeder."""
        with self.lock:
            return self._feeder.status() if self._feeder is not None else None

    def camera_pose_error(self, T_world_camera) -> tuple[float, float]:
        """Position (m) and rotation (deg) error of a camera pose (e.g. a calibration's) against the true camera."""
        with self.lock:
            truth = self._T_world_camera.copy()
        T = np.asarray(T_world_camera, dtype=float)
        position_m = float(np.linalg.norm(T[:3, 3] - truth[:3, 3]))
        cos = (np.trace(T[:3, :3].T @ truth[:3, :3]) - 1.0) / 2.0
        return position_m, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))

    def camera_intrinsics(self, camera_name: str = "overhead") -> dict:
        """fx, fy, cx, cy (OpenCV: pixel centres at integers) of the frustum MuJoCo draws the camera with."""
        import mujoco

        with self.lock:
            model = self._model
            data = mujoco.MjData(model)
            mujoco.mj_forward(model, data)
            scene = mujoco.MjvScene(model, maxgeom=2000)
            camera = mujoco.MjvCamera()
            camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            camera.fixedcamid = model.camera(camera_name).id
            mujoco.mjv_updateScene(model, data, mujoco.MjvOption(), None, camera, mujoco.mjtCatBit.mjCAT_ALL, scene)
            width, height = model.cam_resolution[camera.fixedcamid]
        gl = scene.camera[0]
        left, right = gl.frustum_center - gl.frustum_width, gl.frustum_center + gl.frustum_width
        return {"fx": width * gl.frustum_near / (right - left), "fy": height * gl.frustum_near / (gl.frustum_top - gl.frustum_bottom),
                "cx": -left / (right - left) * width - 0.5, "cy": gl.frustum_top / (gl.frustum_top - gl.frustum_bottom) * height - 0.5}

    def truth(self) -> dict:
        """Ground truth: camera (K, size, true T_world_camera), objects (pose; feeder blocks only once
        fed, as feed_0, feed_1, ...), the feeder's state (None without one), gripper contacts, arm."""
        with self.lock:
            data = self._data
            objects = []
            on_board = [(self._object_bodies[obj.id], obj) for obj in self._scene.objects]
            if self._feeder is not None:
                on_board += self._feeder.fed_bodies()
            for body, obj in on_board:
                objects.append(obj.posed_dict(data.xpos[body], data.xquat[body]))
            if self._suction:
                state = self._suction_truth()
            contacts = {"left_pad": set(), "right_pad": set()}
            for contact in data.contact[: data.ncon]:
                for pad_geom, other_geom in ((contact.geom1, contact.geom2), (contact.geom2, contact.geom1)):
                    pad = self._pad_geoms.get(int(pad_geom))
                    obj_id = self._body_to_object.get(int(self._model.geom_bodyid[other_geom]))
                    if pad is not None and obj_id is not None:
                        contacts[pad].add(obj_id)
            both = sorted(contacts["left_pad"] & contacts["right_pad"])
            left, right = self.finger_positions() if not self._suction else (0.0, 0.0)
            state = state if self._suction else {
                "left_contacts": sorted(contacts["left_pad"]),
                "right_contacts": sorted(contacts["right_pad"]),
                "holding_id": both[0] if both and self.gripper.command == "grasp" else None,
                "width_m": left + right - 2.0 * self._geometry.pad_thickness_m,
                "position_m": data.site_xpos[self._gripper_site].tolist(),
                "quat_wxyz": data.xquat[self._gripper_body].tolist(),
            }
            arm = {"joint_names": list(self._geometry.joint_names), "position_rad": self.arm_positions().tolist()}
            if self.rig is not None:  # the real arm: the links' true angles and the rig drawn for this seed
                arm.update(link_rad=self.link_positions().tolist(), rig=self.rig)
            sim_time = float(data.time)
            feeder = self._feeder.status() if self._feeder is not None else None
        K = self.camera.intrinsics.K
        return {
            "camera": {
                "K": K.tolist(),
                "width": self.camera.intrinsics.width,
                "height": self.camera.intrinsics.height,
                "T_world_camera": self._T_world_camera.tolist(),
                "dist": list(self.camera.intrinsics.dist),
            },
            "objects": objects,
            "feeder": feeder,
            "gripper": state,
            "arm": arm,
            "time_s": sim_time,
        }
