"""Training data for the methods' models from the optimal planner (docs/training.md).

``dataset()`` writes what ``coherent export sft`` writes: every question a method's roles
ask in episodes on the tasks given (one episode with the built-in planner's answers, and
others with the simulated backend's mistakes), each with the optimal planner's answer
from the state it was asked in, in the method's own answer format: chat examples in
``train.jsonl``, ``validation.jsonl`` and ``test.jsonl`` (split by scene) and a datasheet
``README.md``. Each line holds ``prompt`` (the messages as the method sent them) and
``completion`` (the answer), the conversational prompt-completion form that
``datasets.load_dataset("json", ...)`` reads and TRL's ``SFTTrainer`` trains on as is.

Token counts need a tokenizer (``tokenizer=``: a Hugging Face name or folder, or a GGUF
file) and ``transformers`` (the ``training`` extra).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ._coherent import ArgumentError, export_sft

SPLITS = ("train", "validation", "test")


@dataclass
class TrainingData:
    """What ``dataset()`` wrote: the folder, the examples by split and by role, the
    tasks played, the files, and the token counts when a tokenizer was given."""

    out: Path
    examples: dict[str, int]
    by_role: dict[str, int]
    tasks: int
    files: list[Path]
    left_out: dict[str, Any] = field(default_factory=dict)
    tokens: dict[str, dict[str, int]] | None = None

    def load(self):
        """The splits that hold examples, as a ``datasets.DatasetDict`` (needs
        ``datasets``, which cannot read an empty split)."""
        from datasets import load_dataset

        files = {s: str(self.out / f"{s}.jsonl") for s in SPLITS if self.examples.get(s)}
        return load_dataset("json", data_files=files)


def load_tokenizer(spec: str | os.PathLike[str]):
    """The tokenizer ``spec`` names: a GGUF file (its tokenizer, read by transformers'
    GGUF support), a folder or a Hugging Face name. ``ArgumentError`` when it cannot be
    loaded, before anything is written."""
    try:
        from transformers import AutoTokenizer
    except ImportError as e:
        raise ArgumentError(f"tokenizer={str(spec)!r}: counting tokens needs transformers (the training extra): {e}") from None
    path = Path(spec)
    try:
        if path.suffix == ".gguf":
            if not path.is_file():
                raise FileNotFoundError(f"no such file: {path}")
            return AutoTokenizer.from_pretrained(str(path.parent), gguf_file=path.name)
        return AutoTokenizer.from_pretrained(str(spec))
    except Exception as e:  # transformers raises many kinds; each is a tokenizer that did not load
        raise ArgumentError(f"tokenizer={str(spec)!r}: cannot be loaded: {type(e).__name__}: {e}") from None


def count_tokens(out: str | os.PathLike[str], tokenizer) -> dict[str, dict[str, int]]:
    """The tokens of the examples in ``out`` by split: ``examples``, ``tokens`` (the chat
    template applied to prompt and answer), ``answer_tokens``, ``longest``; written into
    the datasheet as a table."""
    out = Path(out)
    counts: dict[str, dict[str, int]] = {}
    for split in SPLITS:
        c = {"examples": 0, "tokens": 0, "answer_tokens": 0, "longest": 0}
        with open(out / f"{split}.jsonl", encoding="utf-8") as f:
            for line in f:
                example = json.loads(line)
                ids = tokenizer.apply_chat_template(example["prompt"] + example["completion"], tokenize=True)
                if hasattr(ids, "keys"):  # a BatchEncoding in some transformers versions
                    ids = ids["input_ids"]
                answer = tokenizer(example["completion"][0]["content"], add_special_tokens=False)["input_ids"]
                c["examples"] += 1
                c["tokens"] += len(ids)
                c["answer_tokens"] += len(answer)
                c["longest"] = max(c["longest"], len(ids))
        counts[split] = c
    name = getattr(tokenizer, "name_or_path", "") or type(tokenizer).__name__
    rows = [f"\n## Tokens\n\nCounted with the tokenizer `{name}` (the chat template applied to prompt and answer).\n",
            "| split | examples | tokens | answer tokens | longest example |", "|---|---|---|---|---|"]
    rows += [f"| {s} | {c['examples']:,} | {c['tokens']:,} | {c['answer_tokens']:,} | {c['longest']:,} |" for s, c in counts.items()]
    with open(out / "README.md", "a", encoding="utf-8") as f:
        f.write("\n".join(rows) + "\n")
    return counts


def dataset(
    files: str | os.PathLike[str] | list[str | os.PathLike[str]],
    method: str = "pefa",
    out: str | os.PathLike[str] = "sft",
    *,
    execution: str | list[str] | None = None,
    roles: list[str] | None = None,
    sim_errors: str = "all=0.1",
    seeds: int = 2,
    history: int | None = None,
    prompts: str | os.PathLike[str] | dict[str, str] | None = None,
    split: tuple[float, float, float] = (0.8, 0.1, 0.1),
    include_eval: bool = False,
    max_states: int | None = None,
    tokenizer: str | os.PathLike[str] | None = None,
) -> TrainingData:
    """Writes the training data of ``method`` (``pefa``, ``pefa-no-history``, ``cmrs``,
    ``dmrs-1d``, ``dmrs-2d``, ``llm-mcts``, ``llm-pddl``) on the tasks of ``files`` (task
    files, folders, generated sets, whose splits are kept, or ``"native"``) into ``out``,
    as ``coherent export sft`` does with the same settings. The evaluation subsets
    (paper40, native40) are left out unless ``include_eval``. A method that asks no
    model, a role it does not have, or a tokenizer that cannot be loaded raises
    ``ArgumentError`` before anything is written."""
    if isinstance(files, (str, os.PathLike)):
        files = [files]
    loaded = load_tokenizer(tokenizer) if tokenizer is not None else None
    written = export_sft(
        list(files),
        method,
        out,
        execution=execution,
        roles=roles,
        sim_errors=sim_errors,
        seeds=seeds,
        history=history,
        prompts=prompts,
        split=tuple(split),
        include_eval=include_eval,
        max_states=max_states,
        command=f"coherent.training.dataset({[os.fspath(f) for f in files]!r}, method={method!r}, seeds={seeds}, "
        f"sim_errors={sim_errors!r}, execution={execution!r}, roles={roles!r}, split={tuple(split)!r}, "
        f"include_eval={include_eval!r})",
    )
    data = TrainingData(
        out=Path(out),
        examples=dict(written["examples"]),
        by_role=dict(written["by_role"]),
        tasks=written["tasks"],
        files=[Path(p) for p in written["files"]],
        left_out={k: written[k] for k in ("left_out_eval", "malformed", "no_answer", "duplicates", "conflicts", "unreadable")},
    )
    if loaded is not None:
        data.tokens = count_tokens(out, loaded)
    return data
