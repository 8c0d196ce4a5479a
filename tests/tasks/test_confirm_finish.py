"""The runner's loop over scripted looks. A job does not end on a look that misses a block it saw before: it
looks again (at most twice; in CI pick_sort L1 ended "succeeded" with done 2 of 3 and left 0: the final look
missed a sorted block, and a policy's finished cannot tell a missed block from a done one). A job starts no
move once its event's time limit has passed (issue 19: a stack_high run went on for 3,108 s simulated)."""

from __future__ import annotations

from types import SimpleNamespace

from seen_blocks import seen_block

from armlab.station.slots import EventLog
from armlab.tasks.pick_sort import policy
from armlab.tasks.place_check import PlaceCheck
from armlab.tasks.policy import Plan, blocks_seen, confirm_finish
from armlab.tasks.runner import MAX_CONFIRM_LOOKS, Progress, TaskRunner


def cube(x: float, y: float, size: str = "large", level: int = 1):
    return seen_block("red", size, x, y, 0.038 * level, level=level)


SORTED = [cube(0.15, -0.07), cube(0.22, -0.07), cube(-0.15, -0.07, "small")]
FIRST = [*SORTED[:2], cube(-0.15, 0.20, "small")]  # the small block still to sort


class ScriptedRunner(TaskRunner):
    """TaskRunner's loop over scripted looks (what the camera reports each time); no arm."""

    def __init__(self, looks: list[list]) -> None:  # noqa: D107 - TaskRunner's own needs a station
        self.looks = list(looks)
        self.looked = 0
        self.name = "pick_sort"
        self.progress = Progress()
        self._attempts, self._given_up = {}, set()
        self.time_limit_s = None
        self.clock_s = 0.0
        self.move_s = 50.0  # each move takes this long on the station clock
        self.station = SimpleNamespace(events=EventLog(), clock_s=lambda: self.clock_s)
        self.ctx = SimpleNamespace(progress=lambda *a, **k: None, job=SimpleNamespace(update_extra=lambda **k: None))
        self.place_check = PlaceCheck(False, 2, 0.006, lambda level, words: None)  # the station's default: off
        self.pick_records = []  # the pick check's records (off, as the station's default)

    def look(self) -> list:
        self.looked += 1
        return self.looks.pop(0) if len(self.looks) > 1 else self.looks[0]

    def park(self) -> None:
        pass

    def execute(self, move, objects) -> bool:
        self.progress.moves += 1
        self.clock_s += self.move_s
        return True  # the next scripted look shows where it went


def test_blocks_seen_counts_the_blocks_under_a_top_and_no_distractors():
    assert blocks_seen([cube(0, 0.1, level=3), cube(0.1, 0.1), seen_block(None, None, 0, 0, 0, cube=False)]) == 4


def test_only_a_finishing_look_that_sees_fewer_blocks_is_confirmed():
    finished, going = Plan([], done=2, left=0, finished=True), Plan([], done=2, left=1)
    assert confirm_finish(finished, 2, 3)
    assert not confirm_finish(finished, 3, 3) and not confirm_finish(finished, 2, None)
    assert not confirm_finish(going, 2, 3)  # not finishing: the job goes on anyway


def test_a_missed_sorted_block_is_looked_for_again_and_counted():
    runner = ScriptedRunner([FIRST, SORTED[:2], SORTED])  # the look after the move misses one
    result = runner.run(lambda objects, given_up: policy(objects, given_up))
    assert runner.looked == 3 and result["moves"] == 1 and result["done"] == 3 and result["left"] == 0
    assert any("2 block(s) seen, 3 before: looking again" in e["message"] for e in runner.station.events.since(0))


def test_a_block_that_stays_gone_ends_the_job_after_the_confirming_looks():
    runner = ScriptedRunner([FIRST, SORTED[:2]])  # gone for good (e.g. knocked off the board)
    result = runner.run(lambda objects, given_up: policy(objects, given_up))
    assert runner.looked == 2 + MAX_CONFIRM_LOOKS and result["done"] == 2


def _never_sorted(look: int) -> list[dict]:
    """A small block on the wrong side, somewhere new at every look (a move that never sticks)."""
    return [cube(-0.15 + 0.03 * (look % 8), 0.20, "small")]


def test_no_move_starts_after_the_events_time_limit():
    runner = ScriptedRunner([_never_sorted(i) for i in range(300)])
    runner.time_limit_s = 180.0
    result = runner.run(lambda objects, given_up: policy(objects, given_up))
    assert result["moves"] == 4 and runner.clock_s == 200.0  # moves start at 0, 50, 100, 150 s; none at 200 s
    assert any("stopped at the event's time limit (180 s)" in f for f in result["failures"]), result["failures"]


def test_without_a_limit_the_same_job_goes_on():
    runner = ScriptedRunner([_never_sorted(i) for i in range(300)])
    result = runner.run(lambda objects, given_up: policy(objects, given_up))
    assert result["moves"] > 4 and not any("time limit" in f for f in result["failures"])
