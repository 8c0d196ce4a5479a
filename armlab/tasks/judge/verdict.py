"""judge(): a finished run's inputs checked, then scored by its event's scorer (DESIGN §7)."""

from __future__ import annotations

from armlab.errors import InvalidInput
from armlab.tasks.judge.inputs import check_event_level, check_path, check_tag_centres, check_time, check_truth
from armlab.tasks.judge.lines import score_line_up
from armlab.tasks.judge.rules import Score
from armlab.tasks.judge.sorting import score_pick_sort, score_sort_stack
from armlab.tasks.judge.stacking import board_tag_centres_m, score_pick_stack, score_stack_high, score_to_the_sky


def judge(
    event: str,
    level: int,
    truth: dict,
    *,
    sim_time_s: float,
    gripper_path_m=None,
    blocks_available: int | None = None,
    tag_centres_m=None,
    workcell: str | None = None,
) -> Score:
    """Score a finished run of `event` at `level` from the final ground truth (DESIGN §7).

    sim_time_s: simulated seconds from the job's start to its end. gripper_path_m: (N, 3) gripper-point positions
    from the end of the job's first motion to the end (pick_stack's bonus; None = not recorded, bonus not earned).
    blocks_available: to_the_sky's block count (board + feeder; default the large blocks in truth).
    tag_centres_m: pick_stack's tag centres, (x, y) pairs or {id: (x, y)}; None = from configuration.
    workcell: the workcell run on (its block sizes and board tags; None = the default).
    Raises ValueError for an unknown event or level, malformed truth, or bad arguments.
    """
    limit_s = check_event_level(event, level)
    time_s = check_time(sim_time_s)
    objects = check_truth(truth, workcell)
    path = check_path(gripper_path_m)
    if blocks_available is not None and event != "to_the_sky":
        raise InvalidInput(f"judge: blocks_available applies to to_the_sky only, not {event!r}")
    if tag_centres_m is not None:
        tags = check_tag_centres(tag_centres_m)
    elif event == "pick_stack":
        tags = check_tag_centres(board_tag_centres_m(workcell))
    level = int(level)
    within_limit = time_s <= limit_s
    blocks = [obj for obj in objects if obj.type == "block"]
    if event == "pick_sort":
        rules, max_points = score_pick_sort(level, blocks, within_limit, limit_s)
    elif event == "pick_stack":
        rules, max_points = score_pick_stack(level, blocks, within_limit, limit_s, path, tags)
    elif event == "line_up":
        rules, max_points = score_line_up(level, objects, blocks)
    elif event == "stack_high":
        rules, max_points = score_stack_high(level, blocks)
    elif event == "to_the_sky":
        rules, max_points = score_to_the_sky(blocks, blocks_available)
    else:
        rules, max_points = score_sort_stack(level, objects, blocks, within_limit, limit_s)
    points = sum(rule.points for rule in rules)
    return Score(points, int(max_points), within_limit, points == max_points and within_limit, tuple(rules), limit_s)
