#!/usr/bin/env python3
"""Builds the project's own benchmark: five scenes with geometry, one hundred tasks.

    python3 benchmark/make.py --coherent target/release/coherent

Each scene is written below as rooms, doors, stairs, furniture, objects and robots in
metres. From each scene the script draws candidate tasks from goal templates (a goal
of one to three predicates, with the robots starting in varied places), has `coherent
plan` solve every candidate, carries the optimal plans of the wanted ones out in physics
(`coherent plan --physics`), and keeps, per scene, tasks of the three types the planner
computes (mono, dual, trio: the fewest robot types that reach the goal) with ground
truth in each type's range (mono 4-8 steps, dual 8-12, trio 10-16) and a plan that runs
in physics. Nothing about a task's type or its ground truth is hand-set: both come from
the planner's output, and the files record the planner's `optimal_steps` as
`ground_truth`. The renders in benchmark/renders are `coherent render --plan` of task 19
of each scene (see benchmark/README.md).

The height labels (HIGH_HEIGHT, LOW_HEIGHT, ON_HIGH_SURFACE) are not written either:
the tasks run under the `geometric` rule set, which derives them from the geometry and
the robot specs when a file is read.

The draw is seeded, so the same script and the same planner give the same files.
Standard library only.
"""

from __future__ import annotations

import argparse
import json
import random
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
SEED = 20261122
GT_RANGE = {"mono": (4, 8), "dual": (8, 12), "trio": (10, 16)}
# Per scene: how many of each type (32 mono, 30 dual, 38 trio over the five scenes).
QUOTA = {
    "s1-apartment": {"mono": 6, "dual": 6, "trio": 8},
    "s2-apartment": {"mono": 6, "dual": 6, "trio": 8},
    "s3-grocery": {"mono": 7, "dual": 6, "trio": 7},
    "s4-restaurant": {"mono": 7, "dual": 6, "trio": 7},
    "s5-house": {"mono": 6, "dual": 6, "trio": 8},
}
# Dual tasks in range are the rarest draw (most dual templates turn out mono or trio,
# or longer than 12 steps), so their templates are drawn more often.
DRAW_WEIGHT = {"mono": 1.0, "dual": 3.0, "trio": 1.5}
# The 40-task subset, in the paper's proportions: per scene 2 mono, 3 dual, 3 trio.
SUBSET40 = {"mono": 2, "dual": 3, "trio": 3}
GAP = 0.06
WALL = 0.04
# The robots, written into every task so that the files say what they assume (these are
# coherent_core::geometry::RobotSpecs' defaults; docs/physics.md explains each field):
# the legged robot's body, shoulder and arm links (its hand reaches 1.34 m), the fixed
# arm's shoulder above its counter and links (1.25 m reach), the quadrotor's mass, frame,
# basket, cruise altitude and speed.
SPECS = {
    "dog_half": [0.3, 0.2, 0.3], "dog_shoulder": [0.0, 0.47, 0.15], "dog_links": [0.45, 0.4],
    "dog_speed": 1.0, "arm_shoulder": 0.3, "arm_links": [0.65, 0.6], "quad_mass": 1.5,
    "quad_half": 0.3, "basket_half": 0.22, "cruise_altitude": 1.9, "flight_speed": 1.0,
    "low_top": 0.45, "high_top": 1.4,
}
# A counter with a fixed arm (width x, height y, depth z): its top is high for the legged
# robot, its right metre is the quadrotor's landing pad and its back strip the arm's.
ARM_TABLE = (2.0, 1.1, 1.2)


