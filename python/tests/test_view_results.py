"""`coherent view` of a benchmark's results in a real browser: the index's tables against
`coherent.report`, each row's link against the episode it names, and `--serve`
following a results file as it grows."""

from __future__ import annotations

import http.client
import json
import math
import re
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from browser import chromium, watch
from test_view import SCREENSHOTS

import coherent

METHODS = ["pefa", "cmrs", "optimal"]


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    with chromium() as b:
        yield b


@pytest.fixture(scope="module")
def results(coherent_exe: str, env0_path: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """paper40 on the simulated backend: three methods, two seeds (240 episodes)."""
    out = tmp_path_factory.mktemp("bench") / "results.jsonl"
    done = subprocess.run(
        [coherent_exe, "bench", "--tasks", str(env0_path.parent), "--subset", "paper40",
         "--methods", ",".join(METHODS), "--seeds", "2", "--sim-errors", "all=0.1", "--out", str(out)],
        capture_output=True, text=True, check=False,
    )
    assert done.returncode == 0, done.stderr
    return out


def close(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12)


def cells(page: Any, table: str) -> dict[tuple[str, str], tuple[float, float]]:
    """(method, column) -> (SR, AS) as the page's table holds them."""
    found = page.eval_on_selector_all(
        f"#{table} tbody tr[data-method] td[data-sr]",
        "ts => ts.map(t => [t.parentElement.dataset.method, t.dataset.column, Number(t.dataset.sr), Number(t.dataset.as)])",
    )
    return {(m, c): (sr, as_) for m, c, sr, as_ in found}


def test_the_results_page_has_the_analysis_numbers_and_links_each_episode(
    coherent_exe: str, results: Path, tmp_path: Path, browser: Any
) -> None:
    site = tmp_path / "site"
    done = subprocess.run([coherent_exe, "view", str(results), "-o", str(site)], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in results.read_text(encoding="utf-8").splitlines()]
    assert done.stdout.strip() == f"wrote {site / 'index.html'} and {len(lines)} episode pages"
    w = watch(browser)
    w.open((site / "index.html").as_uri())
    page = w.page
    if SCREENSHOTS:
        page.screenshot(path=str(Path(SCREENSHOTS) / "view-results.png"), full_page=False)
    report = coherent.report(coherent.results(results))
    for name, table in (("table1", report.table1), ("table2", report.table2)):
        shown = cells(page, name)
        expected = {
            (method, column): (table.loc[method, (column, "SR")], table.loc[method, (column, "AS")])
            for method in table.index if method != "ground truth"
            for column in table.columns.get_level_values(0).unique()
            if not math.isnan(table.loc[method, (column, "SR")])
        }
        assert shown.keys() == expected.keys()
        for key, (sr, as_) in expected.items():
            assert close(shown[key][0], sr) and close(shown[key][1], as_), key
    for method, row in report.costs.iterrows():
        for key in ("calls_per_episode", "tokens_per_episode", "calls_per_step", "tokens_per_step", "cost_per_task"):
            value = page.get_attribute(f"#costs tr[data-method='{method}'] td[data-key='{key}']", "data-value")
            assert close(float("nan") if value is None else float(value), float(row[key])), (method, key)
    # Every row links to its own episode: the page of its transcript.
    rows = page.eval_on_selector_all(
        "#episodes tbody tr",
        "rs => rs.map(r => [Number(r.dataset.line), r.querySelector('a.episode-link').getAttribute('href')])",
    )
    assert len(rows) == len(lines)
    for i, href in rows:
        line = lines[i]
        data = embedded(site / href)
        ep = data["episodes"][0]
        assert ep["header"]["task"] == f"{line['scene']} task {line['task_id']}"
        assert ep["header"]["method"] == line["method"]
        assert ep["header"]["seed"] == line["episode_seed"]
        assert ep["result"]["steps"] == line["steps"] and ep["result"]["status"] == line["status"]
    # ... and the browser opens it there.
    for i in (0, len(rows) // 2, len(rows) - 1):
        line = lines[i]
        page.click(f"#episodes tr[data-line='{i}'] a.episode-link")
        page.wait_for_selector(".header h1")
        assert page.text_content(".header h1").startswith(f"{line['scene']} task {line['task_id']}")
        assert page.text_content(".header [data-field=method]") == line["method"]
        page.go_back()
        page.wait_for_selector("#episodes")
    # The figures are drawn by the page: a point per method.
    assert sorted(page.eval_on_selector_all("#sr-steps circle", "cs => cs.map(c => c.dataset.method)")) == sorted(METHODS)
    # Without events, no reference column.
    assert "reference" not in page.eval_on_selector_all("#episodes thead th", "ts => ts.map(t => t.textContent)")
    w.assert_quiet()


def test_results_with_events_have_each_episodes_reference(coherent_exe: str, tmp_path: Path, browser: Any) -> None:
    demo = Path(__file__).resolve().parents[2] / "examples" / "tasks" / "demo.json"
    variants = tmp_path / "variants"
    subprocess.run([coherent_exe, "generate", "--variants-of", str(demo), "--out", str(variants)], capture_output=True, check=True)
    results = tmp_path / "results.jsonl"
    subprocess.run(
        [coherent_exe, "bench", "--tasks", str(variants), "--methods", "optimal", "--out", str(results)],
        capture_output=True, check=True,
    )
    subprocess.run([coherent_exe, "view", str(results), "-o", str(tmp_path / "site")], capture_output=True, check=True)
    lines = [json.loads(line) for line in results.read_text(encoding="utf-8").splitlines()]
    w = watch(browser)
    w.open((tmp_path / "site" / "index.html").as_uri())
    heads = w.page.eval_on_selector_all("#episodes thead th", "ts => ts.map(t => t.textContent)")
    assert heads.index("reference") == heads.index("GT") + 1
    shown = w.page.eval_on_selector_all(
        "#episodes tbody tr", "rs => rs.map(r => [Number(r.dataset.line), r.querySelector('td.reference').textContent])"
    )
    expected = {
        i: str(line["reference"]["steps"]) if "steps" in line["reference"] else "out of reach"
        for i, line in enumerate(lines)
    }
    assert dict(shown) == expected
    assert "out of reach" in expected.values(), "a robot that goes down for good puts the goal out of reach"
    w.assert_quiet()


def embedded(page_file: Path) -> dict[str, Any]:
    """The data a page embeds (its JSON, as the script reads it)."""
    html = page_file.read_text(encoding="utf-8")
    found = re.search(r'<script type="application/json" id="data">(.*?)</script>', html, re.S)
    assert found
    return json.loads(found.group(1))


def rows(page: Any) -> int:
    return int(page.eval_on_selector_all("#episodes tbody tr", "rs => rs.length"))


def test_serve_follows_the_results_file_as_it_grows(coherent_exe: str, results: Path, tmp_path: Path, browser: Any) -> None:
    lines = results.read_text(encoding="utf-8").splitlines(keepends=True)
    folder = tmp_path / "live"
    folder.mkdir()
    growing = folder / "results.jsonl"
    # The transcripts stay where the lines name them.
    growing.write_text("".join(lines[:10]), encoding="utf-8")
    server = subprocess.Popen(
        [coherent_exe, "view", "--serve", str(folder)], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True
    )
    try:
        assert server.stdout is not None
        first = server.stdout.readline()
        url = re.search(r"(http://127\.0\.0\.1:\d+/)", first)
        assert url, first
        base = url.group(1)
        w = watch(browser)
        w.open(base)
        page = w.page
        assert rows(page) == 10
        with growing.open("a", encoding="utf-8") as f:
            f.write("".join(lines[10:25]))
        # The page asks every two seconds (the policy forbids evaluating strings, so the
        # waiting is done here).
        deadline = time.monotonic() + 15
        while rows(page) != 25 and time.monotonic() < deadline:
            page.wait_for_timeout(200)
        assert rows(page) == 25
        # An episode's page, made when asked for.
        page.click("#episodes tr[data-line='12'] a.episode-link")
        page.wait_for_selector(".header h1")
        line = json.loads(lines[12])
        assert page.text_content(".header [data-field=method]") == line["method"]
        w.assert_quiet(base)
        # Only this server's own name is answered (no page elsewhere reaches it).
        port = int(base.rsplit(":", 1)[1].strip("/"))
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
        conn.request("GET", "/", headers={"Host": "attacker.example:80"})
        assert conn.getresponse().status == 421
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
        conn.request("GET", "/../../etc/passwd")
        assert conn.getresponse().status == 404
    finally:
        server.terminate()
        server.wait(timeout=10)
        if server.stdout is not None:
            server.stdout.close()


def test_a_results_dataframe_shows_the_results_page_in_jupyter(results: Path, browser: Any) -> None:
    df = coherent.results(results)
    page = coherent.view(df)
    assert page.html == coherent.view(results).html
    frame = df.coherent._repr_html_()
    w = watch(browser)
    w.page.set_content(frame)
    inner = w.page.frame_locator("iframe")
    inner.locator("#episodes tbody tr").first.wait_for()
    assert inner.locator("#episodes tbody tr").count() == len(df)
    w.assert_quiet("about:")
