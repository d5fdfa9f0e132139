"""The ``coherent`` console script: the Rust command line, run from the extension module."""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Sequence

from ._coherent import cli_main


def main(argv: Sequence[str] | None = None) -> None:
    """Runs ``coherent`` with ``argv`` (default: the process's arguments) and exits with
    its status (with the process's arguments, at once, without the interpreter's
    shutdown; with ``argv``, by raising ``SystemExit``)."""
    # Python turns SIGINT into KeyboardInterrupt, which would only be seen once the
    # Rust code returns; the default action ends the process at once, like the binary.
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_DFL)
    args = sys.argv[1:] if argv is None else list(argv)
    tokenizer, args = _taken(args, "--tokenizer") if args[:2] == ["export", "sft"] else (None, args)
    loaded = None
    if tokenizer is not None:
        # Loaded first: a tokenizer that cannot be loaded costs no export.
        from ._coherent import ArgumentError
        from .training import load_tokenizer

        try:
            loaded = load_tokenizer(tokenizer)
        except ArgumentError as e:
            print(f"error: --tokenizer: {e}", file=sys.stderr)
            if argv is None:
                os._exit(2)
            sys.exit(2)
    # Rust writes to the file descriptor directly: flush what Python buffered first.
    sys.stdout.flush()
    sys.stderr.flush()
    code = cli_main(["coherent", *args])
    out = _taken(args, "--out", "-o")[0]
    if loaded is not None and out is not None and os.path.isfile(os.path.join(out, "train.jsonl")):
        from .training import count_tokens

        counts = count_tokens(out, loaded)
        print("tokens: " + ", ".join(f"{s} {c['tokens']:,}" for s, c in counts.items()))
    if argv is None:
        # The process's own command: it ends at once, as the binary does. A method's call
        # that was stopped may still be blocked on its thread (in C code), and the
        # interpreter's shutdown must not trip over it when it returns.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


def _taken(args: list[str], *flags: str) -> tuple[str | None, list[str]]:
    """The value of the first of ``flags`` in ``args`` (``--flag V`` or ``--flag=V``), and
    ``args`` without it."""
    for i, a in enumerate(args):
        for flag in flags:
            if a == flag and i + 1 < len(args):
                return args[i + 1], args[:i] + args[i + 2 :]
            if a.startswith(flag + "="):
                return a[len(flag) + 1 :], args[:i] + args[i + 1 :]
    return None, args


if __name__ == "__main__":
    main()
