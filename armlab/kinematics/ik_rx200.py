"""Closed-form inverse kinematics of the RX200 family (cylindrical reduction, wrist centre).

After seeds/002 §C, extended: every solution is enumerated (waist toward the target or turned
half a turn, elbow up or down), the ones within the joint limits and with every joint above the
board are kept, and the one closest to the seed is returned (elbow-up solutions first). With no
pitch given, pitch pi/2 (straight down) is tried first and then the steepest reachable pitch is
searched, so far targets can still be picked. Failures raise Unreachable with the reason.

Scalar code is plain `math` on floats (a few microseconds a call); `solve_batch` is the same maths
vectorised over N targets with numpy.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.kinematics.errors import Unreachable
from armlab.kinematics.rx200_geometry import (
    HALF_PI,
    Rx200Geometry,
    choose_wrist_rotate,
    wrap_angle,
    wrist_rotate_batch,
    wrist_rotate_candidates,
)

_TOL = 1e-9
SEARCH_STEP_RAD = math.radians(1.0)
PITCH_MIN_RAD = -HALF_PI  # approach axis pointing straight up
PITCH_MAX_RAD = math.pi  # approach axis horizontal, pointing back toward the base
_REFINE_STEPS = 24

# Failure ranks: a higher rank got further through the checks, so it explains the failure better.
_RANK_REACH, _RANK_LIMIT, _RANK_TABLE = 1, 2, 3


def _to_base(g: Rx200Geometry, x: float, y: float, z: float) -> tuple[float, float, float]:
    """World point -> base frame (the base is level: a rotation about z and a translation)."""
    bx, by, bz = g.base_xyz_m
    c, s = math.cos(g.base_yaw_rad), math.sin(g.base_yaw_rad)
    dx, dy = x - bx, y - by
    return c * dx + s * dy, -s * dx + c * dy, z - bz


def _solve_at_pitch(g: Rx200Geometry, xb: float, yb: float, zb: float, pitch: float, seed: tuple[float, ...]):
    """Best (q1, q2, q3, q4) reaching base point (xb, yb, zb) at `pitch`, or (None, failure tuple).

    Elbow-up solutions (both waist directions) first; elbow-down ones only when no elbow-up one fits.
    """
    l2, l3 = g.upper_arm_m, g.forearm_m
    beta = g.upper_arm_elevation_rad
    lower, upper = g.lower_rad, g.upper_rad
    radius = math.sqrt(xb * xb + yb * yb)
    phi = math.atan2(yb, xb) if radius > 1e-12 else seed[0]
    cos_pitch, sin_pitch = math.cos(pitch), math.sin(pitch)
    failure = (0, 0.0, "", 0.0)  # (rank, key: larger = nearer miss, what, value)
    families = []  # (waist, psi, rc, zc, cos_bend, bend) of each waist direction that is in reach
    for back in (False, True):
        if back:  # turned half a turn: the target lies behind, the approach pitch is mirrored
            waist, psi, rc = wrap_angle(phi + math.pi), math.pi - pitch, -radius + g.tool_m * cos_pitch
        else:
            waist, psi, rc = wrap_angle(phi), pitch, radius - g.tool_m * cos_pitch
        rc -= g.shoulder_x_m
        for shifted in (waist - 2.0 * math.pi, waist + 2.0 * math.pi):  # e.g. -pi for pi, near a -pi seed
            if lower[0] - _TOL <= shifted <= upper[0] + _TOL and abs(shifted - seed[0]) < abs(waist - seed[0]):
                waist = shifted
        if not lower[0] - _TOL <= waist <= upper[0] + _TOL:
            failure = max(failure, (_RANK_LIMIT, -_excess(waist, lower[0], upper[0]), "waist", waist))
            continue
        zc = zb + g.tool_m * sin_pitch - g.shoulder_z_m
        cos_bend = (rc * rc + zc * zc - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
        if cos_bend > 1.0 + 1e-12 or cos_bend < -1.0 - 1e-12:
            distance = math.sqrt(rc * rc + zc * zc)  # the key (second item) makes max() keep the nearest miss
            failure = max(failure, (_RANK_REACH, -abs(distance - _span_middle(g)), "reach", distance))
            continue
        cos_bend = min(1.0, max(-1.0, cos_bend))
        families.append((waist, psi, rc, zc, cos_bend, math.acos(cos_bend)))
    best, best_cost = None, math.inf
    floor = -g.base_xyz_m[2]
    for elbow_up in (True, False):
        for waist, psi, rc, zc, cos_bend, bend in families:
            # shoulder angle of the elbow triangle as a vector (a, b); elevation of the upper arm =
            # atan2(zc, rc) - atan2(b, a), computed as one atan2 of the rotated vector (x, y)
            a = l2 + l3 * cos_bend
            b = l3 * math.sqrt(1.0 - cos_bend * cos_bend)
            if elbow_up:
                b, q3 = -b, bend - beta
            else:
                q3 = wrap_angle(-bend - beta)
            x, y = rc * a + zc * b, zc * a - rc * b
            q2 = wrap_angle(beta - math.atan2(y, x))
            q4 = wrap_angle(psi - q2 - q3)
            limit = None
            for index, value in ((1, q2), (2, q3), (3, q4)):
                if not lower[index] - _TOL <= value <= upper[index] + _TOL:
                    limit = (_RANK_LIMIT, -_excess(value, lower[index], upper[index]), g.joint_names[index], value)
                    break
            if limit is not None:
                failure = max(failure, limit)
                continue
            elbow_z = g.shoulder_z_m + l2 * y / max(math.sqrt(x * x + y * y), 1e-300)  # + l2 sin(elevation)
            wrist_z = zc + g.shoulder_z_m
            if elbow_z < floor or wrist_z < floor:
                lowest = min(elbow_z, wrist_z) - floor
                failure = max(failure, (_RANK_TABLE, lowest, "elbow" if elbow_z < floor else "wrist", lowest))
                continue
            cost = abs(waist - seed[0]) + abs(q2 - seed[1]) + abs(q3 - seed[2]) + abs(q4 - seed[3])
            if cost < best_cost:
                best, best_cost = (waist, q2, q3, q4), cost
        if best is not None:
            break
    return best, failure


def _excess(value: float, lower: float, upper: float) -> float:
    """How far (rad) a joint value lies outside [lower, upper]."""
    return max(lower - value, value - upper, 0.0)


def _span_middle(g: Rx200Geometry) -> float:
    """Middle of the shoulder-to-wrist distances the arm can span."""
    return 0.5 * (abs(g.upper_arm_m - g.forearm_m) + g.upper_arm_m + g.forearm_m)


def _describe(g: Rx200Geometry, failure: tuple, target: tuple[float, float, float], pitch_text: str) -> Unreachable:
    """Unreachable error for the highest-ranked failure."""
    rank, _key, what, value = failure
    where = f"target ({target[0]:.4f}, {target[1]:.4f}, {target[2]:.4f}) m {pitch_text}"
    if rank == _RANK_TABLE:
        return Unreachable(f"{where}: below the table ({what} would be at z = {value:.4f} m)", "below the table")
    if rank == _RANK_LIMIT:
        index = g.joint_names.index(what)
        return Unreachable(
            f"{where}: joint limit ({what}): needs {math.degrees(value):.1f} deg, limits "
            f"{math.degrees(g.lower_rad[index]):.1f}..{math.degrees(g.upper_rad[index]):.1f} deg",
            f"joint limit ({what})",
        )
    span_min, span_max = abs(g.upper_arm_m - g.forearm_m), g.upper_arm_m + g.forearm_m
    return Unreachable(
        f"{where}: out of reach (wrist centre {value:.4f} m from the shoulder; the arm spans "
        f"{span_min:.4f}..{span_max:.4f} m)",
        "out of reach",
    )


def _search_pitch(g, xb, yb, zb, seed):
    """Steepest reachable pitch: pi/2, then 1-degree steps alternating below/above, then bisection."""
    best, failure = _solve_at_pitch(g, xb, yb, zb, HALF_PI, seed)
    if best is not None:
        return best, HALF_PI, failure
    steps = int(math.ceil(math.pi / SEARCH_STEP_RAD))
    for k in range(1, steps + 1):
        for side in (-1.0, 1.0):
            pitch = HALF_PI + side * k * SEARCH_STEP_RAD
            if not PITCH_MIN_RAD - 1e-12 <= pitch <= PITCH_MAX_RAD + 1e-12:
                continue
            found, reason = _solve_at_pitch(g, xb, yb, zb, pitch, seed)
            if found is None:
                failure = max(failure, reason)
                continue
            good, bad = pitch, pitch - side * SEARCH_STEP_RAD
            for _ in range(_REFINE_STEPS):
                middle = 0.5 * (good + bad)
                trial, _reason = _solve_at_pitch(g, xb, yb, zb, middle, seed)
                if trial is None:
                    bad = middle
                else:
                    good, found = middle, trial
            return found, good, failure
    return None, None, failure


def solve(
    g: Rx200Geometry,
    position_m: tuple[float, float, float],
    pitch_rad: float | None,
    yaw_rad: float | None,
    seed: tuple[float, ...],
) -> tuple[tuple[float, ...], float]:
    """Joint vector (5 floats) and the pitch used, for a world-frame gripper-point target.

    Inputs are assumed finite (the ArmModel validates them). Raises Unreachable with the reason.
    """
    x, y, z = position_m
    if z < 0.0:
        raise Unreachable(f"target ({x:.4f}, {y:.4f}, {z:.4f}) m: below the table (z < 0)", "below the table")
    xb, yb, zb = _to_base(g, x, y, z)
    if pitch_rad is None:
        best, pitch, failure = _search_pitch(g, xb, yb, zb, seed)
        pitch_text = "at every pitch from -90 to 180 deg"
    else:
        pitch = pitch_rad
        best, failure = _solve_at_pitch(g, xb, yb, zb, pitch, seed)
        pitch_text = f"at pitch {math.degrees(pitch):.1f} deg"
    if best is None:
        raise _describe(g, failure, (x, y, z), pitch_text)
    waist, q2, q3, q4 = best
    if yaw_rad is None:
        wrist = seed[4]
        if not g.lower_rad[4] <= wrist <= g.upper_rad[4]:
            wrist = 0.0
    else:
        options = wrist_rotate_candidates(waist, q2 + q3 + q4, yaw_rad, g.base_yaw_rad)
        wrist = choose_wrist_rotate(options, seed[4], g.lower_rad[4], g.upper_rad[4])
        if wrist is None:
            raise Unreachable(
                f"target ({x:.4f}, {y:.4f}, {z:.4f}) m: joint limit (wrist_rotate): no rotation within the limits "
                f"aligns the fingers with yaw {math.degrees(yaw_rad):.1f} deg",
                "joint limit (wrist_rotate)",
            )
    return (waist, q2, q3, q4, wrist), pitch


# ----------------------------------------------------------------------------------------------
# Batch (vectorised) version


def _wrap_array(angles: np.ndarray) -> np.ndarray:
    """Angles within (-3pi, 3pi] wrapped into (-pi, pi] (two selects: cheaper than np.mod)."""
    angles = np.where(angles > np.pi, angles - 2.0 * np.pi, angles)
    return np.where(angles <= -np.pi, angles + 2.0 * np.pi, angles)


def _batch_candidate(g: Rx200Geometry, reach_r, zb, cos_psi, sin_psi, psi, waist, seed, elbow_up: bool):
    """One solution family (waist given, elbow up or down) for N targets: (joints (N, 4), cost (N,)),
    cost = L1 distance to the seed, infinite where the family is out of reach, limits or the board."""
    l2, l3, beta = g.upper_arm_m, g.forearm_m, g.upper_arm_elevation_rad
    lower, upper = g.lower_rad, g.upper_rad
    rc = reach_r - g.tool_m * cos_psi - g.shoulder_x_m
    zc = zb + g.tool_m * sin_psi - g.shoulder_z_m
    cos_bend = (rc * rc + zc * zc - (l2 * l2 + l3 * l3)) / (2.0 * l2 * l3)
    valid = (cos_bend <= 1.0 + 1e-12) & (cos_bend >= -1.0 - 1e-12)
    cos_bend = np.clip(cos_bend, -1.0, 1.0)
    bend = np.arccos(cos_bend)
    # the elbow triangle's angle at the shoulder, as a vector (a, b): atan2(b, a) = atan2(l3 sin g, l2 + l3 cos g)
    a = l2 + l3 * cos_bend
    b = l3 * np.sqrt(1.0 - cos_bend * cos_bend)
    if elbow_up:
        b = -b
        q3 = bend - beta
    else:
        q3 = _wrap_array(-bend - beta)
    # elevation of the upper arm = atan2(zc, rc) - atan2(b, a), as one atan2 of the rotated vector
    x, y = rc * a + zc * b, zc * a - rc * b
    elevation = np.arctan2(y, x)
    q2 = _wrap_array(beta - elevation)
    q4 = _wrap_array(_wrap_array(psi - q2) - q3)
    for index, values in enumerate((waist, q2, q3, q4)):
        valid &= (values >= lower[index] - _TOL) & (values <= upper[index] + _TOL)
    floor = -g.base_xyz_m[2]
    elbow_height = l2 * y / np.maximum(np.sqrt(x * x + y * y), 1e-300)  # l2 sin(elevation)
    valid &= (g.shoulder_z_m + elbow_height >= floor) & (zc + g.shoulder_z_m >= floor)
    cost = np.abs(waist - seed[:, 0]) + np.abs(q2 - seed[:, 1]) + np.abs(q3 - seed[:, 2]) + np.abs(q4 - seed[:, 3])
    joints = np.empty((waist.shape[0], 4))
    joints[:, 0], joints[:, 1], joints[:, 2], joints[:, 3] = waist, q2, q3, q4
    return joints, np.where(valid, cost, np.inf)


def _batch_at_pitch(g: Rx200Geometry, base_xyz: np.ndarray, pitch: np.ndarray, seed: np.ndarray):
    """Vectorised _solve_at_pitch: base points (N, 3), pitch (N,), seed (N, 5) -> (q4 (N, 4), ok (N,)).

    Both waist directions are tried elbow-up; elbow-down only for the targets neither of those fits.
    """
    lower, upper = g.lower_rad, g.upper_rad
    xb, yb, zb = base_xyz[:, 0], base_xyz[:, 1], base_xyz[:, 2]
    radius = np.sqrt(xb * xb + yb * yb)
    phi = np.where(radius > 1e-12, np.arctan2(yb, xb), seed[:, 0])
    cos_psi, sin_psi = np.cos(pitch), np.sin(pitch)
    families = []
    for back in (False, True):
        waist = _wrap_array(phi + np.pi) if back else phi
        for shift in (-2.0 * np.pi, 2.0 * np.pi):  # the 2*pi equivalent nearer the seed, when within limits
            shifted = waist + shift
            better = (shifted >= lower[0] - _TOL) & (shifted <= upper[0] + _TOL)
            better &= np.abs(shifted - seed[:, 0]) < np.abs(waist - seed[:, 0])
            waist = np.where(better, shifted, waist)
        if back:  # turned half a turn: the target lies behind, the approach pitch is mirrored
            families.append((-radius, -cos_psi, np.pi - pitch, waist))
        else:
            families.append((radius, cos_psi, pitch, waist))
    best_q, best_cost = None, None
    for reach_r, cos_family, psi, waist in families:  # elbow up, every target
        joints, cost = _batch_candidate(g, reach_r, zb, cos_family, sin_psi, psi, waist, seed, True)
        if best_q is None:
            best_q, best_cost = joints, cost
        else:
            better = cost < best_cost
            best_cost = np.where(better, cost, best_cost)
            best_q = np.where(better[:, None], joints, best_q)
    rows = np.flatnonzero(~np.isfinite(best_cost))
    for reach_r, cos_family, psi, waist in families if rows.size else ():  # elbow down, the rest only
        joints, cost = _batch_candidate(
            g, reach_r[rows], zb[rows], cos_family[rows], sin_psi[rows], psi[rows], waist[rows], seed[rows], False
        )
        better = cost < best_cost[rows]
        best_cost[rows[better]] = cost[better]
        best_q[rows[better]] = joints[better]
    return best_q, np.isfinite(best_cost)


def _batch_search(g, base_xyz, seed, q_out, ok_out, pitch_out, todo):
    """Steepest reachable pitch for the targets `todo` (indices), vectorised; fills the outputs."""
    offsets = []
    for k in range(1, int(math.ceil(math.pi / SEARCH_STEP_RAD)) + 1):
        for side in (-1.0, 1.0):
            pitch = HALF_PI + side * k * SEARCH_STEP_RAD
            if PITCH_MIN_RAD - 1e-12 <= pitch <= PITCH_MAX_RAD + 1e-12:
                offsets.append((pitch, pitch - side * SEARCH_STEP_RAD))
    chunk = 16
    for start in range(0, len(offsets), chunk):
        if todo.size == 0:
            return
        block = offsets[start : start + chunk]
        pitches = np.array([p for p, _ in block])
        count = todo.size
        tiled_xyz = np.tile(base_xyz[todo], (len(block), 1))
        tiled_seed = np.tile(seed[todo], (len(block), 1))
        tiled_pitch = np.repeat(pitches, count)
        _q, ok = _batch_at_pitch(g, tiled_xyz, tiled_pitch, tiled_seed)
        ok = ok.reshape(len(block), count)
        found = ok.any(axis=0)
        if not found.any():
            continue
        first = np.argmax(ok, axis=0)[found]
        targets = todo[found]
        good = pitches[first]
        bad = np.array([b for _, b in block])[first]
        for _ in range(_REFINE_STEPS):
            middle = 0.5 * (good + bad)
            _q, mid_ok = _batch_at_pitch(g, base_xyz[targets], middle, seed[targets])
            good = np.where(mid_ok, middle, good)
            bad = np.where(mid_ok, bad, middle)
        q_found, ok_found = _batch_at_pitch(g, base_xyz[targets], good, seed[targets])
        q_out[targets] = q_found
        ok_out[targets] = ok_found
        pitch_out[targets] = good
        todo = todo[~found]


def solve_batch(
    g: Rx200Geometry,
    positions_m: np.ndarray,
    pitch_rad: np.ndarray | None,
    yaw_rad: np.ndarray | None,
    seed: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vectorised `solve`: positions (N, 3) world, pitch (N,) or None (search), yaw (N,) or None,
    seed (N, 5) -> (q (N, 5), ok (N,), pitch used (N,)). Rows that fail have ok False (q is NaN)."""
    count = positions_m.shape[0]
    c, s = math.cos(g.base_yaw_rad), math.sin(g.base_yaw_rad)
    delta = positions_m - np.asarray(g.base_xyz_m)
    base_xyz = np.stack([c * delta[:, 0] + s * delta[:, 1], -s * delta[:, 0] + c * delta[:, 1], delta[:, 2]], -1)
    above = positions_m[:, 2] >= 0.0
    pitch_used = np.full(count, HALF_PI) if pitch_rad is None else np.asarray(pitch_rad, dtype=float).copy()
    q4, ok = _batch_at_pitch(g, base_xyz, pitch_used, seed)
    if pitch_rad is None:
        _batch_search(g, base_xyz, seed, q4, ok, pitch_used, np.flatnonzero(~ok & above))
    ok &= above
    if yaw_rad is None:
        wrist = np.where((seed[:, 4] >= g.lower_rad[4]) & (seed[:, 4] <= g.upper_rad[4]), seed[:, 4], 0.0)
    else:
        arm_pitch = q4[:, 1] + q4[:, 2] + q4[:, 3]
        wrist, wrist_ok = wrist_rotate_batch(
            q4[:, 0], arm_pitch, np.asarray(yaw_rad, dtype=float), g.base_yaw_rad, seed[:, 4], g.lower_rad[4], g.upper_rad[4]
        )
        ok &= wrist_ok
    q = np.concatenate([q4, wrist[:, None]], axis=1)
    q[~ok] = np.nan
    return q, ok, pitch_used
