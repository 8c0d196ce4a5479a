"""Sorting events: pick_sort (each block upright on its size's side) and sort_stack (L1 as pick_sort; L2/L3
each side's single column in rainbow order, and L3's distractors' centres kept out of y < 0)."""

from __future__ import annotations

from armlab.scene import SceneObject
from armlab.tasks.judge.geometry import RAINBOW, columns, upright
from armlab.tasks.judge.rules import Rule, bonus_rule, mm, tipped


def _on_its_side(block: SceneObject) -> bool:
    x, y, _ = block.position_m
    return y < 0.0 and (x < 0.0 if block.size == "small" else x > 0.0)


def _side_text(block: SceneObject) -> str:
    return f"{block.size} blocks go to y < 0, x {'<' if block.size == 'small' else '>'} 0"


def _side_rule(block: SceneObject, rule: str, points: int) -> Rule:
    if not upright(block):
        return tipped(block, rule)
    x, y, _ = block.position_m
    if not _on_its_side(block):
        return Rule(rule, 0, f"centre at ({mm(x)}, {mm(y)}): not on its side ({_side_text(block)})", (block.id,))
    return Rule(rule, points, f"upright on its side ({_side_text(block)})", (block.id,))


def score_pick_sort(level, blocks, within_limit, limit_s):
    rules = [_side_rule(block, "sorted", 30) for block in blocks]
    return [*rules, bonus_rule(10 * level, within_limit, limit_s, rules)], 30 * len(blocks) + 10 * level


def score_sort_stack(level, objects, blocks, within_limit, limit_s):
    if level == 1:
        rules = [_side_rule(block, "sorted", 30) for block in blocks]
    else:
        rules = []
        for size in ("large", "small"):
            rules.extend(_sorted_column_rules([b for b in blocks if b.size == size]))
        order = {block.id: i for i, block in enumerate(blocks)}
        rules.sort(key=lambda rule: order[rule.object_ids[0]])
    extra = [bonus_rule(10 * level, within_limit, limit_s, rules)]
    if level == 3:
        strays = tuple(obj.id for obj in objects if obj.type != "block" and obj.position_m[1] < 0.0)
        extra.append(Rule("distractors", 0 if strays else 90,
                          "distractors with centre at y < 0" if strays else "no distractor's centre at y < 0", strays))
    return [*rules, *extra], 30 * len(blocks) + 10 * level + (90 if level == 3 else 0)


def _sorted_column_rules(of_size: list[SceneObject]) -> list[Rule]:
    """sort_stack L2/L3 for one size: on its side and at its rainbow position in the side's single column."""
    ranks = [RAINBOW.index(b.color) for b in of_size]
    allowed = {b.id: (sum(r < rank for r in ranks) + 1, sum(r <= rank for r in ranks))
               for b, rank in zip(of_size, ranks)}

    def placed(stack) -> int:
        return sum(allowed[b.id][0] <= n <= allowed[b.id][1] and _on_its_side(b) for n, b in enumerate(stack, 1))

    side = [s for s in columns([b for b in of_size if upright(b)]) if _on_its_side(s[0])]
    chosen = max(side, key=lambda s: (len(s), placed(s))) if side else ()
    position = {b.id: n for n, b in enumerate(chosen, 1)}
    rules = []
    for block in of_size:
        first, last = allowed[block.id]
        wanted = f"position {first}" if first == last else f"position {first}-{last}"
        if not upright(block) or not _on_its_side(block):
            rules.append(_side_rule(block, "sorted", 0))
        elif block.id not in position:
            rules.append(Rule("sorted", 0, "on its side but not in the side's column", (block.id,)))
        elif not first <= position[block.id] <= last:
            rules.append(Rule("sorted", 0, f"at position {position[block.id]} of the side's column; rainbow order "
                                           f"wants {wanted}", (block.id,)))
        else:
            rules.append(Rule("sorted", 30, f"on its side at {wanted} of the side's column", (block.id,)))
    return rules
