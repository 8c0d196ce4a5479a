"""Closed-form inverse kinematics of the RX200 family (cylindrical reduction, wrist centre).

After seeds/002 §C, extended: every solution is enumerated (waist toward the target or turned
half a turn, elbow up or down), the ones within the joint limits and with every joint above the
board are kept, and the one closest to the seed is returned (elbow-up solutions first). With no
pitch given, pitch pi/2 (straight down) is tried first and then the steepest reachable pitch is
searched, so far targets can still be picked. Failures raise Unreachable with the reason.

The half-turned waist is the "over the back" branch: waist = target direction + pi, the shoulder
leaning back past vertical, the arm reaching over the base to a target behind it. The requested
pitch is a world quantity (below the horizontal, in the vertical plane through the base axis and
the target, 0 = pointing away from the base axis, pi/2 = straight down), so in the arm's own plane,
which faces away from the target on that branch, the gripper's pitch is pi - pitch. Other pitches
ask for other orientations: the arm-plane pitch (shoulder + elbow + wrist_angle) when the gripper
point lies behind the base axis, an rpy/asin pitch (which cannot say "pointing back toward the base")
when the gripper points back toward the base axis; ArmModel.pitch_of gives the pitch ik means.

Plain `math` on floats (about ten microseconds a call); ik_rx200_batch holds the same maths
vectorised over N targets with numpy.
"""

from __future__ import annotations

import math

from armlab.kinematics.errors import Unreachable
from armlab.kinematics.rx200_geometry import (
    HALF_PI,
    Rx200Geometry,
    choose_wrist_rotate,
    wrap_angle,
    wrist_rotate_candidates,
)

LIMIT_TOL_RAD = 1e-9
SEARCH_STEP_RAD = math.radians(1.0)
PITCH_MIN_RAD = -HALF_PI  # approach axis pointing straight up
PITCH_MAX_RAD = math.pi  # approach axis horizontal, pointing back toward the base
REFINE_STEPS = 24

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
            if lower[0] - LIMIT_TOL_RAD <= shifted <= upper[0] + LIMIT_TOL_RAD and abs(shifted - seed[0]) < abs(waist - seed[0]):
                waist = shifted
        if not lower[0] - LIMIT_TOL_RAD <= waist <= upper[0] + LIMIT_TOL_RAD:
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
                if not lower[index] - LIMIT_TOL_RAD <= value <= upper[index] + LIMIT_TOL_RAD:
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


def _reach_hint(g: Rx200Geometry, radius: float, zb: float) -> tuple[bool, float | None]:
    """Where the wrist centre's reach bounds the pitch, in closed form: (never, steepest_pitch).

    The wrist centre's distance from the shoulder satisfies d^2 = rho^2 + L^2 - 2 L rho cos(pitch +
    theta) (rho, theta: the target from the shoulder in the arm plane, L: wrist to gripper point),
    so d <= l2 + l3 is an interval of pitch. never: no pitch is in reach. steepest_pitch: the pitch
    in reach nearest pi/2 when pi/2 itself is out of reach (None when reach does not decide it).
    Exact for a shoulder on the base axis (then both waist directions share the interval).
    """
    if g.shoulder_x_m != 0.0:
        return False, None
    height = zb - g.shoulder_z_m
    rho = math.sqrt(radius * radius + height * height)
    reach = g.upper_arm_m + g.forearm_m
    if rho < 1e-12:
        return False, None
    bound = (rho * rho + g.tool_m * g.tool_m - reach * reach) / (2.0 * g.tool_m * rho)
    if bound > 1.0:
        return True, None
    theta = math.atan2(height, radius)
    if bound <= -1.0 or math.cos(HALF_PI + theta) >= bound:
        return False, None  # pi/2 is in reach: the joint limits decide, not the reach
    half_width = math.acos(bound)
    two_pi = 2.0 * math.pi
    below = -theta + half_width - 1e-9  # upper end of the interval, approached from above
    below -= two_pi * math.ceil((below - HALF_PI) / two_pi)
    above = -theta - half_width + 1e-9  # lower end of the interval, approached from below
    above += two_pi * math.ceil((HALF_PI - above) / two_pi)
    options = [p for p in (below, above) if PITCH_MIN_RAD <= p <= PITCH_MAX_RAD]
    return False, (min(options, key=lambda p: abs(p - HALF_PI)) if options else None)


def _search_pitch(g, xb, yb, zb, seed):
    """Steepest reachable pitch: pi/2; else the reach boundary in closed form when that fits the
    limits; else 1-degree steps alternating below/above pi/2, then bisection to the boundary."""
    best, failure = _solve_at_pitch(g, xb, yb, zb, HALF_PI, seed)
    if best is not None:
        return best, HALF_PI, failure
    never, hint = _reach_hint(g, math.sqrt(xb * xb + yb * yb), zb)
    if never:
        return None, None, failure
    if hint is not None:
        found, reason = _solve_at_pitch(g, xb, yb, zb, hint, seed)
        if found is not None:
            return found, hint, failure
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
            for _ in range(REFINE_STEPS):
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