class Scene:
    """A scene under construction: graph nodes and edges plus their geometry."""

    def __init__(self, name: str, title: str):
        self.name = name
        self.title = title
        self.nodes: list[dict] = []
        self.edges: list[tuple[int, str, int]] = []
        self.rooms: dict[int, dict] = {}
        self.doors: list[dict] = []
        self.stairs: list[dict] = []
        self.items: dict[int, dict] = {}
        self.floor: dict[int, int] = {}
        self.room_of: dict[int, int] = {}
        self.holder: dict[int, tuple[int, bool]] = {}
        self.arms: list[tuple[int, int, list[float]]] = []
        self.quadrotor = self.basket = self.dog = -1
        self.spots_for_dog: dict[int, list[tuple[float, float]]] = {}

    def _node(self, category, name, props=(), states=()):
        i = len(self.nodes)
        self.nodes.append(
            {
                "id": i,
                "category": category,
                "class_name": name,
                "prefab_name": name.replace(" ", "_"),
                "properties": list(props),
                "states": list(states),
            }
        )
        return i

    def room(self, name, lo, hi, level=0.0, dog_spots=()):
        r = self._node("Rooms", name)
        f = self._node("Floor", f"{name} floor", ["SURFACES", "LANDABLE"])
        self.edges.append((f, "INSIDE", r))
        self.rooms[r] = {"id": r, "min": list(lo), "max": list(hi), "level": level}
        self.floor[r] = f
        self.spots_for_dog[r] = list(dog_spots)
        return r

    def door(self, a, b, center, along_x, closed):
        d = self._node(
            "Doors", "door", ["CAN_OPEN"], ["CLOSED" if closed else "OPEN"]
        )
        self.edges += [(d, "LEADING TO", a), (d, "LEADING TO", b)]
        self.doors.append(
            {
                "id": d,
                "rooms": [a, b],
                "center": list(center),
                "along_x": along_x,
                "width": 1.3,
                "height": 2.3,
            }
        )
        return d

    def flight(self, lower, upper, foot, head, width):
        s = self._node("Doors", "stairs", [], ["OPEN"])
        self.edges += [(s, "LEADING TO", lower), (s, "LEADING TO", upper)]
        self.stairs.append(
            {"id": s, "rooms": [lower, upper], "foot": list(foot), "head": list(head),
             "width": width}
        )
        return s

    def furniture(self, name, room, xz, size, *, surface=True, container=False,
                  lid="none", landable=False, closed=None, category="Furniture"):
        props = []
        if surface:
            props.append("SURFACES")
        if landable:
            props.append("LANDABLE")
        if container:
            props.append("CONTAINERS")
        states = []
        if closed is not None:
            props.append("CAN_OPEN")
            states.append("CLOSED" if closed else "OPEN")
        elif container:
            # No door or lid: always open (as the quadrotor's basket), never closed.
            states.append("OPEN_FOREVER")
        n = self._node(category, name, props, states)
        level = self.rooms[room]["level"]
        self.items[n] = {
            "id": n,
            "pos": [xz[0], level, xz[1]],
            "size": list(size),
            "container": container,
            "lid": lid,
            "dynamic": False,
        }
        self.edges.append((n, "ON", self.floor[room]))
        self.room_of[n] = room
        return n

    def obj(self, name, category, size, holder, inside=False, container=False,
            lid="none", closed=None):
        props = ["GRABABLE", "MOVABLE"]
        states = []
        if container:
            props.append("CONTAINERS")
        if closed is not None:
            props.append("CAN_OPEN")
            states.append("CLOSED" if closed else "OPEN")
        elif container:
            # No door or lid: always open (as the quadrotor's basket), never closed.
            states.append("OPEN_FOREVER")
        n = self._node(category, name, props, states)
        self.items[n] = {
            "id": n,
            "pos": [0.0, 0.0, 0.0],
            "size": list(size),
            "container": container,
            "lid": lid,
            "dynamic": True,
        }
        self.holder[n] = (holder, inside)
        return n

    def arm(self, table):
        """A fixed arm on `table`, left of centre in the strip kept free at the back, so
        that it reaches the far corner of the table and the quadrotor's landing pad."""
        a = self._node("Agents", "robot arm")
        g = self.items[table]
        xz = [g["pos"][0] - 0.2, g["pos"][2] + g["size"][2] / 2 - 0.175]
        self.arms.append((a, table, xz))
        return a

    def team(self):
        self.quadrotor = self._node(
            "Agents", "quadrotor", ["MOVABLE", "FLYABLE", "HAVE_A_BASKET"], ["LAND"]
        )
        self.basket = self._node(
            "AgentTool", "basket", ["MOVABLE", "CONTAINERS", "WITH_QUADROTOR"],
            ["OPEN_FOREVER"],
        )
        self.dog = self._node("Agents", "robot dog", ["MOVABLE"])

    # -- one task's start -------------------------------------------------------------

    def landables(self):
        out = [f for f in self.floor.values()]
        out += [n for n, node in enumerate(self.nodes)
                if "LANDABLE" in node["properties"] and n in self.room_of]
        return out

    def clear(self, room, x, z, r):
        """Whether a disc of radius `r` at (x, z) is inside `room`, `r` from its walls, and
        `r` from its furniture and any flight of stairs in it."""
        rm = self.rooms[room]
        if not (rm["min"][0] + r <= x <= rm["max"][0] - r
                and rm["min"][1] + r <= z <= rm["max"][1] - r):
            return False
        boxes = [(g["pos"][0], g["pos"][2], g["size"][0] / 2, g["size"][2] / 2)
                 for n, g in self.items.items() if self.room_of.get(n) == room]
        for f in self.stairs:
            if room in f["rooms"]:
                (x0, z0), (x1, z1) = f["foot"], f["head"]
                w = f["width"] / 2
                boxes.append(((x0 + x1) / 2, (z0 + z1) / 2,
                              abs(x1 - x0) / 2 + (w if x0 == x1 else 0),
                              abs(z1 - z0) / 2 + (w if z0 == z1 else 0)))
        for cx, cz, hx, hz in boxes:
            dx = max(abs(x - cx) - hx, 0.0)
            dz = max(abs(z - cz) - hz, 0.0)
            if (dx * dx + dz * dz) ** 0.5 < r:
                return False
        return True

    def open_floor(self, room, avoid=None):
        """A spot on `room`'s floor with 0.7 m clear all round and 1.2 m from `avoid` (the
        legged robot's start), the nearest to its middle on a 10 cm grid: where the
        quadrotor lands on that floor."""
        rm = self.rooms[room]
        mx, mz = (rm["min"][0] + rm["max"][0]) / 2, (rm["min"][1] + rm["max"][1]) / 2
        spots = [(rm["min"][0] + i / 10, rm["min"][1] + k / 10)
                 for i in range(int((rm["max"][0] - rm["min"][0]) * 10) + 1)
                 for k in range(int((rm["max"][1] - rm["min"][1]) * 10) + 1)]
        spots = [p for p in spots if self.clear(room, p[0], p[1], 0.7)
                 and (avoid is None or (p[0] - avoid[0]) ** 2 + (p[1] - avoid[1]) ** 2 > 1.44)]
        if not spots:
            raise ValueError(f"{self.name}: no open floor in {self.nodes[room]['class_name']}")
        return min(spots, key=lambda p: ((p[0] - mx) ** 2 + (p[1] - mz) ** 2, p))

    def base(self, n):
        """The furniture (or floor) a thing is on or in, through any objects between."""
        while n in self.holder:
            n = self.holder[n][0]
        return n

    def where(self, n):
        """The room a furniture item, floor or object is in."""
        n = self.base(n)
        if n in self.room_of:
            return self.room_of[n]
        return next(r for r, f in self.floor.items() if f == n)

    def build(self, task_id, goal, dog_room, dog_spot, quad_on):
        """The native task: the scene, with the legged robot starting at `dog_spot` in
        `dog_room` and the quadrotor landed on `quad_on`."""
        holder = self.holder
        items = {k: dict(v, pos=list(v["pos"])) for k, v in self.items.items()}
        edges = list(self.edges)
        # Objects packed on or in their holders, in id order, holders first.
        used: dict[tuple[int, bool], list[float]] = {}
        placed = set(self.room_of)
        pending = sorted(holder)
        while pending:
            rest = []
            for n in pending:
                h, inside = holder[n]
                if h not in placed and h not in self.floor.values():
                    rest.append(n)
                    continue
                g = items[n]
                if h in self.floor.values():
                    raise ValueError(f"{self.name}: {self.nodes[n]['class_name']} on a floor")
                hg = items[h]
                x, z = self._spot(used, h, inside, hg, g["size"])
                y = hg["pos"][1] + (min(WALL, hg["size"][1] / 4) if inside else hg["size"][1])
                g["pos"] = [round(x, 3), round(y, 3), round(z, 3)]
                edges.append((n, "INSIDE" if inside else "ON", h))
                placed.add(n)
            if len(rest) == len(pending):
                raise ValueError(f"{self.name}: cannot place {rest}")
            pending = rest
        robots_geom = []
        for a, table, xz in self.arms:
            tg = items[table]
            edges += [(a, "ON", table), (a, "INSIDE", self.room_of[table])]
            robots_geom.append({"id": a, "pos": [xz[0], tg["pos"][1] + tg["size"][1], xz[1]],
                                "yaw": 0.0})
        # The quadrotor on a landable top (right end) or on a floor.
        q_room = self.where(quad_on)
        edges += [(self.quadrotor, "ON", quad_on), (self.quadrotor, "INSIDE", q_room),
                  (self.quadrotor, "WITH", self.basket), (self.basket, "ON", quad_on)]
        if quad_on in items:
            sg = items[quad_on]
            qpos = [sg["pos"][0] + sg["size"][0] / 2 - 0.5, sg["pos"][1] + sg["size"][1],
                    sg["pos"][2]]
        else:
            x, z = self.open_floor(q_room, dog_spot if q_room == dog_room else None)
            qpos = [x, self.rooms[q_room]["level"], z]
        robots_geom.append({"id": self.quadrotor, "pos": [round(v, 3) for v in qpos],
                            "yaw": 0.0})
        if not self.clear(dog_room, dog_spot[0], dog_spot[1], 0.6):
            raise ValueError(f"{self.name}: the legged robot's start {dog_spot} in "
                             f"{self.nodes[dog_room]['class_name']} is not clear")
        edges += [(self.dog, "ON", self.floor[dog_room]), (self.dog, "INSIDE", dog_room)]
        level = self.rooms[dog_room]["level"]
        robots_geom.append({"id": self.dog, "pos": [dog_spot[0], level, dog_spot[1]],
                            "yaw": 0.0})
        robots = [{"id": a, "type": "robot arm"} for a, _, _ in self.arms]
        robots += [{"id": self.quadrotor, "type": "quadrotor"},
                   {"id": self.dog, "type": "robot dog"}]
        return {
            "format": "coherent-task",
            "version": 1,
            "scene": self.name,
            "task_id": task_id,
            "name": "",
            "rules": "geometric",
            "instruction": self.instruction(goal),
            "goal": [{"relation": rel, "subject": s, "target": t, "count": 1}
                     for s, rel, t in goal],
            "robots": robots,
            "graph": {
                "nodes": self.nodes,
                "edges": [{"from_id": a, "to_id": b, "relation_type": r}
                          for a, r, b in edges],
            },
            "geometry": {
                "specs": SPECS,
                "rooms": list(self.rooms.values()),
                "doors": self.doors,
                **({"stairs": self.stairs} if self.stairs else {}),
                "items": [items[k] for k in sorted(items)],
                "robots": robots_geom,
            },
        }

    def _spot(self, used, h, inside, hg, size):
        """Where the next thing goes on (or in) `h`: rows from the front edge, left to
        right; a landable top keeps its right metre free for the quadrotor and an arm's
        table keeps its back 0.35 m free for the arm."""
        rim = WALL + GAP if inside else GAP
        left = hg["pos"][0] - hg["size"][0] / 2 + rim
        right = hg["pos"][0] + hg["size"][0] / 2 - rim - (1.0 if self._pad(h) and not inside else 0.0)
        front = hg["pos"][2] - hg["size"][2] / 2 + rim
        back = hg["pos"][2] + hg["size"][2] / 2 - rim - (
            0.35 if self._arm_on(h) is not None and not inside else 0.0)
        row_depth = 0.3
        cursor = used.setdefault((h, inside), [left, front])
        if cursor[0] + size[0] > right:
            cursor[0], cursor[1] = left, cursor[1] + row_depth + GAP
        if cursor[0] + size[0] > right or cursor[1] + size[2] > back:
            raise ValueError(f"{self.name}: no room for a {size} thing on {self.nodes[h]['class_name']}")
        x = cursor[0] + size[0] / 2
        z = cursor[1] + row_depth / 2
        cursor[0] += size[0] + GAP
        return x, z

    def _pad(self, h):
        return "LANDABLE" in self.nodes[h]["properties"]

    def _arm_on(self, h):
        return next((a for a, t, _ in self.arms if t == h), None)

    def label(self, n):
        return f"<{self.nodes[n]['class_name']}>({n})"

    def instruction(self, goal):
        """The goal in English, each place with its room ("on the landing", "in the
        kitchen"); the quadrotor's basket goes wherever the quadrotor is."""
        parts = []
        for s, rel, t in goal:
            room = self.nodes[self.where(t)]["class_name"] if t != self.basket else None
            where = "in" if rel == "INSIDE" else "on"
            at = "on" if room in ("landing", "sales floor") else "in"
            place = f"{self.label(t)}" + (f" {at} the {room}" if room else "")
            parts.append(f"the {self.label(s)} {where} the {place}")
        text = "Put " + ", ".join(parts[:-1]) + (" and " if len(parts) > 1 else "") + parts[-1]
        return text + "."


