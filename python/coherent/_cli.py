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
    # Rust writes to the file descriptor directly: flush what Python buffered first.
    sys.stdout.flush()
    sys.stderr.flush()
    code = cli_main(["coherent", *args])
    if argv is None:
        # The process's own command: it ends at once, as the binary does. A method's call
        # that was stopped may still be blocked on its thread (in C code), and the
        # interpreter's shutdown must not trip over it when it returns.
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":
    main()
