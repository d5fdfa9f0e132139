"""`coherent view` in a real browser: an episode's page stepped with the keys, two
episodes side by side, a hostile transcript, and `coherent.view` from Python.

The browser is Debian's chromium-headless-shell driven by Playwright (`make browser`
installs it as root); each page is watched for console errors and for any request that
is not the page's own file."""

from __future__ import annotations

import json
import math
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from browser import Watched, chromium, watch
from conftest import DEMO, REPO

import coherent

# The demo's events (docs/dynamic.md): the arm goes down once the mug is in the basket,
# and a door is locked for two steps before step 9.
EVENTS = REPO / "examples" / "events" / "demo.json"

# Where the tests leave the screenshots of the pages (docs/figures when refreshing the
# documentation's pictures); a scratch folder by default.
SCREENSHOTS = os.environ.get("COHERENT_SCREENSHOTS")


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium() as b:
        yield b


def run_episode(exe: str, out: Path, *args: str) -> tuple[list[str], Path]:
    """`coherent run` on the demo task: the step lines it printed, and its transcript."""
    done = subprocess.run([exe, "run", str(DEMO), "--out", str(out), *args], capture_output=True, text=True, check=False)
    assert done.returncode in (0, 1), done.stderr
    lines = done.stdout.splitlines()
    steps = [line for line in lines if line.startswith("step ")]
    transcript = Path(next(line for line in lines if line.startswith("transcript: ")).split(": ", 1)[1])
    return steps, transcript


