"""SimCameraRig: the simulated workcell's camera rig, mixed into SimWorkcell: knocking the camera mount and
placing the intrinsics checkerboard. Both change the MuJoCo model in place and survive scene changes."""

from __future__ import annotations

import mujoco
import numpy as np

from armlab.devices.sim.checkerboard import BODY_NAME as CHECKERBOARD
from armlab.devices.sim.checkerboard import PARKED_POSITION_M, checked_pose
from armlab.devices.sim.mjcf import CAMERA_NAME
from armlab.kinematics.rotations import quat_wxyz_from_matrix, rotation_from_rotvec


class SimCameraRig:
    """The camera mount and the checkerboard of a SimWorkcell (its _model/_data, camera and workcell, under self.lock)."""

    def bump_camera(self, T_old_new: np.ndarray) -> None:
        """Move the camera mount by T_old_new (4x4, in the camera's own OpenCV frame), as a knock on
        the rig would: later frames and truth() use the new pose; scene changes keep it."""
        with self.lock:
            self._T_world_camera = self._T_world_camera @ np.asarray(T_old_new, dtype=float)
            camera_id = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_CAMERA, CAMERA_NAME)
            self._model.cam_pos[camera_id] = self._T_world_camera[:3, 3]
            R_world_mj = self._T_world_camera[:3, :3] @ np.diag([1.0, -1.0, -1.0])  # MuJoCo cameras look along -z, y up
            self._model.cam_quat[camera_id] = quat_wxyz_from_matrix(R_world_mj)
            self._data.cam_xpos[camera_id] = self._T_world_camera[:3, 3]  # the next physics step would recompute these
            self._data.cam_xmat[camera_id] = R_world_mj.ravel()
            self.camera.set_board(self._T_world_camera, self._depth_pivot_m())  # the depth's tilt pivots there

    def _depth_pivot_m(self) -> np.ndarray:
        """Where the realistic depth's offset is measured and its tilt pivots: the board tags' centre."""
        return np.mean(np.asarray(list(self._workcell.board_tags.centres_m.values()), dtype=float), axis=0)

    def knock_camera(self, translation_m, rotation_rad) -> None:
        """bump_camera by a translation (m) and then a rotation vector (rad), both in the camera's frame."""
        T_old_new = np.eye(4)
        T_old_new[:3, :3] = rotation_from_rotvec(np.asarray(rotation_rad, dtype=float))
        T_old_new[:3, 3] = np.asarray(translation_m, dtype=float)
        self.bump_camera(T_old_new)

    def place_checkerboard(self, position_m=None, R_world_board=None) -> None:
        """Put the intrinsics checkerboard (checkerboard.py: board frame, z out of the printed face) at a world
        pose, or park it out of sight with no arguments. Contact-free: nothing else in the cell moves."""
        pose = None if position_m is None else checked_pose(position_m, np.eye(3) if R_world_board is None else R_world_board)
        with self.lock:
            self._checkerboard_pose = pose
            self._show_checkerboard()

    def _show_checkerboard(self) -> None:
        """Move the checkerboard's mocap body to its pose (or parked) and update the drawn positions (under the lock)."""
        pose = getattr(self, "_checkerboard_pose", None)
        position, R = (np.asarray(PARKED_POSITION_M), np.eye(3)) if pose is None else pose
        mocap = self._model.body_mocapid[self._model.body(CHECKERBOARD).id]
        self._data.mocap_pos[mocap] = position
        self._data.mocap_quat[mocap] = quat_wxyz_from_matrix(R)
        mujoco.mj_kinematics(self._model, self._data)
