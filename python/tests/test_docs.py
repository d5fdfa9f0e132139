"""The docs run: every shell and Python block of README.md and docs/*.md is executed as
written, in a scratch copy of the checkout's layout (the bundled examples, the released
files at ``../shared``), with the installed ``coherent`` command and package. A block
that cannot run here says why in a marker on the line before its fence::

    <!-- docs-test: skip: needs a paid API key -->

and a block whose server at ``127.0.0.1:8080`` is the tests' local model says so::

    <!-- docs-test: model -->

In a model block every server on ``127.0.0.1`` (``http://127.0.0.1:PORT/v1``, several
in the examples of several servers) is that one local model. A block that would run too
long for the test suite (a study of minutes or hours) runs at a reduced size that the
doc states beside it, each ``OLD => NEW`` replacement applied to its text (and each must
apply, so that the marker cannot go stale)::

    <!-- docs-test: reduced: --seeds 3 => --seeds 1; --subset all => --subset paper40 -->
    <!-- docs-test: model; reduced: --seeds 3 => --seeds 1 -->

A block that writes into ``docs/`` (the figures, the renders) regenerates what the
repository holds there: each file it writes must be the repository's, byte for byte.

A file's Python blocks share one namespace, in order, as a reader runs them. Where a
Python line prints and ends in a comment (``print(x)   # 22``), the printed text is
checked against the comment (or a comment line alone under it). A failure names the file, the line of the block's fence and
the block's text."""

from __future__ import annotations

import ast
import contextlib
import io
import os
import re
import subprocess
import sys
import sysconfig
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from conftest import ENV_DIR, REPO

DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
MARKER = re.compile(
    r"^<!-- docs-test: (skip: (?P<why>.+?)|(?P<model>model)?(; )?(reduced: (?P<reduced>.+?))?) -->$"
)
FENCE = re.compile(r"^```(?P<lang>\w*)\s*$")
RUN = {"sh": "sh", "bash": "sh", "python": "python"}
# What the docs' commands find beside them, as in a checkout: linked, not copied.
LINKED = ("examples", "benchmark", "scripts", "crates", "pyproject.toml")
# The servers the docs' examples name for a model of one's own: any on loopback.
DOCS_SERVER = re.compile(r"http://127\.0\.0\.1:\d+/v1")


@dataclass(frozen=True)
class Block:
    doc: Path
    line: int
    lang: str
    text: str
    skip: str | None
    model: bool
    reduced: tuple[tuple[str, str], ...] = ()

    @property
    def name(self) -> str:
        return f"{self.doc.relative_to(REPO)}:{self.line}"

    def shown(self) -> str:
        """Where the block is and what it says, for a failure's message."""
        return f"the {self.lang} block at {self.name}:\n{self.text}"

    def as_run(self, model: str | None) -> str:
        """The text the test runs: reduced as its marker says, its servers the local model."""
        text = self.text
        for old, new in self.reduced:
            assert old in text, f"{self.name}: the marker reduces {old!r}, which the block does not say"
            text = text.replace(old, new)
        return DOCS_SERVER.sub(model, text) if model else text


def blocks(doc: Path) -> list[Block]:
    """The shell and Python blocks of `doc`, with their markers."""
    lines = doc.read_text().splitlines()
    found = []
    i = 0
    while i < len(lines):
        fence = FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith("```"))
        lang = RUN.get(fence["lang"])
        if lang:
            marker = MARKER.match(lines[i - 1]) if i > 0 else None
            found.append(
                Block(
                    doc=doc,
                    line=i + 1,
                    lang=lang,
                    text="\n".join(lines[i + 1 : end]) + "\n",
                    skip=marker["why"] if marker else None,
                    model=bool(marker and marker["model"]),
                    reduced=_replacements(marker["reduced"]) if marker and marker["reduced"] else (),
                )
            )
        i = end + 1
    return found


def _replacements(spec: str) -> tuple[tuple[str, str], ...]:
    pairs = [part.split(" => ") for part in spec.split("; ")]
    assert all(len(p) == 2 for p in pairs), f"a reduced marker is OLD => NEW; ...: {spec!r}"
    return tuple((old, new) for old, new in pairs)


ALL = [b for doc in DOCS for b in blocks(doc)]


@pytest.fixture(scope="module")
def checkout(tmp_path_factory: pytest.TempPathFactory) -> dict[Path, Path]:
    """A scratch checkout per document: the repository's examples and scripts linked in,
    the released files at ``../shared/coherent-original/env`` beside it."""
    root = tmp_path_factory.mktemp("docs")
    (root / "shared" / "coherent-original").mkdir(parents=True)
    (root / "shared" / "coherent-original" / "env").symlink_to(ENV_DIR)
    folders = {}
    for doc in DOCS:
        folder = root / doc.stem
        folder.mkdir()
        for name in LINKED:
            (folder / name).symlink_to(REPO / name)
        folders[doc] = folder
    return folders


def _environment(model: str | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("OPENAI_BASE_URL", "OPENAI_API_KEY", "COHERENT_MODEL")}
    scripts = sysconfig.get_path("scripts")
    env["PATH"] = f"{scripts}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    if model:
        env["OPENAI_BASE_URL"] = model
    return env


# Exit status 1 of `coherent` is an episode that spent its budget (or a task with a
# semantic problem): an outcome the docs' commands may have, not a failure to run.
OUTCOME_IS_NO_ERROR = 'coherent() { command coherent "$@" || { s=$?; [ "$s" = 1 ] || return "$s"; }; }\n'