# ---------------------------------------------------------------------------------------
# The five scenes. Furniture sizes are (width x, height y, depth z); a fixed arm stands at
# the back of its table. Tops above 1.04 m are high for the legged robot (its hand gets
# to 1.34 m and the tallest object is 0.30 m).

def s1_apartment() -> Scene:
    s = Scene("s1-apartment", "Apartment A: kitchen, living room, bedroom, bathroom")
    kitchen = s.room("kitchen", (0, 0), (5, 4), dog_spots=[(2.5, 2.0)])
    living = s.room("living room", (5, 0), (11, 5), dog_spots=[(8.0, 3.0)])
    bedroom = s.room("bedroom", (5, 5), (10, 9), dog_spots=[(8.0, 6.5)])
    bath = s.room("bathroom", (0, 4), (5, 7), dog_spots=[(2.5, 5.5)])
    s.door(kitchen, living, (5, 2.0), False, closed=False)
    s.door(living, bedroom, (8.0, 5), True, closed=True)
    s.door(kitchen, bath, (1.5, 4), True, closed=True)
    island = s.furniture("kitchen island", kitchen, (2.5, 0.7), ARM_TABLE, landable=True)
    fridge = s.furniture("fridge", kitchen, (0.5, 3.4), (0.7, 1.8, 0.7), surface=False,
                         container=True, lid="front", closed=True, category="Appliances")
    dining = s.furniture("dining table", kitchen, (3.8, 3.0), (1.4, 0.75, 1.0), landable=True)
    cabinet = s.furniture("kitchen cabinet", kitchen, (2.6, 3.6), (0.8, 0.9, 0.6), container=True,
                          lid="front", closed=True)
    coffee = s.furniture("coffee table", living, (8.0, 1.5), (1.2, 0.45, 1.0), landable=True)
    sofa = s.furniture("sofa", living, (8.0, 0.5), (2.0, 0.45, 0.8))
    shelf = s.furniture("bookshelf", living, (10.5, 3.5), (0.4, 1.6, 1.2))
    tv = s.furniture("tv stand", living, (6.0, 4.6), (1.4, 0.5, 0.5))
    box = s.furniture("storage box", living, (10.4, 0.6), (0.6, 0.45, 0.5), surface=False,
                      container=True, lid="top", closed=True)
    bed = s.furniture("bed", bedroom, (6.5, 8.0), (1.8, 0.55, 1.6), landable=True)
    night = s.furniture("nightstand", bedroom, (8.0, 8.7), (0.5, 0.55, 0.5))
    wardrobe = s.furniture("wardrobe", bedroom, (9.4, 8.6), (1.0, 1.9, 0.6), surface=False,
                           container=True, lid="front", closed=True)
    sink = s.furniture("sink counter", bath, (3.8, 6.6), (1.2, 0.85, 0.6))
    laundry = s.furniture("laundry basket", bath, (1.0, 6.5), (0.5, 0.5, 0.5), surface=False,
                          container=True)
    s.arm(island)
    s.obj("mug", "Tableware", (0.09, 0.10, 0.09), island)
    s.obj("plate", "Tableware", (0.24, 0.03, 0.24), island)
    s.obj("bread", "Food", (0.25, 0.12, 0.12), island)
    s.obj("bread basket", "Containers", (0.32, 0.12, 0.26), island, container=True)
    s.obj("apple", "Fruit", (0.08, 0.08, 0.08), fridge, inside=True)
    s.obj("milk", "Drinks", (0.09, 0.25, 0.09), fridge, inside=True)
    s.obj("bowl", "Tableware", (0.16, 0.07, 0.16), dining)
    s.obj("pan", "Cookware", (0.28, 0.06, 0.28), cabinet, inside=True)
    s.obj("remote control", "Electronics", (0.05, 0.03, 0.17), coffee)
    s.obj("magazine", "Books", (0.21, 0.01, 0.28), sofa)
    s.obj("book", "Books", (0.17, 0.24, 0.04), shelf)
    s.obj("vase", "Decor", (0.12, 0.30, 0.12), shelf)
    s.obj("toy car", "Toys", (0.15, 0.08, 0.08), box, inside=True)
    s.obj("phone", "Electronics", (0.08, 0.01, 0.16), night)
    s.obj("pillow", "Bedding", (0.5, 0.12, 0.3), bed)
    s.obj("jacket", "Clothes", (0.4, 0.08, 0.3), wardrobe, inside=True)
    s.obj("towel", "Bathroom", (0.3, 0.06, 0.2), sink)
    s.obj("shirt", "Clothes", (0.3, 0.04, 0.25), laundry, inside=True)
    s.obj("lamp", "Decor", (0.18, 0.30, 0.18), tv)
    s.team()
    return s


