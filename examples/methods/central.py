"""A compact CMRS-like planner, written from scratch: each step one model sees the task,
what every robot sees, the last steps and every robot's actions as ``<robot>: <action>``
lines, and picks one line, which is run. One model call per step, through
``coherent.LLM`` (so the call, its tokens and its latency are in the transcript).

The model comes from ``OPENAI_BASE_URL``, ``COHERENT_MODEL`` and ``OPENAI_API_KEY``, or
from a subclass that sets ``llm``::

    OPENAI_BASE_URL=http://127.0.0.1:8080/v1 COHERENT_MODEL=smollm2 \\
        coherent run TASK --method examples/methods/central.py:CentralPlanner

    class Mine(CentralPlanner):
        llm = coherent.LLM(base_url="http://127.0.0.1:8080/v1", model="smollm2")

    coherent.bench(tasks, ["cmrs", Mine], backend=Mine.llm)
"""

from __future__ import annotations

import json
from typing import ClassVar

import coherent

SYSTEM = """You coordinate a team of robots in a house. Each step exactly one robot does one
action. Choose the action that brings the task closest to done, from the list only, and
answer with JSON: {"action": "<one line of the list, copied exactly>"}."""


class CentralPlanner:
    """One model, one line of the team's action list per step."""

    name = "central"
    llm: ClassVar[coherent.LLM | None] = None
    """The model; None: from the environment (OPENAI_BASE_URL, COHERENT_MODEL)."""
    history: ClassVar[int] = 5
    """Earlier steps shown to the model."""

    def __init__(self, task: coherent.Task) -> None:
        self.task = task
        self.llm = type(self).llm or coherent.LLM()

    def act(self, view: coherent.View) -> coherent.Decision:
        lines = [f"{robot}: {action}" for robot, actions in view.actions.items() for action in actions]
        if not lines:
            return coherent.Decision(None, None, note="no robot can act")
        reply = self.llm.chat(self.messages(view, lines), schema=self.schema(lines), max_tokens=100)
        chosen = self.read(reply.text, lines)
        if chosen is None:
            # A step without an action: the model's answer was not a line of the list.
            return coherent.Decision(None, None, note=f"not a line of the list: {reply.text[:120]!r}")
        robot, action = chosen.split(": ", 1)
        return coherent.Decision(int(robot), action, note=f"the model chose {chosen!r}")

    def messages(self, view: coherent.View, lines: list[str]) -> list[dict[str, str]]:
        team = "\n".join(f"- robot {robot}: a {kind}" for robot, kind in view.robot_types.items())
        steps = [
            f"- robot {robot}: {action} ({'done' if ok else f'failed: {reason}'})"
            for robot, action, ok, reason in view.history[-self.history :]
            if robot is not None
        ]
        user = "\n\n".join(
            [
                f"Task: {self.task.instruction}",
                f"Team:\n{team}",
                f"What the robots see:\n{view.observation_text()}",
                "Last steps:\n" + ("\n".join(steps) or "(none yet)"),
                f"Step {view.step} of {view.max_steps}. Actions (robot: action):\n" + "\n".join(lines),
            ]
        )
        return [{"role": "system", "content": SYSTEM}, {"role": "user", "content": user}]

    @staticmethod
    def schema(lines: list[str]) -> dict[str, object]:
        return {
            "type": "object",
            "properties": {"action": {"type": "string", "enum": lines}},
            "required": ["action"],
            "additionalProperties": False,
        }

    @staticmethod
    def read(text: str, lines: list[str]) -> str | None:
        """The line the answer names: its JSON's ``action``, else the first line that
        appears in the text."""
        start = text.find("{")
        if start >= 0:
            try:
                answer, _ = json.JSONDecoder().raw_decode(text, start)
            except ValueError:
                answer = None
            if isinstance(answer, dict) and str(answer.get("action", "")).strip() in lines:
                return str(answer["action"]).strip()
        found = [(text.find(line), line) for line in lines if line in text]
        return min(found)[1] if found else None
