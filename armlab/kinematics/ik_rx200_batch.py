"""Batch (vectorised) closed-form IK of the RX200 family: the maths of ik_rx200 over N targets.

Same solutions, same choice among them and the same pitch search as the scalar `ik_rx200.solve`
(the tests check they agree), as numpy array expressions: 10,000 targets in a few milliseconds.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.kinematics.ik_rx200 import LIMIT_TOL_RAD, PITCH_MAX_RAD, PITCH_MIN_RAD, REFINE_STEPS, SEARCH_STEP_RAD
from armlab.kinematics.rx200_geometry import HALF_PI, Rx200Geometry, wrist_rotate_batch


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
        valid &= (values >= lower[index] - LIMIT_TOL_RAD) & (values <= upper[index] + LIMIT_TOL_RAD)
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
            better = (shifted >= lower[0] - LIMIT_TOL_RAD) & (shifted <= upper[0] + LIMIT_TOL_RAD)
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


def _reach_hint_batch(g: Rx200Geometry, radius: np.ndarray, zb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised _reach_hint: (never (N,) bool, steepest_pitch (N,), NaN where reach does not decide)."""
    count = radius.shape[0]
    if g.shoulder_x_m != 0.0:
        return np.zeros(count, dtype=bool), np.full(count, np.nan)
    height = zb - g.shoulder_z_m
    rho = np.sqrt(radius * radius + height * height)
    reach = g.upper_arm_m + g.forearm_m
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = (rho * rho + g.tool_m * g.tool_m - reach * reach) / (2.0 * g.tool_m * rho)
    usable = rho >= 1e-12
    never = usable & (bound > 1.0)
    theta = np.arctan2(height, radius)
    decides = usable & ~never & (bound > -1.0) & (np.cos(HALF_PI + theta) < bound)
    half_width = np.arccos(np.clip(bound, -1.0, 1.0))
    two_pi = 2.0 * np.pi
    below = -theta + half_width - 1e-9
    below -= two_pi * np.ceil((below - HALF_PI) / two_pi)
    above = -theta - half_width + 1e-9
    above += two_pi * np.ceil((HALF_PI - above) / two_pi)
    below_ok = (below >= PITCH_MIN_RAD) & (below <= PITCH_MAX_RAD)
    above_ok = (above >= PITCH_MIN_RAD) & (above <= PITCH_MAX_RAD)
    below_gap = np.where(below_ok, np.abs(below - HALF_PI), np.inf)
    above_gap = np.where(above_ok, np.abs(above - HALF_PI), np.inf)
    hint = np.where(below_gap <= above_gap, below, above)
    hint = np.where(decides & (below_ok | above_ok), hint, np.nan)
    return never, hint


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
        for _ in range(REFINE_STEPS):
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
        todo = np.flatnonzero(~ok & above)
        if todo.size:
            never, hint = _reach_hint_batch(g, np.hypot(base_xyz[todo, 0], base_xyz[todo, 1]), base_xyz[todo, 2])
            hinted = np.isfinite(hint)
            if hinted.any():
                rows = todo[hinted]
                q_hint, ok_hint = _batch_at_pitch(g, base_xyz[rows], hint[hinted], seed[rows])
                q4[rows[ok_hint]], ok[rows[ok_hint]] = q_hint[ok_hint], True
                pitch_used[rows[ok_hint]] = hint[hinted][ok_hint]
            _batch_search(g, base_xyz, seed, q4, ok, pitch_used, todo[~never & ~ok[todo]])
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