def s2_apartment() -> Scene:
    s = Scene("s2-apartment", "Apartment B: a hall with kitchen, living room, study, bedroom")
    hall = s.room("hall", (0, 0), (2.5, 9), dog_spots=[(1.25, 4.5)])
    kitchen = s.room("kitchen", (2.5, 0), (7.5, 4), dog_spots=[(3.6, 2.2)])
    living = s.room("living room", (2.5, 4), (8.5, 9), dog_spots=[(4.0, 6.5)])
    study = s.room("study", (-4, 5), (0, 9), dog_spots=[(-2.0, 7.0)])
    bedroom = s.room("bedroom", (-4, 0), (0, 5), dog_spots=[(-2.0, 3.2)])
    s.door(hall, kitchen, (2.5, 2.0), False, closed=False)
    s.door(hall, living, (2.5, 6.5), False, closed=False)
    s.door(hall, study, (0, 7.0), False, closed=True)
    s.door(hall, bedroom, (0, 2.5), False, closed=True)
    bar = s.furniture("bar counter", kitchen, (5.2, 0.7), ARM_TABLE, landable=True)
    fridge = s.furniture("fridge", kitchen, (7.0, 3.5), (0.7, 1.8, 0.7), surface=False,
                         container=True, lid="front", closed=True, category="Appliances")
    pantry = s.furniture("pantry shelf", kitchen, (4.2, 3.75), (1.0, 1.5, 0.4))
    table = s.furniture("kitchen table", kitchen, (5.3, 2.6), (1.8, 0.75, 1.0), landable=True)
    sofa = s.furniture("sofa", living, (5.5, 8.5), (2.0, 0.45, 0.8))
    coffee = s.furniture("coffee table", living, (5.5, 7.2), (1.8, 0.45, 1.0), landable=True)
    tv = s.furniture("tv stand", living, (5.5, 4.35), (1.4, 0.5, 0.5))
    chest = s.furniture("toy chest", living, (8.0, 5.0), (0.6, 0.45, 0.5), surface=False,
                        container=True, lid="top", closed=True)
    desk = s.furniture("desk", study, (-2.0, 8.5), (1.4, 0.75, 0.7))
    shelf = s.furniture("wall shelf", study, (-3.7, 6.5), (0.5, 1.6, 1.0))
    filing = s.furniture("filing cabinet", study, (-0.5, 8.6), (0.5, 1.0, 0.6), container=True,
                         lid="front", closed=True)
    bed = s.furniture("bed", bedroom, (-2.5, 1.0), (1.8, 0.55, 1.6), landable=True)
    dresser = s.furniture("dresser", bedroom, (-3.5, 4.6), (1.0, 0.8, 0.5), container=True,
                          lid="front", closed=True)
    shoes = s.furniture("shoe cabinet", hall, (1.25, 8.7), (0.8, 0.9, 0.5), container=True,
                        lid="front", closed=False)
    s.arm(bar)
    s.obj("cup", "Tableware", (0.08, 0.10, 0.08), bar)
    s.obj("cereal box", "Food", (0.2, 0.28, 0.07), bar)
    s.obj("banana", "Fruit", (0.2, 0.04, 0.06), bar)
    s.obj("snack bowl", "Tableware", (0.3, 0.08, 0.26), bar, container=True)
    s.obj("yogurt", "Food", (0.07, 0.08, 0.07), fridge, inside=True)
    s.obj("juice", "Drinks", (0.09, 0.25, 0.09), fridge, inside=True)
    s.obj("jar", "Food", (0.1, 0.15, 0.1), pantry)
    s.obj("napkins", "Tableware", (0.2, 0.04, 0.2), table)
    s.obj("teddy bear", "Toys", (0.25, 0.28, 0.18), chest, inside=True)
    s.obj("newspaper", "Books", (0.3, 0.01, 0.25), coffee)
    s.obj("cushion", "Decor", (0.4, 0.12, 0.3), sofa)
    s.obj("headphones", "Electronics", (0.18, 0.08, 0.16), tv)
    s.obj("notebook", "Books", (0.21, 0.02, 0.28), desk)
    s.obj("globe", "Decor", (0.25, 0.30, 0.25), shelf)
    s.obj("folder", "Office", (0.24, 0.03, 0.3), filing, inside=True)
    s.obj("alarm clock", "Electronics", (0.12, 0.1, 0.07), bed)
    s.obj("sweater", "Clothes", (0.35, 0.06, 0.3), dresser, inside=True)
    s.obj("sneakers", "Clothes", (0.3, 0.12, 0.25), shoes, inside=True)
    s.team()
    return s


