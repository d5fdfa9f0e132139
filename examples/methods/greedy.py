"""A method that needs no model: each step, a greedy choice among every robot's actions.

It reads the task's goal (``on_<a>(i)_<b>(j)``, ``inside_<a>(i)_<b>(j)``), sees in the
robots' observations which parts already hold, and scores each robot's actions of the
step: putting a thing where the goal wants it first, then grabbing such a thing, opening
a container the goal names, walking or flying towards the things the goal names, then
towards rooms not yet visited; an action it has tried before counts less each time, so
that it explores instead of circling. It is a baseline to copy and change, not a planner: it has no lookahead.

    coherent run TASK --method examples/methods/greedy.py:Greedy
    coherent bench --tasks ../shared/coherent-original/env --subset paper40 \\
        --methods optimal,examples/methods/greedy.py:Greedy --out greedy.jsonl

or from Python: ``coherent.bench(tasks, ["optimal", Greedy])``.
"""

from __future__ import annotations

import re
from collections import Counter

import coherent

GOAL = re.compile(r"^(on|inside)_<.+?>\((\d+)\)_<.+?>\((\d+)\)$")
VERB = re.compile(r"^\[(\w+)\]")
IDS = re.compile(r"\((\d+)\)")


class Greedy:
    """Scores every robot's actions against the goals that do not hold yet."""

    name = "greedy"

    def __init__(self, task: coherent.Task) -> None:
        # (relation, the thing to place, where): ("INSIDE", 26, 51).
        self.goals = []
        for predicate in task.goal:
            match = GOAL.match(predicate)
            if match:
                relation, thing, place = match.groups()
                self.goals.append((relation.upper(), int(thing), int(place)))
        self.tried: Counter[tuple[int, str]] = Counter()
        # The rooms each robot has been in.
        self.visited: dict[int, set[int]] = {}

    def act(self, view: coherent.View) -> coherent.Decision:
        seen = set()
        for robot in view.robots:
            observation = view.observation(robot)
            self.visited.setdefault(robot, set()).add(observation["room"])
            for edge in observation["edges"]:
                seen.add((edge["relation_type"], edge["from_id"], edge["to_id"]))
        open_goals = [(rel, thing, place) for rel, thing, place in self.goals if (rel, thing, place) not in seen]
        things = {thing for _, thing, _ in open_goals}
        places = {place for _, _, place in open_goals}
        pairs = {(thing, place) for _, thing, place in open_goals}

        best: tuple[float, int, str] | None = None
        for robot, actions in view.actions.items():
            for action in actions:
                score = self.score(robot, action, things, places, pairs, self.visited[robot])
                score -= 20 * self.tried[(robot, action)]
                if best is None or score > best[0]:
                    best = (score, robot, action)
        if best is None:
            return coherent.Decision(None, None, note="no robot can act")
        score, robot, action = best
        self.tried[(robot, action)] += 1
        return coherent.Decision(robot, action, note=f"score {score:g}, {len(open_goals)} goal(s) left")

    @staticmethod
    def score(
        robot: int, action: str, things: set[int], places: set[int], pairs: set[tuple[int, int]], visited: set[int]
    ) -> float:
        verb = VERB.match(action)
        ids = [int(i) for i in IDS.findall(action)]
        if verb is None or not ids:
            return 0
        verb_name = verb.group(1)
        if verb_name in ("puton", "putinto") and len(ids) == 2 and (ids[0], ids[1]) in pairs:
            return 100
        if verb_name == "land_on" and (robot, ids[0]) in pairs:
            return 100
        if verb_name == "grab":
            return 60 if ids[0] in things else -5
        if verb_name == "open":
            return 30 if ids[0] in places else 15
        if verb_name == "movetowards":
            if ids[0] in things | places:
                return 25
            return 1 if ids[0] in visited else 5
        if verb_name == "takeoff_from":
            return 8
        if verb_name == "close":
            return -10
        return 0
