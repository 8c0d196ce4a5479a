"""Seeded scene generators for every competition event and level of DESIGN §7 and for the sort_by_tag and
clear_table jobs, on a workcell's board, tags, reach, places, feed spot and bin."""

from __future__ import annotations

import numpy as np

from armlab.errors import InvalidInput
from armlab.scene.layout import SPACING_MARGIN_M, Region, block_items, board_regions, into_piles, place_piles
from armlab.scene.model import COLORS, DISTRACTOR_TYPES, SIZES, Feeder, Scene, as_workcell
from armlab.workcell import Workcell

# Event name -> levels defined for it (DESIGN §7). Order matters: it seeds the generators.
EVENTS: dict[str, tuple[int, ...]] = {
    "pick_sort": (1, 2, 3),
    "pick_stack": (1, 2, 3),
    "line_up": (1, 2, 3),
    "stack_high": (1, 2),
    "to_the_sky": (1,),
    "sort_stack": (1, 2, 3),
}
# Every job with a scene generator: the judged events plus sort_by_tag and clear_table (not judged by §7).
JOBS: dict[str, tuple[int, ...]] = {**EVENTS, "sort_by_tag": (1, 2, 3), "clear_table": (1, 2, 3)}


def generate_scene(event: str, level: int = 1, seed: int = 0, workcell: Workcell | str | None = None) -> Scene:
    """A starting layout for a job and level on `workcell` (its board, tags, reach, places, block tags and
    sizes; None = the default workcell), reproducible from (event, level, seed, workcell): the competition
    events of DESIGN §7 (EVENTS) and the sort_by_tag and clear_table jobs (JOBS). The scene remembers
    (event, level, seed) as its origin (the page's scene picker shows it) and the workcell it is for."""
    cell = as_workcell(workcell)
    scene = _generate_scene(event, level, seed, cell)
    return Scene(scene.objects, scene.feeder, origin=(event, int(level), int(seed)), workcell=cell.name)


def _generate_scene(event: str, level: int, seed: int, workcell: Workcell) -> Scene:
    if event not in JOBS:
        raise InvalidInput(f"unknown event {event!r}; events: {', '.join(JOBS)}")
    if level not in JOBS[event]:
        raise InvalidInput(f"event {event!r} has levels {JOBS[event]}, not {level!r}")
    rng = np.random.default_rng([int(seed), list(JOBS).index(event), int(level)])
    regions = board_regions(workcell)

    def random_colors(count: int) -> list[str]:
        return [str(c) for c in rng.choice(COLORS, size=count)]

    def distractors(count: int, sizes: bool = False) -> list[list[tuple]]:
        kinds = rng.choice(DISTRACTOR_TYPES, size=count)
        return [[(str(kind), str(rng.choice(SIZES)) if sizes else None, str(rng.choice(COLORS)))] for kind in kinds]

    def three_or_six_blocks(level: int, max_height: int) -> list[list[tuple]]:
        """§7's L1 (3 large R, G, B), L2 (3 large + 3 small, random colours), L3 (L2 piled up to max_height)."""
        if level == 1:
            return [[item] for item in block_items(["large"] * 3, ["red", "green", "blue"])]
        items = block_items(["large"] * 3 + ["small"] * 3, random_colors(6))
        return [[item] for item in items] if level == 2 else into_piles(items, max_height, 0.35, rng)

    rainbow = list(COLORS)
    if event == "pick_sort":
        if level < 3:
            piles = three_or_six_blocks(level, 1)
        else:
            sizes = [str(s) for s in rng.choice(SIZES, size=9)]
            piles = into_piles(block_items(sizes, random_colors(9)), 2, 0.35, rng)
        return place_piles(piles, regions["positive_half"], rng, workcell)
    if event == "pick_stack":
        return place_piles(three_or_six_blocks(level, 2), regions["tag_rectangle"], rng, workcell)
    if event == "sort_stack":
        piles = three_or_six_blocks(level, 2) + (distractors(2) if level == 3 else [])
        return place_piles(piles, regions["positive_half"], rng, workcell)
    if event == "line_up":
        items = block_items(["large"] * 6, rainbow)
        if level == 1:
            piles = [[item] for item in items]
        else:
            piles = into_piles(items + block_items(["small"] * 6, rainbow), 4, 0.4, rng)
        if level == 3:
            kinds = rng.choice(DISTRACTOR_TYPES, size=int(rng.integers(2, 5)))
            piles += [[(str(kind), None, str(rng.choice(COLORS)))] for kind in kinds]
        return place_piles(piles, regions["whole_board"], rng, workcell)
    if event == "stack_high":
        items = block_items(["large"] * 6, rainbow)
        if level == 1:
            piles = [[item] for item in items]
        else:
            piles = into_piles(items, 4, 0.4, rng) + into_piles(block_items(["small"] * 6, rainbow), 4, 0.4, rng)
        return place_piles(piles, regions["whole_board"], rng, workcell)
    if event == "to_the_sky":
        return _to_the_sky(rng, workcell, regions["whole_board"])
    if event == "sort_by_tag":
        return _sort_by_tag(level, rng, workcell, regions["positive_half"])
    return _clear_table(level, rng, workcell, regions["whole_board"], distractors)