def s3_grocery() -> Scene:
    s = Scene("s3-grocery", "Grocery store: sales floor, storage room, office")
    sales = s.room("sales floor", (0, 0), (12, 8), dog_spots=[(6.0, 4.0), (2.0, 6.5)])
    storage = s.room("storage room", (12, 0), (17, 8), dog_spots=[(14.5, 4.0)])
    office = s.room("office", (0, 8), (4, 11), dog_spots=[(2.0, 9.5)])
    s.door(sales, storage, (12, 4.0), False, closed=True)
    s.door(sales, office, (2.0, 8), True, closed=True)
    deli = s.furniture("deli counter", sales, (9.5, 0.7), ARM_TABLE, landable=True)
    produce = s.furniture("produce stand", sales, (3.0, 4.0), (1.6, 0.8, 1.0), landable=True)
    low_shelf = s.furniture("low shelf", sales, (6.5, 6.0), (2.0, 0.6, 0.5))
    top_shelf = s.furniture("top shelf", sales, (6.5, 7.7), (2.0, 1.6, 0.5))
    cooler = s.furniture("drinks cooler", sales, (0.5, 1.5), (0.7, 1.9, 0.8), surface=False,
                         container=True, lid="front", closed=True, category="Appliances")
    checkout = s.furniture("checkout counter", sales, (3.5, 1.0), (1.8, 0.9, 1.0), landable=True)
    bin_ = s.furniture("bargain bin", sales, (9.5, 4.0), (0.8, 0.6, 0.6), surface=False,
                       container=True)
    bench = s.furniture("packing bench", storage, (14.5, 0.7), ARM_TABLE, landable=True)
    rack = s.furniture("storage rack", storage, (16.5, 5.0), (0.6, 1.7, 1.4))
    pallet = s.furniture("pallet", storage, (14.0, 7.0), (1.8, 0.15, 1.0), landable=True)
    crate = s.furniture("crate", storage, (16.3, 7.4), (0.6, 0.4, 0.5), surface=False,
                        container=True)
    desk = s.furniture("office desk", office, (2.0, 10.5), (1.4, 0.75, 0.7))
    safe = s.furniture("safe", office, (3.6, 10.6), (0.5, 0.6, 0.5), container=True, lid="front",
                       closed=True)
    s.arm(deli)
    s.arm(bench)
    s.obj("cheese", "Food", (0.12, 0.06, 0.1), deli)
    s.obj("ham", "Food", (0.2, 0.08, 0.1), deli)
    s.obj("deli tray", "Containers", (0.32, 0.05, 0.26), deli, container=True)
    s.obj("orange", "Fruit", (0.08, 0.08, 0.08), produce)
    s.obj("lettuce", "Vegetables", (0.18, 0.15, 0.18), produce)
    s.obj("pasta", "Food", (0.2, 0.05, 0.08), low_shelf)
    s.obj("olive oil", "Food", (0.07, 0.3, 0.07), top_shelf)
    s.obj("coffee beans", "Food", (0.12, 0.2, 0.07), top_shelf)
    s.obj("soda", "Drinks", (0.07, 0.12, 0.07), cooler, inside=True)
    s.obj("water bottle", "Drinks", (0.07, 0.25, 0.07), cooler, inside=True)
    s.obj("receipt roll", "Office", (0.08, 0.08, 0.08), checkout)
    s.obj("shopping basket", "Containers", (0.4, 0.2, 0.3), checkout, container=True)
    s.obj("candy", "Food", (0.1, 0.03, 0.15), bin_, inside=True)
    s.obj("flour", "Food", (0.16, 0.25, 0.1), bench)
    s.obj("tape", "Office", (0.1, 0.05, 0.1), bench)
    s.obj("cardboard box", "Containers", (0.32, 0.25, 0.26), bench, container=True,
          lid="top", closed=True)
    s.obj("canned beans", "Food", (0.08, 0.11, 0.08), rack)
    s.obj("potato sack", "Vegetables", (0.35, 0.25, 0.25), pallet)
    s.obj("apples", "Fruit", (0.3, 0.15, 0.2), crate, inside=True)
    s.obj("cash box", "Office", (0.25, 0.1, 0.18), safe, inside=True)
    s.obj("price gun", "Office", (0.18, 0.12, 0.05), desk)
    s.team()
    return s


