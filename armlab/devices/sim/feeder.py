"""to_the_sky's feeder in the simulation: the rules let the team add blocks while the arm moves, so the
simulation puts a new large block at the feed spot whenever the spot is clear.

MuJoCo cannot add bodies at run time, so the model holds the feeder's blocks from the start, parked far
outside the board and the camera view, weightless (gravcomp) and without contacts. Feeding one turns
its contacts and weight on and teleports it (free-joint qpos, zero qvel) onto the spot. The checks run
inside the physics stepping at a fixed simulated period, so fast mode stays deterministic."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from armlab.scene import COLORS, SceneObject
from armlab.scene.model import Feeder
from armlab.workcell import Workcell
from armlab.workcell.spots import FeederSpec

FEEDER_PROBE = "feeder_probe"  # invisible block-sized geom at the spot, for the arm's distance to it
PARK_ORIGIN_M = (3.0, 3.0, 0.5)  # far outside the board and the camera's view
PARK_PITCH_M = 0.1
DROP_GAP_M = 1e-4  # a fed block appears this far above the board
FOOTPRINT_GAP_M = 0.003  # least gap between the fed block's and a neighbour's footprint circles


def parked_objects(feeder: Feeder, workcell: Workcell) -> list[SceneObject]:
    """The blocks the feeder still holds, in feeding order, at their parking places."""
    objects = []
    for index in range(feeder.fed, feeder.count):
        position = (PARK_ORIGIN_M[0] + PARK_PITCH_M * (index % 10), PARK_ORIGIN_M[1] + PARK_PITCH_M * (index // 10),
                    PARK_ORIGIN_M[2])
        objects.append(SceneObject(feeder.block_id(index), "block", COLORS[index % len(COLORS)], "large", position,
                                   workcell=workcell.name))
    return objects


class FeederRuntime:
    """The feeder of one built model. Call everything under the workcell's lock.

    watched: (body id, SceneObject) of every object already on the board; parked: the same for the
    feeder's waiting blocks, in feeding order; arm_geoms: geoms that must keep clear of a new block."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, feeder: Feeder, spec: FeederSpec,
                 edge_m: float, watched: list[tuple[int, SceneObject]], parked: list[tuple[int, SceneObject]],
                 arm_geoms: list[int]) -> None:
        self.feeder = feeder
        self.spec = spec
        self.fed = feeder.fed
        self._edge_m = edge_m
        self._parked = parked
        self._watched_bodies = [body for body, _ in watched]
        self._watched_radii = [obj.footprint_radius_m for _, obj in watched]
        self._fed_objects: list[SceneObject] = []
        self._probe = model.geom(FEEDER_PROBE).id
        self._arm_geoms = np.asarray(arm_geoms, dtype=int)
        self._spot = np.asarray(feeder.spot_m, dtype=float)
        self.next_check_s = float(data.time)

    @property
    def remaining(self) -> int:
        return self.feeder.count - self.fed

    def fed_bodies(self) -> list[tuple[int, SceneObject]]:
        """(body id, object) of the blocks this run has fed, in order."""
        return [self._parked[i] for i in range(len(self._fed_objects))]

    def status(self) -> dict:
        """Feeder state for the ground truth: spot, count, fed, remaining."""
        return {"spot_m": self._spot.tolist(), "count": self.feeder.count, "fed": self.fed, "remaining": self.remaining}

    def tick(self, model: mujoco.MjModel, data: mujoco.MjData) -> bool:
        """At each check period: feed the next block if the spot is clear. True if a block was fed."""
        if self.remaining <= 0 or data.time + 1e-9 < self.next_check_s:
            return False
        self.next_check_s = float(data.time) + self.spec.check_period_s
        if not self.spot_clear(model, data):
            return False
        self._feed(model, data)
        return True

    def spot_clear(self, model: mujoco.MjModel, data: mujoco.MjData) -> bool:
        """No object's footprint near the spot (within clear_radius_m, or touching the new block's
        footprint circle), and no part of the arm within arm_clearance_m of the new block's volume."""
        new_radius = 0.5 * math.sqrt(2.0) * self._edge_m
        if self._watched_bodies:
            distances = np.linalg.norm(data.xpos[self._watched_bodies, :2] - self._spot, axis=1)
            needed = np.maximum(self.spec.clear_radius_m, new_radius + np.asarray(self._watched_radii) + FOOTPRINT_GAP_M)
            if np.any(distances < needed):
                return False
        clearance = self.spec.arm_clearance_m
        probe_centre = data.geom_xpos[self._probe]
        reach = model.geom_rbound[self._probe] + model.geom_rbound[self._arm_geoms] + clearance
        near = self._arm_geoms[np.linalg.norm(data.geom_xpos[self._arm_geoms] - probe_centre, axis=1) < reach]
        return all(mujoco.mj_geomDistance(model, data, self._probe, int(geom), clearance, None) >= clearance for geom in near)

    def _feed(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        body, obj = self._parked[len(self._fed_objects)]
        first = model.body_geomadr[body]
        for geom in range(first, first + model.body_geomnum[body]):
            if model.geom_group[geom] != 2:  # group 2 = visual-only stickers, never in contact
                model.geom_contype[geom] = 1
                model.geom_conaffinity[geom] = 1
        model.body_contype[body] = 1
        model.body_conaffinity[body] = 1
        model.body_gravcomp[body] = 0.0
        joint = model.body_jntadr[body]
        qpos, dof = model.jnt_qposadr[joint], model.jnt_dofadr[joint]
        data.qpos[qpos : qpos + 3] = (self._spot[0], self._spot[1], 0.5 * self._edge_m + DROP_GAP_M)
        data.qpos[qpos + 3 : qpos + 7] = (1.0, 0.0, 0.0, 0.0)
        data.qvel[dof : dof + 6] = 0.0
        mujoco.mj_forward(model, data)
        self._fed_objects.append(obj)
        self._watched_bodies.append(body)
        self._watched_radii.append(obj.footprint_radius_m)
        self.fed += 1
