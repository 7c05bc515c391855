"""Split a frame's tile plan between farm tasks so that every task costs about the same.

The rectangles come from the director maps, which the job computes after it is submitted, so
a job has a fixed number K of tile tasks per frame and each takes its share with
``plan_group`` once the plan exists; every task computes the same partition, so together they
render each rectangle once. A rectangle costs its pixels times its samples plus
``render_cost`` (the plan's own model); the partition is the longest-processing-time rule
(Graham 1969), whose largest group is at most 4/3 of the best possible."""
from __future__ import annotations

import heapq
from dataclasses import dataclass

from ..errors import SettingError
from ..option_table import MAX_GROUPS, OPTIONS  # noqa: F401 (the bound of check_groups)
from ..sampling.tile_plan import Rect

#: More tile tasks per frame than this is a submission mistake, not a plan (a 4K frame at
#: the smallest tile has ~130k rectangles, but a farm job of a million tasks is no help).


def rect_cost(rect: Rect, render_cost: int) -> int:
    """Pixel-samples one rectangle costs: pixels x samples + the fixed cost of a render."""
    return rect.samples + render_cost


def check_groups(groups: int) -> int:
    """``groups`` if it is a sensible number of tile tasks per frame, else InputError."""
    return OPTIONS["tasks_per_frame"].check(groups)


def partition(costs: list[int], groups: int) -> list[list[int]]:
    """Indices of ``costs`` in ``groups`` lists whose sums are as equal as LPT makes them.

    Deterministic: equal costs go in index order and equal loads to the lowest group, so
    every task of a farm job computes the same partition. Each list is sorted (plan order).
    """
    check_groups(groups)
    order = sorted(range(len(costs)), key=lambda index: (-costs[index], index))
    loads = [(0, group) for group in range(groups)]     # a heap of (cost so far, group)
    members: list[list[int]] = [[] for _ in range(groups)]
    for index in order:
        load, group = heapq.heappop(loads)
        members[group].append(index)
        heapq.heappush(loads, (load + costs[index], group))
    return [sorted(indices) for indices in members]


@dataclass(frozen=True)
class Grouping:
    """A plan's rectangles split into tile tasks, and how even the split is."""

    groups: list[list[int]]         # rectangle indices (into plan.rects) of each task
    costs: list[int]                # pixel-samples of each task

    @property
    def balance(self) -> float:
        """Most expensive task / mean task cost: 1.0 is a perfect split (0 for an empty plan)."""
        total = sum(self.costs)
        return max(self.costs) * len(self.costs) / total if total else 0.0

    def to_dict(self) -> dict:
        return {"groups": len(self.groups), "rects_per_group": [len(g) for g in self.groups],
                "costs": self.costs, "balance": self.balance}


def group_plan(rects: list[Rect], groups: int, render_cost: int) -> Grouping:
    """Split ``rects`` into ``groups`` tile tasks of about equal cost."""
    costs = [rect_cost(rect, render_cost) for rect in rects]
    members = partition(costs, groups)
    return Grouping(members, [sum(costs[i] for i in indices) for indices in members])


def plan_group(rects: list[Rect], group: int, groups: int, render_cost: int) -> list[Rect]:
    """The rectangles tile task ``group`` (1..groups, as the job template counts) renders."""
    check_groups(groups)
    if not 1 <= group <= groups:
        raise SettingError("{group.name} must be between 1 and {groups} (got {group.value})",
                           group=group, groups=groups)
    return [rects[index] for index in group_plan(rects, groups, render_cost).groups[group - 1]]