def s4_restaurant() -> Scene:
    s = Scene("s4-restaurant", "Restaurant: dining hall, kitchen, storeroom")
    hall = s.room("dining hall", (0, 0), (10, 8), dog_spots=[(5.0, 4.0), (3.8, 3.8)])
    kitchen = s.room("kitchen", (10, 0), (16, 6), dog_spots=[(13.0, 3.0)])
    store = s.room("storeroom", (10, 6), (16, 9), dog_spots=[(13.0, 7.5)])
    s.door(hall, kitchen, (10, 3.0), False, closed=False)
    s.door(kitchen, store, (13.0, 6), True, closed=True)
    bar = s.furniture("bar counter", hall, (7.5, 7.3), ARM_TABLE, landable=True)
    t1 = s.furniture("table one", hall, (2.0, 2.0), (1.8, 0.75, 1.0), landable=True)
    t2 = s.furniture("table two", hall, (2.0, 5.5), (1.8, 0.75, 1.0), landable=True)
    t3 = s.furniture("table three", hall, (5.5, 1.5), (1.8, 0.75, 1.0), landable=True)
    bar_shelf = s.furniture("bar shelf", hall, (9.75, 6.0), (0.4, 1.6, 1.2))
    station = s.furniture("service station", hall, (0.4, 7.5), (0.7, 0.9, 0.8), container=True,
                          lid="front", closed=True)
    pass_ = s.furniture("pass counter", kitchen, (12.5, 0.7), ARM_TABLE, landable=True)
    stove = s.furniture("stove", kitchen, (15.5, 1.5), (0.8, 0.9, 0.7), category="Appliances")
    fridge = s.furniture("kitchen fridge", kitchen, (15.5, 4.5), (0.8, 1.9, 0.8), surface=False,
                         container=True, lid="front", closed=True, category="Appliances")
    sink = s.furniture("dish sink", kitchen, (11.0, 5.5), (1.2, 0.9, 0.6), container=True)
    shelf = s.furniture("dry store shelf", store, (15.6, 7.5), (0.5, 1.5, 1.6))
    sack = s.furniture("rice bin", store, (11.0, 8.4), (0.6, 0.7, 0.5), surface=False,
                       container=True, lid="top", closed=True)
    s.arm(bar)
    s.arm(pass_)
    s.obj("wine glass", "Tableware", (0.08, 0.2, 0.08), bar)
    s.obj("cocktail shaker", "Tableware", (0.09, 0.25, 0.09), bar)
    s.obj("ice bucket", "Tableware", (0.3, 0.22, 0.26), bar, container=True)
    s.obj("menu", "Books", (0.22, 0.01, 0.3), t1)
    s.obj("salt shaker", "Tableware", (0.05, 0.1, 0.05), t1)
    s.obj("candle", "Decor", (0.07, 0.12, 0.07), t2)
    s.obj("dirty plate", "Tableware", (0.26, 0.03, 0.26), t3)
    s.obj("wine bottle", "Drinks", (0.08, 0.3, 0.08), bar_shelf)
    s.obj("tablecloth", "Linen", (0.3, 0.06, 0.25), station, inside=True)
    s.obj("soup bowl", "Tableware", (0.16, 0.07, 0.16), pass_)
    s.obj("steak", "Food", (0.2, 0.04, 0.12), pass_)
    s.obj("serving tray", "Tableware", (0.32, 0.04, 0.26), pass_, container=True)
    s.obj("frying pan", "Cookware", (0.3, 0.06, 0.3), stove)
    s.obj("butter", "Food", (0.1, 0.05, 0.07), fridge, inside=True)
    s.obj("cream", "Drinks", (0.08, 0.18, 0.08), fridge, inside=True)
    s.obj("ladle", "Cookware", (0.3, 0.05, 0.08), sink, inside=True)
    s.obj("spice jar", "Food", (0.06, 0.12, 0.06), shelf)
    s.obj("flour bag", "Food", (0.2, 0.28, 0.12), shelf)
    s.obj("rice scoop", "Cookware", (0.2, 0.05, 0.08), sack, inside=True)
    s.team()
    return s


def s5_house() -> Scene:
    s = Scene("s5-house", "Two-floor house with a garden: stairs from the hall to the landing")
    hall = s.room("hall", (0, 0), (4, 8), dog_spots=[(2.8, 1.5)])
    kitchen = s.room("kitchen", (4, 0), (9, 5), dog_spots=[(6.5, 2.15)])
    living = s.room("living room", (4, 5), (10, 10), dog_spots=[(7.0, 6.6)])
    garden = s.room("garden", (-7, 0), (0, 10), dog_spots=[(-3.5, 5.0)])
    landing = s.room("landing", (0, 6.5), (4, 10), level=3.0, dog_spots=[(2.8, 8.5)])
    bedroom = s.room("bedroom", (4, 5), (10, 10), level=3.0, dog_spots=[(6.0, 7.0)])
    bath = s.room("bathroom", (4, 0), (9, 5), level=3.0, dog_spots=[(6.5, 2.5)])
    s.door(hall, kitchen, (4, 2.5), False, closed=False)
    s.door(hall, living, (4, 6.0), False, closed=False)
    s.door(hall, garden, (0, 1.0), False, closed=True)
    s.flight(hall, landing, (0.55, 2.0), (0.55, 6.5), 1.0)
    s.door(landing, bedroom, (4, 8.0), False, closed=True)
    s.door(bedroom, bath, (7.0, 5), True, closed=False)
    counter = s.furniture("kitchen counter", kitchen, (6.5, 0.7), ARM_TABLE, landable=True)
    fridge = s.furniture("fridge", kitchen, (8.5, 4.5), (0.7, 1.8, 0.7), surface=False,
                         container=True, lid="front", closed=True, category="Appliances")
    dining = s.furniture("dining table", kitchen, (6.0, 3.5), (1.4, 0.75, 1.0), landable=True)
    sofa = s.furniture("sofa", living, (7.0, 9.5), (2.0, 0.45, 0.8))
    coffee = s.furniture("coffee table", living, (7.0, 8.0), (1.8, 0.45, 1.0), landable=True)
    mantel = s.furniture("mantelpiece", living, (9.75, 6.5), (0.4, 1.3, 1.4))
    console = s.furniture("hall console", hall, (3.6, 0.5), (0.7, 0.8, 0.4))
    garden_table = s.furniture("garden table", garden, (-3.5, 3.0), (1.8, 0.75, 1.0),
                               landable=True)
    shed = s.furniture("tool shed", garden, (-6.0, 8.5), (1.2, 2.0, 1.0), surface=False,
                       container=True, lid="front", closed=True)
    planter = s.furniture("planter", garden, (-1.0, 8.0), (1.0, 0.5, 0.6), surface=False,
                          container=True)
    bed = s.furniture("bed", bedroom, (7.0, 8.8), (1.8, 0.55, 1.6), landable=True)
    wardrobe = s.furniture("wardrobe", bedroom, (9.4, 9.5), (1.0, 1.9, 0.6), surface=False,
                           container=True, lid="front", closed=True)
    bedside = s.furniture("bedside table", bedroom, (5.0, 9.5), (0.5, 0.55, 0.5))
    vanity = s.furniture("vanity", bath, (6.0, 0.5), (1.6, 0.85, 0.6), landable=False)
    cabinet = s.furniture("mirror cabinet", bath, (8.7, 2.5), (0.4, 1.6, 0.8), container=True,
                          lid="front", closed=True)
    shelf = s.furniture("landing shelf", landing, (3.6, 9.5), (0.6, 0.9, 0.8))
    s.arm(counter)
    s.obj("kettle", "Appliances", (0.2, 0.25, 0.15), counter)
    s.obj("teapot", "Tableware", (0.18, 0.15, 0.14), counter)
    s.obj("bread bin", "Containers", (0.32, 0.18, 0.26), counter, container=True, lid="top",
          closed=True)
    s.obj("eggs", "Food", (0.2, 0.07, 0.1), fridge, inside=True)
    s.obj("lemonade", "Drinks", (0.09, 0.28, 0.09), fridge, inside=True)
    s.obj("fruit bowl", "Tableware", (0.25, 0.1, 0.25), dining, container=True)
    s.obj("board game", "Toys", (0.3, 0.06, 0.3), coffee)
    s.obj("blanket", "Bedding", (0.4, 0.1, 0.3), sofa)
    s.obj("photo frame", "Decor", (0.15, 0.2, 0.04), mantel)
    s.obj("keys", "Tools", (0.08, 0.02, 0.05), console)
    s.obj("watering can", "Tools", (0.3, 0.25, 0.15), garden_table)
    s.obj("trowel", "Tools", (0.28, 0.04, 0.08), shed, inside=True)
    s.obj("flower pot", "Plants", (0.15, 0.15, 0.15), planter, inside=True)
    s.obj("slippers", "Clothes", (0.25, 0.06, 0.28), bed)
    s.obj("hat", "Clothes", (0.3, 0.12, 0.3), wardrobe, inside=True)
    s.obj("reading lamp", "Decor", (0.15, 0.28, 0.15), bedside)
    s.obj("toothbrush", "Bathroom", (0.18, 0.02, 0.03), vanity)
    s.obj("soap", "Bathroom", (0.09, 0.04, 0.06), cabinet, inside=True)
    s.obj("towel", "Bathroom", (0.3, 0.06, 0.2), shelf)
    s.team()
    return s


