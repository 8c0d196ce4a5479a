"""MJCF for what `realism: real` adds to the workcell's world: a second light that casts shadows, and
clutter lying on or at the edge of the board (cables, pliers, a hand) as static, contact-free geoms that
are not scene objects: the judge, the feeder and the ground truth never see them, only the camera."""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.sim.config import ClutterItem, LightConfig, SceneRealismConfig
from armlab.devices.sim.mjcf_numbers import fmt_numbers as _fmt

CLUTTER_PREFIX = "clutter:"
VISUAL = 'contype="0" conaffinity="0" group="0"'
SLEEVE_RGBA = (0.45, 0.46, 0.48, 1.0)
STEEL_RGBA = (0.55, 0.56, 0.58, 1.0)


def light_xml(light: LightConfig) -> str:
    return (f'<light name="second_light" pos="{_fmt(light.position_m)}" dir="{_fmt(light.direction)}" '
            f'diffuse="{light.diffuse} {light.diffuse} {light.diffuse}" specular="0 0 0" cutoff="{light.cutoff_deg}" exponent="{light.exponent}" '
            f'castshadow="{str(light.cast_shadow).lower()}"/>')


def _capsule(name: str, a, b, radius_m: float, rgba) -> str:
    return (f'<geom name="{name}" type="capsule" fromto="{_fmt([*a, *b])}" size="{radius_m:.9g}" rgba="{_fmt(rgba)}" '
            f'{VISUAL}/>')


def _local(origin, yaw_rad: float, x: float, y: float, z: float) -> list[float]:
    """A point given in an item's own frame (x forward along yaw) in the world frame."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return [origin[0] + c * x - s * y, origin[1] + s * x + c * y, z]


def _item_xml(index: int, item: ClutterItem) -> str:
    name = f"{CLUTTER_PREFIX}{index}:{item.kind}"
    r = item.radius_m
    if item.kind == "cable":
        points = [[x, y, r] for x, y in item.points_m]
        return "".join(_capsule(f"{name}:{k}", a, b, r, item.rgba) for k, (a, b) in enumerate(zip(points, points[1:])))
    origin, yaw = item.position_m, math.radians(item.yaw_deg)
    if item.kind == "pliers":  # handles (radius r) spread from a pivot at the origin; steel jaws ahead of it
        parts = [_capsule(f"{name}:handle{k}", _local(origin, yaw, 0.0, 0.0, r), _local(origin, yaw, -0.11, side * 0.025, r), r, item.rgba)
                 for k, side in enumerate((-1.0, 1.0))]
        jaw = _local(origin, yaw, 0.025, 0.0, 0.006)
        parts.append(f'<geom name="{name}:jaw" type="box" size="0.025 0.008 0.006" pos="{_fmt(jaw)}" '
                     f'euler="0 0 {yaw:.9g}" rgba="{_fmt(STEEL_RGBA)}" {VISUAL}/>')
        return "".join(parts)
    # A hand (its rgba: the skin) reaching in along +x of its frame: a sleeved forearm, a palm, four fingers of radius r.
    palm = _local(origin, yaw, 0.0, 0.0, 0.018)
    parts = [_capsule(f"{name}:forearm", _local(origin, yaw, -0.06, 0.0, 0.035), _local(origin, yaw, -0.30, 0.0, 0.05), 0.035, SLEEVE_RGBA),
             f'<geom name="{name}:palm" type="ellipsoid" size="0.045 0.04 0.016" pos="{_fmt(palm)}" euler="0 0 {yaw:.9g}" '
             f'rgba="{_fmt(item.rgba)}" {VISUAL}/>']
    for k, y in enumerate(np.linspace(-0.027, 0.027, 4)):
        parts.append(_capsule(f"{name}:finger{k}", _local(origin, yaw, 0.04, y, 0.014), _local(origin, yaw, 0.09, 1.1 * y, r), r, item.rgba))
    return "".join(parts)


def realism_world_xml(realism: SceneRealismConfig | None) -> str:
    """The second light and the clutter (worldbody XML), or nothing for the ideal workcell."""
    if realism is None:
        return ""
    return light_xml(realism.second_light) + "".join(_item_xml(i, item) for i, item in enumerate(realism.clutter))