def _run_shell(block: Block, cwd: Path, model: str | None) -> None:
    run = subprocess.run(
        ["bash", "-e", "-o", "pipefail", "-c", OUTCOME_IS_NO_ERROR + block.as_run(model)],
        cwd=cwd, env=_environment(model), capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    if run.returncode != 0:
        pytest.fail(
            f"{block.shown()}exits {run.returncode}\n--- stdout\n{run.stdout[-3000:]}\n--- stderr\n{run.stderr[-3000:]}",
            pytrace=False,
        )


def _printed_comment(source: str, node: ast.stmt, first: int) -> str | None:
    """The comment at the end of a `print(...)` statement's last line, or on the line
    under it when that line is a comment alone (for a long output), if any (`first`: the
    line number of the source's first line in the node's numbering)."""
    call = node.value if isinstance(node, ast.Expr) else None
    if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id == "print"):
        return None
    lines = source.splitlines()
    end = (node.end_lineno or node.lineno) - first
    tail = lines[end][node.end_col_offset :] if node.end_col_offset is not None else ""
    comment = tail.strip()
    if not comment and end + 1 < len(lines):
        comment = lines[end + 1].strip()
    return comment[1:].strip() if comment.startswith("#") else None


def _run_python(block: Block, cwd: Path, namespace: dict[str, Any], model: str | None) -> None:
    text = block.as_run(model)
    # Line numbers of the doc, in a traceback too: the block starts after its fence.
    tree = ast.increment_lineno(ast.parse(text, filename=block.name), block.line)
    previous = Path.cwd()
    os.chdir(cwd)
    try:
        for node in tree.body:
            where = node.lineno
            code = compile(ast.Module(body=[node], type_ignores=[]), str(block.doc), "exec")
            out = io.StringIO()
            try:
                with contextlib.redirect_stdout(out):
                    exec(code, namespace)
            except Exception as error:
                pytest.fail(f"{block.shown()}raises at {block.doc.relative_to(REPO)}:{where}: {error!r}")
            expected = _printed_comment(text, node, block.line + 1)
            if expected is not None:
                printed = out.getvalue().strip()
                if printed != expected:
                    pytest.fail(f"{block.shown()}line {where} printed {printed!r}, the docs say {expected!r}", pytrace=False)
    finally:
        os.chdir(previous)


NAMESPACES: dict[Path, dict[str, Any]] = {}


@pytest.mark.parametrize("block", [b for b in ALL if b.skip is None], ids=lambda b: b.name)
def test_the_block_runs_as_written(block: Block, checkout: dict[Path, Path], request: pytest.FixtureRequest) -> None:
    model = f"{request.getfixturevalue('local_model')}/v1" if block.model else None
    cwd = checkout[block.doc]
    if block.lang == "sh":
        _run_shell(block, cwd, model)
    else:
        namespace = NAMESPACES.setdefault(block.doc, {"__name__": "__docs__"})
        _run_python(block, cwd, namespace, model)
    _check_regenerated(block, cwd)


def _check_regenerated(block: Block, cwd: Path) -> None:
    """The files a block wrote under docs/ are the repository's, byte for byte."""
    written = sorted(p for p in (cwd / "docs").rglob("*") if p.is_file())
    differ = [p.relative_to(cwd) for p in written if not _same_bytes(p, REPO / p.relative_to(cwd))]
    if differ:
        listed = ", ".join(str(p) for p in differ)
        pytest.fail(
            f"{block.shown()}writes {listed} other than the repository holds: run the block in the "
            "repository's root to regenerate them, and commit them",
            pytrace=False,
        )


def _same_bytes(a: Path, b: Path) -> bool:
    return b.is_file() and a.read_bytes() == b.read_bytes()


# docs/figures: what examples/benchmark_figures.py writes (docs/python.md, "Figures"),
# except tokens.png (a model's episode, minutes on two cores) and the pages' screenshots
# (python/tests/test_view.py, a browser's rendering).
FIGURES = (
    "builtin-by-scene.png",
    "builtin-by-type.png",
    "scene.png",
    "simulated-by-scene.png",
    "simulated-by-type.png",
    "storeys.png",
    "timeline.png",
)


def test_the_figures_are_what_the_script_writes(tmp_path: Path) -> None:
    script = REPO / "examples" / "benchmark_figures.py"
    run = subprocess.run(
        [sys.executable, str(script), "--out", str(tmp_path)],
        cwd=tmp_path, env=_environment(None), capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    differ = [name for name in FIGURES if (tmp_path / name).read_bytes() != (REPO / "docs" / "figures" / name).read_bytes()]
    assert not differ, (
        f"docs/figures/{', '.join(differ)} not what `python examples/benchmark_figures.py --out docs/figures` "
        "writes: regenerate them (docs/python.md, Figures) and commit them"
    )


def test_every_marker_is_well_formed_and_over_a_block() -> None:
    # A marker that is misspelt, or not right above a fence, would silently run or skip.
    for doc in DOCS:
        lines = doc.read_text().splitlines()
        for i, line in enumerate(lines):
            if line.startswith("<!-- docs-test"):
                marker = MARKER.match(line)
                assert marker and (marker["why"] or marker["model"] or marker["reduced"]), (
                    f"{doc.name}:{i + 1}: a marker is skip: WHY, model, reduced: OLD => NEW or model; reduced: ..."
                )
                assert i + 1 < len(lines) and FENCE.match(lines[i + 1]), f"{doc.name}:{i + 1}: no block under it"
    assert all(b.skip.strip() for b in ALL if b.skip is not None)


if __name__ == "__main__":
    for b in ALL:
        print(b.name, b.lang, "skip: " + b.skip if b.skip else ("model" if b.model else "run"))
    sys.exit(0)