def view(exe: str, *args: str) -> str:
    done = subprocess.run([exe, "view", *args], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


def rounds(transcript: Path) -> list[dict[str, Any]]:
    records = [json.loads(line) for line in transcript.read_text(encoding="utf-8").splitlines() if line.strip()]
    return [r for r in records if r["type"] == "round"]


def drawn(page: Any) -> dict[int, tuple[float, float]]:
    """Where the page draws each robot now, in picture coordinates."""
    marks = page.eval_on_selector_all(
        ".scene use.robot", "us => us.map(u => [u.dataset.robot, u.dataset.x, u.dataset.y])"
    )
    return {int(r): (float(x), float(y)) for r, x, y in marks}


def rooms_by_the_rules(env: coherent.Env) -> dict[int, int]:
    """Each robot's room in the environment's graph (its INSIDE edge to a room)."""
    graph = env.graph()
    rooms = {n["id"] for n in graph["nodes"] if n["category"] == "Rooms"}
    robots = set(env.robots)
    return {
        e["from_id"]: e["to_id"]
        for e in graph["edges"]
        if e["relation_type"] == "INSIDE" and e["from_id"] in robots and e["to_id"] in rooms
    }


def room_rects(page: Any, task: coherent.Task) -> dict[int, tuple[float, float, float, float]]:
    """The drawn rectangle of each room: the picture draws the layout's rooms in order."""
    rects = page.eval_on_selector_all(
        ".scene svg g.rooms rect",
        "rs => rs.map(r => ['x', 'y', 'width', 'height'].map(a => Number(r.getAttribute(a))))",
    )
    ids = [room["id"] for room in coherent.scene_layout(task)["rooms"]]
    assert len(rects) == len(ids)
    return {i: (x, y, x + w, y + h) for i, (x, y, w, h) in zip(ids, rects)}


def test_the_demo_page_shows_each_step_as_run_printed_it_and_moves_the_robots_by_the_rules(
    coherent_exe: str, tmp_path: Path, browser: Any
) -> None:
    printed, transcript = run_episode(coherent_exe, tmp_path / "runs")
    page_file = tmp_path / "demo.html"
    view(coherent_exe, str(transcript), "-o", str(page_file))
    w = watch(browser)
    w.open(page_file.as_uri())
    page = w.page
    task = coherent.load_tasks(DEMO)[0]
    env = coherent.Env(task)
    rects = room_rects(page, task)
    recorded = rounds(transcript)
    assert len(printed) == len(recorded) > 0
    # Without events, no event is marked and no reference is shown.
    assert page.query_selector_all(".steps li.event, .happened, .card.reference, .badge.event") == []

    def check_rooms() -> None:
        expected = rooms_by_the_rules(env)
        listed = dict(page.eval_on_selector_all(".scene li[data-robot]", "ls => ls.map(l => [Number(l.dataset.robot), Number(l.dataset.room)])"))
        assert listed == expected
        for robot, (x, y) in drawn(page).items():
            x0, y0, x1, y1 = rects[expected[robot]]
            assert x0 <= x <= x1 and y0 <= y <= y1, (robot, expected[robot])

    before = drawn(page)
    check_rooms()
    for k, (line, rnd) in enumerate(zip(printed, recorded), start=1):
        page.keyboard.press("ArrowRight")
        assert page.text_content(".detail pre.line") == line
        assert page.text_content(".steps li.current") == line
        assert page.evaluate("location.hash") == f"#step={k}"
        acting = rnd["proposal"]["robot"] if rnd["proposal"] else None
        action = (rnd["decision"] or {}).get("action")
        executed = rnd["outcome"]["kind"] == "executed"
        if executed:
            env.step(acting, action)
        now = drawn(page)
        for robot, (x, y) in now.items():
            moved = math.dist(before[robot], (x, y)) > 0.5
            its_own = executed and robot == acting
            # A robot's own move takes it elsewhere; a landing may shift it onto the
            # surface below; nothing else moves a robot on the floor plan.
            if its_own and action.startswith("[movetowards]"):
                assert moved, (k, robot, action)
            if moved:
                assert its_own and action.startswith(("[movetowards]", "[land_on]")), (k, robot, action)
        check_rooms()
        before = now
    page.keyboard.press("Home")
    assert page.text_content(".steps li.current") == "start"
    page.keyboard.press("End")
    assert page.text_content(".detail pre.line") == printed[-1]
    # A link to a step opens the page there.
    page.goto(page_file.as_uri() + "#step=3")
    page.wait_for_selector(".steps li.current")
    assert page.text_content(".steps li.current") == printed[2]
    if SCREENSHOTS:
        page.keyboard.press("Home")
        for _ in range(9):
            page.keyboard.press("ArrowRight")
        page.screenshot(path=str(Path(SCREENSHOTS) / "view-episode.png"), full_page=False)
    w.assert_quiet()


def test_refused_steps_are_marked_with_the_engines_reason(coherent_exe: str, tmp_path: Path, browser: Any) -> None:
    printed, transcript = run_episode(coherent_exe, tmp_path / "runs", "--sim-errors", "hallucinate=0.5", "--seed", "3")
    refused = [(i, r) for i, r in enumerate(rounds(transcript), start=1) if r["outcome"]["kind"] == "infeasible"]
    assert refused, "the simulated mistakes refuse some step"
    page_file = tmp_path / "refused.html"
    view(coherent_exe, str(transcript), "-o", str(page_file))
    w = watch(browser)
    w.open(page_file.as_uri())
    for k, r in refused:
        w.page.goto(f"{page_file.as_uri()}#step={k}")
        w.page.wait_for_selector(f".steps li.current[data-step='{k}']")
        assert w.page.get_attribute(f".steps li[data-step='{k}']", "class") == "refused current"
        assert w.page.get_attribute(".detail .refusal", "data-reason") == r["outcome"]["reason"]
        assert w.page.text_content(".detail pre.line") == printed[k - 1]
    w.assert_quiet()


def test_a_parallel_step_shows_every_robots_part_and_moves_them_together(
    coherent_exe: str, tmp_path: Path, browser: Any
) -> None:
    done = subprocess.run(
        [coherent_exe, "run", str(DEMO), "--execution", "parallel", "--out", str(tmp_path / "runs")],
        capture_output=True,
        text=True,
        check=True,
    )
    # Each joint step as printed: its line, then its robots' indented lines.
    printed: list[str] = []
    for line in done.stdout.splitlines():
        if line.startswith("step "):
            printed.append(line)
        elif line.startswith("  "):
            printed[-1] += "\n" + line
    transcript = Path(next(line for line in done.stdout.splitlines() if line.startswith("transcript: ")).split(": ", 1)[1])
    page_file = tmp_path / "parallel.html"
    view(coherent_exe, str(transcript), "-o", str(page_file))
    w = watch(browser)
    w.open(page_file.as_uri())
    page = w.page
    task = coherent.load_tasks(DEMO)[0]
    env = coherent.Env(task)
    rects = room_rects(page, task)
    recorded = rounds(transcript)
    assert len(printed) == len(recorded) > 0
    assert "parallel" in (page.text_content(".header") or "")
    together = 0
    for k, (text, rnd) in enumerate(zip(printed, recorded), start=1):
        page.keyboard.press("ArrowRight")
        assert page.text_content(".detail pre.line") == text
        shown = page.eval_on_selector_all(".detail .entry", "es => es.map(e => Number(e.dataset.robot))")
        assert shown == [p["robot"] for p in rnd["parts"]], "an entry per robot's part"
        acting = {
            p["robot"]: p["decision"]["action"] for p in rnd["parts"] if p["outcome"]["kind"] == "executed"
        }
        if rnd["outcome"]["kind"] == "executed":
            oks, _, _ = env.step(acting)
            assert all(oks)
        together += len(acting) >= 2
        expected = rooms_by_the_rules(env)
        listed = dict(
            page.eval_on_selector_all(
                ".scene li[data-robot]", "ls => ls.map(l => [Number(l.dataset.robot), Number(l.dataset.room)])"
            )
        )
        assert listed == expected, k
        for robot, (x, y) in drawn(page).items():
            x0, y0, x1, y1 = rects[expected[robot]]
            assert x0 <= x <= x1 and y0 <= y <= y1, (k, robot)
    assert together > 0, "some step moves several robots"
    assert env.goal_satisfied()
    w.assert_quiet()


def first_differing_round(a: Path, b: Path) -> int | None:
    """Where two transcripts' decisions (robot and action) first differ, read here."""

    def decided(r: dict[str, Any]) -> tuple[Any, Any]:
        return ((r["proposal"] or {}).get("robot"), (r["decision"] or {}).get("action"))

    ra, rb = rounds(a), rounds(b)
    for x, y in zip(ra, rb):
        if decided(x) != decided(y):
            return int(x["step"])
    return None if len(ra) == len(rb) else min(len(ra), len(rb)) + 1


def test_side_by_side_marks_the_first_round_whose_decisions_differ(coherent_exe: str, tmp_path: Path, browser: Any) -> None:
    _, a = run_episode(coherent_exe, tmp_path / "a", "--sim-errors", "all=0.3", "--seed", "1")
    _, b = run_episode(coherent_exe, tmp_path / "b", "--sim-errors", "all=0.3", "--seed", "2")
    expected = first_differing_round(a, b)
    assert expected is not None
    page_file = tmp_path / "both.html"
    view(coherent_exe, str(a), str(b), "-o", str(page_file))
    w = watch(browser)
    w.open(page_file.as_uri())
    page = w.page
    assert page.get_attribute("#first-difference", "data-step") == str(expected)
    assert page.eval_on_selector_all("tr.differs", "rs => rs.map(r => Number(r.dataset.step))") == [expected]
    # Both sides step together.
    page.click("#first-difference a")
    assert page.evaluate("location.hash") == f"#step={expected}"
    details = page.query_selector_all(".detail")
    assert len(details) == 2
    for detail, t in zip(details, (a, b)):
        if expected <= len(rounds(t)):
            assert detail.query_selector("pre.line").text_content().split()[1] == f"{expected}/{_budget(t)}"
    page.keyboard.press("ArrowRight")
    assert page.evaluate("document.body.dataset.step") == str(expected + 1)
    w.assert_quiet()


def _budget(transcript: Path) -> int:
    return int(json.loads(transcript.read_text(encoding="utf-8").splitlines()[0])["max_steps"])


HOSTILE = [
    "</script><script>window.__pwned = 'script'</script>",
    "<img src=x onerror=\"window.__pwned = 'img'\"> and <b>bold</b> & &amp;",
    "colour \x1b[31mred\x1b[0m and a bell \x07 and a right-to-left \u202e mark",
]


def hostile_transcript(source: Path, out: Path) -> tuple[Path, list[str]]:
    """`source` with hostile text as the model's answers, the task's name and instruction,
    a feedback line, and one 64 KiB answer; returns it and the texts put in."""
    records = [json.loads(line) for line in source.read_text(encoding="utf-8").splitlines() if line.strip()]
    header = records[0]
    header["task_name"] = HOSTILE[0]
    header["task"]["name"] = HOSTILE[0]
    header["task"]["instruction"] = HOSTILE[1] + " " + header["task"]["instruction"]
    # A name in the scene's picture too: the sofa, which no action names.
    sofa = next(n for n in header["task"]["graph"]["nodes"] if n["id"] == 14)
    sofa["class_name"] = HOSTILE[0]
    long = ("<i>" + "y" * 56 + "</i>\n") * 1024  # 64 KiB
    texts = [*HOSTILE, long]
    calls = [c for r in records if r.get("type") == "round" for c in r["calls"] if c["answer"]]
    assert len(calls) >= len(texts)
    for call, text in zip(calls, texts):
        call["answer"]["text"] = text
    rnd = next(r for r in records if r.get("type") == "round")
    rnd["feedback"] = HOSTILE[0]
    out.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    return out, texts


def as_shown(text: str) -> str:
    """What the page shows for `text`: as a terminal shows it (coherent_core::text),
    line breaks kept, other control characters and direction marks as \\u{..}."""
    out = []
    for c in text:
        if c == "\n":
            out.append(c)
        elif c == "\r":
            out.append("\\r")
        elif c == "\t":
            out.append("\\t")
        elif ord(c) < 0x20 or 0x7F <= ord(c) < 0xA0 or c in "\u061c\u200e\u200f" or 0x202A <= ord(c) <= 0x202E or 0x2066 <= ord(c) <= 0x2069:
            out.append("\\u{%x}" % ord(c))
        else:
            out.append(c)
    return "".join(out)


def test_a_hostile_transcript_runs_nothing_and_shows_its_text_as_written(coherent_exe: str, tmp_path: Path, browser: Any) -> None:
    # The simulated backend answers the roles: every round has calls with answers.
    _, source = run_episode(coherent_exe, tmp_path / "runs", "--sim-errors", "all=0.0")
    transcript, texts = hostile_transcript(source, tmp_path / "hostile.jsonl")
    page_file = tmp_path / "hostile.html"
    view(coherent_exe, str(transcript), "-o", str(page_file))
    html = page_file.read_text(encoding="utf-8")
    # Nothing of the data can close the data's element or open one.
    assert html.count("</script>") == 2 and "<img" not in html
    w = watch(browser)
    w.open(page_file.as_uri())
    page = w.page
    assert page.evaluate("window.__pwned") is None
    assert page.evaluate("document.scripts.length") == 2
    assert page.query_selector_all("img") == []
    assert page.text_content(".header h1").startswith("demo-apartment task 0 · " + HOSTILE[0])
    assert page.text_content(".header .instruction").startswith(HOSTILE[1])
    labels = page.eval_on_selector_all(".scene svg text", "ts => ts.map(t => t.textContent)")
    assert any(label.startswith(f"{HOSTILE[0]} 14") for label in labels)  # then its height
    answers: list[str] = []
    for k in range(1, len(rounds(transcript)) + 1):
        page.keyboard.press("ArrowRight")
        answers += page.eval_on_selector_all(".detail pre.answer", "ps => ps.map(p => p.textContent)")
        if k == 1:
            assert page.text_content(".detail [data-field=feedback]") == HOSTILE[0]
    for text in texts:
        assert as_shown(text) in answers
    assert page.evaluate("window.__pwned") is None
    w.assert_quiet()


def records(transcript: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in transcript.read_text(encoding="utf-8").splitlines() if line.strip()]


def optimum_shown(p: dict[str, Any]) -> str:
    """The optimum as the page words it."""
    if "unreachable" in p:
        return "unreachable: " + p["unreachable"]
    if "steps" in p:
        joint = f", {p['makespan']} joint" if "makespan" in p else ""
        return f"{p['steps']} step{'' if p['steps'] == 1 else 's'}{joint}"
    return "unknown: " + p["unknown"] if "unknown" in p else "unknown"


EVENT_ROWS = """ls => ls.map(l => ({
  event: Number(l.dataset.event), before: Number(l.dataset.before), kind: l.dataset.kind,
  ended: l.classList.contains('ended'), told: l.querySelector('.told')?.textContent ?? '',
  optimum: l.querySelector('.optimum').textContent }))"""


def test_events_are_marked_where_they_happened_with_what_was_told_and_the_reference(
    coherent_exe: str, tmp_path: Path, browser: Any
) -> None:
    printed, transcript = run_episode(coherent_exe, tmp_path / "runs", "--events", str(EVENTS))
    recorded = rounds(transcript)
    summary = records(transcript)[-1]
    reference = summary["reference"]
    happened = [(r["step"], e) for r in recorded for e in r.get("events", [])]
    assert sorted((e["kind"], e.get("ended", False)) for _, e in happened) == [
        ("blocked", False), ("blocked", True), ("robot_down", False)
    ]
    page_file = tmp_path / "events.html"
    view(coherent_exe, str(transcript), "-o", str(page_file))
    w = watch(browser)
    w.open(page_file.as_uri())
    page = w.page
    # A row per event in the step list, just before the line of the step it came before.
    rows = page.eval_on_selector_all(".steps li.event", EVENT_ROWS)
    assert rows == [
        {
            "event": e["event"], "before": step, "kind": e["kind"], "ended": e.get("ended", False),
            "told": "told: " + e["told"] if e["told"] else "",
            "optimum": "optimum after it: " + optimum_shown(e["optimum"]),
        }
        for step, e in happened
    ]
    order = page.eval_on_selector_all(".steps li", "ls => ls.map(l => l.dataset.step ?? 'before ' + l.dataset.before)")
    for i, item in enumerate(order):
        if item.startswith("before "):
            after = next((x for x in order[i + 1 :] if not x.startswith("before ")), None)
            assert after == item.removeprefix("before "), order
    assert page.get_attribute(".steps li.event.ended", "data-kind") == "blocked"
    # The chosen step shows what happened before it, in full, above its line.
    for step, e in happened:
        page.goto(f"{page_file.as_uri()}#step={step}")
        page.wait_for_selector(f".steps li.current[data-step='{step}']")
        shown = page.query_selector(f".detail .happened[data-event='{e['event']}']{'.ended' if e.get('ended') else ':not(.ended)'}")
        assert shown is not None, (step, e)
        assert shown.query_selector("[data-field=told]").text_content() == as_shown(e["told"])
        assert shown.query_selector("[data-field=optimum]").text_content() == optimum_shown(e["optimum"])
        assert page.text_content(".detail pre.line") == printed[step - 1]
    # The reference beside the episode: its steps against those taken, the optimum at
    # the start, and the recovery from each event that changed the world.
    steps = page.query_selector(".reference [data-field=reference] span")
    assert steps.get_attribute("data-reference") == str(reference["steps"])
    assert steps.get_attribute("data-taken") == str(summary["steps"])
    assert summary["steps"] == reference["steps"], "the built-in backend ends in the reference's steps"
    assert page.text_content(".reference [data-field=start]") == "optimum " + optimum_shown(reference["start"])
    recoveries = page.eval_on_selector_all(
        ".reference table.recoveries tbody tr",
        "rs => rs.map(r => [Number(r.dataset.event), ...['rounds', 'wasted', 'calls'].map(k => r.querySelector(`[data-key=${k}]`).textContent)])",
    )
    assert recoveries == [
        [c["event"], "none" if c.get("rounds") is None else str(c["rounds"]), str(c["wasted"]), str(c["calls"])]
        for c in reference["recoveries"]
    ]
    assert recoveries, "the arm going down changes the world"
    assert page.query_selector(".reference [data-field=unreachable]") is None
    if SCREENSHOTS:
        # At the step before which the door is locked, tall enough for its detail.
        locked = next(step for step, e in happened if e["kind"] == "blocked" and not e.get("ended"))
        page.set_viewport_size({"width": 1500, "height": 1160})
        page.goto(f"{page_file.as_uri()}#step={locked}")
        page.wait_for_selector(".steps li.current")
        page.screenshot(path=str(Path(SCREENSHOTS) / "view-events.png"), full_page=False)
    w.assert_quiet()

    # Text about events is data: hostile words where the engine's would be are shown as
    # written and run nothing.
    lines = records(transcript)
    first = next(r for r in lines if r.get("type") == "round" and r.get("events"))
    first["events"][0]["told"] = HOSTILE[0]
    first["events"][0]["void"] = HOSTILE[1]
    first["events"][0]["optimum"] = {"unreachable": HOSTILE[2]}
    lines[-1]["reference"]["unreachable"] = HOSTILE[0]
    hostile = tmp_path / "hostile-events.jsonl"
    hostile.write_text("".join(json.dumps(r) + "\n" for r in lines), encoding="utf-8")
    page_file = tmp_path / "hostile-events.html"
    view(coherent_exe, str(hostile), "-o", str(page_file))
    w = watch(browser)
    w.open(f"{page_file.as_uri()}#step={first['step']}")
    page = w.page
    detail = page.query_selector(".detail .happened")
    assert detail.query_selector("[data-field=told]").text_content() == HOSTILE[0]
    assert detail.query_selector("[data-field=void]").text_content() == HOSTILE[1]
    assert detail.query_selector("[data-field=optimum]").text_content() == "unreachable: " + as_shown(HOSTILE[2])
    assert page.text_content(".reference [data-field=unreachable]") == "for good: " + HOSTILE[0]
    assert page.evaluate("window.__pwned") is None
    assert page.query_selector_all("img") == []
    w.assert_quiet()


def test_where_the_robots_are_follows_an_event_that_moves_a_thing(
    coherent_exe: str, tmp_path: Path, browser: Any
) -> None:
    # The demo's variant where the mug is moved mid-task: the team fetches it from where
    # the event put it, which the rules allow only with the event carried out.
    subprocess.run(
        [coherent_exe, "generate", "--variants-of", str(DEMO), "--out", str(tmp_path / "variants")],
        capture_output=True, text=True, check=True,
    )
    task = tmp_path / "variants" / "demo-apartment-task0-object_moved.json"
    done = subprocess.run(
        [coherent_exe, "run", str(task), "--out", str(tmp_path / "runs")], capture_output=True, text=True, check=True
    )
    transcript = Path(next(line for line in done.stdout.splitlines() if line.startswith("transcript: ")).split(": ", 1)[1])
    recorded = rounds(transcript)
    moved = next(r["step"] for r in recorded if r.get("events"))
    grabs = [
        (r["step"], r["decision"]["robot"], r["decision"]["action"].removeprefix("[grab] "))
        for r in recorded
        if r["step"] > moved and r["outcome"]["kind"] == "executed" and r["decision"]["action"].startswith("[grab]")
    ]
    assert grabs, "the team picks the moved thing up again"
    page_file = tmp_path / "moved.html"
    view(coherent_exe, str(transcript), "-o", str(page_file))
    w = watch(browser)
    w.open(page_file.as_uri())
    for step, robot, thing in grabs:
        w.page.goto(f"{page_file.as_uri()}#step={step}")
        w.page.wait_for_selector(f".steps li.current[data-step='{step}']")
        held = w.page.text_content(f".scene li[data-robot='{robot}'] .holds") or ""
        assert thing in held, (step, robot, thing, held)
    # Physics follows the event too: the thing set down where the event put it, the
    # robots drawn where Rapier has them to the end, with no word of physics stopping.
    assert w.page.locator(".scene .warning").count() == 0, w.page.text_content(".scene .warning")
    w.assert_quiet()


def test_coherent_view_in_python_gives_the_page_and_a_frame_for_jupyter(tmp_path: Path, browser: Any) -> None:
    task = coherent.load_tasks(DEMO)[0]
    episode = coherent.run(task, out=tmp_path / "runs")
    page = coherent.view(episode)
    assert isinstance(page, coherent.Page)
    assert coherent.view(episode.path).html == page.html
    frame = episode._repr_html_()
    assert frame.startswith('<iframe sandbox="allow-scripts"') and "srcdoc=" in frame
    w = watch(browser)
    w.page.set_content(frame)
    inner = w.page.frame_locator("iframe")
    inner.locator(".steps li.current").wait_for()
    assert inner.locator(".steps li").count() == episode.steps + 1
    saved = page.save(tmp_path / "episode.html")
    w.open(saved.as_uri())
    w.page.keyboard.press("End")
    assert w.page.text_content(".steps li.current").startswith(f"step {episode.steps}/")
    w.assert_quiet("about:")


def test_a_view_that_cannot_be_made_raises_the_exception_of_its_kind(tmp_path: Path, env0_tasks: list[coherent.Task]) -> None:
    task = coherent.load_tasks(DEMO)[0]
    episode = coherent.run(task, out=tmp_path / "runs")
    text = Path(episode.path).read_text(encoding="utf-8")
    # A transcript whose second line follows no record of the format.
    broken = tmp_path / "broken.jsonl"
    broken.write_text(text.replace('"type":"round"', '"type":"roundabout"', 1), encoding="utf-8")
    with pytest.raises(coherent.DataFileError) as raised:
        coherent.view(broken)
    assert (raised.value.file, raised.value.line) == (str(broken), 2)
    # Cut in the middle of its last line: the whole rounds are shown, and the page says so.
    cut = tmp_path / "cut.jsonl"
    cut.write_text(text[: len(text) - 40], encoding="utf-8")
    assert "cut short" in coherent.view(cut).html
    # Two episodes of different tasks side by side: arguments that cannot be used.
    other = coherent.run(env0_tasks[0], method="optimal", out=tmp_path / "runs")
    with pytest.raises(coherent.ArgumentError, match="different tasks"):
        coherent.view(episode, other)
