"""The error hierarchy (armlab.errors) and its HTTP mapping (server/errors.py), as the API documents it:
each library error class → status and wire code, written out here (not read from the mapping), and a
bare ValueError, KeyError or RuntimeError → 500 "internal"."""

from __future__ import annotations

import pytest

from armlab.errors import (
    PLAN_REFUSALS,
    ArmlabError,
    ArmMoving,
    CalibrationUntrusted,
    CommandRefused,
    ConfigError,
    DeviceFault,
    DeviceLost,
    DeviceNotConnectedError,
    InvalidInput,
    NeedsConfirmation,
    NoArmError,
    NotController,
    PlanRefused,
    RefusedByCheck,
    ShuttingDown,
    Unreachable,
    is_internal,
)
from armlab.motion.errors import DiscontinuousPath, StepRefused
from armlab.motion.safety import UnsafeTrajectory
from armlab.program_io import ProgramFileError
from armlab.station.core import NotCalibrated
from armlab.store import NotFound
from armlab.tasks.registry import JobUnsupported
from server.errors import error_status as _classify

CASES = [
    (InvalidInput("position_m must be 3 numbers"), 422, "invalid"),
    (ConfigError("arm.yaml: limits"), 422, "invalid"),
    (ProgramFileError("not a program file"), 422, "invalid"),
    (JobUnsupported("no suction here"), 422, "invalid"),
    (Unreachable("out of reach", "out of reach"), 422, "unreachable"),
    (StepRefused("off the line", "off the line"), 422, "unreachable"),
    (UnsafeTrajectory("below the board"), 422, "unsafe"),
    (DiscontinuousPath("joint jumps"), 422, "invalid"),
    (PlanRefused("no jerk-limited trajectory"), 422, "invalid"),
    (CommandRefused("grab", "auto", ["estop"]), 409, "wrong_state"),
    (ArmMoving("step", "idle", []), 409, "wrong_state"),
    (NoArmError("home"), 409, "no_arm"),
    (NotController("home", "alice"), 409, "not_controller"),
    (NeedsConfirmation("confirm"), 409, "needs_confirmation"),
    (NotCalibrated("grab"), 409, "not_calibrated"),
    (CalibrationUntrusted("the camera moved"), 409, "not_calibrated"),
    (NotFound("program 7"), 404, "not_found"),
    (DeviceLost("the arm stopped answering"), 503, "device"),
    (DeviceNotConnectedError(), 503, "device"),
    (ShuttingDown("closing"), 503, "device"),
    (TimeoutError("read timed out"), 503, "device"),
    (ValueError("operands could not be broadcast together"), 500, "internal"),
    (KeyError("position_m"), 500, "internal"),
    (RuntimeError("oops"), 500, "internal"),
]


@pytest.mark.parametrize(("error", "status", "code"), CASES, ids=[type(case[0]).__name__ + str(i) for i, case in enumerate(CASES)])
def test_each_error_maps_to_its_documented_status_and_code(error, status, code):
    assert _classify(error) == (status, code)


@pytest.mark.parametrize(
    ("error_class", "category"),
    [
        (ConfigError, InvalidInput), (ProgramFileError, InvalidInput), (JobUnsupported, InvalidInput),
        (StepRefused, Unreachable), (UnsafeTrajectory, PlanRefused), (DiscontinuousPath, PlanRefused),
        (PlanRefused, RefusedByCheck), (CommandRefused, RefusedByCheck), (NotController, RefusedByCheck),
        (NeedsConfirmation, RefusedByCheck), (NotCalibrated, RefusedByCheck), (CalibrationUntrusted, RefusedByCheck),
        (DeviceLost, DeviceFault), (DeviceNotConnectedError, DeviceFault),
    ],
)
def test_existing_classes_sit_under_their_category(error_class, category):
    assert issubclass(error_class, category) and issubclass(category, ArmlabError)


def test_the_categories_keep_their_old_bases_so_existing_except_clauses_still_catch_them():
    assert issubclass(InvalidInput, ValueError) and issubclass(Unreachable, ValueError) and issubclass(PlanRefused, ValueError)
    assert issubclass(DeviceFault, ConnectionError) and issubclass(CommandRefused, RuntimeError)


def test_a_bare_value_error_is_internal_and_no_refusal_catches_it():
    bug = ValueError("shapes (3,) and (4,) not aligned")
    assert is_internal(bug) and is_internal(KeyError("x")) and is_internal(TypeError("x"))
    assert not isinstance(bug, PLAN_REFUSALS)
    for refusal in (InvalidInput("x"), Unreachable("x", "out of reach"), UnsafeTrajectory("x"), CommandRefused("a", "b", [])):
        assert not is_internal(refusal)
    assert not is_internal(RuntimeError("no free spot on the board"))  # an expected failure, not a bug
