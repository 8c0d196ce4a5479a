"""The competition judge (DESIGN §7): points for a finished run from the final ground truth, the run's
simulated time and the gripper path. A pure function of those; perception never uses it.

Readings chosen where §7 leaves a choice (one line each):
- Thresholds are inclusive ("within 15°/30 mm" means <=), side tests strict (y < 0, x > 0), neatness strict (< 300 mm).
- Distances between centres are horizontal (xy); "on the board" and stacking use centre z -/+ edge/2 whatever the tilt.
- columns(): blocks only (a block on a distractor is in no column); blocks join lowest first, onto the nearest top.
- pick_sort / sort_stack sides: a block need not rest on the board; its centre decides (y < 0, then x by size).
- pick_stack: columns hold all blocks (any size, tipped ones too) and count them all; only upright blocks score.
- stack_high, to_the_sky, sort_stack: columns are built from upright blocks of one size, so a tipped or other-size block
  ends the column under it.
- line_up L1 and stack_high L1 score large blocks only (their max has no small line or column).
- line_up: a line's blocks are ordered by projection on the TLS direction (ties by id); the direction giving more
  points (neatness included) is used.
- line_up: a block that misses +30 gets +10 if within 60 mm of the line, whatever its colour.
- line_up neatness needs exactly six blocks in the line; its length is the xy distance between first and last centres.
- line_up L3: a line's segment spans its blocks' projections on the TLS line; a distractor's distance is from its
  centre (xy); the +100 needs both lines to hold at least one block.
- stack_high: +40 needs the column to be exactly red, orange, yellow, green, blue, violet bottom-up.
- sort_stack L2/L3: the side's single column is the tallest column of that size's upright blocks whose bottom block is
  on the side (equal heights: the one scoring more).
- sort_stack L2/L3: a block's expected position is 1 + the number of blocks of its size (all in truth) with a lower
  rainbow rank; blocks of equal colour may take their positions either way.
- Time: over the limit loses only the level bonus (pick_sort, pick_stack, sort_stack); other points stand, and the
  line_up / sort_stack distractor points are not a bonus. within_limit is sim_time_s <= limit.
- "Every block scoring" (bonus) is over all blocks in truth; pick_stack's bonus also needs a recorded gripper path,
  and an empty path (no samples after the first motion) never left the box.
- to_the_sky: blocks_available may not be below the number of large blocks in truth; other events refuse it.
"""

from armlab.tasks.judge.geometry import (
    RAINBOW,
    STACK_XY_TOLERANCE_M,
    SURFACE_TOLERANCE_M,
    UPRIGHT_MAX_TILT_RAD,
    columns,
    on_board,
    tilt_rad,
    tls_line,
    upright,
)
from armlab.tasks.judge.inputs import EVENT_LIMITS_S
from armlab.tasks.judge.lines import DISTRACTOR_CLEARANCE_M, LINE_FAR_M, LINE_NEAR_M, NEAT_LENGTH_M
from armlab.tasks.judge.rules import Rule, Score
from armlab.tasks.judge.stacking import (
    GRIPPER_BOX_M,
    PICK_STACK_MIN_HEIGHT,
    TAG_RADIUS_M,
    board_tag_centres_m,
    tower_points,
)
from armlab.tasks.judge.verdict import judge

__all__ = [
    "DISTRACTOR_CLEARANCE_M",
    "EVENT_LIMITS_S",
    "GRIPPER_BOX_M",
    "LINE_FAR_M",
    "LINE_NEAR_M",
    "NEAT_LENGTH_M",
    "PICK_STACK_MIN_HEIGHT",
    "RAINBOW",
    "Rule",
    "STACK_XY_TOLERANCE_M",
    "SURFACE_TOLERANCE_M",
    "Score",
    "TAG_RADIUS_M",
    "UPRIGHT_MAX_TILT_RAD",
    "board_tag_centres_m",
    "columns",
    "judge",
    "on_board",
    "tilt_rad",
    "tls_line",
    "tower_points",
    "upright",
]