SCENES = [s1_apartment, s2_apartment, s3_grocery, s4_restaurant, s5_house]


# ---------------------------------------------------------------------------------------
# Candidate tasks
#
# A random goal over all objects and places is mostly a one-robot errand or impossible
# (nothing can reach a high shelf without an arm on it). So candidates are drawn from
# templates that need one, two or three kinds of robot, and the planner, not the
# template, decides each task's type: a template only makes a type likely.

HAND = 1.34  # the legged robot's hand with the default specs (geometry::RobotSpecs)


def movables(s: Scene):
    return [n for n, node in enumerate(s.nodes) if "GRABABLE" in node["properties"]]


def destinations(s: Scene):
    """Every place something can be put: (node, "ON") for a surface, (node, "INSIDE")
    for a container; rooms, floors, robots and doors are not places."""
    out = []
    for n, node in enumerate(s.nodes):
        p = node["properties"]
        if node["category"] in ("Rooms", "Floor", "Agents", "AgentTool", "Doors"):
            continue
        if "SURFACES" in p:
            out.append((n, "ON"))
        if "CONTAINERS" in p:
            out.append((n, "INSIDE"))
    return out


class Places:
    """What each robot can get at in a scene, from the same height rule as the
    `geometric` rule set: a surface is high when its top above the floor plus the
    tallest object is above the legged robot's hand."""

    def __init__(self, s: Scene):
        tallest = max(s.items[n]["size"][1] for n in movables(s))
        self.high = set()
        for n, g in s.items.items():
            if n not in s.room_of:
                continue
            props = s.nodes[n]["properties"]
            top = g["size"][1] if "SURFACES" in props else min(WALL, g["size"][1] / 4)
            if top + tallest > HAND:
                self.high.add(n)
        self.tables = {t: a for a, t, _ in s.arms}
        self.table_objs = {t: [] for t in self.tables}
        self.low_objs = []
        for n in movables(s):
            base = s.base(n)
            if base in self.tables:
                self.table_objs[base].append(n)
            elif base not in self.high:
                self.low_objs.append(n)
        self.table_dests = {t: [(t, "ON")] for t in self.tables}
        self.low_dests = []
        for n, rel in destinations(s):
            base = s.base(n)
            if base in self.tables:
                if n != base:
                    self.table_dests[base].append((n, rel))
            elif base not in self.high:
                self.low_dests.append((n, rel))


def fits(s: Scene, x: int, t: int, rel: str) -> bool:
    """Whether object `x` fits on or in `t` with room to spare: in a container, inside its
    walls and under its rim; on a surface, within its top; in the quadrotor's basket
    (0.40 m square inside its walls, 0.20 m under the craft's hub), within 0.34 m each
    way and 0.18 m high."""
    w, h, d = s.items[x]["size"]
    if t == s.basket:
        return max(w, d) <= 0.34 and h <= 0.18
    tw, th, td = s.items[t]["size"]
    if rel == "INSIDE":
        wall = 2 * min(WALL, th / 4) + 0.03
        return w <= tw - wall and d <= td - wall and h <= th
    return w <= tw - 0.1 and d <= td - 0.1


def predicate(s: Scene, rng: random.Random, objs, dests, used):
    """One goal predicate moving an object of `objs` (not in `used`) to a place of
    `dests` other than where it is, that it fits; None when there is none."""
    for _ in range(20):
        x = rng.choice(objs)
        t, rel = rng.choice(dests)
        if x in used or t == x or t in used or s.holder.get(x) == (t, rel == "INSIDE"):
            continue
        if not fits(s, x, t, rel):
            continue
        # A movable container (and the basket) takes one goal object: two rarely fit.
        if rel == "INSIDE" and (t == s.basket or s.items[t]["dynamic"]):
            if ("into", t) in used:
                continue
            used.add(("into", t))
        # Nothing into itself through a chain of holders.
        n = t
        while n in s.holder and n != x:
            n = s.holder[n][0]
        if n == x:
            continue
        used.add(x)
        return (x, rel, t)
    return None


def template(s: Scene, pl: Places, rng: random.Random, kind: str):
    """A goal drawn from the templates of `kind` (mono, dual or trio), or None."""
    used: set = set()
    tables = list(pl.tables)
    basket = [(s.basket, "INSIDE")]
    low = lambda: predicate(s, rng, pl.low_objs, pl.low_dests, used)  # noqa: E731
    if kind == "mono":
        k = rng.choice([1, 1, 2])
        if rng.random() < 0.2:
            t = rng.choice(tables)
            return [predicate(s, rng, pl.table_objs[t], pl.table_dests[t], used)
                    for _ in range(2)]
        return [low() for _ in range(k)]
    if kind == "dual":
        form = rng.choice(["dog+arm", "dog+quadrotor", "arm+quadrotor"]
                          if len(tables) > 1 else ["dog+arm", "dog+quadrotor"])
        if form == "dog+arm":
            t = rng.choice(tables)
            goal = [predicate(s, rng, pl.table_objs[t], pl.table_dests[t], used), low()]
            if rng.random() < 0.4:
                goal.append(low())
            return goal
        if form == "dog+quadrotor":
            goal = [predicate(s, rng, pl.low_objs, basket, used)]
            if rng.random() < 0.6:
                goal.append(low())
            return goal
        a, b = rng.sample(tables, 2)
        goal = [predicate(s, rng, pl.table_objs[a], pl.table_dests[b], used)]
        if rng.random() < 0.5:
            goal.append(predicate(s, rng, pl.table_objs[b], pl.table_dests[b], used))
        return goal
    t = rng.choice(tables)
    if rng.random() < 0.5:
        goal = [predicate(s, rng, pl.low_objs, pl.table_dests[t], used)]
    else:
        goal = [predicate(s, rng, pl.table_objs[t], pl.low_dests, used)]
    extra = rng.random()
    if extra < 0.35:
        goal.append(low())
    elif extra < 0.6:
        goal.append(predicate(s, rng, pl.table_objs[t], pl.table_dests[t], used))
    return goal