def _to_the_sky(rng: np.random.Generator, workcell: Workcell, board: Region) -> Scene:
    """Large blocks only, as many as the board takes comfortably, clear of the feed spot; plus the feeder."""
    spec = workcell.feeder
    feeder = Feeder(spot_m=spec.spot_m, count=spec.count)
    keepout = (*spec.spot_m, spec.clear_radius_m + SPACING_MARGIN_M)
    region = Region(board.x_m, board.y_m, keepout_circles=(keepout,))
    items = block_items(["large"] * 10, [COLORS[i % 6] for i in range(10)])
    return place_piles([[item] for item in items], region, rng, workcell, feeder)


def _sort_by_tag(level: int, rng: np.random.Generator, workcell: Workcell, half: Region) -> Scene:
    """Blocks with ArUco tops (id and colour from the workcell's block_tags), in y > 0, clear of the places.
    L1: one large block per id; L2: 6 blocks of random sizes and ids (ids repeat); L3: 8, piled up to 2 high."""
    tags = workcell.block_tags.ids
    if not tags:
        raise InvalidInput(f"sort_by_tag needs block_tags.ids in the workcell config {workcell.name!r}")
    ids = sorted(tags)
    if level == 1:
        chosen, sizes = ids, ["large"] * len(ids)
    else:
        count = 6 if level == 2 else 8
        chosen = [int(i) for i in rng.choice(ids, size=count)]
        sizes = [str(s) for s in rng.choice(SIZES, size=count)]
    items = [("block", size, tags[tag_id].color, tag_id) for size, tag_id in zip(sizes, chosen)]
    piles = [[item] for item in items] if level < 3 else into_piles(items, 2, 0.35, rng)
    keepouts = tuple((x, y, 0.04) for x, y in workcell.places_m.values())
    region = Region(half.x_m, half.y_m, keepout_circles=keepouts)
    return place_piles(piles, region, rng, workcell)


def _clear_table(level: int, rng: np.random.Generator, workcell: Workcell, board: Region, distractors) -> Scene:
    """Random blocks and distractors (any colour, shape and size) anywhere reachable outside the bin.
    L1: 3 blocks + 1 distractor; L2: 5 + 2; L3: 6 + 3, blocks piled up to 2 high."""
    n_blocks, n_distractors = {1: (3, 1), 2: (5, 2), 3: (6, 3)}[level]
    sizes = [str(s) for s in rng.choice(SIZES, size=n_blocks)]
    colors = [str(c) for c in rng.choice(COLORS, size=n_blocks)]
    items = block_items(sizes, colors)
    piles = [[item] for item in items] if level < 3 else into_piles(items, 2, 0.35, rng)
    piles += distractors(n_distractors, sizes=True)
    bin_ = workcell.bin
    region = Region(board.x_m, board.y_m, keepout_rects=((*bin_.x_range_m, *bin_.y_range_m),))
    return place_piles(piles, region, rng, workcell)