def candidates(s: Scene, rng: random.Random, per_kind: dict[str, int]):
    """Candidate (goal, dog room, dog spot, quadrotor's landing place) tuples, about
    `per_kind[kind]` from each kind's templates, no two alike."""
    pl = Places(s)
    landables = s.landables()
    seen = set()
    out = []
    for kind, count in per_kind.items():
        drawn = tries = 0
        while drawn < count and tries < 50 * count:
            tries += 1
            goal = template(s, pl, rng, kind)
            if not goal or None in goal:
                continue
            dog_room = rng.choice([r for r in s.rooms if s.spots_for_dog[r]])
            dog_spot = rng.choice(s.spots_for_dog[dog_room])
            quad_on = rng.choice(landables)
            key = (tuple(sorted(goal)), dog_room, dog_spot, quad_on)
            if key in seen:
                continue
            seen.add(key)
            out.append((goal, dog_room, dog_spot, quad_on))
            drawn += 1
    return out


def plan(coherent: str, folder: str, *flags: str) -> list[dict]:
    """`coherent plan --json` on every task file in `folder`, one result per task."""
    run = subprocess.run([coherent, "plan", folder, "--json", "--max-states", "400000", *flags],
                         capture_output=True, text=True, check=False)
    if run.returncode not in (0, 1):
        sys.exit(f"coherent plan failed:\n{run.stderr}")
    return [json.loads(line) for line in run.stdout.splitlines() if line.startswith("{")]


def in_range(r: dict | None) -> bool:
    """Whether a planner result is solvable, typed, and within its type's GT range."""
    if not r or not r.get("solvable") or not r.get("task_type"):
        return False
    lo, hi = GT_RANGE[r["task_type"]]
    return lo <= r["optimal_steps"] <= hi


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--coherent", default="target/release/coherent")
    ap.add_argument("--draws", type=int, default=16,
                    help="candidates drawn per task wanted, from each type's templates")
    ap.add_argument("--scenes", nargs="*", help="only these scenes (names)")
    args = ap.parse_args()
    out_dir = HERE / "tasks"
    for make in SCENES:
        s = make()
        if args.scenes and s.name not in args.scenes:
            continue
        quota = QUOTA[s.name]
        # One stream per scene: a scene's tasks do not depend on which others are made.
        rng = random.Random(f"{SEED}-{s.name}")
        cands = candidates(s, rng, {t: round(args.draws * DRAW_WEIGHT[t] * q)
                                    for t, q in quota.items()})
        with tempfile.TemporaryDirectory() as tmp:
            for i, (goal, dog_room, dog_spot, quad_on) in enumerate(cands):
                task = s.build(1000 + i, goal, dog_room, dog_spot, quad_on)
                (Path(tmp) / f"{i:04d}.json").write_text(json.dumps(task))
            results = {r["task_id"]: r for r in plan(args.coherent, tmp)}
        # The candidates of the right size for their type, carried out in physics.
        fit = [i for i, _ in enumerate(cands) if in_range(results.get(1000 + i))]
        with tempfile.TemporaryDirectory() as tmp:
            for i in fit:
                (Path(tmp) / f"{i:04d}.json").write_text(json.dumps(s.build(1000 + i, *cands[i])))
            physical = {r["task_id"] for r in plan(args.coherent, tmp, "--physics")
                        if r.get("physics_ok")}
        kept: dict[str, list] = {t: [] for t in GT_RANGE}
        goals = set()
        for i in fit:
            if 1000 + i not in physical:
                continue
            r = results[1000 + i]
            ty, gt = r["task_type"], r["optimal_steps"]
            goal = tuple(sorted(cands[i][0]))
            # Each goal once per scene, so that no two tasks share a goal at all.
            if len(kept[ty]) < quota[ty] and goal not in goals:
                goals.add(goal)
                kept[ty].append((cands[i], gt))
        print(f"{s.name}: {len(cands)} candidates, {len(fit)} of a type and size wanted, "
              f"{len(physical)} of those carried out in physics")
        counts = {t: len(v) for t, v in kept.items()}
        print(f"{s.name}: kept {counts} of quota {QUOTA[s.name]}; "
              f"types drawn {Counter(r.get('task_type') for r in results.values())}")
        for ty in GT_RANGE:
            gts = Counter(r["optimal_steps"] for r in results.values() if r.get("task_type") == ty)
            print(f"  {ty} ground truths drawn: {dict(sorted(gts.items()))}")
        scene_dir = out_dir / s.name
        if scene_dir.exists():
            shutil.rmtree(scene_dir)
        scene_dir.mkdir(parents=True)
        task_id = 0
        for ty in ("mono", "dual", "trio"):
            for j, ((goal, dog_room, dog_spot, quad_on), gt) in enumerate(kept[ty]):
                task = s.build(task_id, goal, dog_room, dog_spot, quad_on)
                task["name"] = f"{ty}-{j}"
                task["ground_truth"] = {"steps": gt}
                (scene_dir / f"task-{task_id:02d}.json").write_text(
                    json.dumps(task, indent=1) + "\n")
                task_id += 1
    write_subset()


def write_subset() -> None:
    """benchmark/subset-40.txt from the task files: per scene the first two mono, three
    dual and three trio tasks (the paper's proportions)."""
    lines = ["# The 40-task subset: per scene 2 mono, 3 dual, 3 trio (the paper's proportions)."]
    for f in sorted((HERE / "tasks").glob("*/task-*.json")):
        task = json.loads(f.read_text())
        ty, j = task["name"].split("-")
        if int(j) < SUBSET40[ty]:
            lines.append(f"{task['scene']} {task['task_id']}")
    (HERE / "subset-40.txt").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
